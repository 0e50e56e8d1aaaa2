//! `bake:` of a fiber spec: how `baker bake` tabulates the BCSDFs (angular resolution,
//! photons, seed, split, precision and kept mantissa bits, channels, spectrum), each with the
//! default of [`BakeSettings`] when absent or wrong.

use super::raw::{RawBake, RawEstimators, RawLambda};
use super::FiberCx;
use crate::fiber::slices::{BakeSettings, Estimators, ExpectedExits, NoiseTarget, Sampling};
use crate::fiber::sweep::ChannelKind;
use crate::fiber::tracer::shared::MAX_SHARED;
use crate::spec::check::{loc, num, Bounds};
use crate::spec::limits::{wavelength_count, Limits};
use crate::spec::skin::raw::Token;
use crate::spec::yaml::Spanned;
use formats::Precision;

/// `bake.resolution_deg`: angular bin width, degrees (a divisor of 180).
pub(in crate::spec) const RESOLUTION_DEG: Bounds = Bounds::closed(0.25, 30.0);
/// `bake.photons_per_direction`: photons traced per stored incoming bin.
pub(in crate::spec) const PHOTONS_PER_DIRECTION: Bounds = Bounds::whole(1.0, 1e12);
/// `bake.seed`: any whole number an f64 holds exactly (up to 2^53).
pub(in crate::spec) const SEED: Bounds = Bounds::whole(0.0, 9_007_199_254_740_992.0);
/// The most draws per boundary event of the main path (`bake.split`, `--split`).
pub const MAX_SPLIT: u32 = 64;
/// The most draws per boundary event met from inside (`bake.exit_draws`, `--exit-draws`).
pub const MAX_EXIT_DRAWS: u32 = 256;
/// `bake.split`: draws per boundary event of the main path.
pub(in crate::spec) const SPLIT: Bounds = Bounds::whole(1.0, MAX_SPLIT as f64);
/// `bake.exit_draws`: draws per boundary event met from inside.
pub(in crate::spec) const EXIT_DRAWS: Bounds = Bounds::whole(1.0, MAX_EXIT_DRAWS as f64);
/// `bake.share_theta`: incoming directions sharing their photons.
pub(in crate::spec) const SHARE_THETA: Bounds = Bounds::whole(1.0, MAX_SHARED as f64);
/// `bake.target_rel_se` as a number: a relative standard error.
pub(in crate::spec) const TARGET_REL_SE: Bounds = Bounds::above(0.0, 0.5);
/// `bake.max_photons_per_direction`: the cap of adaptive allocation.
pub(in crate::spec) const MAX_PHOTONS_PER_DIRECTION: Bounds = Bounds::whole(1.0, 1e12);
/// `bake.precision`: of the stored tables.
pub(in crate::spec) const PRECISIONS: [(&str, Precision); 2] =
    [("f16", Precision::F16), ("f32", Precision::F32)];
/// `bake.channels`: linear sRGB (D65) or one channel per wavelength.
pub(in crate::spec) const CHANNELS: [(&str, ChannelKind); 2] = [
    ("rgb", ChannelKind::Rgb),
    ("spectral", ChannelKind::Spectral),
];
/// `bake.expected_exits`: which exit lobes are scored in expectation (`crate::fiber::lobe`).
pub const EXPECTED_EXITS: [(&str, ExpectedExits); 3] = [
    ("none", ExpectedExits::None),
    ("inside", ExpectedExits::Inside),
    ("all", ExpectedExits::All),
];
/// `bake.sampling`: where the photons take their uniform numbers (`crate::math::sampler`).
pub const SAMPLINGS: [(&str, Sampling); 2] =
    [("random", Sampling::Random), ("sobol", Sampling::Sobol)];

/// The value of `word` in a table of choices, or the allowed words (for command-line flags
/// that override a `bake:` choice).
pub fn choice_of<T: Copy>(options: &[(&str, T)], word: &str) -> Result<T, String> {
    options
        .iter()
        .find(|(k, _)| *k == word)
        .map(|(_, t)| *t)
        .ok_or_else(|| {
            let allowed: Vec<&str> = options.iter().map(|o| o.0).collect();
            format!("`{word}` is not one of {}", allowed.join(", "))
        })
}

/// `bake.quantise_to_se`: the rounding error allowed per stored value, as a fraction of its
/// bin's standard error (0 = off; above one the error would exceed the noise).
pub(in crate::spec) const QUANTISE_TO_SE: Bounds = Bounds::closed(0.0, 1.0);
/// `bake.lambda_nm.start` and `end`: the colour-matching tables, nm.
pub(in crate::spec) const LAMBDA_NM: Bounds = Bounds::closed(360.0, 830.0);
/// `bake.lambda_nm.step`, nm.
pub(in crate::spec) const LAMBDA_STEP_NM: Bounds = Bounds::above(0.0, 100.0);

/// The estimator fields as written, in `bake:` or a fiber's `estimators:`.
struct EstimatorFields<'a> {
    split: &'a Option<Spanned<f64>>,
    exit_draws: &'a Option<Spanned<f64>>,
    expected_exits: &'a Option<Spanned<String>>,
    sampling: &'a Option<Spanned<String>>,
    share_theta: &'a Option<Spanned<f64>>,
}

/// `bake.zstd_level` as a number.
pub(in crate::spec) const ZSTD_LEVEL: Bounds = Bounds::whole(1.0, 22.0);

/// `bake.zstd_level`: the zstd level of the `.bcsdf` frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ZstdLevel {
    /// Chosen per stored direction from the photons its slice took
    /// (`crate::bake::fiber::tables::auto_zstd_level`).
    Auto,
    Level(i32),
}

impl serde::Serialize for ZstdLevel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            ZstdLevel::Auto => s.serialize_str("auto"),
            ZstdLevel::Level(l) => s.serialize_i32(*l),
        }
    }
}

/// How the tables store the traced values (`bake:` settings that change the tables, not the
/// traced units).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TableStorage {
    /// Each value is rounded to the fewest mantissa bits whose rounding error stays within
    /// this fraction of its bin's standard error (0 = off); `keep_bits` stays the upper bound.
    pub quantise_to_se: f64,
    pub zstd_level: ZstdLevel,
}

impl Default for TableStorage {
    fn default() -> Self {
        // A quarter of the standard error adds 1/16 of the variance at most (≤ 3 % to the
        // noise's standard deviation) and frees the bits below it for zstd.
        TableStorage {
            quantise_to_se: 0.25,
            zstd_level: ZstdLevel::Auto,
        }
    }
}

impl FiberCx {
    /// `bake:`'s table storage settings.
    pub(super) fn storage(&mut self, b: &RawBake) -> TableStorage {
        let d = TableStorage::default();
        TableStorage {
            quantise_to_se: self.opt_bounds(
                "bake.quantise_to_se",
                &b.quantise_to_se,
                QUANTISE_TO_SE,
                d.quantise_to_se,
            ),
            zstd_level: match &b.zstd_level {
                Some(z) => self.zstd_level(z).unwrap_or(d.zstd_level),
                None => d.zstd_level,
            },
        }
    }

    /// `zstd_level`: `auto` or a whole number in [1, 22].
    fn zstd_level(&mut self, z: &Spanned<Token>) -> Option<ZstdLevel> {
        match &z.value {
            Token::Text(w) if w == "auto" => Some(ZstdLevel::Auto),
            Token::Number(x) if x.fract() == 0.0 && (ZSTD_LEVEL.lo..=ZSTD_LEVEL.hi).contains(x) => {
                Some(ZstdLevel::Level(*x as i32))
            }
            other => {
                self.out_of_range(
                    loc(z),
                    "bake.zstd_level",
                    other.to_string(),
                    "a whole number in [1, 22], or `auto`".into(),
                );
                None
            }
        }
    }

    pub(super) fn bake(&mut self, b: &RawBake, limits: &Limits) -> BakeSettings {
        let d = BakeSettings::default();
        let res_deg = match &b.resolution_deg {
            Some(r) => self.resolution_deg(r).unwrap_or(d.res_deg),
            None => d.res_deg,
        };
        let photons = self.count(
            "bake.photons_per_direction",
            &b.photons_per_direction,
            PHOTONS_PER_DIRECTION.lo,
            PHOTONS_PER_DIRECTION.hi,
            d.photons,
        );
        let seed = self.count("bake.seed", &b.seed, SEED.lo, SEED.hi, d.seed);
        let fields = EstimatorFields {
            split: &b.split,
            exit_draws: &b.exit_draws,
            expected_exits: &b.expected_exits,
            sampling: &b.sampling,
            share_theta: &b.share_theta,
        };
        let estimators = self.estimator_fields("bake", fields, d.estimators());
        let target = b.target_rel_se.as_ref().and_then(|t| self.noise_target(t));
        let max_photons = self.count(
            "bake.max_photons_per_direction",
            &b.max_photons_per_direction,
            MAX_PHOTONS_PER_DIRECTION.lo,
            MAX_PHOTONS_PER_DIRECTION.hi,
            d.max_photons,
        );
        let precision = self.opt_choice("bake.precision", &b.precision, &PRECISIONS, d.precision);
        let keep_bits = self.keep_bits(&b.keep_bits, precision);
        let channels = self.opt_choice("bake.channels", &b.channels, &CHANNELS, d.channels);
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
            target,
            max_photons,
            precision,
            keep_bits,
            channels,
            lambda_nm,
            ..d
        }
        .with_estimators(estimators)
    }

    /// A fiber's `estimators:`, each absent field the spec's (`bake`).
    pub(super) fn estimators(&mut self, r: &RawEstimators, bake: &BakeSettings) -> Estimators {
        let fields = EstimatorFields {
            split: &r.split,
            exit_draws: &r.exit_draws,
            expected_exits: &r.expected_exits,
            sampling: &r.sampling,
            share_theta: &r.share_theta,
        };
        self.estimator_fields("fibers.estimators", fields, bake.estimators())
    }

    /// The estimator fields of `bake:` or of a fiber's `estimators:` (named `{at}.split`, …),
    /// each absent or wrong one `d`'s.
    ///
    /// Events met from inside are drawn at least `split` times (the tracer's
    /// [`crate::fiber::slices::BakeSettings::draws`]): an `exit_draws` below the block's
    /// `split`, written or inherited, becomes `split` here, so that what the manifest and
    /// the tables' metadata record is what is traced.
    fn estimator_fields(&mut self, at: &str, f: EstimatorFields, d: Estimators) -> Estimators {
        let field = |name: &str| format!("{at}.{name}");
        let (split, draws) = (d.split as u64, d.exit_draws as u64);
        let split = self.count(&field("split"), f.split, SPLIT.lo, SPLIT.hi, split) as u32;
        let exit_draws = self.count(
            &field("exit_draws"),
            f.exit_draws,
            EXIT_DRAWS.lo,
            EXIT_DRAWS.hi,
            draws,
        ) as u32;
        Estimators {
            split,
            // Never fewer than `split` (the tracer's `BakeSettings::draws`), as traced.
            exit_draws: exit_draws.max(split),
            expected_exits: self.opt_choice(
                &field("expected_exits"),
                f.expected_exits,
                &EXPECTED_EXITS,
                d.expected_exits,
            ),
            sampling: self.opt_choice(&field("sampling"), f.sampling, &SAMPLINGS, d.sampling),
            share_theta: self.count(
                &field("share_theta"),
                f.share_theta,
                SHARE_THETA.lo,
                SHARE_THETA.hi,
                d.share_theta as u64,
            ) as u32,
        }
    }

    /// `target_rel_se`: `thesis` or a relative standard error in (0, 1).
    fn noise_target(&mut self, t: &Spanned<Token>) -> Option<NoiseTarget> {
        match &t.value {
            Token::Text(w) if w == "thesis" => Some(NoiseTarget::Thesis),
            Token::Number(x) => {
                let v = Spanned::new(*x, t.referenced, t.defined);
                self.in_bounds("bake.target_rel_se", &v, TARGET_REL_SE)
                    .map(NoiseTarget::RelSe)
            }
            Token::Text(w) => {
                self.out_of_range(
                    loc(t),
                    "bake.target_rel_se",
                    w.clone(),
                    "a relative standard error in (0, 0.5], e.g. 0.03, or `thesis`".into(),
                );
                None
            }
        }
    }

    /// `resolution_deg`: in range and a divisor of 180 (the angular grid's bins).
    fn resolution_deg(&mut self, r: &Spanned<f64>) -> Option<f64> {
        let x = self.in_bounds("bake.resolution_deg", r, RESOLUTION_DEG)?;
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
                    num(k.value),
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
        let a = self.in_bounds("bake.lambda_nm.start", &r.start, LAMBDA_NM);
        let e = self.in_bounds("bake.lambda_nm.end", &r.end, LAMBDA_NM);
        let st = self.in_bounds("bake.lambda_nm.step", &r.step, LAMBDA_STEP_NM);
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
