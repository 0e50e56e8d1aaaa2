//! The outgoing bin of a leaving direction without inverse trigonometry: the tracer's
//! [`AngularGrid::bin`] for one incoming azimuth φi, by table lookup and comparisons.
//!
//! [`AngularGrid::bin`] takes asin(ω·z) for the θ row and atan2 for Δφ = φo − φi, then a floor
//! and a wrap. Cotton's exits are drawn and binned one by one, and those library calls took
//! about 6 % of its thesis bench (`perf`, 2026-12-07). Here:
//! - the θ row of z = ω·z is the number of interior θ edges whose sine is ≤ z: a table over z
//!   in 4·n_θ equal cells gives the row of each cell's lower end, and the rows of the edges
//!   between that and z are stepped over (a few at most, near the poles, where rows are thin
//!   in z);
//! - the Δφ column of (x′, y′), the xy direction turned by −φi, is found the same way over a
//!   pseudo-angle monotone in Δφ (the "diamond angle", one division); the column edges above
//!   the cell's are stepped over by the sign of a cross product with each edge's unit vector.
//!
//! Bins are the grid's: the same rows and columns as [`AngularGrid::bin`], except for a
//! direction within rounding of a bin edge (tested), which either side may claim with equal
//! right.

use formats::AngularGrid;

/// θ lookup cells per θ row.
const Z_CELLS_PER_ROW: usize = 4;
/// Pseudo-angle lookup cells per Δφ column.
const P_CELLS_PER_COL: usize = 4;

/// [`AngularGrid::bin`] for one incoming azimuth, by tables.
#[derive(Debug, Clone)]
pub struct ExitBins {
    n_theta: usize,
    n_phi: usize,
    /// sin of the θ edges −90° + i·res, i = 0 … n_θ.
    sin_edges: Vec<f64>,
    /// Per z cell [−1 + k·dz, −1 + (k + 1)·dz): the row of its lower end.
    z_rows: Vec<u32>,
    /// 1/dz.
    z_scale: f64,
    /// Unit vectors of the Δφ column edges −180° + j·res, j = 0 … n_φ.
    col_edges: Vec<[f64; 2]>,
    /// Per pseudo-angle cell: a column at or below that of every direction in it.
    p_cols: Vec<u32>,
    p_scale: f64,
    /// cos φi, sin φi.
    rot: [f64; 2],
}

impl ExitBins {
    pub fn new(grid: &AngularGrid, phi_i_rad: f64) -> Self {
        let (n_theta, n_phi) = (grid.n_theta, grid.n_phi);
        let res = grid.res_deg.to_radians();
        let sin_edges: Vec<f64> = (0..=n_theta)
            .map(|i| grid.theta_lower_rad(i).sin())
            .collect();
        // A cell's row: the interior edges at or below its lower end, counted by one sweep
        // (cells and edges both ascend).
        let nz = Z_CELLS_PER_ROW * n_theta;
        let z_scale = nz as f64 / 2.0;
        let mut row = 0;
        let z_rows = (0..nz)
            .map(|k| {
                let z = -1.0 + k as f64 / z_scale;
                while row + 1 < n_theta && sin_edges[row + 1] <= z {
                    row += 1;
                }
                row as u32
            })
            .collect();
        let col_edges: Vec<[f64; 2]> = (0..=n_phi)
            .map(|j| {
                let (s, c) = (-std::f64::consts::PI + j as f64 * res).sin_cos();
                [c, s]
            })
            .collect();
        let np = P_CELLS_PER_COL * n_phi;
        let p_scale = np as f64 / 4.0;
        // A cell's lower end as a direction, its angle and column, one column lower for the
        // rounding of the angle (the lookup steps up from it).
        let p_cols = (0..np)
            .map(|k| {
                let [x, y] = unpseudo(-2.0 + k as f64 / p_scale);
                let a = y.atan2(x) + std::f64::consts::PI;
                ((a / res).floor() as usize)
                    .saturating_sub(1)
                    .min(n_phi - 1) as u32
            })
            .collect();
        let (s, c) = phi_i_rad.sin_cos();
        Self {
            n_theta,
            n_phi,
            sin_edges,
            z_rows,
            z_scale,
            col_edges,
            p_cols,
            p_scale,
            rot: [c, s],
        }
    }

    /// Flat bin index (θ row-major) of the unit direction `dir`, as [`AngularGrid::bin`] with
    /// this incoming azimuth.
    #[inline]
    pub fn bin(&self, dir: [f64; 3]) -> u32 {
        (self.row(dir[2]) * self.n_phi + self.column(dir[0], dir[1])) as u32
    }

    #[inline]
    fn row(&self, z: f64) -> usize {
        let z = z.clamp(-1.0, 1.0);
        let k = (((z + 1.0) * self.z_scale) as usize).min(self.z_rows.len() - 1);
        let mut it = self.z_rows[k] as usize;
        while it + 1 < self.n_theta && z >= self.sin_edges[it + 1] {
            it += 1;
        }
        it
    }

    #[inline]
    fn column(&self, x: f64, y: f64) -> usize {
        let [c, s] = self.rot;
        let (xr, yr) = (x * c + y * s, y * c - x * s);
        let k = ((pseudo(xr, yr) + 2.0) * self.p_scale) as usize;
        let mut jp = self.p_cols[k.min(self.p_cols.len() - 1)] as usize;
        // Up while the direction lies at or past the next edge (a cross product ≥ 0: within
        // half a turn of it, as every direction of a cell is of its cell's edges).
        while jp + 1 < self.n_phi {
            let e = self.col_edges[jp + 1];
            if e[0] * yr - e[1] * xr < 0.0 {
                break;
            }
            jp += 1;
        }
        jp
    }
}

/// The diamond angle of (x, y): in (−2, 2], increasing with atan2(y, x) over (−π, π] (0 along
/// +x, 1 along +y, 2 along −x, −1 along −y); (0, 0) counts as +x.
#[inline]
fn pseudo(x: f64, y: f64) -> f64 {
    let s = x.abs() + y.abs();
    let a = if s > 0.0 { x / s } else { 1.0 };
    if y >= 0.0 {
        1.0 - a
    } else {
        a - 1.0
    }
}

/// A direction (not unit) whose [`pseudo`] angle is `p` ∈ [−2, 2].
fn unpseudo(p: f64) -> [f64; 2] {
    if p >= 0.0 {
        let a = 1.0 - p;
        [a, 1.0 - a.abs()]
    } else {
        let a = p + 1.0;
        [a, -(1.0 - a.abs())]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{batch_rng, uniform};
    use rand_core::Rng;

    /// The grid's bin for random directions, for several resolutions and incoming azimuths,
    /// and for directions on and next to every bin edge; where the two differ the direction
    /// lies within rounding of an edge the two sides of which they chose.
    #[test]
    fn bins_are_the_grids() {
        let mut rng = batch_rng(3, 0);
        let mut u = || uniform(rng.next_u64());
        for res in [2.0, 6.0, 0.25, 30.0, 4.5] {
            let g = AngularGrid::new(res).unwrap();
            for phi_i_deg in [0.0, 1.0, -179.0, 37.3, 180.0] {
                let phi_i = f64::to_radians(phi_i_deg);
                let eb = ExitBins::new(&g, phi_i);
                let mut dirs = Vec::new();
                for _ in 0..20_000 {
                    let z = 2.0 * u() - 1.0;
                    let r = (1.0 - z * z).sqrt();
                    let (s, c) = (std::f64::consts::TAU * u()).sin_cos();
                    dirs.push([r * c, r * s, z]);
                }
                // On and around the edges of every row and column (absolute azimuth φi + Δφ).
                let (si, sj) = ((g.n_theta / 45).max(1), (g.n_phi / 90).max(1));
                for i in (0..=g.n_theta).step_by(si) {
                    for j in (0..=g.n_phi).step_by(sj) {
                        for (dt, dp) in [(0.0, 0.0), (1e-9, 1e-9), (-1e-9, -1e-9), (0.3, 0.7)] {
                            let th = (-90.0 + (i as f64 + dt) * res).clamp(-90.0, 90.0);
                            let ph = phi_i_deg - 180.0 + (j as f64 + dp) * res;
                            let (st, ct) = th.to_radians().sin_cos();
                            let (sp, cp) = ph.to_radians().sin_cos();
                            dirs.push([ct * cp, ct * sp, st]);
                        }
                    }
                }
                dirs.extend([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [-1.0, -0.0, 0.0]]);
                for d in dirs {
                    let (a, b) = (eb.bin(d), g.bin(d, phi_i));
                    if a != b {
                        let near = |x: f64| (x - x.round()).abs() < 1e-7;
                        let th = d[2].clamp(-1.0, 1.0).asin().to_degrees();
                        let dphi = d[1].atan2(d[0]).to_degrees() - phi_i_deg;
                        let on_edge = near((th + 90.0) / res)
                            || near((dphi + 180.0) / res)
                            || d[0].hypot(d[1]) < 1e-12;
                        assert!(
                            on_edge,
                            "res {res} φi {phi_i_deg}: {d:?} → {a} against the grid's {b}"
                        );
                        // The neighbouring bin, not any other: one row or one column apart.
                        let n = g.n_phi as i64;
                        let (ra, ca) = (a as i64 / n, a as i64 % n);
                        let (rb, cb) = (b as i64 / n, b as i64 % n);
                        let dc = (ca - cb).rem_euclid(n).min((cb - ca).rem_euclid(n));
                        assert!(
                            (ra - rb).abs() + dc <= 2 || d[0].hypot(d[1]) < 1e-12,
                            "res {res} φi {phi_i_deg}: {d:?} → {a} against {b}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn pseudo_angles_invert_and_increase() {
        let mut last = -2.0;
        for k in 1..=4000 {
            let a = -std::f64::consts::PI + k as f64 * std::f64::consts::TAU / 4000.0;
            let p = pseudo(a.cos(), a.sin());
            assert!(p > last, "{a}: {p} after {last}");
            last = p;
            let [x, y] = unpseudo(p);
            assert!((pseudo(x, y) - p).abs() < 1e-12);
        }
    }
}
