//! Numerical building blocks shared by the physics: run-time AVX2 dispatch, random streams
//! and their seeds, quadrature rules, Fresnel factors, a vectorisable exponential and sin/cos
//! of angles in turns.

pub mod avx2;
pub mod exp;
pub mod fresnel;
pub mod poly;
pub mod quadrature;
pub mod rng;
pub mod sampler;
pub mod turns;
