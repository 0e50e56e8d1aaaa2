//! Mitsuba's local frame of a fiber (`hair.cpp`: tangent local y, normal local z) and its
//! relation to the table frame (fiber axis +z); see the module docs, "Frames".

use super::safe_sqrt;

/// Fiber tangent `y`, normal `z`: Mitsuba's local direction of longitudinal angle θ and
/// azimuth φ (`hair.cpp`: sin θ = w.y, φ = atan2(w.z, w.x)).
pub fn local_direction(theta: f64, phi: f64) -> [f64; 3] {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [ct * cp, st, ct * sp]
}

/// Mitsuba's local incident direction for longitudinal angle θi and offset h ∈ \[−1, 1\]
/// (on the lit side, z ≥ 0): the inverse of `hair.cpp`'s h = sin γ(wi).
pub fn local_wi(theta_i: f64, h: f64) -> [f64; 3] {
    let (st, ct) = theta_i.sin_cos();
    [-h * ct, st, safe_sqrt(1.0 - h * h) * ct]
}

/// Table-frame vector (fiber axis +z) → Mitsuba local vector (fiber axis +y): (x, z, y).
pub fn table_to_local(w: [f64; 3]) -> [f64; 3] {
    [w[0], w[2], w[1]]
}

/// `hair.cpp` `gamma()`: signed angle between w's projection on the x–z plane and z.
pub(super) fn gamma_of(w: [f64; 3]) -> f64 {
    let r = safe_sqrt(w[0] * w[0] + w[2] * w[2]);
    if r == 0.0 {
        return 0.0;
    }
    let g = (w[2] / r).clamp(-1.0, 1.0).acos();
    if w[0] < 0.0 {
        g
    } else {
        -g
    }
}
