//! Fresnel reflection and refraction at an index mismatch (unpolarised light): the transport's
//! names for [`crate::math::fresnel`] (`fresnel(ni, nt, cos_i) -> (R, cos θt)`).

pub use crate::math::fresnel::{dielectric as fresnel, normal_reflectance};
