//! Parametric cross-sections per fiber type, with seeded variability (§5.3: "we analyzed SEM
//! samples of real fibers, and manually modeled a representative set of different cross
//! sections for each type"; Fig. 59, Table 8). Every outline is centred on its area centroid,
//! has its long axis along x, and is scaled so that its mean projected width equals the
//! requested diameter (Table 9 diameters are microscope widths).
//!
//! Shape parameters are our reading of the SEM literature the thesis cites (Hearle & Morton
//! \[104\]; Trotman \[219\]), stated per generator below; the ranges are deliberately wide so
//! that a set of seeded variants spans the variability of Fig. 64.

use std::f64::consts::{PI, TAU};

use rand_core::Rng;

use super::{Polygon, Section, SectionError};
use crate::math::rng::{batch_rng, uniform, BatchRng};

/// Vertices per generated outline: caustics are resolved to well under the 2° bins (the
/// normal turns by at most 360°/256 ≈ 1.4° between vertices of a round outline, less on
/// flat sides).
pub const OUTLINE_VERTICES: usize = 256;

/// The parametric shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Shape {
    /// Polyester: melt-spun through a round spinneret, an exact circle.
    Circle,
    /// Polyester from a trilobal spinneret: r(θ) = 1 + a·cos 3θ, a ∈ [0.18, 0.26].
    Trilobal,
    /// Silk fibroin filament: an irregular, flattened, rounded triangle: harmonics 2–6 with
    /// random amplitudes and phases (a₃ ∈ [0.08, 0.16], a₂ ∈ [0.04, 0.12], a₄..₆ ≤ 0.02), then
    /// flattened to a y/x ratio in [0.55, 0.8].
    Silk,
    /// Raw (untreated) cotton: a collapsed tube, a bean with a slit lumen. Outer: ellipse with
    /// b/a ∈ [0.30, 0.45] bent along an arc of curvature κ·a ∈ [0.5, 0.9]; lumen: a thin
    /// ellipse along the mid-line, half-length ∈ [0.45, 0.65]·a, half-width ∈ [0.15, 0.3]·b.
    CottonRaw,
    /// Mercerised cotton: swollen in caustic soda, rounder (b/a ∈ [0.65, 0.85], κ·a ≤ 0.3)
    /// with a small round lumen (half-axes [0.12, 0.2]·a × [0.3, 0.5]·b).
    CottonMercerised,
    /// Wool: near-elliptical, axis ratio in [0.85, 0.95], exact conic. Cuticle scales are a
    /// longitudinal variation added by the tracer ([`crate::fiber::Cuticle`]).
    Wool,
}

impl Shape {
    pub const ALL: [(&'static str, Shape); 6] = [
        ("circle", Shape::Circle),
        ("trilobal", Shape::Trilobal),
        ("silk", Shape::Silk),
        ("cotton_raw", Shape::CottonRaw),
        ("cotton_mercerised", Shape::CottonMercerised),
        ("wool", Shape::Wool),
    ];

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|s| s.1 == self)
            .map(|s| s.0)
            .unwrap_or("?")
    }
}

struct Draw(BatchRng);

impl Draw {
    fn u(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * uniform(self.0.next_u64())
    }
}

/// Variant `variant` of `shape` for seed `seed`, scaled to a mean width of `diameter_um`.
pub fn generate(
    shape: Shape,
    diameter_um: f64,
    seed: u64,
    variant: u64,
) -> Result<Section, SectionError> {
    let mut r = Draw(batch_rng(seed ^ 0x5ec7_1045, variant));
    let n = OUTLINE_VERTICES;
    let section = match shape {
        Shape::Circle => Section::circle(1.0),
        Shape::Wool => Section::Conic {
            rx_um: 1.0,
            ry_um: r.u(0.85, 0.95),
        },
        Shape::Trilobal => {
            let a = r.u(0.18, 0.26);
            polar(n, |t| 1.0 + a * (3.0 * t).cos(), 1.0)?
        }
        Shape::Silk => {
            let mut harm = vec![(3.0, r.u(0.08, 0.16), r.u(0.0, TAU))];
            harm.push((2.0, r.u(0.04, 0.12), r.u(0.0, TAU)));
            for k in 4..=6 {
                harm.push((k as f64, r.u(0.0, 0.02), r.u(0.0, TAU)));
            }
            let flat = r.u(0.55, 0.8);
            polar(
                n,
                |t| {
                    1.0 + harm
                        .iter()
                        .map(|(k, a, p)| a * (k * t + p).cos())
                        .sum::<f64>()
                },
                flat,
            )?
        }
        Shape::CottonRaw | Shape::CottonMercerised => {
            let raw = shape == Shape::CottonRaw;
            let b = if raw {
                r.u(0.30, 0.45)
            } else {
                r.u(0.65, 0.85)
            };
            let kappa = if raw { r.u(0.5, 0.9) } else { r.u(0.0, 0.3) };
            let (la, lb) = if raw {
                (r.u(0.45, 0.65), r.u(0.15, 0.3) * b)
            } else {
                (r.u(0.12, 0.2), r.u(0.3, 0.5) * b)
            };
            // Small wall-thickness irregularity (harmonics 3–5, ≤ 3 % of b).
            let wob: Vec<(f64, f64, f64)> = (3..=5)
                .map(|k| (k as f64, r.u(0.0, 0.03) * b, r.u(0.0, TAU)))
                .collect();
            let outer: Vec<[f64; 2]> = (0..n)
                .map(|i| {
                    let t = TAU * i as f64 / n as f64;
                    let w: f64 = wob.iter().map(|(k, a, p)| a * (k * t + p).sin()).sum();
                    bend([t.cos(), (b + w) * t.sin()], kappa)
                })
                .collect();
            let m = n / 4;
            let lumen: Vec<[f64; 2]> = (0..m)
                .map(|i| {
                    let t = TAU * i as f64 / m as f64;
                    bend([la * t.cos(), lb * t.sin()], kappa)
                })
                .collect();
            Section::Polygon(Polygon::new(outer, vec![lumen])?)
        }
    };
    let centred = match section {
        Section::Polygon(p) => {
            let c = p.centroid();
            Section::Polygon(p.transformed(c, 1.0)?)
        }
        s => s,
    };
    centred.scaled_to_diameter(diameter_um)
}

/// r(θ) sampled at `n` angles, then y scaled by `flat`.
fn polar(n: usize, r: impl Fn(f64) -> f64, flat: f64) -> Result<Section, SectionError> {
    let pts = (0..n)
        .map(|i| {
            let t = TAU * i as f64 / n as f64;
            let rr = r(t);
            [rr * t.cos(), flat * rr * t.sin()]
        })
        .collect();
    Ok(Section::Polygon(Polygon::new(pts, vec![])?))
}

/// Bends the x axis onto an arc of curvature `kappa` (centre at (0, 1/κ)): a flat ribbon
/// becomes the kidney shape of a collapsed cotton tube.
fn bend(p: [f64; 2], kappa: f64) -> [f64; 2] {
    if kappa.abs() < 1e-9 {
        return p;
    }
    let rc = 1.0 / kappa;
    let a = (p[0] * kappa).clamp(-PI, PI);
    [(rc - p[1]) * a.sin(), rc - (rc - p[1]) * a.cos()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shape_builds_with_its_diameter_and_is_seeded() {
        for (name, s) in Shape::ALL {
            for v in 0..6 {
                let sec = generate(s, 17.0, 42, v).unwrap_or_else(|e| panic!("{name} v{v}: {e}"));
                assert!((sec.mean_width_um() - 17.0).abs() < 1e-9, "{name}");
                let again = generate(s, 17.0, 42, v).unwrap();
                assert_eq!(sec.area_um2(), again.area_um2());
            }
        }
        let a = generate(Shape::Silk, 8.0, 1, 0).unwrap().area_um2();
        let b = generate(Shape::Silk, 8.0, 1, 1).unwrap().area_um2();
        assert_ne!(a, b, "variants differ");
    }

    #[test]
    fn cotton_has_a_lumen_and_raw_is_flatter() {
        let raw = generate(Shape::CottonRaw, 18.0, 3, 0).unwrap();
        let mer = generate(Shape::CottonMercerised, 18.0, 3, 0).unwrap();
        assert_eq!(raw.hole_count(), 1);
        assert_eq!(mer.hole_count(), 1);
        // Same mean width: the rounder mercerised section encloses more area.
        assert!(mer.area_um2() > raw.area_um2());
    }
}
