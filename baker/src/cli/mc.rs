//! `baker mc`: layered Monte Carlo transport of a stack file, an MCML input file, or a skin
//! spec entry at one wavelength.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use super::optics::load_spec;
use crate::error::UsageError;
use crate::output::atomic;
use crate::transport::engine::ROULETTE_WEIGHT;
use crate::transport::{self, mcml, McOptions, McResult, Stack};

#[derive(Debug, Args)]
pub struct McArgs {
    /// Stack file (JSON): {"n_above", "n_below", "layers": [{"name", "d_mm" (number or "inf"),
    /// "eta", "mua_per_mm", "mus_per_mm", "g"}], "grid": {"dr_mm", "nr"}, "junction"?}.
    #[arg(conflicts_with_all = ["mci_in", "spec"])]
    pub stack: Option<PathBuf>,
    /// Read an MCML input file instead: MCML 1.x (`1.0`) or MCML 2.0 (`mcmli2.0`, with a media
    /// list), cm units; every run in it is simulated and written as .mco under its own output
    /// name.
    #[arg(long, value_name = "FILE.mci", conflicts_with = "spec")]
    pub mci_in: Option<PathBuf>,
    /// Where MCML's output format (.mco) goes. With --mci-in: a folder (created if missing)
    /// that each run's output name is joined to; without -o the names are relative to the
    /// current directory, as MCML writes them. Names that would leave that folder (absolute
    /// paths, `..`) are refused either way. With a STACK.json or one --entry: FILE.mco, or an
    /// existing folder to write baker.mco (or <entry>.mco) in; with several --entry, a folder
    /// (created if missing) of <entry>.mco files; without -o no .mco is written.
    #[arg(short = 'o', long = "out", value_name = "PATH")]
    pub out: Option<PathBuf>,
    /// Earlier name of -o for a stack: the .mco file itself (with --mci-in and several runs,
    /// FILE.<k>.mco for run k counted from 0).
    #[arg(long, value_name = "FILE", hide = true, conflicts_with = "out")]
    pub mco: Option<PathBuf>,
    /// Take the stack from a skin spec entry (with --entry and --lambda-nm).
    #[arg(long, value_name = "SPEC", requires_all = ["entries", "lambda_nm"])]
    pub spec: Option<PathBuf>,
    /// Entry of the skin spec to simulate (with --spec; repeatable: each is simulated in turn).
    #[arg(long = "entry", value_name = "NAME", requires = "spec")]
    pub entries: Vec<String>,
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
    #[command(flatten)]
    pub progress: super::observer::ProgressArgs,
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
        return run_mci(&a, &o, path);
    }
    let stacks = stacks_of(&a)?;
    let events = a.progress.events();
    let total = stacks.len();
    for (index, (name, stack)) in stacks.iter().enumerate() {
        let mco = match (&a.out, &a.mco) {
            (Some(p), _) if total > 1 => {
                std::fs::create_dir_all(p).with_context(|| format!("creating {}", p.display()))?;
                Some(p.join(format!("{name}.mco")))
            }
            (Some(p), _) if p.is_dir() => Some(p.join(format!("{name}.mco"))),
            (Some(p), _) | (None, Some(p)) => Some(p.clone()),
            (None, None) => None,
        };
        events.emit(
            serde_json::json!({"event": "run_started", "run": name, "index": index,
            "total": total, "photons": o.photons}),
        );
        let hide = a.json || !a.progress.bar();
        if let Some(out) = &mco {
            let run = mcml::McmlRun::from_stack(stack, o.photons);
            let (r, grid) = with_bar(&o, hide, |o| mcml::simulate_grid(&run, o))?;
            report(&r, a.json)?;
            write_mco(out, &run, &r, &grid, a.progress.quiet)?;
        } else {
            let r = with_bar(&o, hide, |o| transport::run(stack, o))?;
            report(&r, a.json)?;
        }
        events.emit(
            serde_json::json!({"event": "run_finished", "run": name, "index": index,
            "total": total}),
        );
    }
    Ok(())
}

/// The stacks to simulate, named: each `--entry` of `--spec` at `--lambda-nm`, or the stack
/// file (`baker`).
fn stacks_of(a: &McArgs) -> anyhow::Result<Vec<(String, Stack)>> {
    if let Some(spec) = &a.spec {
        let s = load_spec(spec)?;
        let entries = super::optics::evaluate_entries(&s, &a.entries)?;
        let i = super::optics::wavelength_index(&s, a.lambda_nm.unwrap(), "--lambda-nm")?;
        return Ok(entries
            .iter()
            .map(|e| (e.name.clone(), transport::stack::from_skin(e, i)))
            .collect());
    }
    match &a.stack {
        Some(path) => Ok(vec![("baker".to_string(), read_stack(path)?)]),
        None => Err(UsageError(
            "give a STACK.json, --mci-in FILE.mci, or --spec SPEC --entry NAME --lambda-nm NM"
                .into(),
        )
        .into()),
    }
}

/// `--mci-in`: every run of an MCML input file, each written as .mco where
/// [`mcml::resolve_output`] puts its name (in `-o DIR`, else the current directory).
fn run_mci(a: &McArgs, o: &McOptions, path: &Path) -> anyhow::Result<()> {
    let text = crate::files::read_text(path, crate::files::MAX_SPEC_BYTES, "an .mci file")
        .map_err(|e| UsageError(e.to_string()))?;
    let runs =
        mcml::parse_mci(&text).map_err(|e| UsageError(format!("{}: {e}", path.display())))?;
    let outs = runs
        .iter()
        .enumerate()
        .map(|(k, run)| match (&a.mco, runs.len()) {
            (Some(p), 1) => Ok(p.clone()),
            (Some(p), _) => Ok(p.with_extension(format!("{k}.mco"))),
            (None, _) => mcml::resolve_output(&run.output_file, a.out.as_deref()),
        })
        .collect::<Result<Vec<PathBuf>, String>>()
        .map_err(|e| UsageError(format!("{}: {e}", path.display())))?;
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    for (run, out) in runs.iter().zip(&outs) {
        if run.threshold_weight != ROULETTE_WEIGHT && !a.json {
            eprintln!(
                "warning: {}: {}: threshold weight {} traced as {ROULETTE_WEIGHT} (roulette is \
                 unbiased at any threshold; only the noise differs)",
                path.display(),
                run.output_file,
                run.threshold_weight
            );
        }
        let mut ok = o.clone();
        if a.photons.is_none() {
            ok.photons = run.photons; // the file's own photon count unless --photons is given
        }
        let hide = a.json || !a.progress.bar();
        let (r, grid) = with_bar(&ok, hide, |o| mcml::simulate_grid(run, o))?;
        report(&r, a.json)?;
        if let Some(parent) = out.parent().filter(|_| a.out.is_some()) {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        write_mco(out, run, &r, &grid, a.progress.quiet)?;
    }
    Ok(())
}

fn write_mco(
    out: &Path,
    run: &mcml::McmlRun,
    r: &McResult,
    grid: &mcml::McmlGrid,
    quiet: bool,
) -> anyhow::Result<()> {
    atomic::write(out, mcml::write_mco(run, r, grid).as_bytes())
        .with_context(|| format!("writing {}", out.display()))?;
    if !quiet {
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}

/// Runs `f` with a progress bar over `o.photons` on a terminal, unless `hide`.
fn with_bar<T>(
    o: &McOptions,
    hide: bool,
    f: impl FnOnce(&McOptions) -> anyhow::Result<T>,
) -> anyhow::Result<T> {
    let bar = (!hide).then(|| super::progress::bar(o.photons, "photons"));
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
    if let (Some(a), Some(s)) = (r.absorbed_total, r.absorbed_total_se) {
        outln!("absorbed in all layers A  {a:.6} ± {s:.6}")?;
    }
    outln!("∫Rd(r) over the grid      {:.6}", r.rd_r_integrated)?;
    outln!("energy balance            {:.6}", r.energy())?;
    Ok(())
}
