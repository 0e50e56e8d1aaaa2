//! The layer stack a transport run takes: plain numbers, validated once.

use std::fmt;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// One laterally infinite layer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    pub name: String,
    /// Thickness, mm; `f64::INFINITY` for a semi-infinite last layer.
    pub d_mm: f64,
    pub eta: f64,
    pub mua_per_mm: f64,
    pub mus_per_mm: f64,
    /// Henyey–Greenstein anisotropy g ∈ (−1, 1).
    pub g: f64,
}

/// The non-planar interface between layer `upper_layer` and the next one (thesis Eq. 1):
/// z = z̄ + A·sin(ωx·x + φx)·sin(ωy·y + φy), z̄ the planar bottom of `upper_layer`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Junction {
    pub upper_layer: usize,
    pub amplitude_mm: f64,
    pub omega_x_per_mm: f64,
    pub omega_y_per_mm: f64,
    #[serde(default)]
    pub phi_x_rad: f64,
    #[serde(default)]
    pub phi_y_rad: f64,
}

/// Uniform annular grid of the radial reflectance profile Rd(r) of a direct run (MCML's `dr`,
/// `nr`): `nr` annuli of width `dr_mm` from the beam. (Profiles with arbitrary edges use
/// [`super::RadialBins`].)
#[derive(Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RadialGrid {
    pub dr_mm: f64,
    pub nr: usize,
}

/// Prints the type's former name `Grid`: skin cache keys hash the `Debug` rendering of a
/// [`Stack`] (`pipeline::KeyBuilder::part`), and a rename must not change them.
impl fmt::Debug for RadialGrid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Grid")
            .field("dr_mm", &self.dr_mm)
            .field("nr", &self.nr)
            .finish()
    }
}

impl Default for RadialGrid {
    fn default() -> Self {
        RadialGrid {
            dr_mm: 0.01,
            nr: 500,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Stack {
    /// Refractive index above the surface and below the last layer.
    pub n_above: f64,
    pub n_below: f64,
    pub layers: Vec<Layer>,
    pub junction: Option<Junction>,
    pub grid: RadialGrid,
}

#[derive(Debug, Error, PartialEq)]
pub enum StackError {
    #[error("the stack has no layers")]
    Empty,
    #[error("at most {max} layers are supported, got {got}")]
    TooManyLayers { max: usize, got: usize },
    #[error("layer {index} ({name}): {field} = {value} is out of range; allowed: {allowed}")]
    OutOfRange {
        index: usize,
        name: String,
        field: &'static str,
        value: f64,
        allowed: &'static str,
    },
    #[error("{field} = {value} is out of range; allowed: {allowed}")]
    Global {
        field: &'static str,
        value: f64,
        allowed: &'static str,
    },
    #[error("only the last layer may be semi-infinite (layer {index} is)")]
    InfiniteNotLast { index: usize },
    #[error("junction: {0}")]
    Junction(String),
}

/// Most layers a stack may have (per-photon accumulators live on the stack).
pub const MAX_LAYERS: usize = 16;

impl Stack {
    /// Checks every value; the engine relies on these invariants.
    pub fn validate(&self) -> Result<(), StackError> {
        if self.layers.is_empty() {
            return Err(StackError::Empty);
        }
        if self.layers.len() > MAX_LAYERS {
            return Err(StackError::TooManyLayers {
                max: MAX_LAYERS,
                got: self.layers.len(),
            });
        }
        for (field, value) in [("n_above", self.n_above), ("n_below", self.n_below)] {
            if !(value.is_finite() && (1.0..=5.0).contains(&value)) {
                return Err(StackError::Global {
                    field,
                    value,
                    allowed: "[1, 5]",
                });
            }
        }
        if !(self.grid.dr_mm.is_finite() && self.grid.dr_mm > 0.0) {
            return Err(StackError::Global {
                field: "grid.dr_mm",
                value: self.grid.dr_mm,
                allowed: "> 0",
            });
        }
        if self.grid.nr == 0 || self.grid.nr > 100_000 {
            return Err(StackError::Global {
                field: "grid.nr",
                value: self.grid.nr as f64,
                allowed: "[1, 100000]",
            });
        }
        let last = self.layers.len() - 1;
        for (i, l) in self.layers.iter().enumerate() {
            let bad = |field, value, allowed| StackError::OutOfRange {
                index: i,
                name: l.name.clone(),
                field,
                value,
                allowed,
            };
            if l.d_mm.is_infinite() && l.d_mm > 0.0 {
                if i != last {
                    return Err(StackError::InfiniteNotLast { index: i });
                }
            } else if !(l.d_mm.is_finite() && l.d_mm > 0.0) {
                return Err(bad("d_mm", l.d_mm, "> 0, or \"inf\" for the last layer"));
            }
            if !(l.eta.is_finite() && (1.0..=5.0).contains(&l.eta)) {
                return Err(bad("eta", l.eta, "[1, 5]"));
            }
            if !(l.mua_per_mm.is_finite() && l.mua_per_mm >= 0.0) {
                return Err(bad("mua_per_mm", l.mua_per_mm, ">= 0"));
            }
            if !(l.mus_per_mm.is_finite() && l.mus_per_mm >= 0.0) {
                return Err(bad("mus_per_mm", l.mus_per_mm, ">= 0"));
            }
            if !(l.g.is_finite() && l.g > -1.0 && l.g < 1.0) {
                return Err(bad("g", l.g, "(-1, 1)"));
            }
            if l.d_mm.is_infinite() && l.mua_per_mm == 0.0 && l.mus_per_mm == 0.0 {
                return Err(bad(
                    "mua_per_mm",
                    0.0,
                    "> 0 or mus > 0 in a semi-infinite layer",
                ));
            }
        }
        if let Some(j) = &self.junction {
            let u = j.upper_layer;
            if u + 1 >= self.layers.len() {
                return Err(StackError::Junction(format!(
                    "upper_layer {u} needs a layer below it (the stack has {})",
                    self.layers.len()
                )));
            }
            if !(j.amplitude_mm.is_finite() && j.amplitude_mm >= 0.0) {
                return Err(StackError::Junction(format!(
                    "amplitude_mm = {} must be >= 0",
                    j.amplitude_mm
                )));
            }
            let (above, below) = (self.layers[u].d_mm, self.layers[u + 1].d_mm);
            if j.amplitude_mm > 0.0 && (j.amplitude_mm >= above || j.amplitude_mm >= below) {
                return Err(StackError::Junction(format!(
                    "amplitude_mm = {} must be below the thickness of both layers it separates ({above} and {below} mm)",
                    j.amplitude_mm
                )));
            }
            for (name, v) in [
                ("omega_x_per_mm", j.omega_x_per_mm),
                ("omega_y_per_mm", j.omega_y_per_mm),
                ("phi_x_rad", j.phi_x_rad),
                ("phi_y_rad", j.phi_y_rad),
            ] {
                if !v.is_finite() {
                    return Err(StackError::Junction(format!("{name} = {v} must be finite")));
                }
            }
        }
        Ok(())
    }

    /// Depth of the top of each layer and the bottom of the last, mm.
    pub fn boundaries_mm(&self) -> Vec<f64> {
        let mut z = vec![0.0];
        for l in &self.layers {
            z.push(z.last().unwrap() + l.d_mm);
        }
        z
    }
}

/// `STACK.json` as users write it (`d_mm` may be the string "inf").
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StackFile {
    pub n_above: f64,
    pub n_below: f64,
    pub layers: Vec<LayerFile>,
    #[serde(default)]
    pub grid: Option<RadialGrid>,
    #[serde(default)]
    pub junction: Option<Junction>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerFile {
    #[serde(default)]
    pub name: Option<String>,
    pub d_mm: Thickness,
    pub eta: f64,
    pub mua_per_mm: f64,
    pub mus_per_mm: f64,
    #[serde(default)]
    pub g: f64,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum Thickness {
    Mm(f64),
    Text(String),
}

impl StackFile {
    pub fn into_stack(self) -> Result<Stack, StackError> {
        let mut layers = Vec::new();
        for (i, l) in self.layers.into_iter().enumerate() {
            let d_mm = match l.d_mm {
                Thickness::Mm(x) => x,
                Thickness::Text(s) if s == "inf" => f64::INFINITY,
                Thickness::Text(_) => f64::NAN,
            };
            layers.push(Layer {
                name: l.name.unwrap_or_else(|| format!("layer {i}")),
                d_mm,
                eta: l.eta,
                mua_per_mm: l.mua_per_mm,
                mus_per_mm: l.mus_per_mm,
                g: l.g,
            });
        }
        let s = Stack {
            n_above: self.n_above,
            n_below: self.n_below,
            layers,
            junction: self.junction,
            grid: self.grid.unwrap_or_default(),
        };
        s.validate()?;
        Ok(s)
    }
}

/// The stack of a skin entry at wavelength index `i` (thesis §3.5): μs = μs′ with g = 0, air
/// above, and below the hypodermis a medium of the hypodermis's own index, so light leaving
/// the bottom is lost as transmittance. The junction comes from Eq. 1 when it is non-planar.
pub fn from_skin(e: &formats::OpticsEntry, i: usize) -> Stack {
    let layers: Vec<Layer> = e
        .layers
        .iter()
        .map(|l| Layer {
            name: l.name.clone(),
            d_mm: l.d_mm,
            eta: l.eta,
            mua_per_mm: l.mua_per_mm[i],
            mus_per_mm: l.musp_per_mm[i],
            g: 0.0,
        })
        .collect();
    let n_below = layers.last().map_or(1.0, |l| l.eta);
    let j = &e.junction;
    let junction = (j.amplitude_mm > 0.0 && e.model == "five_layer").then_some(Junction {
        upper_layer: 1,
        amplitude_mm: j.amplitude_mm,
        omega_x_per_mm: j.omega_x_per_mm,
        omega_y_per_mm: j.omega_y_per_mm,
        phi_x_rad: j.phi_x_rad,
        phi_y_rad: j.phi_y_rad,
    });
    Stack {
        n_above: 1.0,
        n_below,
        layers,
        junction,
        grid: RadialGrid::default(),
    }
}

/// Tests' shorthand: `layer` alone between two index-1 media, no junction, on `nr` annuli of
/// `dr_mm`.
#[cfg(test)]
impl Stack {
    pub(crate) fn in_air(layer: Layer, dr_mm: f64, nr: usize) -> Stack {
        Stack {
            n_above: 1.0,
            n_below: 1.0,
            layers: vec![layer],
            junction: None,
            grid: RadialGrid { dr_mm, nr },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skin::{self, BodyLocation, Gender, MelaninInput, SkinParams, SkinType};
    use crate::spectral::WavelengthGrid;

    /// Issue 22, the junction: a skin entry's Eq. 1 reaches the photon loop unchanged. The
    /// defaults are pinned against the thesis (§3.4.1 and Table 4's caption: 100 µm rete
    /// ridges at 30, flat at 80; DECISIONS.md #18: peak amplitude A = 50 µm, half the 100 µm
    /// peak-to-valley, period 100 µm), and the engine's height field (z̄ = bottom of the
    /// living epidermis in the stack) equals Eq. 1 evaluated from the optics document's
    /// junction at many points, written out here independently.
    #[test]
    fn skin_junction_reaches_the_engine_as_eq1() {
        let grid = WavelengthGrid::uniform(500.0, 600.0, 50.0);
        for (age, a_mm) in [(30.0, 0.050), (55.0, 0.025), (70.0, 0.010)] {
            let p = SkinParams::new(
                age,
                Gender::Female,
                BodyLocation::Forearm,
                MelaninInput::SkinType(SkinType::II),
                0.5,
            );
            let o = skin::evaluate(&p, &grid).unwrap();
            let e = skin::document::entry("e", &p, &o);
            let j = e.junction;
            assert!(
                (j.amplitude_mm - a_mm).abs() < 1e-12,
                "A at {age}: {}",
                j.amplitude_mm
            );
            for w in [j.omega_x_per_mm, j.omega_y_per_mm] {
                assert!(
                    (std::f64::consts::TAU / w - 0.1).abs() < 1e-12,
                    "period {}",
                    std::f64::consts::TAU / w
                );
            }
            let z_bar = e.layers[0].d_mm + e.layers[1].d_mm;
            assert!((j.z_mean_mm - z_bar).abs() < 1e-15);
            let stack = from_skin(&e, 1);
            let prepared = super::super::engine::Prepared::new(&stack).unwrap();
            let (upper, field) = prepared.junction.expect("a non-planar junction");
            assert_eq!(upper, 1);
            for k in 0..400 {
                let (x, y) = (0.0137 * k as f64 - 2.0, 0.0291 * (k % 37) as f64 - 0.5);
                let eq1 = j.z_mean_mm
                    + j.amplitude_mm
                        * (j.omega_x_per_mm * x + j.phi_x_rad).sin()
                        * (j.omega_y_per_mm * y + j.phi_y_rad).sin();
                assert!(
                    (field.z(x, y) - eq1).abs() < 1e-13,
                    "({x}, {y}): {} vs {eq1}",
                    field.z(x, y)
                );
            }
        }
        // Flat at 80 (Table 4): no junction in the stack.
        let p = SkinParams::new(
            80.0,
            Gender::Female,
            BodyLocation::Forearm,
            MelaninInput::SkinType(SkinType::II),
            0.5,
        );
        let e = skin::document::entry("e", &p, &skin::evaluate(&p, &grid).unwrap());
        assert_eq!(e.junction.amplitude_mm, 0.0);
        assert!(from_skin(&e, 0).junction.is_none());
    }

    /// Cache keys of skin bakes hash `format!("{stack:?}")`: the rendering must not change.
    #[test]
    fn radial_grid_debug_keeps_the_cache_key_rendering() {
        assert_eq!(
            format!("{:?}", RadialGrid::default()),
            "Grid { dr_mm: 0.01, nr: 500 }"
        );
    }

    fn slab() -> Stack {
        Stack {
            n_above: 1.0,
            n_below: 1.0,
            layers: vec![Layer {
                name: "slab".into(),
                d_mm: 1.0,
                eta: 1.4,
                mua_per_mm: 0.1,
                mus_per_mm: 10.0,
                g: 0.5,
            }],
            junction: None,
            grid: RadialGrid::default(),
        }
    }

    /// The ranges `validate` allows, at their edges: what is inside passes, the first value
    /// outside names its field and range.
    #[test]
    fn validation_accepts_the_edges_and_refuses_beyond() {
        let ok = |f: &dyn Fn(&mut Stack)| {
            let mut s = slab();
            f(&mut s);
            s.validate()
        };
        assert!(ok(&|s| s.grid.nr = 100_000).is_ok());
        let e = ok(&|s| s.grid.nr = 100_001).unwrap_err().to_string();
        assert!(e.contains("grid.nr") && e.contains("[1, 100000]"), "{e}");
        assert!(ok(&|s| s.grid.nr = 0).is_err());
        assert!(ok(&|s| s.layers[0].eta = 1.0).is_ok());
        assert!(ok(&|s| s.layers[0].eta = 5.0).is_ok());
        assert!(ok(&|s| s.layers[0].eta = 5.0001).is_err());
        assert!(ok(&|s| s.layers[0].eta = 0.9999).is_err());
        assert!(ok(&|s| s.layers[0].g = 0.999).is_ok());
        assert!(ok(&|s| s.layers[0].g = 1.0)
            .unwrap_err()
            .to_string()
            .contains("(-1, 1)"));
        assert!(ok(&|s| s.layers[0].g = -1.0).is_err());
        assert!(ok(&|s| s.layers[0].mua_per_mm = 0.0).is_ok());
        assert!(ok(&|s| s.layers[0].mua_per_mm = -1e-9).is_err());
        assert!(ok(&|s| s.layers[0].mus_per_mm = -1e-9).is_err());
        assert!(ok(&|s| s.grid.dr_mm = 0.0).is_err());
        assert!(ok(&|s| s.layers[0].d_mm = f64::INFINITY).is_ok());
        assert!(ok(&|s| {
            s.layers[0].d_mm = f64::INFINITY;
            s.layers[0].mua_per_mm = 0.0;
            s.layers[0].mus_per_mm = 0.0;
        })
        .is_err());
    }

    /// The three-layer model (§3.6.1) has a flat junction even where Eq. 1's amplitude is not
    /// zero: its stack carries none.
    #[test]
    fn three_layer_stacks_are_flat() {
        let grid = WavelengthGrid::uniform(500.0, 600.0, 50.0);
        let mut p = SkinParams::new(
            30.0,
            Gender::Female,
            BodyLocation::Forearm,
            MelaninInput::SkinType(SkinType::II),
            0.5,
        );
        p.model = crate::skin::ModelKind::ThreeLayer;
        let e = skin::document::entry("e", &p, &skin::evaluate(&p, &grid).unwrap());
        assert_eq!(e.model, "three_layer");
        let mut forced = e.clone();
        forced.junction.amplitude_mm = 0.05;
        assert!(from_skin(&forced, 0).junction.is_none());
        assert_eq!(from_skin(&forced, 0).layers.len(), 3);
    }
}
