//! The preview of a fiber table, read back through the renderer's reader: the layout of the
//! thesis's Table 8 (ch. 5 §5.3): rows θi = 0°, −45°, −80° (normal to near-grazing
//! incidence), columns the fiber turned by 0° and 90° about its axis (here the incoming
//! azimuth φi = 0°, 90° in the table's frame, which turns with the fiber), each panel the
//! outgoing field over θo × Δφ.

use std::path::{Path, PathBuf};

use crate::output::paths::Staged;
use crate::output::plot::{Drawn, Panel};
use crate::output::{exr, plot, slice};
use crate::spectral::ColourMap;
use formats::bcsdf::{self, Bcsdf};

/// θi of the preview rows and φi of its columns, degrees (Table 8); each is drawn at the
/// centre of the table bin it falls in, a tie on a bin edge going to the lower bin in θ and
/// the upper bin in φ.
const PREVIEW_THETA: [f64; 3] = [0.0, -45.0, -80.0];
const PREVIEW_PHI: [f64; 2] = [0.0, 90.0];

/// Pixels of each panel's map in the PNG (2° bins: 2.3 px per bin; 6°: 7 px).
const MAP_PX: (u32, u32) = (420, 210);

/// Preview grid from a written table (read back through the renderer's reader): PNG of the
/// mean-channel f on a log scale with axes and a colour bar, EXR of linear RGB f (variant 0).
pub fn write_previews(
    out: &Staged,
    entry: &str,
    table: &Path,
    lambda_nm: &[f64],
) -> anyhow::Result<Vec<PathBuf>> {
    let t = Bcsdf::open(table)?;
    let png = out.path(&format!("preview/{entry}.png"))?;
    let exr_path = out.path(&format!("preview/{entry}.exr"))?;
    render(&t, entry, lambda_nm, &png, &exr_path)?;
    Ok(vec![png, exr_path])
}

/// The incoming directions of the panels (row-major: θi rows × φi columns) as the bin
/// centres they fall in, degrees.
fn panel_directions(grid: &formats::AngularGrid) -> Vec<(f64, f64)> {
    let nudge = 1e-7;
    let mut dirs = Vec::new();
    for &th in &PREVIEW_THETA {
        for &ph in &PREVIEW_PHI {
            let (it, jp) = grid.cell((th - nudge).to_radians(), (ph + nudge).to_radians());
            dirs.push((grid.theta_centre_deg(it), grid.phi_centre_deg(jp)));
        }
    }
    dirs
}

/// Draws the preview of variant 0 of `t` into `png` and `exr_path`; returns the PNG's layout.
fn render(
    t: &Bcsdf,
    entry: &str,
    lambda_nm: &[f64],
    png: &Path,
    exr_path: &Path,
) -> anyhow::Result<Drawn> {
    let grid = t.dir.grid();
    let (nt, np) = (grid.n_theta, grid.n_phi);
    let nc = t.dir.channels.len();
    let spectral = nc != 3;
    let cmap = spectral.then(|| ColourMap::new(lambda_nm));
    let dirs = panel_directions(&grid);
    let mut panels = Vec::new();
    let mut rgb_panels = Vec::new();
    for &(th, ph) in &dirs {
        let wi = bcsdf::direction(th.to_radians(), ph.to_radians());
        let mut mono = vec![0.0; nt * np];
        let mut rgb = vec![[0f32; 3]; nt * np];
        for it in 0..nt {
            let to = grid.theta_centre_deg(it).to_radians();
            for j in 0..np {
                let dp = grid.phi_centre_deg(j).to_radians();
                let wo = bcsdf::direction(to, ph.to_radians() + dp);
                let f = t.eval(wi, wo, 0)?;
                mono[it * np + j] = f.iter().map(|&x| x as f64).sum::<f64>() / nc as f64;
                rgb[it * np + j] = match &cmap {
                    Some(cm) => {
                        let r = cm.rgb(&f.iter().map(|&x| x as f64).collect::<Vec<_>>());
                        [r[0] as f32, r[1] as f32, r[2] as f32]
                    }
                    None => [f[0], f[1], f[2]],
                };
            }
        }
        panels.push(Panel {
            caption: format!("θi = {}°,  φi = {}°", signed(th), signed(ph)),
            values: mono,
        });
        rgb_panels.push(rgb);
    }
    let meta = &t.dir.metadata;
    let field = |k: &str| meta.get(k).and_then(|v| v.as_str());
    let fiber = match field("fiber_type") {
        Some(ty) if ty != entry => format!("{entry} ({ty})"),
        _ => entry.to_string(),
    };
    let table = field("table").unwrap_or("table");
    let variant = &t.dir.variants[0];
    let more = match t.dir.variants.len() {
        1 => String::new(),
        n => format!(" (1 of {n})"),
    };
    let channels = if spectral {
        format!("mean of {nc} wavelengths")
    } else {
        "mean of R, G, B".to_string()
    };
    let figure = plot::AngularFigure {
        title: format!("{fiber}: {table}, variant {variant}{more}"),
        subtitle: format!(
            "BCSDF f ({channels}) on one log scale, {} decades (black: below it or nothing \
             scattered); {}° bins; θi, φi: the bin centres nearest Table 8's 0°, −45°, −80° and \
             0°, 90°",
            slice::DECADES,
            t.dir.res_deg
        ),
        x_desc: slice::X_DESC.into(),
        y_desc: slice::Y_DESC.into(),
        bar_desc: "f (sr⁻¹)".into(),
        n_theta: nt,
        n_phi: np,
        panels,
        cols: PREVIEW_PHI.len(),
        map_px: MAP_PX,
        decades: slice::DECADES,
    };
    let drawn = plot::angular_figure(png, &figure)?;
    // EXR: same grid, one pixel per bin, θo increasing upwards like the PNG.
    let cols = PREVIEW_PHI.len();
    let (w, h) = (cols * np, PREVIEW_THETA.len() * nt);
    let mut chans = [vec![0f32; w * h], vec![0f32; w * h], vec![0f32; w * h]];
    for (k, p) in rgb_panels.iter().enumerate() {
        let (r, c) = (k / cols, k % cols);
        for it in 0..nt {
            for j in 0..np {
                let (x, y) = (c * np + j, r * nt + (nt - 1 - it));
                for ch in 0..3 {
                    chans[ch][y * w + x] = p[it * np + j][ch];
                }
            }
        }
    }
    let where_ = dirs
        .iter()
        .map(|(th, ph)| format!("({th}, {ph})"))
        .collect::<Vec<_>>()
        .join(", ");
    exr::write_rgb(
        exr_path,
        w,
        h,
        chans,
        &format!(
            "baker fiber BCSDF preview of variant {}: {} rows x {cols} columns of panels, \
             (theta_i, phi_i) deg row-major = {where_}; in each panel theta_o increases upwards, \
             dphi from -180 (left) to 180 deg; linear sRGB f in sr^-1",
            variant.replace(|c: char| !c.is_ascii() || c.is_ascii_control(), "?"),
            PREVIEW_THETA.len()
        ),
    )?;
    Ok(drawn)
}

/// An angle in degrees with a true minus sign and no needless decimals.
fn signed(v: f64) -> String {
    let s = format!("{}", (v * 1000.0).round() / 1000.0);
    match s.strip_prefix('-') {
        Some(rest) => format!("−{rest}"),
        None => s,
    }
}
