//! A fiber's surface: the Beckmann slope β of its facets (given, or from the roughness's
//! Ra and correlation length) and its cuticle scales (wool's by default).

use super::raw::RawFiber;
use super::FiberCx;
use crate::fiber::material::{FiberType, WOOL_SCALE_LENGTH_UM, WOOL_SCALE_TILT_DEG};
use crate::fiber::Cuticle;
use crate::spec::check::{loc, Bounds};

/// Largest Beckmann slope angle β, degrees, whether given as `beta_deg` or from `roughness`.
pub const MAX_BETA_DEG: f64 = 45.0;

/// `roughness.ra_nm`: arithmetic mean roughness Ra, nm.
pub(in crate::spec) const RA_NM: Bounds = Bounds::closed(0.0, 1000.0);
/// `roughness.l_nm`: correlation length of the roughness, nm.
pub(in crate::spec) const L_NM: Bounds = Bounds::above(0.0, 1e4);
/// `cuticle.length_um`: length of a cuticle scale, µm.
pub(in crate::spec) const CUTICLE_LENGTH_UM: Bounds = Bounds::closed(0.5, 200.0);
/// `cuticle.tilt_deg`: tilt of a cuticle scale, degrees.
pub(in crate::spec) const CUTICLE_TILT_DEG: Bounds = Bounds::closed(0.0, 20.0);

impl FiberCx {
    /// β in degrees: `beta_deg`, or from `roughness`, or the type's (Table 9).
    pub(super) fn beta_deg(&mut self, r: &RawFiber, ft: &FiberType) -> Option<f64> {
        Some(match (&r.beta_deg, &r.roughness) {
            (Some(_), Some(rr)) => {
                self.invalid(
                    loc(rr),
                    "fibers.roughness",
                    "give `beta_deg` or `roughness`, not both",
                );
                return None;
            }
            (Some(b), None) => self.in_range("fibers.beta_deg", b, 0.0, MAX_BETA_DEG, false)?,
            (None, Some(rr)) => {
                let ra = self.in_bounds("fibers.roughness.ra_nm", &rr.value.ra_nm, RA_NM)?;
                let l = self.in_bounds("fibers.roughness.l_nm", &rr.value.l_nm, L_NM)?;
                let beta = (ra / l).atan().to_degrees(); // §5.3.1: β = arctan(Ra/l)
                                                         // The same range as `beta_deg`: the facet model is not meant for steeper slopes.
                if beta > MAX_BETA_DEG {
                    self.out_of_range(
                        loc(rr),
                        "fibers.roughness",
                        format!("ra_nm = {ra}, l_nm = {l} (β = arctan(Ra/l) = {beta:.2}°)"),
                        format!("Ra/l ≤ tan {MAX_BETA_DEG}° = 1, as `beta_deg` is in [0, {MAX_BETA_DEG}]"),
                    );
                    return None;
                }
                beta
            }
            (None, None) => ft.beta_deg(),
        })
    }

    /// The cuticle: as `cuticle:` sets it (on unless `enabled: false`, wool's scale size and
    /// tilt by default), or the type's (wool has one).
    pub(super) fn cuticle(&mut self, r: &RawFiber, ft: &FiberType) -> Option<Cuticle> {
        match &r.cuticle {
            Some(c) => {
                let on = c.value.enabled.as_ref().is_none_or(|e| e.value);
                let len = self.opt_bounds(
                    "fibers.cuticle.length_um",
                    &c.value.length_um,
                    CUTICLE_LENGTH_UM,
                    WOOL_SCALE_LENGTH_UM,
                );
                let tilt = self.opt_bounds(
                    "fibers.cuticle.tilt_deg",
                    &c.value.tilt_deg,
                    CUTICLE_TILT_DEG,
                    WOOL_SCALE_TILT_DEG,
                );
                on.then_some(Cuticle {
                    length_um: len,
                    tilt_deg: tilt,
                })
            }
            None => ft.cuticle.then_some(Cuticle {
                length_um: WOOL_SCALE_LENGTH_UM,
                tilt_deg: WOOL_SCALE_TILT_DEG,
            }),
        }
    }
}
