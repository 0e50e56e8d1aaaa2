//! sin and cos of an angle given in turns, 2π·u, for the azimuths a sampler draws from a
//! uniform number u (the Beckmann facet's φm = 2π·u2 at every boundary draw of
//! [`crate::fiber::Surface::scatter`]).
//!
//! glibc's `sincos` reduces any double modulo π/2 in extended precision and picks table
//! entries; an angle in turns needs neither. [`sin_cos_turns`] splits 256·u exactly into the
//! nearest integer k and a remainder f = 256·u − k in [−½, ½] (exact: Sterbenz), reads
//! sin and cos of the k-th 256th of a turn from a table, and turns them by r = f·2π/256,
//! |r| ≤ π/256, with the angle-sum formulas: sin(a + r) = sin a·cos r + cos a·sin r and
//! cos(a + r) = cos a·cos r − sin a·sin r. On so short an interval the Taylor polynomials of
//! sin r to r⁷ and cos r to r⁶ are within r⁹/9! < 2·10⁻²³ and r⁸/8! < 2·10⁻²⁰ of the
//! functions. Six multiplies and adds for the polynomials and six for the turn, against the
//! sixteen-term polynomials of [`sin_cos_quadrant`] (which builds the table, in constant
//! evaluation, and is exact at the quarter turns: so is the table, and so the result there).
//! No fused multiply-add: the same bits on every x86-64 machine.
//!
//! Accuracy: within 2.4 ulp of the exact values (20,000 random u against 200-bit mpmath;
//! [`sin_cos_quadrant`]: 1.6 ulp); the unit test holds both within 2 ulp of the library plus
//! one ulp of the argument 2π·u. Speed, 2·10⁷ random u in a loop whose sum depends on each
//! result: 6.3–6.6 ns per call against 21.2–22.0 ns for [`sin_cos_quadrant`]
//! (validation/bench-runs/2026-12-07-fiber-sincos-table).

use std::f64::consts::{FRAC_PI_2, TAU};

use super::exp::ROUND_F64;
use super::poly::estrin;

/// Table steps per turn (a power of two: the index wraps by a mask).
const STEPS: usize = 256;

/// (sin, cos) of k/256 of a turn, k = 0 … 255, by [`sin_cos_quadrant`].
static TABLE: [[f64; 2]; STEPS] = {
    let mut t = [[0.0; 2]; STEPS];
    let mut k = 0;
    while k < STEPS {
        let (s, c) = sin_cos_quadrant(k as f64 / STEPS as f64);
        t[k] = [s, c];
        k += 1;
    }
    t
};

/// (sin 2πu, cos 2πu) for finite `u` (the sampler's u ∈ [0, 1); any finite u is reduced
/// exactly for |u| < 2⁴³).
#[inline]
pub fn sin_cos_turns(u: f64) -> (f64, f64) {
    let x = STEPS as f64 * u;
    // The nearest integer (ties to even) by adding and removing 1.5·2⁵² (exact for
    // |x| < 2⁵¹; `f64::round` is a library call on baseline x86-64).
    let q = (x + ROUND_F64) - ROUND_F64;
    let r = (x - q) * (TAU / STEPS as f64);
    let r2 = r * r;
    // Two's complement: the mask is q mod 256 for negative q too.
    let [s, c] = TABLE[(q as i64 as usize) & (STEPS - 1)];
    let sin_r = r + r * (r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5_040.0))));
    let cos_r = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0)));
    (s * cos_r + c * sin_r, c * cos_r - s * sin_r)
}

/// (sin 2πu, cos 2πu) for finite `u` by quadrants: u·4 splits exactly into the quadrant q
/// (nearest integer) and a remainder f = u·4 − q in [−½, ½], and r = f·π/2 lies in
/// [−π/4, π/4], where the Taylor polynomials of sin to r¹⁵ and cos to r¹⁶ are within
/// r¹⁷/17! < 5·10⁻¹⁷ and r¹⁸/18! < 3·10⁻¹⁸ (|r| ≤ π/4) of the functions: below half an ulp of
/// results ≥ 2⁻⁵. Evaluated by Estrin's scheme in r² ([`super::poly::estrin`]). Within
/// 1.1–1.6 ulp of the exact values (two samples of 20,000 random u against 200-bit mpmath).
/// A constant function: it builds [`sin_cos_turns`]'s table.
pub const fn sin_cos_quadrant(u: f64) -> (f64, f64) {
    let x = 4.0 * u;
    let q = (x + ROUND_F64) - ROUND_F64;
    let r = (x - q) * FRAC_PI_2;
    let r2 = r * r;
    // sin r = r·(1 + r²·S(r²)), S's coefficients −1/3!, 1/5!, …, −1/15!; cos r = 1 + r²·C(r²),
    // C's −1/2!, 1/4!, …, 1/16!.
    let sin_r = r + r * (r2 * estrin(&S, r2));
    let cos_r = 1.0 + r2 * estrin(&C, r2);
    // Rotate by q quarter turns without branches (the quadrant of a uniform draw is random):
    // odd q swaps sin and cos; sin is negated for q ≡ 2, 3 and cos for q ≡ 1, 2 (mod 4).
    let qi = q as i64;
    let swap = qi & 1 != 0;
    let (a, b) = if swap { (cos_r, sin_r) } else { (sin_r, cos_r) };
    let sign_s = ((qi as u64 >> 1) & 1) << 63;
    let sign_c = (((qi + 1) as u64 >> 1) & 1) << 63;
    (
        f64::from_bits(a.to_bits() ^ sign_s),
        f64::from_bits(b.to_bits() ^ sign_c),
    )
}

/// (−1)^k/(2k + 1)! for k = 1 … 7.
const S: [f64; 7] = [
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
];

/// (−1)^k/(2k)! for k = 1 … 8.
const C: [f64; 8] = [
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{batch_rng, uniform};
    use rand_core::Rng;

    /// |a − b| within 2 ulp of b plus what the rounding of the library's argument 2π·u
    /// allows (an ulp of it).
    fn close(a: f64, b: f64, u: f64) -> bool {
        let arg = (std::f64::consts::TAU * u).abs().max(1.0);
        (a - b).abs() <= 2.0 * f64::EPSILON * b.abs() + f64::EPSILON * arg
    }

    /// Within 2 ulp of the library's sin and cos of 2π·u (plus the rounding of 2π·u) over
    /// random u, the quarter points and the ends of every quadrant; exact at the quarters.
    #[test]
    fn sin_cos_turns_matches_the_library() {
        let mut rng = batch_rng(11, 0);
        let mut us: Vec<f64> = (0..200_000).map(|_| uniform(rng.next_u64())).collect();
        for k in 0..=8 {
            let q = k as f64 / 8.0;
            us.extend([q, q - 1e-12, q + 1e-12, (q - f64::EPSILON).max(0.0)]);
        }
        us.extend([1e-300, 0.999_999_999_999_999_9, -0.3, 7.25, -1e6 - 0.1]);
        for u in us {
            let (s0, c0) = (std::f64::consts::TAU * u).sin_cos();
            for (s, c) in [sin_cos_turns(u), sin_cos_quadrant(u)] {
                assert!(
                    close(s, s0, u) && close(c, c0, u),
                    "u {u}: {s} {c} vs {s0} {c0}"
                );
            }
        }
        // Exact at the quarter turns (a zero's sign aside).
        for f in [sin_cos_turns, sin_cos_quadrant] {
            assert_eq!(f(0.0), (0.0, 1.0));
            assert_eq!(f(0.25), (1.0, 0.0));
            assert_eq!(f(0.5), (0.0, -1.0));
            assert_eq!(f(0.75), (-1.0, 0.0));
            assert_eq!(f(-0.25), (-1.0, 0.0));
        }
    }
}
