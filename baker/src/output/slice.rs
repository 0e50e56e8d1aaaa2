//! False-colour PNGs of a fiber's outgoing scattering over θo × Δφ (the layout of the
//! thesis's Table 8): Δφ = φo − φi across from −180° to 180°, θo up from −90° to 90°, log10
//! colour over [`DECADES`] below the largest value shown, black where nothing scattered;
//! drawn by [`crate::output::plot::angular_figure`] with axes, degree ticks, captions and a
//! colour bar.

use std::path::Path;

use super::plot::{angular_figure, AngularFigure, Drawn, Panel};

/// Decades of dynamic range shown.
pub const DECADES: f64 = 5.0;

/// Axis titles of every θo × Δφ map.
pub const X_DESC: &str = "Δφ = φo − φi";
pub const Y_DESC: &str = "θo";

/// Writes one slice (`value`: one number per bin, θ row-major, `nt × np`, row 0 at
/// θo = −90°) to `path` as a 964 × 518 image (a 720 × 360 map), titled `title`, with the
/// colour bar titled `bar_desc`.
pub fn write_slice_png(
    path: &Path,
    (nt, np): (usize, usize),
    value: &[f64],
    title: &str,
    bar_desc: &str,
) -> anyhow::Result<Drawn> {
    angular_figure(
        path,
        &AngularFigure {
            title: title.to_string(),
            subtitle: format!(
                "log scale, {DECADES} decades below the maximum; {}° bins; black: nothing scattered",
                180.0 / nt as f64
            ),
            x_desc: X_DESC.into(),
            y_desc: Y_DESC.into(),
            bar_desc: bar_desc.to_string(),
            n_theta: nt,
            n_phi: np,
            panels: vec![Panel {
                caption: String::new(),
                values: value.to_vec(),
            }],
            cols: 1,
            map_px: (720, 360),
            decades: DECADES,
        },
    )
}
