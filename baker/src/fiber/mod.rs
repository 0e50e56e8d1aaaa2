//! Textile fibers (thesis ch. 5): realistic cross-sections ([`section`]), Table 9 materials
//! ([`material`]), rough dielectric boundaries ([`surface`]), dye absorption ([`dye`]), and a
//! brute-force photon tracer for a single straight fiber in the far field ([`tracer`], §5.3.2)
//! whose exiting photons are binned over the outgoing sphere ([`tally`]).
//!
//! Conventions (also in README "Fibers"): fiber axis +z; ωi points towards the light, ωo is
//! the direction a photon leaves in; θ = asin(ω·z), φ = atan2(ω·y, ω·x). Lengths in µm.

pub mod dye;
pub mod exit_bins;
pub mod lobe;
pub mod material;
mod scratch;
pub mod section;
pub mod slices;
pub mod surface;
pub mod sweep;
pub mod symmetry;
pub mod tally;
pub mod tracer;

pub use formats::AngularGrid;
pub use section::Section;
pub use surface::Surface;
pub use tally::DirectionTally;
pub use tracer::{trace, Incident, TraceOptions, TraceResult};

/// Wool's cuticle scales as a periodic variation along the axis (§5.3, "we approximate this
/// effect by modeling shape variations along the longitudinal axis"): within each scale of
/// length L the section grows linearly, s(z) = 1 + (tan α / r̄)·(z mod L), so the surface
/// rises with slope tan α (the scale's tilt), then steps back down at the scale's free edge
/// (a ring face normal to the axis). Scales point to +z (the fiber tip).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Cuticle {
    /// Scale interval along the axis, µm.
    pub length_um: f64,
    /// Tilt of the scale surface against the axis, degrees.
    pub tilt_deg: f64,
}

/// One fiber ready to trace.
#[derive(Debug, Clone)]
pub struct Fiber {
    pub section: Section,
    pub surface: Surface,
    pub cuticle: Option<Cuticle>,
}

impl Fiber {
    /// ds/dz of the cuticle scaling, per µm, and the largest scale s_max = 1 + L·ds/dz.
    pub fn cuticle_slope(&self) -> Option<(f64, f64)> {
        self.cuticle.map(|c| {
            let r_mean = 0.5 * self.section.mean_width_um();
            let k = c.tilt_deg.to_radians().tan() / r_mean;
            (k, 1.0 + k * c.length_um)
        })
    }

    /// Projected area per unit length A(ω) for light arriving from azimuth `phi_rad`, µm
    /// (µm²/µm): the shadow width of the section, averaged along the axis for cuticles.
    /// Multiply by cos θ for the area seen along ω (Eq. 17's sin(ω, ω_f)).
    pub fn projected_width_um(&self, phi_rad: f64) -> f64 {
        let w = self.section.projected_width_um(phi_rad);
        match self.cuticle_slope() {
            Some((_, s_max)) => w * 0.5 * (1.0 + s_max),
            None => w,
        }
    }
}
