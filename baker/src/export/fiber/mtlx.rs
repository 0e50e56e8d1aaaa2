//! `mtlx`: a MaterialX 1.39 document holding one `chiang_hair_bsdf` (pbrlib), its `surface`
//! and a `surfacematerial`.
//!
//! The nodedef (`libraries/pbrlib/pbrlib_defs.mtlx`, `ND_chiang_hair_bsdf`): `tint_R`,
//! `tint_TT`, `tint_TRT` (color3), `ior` (float), `roughness_R`, `roughness_TT`,
//! `roughness_TRT` (vector2), `cuticle_angle` (float, \[0, 1\]), `absorption_coefficient`
//! (vector3), `normal`, `curve_direction` (geometric defaults `Nworld`, `Tworld`). Its GLSL
//! implementation (`libraries/pbrlib/genglsl/mx_chiang_hair_bsdf.glsl`) fixes the units:
//! - `roughness_*` = (v, s): the longitudinal variance and the logistic scale *before* the
//!   √(π/8) factor, which `mx_hair_trimmed_logistic` applies (`s *= 0.626657`). They are what
//!   `mx_chiang_hair_roughness(β_m, β_n, scale_TT = 0.5, scale_TRT = 2)` returns:
//!   v_R = (0.726β_m + 0.812β_m² + 3.7β_m²⁰)², v_TT = v_R/4, v_TRT = 4·v_R,
//!   s = 0.265β_n + 1.194β_n² + 5.372β_n²² — the same v and s (with √(π/8)) as Mitsuba's
//!   `hair.cpp`, whose model the fit is. They are written as values: the OSL implementation of
//!   `chiang_hair_roughness` is a stub returning zeros in MaterialX 1.39. MaterialX clamps each
//!   to \[0.001, 1\].
//! - `absorption_coefficient` = σa per unit fiber radius: `T = exp(−σa·2cos γt/cos θt)`, the
//!   chord of `hair.cpp`.
//! - `cuticle_angle` = 0.5 − α/π (α in radians): the shader tilts by
//!   `alpha = cuticle_angle·π − π/2` on the light side, `m·alpha` with m = 2, −1, −4 for R, TT,
//!   TRT (`mx_hair_alpha_angles`, as Cycles' `hair_alpha_angles`), so its R lobe peaks at
//!   θi + θo = −2·alpha where Mitsuba's peaks at +2α: alpha = −α (Blender's Offset).
//! - `ior` = η; tints 1 (the fit's colour is all in σa); `curve_direction` left at `Tworld`,
//!   the curve's tangent, first control point to last: the table's +z.

use std::fmt::Write as _;

use super::fit::FiberFit;
use super::summary::{exact, exact_list, summary};
use crate::export::xml::{xml_comment, xml_escape};

/// MaterialX's (v, s) of R, TT and TRT for (β_m, β_n) ([module docs](self)).
pub(super) fn mtlx_roughness(beta_m: f64, beta_n: f64) -> [[f64; 2]; 3] {
    let v = (0.726 * beta_m + 0.812 * beta_m.powi(2) + 3.7 * beta_m.powi(20)).powi(2);
    let s = 0.265 * beta_n + 1.194 * beta_n.powi(2) + 5.372 * beta_n.powi(22);
    [[v, s], [0.25 * v, s], [4.0 * v, s]]
}

/// MaterialX's `cuticle_angle` for the fit's α (degrees) ([module docs](self)).
pub(super) fn mtlx_cuticle_angle(alpha_deg: f64) -> f64 {
    0.5 - alpha_deg.to_radians() / std::f64::consts::PI
}

/// An identifier (letters, digits, `_`; not starting with a digit) from `s`.
fn identifier(s: &str) -> String {
    let mut id: String = s
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
        id.insert(0, '_');
    }
    id
}

/// The `mtlx` target ([module docs](self)). The table must have R, G, B channels.
pub fn write_mtlx(fit: &FiberFit) -> String {
    let p = &fit.report.params;
    let id = identifier(&fit.variant);
    let rough = mtlx_roughness(p.beta_m, p.beta_n);
    let mut s = String::from("<?xml version=\"1.0\"?>\n<!--\n");
    s += "  MaterialX chiang_hair_bsdf written by baker export (target mtlx).\n";
    for line in summary(fit) {
        let _ = writeln!(s, "  {}", xml_comment(&line));
    }
    s += "  Conversions (MaterialX 1.39 libraries/pbrlib/genglsl/mx_chiang_hair_bsdf.glsl):\n  \
          roughness_R/TT/TRT = (v, s) of mx_chiang_hair_roughness(beta_m, beta_n, 0.5, 2.0):\n  \
          v = (0.726 b_m + 0.812 b_m^2 + 3.7 b_m^20)^2 times 1, 1/4, 4; s = 0.265 b_n + 1.194 b_n^2\n  \
          + 5.372 b_n^22 (the shader applies sqrt(pi/8)); absorption_coefficient = sigma_a per unit\n  \
          radius; cuticle_angle = 0.5 - alpha/pi (alpha in radians; the shader's tilt is\n  \
          cuticle_angle pi - pi/2 = -alpha); ior = eta. Fiber axis: curve_direction = Tworld.\n-->\n";
    s += "<materialx version=\"1.39\" colorspace=\"lin_rec709\">\n";
    let doc = format!(
        "fiber {} ({}): Chiang fit, relative L1 error {:.4}; beta_m {:.6}, beta_n {:.6}, \
         alpha {:.4} deg, sigma_a ({})",
        fit.variant,
        fit.table,
        fit.report.rel_l1,
        p.beta_m,
        p.beta_n,
        p.alpha_deg,
        exact_list(&p.sigma_a, ", ")
    );
    let _ = writeln!(
        s,
        "  <chiang_hair_bsdf name=\"BSDF_{id}\" type=\"BSDF\" doc=\"{}\">",
        xml_escape(&doc)
    );
    let input = |s: &mut String, name: &str, ty: &str, value: String| {
        let _ = writeln!(
            s,
            "    <input name=\"{name}\" type=\"{ty}\" value=\"{value}\" />"
        );
    };
    for lobe in ["R", "TT", "TRT"] {
        input(&mut s, &format!("tint_{lobe}"), "color3", "1, 1, 1".into());
    }
    input(&mut s, "ior", "float", exact(p.eta));
    for (lobe, vs) in ["R", "TT", "TRT"].iter().zip(rough) {
        input(
            &mut s,
            &format!("roughness_{lobe}"),
            "vector2",
            exact_list(&vs, ", "),
        );
    }
    input(
        &mut s,
        "cuticle_angle",
        "float",
        exact(mtlx_cuticle_angle(p.alpha_deg)),
    );
    input(
        &mut s,
        "absorption_coefficient",
        "vector3",
        exact_list(&p.sigma_a, ", "),
    );
    s += "  </chiang_hair_bsdf>\n";
    let _ = writeln!(
        s,
        "  <surface name=\"SR_{id}\" type=\"surfaceshader\">\n    \
         <input name=\"bsdf\" type=\"BSDF\" nodename=\"BSDF_{id}\" />\n  </surface>\n  \
         <surfacematerial name=\"M_{id}\" type=\"material\">\n    \
         <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR_{id}\" />\n  \
         </surfacematerial>"
    );
    s += "</materialx>\n";
    s
}
