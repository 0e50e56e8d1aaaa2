//! Layered Monte Carlo photon transport (MCML class, Wang, Jacques & Zheng 1995[^wang95]), with
//! the non-planar dermo-epidermal junction of thesis Eq. 1 and absorption reuse ("white"
//! Monte Carlo).
//!
//! A pencil beam enters a stack of laterally infinite layers at normal incidence. Packets of
//! weight are moved with exponential free paths, scattered with the Henyey–Greenstein phase
//! function, reflected or refracted at every index mismatch (Fresnel, unpolarised), and
//! terminated with unbiased Russian roulette. Work is split into fixed-size batches, each with
//! its own RNG seeded from (seed, batch index), and reduced in batch order: the result is
//! bit-identical for any thread count.
//!
//! [^wang95]: L. Wang, S. L. Jacques, L. Zheng, "MCML — Monte Carlo modeling of light transport
//! in multi-layered tissues", Computer Methods and Programs in Biomedicine 47, 131–146 (1995).

pub mod boundary;
pub mod engine;
pub mod junction;
pub mod mcml;
pub mod phase;
pub mod radial;
pub mod stack;
pub mod tally;
pub mod white;

pub use engine::{run, McOptions};
pub use radial::RadialBins;
pub use stack::{Junction, Layer, RadialGrid, Stack, StackError};
pub use tally::McResult;
pub use white::{run_white, run_white_sets, AbsorptionSet, SetTally, WhiteRun, WhiteSets};
