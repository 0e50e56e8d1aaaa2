//! e^x for x ≤ 0 without branches or table lookups, so that loops over many arguments
//! vectorise: eight f32 lanes to an AVX2 register for the exit-lobe densities of
//! [`crate::fiber::lobe`], four f64 lanes for the dye sweep's attenuation table
//! ([`crate::fiber::sweep`]). Both use Cody–Waite argument reduction x = k·ln 2 + r,
//! |r| ≤ ln 2 / 2, with ln 2 split in two (the constants of fdlibm's `e_expf.c` and `e_exp.c`),
//! then the Taylor polynomial of e^r and the exact scaling by 2^k through the exponent bits:
//! - [`exp_neg_f32`]: degree 7 (truncation r⁸/8! < 6·10⁻⁹ relative, below half an f32 ulp);
//!   within 2 ulp of e^x rounded to f32; 0 below −87 (e^x < 1.7·10⁻³⁸, the smallest normal
//!   f32's size);
//! - [`exp_neg_f64`]: degree 13 (truncation r¹⁴/14! < 5·10⁻¹⁸ relative), evaluated by
//!   Estrin's scheme (a dependency chain of 8 operations, not Horner's 22: the sweep table's
//!   rows are bound by latency); tested within 4 ulp of `f64::exp` (measured: 1 ulp over the
//!   test's 300,000 arguments); 0 below −708 (e^x < 4·10⁻³⁰⁸).

use super::poly::estrin;

/// The f32 constants: ln 2 in two parts (fdlibm's `expf` ln2_hi, ln2_lo, by their bits; the
/// high part has nine trailing zero bits, so k·LN2_HI is exact for |k| < 2⁹), 1.5·2²³ (adding
/// it rounds a value below 2²² to the nearest integer, ties to even, and leaves that integer
/// in the low bits of the sum), and the floor.
const LN2_HI_F32: f32 = f32::from_bits(0x3f31_7200);
const LN2_LO_F32: f32 = f32::from_bits(0x35bf_be8e);
const ROUND_F32: f32 = 12_582_912.0;
const FLOOR_F32: f32 = -87.0;

/// The f64 constants: fdlibm's `exp` ln2_hi (eleven trailing zero bits: k·LN2_HI is exact for
/// |k| < 2¹¹) and ln2_lo, 1.5·2⁵², and the floor.
const LN2_HI_F64: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO_F64: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
pub(crate) const ROUND_F64: f64 = 6_755_399_441_055_744.0;
const FLOOR_F64: f64 = -708.0;

/// 1/k! for k = 2 … N + 1.
const fn inv_fact<const N: usize>() -> [f64; N] {
    let mut c = [0.0; N];
    let mut f = 1.0;
    let mut k = 0;
    while k < N {
        f *= (k + 2) as f64;
        c[k] = 1.0 / f;
        k += 1;
    }
    c
}

const INV_FACT_F32: [f32; 6] = {
    let c = inv_fact::<6>();
    let mut out = [0.0f32; 6];
    let mut k = 0;
    while k < 6 {
        out[k] = c[k] as f32;
        k += 1;
    }
    out
};
const INV_FACT_F64: [f64; 12] = inv_fact::<12>();

/// e^x for x ≤ 0 in f32 (any x ≤ 0, −∞ included; NaN gives a meaningless finite value, which
/// callers mask out).
#[inline(always)]
pub fn exp_neg_f32(x: f32) -> f32 {
    let xc = if x < FLOOR_F32 { FLOOR_F32 } else { x };
    let t = xc * std::f32::consts::LOG2_E + ROUND_F32;
    let kf = t - ROUND_F32;
    let k = (t.to_bits() as i32).wrapping_sub(ROUND_F32.to_bits() as i32);
    let r = (xc - kf * LN2_HI_F32) - kf * LN2_LO_F32;
    let mut p = INV_FACT_F32[5];
    for &c in INV_FACT_F32[..5].iter().rev() {
        p = p * r + c;
    }
    let er = 1.0 + r * (1.0 + r * p);
    let scale = f32::from_bits(((k + 127) as u32) << 23);
    if x < FLOOR_F32 {
        0.0
    } else {
        er * scale
    }
}

/// e^x for x ≤ 0 in f64 (any x ≤ 0, −∞ included; NaN gives a meaningless finite value, which
/// callers mask out).
#[inline(always)]
pub fn exp_neg_f64(x: f64) -> f64 {
    let xc = if x < FLOOR_F64 { FLOOR_F64 } else { x };
    let t = xc * std::f64::consts::LOG2_E + ROUND_F64;
    let kf = t - ROUND_F64;
    let k = (t.to_bits() as i64).wrapping_sub(ROUND_F64.to_bits() as i64);
    let r = (xc - kf * LN2_HI_F64) - kf * LN2_LO_F64;
    // Estrin's scheme: a dependency chain of 8 operations instead of Horner's 22, so a row of
    // the sweep table is not bound by add latency.
    let p = estrin(&INV_FACT_F64, r);
    let er = 1.0 + r * (1.0 + r * p);
    let scale = f64::from_bits(((k + 1023) as u64) << 52);
    if x < FLOOR_F64 {
        0.0
    } else {
        er * scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The arguments both tests take: dense near 0 and across [floor, 0].
    fn arguments(floor: f64) -> impl Iterator<Item = f64> {
        (0..200_000)
            .map(|i| -(i as f64) * 1e-4)
            .chain((0..100_000).map(move |i| floor * i as f64 / 100_000.0))
    }

    /// Within 2 ulp of e^x rounded to f32 over [−87, 0] (where the densities of the exit lobes
    /// take it); 0 below −87 and at −∞; e^0 = 1.
    #[test]
    fn exp_neg_f32_matches_the_library_exp() {
        let ulps = |a: f32, b: f32| (a.to_bits() as i32 - b.to_bits() as i32).unsigned_abs();
        let worst = arguments(-87.0)
            .map(|x| x as f32)
            .map(|x| ulps(exp_neg_f32(x), (x as f64).exp() as f32))
            .max();
        assert!(worst <= Some(2), "worst {worst:?} ulp");
        assert_eq!(exp_neg_f32(0.0), 1.0);
        assert_eq!(exp_neg_f32(-87.5), 0.0);
        assert_eq!(exp_neg_f32(f32::NEG_INFINITY), 0.0);
        assert!((exp_neg_f32(-1.0) - (-1.0f32).exp()).abs() <= f32::EPSILON);
    }

    /// Within 4 ulp of `f64::exp` over [−708, 0]; 0 below −708 and at −∞; e^0 = 1.
    #[test]
    fn exp_neg_f64_matches_the_library_exp() {
        let ulps = |a: f64, b: f64| (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs();
        let worst = arguments(-708.0)
            .map(|x| ulps(exp_neg_f64(x), x.exp()))
            .max();
        assert!(worst <= Some(4), "worst {worst:?} ulp");
        assert_eq!(exp_neg_f64(0.0), 1.0);
        assert_eq!(exp_neg_f64(-709.0), 0.0);
        assert_eq!(exp_neg_f64(f64::NEG_INFINITY), 0.0);
        assert!((exp_neg_f64(-1.0) - (-1.0f64).exp()).abs() <= f64::EPSILON);
    }
}
