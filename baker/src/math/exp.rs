//! e^x for x ≤ 0 in single precision without branches or table lookups, so that loops over
//! many arguments (the exit-lobe densities of [`crate::fiber::lobe`]) vectorise eight lanes to
//! an AVX2 register: Cody–Waite argument reduction x = k·ln 2 + r, |r| ≤ ln 2 / 2, with ln 2
//! split in two (the constants of fdlibm's `e_expf.c`), then the Taylor polynomial of e^r to
//! degree 7 (truncation error r⁸/8! < 6·10⁻⁹ relative, below half an f32 ulp) and the exact
//! scaling by 2^k through the exponent bits. Within 2 ulp of the correctly rounded value
//! (tested against `f64::exp` rounded to f32); 0 below −87 (where e^x < 1.7·10⁻³⁸, the
//! smallest normal f32's size).

/// ln 2 in two parts (fdlibm's ln2_hi, ln2_lo for `expf`, by their bits): the high part has
/// nine trailing zero bits, so k·LN2_HI is exact for |k| < 2⁹.
const LN2_HI: f32 = f32::from_bits(0x3f31_7200);
const LN2_LO: f32 = f32::from_bits(0x35bf_be8e);
/// 1.5·2²³: adding it rounds a value of magnitude below 2²² to the nearest integer (ties to
/// even) and leaves that integer in the low bits of the sum.
const ROUND: f32 = 12_582_912.0;
/// Below this e^x is taken as 0 (k stays ≥ −126, a normal scale).
const FLOOR: f32 = -87.0;

/// 1/k! for k = 2 … 7.
const INV_FACT: [f32; 6] = {
    let mut c = [0.0; 6];
    let mut f = 1.0f64;
    let mut k = 0;
    while k < 6 {
        f *= (k + 2) as f64;
        c[k] = (1.0 / f) as f32;
        k += 1;
    }
    c
};

/// e^x for x ≤ 0 (any x ≤ 0, −∞ included; NaN gives a meaningless finite value, which callers
/// mask out).
#[inline(always)]
pub fn exp_neg(x: f32) -> f32 {
    let xc = if x < FLOOR { FLOOR } else { x };
    let t = xc * std::f32::consts::LOG2_E + ROUND;
    let kf = t - ROUND;
    let k = (t.to_bits() as i32).wrapping_sub(ROUND.to_bits() as i32);
    let r = (xc - kf * LN2_HI) - kf * LN2_LO;
    let mut p = INV_FACT[5];
    for &c in INV_FACT[..5].iter().rev() {
        p = p * r + c;
    }
    let er = 1.0 + r * (1.0 + r * p);
    let scale = f32::from_bits(((k + 127) as u32) << 23);
    if x < FLOOR {
        0.0
    } else {
        er * scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(a: f32, b: f32) -> u32 {
        (a.to_bits() as i32 - b.to_bits() as i32).unsigned_abs()
    }

    /// Within 2 ulp of e^x rounded to f32 over [−87, 0] (dense near 0, where the densities of
    /// the exit lobes take it, and across the whole range); 0 below −87 and at −∞; e^0 = 1.
    #[test]
    fn exp_neg_matches_the_library_exp() {
        let mut worst = 0;
        let mut check = |x: f32| worst = worst.max(ulps(exp_neg(x), (x as f64).exp() as f32));
        for i in 0..200_000 {
            check(-(i as f32) * 1e-4);
        }
        for i in 0..100_000 {
            check(-87.0 * i as f32 / 100_000.0);
        }
        assert!(worst <= 2, "worst {worst} ulp");
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(-87.5), 0.0);
        assert_eq!(exp_neg(f32::NEG_INFINITY), 0.0);
        assert!((exp_neg(-1.0) - (-1.0f32).exp()).abs() <= f32::EPSILON);
    }
}
