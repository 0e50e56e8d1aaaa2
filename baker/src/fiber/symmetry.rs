//! Symmetries of a fiber that shrink its BCSDF table (Table 10: "for rotationally symmetric
//! fibers, such as polyester, very few angular samples are needed … fibers with longitudinal
//! symmetry (silk, cotton) require half the measurements than wool").
//!
//! - **Along the axis** (z → −z): any straight extrusion. f(θi, φi; θo, Δφ) =
//!   f(−θi, φi; −θo, Δφ). Wool's cuticle scales point one way, so wool has none.
//! - **Rotations of the section** by 360°/k about its centroid: f depends on φi modulo 360°/k
//!   (Δφ is relative). A circle is symmetric under every rotation: one φi.
//! - **Mirrors of the section** about a line through the centroid at angle α:
//!   f(φi; Δφ) = f(2α − φi; −Δφ).
//!
//! Only symmetries that map bins onto bins are used (360°/k and 2α multiples of the bin
//! width), so the table is exact, not resampled. Detection compares the outline with its
//! transformed self: every transformed vertex must lie within 10⁻⁴ of the mean width of the
//! original outline.

use formats::bcsdf::{FLIP_DPHI, FLIP_THETA};

use super::section::grid::{Segment, SegmentGrid};
use super::{Fiber, Section};

/// Rotational symmetry of the cross-section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Rotation {
    /// Only the identity.
    None,
    /// Rotations by 360°/k.
    Order(u32),
    /// Every rotation (a circle).
    Continuous,
}

/// The symmetry group used for a table.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Symmetry {
    pub z_mirror: bool,
    pub rotation: Rotation,
    /// Angle of a mirror line of the section, degrees in [0, 180).
    pub mirror_deg: Option<f64>,
}

impl Symmetry {
    /// No symmetry: every incoming direction is traced.
    pub const NONE: Symmetry = Symmetry {
        z_mirror: false,
        rotation: Rotation::None,
        mirror_deg: None,
    };

    /// Short description, e.g. `z-mirror, 3-fold, mirror 90°`.
    pub fn describe(&self) -> String {
        let mut p = Vec::new();
        if self.z_mirror {
            p.push("z-mirror".to_string());
        }
        match self.rotation {
            Rotation::None => {}
            Rotation::Order(k) => p.push(format!("{k}-fold")),
            Rotation::Continuous => p.push("rotationally symmetric".into()),
        }
        if let Some(a) = self.mirror_deg {
            p.push(format!("mirror {a}°"));
        }
        if p.is_empty() {
            "none".into()
        } else {
            p.join(", ")
        }
    }

    /// The symmetries both `self` and `o` have (what a table averaging both may use).
    pub fn common(&self, o: &Symmetry) -> Symmetry {
        if self == o {
            return *self;
        }
        Symmetry {
            z_mirror: self.z_mirror && o.z_mirror,
            rotation: Rotation::None,
            mirror_deg: None,
        }
    }

    /// How many incoming bins a table stores on an `n_theta × n_phi` grid.
    pub fn stored_count(&self, n_theta: usize, n_phi: usize, res_deg: f64) -> usize {
        self.wi_map(n_theta, n_phi, res_deg).0.len()
    }

    /// Maps the full grid of incoming bins (`n_theta × n_phi`, θ row-major) to stored ones:
    /// returns the stored bins (full-grid indices, ascending) and, per full bin, the stored
    /// index with [`FLIP_THETA`] / [`FLIP_DPHI`] flags (the `.bcsdf` `wi_map`).
    pub fn wi_map(&self, n_theta: usize, n_phi: usize, res_deg: f64) -> (Vec<usize>, Vec<u32>) {
        let n = n_theta * n_phi;
        let mut map = vec![u32::MAX; n];
        let mut stored = Vec::new();
        let rot_step = match self.rotation {
            Rotation::Order(k) if n_phi % k as usize == 0 => Some(n_phi / k as usize),
            Rotation::Continuous => Some(1),
            _ => None,
        };
        let mirror_m = self
            .mirror_deg
            .map(|a| (2.0 * a / res_deg).round() as i64)
            .filter(|_| self.rotation != Rotation::Continuous);
        for b in 0..n {
            if map[b] != u32::MAX {
                continue;
            }
            let s = stored.len() as u32;
            stored.push(b);
            // Breadth-first over the orbit of b, carrying the flags from b.
            let mut queue = vec![(b, 0u32)];
            map[b] = s;
            while let Some((x, f)) = queue.pop() {
                let (it, jp) = (x / n_phi, x % n_phi);
                let mut next = Vec::with_capacity(3);
                if self.z_mirror {
                    next.push(((n_theta - 1 - it) * n_phi + jp, f ^ FLIP_THETA));
                }
                if let Some(st) = rot_step {
                    next.push((it * n_phi + (jp + st) % n_phi, f));
                }
                if let Some(m) = mirror_m {
                    let j2 = (m - jp as i64 - 1).rem_euclid(n_phi as i64) as usize;
                    next.push((it * n_phi + j2, f ^ FLIP_DPHI));
                }
                for (y, g) in next {
                    if map[y] == u32::MAX {
                        map[y] = s | g;
                        queue.push((y, g));
                    }
                }
            }
        }
        (stored, map)
    }
}

/// Largest rotation order tested.
const MAX_ORDER: u32 = 12;
/// Tolerance of the outline comparison, in units of the mean width.
const TOL: f64 = 1e-4;

/// The symmetries of `fiber` usable on a grid of `res_deg` bins.
pub fn detect(fiber: &Fiber, res_deg: f64) -> Symmetry {
    let z_mirror = fiber.cuticle.is_none();
    let n_phi = (360.0 / res_deg).round() as u32;
    match &fiber.section {
        Section::Conic { rx_um, ry_um } => {
            if (rx_um - ry_um).abs() <= TOL * rx_um.max(*ry_um) {
                return Symmetry {
                    z_mirror,
                    rotation: Rotation::Continuous,
                    mirror_deg: None,
                };
            }
            Symmetry {
                z_mirror,
                rotation: if n_phi % 2 == 0 {
                    Rotation::Order(2)
                } else {
                    Rotation::None
                },
                mirror_deg: Some(0.0),
            }
        }
        Section::Polygon(p) => {
            let c = p.centroid();
            let loops: Vec<Vec<[f64; 2]>> = std::iter::once(p.outer().to_vec())
                .chain(p.holes().iter().cloned())
                .map(|l| l.iter().map(|v| [v[0] - c[0], v[1] - c[1]]).collect())
                .collect();
            let tol = TOL * fiber.section.mean_width_um();
            let near = EdgeGrid::new(&loops);
            let maps = |f: &dyn Fn([f64; 2]) -> [f64; 2]| {
                loops.iter().flatten().all(|&v| near.within(f(v), tol))
            };
            let mut rotation = Rotation::None;
            for k in (2..=MAX_ORDER).rev() {
                if n_phi % k != 0 {
                    continue;
                }
                let (s, co) = (std::f64::consts::TAU / k as f64).sin_cos();
                if maps(&|v| [co * v[0] - s * v[1], s * v[0] + co * v[1]]) {
                    rotation = Rotation::Order(k);
                    break;
                }
            }
            // Mirror lines at multiples of half a bin.
            let steps = (180.0 / (0.5 * res_deg)).round() as usize;
            let mut mirror_deg = None;
            for i in 0..steps {
                let a = i as f64 * 0.5 * res_deg;
                let (s2, c2) = (2.0 * a.to_radians()).sin_cos();
                if maps(&|v| [c2 * v[0] + s2 * v[1], s2 * v[0] - c2 * v[1]]) {
                    mirror_deg = Some(a);
                    break;
                }
            }
            Symmetry {
                z_mirror,
                rotation,
                mirror_deg,
            }
        }
    }
}

/// Squared distance from `q` to the segment `a`–`b`.
fn distance2_to_segment(a: [f64; 2], b: [f64; 2], q: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (a[0] + t * dx - q[0], a[1] + t * dy - q[1]);
    ex * ex + ey * ey
}

/// The edges of closed loops in a [`SegmentGrid`] (about one edge per cell), so "is `q` within
/// `tol` of the outline" looks at the few edges near `q`: a symmetry test of an outline of V
/// vertices costs O(V), not O(V²).
struct EdgeGrid {
    edges: Vec<Segment>,
    grid: SegmentGrid,
}

impl EdgeGrid {
    fn new(loops: &[Vec<[f64; 2]>]) -> EdgeGrid {
        let edges: Vec<Segment> = loops
            .iter()
            .flat_map(|l| (0..l.len()).map(move |i| (l[i], l[(i + 1) % l.len()])))
            .collect();
        let grid = SegmentGrid::new(&edges, (edges.len() as f64).sqrt().clamp(1.0, 2048.0));
        EdgeGrid { edges, grid }
    }

    /// Whether `q` is within `tol` of an edge.
    fn within(&self, q: [f64; 2], tol: f64) -> bool {
        let lo = self.grid.cell_of([q[0] - tol, q[1] - tol]);
        let hi = self.grid.cell_of([q[0] + tol, q[1] + tol]);
        let tol2 = tol * tol;
        (lo[1]..=hi[1]).any(|y| {
            (lo[0]..=hi[0]).any(|x| {
                self.grid.cell(x, y).iter().any(|&e| {
                    let (a, b) = self.edges[e as usize];
                    distance2_to_segment(a, b, q) <= tol2
                })
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fiber::section::generate::{generate, Shape};
    use crate::fiber::{Cuticle, Surface};

    fn fiber(section: Section, cuticle: bool) -> Fiber {
        Fiber {
            section,
            surface: Surface {
                eta: 1.55,
                alpha: 0.05,
            },
            cuticle: cuticle.then_some(Cuticle {
                length_um: 10.0,
                tilt_deg: 3.0,
            }),
        }
    }

    #[test]
    fn detects_circle_trilobal_and_none() {
        let c = detect(&fiber(Section::circle(10.0), false), 2.0);
        assert_eq!(c.rotation, Rotation::Continuous);
        assert!(c.z_mirror);
        let (stored, _) = c.wi_map(90, 180, 2.0);
        assert_eq!(stored.len(), 45);
        let t = detect(
            &fiber(generate(Shape::Trilobal, 10.0, 1, 0).unwrap(), false),
            2.0,
        );
        assert_eq!(t.rotation, Rotation::Order(3), "{t:?}");
        assert!(t.mirror_deg.is_some(), "{t:?}");
        let (stored, _) = t.wi_map(90, 180, 2.0);
        // 45 θ rows × 180 φ bins / 6 (the dihedral group of order 6).
        assert_eq!(stored.len(), 45 * 30);
        let w = detect(
            &fiber(generate(Shape::CottonRaw, 10.0, 3, 0).unwrap(), true),
            2.0,
        );
        assert_eq!(w, Symmetry::NONE);
        assert_eq!(w.wi_map(90, 180, 2.0).0.len(), 90 * 180);
    }

    #[test]
    fn map_flags_are_consistent() {
        let s = Symmetry {
            z_mirror: true,
            rotation: Rotation::Order(2),
            mirror_deg: Some(0.0),
        };
        let (stored, map) = s.wi_map(6, 12, 30.0);
        // Every stored bin maps to itself without flags.
        for (i, &b) in stored.iter().enumerate() {
            assert_eq!(map[b], i as u32);
        }
        // θ row 0 ↔ row 5 with FLIP_THETA; φ bin j ↔ 11 − j (mirror about 0°) with FLIP_DPHI.
        assert_eq!(map[5 * 12 + 3] & FLIP_THETA, FLIP_THETA);
        assert_eq!(
            map[0] & !(FLIP_THETA | FLIP_DPHI),
            map[11] & !(FLIP_THETA | FLIP_DPHI)
        );
        assert_eq!(map[11] & FLIP_DPHI, FLIP_DPHI);
        assert_eq!(stored.len(), 3 * 3);
    }
}
