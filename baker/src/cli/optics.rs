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
    /// Spec file (YAML).
    pub spec: PathBuf,
    /// Only this entry (default: all).
    #[arg(long)]
    pub entry: Option<String>,
    /// Print one JSON document (format `baker.skin-optics`, see formats/FORMAT.md) to stdout.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Write one CSV per entry into DIR.
    #[arg(long, value_name = "DIR")]
    pub csv: Option<PathBuf>,
    /// Write PNG plots of μa(λ) and μs′(λ) per entry into DIR.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Write an MCML input file (.mci) for --entry at this wavelength (nm, on the spec's grid).
    #[arg(long, value_name = "LAMBDA_NM", requires = "entry")]
    pub mci: Option<f64>,
    /// Where to write the .mci file (default: <entry>_<λ>nm.mci).
    #[arg(long, value_name = "FILE", requires = "mci")]
    pub mci_out: Option<PathBuf>,
    /// Photons written into the .mci file.
    #[arg(long, default_value_t = 1_000_000, requires = "mci")]
    pub photons: u64,
}

/// Evaluates the model for the selected entries of `spec`.
pub fn evaluate_entries(
    spec: &SkinSpec,
    only: Option<&str>,
) -> anyhow::Result<Vec<formats::OpticsEntry>> {
    let selected: Vec<_> = spec
        .entries
        .iter()
        .filter(|e| only.is_none_or(|n| e.name == n))
        .collect();
    if selected.is_empty() {
        let names: Vec<&str> = spec.entries.iter().map(|e| e.name.as_str()).collect();
        let name = only.unwrap_or("");
        return Err(UsageError(crate::spec::names::unknown_entry(&spec.file, name, &names)).into());
    }
    Ok(crate::bake::skin::optics_of(spec, |e| {
        only.is_none_or(|n| e.name == n)
    }))
}

pub fn run(a: OpticsArgs) -> anyhow::Result<()> {
    let spec = load_spec(&a.spec)?;
    let entries = evaluate_entries(&spec, a.entry.as_deref())?;
    let lam = spec.wavelengths.lambda_nm();
    let mut wrote_files = false;
    if let Some(dir) = &a.csv {
        for e in &entries {
            let p = dir.join(format!("{}.csv", e.name));
            atomic::write(&p, output::csv::entry_csv(lam, e).as_bytes())
                .with_context(|| format!("writing {}", p.display()))?;
            eprintln!("wrote {}", p.display());
        }
        wrote_files = true;
    }
    if let Some(dir) = &a.plot {
        write_plots(dir, lam, &entries)?;
        wrote_files = true;
    }
    if let Some(lambda) = a.mci {
        let e = &entries[0];
        let i = wavelength_index(&spec, lambda, "--mci")?;
        let path = a
            .mci_out
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("{}_{}nm.mci", e.name, lambda)));
        let mco = path
            .with_extension("mco")
            .file_name()
            .unwrap()
            .to_string_lossy()
            .to_string();
        let text = output::mci::mci(e, i, lambda, &MciRun::new(mco, a.photons));
        atomic::write(&path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        eprintln!("wrote {}", path.display());
        wrote_files = true;
    }
    if a.json {
        let doc = crate::skin::document::document(&spec.file, lam, entries);
        outln!("{}", serde_json::to_string_pretty(&doc)?)?;
    } else if !wrote_files {
        out!("{}", text_report(lam, &entries))?;
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

pub fn write_plots(
    dir: &Path,
    lam: &[f64],
    entries: &[formats::OpticsEntry],
) -> anyhow::Result<()> {
    for p in output::plot::optics_plots(dir, lam, entries)? {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
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
