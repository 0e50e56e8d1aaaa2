//! `baker bake`: every product of every entry of the given specs, written atomically.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;

use super::load_spec;
use crate::output::{self, atomic};

#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Spec files (YAML).
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Output root; each spec bakes into OUT/<spec name>/.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Also write PNG plots of every entry's coefficients.
    #[arg(long)]
    pub plots: bool,
}

pub fn run(a: BakeArgs) -> anyhow::Result<()> {
    // Validate every spec before writing anything.
    let specs = a
        .specs
        .iter()
        .map(|p| load_spec(p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    for (path, spec) in a.specs.iter().zip(&specs) {
        let t0 = Instant::now();
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_else(|| "spec".into());
        let dir = a.out.join(&stem);
        let entries = super::optics::evaluate_entries(spec, None)?;
        let lam = spec.wavelengths.lambda_nm();
        for e in &entries {
            let p = dir.join("optics").join(format!("{}.csv", e.name));
            atomic::write(&p, output::csv::entry_csv(lam, e).as_bytes())
                .with_context(|| format!("writing {}", p.display()))?;
        }
        if a.plots {
            super::optics::write_plots(&dir.join("plots"), lam, &entries)?;
        }
        let n = entries.len();
        let doc = output::document::document(&spec.file, lam, entries);
        let p = dir.join("optics.json");
        atomic::write(&p, serde_json::to_string_pretty(&doc)?.as_bytes())
            .with_context(|| format!("writing {}", p.display()))?;
        eprintln!(
            "baked {}: {n} entries × {} wavelengths → {} ({:.2} s)",
            path.display(),
            lam.len(),
            dir.display(),
            t0.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
