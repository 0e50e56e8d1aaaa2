//! Statistics for tests and reports: χ² goodness of fit (unit tests only: it needs the
//! dev-dependency `statrs`), running sums with standard errors.

#[cfg(test)]
pub mod chi2;
pub mod running;

pub use running::Sums;
