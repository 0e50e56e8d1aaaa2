//! `dyes:` of a fiber spec: each a Gaussian band model or a measured CSV spectrum, of a dye
//! class whose peak extinction it must have (§5.3.1), added to the presets under a new name.

use std::path::Path;

use super::raw::{RawBand, RawDye};
use super::FiberCx;
use crate::fiber::dye::{self, Band, Dye, DyeClass, Spectrum};
use crate::spec::check::{loc, Bounds};
use crate::spec::yaml::Spanned;

/// `bands.peak_nm`: wavelength of a band's peak, nm.
pub(in crate::spec) const PEAK_NM: Bounds = Bounds::closed(300.0, 800.0);
/// `bands.fwhm_nm`: full width at half maximum, nm.
pub(in crate::spec) const FWHM_NM: Bounds = Bounds::closed(1.0, 500.0);
/// `bands.peak_eps_l_per_mg_cm`: extinction at the peak, l mg⁻¹ cm⁻¹.
pub(in crate::spec) const PEAK_EPS: Bounds = Bounds::above(0.0, 1.0);

impl FiberCx {
    /// The presets and the spec's dyes, and the names of the spec's dyes that failed their
    /// checks.
    pub(super) fn dyes(&mut self, raw: &[Spanned<RawDye>], dir: &Path) -> (Vec<Dye>, Vec<String>) {
        let mut dyes = dye::presets();
        // Dyes of the spec that failed their checks: already reported, so a fiber naming one
        // is not told the name is unknown.
        let mut broken: Vec<String> = Vec::new();
        for d in raw {
            let Some(dy) = self.dye(&d.value, dir) else {
                broken.push(d.value.name.value.clone());
                continue;
            };
            if dyes.iter().any(|x| x.name == dy.name) {
                self.invalid(
                    loc(&d.value.name),
                    "dyes.name",
                    format!("{:?} is already defined (presets included)", dy.name),
                );
            } else {
                dyes.push(dy);
            }
        }
        (dyes, broken)
    }

    fn dye(&mut self, d: &RawDye, dir: &Path) -> Option<Dye> {
        let class = self.choice("dyes.class", &d.class, &DyeClass::ALL)?;
        let spectrum = match (&d.bands, &d.csv) {
            (Some(b), None) => Spectrum::Bands(self.bands(b)?),
            (None, Some(c)) => match dye::spectrum_from_csv(&self.data_file(
                c,
                "dyes.csv",
                dir,
                "a CSV of lambda_nm,eps_l_per_mg_cm rows",
            )?) {
                Ok(s) => s,
                Err(m) => {
                    self.invalid(loc(c), "dyes.csv", format!("{}: {m}", c.value));
                    return None;
                }
            },
            _ => {
                self.invalid(
                    loc(&d.name),
                    "dyes",
                    "give exactly one of `bands` (Gaussian band model) or `csv` (lambda_nm,eps_l_per_mg_cm)",
                );
                return None;
            }
        };
        let dye = Dye {
            name: d.name.value.clone(),
            class,
            spectrum,
            source: d
                .source
                .as_ref()
                .map_or_else(|| self.file.clone(), |s| s.value.clone()),
        };
        let (lo, hi) = class.peak_range();
        let peak = dye.peak_eps();
        if !(lo..=hi).contains(&peak) {
            self.out_of_range(
                loc(&d.class),
                &format!("dyes.{}: peak extinction", dye.name),
                format!("{peak:.4} l/(mg·cm)"),
                format!("[{lo}, {hi}] for {} dyes (thesis §5.3.1)", class.name()),
            );
            return None;
        }
        Some(dye)
    }

    /// `bands:`, at least one; `None` at the first band with a value out of range.
    fn bands(&mut self, b: &Spanned<Vec<Spanned<RawBand>>>) -> Option<Vec<Band>> {
        let mut bands = Vec::new();
        for rb in &b.value {
            let r = &rb.value;
            let peak = self.in_bounds("dyes.bands.peak_nm", &r.peak_nm, PEAK_NM);
            let fwhm = self.in_bounds("dyes.bands.fwhm_nm", &r.fwhm_nm, FWHM_NM);
            let eps = self.in_bounds(
                "dyes.bands.peak_eps_l_per_mg_cm",
                &r.peak_eps_l_per_mg_cm,
                PEAK_EPS,
            );
            bands.push(Band {
                peak_nm: peak?,
                fwhm_nm: fwhm?,
                peak_eps_l_per_mg_cm: eps?,
            });
        }
        if bands.is_empty() {
            self.invalid(loc(b), "dyes.bands", "give at least one band");
            return None;
        }
        Some(bands)
    }
}
