//! Statistics for tests and reports: χ² goodness of fit, running sums with standard errors.

pub mod chi2;
pub mod running;

pub use running::Sums;
