//! `baker validate`: specs checked as `baker bake` checks them, and what they define.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::bake::Request;

#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// Spec files (YAML); every one is checked, and every error of each is listed.
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Check that this entry exists (repeatable) and list only the entries asked for.
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Print nothing when the specs are valid (the exit code says it: 0 valid, 2 not).
    #[arg(short, long)]
    pub quiet: bool,
}

/// `baker validate`: the checks `baker bake` makes before it writes anything — the same code
/// path, including the entry names a bake would be asked for — and what the specs define.
pub fn run(a: ValidateArgs) -> anyhow::Result<()> {
    let req = Request {
        specs: a.specs.clone(),
        entries: a.entries.clone(),
        ..Request::default()
    };
    let (mut specs, mut costs) = (Vec::new(), Vec::new());
    for path in &a.specs {
        let (s, cost) = crate::bake::load_checked(path, &req.overrides())?;
        crate::bake::spec_stem(path)?;
        specs.push(s);
        costs.push(cost);
    }
    crate::bake::check_entries(&req, &specs)?;
    if a.quiet {
        return Ok(());
    }
    for ((path, s), cost) in a.specs.iter().zip(&specs).zip(&costs) {
        describe(path, s, cost, &req)?;
    }
    Ok(())
}

/// What one valid spec defines: its entries (those `req` selects) and its cost.
fn describe(
    spec: &Path,
    s: &crate::spec::Spec,
    cost: &crate::spec::budget::Cost,
    req: &Request,
) -> anyhow::Result<()> {
    match s {
        crate::spec::Spec::Fiber(s) => {
            outln!(
                "{}: ok, {} fibers, {} dyes (presets included); {}",
                spec.display(),
                s.fibers.len(),
                s.dyes.len(),
                cost.describe()
            )?;
            for f in s.fibers.iter().filter(|f| req.selects(&f.name)) {
                outln!(
                    "  {} (line {}): {}, {:.2} µm, area {:.1} µm², {} hole(s), η {:.4}, β {:.2}°{}{}",
                    f.name,
                    f.line,
                    f.fiber_type.name,
                    f.diameter_um,
                    f.section.area_um2(),
                    f.section.hole_count(),
                    f.eta,
                    f.beta_deg,
                    f.cuticle.map_or(String::new(), |c| format!(
                        ", cuticle {} µm × {}°",
                        c.length_um, c.tilt_deg
                    )),
                    f.dye.as_ref().map_or(String::new(), |(d, z)| format!(
                        ", {} at {}% (μa(550 nm) = {:.3} /mm)",
                        d.name,
                        z * 100.0,
                        f.mua_per_um(550.0) * 1e3
                    )),
                )?;
            }
        }
        crate::spec::Spec::Skin(s) => {
            outln!(
                "{}: ok, {} entries, {} wavelengths ({}–{} nm); {}",
                spec.display(),
                s.entries.len(),
                s.wavelengths.len(),
                s.wavelengths.lambda_nm()[0],
                s.wavelengths.lambda_nm()[s.wavelengths.len() - 1],
                cost.describe()
            )?;
            for e in s.entries.iter().filter(|e| req.selects(&e.name)) {
                outln!("  {} (line {})", e.name, e.line)?;
            }
        }
    }
    Ok(())
}
