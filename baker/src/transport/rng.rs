//! Per-batch random number generators: Xoshiro256++ seeded from (spec seed, batch index), so a
//! run is reproducible whatever the thread count.

use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

pub type BatchRng = Xoshiro256PlusPlus;

/// SplitMix64 finaliser (Steele, Lea & Flood 2014): decorrelates consecutive batch indices.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The generator of batch `batch` of a run seeded with `seed`.
pub fn batch_rng(seed: u64, batch: u64) -> BatchRng {
    Xoshiro256PlusPlus::seed_from_u64(mix(seed ^ mix(batch.wrapping_add(0x9e37_79b9_7f4a_7c15))))
}

/// Uniform in the open interval (0, 1) from 53 random bits: −ln u is finite and positive.
#[inline]
pub fn uniform(bits: u64) -> f64 {
    ((bits >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}
