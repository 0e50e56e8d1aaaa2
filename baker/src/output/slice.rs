//! False-colour PNG of one outgoing slice of a fiber's scattering (like Table 8's plots): Δφ
//! from −180° (left) to 180° (right), θo from +90° (top) to −90° (bottom), colour = log10 of
//! the scattered intensity per solid angle divided by cos θo (a BCSDF value up to the
//! incident normalisation), over five decades below the maximum; black where nothing landed.

use std::path::Path;

/// Matplotlib's "inferno" colour map, sampled at nine stops (van der Walt & Smith, 2015).
const INFERNO: [[f64; 3]; 9] = [
    [0.0, 0.0, 4.0],
    [31.0, 12.0, 72.0],
    [85.0, 15.0, 109.0],
    [136.0, 34.0, 106.0],
    [186.0, 54.0, 85.0],
    [227.0, 89.0, 51.0],
    [249.0, 140.0, 10.0],
    [249.0, 201.0, 50.0],
    [252.0, 255.0, 164.0],
];

fn colour(t: f64) -> [u8; 3] {
    let x = t.clamp(0.0, 1.0) * 8.0;
    let i = (x as usize).min(7);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (INFERNO[i][k] + f * (INFERNO[i + 1][k] - INFERNO[i][k])).round() as u8;
    }
    c
}

/// Decades of dynamic range shown.
pub const DECADES: f64 = 5.0;

/// The false colour of `v` on a log scale [`DECADES`] deep below `vmax`; black for 0.
fn log_colour(v: f64, vmax: f64) -> [u8; 3] {
    if v > 0.0 && vmax > 0.0 {
        colour(1.0 + (v / vmax).log10() / DECADES)
    } else {
        [0, 0, 0]
    }
}

/// Writes `value` (a density per bin, θ row-major, `nt × np`, θ increasing upwards) to
/// `path`, `px` pixels per bin, with a colour bar along the bottom.
pub fn write_slice_png(
    path: &Path,
    (nt, np): (usize, usize),
    value: &[f64],
    px: u32,
) -> anyhow::Result<()> {
    let vmax = value.iter().copied().fold(0.0, f64::max);
    let (w, h_map) = (np as u32 * px, nt as u32 * px);
    let bar = 16u32;
    let h = h_map + bar;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    for y in 0..h_map {
        let it = nt - 1 - (y / px) as usize;
        for x in 0..w {
            let c = log_colour(value[it * np + (x / px) as usize], vmax);
            let o = ((y * w + x) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&c);
        }
    }
    for y in h_map..h {
        for x in 0..w {
            let c = colour(x as f64 / (w - 1) as f64);
            let o = ((y * w + x) * 3) as usize;
            buf[o..o + 3].copy_from_slice(&c);
        }
    }
    super::plot::write_png(path, w, h, buf)
}

/// Writes a grid of slices (Table 8's layout): `panels[r * cols + c]` holds densities per
/// bin (θ row-major, `n_theta × n_phi`), each shown on its own log scale ([`DECADES`] below
/// its maximum), `px` pixels per bin, panels separated by 2 black pixels.
pub fn write_panels_png(
    path: &Path,
    n_theta: usize,
    n_phi: usize,
    panels: &[Vec<f64>],
    cols: usize,
    px: u32,
) -> anyhow::Result<()> {
    anyhow::ensure!(!panels.is_empty() && cols > 0, "no panels");
    let rows = panels.len().div_ceil(cols);
    let gap = 2u32;
    let (pw, ph) = (n_phi as u32 * px, n_theta as u32 * px);
    let w = cols as u32 * (pw + gap) - gap;
    let h = rows as u32 * (ph + gap) - gap;
    let mut buf = vec![0u8; (w * h * 3) as usize];
    for (k, p) in panels.iter().enumerate() {
        let (r, c) = ((k / cols) as u32, (k % cols) as u32);
        let vmax = p.iter().copied().fold(0.0, f64::max);
        for y in 0..ph {
            let it = n_theta - 1 - (y / px) as usize;
            for x in 0..pw {
                let col = log_colour(p[it * n_phi + (x / px) as usize], vmax);
                let (gx, gy) = (c * (pw + gap) + x, r * (ph + gap) + y);
                let o = ((gy * w + gx) * 3) as usize;
                buf[o..o + 3].copy_from_slice(&col);
            }
        }
    }
    super::plot::write_png(path, w, h, buf)
}
