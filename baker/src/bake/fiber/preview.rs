//! The preview of a fiber table, read back through the renderer's reader.

use std::path::{Path, PathBuf};

use crate::output::paths::Staged;
use crate::output::{exr, slice};
use crate::spectral::ColourMap;
use formats::bcsdf::{self, Bcsdf};

/// θi of the preview rows and φi (fiber rotations) of its columns, degrees.
const PREVIEW_THETA: [f64; 3] = [-0.001, -45.0, -80.0];
const PREVIEW_PHI: [f64; 4] = [0.0, 30.0, 60.0, 90.0];

/// Preview grid from a written table (read back through the renderer's reader): PNG of the
/// mean-channel f on a log scale, EXR of linear RGB f (variant 0).
pub fn write_previews(
    out: &Staged,
    entry: &str,
    table: &Path,
    lambda_nm: &[f64],
) -> anyhow::Result<Vec<PathBuf>> {
    let t = Bcsdf::open(table)?;
    let (nt, np) = (t.dir.n_theta, t.dir.n_phi);
    let res = t.dir.res_deg;
    let grid = formats::AngularGrid {
        res_deg: res,
        n_theta: nt,
        n_phi: np,
    };
    let spectral = t.dir.channels.len() != 3;
    let cmap = spectral.then(|| ColourMap::new(lambda_nm));
    let mut panels = Vec::new();
    let mut rgb_panels = Vec::new();
    for &th in &PREVIEW_THETA {
        for &ph in &PREVIEW_PHI {
            let wi = bcsdf::direction(th.to_radians(), ph.to_radians());
            let mut mono = vec![0.0; nt * np];
            let mut rgb = vec![[0f32; 3]; nt * np];
            for it in 0..nt {
                for j in 0..np {
                    let to = grid.theta_centre_deg(it).to_radians();
                    let dp = grid.phi_centre_deg(j).to_radians();
                    let wo = bcsdf::direction(to, ph.to_radians() + dp);
                    let f = t.eval(wi, wo, 0)?;
                    mono[it * np + j] = f.iter().map(|&x| x as f64).sum::<f64>() / f.len() as f64;
                    rgb[it * np + j] = match &cmap {
                        Some(cm) => {
                            let r = cm.rgb(&f.iter().map(|&x| x as f64).collect::<Vec<_>>());
                            [r[0] as f32, r[1] as f32, r[2] as f32]
                        }
                        None => [f[0], f[1], f[2]],
                    };
                }
            }
            panels.push(mono);
            rgb_panels.push(rgb);
        }
    }
    let png = out.path(&format!("preview/{entry}.png"))?;
    let px = (4.0 * 2.0 / res).round().max(1.0) as u32;
    slice::write_panels_png(&png, nt, np, &panels, PREVIEW_PHI.len(), px)?;
    // EXR: same grid, one pixel per bin, θo increasing downwards reversed like the PNG.
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
    let exr_path = out.path(&format!("preview/{entry}.exr"))?;
    exr::write_rgb(
        &exr_path,
        w,
        h,
        chans,
        "baker fiber BCSDF preview: rows theta_i = 0, -45, -80 deg; columns phi_i = 0, 30, 60, 90 deg; \
         in each panel theta_o increases upwards, dphi from -180 (left) to 180 deg; linear sRGB f in sr^-1",
    )?;
    Ok(vec![png, exr_path])
}
