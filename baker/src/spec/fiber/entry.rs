//! A resolved fiber entry: its type, cross-section (and the population of seeded variants a
//! bake traces), surface, dyeings and symmetries, and the fiber and absorption it gives.

use std::path::PathBuf;

use crate::fiber::dye::Dye;
use crate::fiber::material::FiberType;
use crate::fiber::section::generate::{generate, Shape};
use crate::fiber::slices::{BakeSettings, Estimators};
use crate::fiber::symmetry::Symmetry;
use crate::fiber::{Cuticle, Fiber, Section, Surface};

/// Where a section came from.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SectionSource {
    Generator {
        shape: Shape,
        seed: u64,
        variant: u64,
    },
    Ellipse {
        ratio: f64,
    },
    Polygon {
        file: PathBuf,
    },
    Mask {
        file: PathBuf,
        um_per_px: f64,
    },
}

/// One fiber of a spec, resolved.
#[derive(Debug, Clone)]
pub struct FiberEntry {
    pub name: String,
    pub line: u64,
    pub fiber_type: &'static FiberType,
    pub source: SectionSource,
    pub diameter_um: f64,
    pub eta: f64,
    pub beta_deg: f64,
    pub section: Section,
    pub cuticle: Option<Cuticle>,
    /// The dye and its depth of shade ζ (fraction).
    pub dye: Option<(Dye, f64)>,
    /// Seeded cross-sections baked for this entry (variants `variant`, `variant + 1`, …).
    pub sections: u64,
    /// The dyeings baked from one trace: `None` is the undyed fiber.
    pub variants: Vec<Option<(Dye, f64)>>,
    /// `auto`: detect the symmetries; `none`: trace every incoming direction.
    pub symmetry: SymmetryMode,
    /// Every cross-section baked (`sections` of them, the first is [`FiberEntry::section`]),
    /// built by the resolver so a bake cannot fail on one.
    pub population: Vec<Section>,
    /// The symmetries the bake uses (those every section shares, on the bake's grid; none
    /// with `symmetry: none`).
    pub symmetries: Symmetry,
    /// Incoming directions the tables store after symmetry reduction.
    pub stored_directions: usize,
    /// How this fiber's photons are scored: its `estimators:` over the spec's `bake:`.
    pub estimators: Estimators,
}

impl FiberEntry {
    /// The settings this fiber bakes with: `bake` (the spec's, with any command-line
    /// overrides) with the fiber's own estimators. A fiber whose photons cannot be shared
    /// across θi (cuticle scales or a smooth boundary,
    /// [`crate::fiber::tracer::shared::shares`]) has `share_theta` 1: each direction is
    /// traced alone, and the manifest and tables say so.
    pub fn settings(&self, bake: &BakeSettings) -> BakeSettings {
        let mut st = bake.with_estimators(self.estimators);
        let shares = crate::fiber::tracer::shared::shares(&self.surface(), self.cuticle.as_ref());
        if st.share_theta > 1 && !shares {
            st.share_theta = 1;
        }
        st
    }

    pub fn fiber(&self) -> Fiber {
        self.fiber_with(self.section.clone())
    }

    /// Cross-section `s` of the entry's population (0 is [`FiberEntry::section`]): the
    /// generator's next variants, scaled to the same mean width.
    pub fn section_variant(&self, s: u64) -> Result<Section, String> {
        if s == 0 {
            return Ok(self.section.clone());
        }
        match &self.source {
            SectionSource::Generator {
                shape,
                seed,
                variant,
            } => generate(*shape, 1.0, *seed, variant + s)
                .and_then(|x| x.scaled_to_diameter(self.diameter_um))
                .map_err(|e| e.to_string()),
            _ => Err("only generated sections have variants".into()),
        }
    }

    /// The fiber with another cross-section of the population.
    pub fn fiber_with(&self, section: Section) -> Fiber {
        Fiber {
            section,
            surface: self.surface(),
            cuticle: self.cuticle,
        }
    }

    /// The fiber's boundary: refractive index and Beckmann slope α = tan β.
    pub fn surface(&self) -> Surface {
        Surface {
            eta: self.eta,
            alpha: self.beta_deg.to_radians().tan(),
        }
    }

    /// μa(λ) of the dyed fiber, per µm (0 undyed).
    pub fn mua_per_um(&self, lambda_nm: f64) -> f64 {
        self.variant_mua_per_um(self.dye.as_ref(), lambda_nm)
    }

    /// μa(λ) of the fiber dyed with `dye` at its depth of shade, per µm (Eq. of §5.3.1:
    /// μa = ρ·ζ·ε).
    pub fn variant_mua_per_um(&self, dye: Option<&(Dye, f64)>, lambda_nm: f64) -> f64 {
        dye.map_or(0.0, |(d, dos)| {
            d.mua_per_mm(lambda_nm, self.fiber_type.density_g_per_cm3, *dos) * 1e-3
        })
    }

    /// Name of a dyeing: `undyed` or `<dye>@<DoS>%`.
    pub fn variant_name(v: Option<&(Dye, f64)>) -> String {
        v.map_or("undyed".into(), |(d, z)| {
            format!("{}@{}%", d.name, z * 100.0)
        })
    }
}

/// How the bake finds the fiber's symmetries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SymmetryMode {
    Auto,
    None,
}
