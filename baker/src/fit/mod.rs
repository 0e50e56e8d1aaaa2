//! Fits of baked tables to the analytic forms renderers evaluate.

pub mod gaussians;
pub mod nnls;
pub mod simplex;

pub use gaussians::{fit_sum_of_gaussians, gaussian_energy, GaussianFit, GaussianFitOptions};
pub use simplex::nelder_mead;
