//! `bake:` of a fiber spec: how `baker bake` tabulates the BCSDFs (angular resolution,
//! photons, seed, split, precision and kept mantissa bits, channels, spectrum), each with the
//! default of [`BakeSettings`] when absent or wrong.

use super::raw::{RawBake, RawLambda};
use super::FiberCx;
use crate::fiber::slices::BakeSettings;
use crate::fiber::sweep::ChannelKind;
use crate::spec::check::loc;
use crate::spec::limits::{wavelength_count, Limits};
use crate::spec::yaml::Spanned;
use formats::Precision;

impl FiberCx {
    pub(super) fn bake(&mut self, b: &RawBake, limits: &Limits) -> BakeSettings {
        let d = BakeSettings::default();
        let res_deg = match &b.resolution_deg {
            Some(r) => self.resolution_deg(r).unwrap_or(d.res_deg),
            None => d.res_deg,
        };
        let photons = self.count(
            "bake.photons_per_direction",
            &b.photons_per_direction,
            1.0,
            1e12,
            d.photons,
        );
        let seed = self.count("bake.seed", &b.seed, 0.0, 2f64.powi(53), d.seed);
        let split = self.count("bake.split", &b.split, 1.0, 64.0, d.split as u64) as u32;
        let precision = match &b.precision {
            Some(p) => self
                .choice(
                    "bake.precision",
                    p,
                    &[("f16", Precision::F16), ("f32", Precision::F32)],
                )
                .unwrap_or(d.precision),
            None => d.precision,
        };
        let keep_bits = self.keep_bits(&b.keep_bits, precision);
        let channels = match &b.channels {
            Some(c) => self
                .choice(
                    "bake.channels",
                    c,
                    &[
                        ("rgb", ChannelKind::Rgb),
                        ("spectral", ChannelKind::Spectral),
                    ],
                )
                .unwrap_or(d.channels),
            None => d.channels,
        };
        let lambda_nm = match &b.lambda_nm {
            Some(l) => self
                .lambda_nm(&l.value, limits)
                .unwrap_or_else(|| d.lambda_nm.clone()),
            None => d.lambda_nm.clone(),
        };
        BakeSettings {
            res_deg,
            photons: photons.max(1),
            seed,
            split,
            precision,
            keep_bits,
            channels,
            lambda_nm,
            ..d
        }
    }

    /// `resolution_deg`: in range and a divisor of 180 (the angular grid's bins).
    fn resolution_deg(&mut self, r: &Spanned<f64>) -> Option<f64> {
        let x = self.in_range("bake.resolution_deg", r, 0.25, 30.0, false)?;
        if crate::fiber::AngularGrid::new(x).is_ok() {
            return Some(x);
        }
        self.out_of_range(
            loc(r),
            "bake.resolution_deg",
            x.to_string(),
            "a divisor of 180 in [0.25, 30], e.g. 1, 2, 3, 5, 6, 10".into(),
        );
        None
    }

    /// `keep_bits`: a whole number up to the mantissa bits of `precision` (all of them by
    /// default).
    fn keep_bits(&mut self, k: &Option<Spanned<f64>>, precision: Precision) -> u32 {
        let bits = precision.mantissa_bits();
        match k {
            Some(k) if k.value.fract() != 0.0 || !(0.0..=bits as f64).contains(&k.value) => {
                let name = match precision {
                    Precision::F16 => "f16",
                    Precision::F32 => "f32",
                };
                self.out_of_range(
                    loc(k),
                    "bake.keep_bits",
                    k.value.to_string(),
                    format!("a whole number in [0, {bits}] ({name} has {bits} mantissa bits)"),
                );
                bits
            }
            Some(k) => k.value as u32,
            None => bits,
        }
    }

    /// `lambda_nm: {start, end, step}`, the bake's spectrum (counted before any wavelength is
    /// built); `None` for the default.
    fn lambda_nm(&mut self, r: &RawLambda, limits: &Limits) -> Option<Vec<f64>> {
        let a = self.in_range("bake.lambda_nm.start", &r.start, 360.0, 830.0, false);
        let e = self.in_range("bake.lambda_nm.end", &r.end, 360.0, 830.0, false);
        let st = self.in_range("bake.lambda_nm.step", &r.step, 0.0, 100.0, true);
        match (a, e, st) {
            (Some(a), Some(e), Some(st)) if e >= a => {
                let n = wavelength_count(a, e, st);
                if n > limits.wavelengths as f64 {
                    self.too_many_wavelengths(
                        loc(&r.step),
                        "bake.lambda_nm.step",
                        (a, e, st),
                        n,
                        limits,
                    );
                    None
                } else {
                    Some((0..n as usize).map(|i| a + st * i as f64).collect())
                }
            }
            (Some(a), Some(e), Some(_)) => {
                self.out_of_range(
                    loc(&r.end),
                    "bake.lambda_nm.end",
                    e.to_string(),
                    format!("[{a}, 830] (not below start = {a})"),
                );
                None
            }
            _ => None,
        }
    }
}
