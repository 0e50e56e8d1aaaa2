//! Numerical building blocks shared by the physics: random streams and their seeds,
//! quadrature rules, Fresnel factors and a vectorisable exponential.

pub mod exp;
pub mod fresnel;
pub mod quadrature;
pub mod rng;
pub mod sampler;
