//! `baker optics`: print or write per-layer optical properties.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use crate::error::UsageError;
use crate::output::{self, atomic, mci::MciRun};
use crate::spec::SkinSpec;

#[derive(Debug, Args)]
pub struct OpticsArgs {
    /// Skin spec files (YAML).
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Only this entry (repeatable; default: all).
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Print one JSON document per spec (format `baker.skin-optics`, see formats/FORMAT.md) to
    /// stdout; with several specs, one document per line.
    #[arg(long)]
    pub json: bool,
    /// Write one CSV per entry into the output folder.
    #[arg(long)]
    pub csv: bool,
    /// Write PNG plots of μa(λ) and μs′(λ) per entry into the output folder.
    #[arg(long)]
    pub plots: bool,
    /// Write an MCML input file (.mci) per entry at this wavelength (nm, on the spec's grid),
    /// named `<entry>_<λ>nm.mci`, into the output folder.
    #[arg(long, value_name = "LAMBDA_NM")]
    pub mci: Option<f64>,
    /// Photons written into the .mci file.
    #[arg(long, default_value_t = 1_000_000, requires = "mci")]
    pub photons: u64,
    /// Output folder of --csv, --plots and --mci, created if needed (default: the current
    /// directory).
    #[arg(short = 'o', long, value_name = "DIR", default_value = ".")]
    pub out: PathBuf,
    /// No "wrote" lines on stderr (errors still go there).
    #[arg(short, long)]
    pub quiet: bool,
}

/// Evaluates the model for the entries of `spec` that `only` names (all when empty); a name
/// that is not in the spec is a usage error.
pub fn evaluate_entries(
    spec: &SkinSpec,
    only: &[String],
) -> anyhow::Result<Vec<formats::OpticsEntry>> {
    let names: Vec<&str> = spec.entries.iter().map(|e| e.name.as_str()).collect();
    for name in only {
        if !names.contains(&name.as_str()) {
            return Err(
                UsageError(crate::spec::names::unknown_entry(&spec.file, name, &names)).into(),
            );
        }
    }
    let selects = |n: &str| only.is_empty() || only.iter().any(|o| o == n);
    Ok(crate::bake::skin::optics_of(spec, |e| selects(&e.name)))
}

pub fn run(a: OpticsArgs) -> anyhow::Result<()> {
    // Every spec and entry name is checked before anything is written.
    let all = a
        .specs
        .iter()
        .map(|p| load_spec(p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let names: Vec<&str> = (all.iter())
        .flat_map(|s| s.entries.iter().map(|e| e.name.as_str()))
        .collect();
    if let Some(missing) = a.entries.iter().find(|n| !names.contains(&n.as_str())) {
        let files: Vec<&str> = all.iter().map(|s| s.file.as_str()).collect();
        let msg = crate::spec::names::unknown_entry(&files.join(", "), missing, &names);
        return Err(UsageError(msg).into());
    }
    let loaded: Vec<&SkinSpec> = (all.iter())
        .filter(|s| a.entries.is_empty() || s.entries.iter().any(|e| a.entries.contains(&e.name)))
        .collect();
    for spec in loaded.iter().copied() {
        if let Some(lambda) = a.mci {
            wavelength_index(spec, lambda, "--mci")?;
        }
    }
    for spec in loaded {
        let here: Vec<String> = (a.entries.iter())
            .filter(|n| spec.entries.iter().any(|e| &e.name == *n))
            .cloned()
            .collect();
        let entries = evaluate_entries(spec, &here)?;
        report(&a, spec, &entries)?;
    }
    Ok(())
}

/// The outputs `a` asks for, of one spec's evaluated entries.
fn report(a: &OpticsArgs, spec: &SkinSpec, entries: &[formats::OpticsEntry]) -> anyhow::Result<()> {
    let lam = spec.wavelengths.lambda_nm();
    let note = |p: &Path| {
        if !a.quiet {
            eprintln!("wrote {}", p.display());
        }
    };
    if a.csv {
        for e in entries {
            let p = a.out.join(format!("{}.csv", e.name));
            atomic::write(&p, output::csv::entry_csv(lam, e).as_bytes())
                .with_context(|| format!("writing {}", p.display()))?;
            note(&p);
        }
    }
    if a.plots {
        for p in output::plot::optics_plots(&a.out, lam, entries)? {
            note(&p);
        }
    }
    if let Some(lambda) = a.mci {
        let i = wavelength_index(spec, lambda, "--mci")?;
        for e in entries {
            let name = format!("{}_{}nm", e.name, lambda);
            let path = a.out.join(format!("{name}.mci"));
            let text =
                output::mci::mci(e, i, lambda, &MciRun::new(format!("{name}.mco"), a.photons));
            atomic::write(&path, text.as_bytes())
                .with_context(|| format!("writing {}", path.display()))?;
            note(&path);
        }
    }
    if a.json {
        let doc = crate::skin::document::document(&spec.file, lam, entries.to_vec());
        outln!("{}", serde_json::to_string(&doc)?)?;
    } else if !(a.csv || a.plots || a.mci.is_some()) {
        out!("{}", text_report(lam, entries))?;
    }
    Ok(())
}

/// Index of `lambda_nm` on the spec's wavelength grid, or a usage error naming `flag`.
pub fn wavelength_index(spec: &SkinSpec, lambda_nm: f64, flag: &str) -> anyhow::Result<usize> {
    let lam = spec.wavelengths.lambda_nm();
    lam.iter()
        .position(|&l| (l - lambda_nm).abs() < 1e-9)
        .ok_or_else(|| {
            UsageError(format!(
                "{flag} {lambda_nm}: not on the spec's wavelength grid ({}–{} nm, {} values)",
                lam[0],
                lam[lam.len() - 1],
                lam.len()
            ))
            .into()
        })
}

/// Human-readable listing: structure, junction and surface, then a λ table per entry.
pub fn text_report(lam: &[f64], entries: &[formats::OpticsEntry]) -> String {
    let mut s = String::new();
    for e in entries {
        let _ = writeln!(s, "entry {} ({})", e.name, e.model);
        for l in &e.layers {
            let _ = writeln!(s, "  {:<18} d_mm {:>8.4}  eta {:.3}", l.name, l.d_mm, l.eta);
        }
        let j = &e.junction;
        let _ = writeln!(
            s,
            "  junction (Eq. 1)   z_mean_mm {:.4}  amplitude_mm {:.4}  period_mm {:.4}",
            j.z_mean_mm,
            j.amplitude_mm,
            2.0 * std::f64::consts::PI / j.omega_x_per_mm
        );
        let f = &e.surface;
        let _ = writeln!(
            s,
            "  surface            Rz {:.1} µm  sebum {:.3} mg/10cm²/3h  Beckmann m {:.4}  F0 {:.4}",
            f.rz_um, f.sebum_mg_per_10cm2_3h, f.beckmann_m, f.f0
        );
        let _ = write!(s, "  {:>6}", "λ nm");
        for l in &e.layers {
            let short: String = l
                .name
                .split(' ')
                .map(|w| w.chars().next().unwrap().to_ascii_uppercase())
                .collect();
            let _ = write!(
                s,
                " {:>10} {:>10}",
                format!("μa {short}"),
                format!("μs′ {short}")
            );
        }
        s.push('\n');
        for (i, l) in lam.iter().enumerate() {
            let _ = write!(s, "  {l:>6}");
            for layer in &e.layers {
                let _ = write!(
                    s,
                    " {:>10.4} {:>10.4}",
                    layer.mua_per_mm[i], layer.musp_per_mm[i]
                );
            }
            s.push('\n');
        }
        s.push('\n');
    }
    s
}

/// Loads a spec; its errors become a [`UsageError`] listing every problem.
pub fn load_spec(path: &std::path::Path) -> anyhow::Result<crate::spec::SkinSpec> {
    crate::spec::load(path).map_err(|e| UsageError(e.to_string().trim_end().to_string()).into())
}
