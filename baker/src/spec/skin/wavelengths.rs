//! `wavelengths:` of a skin spec: a list (`list_nm`, rising) or a range (`start_nm`,
//! `stop_nm`, `step_nm`) within the embedded spectra, counted against `limits.wavelengths`.

use super::cx::SkinCx;
use super::raw::{RawSpec, RawWavelengths};
use super::types::LAMBDA_RANGE_NM;
use crate::spec::check::{count_text, loc, Bounds};
use crate::spec::limits::{wavelength_count, Limits};
use crate::spec::yaml::Spanned;
use crate::spectral::WavelengthGrid;

/// `wavelengths.start_nm`, `stop_nm` and each of `list_nm`: the embedded spectra, nm.
pub(in crate::spec) const LAMBDA_NM: Bounds = Bounds::closed(LAMBDA_RANGE_NM.0, LAMBDA_RANGE_NM.1);
/// `wavelengths.step_nm`, nm: positive, at most the whole range.
pub(in crate::spec) const STEP_NM: Bounds =
    Bounds::above(0.0, LAMBDA_RANGE_NM.1 - LAMBDA_RANGE_NM.0);

impl SkinCx {
    pub(super) fn wavelengths(&mut self, raw: &RawSpec, limits: &Limits) -> WavelengthGrid {
        let Some(w) = &raw.wavelengths else {
            return WavelengthGrid::thesis_default();
        };
        let v = &w.value;
        if let Some(list) = &v.list_nm {
            return self.wavelength_list(v, list, limits);
        }
        self.wavelength_range(w, limits)
    }

    /// `list_nm`: each in range and above the one before.
    fn wavelength_list(
        &mut self,
        v: &RawWavelengths,
        list: &Spanned<Vec<Spanned<f64>>>,
        limits: &Limits,
    ) -> WavelengthGrid {
        let hi = LAMBDA_NM.hi;
        let range = [&v.start_nm, &v.stop_nm, &v.step_nm];
        if let Some(other) = range.iter().find_map(|x| x.as_ref()) {
            self.invalid(
                loc(list),
                "wavelengths.list_nm",
                format!(
                    "give either list_nm or start_nm/stop_nm/step_nm, not both (a range \
                     field is on line {})",
                    loc(other).0
                ),
            );
        }
        let mut out = Vec::new();
        for x_at in &list.value {
            if let Some(x) = self.in_bounds("wavelengths.list_nm", x_at, LAMBDA_NM) {
                if let Some(&p) = out.last().filter(|&&p| x <= p) {
                    self.out_of_range(
                        loc(x_at),
                        "wavelengths.list_nm",
                        x.to_string(),
                        format!("above the previous wavelength, ({p}, {hi}]"),
                    );
                }
                out.push(x);
            }
        }
        if out.is_empty() {
            self.invalid(loc(list), "wavelengths.list_nm", "empty list");
            return WavelengthGrid::thesis_default();
        }
        if out.len() as u64 > limits.wavelengths {
            self.over_limit(
                loc(list),
                "wavelengths.list_nm",
                format!("{} wavelengths", count_text(out.len() as u64)),
                "wavelengths",
                count_text(limits.wavelengths),
            );
            return WavelengthGrid::thesis_default();
        }
        WavelengthGrid::from_list(out)
    }

    /// `start_nm`, `stop_nm`, `step_nm` (400, 700 and 10 nm by default).
    fn wavelength_range(&mut self, w: &Spanned<RawWavelengths>, limits: &Limits) -> WavelengthGrid {
        let (lo, hi) = (LAMBDA_NM.lo, LAMBDA_NM.hi);
        let v = &w.value;
        let start = self.opt_bounds("wavelengths.start_nm", &v.start_nm, LAMBDA_NM, 400.0);
        let stop = self.opt_bounds("wavelengths.stop_nm", &v.stop_nm, LAMBDA_NM, 700.0);
        let step = self.opt_bounds("wavelengths.step_nm", &v.step_nm, STEP_NM, 10.0);
        if stop < start {
            match (&v.stop_nm, &v.start_nm) {
                (Some(s), _) => self.out_of_range(
                    loc(s),
                    "wavelengths.stop_nm",
                    stop.to_string(),
                    format!("[{start}, {hi}] (not below start_nm = {start})"),
                ),
                (None, Some(s)) => self.out_of_range(
                    loc(s),
                    "wavelengths.start_nm",
                    start.to_string(),
                    format!("[{lo}, {stop}] (not above the default stop_nm = {stop})"),
                ),
                (None, None) => {}
            }
            return WavelengthGrid::thesis_default();
        }
        let n = wavelength_count(start, stop, step);
        if n > limits.wavelengths as f64 {
            let at = v.step_nm.as_ref().map_or_else(|| loc(w), loc);
            self.too_many_wavelengths(at, "wavelengths.step_nm", (start, stop, step), n, limits);
            return WavelengthGrid::thesis_default();
        }
        WavelengthGrid::uniform(start, stop, step)
    }
}
