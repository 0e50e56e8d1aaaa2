//! Numerical building blocks shared by the physics: random streams and their seeds,
//! quadrature rules and Fresnel factors.

pub mod fresnel;
pub mod quadrature;
pub mod rng;
pub mod sampler;
