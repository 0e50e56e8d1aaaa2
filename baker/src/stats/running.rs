//! Σx and Σx² of per-photon contributions, and the standard error of their mean.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Sums {
    pub sum: f64,
    pub sum2: f64,
}

impl Sums {
    #[inline]
    pub fn add(&mut self, x: f64) {
        self.sum += x;
        self.sum2 += x * x;
    }

    #[inline]
    pub fn merge(&mut self, o: &Sums) {
        self.sum += o.sum;
        self.sum2 += o.sum2;
    }

    /// Mean over `n` samples (the samples that contributed nothing count as zeros).
    pub fn mean(&self, n: u64) -> f64 {
        self.sum / n as f64
    }

    /// Standard error of the mean over `n` samples.
    pub fn se(&self, n: u64) -> f64 {
        if n < 2 {
            return f64::NAN;
        }
        let nf = n as f64;
        let m = self.sum / nf;
        ((self.sum2 / nf - m * m).max(0.0) / (nf - 1.0)).sqrt()
    }
}
