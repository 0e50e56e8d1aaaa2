//! `baker mc`: layered Monte Carlo transport of a stack file, an MCML input file, or a skin
//! spec entry at one wavelength.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use super::optics::load_spec;
use crate::error::UsageError;
use crate::output::atomic;
use crate::transport::{self, mcml, McOptions, McResult, Stack};

#[derive(Debug, Args)]
pub struct McArgs {
    /// Stack file (JSON): {"n_above", "n_below", "layers": [{"name", "d_mm" (number or "inf"),
    /// "eta", "mua_per_mm", "mus_per_mm", "g"}], "grid": {"dr_mm", "nr"}, "junction"?}.
    #[arg(conflicts_with_all = ["mci_in", "spec"])]
    pub stack: Option<PathBuf>,
    /// Read an MCML input file instead (cm units; every run in it is simulated).
    #[arg(long, value_name = "FILE.mci", conflicts_with = "spec")]
    pub mci_in: Option<PathBuf>,
    /// Write MCML's output format (.mco). With --mci-in and no --mco, each run's own output
    /// file name is used.
    #[arg(long, value_name = "FILE")]
    pub mco: Option<PathBuf>,
    /// Take the stack from a skin spec entry (with --entry and --lambda-nm).
    #[arg(long, value_name = "SPEC", requires_all = ["entry", "lambda_nm"])]
    pub spec: Option<PathBuf>,
    #[arg(long, requires = "spec")]
    pub entry: Option<String>,
    /// Wavelength of the skin entry, nm (on the spec's grid).
    #[arg(long, value_name = "NM", requires = "spec")]
    pub lambda_nm: Option<f64>,
    /// Photon packets to trace (default 1,000,000; with --mci-in, each run's own count).
    #[arg(long)]
    pub photons: Option<u64>,
    /// Seed: the same input and seed give bit-identical output for any thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print one JSON object instead of a summary.
    #[arg(long)]
    pub json: bool,
    /// With a junction, enter each packet at a random point of the junction's period cell and
    /// measure radii from there (the profile averaged over entry points, as `bake` does).
    #[arg(long)]
    pub random_entry: bool,
}

pub fn run(a: McArgs) -> anyhow::Result<()> {
    let mut o = McOptions::new(a.photons.unwrap_or(1_000_000), a.seed);
    o.threads = a.threads;
    o.random_entry = a.random_entry;
    if a.photons == Some(0) {
        return Err(UsageError("--photons must be at least 1".into()).into());
    }
    if let Some(path) = &a.mci_in {
        let text = crate::files::read_text(path, crate::files::MAX_SPEC_BYTES, "an .mci file")
            .map_err(|e| UsageError(e.to_string()))?;
        let runs =
            mcml::parse_mci(&text).map_err(|e| UsageError(format!("{}: {e}", path.display())))?;
        for (k, run) in runs.iter().enumerate() {
            let mut ok = o.clone();
            if a.photons.is_none() {
                ok.photons = run.photons; // the file's own photon count unless --photons is given
            }
            let (r, grid) = with_bar(&ok, a.json, |o| mcml::simulate_grid(run, o))?;
            report(&r, a.json)?;
            let out = match (&a.mco, runs.len()) {
                (Some(p), 1) => p.clone(),
                (Some(p), _) => p.with_extension(format!("{k}.mco")),
                (None, _) => path
                    .parent()
                    .unwrap_or(std::path::Path::new("."))
                    .join(&run.output_file),
            };
            atomic::write(&out, mcml::write_mco(run, &r, &grid).as_bytes())
                .with_context(|| format!("writing {}", out.display()))?;
            eprintln!("wrote {}", out.display());
        }
        return Ok(());
    }
    let stack = if let Some(spec) = &a.spec {
        let s = load_spec(spec)?;
        let name = a.entry.clone().unwrap();
        let entries = super::optics::evaluate_entries(&s, &[name])?;
        let i = super::optics::wavelength_index(&s, a.lambda_nm.unwrap(), "--lambda-nm")?;
        transport::stack::from_skin(&entries[0], i)
    } else if let Some(path) = &a.stack {
        read_stack(path)?
    } else {
        return Err(UsageError(
            "give a STACK.json, --mci-in FILE.mci, or --spec SPEC --entry NAME --lambda-nm NM"
                .into(),
        )
        .into());
    };
    if let Some(out) = &a.mco {
        let run = mcml::McmlRun::from_stack(&stack, o.photons);
        let (r, grid) = with_bar(&o, a.json, |o| mcml::simulate_grid(&run, o))?;
        report(&r, a.json)?;
        atomic::write(out, mcml::write_mco(&run, &r, &grid).as_bytes())
            .with_context(|| format!("writing {}", out.display()))?;
        eprintln!("wrote {}", out.display());
    } else {
        let r = with_bar(&o, a.json, |o| transport::run(&stack, o))?;
        report(&r, a.json)?;
    }
    Ok(())
}

/// Runs `f` with a progress bar over `o.photons` on a terminal (none with `--json`).
fn with_bar<T>(
    o: &McOptions,
    json: bool,
    f: impl FnOnce(&McOptions) -> anyhow::Result<T>,
) -> anyhow::Result<T> {
    let bar = (!json).then(|| super::progress::bar(o.photons, "photons"));
    let mut with = o.clone();
    with.progress = super::progress::reporter(&bar);
    let r = f(&with);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    r
}

pub fn read_stack(path: &std::path::Path) -> anyhow::Result<Stack> {
    let text = crate::files::read_text(path, crate::files::MAX_SPEC_BYTES, "a stack file")
        .map_err(|e| UsageError(e.to_string()))?;
    let file: transport::stack::StackFile =
        serde_json::from_str(&text).map_err(|e| UsageError(format!("{}: {e}", path.display())))?;
    file.into_stack()
        .map_err(|e| UsageError(format!("{}: {e}", path.display())).into())
}

fn report(r: &McResult, json: bool) -> anyhow::Result<()> {
    if json {
        outln!("{}", serde_json::to_string(r)?)?;
        return Ok(());
    }
    outln!(
        "photons {}  threads {}  {:.3} s  {:.0} photons/s  {:.3e} scattering events/s",
        r.photons,
        r.threads,
        r.seconds,
        r.photons_per_s,
        r.scattering_events_per_s
    )?;
    outln!("specular reflectance Rsp  {:.6}", r.rsp)?;
    outln!("diffuse reflectance  Rd   {:.6} ± {:.6}", r.rd, r.rd_se)?;
    outln!(
        "unscattered reflect.      {:.6} ± {:.6}",
        r.rd_unscattered,
        r.rd_unscattered_se
    )?;
    outln!("transmittance        Tt   {:.6} ± {:.6}", r.tt, r.tt_se)?;
    for (i, (a, s)) in r.absorbed.iter().zip(&r.absorbed_se).enumerate() {
        outln!("absorbed in layer {i:<2}      {a:.6} ± {s:.6}")?;
    }
    outln!("∫Rd(r) over the grid      {:.6}", r.rd_r_integrated)?;
    outln!("energy balance            {:.6}", r.energy())?;
    Ok(())
}
