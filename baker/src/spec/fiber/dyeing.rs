//! How a fiber is dyed: one dye at a depth of shade ζ (`dye`, `depth_of_shade_percent`), or a
//! `sweep` of every dye × every depth of shade (and undyed) baked from the same trace.

use std::collections::HashMap;

use super::raw::{RawFiber, RawSweep};
use super::{FiberCx, Scope};
use crate::fiber::dye::{self, Dye};
use crate::spec::check::{count_text, loc};
use crate::spec::limits::Limits;
use crate::spec::yaml::Spanned;

/// A dyeing: the dye and its depth of shade ζ (fraction); `None` is the undyed fiber.
type Dyeing = Option<(Dye, f64)>;

impl FiberCx {
    /// `dye` and `depth_of_shade_percent`: both or neither.
    pub(super) fn dye_of(&mut self, r: &RawFiber, sc: &Scope) -> Option<Dyeing> {
        match (&r.dye, &r.depth_of_shade_percent) {
            (Some(name), dos) => {
                let d = self.known_dye(name, "fibers.dye", sc)?;
                let Some(dos) = dos else {
                    self.invalid(
                        loc(name),
                        "fibers.depth_of_shade_percent",
                        "a dyed fiber needs its depth of shade, 0.1–4 % (§5.3.1)",
                    );
                    return None;
                };
                let z = self.depth_of_shade("fibers.depth_of_shade_percent", dos)?;
                Some(Some((d.clone(), z)))
            }
            (None, Some(dos)) => {
                self.invalid(loc(dos), "fibers.depth_of_shade_percent", "set `dye` too");
                None
            }
            (None, None) => Some(None),
        }
    }

    /// The dyeings of `sweep` (undyed first, then each dye at each depth of shade), which
    /// replaces the fiber's own `dye`.
    pub(super) fn sweep_variants(
        &mut self,
        r: &RawFiber,
        sweep: &Spanned<RawSweep>,
        dye: &Dyeing,
        sc: &Scope,
    ) -> Option<Vec<Dyeing>> {
        let sw = &sweep.value;
        let undyed = sw.undyed.as_ref().is_some_and(|u| u.value);
        self.variants_within_limit(sweep, undyed, sc.limits)?;
        let mut variants = Vec::new();
        if undyed {
            variants.push(None);
        }
        self.reject_repeated_depths(sw)?;
        let mut first_dye: HashMap<&str, u64> = Default::default();
        for name in &sw.dyes.value {
            if let Some(first_line) = first_dye.insert(name.value.as_str(), loc(name).0) {
                self.invalid(
                    loc(name),
                    "fibers.sweep.dyes",
                    format!(
                        "{:?} is listed twice (first on line {first_line}); allowed: each dye once",
                        name.value,
                    ),
                );
                return None;
            }
            let d = self.known_dye(name, "fibers.sweep.dyes", sc)?;
            for dos in &sw.depth_of_shade_percent.value {
                let z = self.depth_of_shade("fibers.sweep.depth_of_shade_percent", dos)?;
                variants.push(Some((d.clone(), z)));
            }
        }
        if variants.is_empty() {
            self.invalid(
                loc(&r.name),
                "fibers.sweep",
                "the sweep lists no dye or depth of shade",
            );
            return None;
        }
        if let (Some(_), Some(d)) = (dye, &r.dye) {
            self.invalid(
                loc(sweep),
                "fibers.sweep",
                format!("give `dye` (line {}) or `sweep`, not both", loc(d).0),
            );
            return None;
        }
        Some(variants)
    }

    /// Counted before any is built: every dye × every depth of shade (+ undyed), against
    /// `limits.variants`.
    fn variants_within_limit(
        &mut self,
        sweep: &Spanned<RawSweep>,
        undyed: bool,
        limits: &Limits,
    ) -> Option<()> {
        let sw = &sweep.value;
        let n = (sw.dyes.value.len() as u64)
            .saturating_mul(sw.depth_of_shade_percent.value.len() as u64)
            .saturating_add(u64::from(undyed));
        if n <= limits.variants {
            return Some(());
        }
        self.over_limit(
            loc(sweep),
            "fibers.sweep",
            format!(
                "{} dyes × {} depths of shade{} are {} variants",
                count_text(sw.dyes.value.len() as u64),
                count_text(sw.depth_of_shade_percent.value.len() as u64),
                if undyed { " + undyed" } else { "" },
                count_text(n)
            ),
            "variants",
            count_text(limits.variants),
        );
        None
    }

    /// Each depth of shade of a sweep once.
    fn reject_repeated_depths(&mut self, sw: &RawSweep) -> Option<()> {
        let mut first_dos: HashMap<u64, u64> = Default::default();
        for dos in &sw.depth_of_shade_percent.value {
            if let Some(l) = first_dos.insert(dos.value.to_bits(), loc(dos).0) {
                self.invalid(
                    loc(dos),
                    "fibers.sweep.depth_of_shade_percent",
                    format!(
                        "{} is listed twice (first on line {l}); allowed: each depth of shade once",
                        dos.value
                    ),
                );
                return None;
            }
        }
        Some(())
    }

    /// The dye `name` names, among the presets and the spec's dyes; a dye of the spec that
    /// failed its checks is already reported.
    fn known_dye<'a>(
        &mut self,
        name: &Spanned<String>,
        field: &str,
        sc: &Scope<'a>,
    ) -> Option<&'a Dye> {
        if let Some(d) = sc.dyes.iter().find(|d| d.name == name.value) {
            return Some(d);
        }
        if sc.broken.contains(&name.value) {
            return None;
        }
        let names: Vec<&str> = sc.dyes.iter().map(|d| d.name.as_str()).collect();
        self.unknown_name(
            field,
            name,
            &names,
            "the presets (baker/src/fiber/data/dye_presets.csv) and the spec's `dyes:` list them",
        );
        None
    }

    /// A depth of shade in percent within §5.3.1's range, as a fraction ζ.
    fn depth_of_shade(&mut self, field: &str, dos: &Spanned<f64>) -> Option<f64> {
        let z = self.in_range(
            field,
            dos,
            100.0 * dye::DOS_RANGE.0,
            100.0 * dye::DOS_RANGE.1,
            false,
        )?;
        Some(z / 100.0)
    }
}
