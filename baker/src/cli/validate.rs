//! `baker validate`: a spec checked as `baker bake` checks it, and what it defines.

/// `baker validate`: the checks `baker bake` makes before it writes anything — the same code
/// path — and what the spec defines.
pub fn run(spec: &std::path::Path) -> anyhow::Result<()> {
    let (s, cost) = crate::bake::load_checked(spec, &crate::spec::budget::Overrides::none())?;
    crate::bake::spec_stem(spec)?;
    match &s {
        crate::spec::Spec::Fiber(s) => {
            outln!(
                "{}: ok, {} fibers, {} dyes (presets included); {}",
                spec.display(),
                s.fibers.len(),
                s.dyes.len(),
                cost.describe()
            )?;
            for f in &s.fibers {
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
            for e in &s.entries {
                outln!("  {} (line {})", e.name, e.line)?;
            }
        }
    }
    Ok(())
}
