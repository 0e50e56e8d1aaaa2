//! The angular grid of fiber BCSDF tables (thesis §5.3.2: exiting photons "collected in an
//! infinite sphere bounding the fiber, as a function of ωo = ⟨φo, θo⟩").
//!
//! Conventions: fiber axis +z; θ = asin(ω·z) ∈ [−90°, 90°]; φ = atan2(ω·y, ω·x). The grid has
//! `n_theta = 180/res` θ rows from −90° and `n_phi = 360/res` φ (or Δφ) columns from −180°,
//! all `res_deg` wide; bins are numbered θ row-major, `it · n_phi + jp`. Outgoing azimuths are
//! stored relative to the incident one, Δφ = φo − φi wrapped to [−180°, 180°).
//!
//! The tracer bins photons with it, the `.bcsdf` reader looks directions up with it, and the
//! bakes and exporters place incoming directions at its bin centres: every one of them must
//! compute the same numbers, so the formulas live here only.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use serde::Serialize;

/// Bins of θ × φ (or θo × Δφ) at a resolution that divides 180°.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AngularGrid {
    /// Bin width of θ and φ, degrees.
    pub res_deg: f64,
    /// θ rows, `180 / res_deg`.
    pub n_theta: usize,
    /// φ columns, `360 / res_deg`.
    pub n_phi: usize,
}

impl AngularGrid {
    /// `res_deg` must divide 180 into a whole number of bins (0.25°–30°).
    pub fn new(res_deg: f64) -> Result<Self, String> {
        let n = 180.0 / res_deg;
        if !(0.25..=30.0).contains(&res_deg) || (n - n.round()).abs() > 1e-9 {
            return Err(format!(
                "resolution {res_deg}° must divide 180° into whole bins, within [0.25°, 30°]"
            ));
        }
        let n = n.round() as usize;
        Ok(Self {
            res_deg,
            n_theta: n,
            n_phi: 2 * n,
        })
    }

    /// Number of bins, `n_theta × n_phi`.
    pub fn bins(&self) -> usize {
        self.n_theta * self.n_phi
    }

    /// Flat bin index (θ row-major) of direction `dir` leaving a fiber lit from `phi_i_rad`:
    /// θ row of asin(dir·z), column of Δφ = atan2(dir·y, dir·x) − φi.
    #[inline]
    pub fn bin(&self, dir: [f64; 3], phi_i_rad: f64) -> u32 {
        let theta = dir[2].clamp(-1.0, 1.0).asin();
        let dphi = dir[1].atan2(dir[0]) - phi_i_rad;
        let (it, ip) = self.cell(theta, dphi);
        (it * self.n_phi + ip) as u32
    }

    /// θ row and φ column of angles `theta_rad` (in [−π/2, π/2]) and `phi_rad` (any value:
    /// wrapped to [−π, π) first); the last row and column take the upper edges.
    #[inline]
    pub fn cell(&self, theta_rad: f64, phi_rad: f64) -> (usize, usize) {
        let res = self.res_deg.to_radians();
        let it = (((theta_rad + FRAC_PI_2) / res) as usize).min(self.n_theta - 1);
        let p = phi_rad - TAU * ((phi_rad + PI) / TAU).floor();
        let jp = (((p + PI) / res) as usize).min(self.n_phi - 1);
        (it, jp)
    }

    /// Centre of θ row `it`, degrees.
    #[inline]
    pub fn theta_centre_deg(&self, it: usize) -> f64 {
        -90.0 + (it as f64 + 0.5) * self.res_deg
    }

    /// Centre of φ (or Δφ) column `jp`, degrees.
    #[inline]
    pub fn phi_centre_deg(&self, jp: usize) -> f64 {
        -180.0 + (jp as f64 + 0.5) * self.res_deg
    }

    /// Lower edge of θ row `it`, radians.
    #[inline]
    pub fn theta_lower_rad(&self, it: usize) -> f64 {
        -FRAC_PI_2 + it as f64 * self.res_deg.to_radians()
    }

    /// The `n_theta + 1` θ edges, degrees, from −90° to 90°.
    pub fn theta_edges_deg(&self) -> Vec<f64> {
        (0..=self.n_theta)
            .map(|i| -90.0 + i as f64 * self.res_deg)
            .collect()
    }

    /// The `n_phi + 1` Δφ edges, degrees, from −180° to 180°.
    pub fn dphi_edges_deg(&self) -> Vec<f64> {
        (0..=self.n_phi)
            .map(|i| -180.0 + i as f64 * self.res_deg)
            .collect()
    }

    /// Solid angle of one bin of θ row `it`, sr.
    #[inline]
    pub fn solid_angle(&self, it: usize) -> f64 {
        solid_angle(self.res_deg, it)
    }
}

/// Solid angle of one bin of θ row `it` at `res_deg`, sr: Δφ·(sin θ₁ − sin θ₀).
pub fn solid_angle(res_deg: f64, it: usize) -> f64 {
    let r = res_deg.to_radians();
    let t0 = -FRAC_PI_2 + it as f64 * r;
    r * ((t0 + r).sin() - t0.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_follow_the_conventions() {
        let g = AngularGrid::new(2.0).unwrap();
        assert_eq!((g.n_theta, g.n_phi), (90, 180));
        // Straight back towards the light (Δφ = 0) at θ = 0: θ row 45, Δφ column 90.
        let b = g.bin([1.0, 0.0, 0.0], 0.0);
        assert_eq!(b as usize, 45 * 180 + 90);
        // Forward (Δφ = ±180° wraps to −180°): column 0.
        let b = g.bin([-1.0, 0.0, 0.0], 0.0);
        assert_eq!(b as usize % 180, 0);
        assert!(AngularGrid::new(7.0).is_err());
        let total: f64 = (0..g.n_theta).map(|i| g.solid_angle(i)).sum::<f64>() * g.n_phi as f64;
        assert!((total - 4.0 * PI).abs() < 1e-9);
    }

    #[test]
    fn resolution_limits() {
        assert!(AngularGrid::new(0.25).is_ok());
        assert!(AngularGrid::new(30.0).is_ok());
        assert!(AngularGrid::new(0.2).is_err());
        assert!(AngularGrid::new(36.0).is_err());
        assert!(AngularGrid::new(f64::NAN).is_err());
        let g = AngularGrid::new(30.0).unwrap();
        assert_eq!((g.n_theta, g.n_phi, g.bins()), (6, 12, 72));
    }

    #[test]
    fn centres_and_edges() {
        let g = AngularGrid::new(30.0).unwrap();
        assert_eq!(g.theta_centre_deg(0), -75.0);
        assert_eq!(g.theta_centre_deg(5), 75.0);
        assert_eq!(g.phi_centre_deg(0), -165.0);
        assert_eq!(g.phi_centre_deg(11), 165.0);
        assert_eq!(
            g.theta_edges_deg(),
            vec![-90.0, -60.0, -30.0, 0.0, 30.0, 60.0, 90.0]
        );
        let e = g.dphi_edges_deg();
        assert_eq!((e.len(), e[0], e[12]), (13, -180.0, 180.0));
        assert_eq!(g.theta_lower_rad(0), -FRAC_PI_2);
        assert!((g.theta_lower_rad(3)).abs() < 1e-15);
        // Every centre falls in its own bin.
        for it in 0..g.n_theta {
            for jp in 0..g.n_phi {
                let c = g.cell(
                    g.theta_centre_deg(it).to_radians(),
                    g.phi_centre_deg(jp).to_radians(),
                );
                assert_eq!(c, (it, jp));
            }
        }
    }

    #[test]
    fn cell_wraps_azimuths_and_clamps_the_poles() {
        let g = AngularGrid::new(30.0).unwrap();
        assert_eq!(g.cell(FRAC_PI_2, PI), (5, 0));
        assert_eq!(g.cell(-FRAC_PI_2, -PI), (0, 0));
        assert_eq!(g.cell(0.0, 3.0 * PI - 1e-9), g.cell(0.0, PI - 1e-9));
        assert_eq!(g.cell(0.0, -1e-9).1, 5);
        assert_eq!(g.cell(0.0, TAU + 1e-9).1, 6);
        // A bin's solid angle is the same from the method and the free function.
        assert_eq!(g.solid_angle(2), solid_angle(30.0, 2));
        assert!(g.solid_angle(0) < g.solid_angle(2));
    }
}
