//! Random numbers and seeds. Every stream is a Xoshiro256++ generator seeded from (seed, batch
//! index), so a run is reproducible whatever the thread count; task seeds are digests of what a
//! task computes, so they do not depend on the order tasks run in.
//!
//! All of it is built on the SplitMix64 finaliser ([`mix64`]; Steele, Lea & Flood, "Fast
//! splittable pseudorandom number generators", OOPSLA 2014). The seeds take part in cache keys
//! and outputs: changing any constant or the order of any step changes every result.

use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// The generator of one batch of photons (one RNG stream).
pub type BatchRng = Xoshiro256PlusPlus;

/// SplitMix64's increment γ = 2⁶⁴/φ (φ the golden ratio), rounded to odd.
const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): a well-mixed 64-bit digest step that
/// decorrelates consecutive inputs (batch indices, coordinates).
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The generator of batch `batch` of a run seeded with `seed`.
pub fn batch_rng(seed: u64, batch: u64) -> BatchRng {
    Xoshiro256PlusPlus::seed_from_u64(mix64(seed ^ mix64(batch.wrapping_add(GOLDEN_GAMMA))))
}

/// Uniform in the open interval (0, 1) from 53 random bits: −ln u is finite and positive.
/// (Strictly, in (0, 1]: the largest of the 2⁵³ values, (2⁵³ − ½)·2⁻⁵³, rounds to 1.)
#[inline]
pub fn uniform(bits: u64) -> f64 {
    ((bits >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

/// Two uniforms in the open interval (−1, 1) from one 64-bit draw, 32 bits each (the high and
/// low halves of a xoshiro256++ output are both full-quality): a point in the square for
/// rejection sampling of a disk, where 2⁻³¹ resolution is far below any tally's (half the
/// generator calls of two [`uniform`]s).
#[inline(always)]
pub fn symmetric_pair(bits: u64) -> (f64, f64) {
    const SCALE: f64 = 1.0 / (1u64 << 31) as f64;
    let hi = (bits >> 32) as f64 + 0.5;
    let lo = (bits & 0xffff_ffff) as f64 + 0.5;
    (hi * SCALE - 1.0, lo * SCALE - 1.0)
}

/// Seed of a fiber-bake task from the spec seed and the task's coordinates (entry name hash,
/// section, bin), so the result does not depend on the order or the threads tasks run on:
/// h₀ = mix64(seed), then h ← mix64(h ⊕ mix64(p + γ)) for each coordinate p.
///
/// Not the same function as [`group_wavelength_seed`] (different start and step): each keeps
/// the seeds, hence the tables and cache keys, its callers have always had.
pub fn coordinate_seed(seed: u64, parts: &[u64]) -> u64 {
    parts.iter().fold(mix64(seed), |h, &p| {
        mix64(h ^ mix64(p.wrapping_add(GOLDEN_GAMMA)))
    })
}

/// 64-bit digest of `words`: h₀ = γ, then h ← mix64(h ⊕ mix64(w)) for each word.
pub fn digest_words(words: &[u64]) -> u64 {
    words.iter().fold(GOLDEN_GAMMA, |h, &w| mix64(h ^ mix64(w)))
}

/// Seed of a skin-profile simulation of the group with scattering digest `group_digest` at
/// wavelength index `lambda_index`: [`digest_words`] of (seed, digest, index), so it depends on
/// the spec seed and what is simulated, not on which other entries are in the bake.
pub fn group_wavelength_seed(seed: u64, group_digest: u64, lambda_index: usize) -> u64 {
    digest_words(&[seed, group_digest, lambda_index as u64])
}

/// FNV-1a (64-bit) of a name: the coordinate of a named entry in [`coordinate_seed`].
pub fn fnv1a(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::Rng;

    /// Fixed values: any change to these functions changes every table and cache key.
    #[test]
    fn seeds_are_frozen() {
        assert_eq!(mix64(0), 0);
        assert_eq!(mix64(1), 0x5692_161d_100b_05e5);
        assert_eq!(fnv1a(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a("a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(coordinate_seed(7, &[]), mix64(7));
        assert_eq!(
            coordinate_seed(7, &[3]),
            mix64(mix64(7) ^ mix64(3u64.wrapping_add(GOLDEN_GAMMA)))
        );
        assert_eq!(digest_words(&[]), GOLDEN_GAMMA);
        assert_eq!(
            group_wavelength_seed(1, 2, 3),
            mix64(mix64(mix64(GOLDEN_GAMMA ^ mix64(1)) ^ mix64(2)) ^ mix64(3))
        );
        // The two task seeds are different functions.
        assert_ne!(coordinate_seed(1, &[2, 3]), group_wavelength_seed(1, 2, 3));
    }

    /// Both halves span (−1, 1) symmetrically, never reach ±1, and are uncorrelated uniforms:
    /// means 0 and variances 1/3 within 4 standard errors, correlation within 4/√n.
    #[test]
    fn symmetric_pairs_are_two_independent_uniforms() {
        assert_eq!(
            symmetric_pair(0),
            (-1.0 + 2f64.powi(-32), -1.0 + 2f64.powi(-32))
        );
        let top = symmetric_pair(u64::MAX);
        assert_eq!(top, (1.0 - 2f64.powi(-32), 1.0 - 2f64.powi(-32)));
        let mut rng = batch_rng(9, 0);
        let n = 400_000;
        let (mut s, mut s2, mut sab) = ([0.0f64; 2], [0.0f64; 2], 0.0);
        for _ in 0..n {
            let (a, b) = symmetric_pair(rng.next_u64());
            assert!(a > -1.0 && a < 1.0 && b > -1.0 && b < 1.0);
            for (k, v) in [a, b].into_iter().enumerate() {
                s[k] += v;
                s2[k] += v * v;
            }
            sab += a * b;
        }
        let nf = n as f64;
        for k in 0..2 {
            // Var(U) = 1/3, Var(U²) = 4/45 for U uniform on (−1, 1).
            assert!(
                (s[k] / nf).abs() < 4.0 * (1.0 / 3.0 / nf).sqrt(),
                "mean {k}"
            );
            assert!(
                (s2[k] / nf - 1.0 / 3.0).abs() < 4.0 * (4.0 / 45.0 / nf).sqrt(),
                "var {k}"
            );
        }
        assert!((sab / nf).abs() < 4.0 / 3.0 / nf.sqrt(), "correlation");
    }

    #[test]
    fn batches_are_reproducible_and_distinct() {
        let a: Vec<u64> = (0..4).map(|_| batch_rng(5, 0).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(batch_rng(5, 0).next_u64(), batch_rng(5, 1).next_u64());
        assert_ne!(batch_rng(5, 0).next_u64(), batch_rng(6, 0).next_u64());
    }

    #[test]
    fn uniform_is_positive_and_at_most_one() {
        assert_eq!(uniform(0), 0.5 / (1u64 << 53) as f64);
        assert_eq!(uniform(1 << 63), 0.5);
        // The largest input rounds up to exactly 1 (then −ln u = 0, still finite).
        assert_eq!(uniform(u64::MAX), 1.0);
        assert!(uniform(u64::MAX - (1 << 11)) < 1.0);
    }
}
