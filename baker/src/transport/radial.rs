//! Annular bins of a radial reflectance profile with arbitrary edges: uniform, or fine near the
//! beam and geometric beyond, so one table resolves the peak at r → 0 and the red tail several
//! millimetres out with a hundred-odd bins.

use serde::{Deserialize, Serialize};

/// Bin edges r₀ = 0 < r₁ < … < r_n, mm. Bin k is the annulus [r_k, r_{k+1}).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RadialBins {
    edges_mm: Vec<f64>,
}

impl RadialBins {
    /// `nr` bins of width `dr_mm` (MCML's grid).
    pub fn uniform(dr_mm: f64, nr: usize) -> Self {
        assert!(dr_mm > 0.0 && nr > 0, "invalid uniform grid");
        Self {
            edges_mm: (0..=nr).map(|k| k as f64 * dr_mm).collect(),
        }
    }

    /// Width `dr_min_mm` while that is wider than `growth − 1` times the radius, then each bin
    /// `growth` times wider than the last (log-spaced), up to the first edge ≥ `r_max_mm`.
    /// Relative resolution is what a renderer needs: Δr/r stays ≤ growth − 1 beyond the fine core.
    pub fn fine_then_log(dr_min_mm: f64, growth: f64, r_max_mm: f64) -> Self {
        assert!(
            dr_min_mm > 0.0 && growth > 1.0 && r_max_mm > dr_min_mm,
            "invalid grid"
        );
        let mut edges_mm = vec![0.0];
        let mut r = 0.0f64;
        while r < r_max_mm * (1.0 - 1e-12) {
            r += dr_min_mm.max(r * (growth - 1.0));
            edges_mm.push(r);
        }
        Self { edges_mm }
    }

    /// How many bins [`RadialBins::fine_then_log`] gives, counting no further than `cap + 1`
    /// (so a hostile grid is measured without being built).
    pub fn fine_then_log_count(dr_min_mm: f64, growth: f64, r_max_mm: f64, cap: u64) -> u64 {
        let mut r = 0.0f64;
        let mut n = 0u64;
        while r < r_max_mm * (1.0 - 1e-12) && n <= cap {
            r += dr_min_mm.max(r * (growth - 1.0));
            n += 1;
        }
        n
    }

    /// Explicit edges; they must start at 0 and increase strictly.
    pub fn from_edges(edges_mm: Vec<f64>) -> Result<Self, String> {
        if edges_mm.len() < 2 || edges_mm[0] != 0.0 {
            return Err("radial edges must start at 0 and hold at least one bin".into());
        }
        if !edges_mm.windows(2).all(|w| w[1] > w[0] && w[1].is_finite()) {
            return Err("radial edges must increase strictly and be finite".into());
        }
        Ok(Self { edges_mm })
    }

    pub fn edges_mm(&self) -> &[f64] {
        &self.edges_mm
    }

    pub fn len(&self) -> usize {
        self.edges_mm.len() - 1
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn r_max_mm(&self) -> f64 {
        *self.edges_mm.last().unwrap()
    }

    /// Annulus areas π(r_{k+1}² − r_k²), mm².
    pub fn areas_mm2(&self) -> Vec<f64> {
        self.edges_mm
            .windows(2)
            .map(|w| std::f64::consts::PI * (w[1] * w[1] - w[0] * w[0]))
            .collect()
    }

    /// The bin holding radius `r_mm`, or `None` beyond the last edge.
    #[inline]
    pub fn index(&self, r_mm: f64) -> Option<usize> {
        // First edge > r, minus one: the bin whose [lo, hi) holds r.
        let k = self.edges_mm.partition_point(|&e| e <= r_mm);
        (k >= 1 && k < self.edges_mm.len()).then(|| k - 1)
    }
}

/// Radius where the cumulative energy of `rd` (per unit area, on annuli `edges_mm`) first
/// reaches `target`, interpolating the cumulative linearly in r inside the bin; NaN if never.
pub fn radius_of_energy(edges_mm: &[f64], rd: impl Iterator<Item = f64>, target: f64) -> f64 {
    let mut cum = 0.0;
    for (k, v) in rd.enumerate() {
        let (a, b) = (edges_mm[k], edges_mm[k + 1]);
        let e = v * std::f64::consts::PI * (b * b - a * a);
        if cum + e >= target && e > 0.0 {
            return a + (b - a) * ((target - cum) / e).clamp(0.0, 1.0);
        }
        cum += e;
    }
    f64::NAN
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fine_then_log_is_fine_near_zero_and_relative_beyond() {
        let b = RadialBins::fine_then_log(0.01, 1.05, 20.0);
        let e = b.edges_mm();
        assert!((e[1] - 0.01).abs() < 1e-15);
        assert!(b.r_max_mm() >= 20.0);
        for w in e.windows(2).skip(1) {
            let width = w[1] - w[0];
            assert!(width >= 0.01 - 1e-12);
            assert!(width <= (0.01f64).max(w[0] * 0.05) + 1e-12);
        }
        // About 20 fine bins and ln(20/0.2)/ln(1.05) ≈ 94 log bins.
        assert!((100..130).contains(&b.len()), "{} bins", b.len());
    }

    #[test]
    fn index_finds_the_annulus() {
        let b = RadialBins::from_edges(vec![0.0, 0.1, 0.3, 1.0]).unwrap();
        assert_eq!(b.index(0.0), Some(0));
        assert_eq!(b.index(0.0999), Some(0));
        assert_eq!(b.index(0.1), Some(1));
        assert_eq!(b.index(0.99), Some(2));
        assert_eq!(b.index(1.0), None);
        assert_eq!(b.index(7.0), None);
        let areas: f64 = b.areas_mm2().iter().sum();
        assert!((areas - std::f64::consts::PI).abs() < 1e-12);
    }

    #[test]
    fn bad_edges_are_rejected() {
        assert!(RadialBins::from_edges(vec![0.0]).is_err());
        assert!(RadialBins::from_edges(vec![0.1, 0.2]).is_err());
        assert!(RadialBins::from_edges(vec![0.0, 0.2, 0.2]).is_err());
    }
}
