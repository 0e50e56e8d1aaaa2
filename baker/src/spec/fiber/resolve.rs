//! The fiber resolver's steps over the whole spec (dyes, the cross-section budget, bake
//! settings, every fiber and their names) and over one fiber, in the order its fields are
//! checked.

use super::entry::{FiberEntry, SectionSource, SymmetryMode};
use super::raw::{RawFiber, RawFiberSpec};
use super::section::Seeds;
use super::{FiberCx, FiberSpec, Scope};
use crate::fiber::material::{FiberType, TABLE_9};
use crate::fiber::slices::BakeSettings;
use crate::fiber::symmetry::Symmetry;
use crate::spec::check::{count_text, duplicate_message, loc, Bounds};
use crate::spec::limits::Limits;
use crate::spec::names;
use crate::spec::yaml::Spanned;

/// `fibers.seed`: any whole number an f64 holds exactly (up to 2^53).
pub(in crate::spec) const SEED: Bounds = Bounds::whole(0.0, 9_007_199_254_740_992.0);
/// `fibers.variant`: which fiber of the seeded population.
pub(in crate::spec) const VARIANT: Bounds = Bounds::whole(0.0, 1e6);
/// `fibers.eta`: refractive index of the fiber.
pub(in crate::spec) const ETA: Bounds = Bounds::above(1.0, 3.0);
/// `fibers.sections`: seeded cross-sections baked into one table.
pub(in crate::spec) const SECTIONS: Bounds = Bounds::whole(1.0, 64.0);
/// `fibers.symmetry`.
pub(in crate::spec) const SYMMETRY: [(&str, SymmetryMode); 2] =
    [("auto", SymmetryMode::Auto), ("none", SymmetryMode::None)];

impl FiberCx {
    pub(super) fn fiber_spec(&mut self, raw: RawFiberSpec, dir: &std::path::Path) -> FiberSpec {
        self.version(&raw.version);
        let limits = self.limits(raw.limits.as_ref());
        let (dyes, broken) = self.dyes(&raw.dyes, dir);
        let within = self.sections_within_limit(&raw.fibers, &limits);
        let bake = raw
            .bake
            .as_ref()
            .map_or_else(BakeSettings::default, |b| self.bake(&b.value, &limits));
        let storage = raw
            .bake
            .as_ref()
            .map_or_else(Default::default, |b| self.storage(&b.value));
        let sc = Scope {
            dyes: &dyes,
            broken: &broken,
            dir,
            bake: &bake,
            limits: &limits,
        };
        let mut fibers: Vec<FiberEntry> = Vec::new();
        for f in raw.fibers.iter().filter(|_| within) {
            if let Some(e) = self.fiber(f, &sc) {
                if let Some(first) = fibers.iter().find(|x| x.name.eq_ignore_ascii_case(&e.name)) {
                    self.invalid(
                        loc(&f.value.name),
                        "fibers.name",
                        duplicate_message(&e.name, &first.name, first.line),
                    );
                } else {
                    fibers.push(e);
                }
            }
        }
        if raw.fibers.is_empty() {
            self.invalid((1, 1), "fibers", "the spec lists no fibers");
        }
        let photons_at = raw
            .bake
            .as_ref()
            .and_then(|b| b.value.photons_per_direction.as_ref().map(loc))
            .unwrap_or((1, 1));
        FiberSpec {
            file: self.file.clone(),
            dyes,
            fibers,
            bake,
            storage,
            limits,
            photons_at,
            sha256: String::new(),
        }
    }

    /// Whether the fibers are resolved: each cross-section of each fiber is built, measured
    /// and checked for symmetry here, so they count as entries (counted before any is built).
    fn sections_within_limit(&mut self, fibers: &[Spanned<RawFiber>], limits: &Limits) -> bool {
        let sections: f64 = fibers
            .iter()
            .map(|f| {
                f.value
                    .sections
                    .as_ref()
                    .map_or(1.0, |s| s.value.clamp(SECTIONS.lo, SECTIONS.hi))
            })
            .sum();
        let within = sections <= limits.entries as f64;
        if !within {
            self.over_limit(
                (1, 1),
                "fibers",
                format!(
                    "the spec lists {} fibers with {} cross-sections",
                    count_text(fibers.len() as u64),
                    count_text(sections as u64)
                ),
                "entries",
                count_text(limits.entries),
            );
        }
        within
    }

    /// One fiber entry; `None` (with the error recorded) at its first wrong field.
    fn fiber(&mut self, f: &Spanned<RawFiber>, sc: &Scope) -> Option<FiberEntry> {
        let r = &f.value;
        if let Err(m) = names::check(&r.name.value) {
            self.invalid(
                loc(&r.name),
                "fibers.name",
                names::message(&r.name.value, &m),
            );
            return None;
        }
        let types: Vec<(&str, &'static FiberType)> = TABLE_9.iter().map(|t| (t.name, t)).collect();
        let ft: &'static FiberType = self.choice("fibers.type", &r.kind, &types)?;
        let seeds = Seeds {
            seed: self.count("fibers.seed", &r.seed, SEED.lo, SEED.hi, 1),
            variant: self.count("fibers.variant", &r.variant, VARIANT.lo, VARIANT.hi, 0),
        };
        let diameter_um = self.diameter_um(r, ft, seeds)?;
        let eta = self.opt_bounds("fibers.eta", &r.eta, ETA, ft.eta());
        let beta_deg = self.beta_deg(r, ft)?;
        let (source, section) = self.sized_section(r, ft, seeds, diameter_um, sc)?;
        let diameter_um = section.mean_width_um();
        let cuticle = self.cuticle(r, ft);
        let dye = self.dye_of(r, sc)?;
        let sections = self.count("fibers.sections", &r.sections, SECTIONS.lo, SECTIONS.hi, 1);
        if sections > 1 && !matches!(source, SectionSource::Generator { .. }) {
            self.invalid(
                loc(r.sections.as_ref().unwrap()),
                "fibers.sections",
                "several sections need a generated `shape` (a polygon or mask is one section)",
            );
            return None;
        }
        let variants = match &r.sweep {
            Some(sweep) => self.sweep_variants(r, sweep, &dye, sc)?,
            None => vec![dye.clone()],
        };
        // With a sweep, the entry's representative dyeing (what `fiber trace` and `validate`
        // use) is its first dyed variant.
        let dye = dye.or_else(|| variants.iter().flatten().next().cloned());
        let symmetry = match &r.symmetry {
            Some(sy) => self.choice("fibers.symmetry", sy, &SYMMETRY)?,
            None => SymmetryMode::Auto,
        };
        let estimators = match &r.estimators {
            Some(x) => self.estimators(&x.value, sc.bake),
            None => sc.bake.estimators(),
        };
        let mut e = FiberEntry {
            sections,
            variants,
            symmetry,
            name: r.name.value.clone(),
            line: loc(f).0,
            fiber_type: ft,
            source,
            diameter_um,
            eta,
            beta_deg,
            section: section.clone(),
            cuticle,
            dye,
            population: vec![section],
            symmetries: Symmetry::NONE,
            stored_directions: 0,
            estimators,
        };
        self.populate(r, &mut e)?;
        self.population_costs(loc(f), &mut e, sc.bake, sc.limits)?;
        Some(e)
    }
}
