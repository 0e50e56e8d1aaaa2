//! Spectral profile → linear sRGB profile, 99 % radii and the sum-of-Gaussians fit.

use super::simulate::SpectralProfile;
use crate::cancel::{Cancel, Cancelled};
use crate::fit::{fit_sum_of_gaussians, GaussianFit, GaussianFitOptions};
use crate::spectral::ColourMap;
use crate::transport::radial::radius_of_energy;

/// What a renderer loads for one entry.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RgbProfile {
    /// CIE XYZ of the total diffuse reflectance (Y = 1 for a white diffuser).
    pub xyz: [f64; 3],
    /// Linear sRGB total diffuse reflectance (white diffuser = 1).
    pub albedo_rgb: [f64; 3],
    pub albedo_rgb_se: [f64; 3],
    /// `[nr]` linear sRGB Rd(r), mm⁻², bin averages.
    pub rd_rgb_per_mm2: Vec<[f64; 3]>,
    pub rd_rgb_per_mm2_se: Vec<[f64; 3]>,
    /// Radius holding 99 % of each channel's diffuse energy, mm; NaN when the grid ends first.
    pub r99_mm: [f64; 3],
    pub fit: GaussianFit,
}

/// The RGB profile of `p` and its sum-of-`gaussians` fit; `Err` once `cancel` is set.
pub fn rgb_profile(
    p: &SpectralProfile,
    colour: &ColourMap,
    gaussians: usize,
    cancel: Cancel,
) -> Result<RgbProfile, Cancelled> {
    rgb_profile_with(
        p,
        colour,
        &GaussianFitOptions {
            count: gaussians,
            cancel,
            ..GaussianFitOptions::default()
        },
    )
}

/// [`rgb_profile`] with the fit's options (`baker plan` times a shortened fit).
pub fn rgb_profile_with(
    p: &SpectralProfile,
    colour: &ColourMap,
    o: &GaussianFitOptions,
) -> Result<RgbProfile, Cancelled> {
    let nr = p.r_edges_mm.len() - 1;
    let w = &colour.rgb_weights;
    let rd_rgb: Vec<[f64; 3]> = (0..nr)
        .map(|k| std::array::from_fn(|c| (0..w.len()).map(|i| w[i][c] * p.rd_per_mm2[i][k]).sum()))
        .collect();
    let rd_rgb_se: Vec<[f64; 3]> = (0..nr)
        .map(|k| {
            let se: Vec<f64> = (0..w.len()).map(|i| p.rd_per_mm2_se[i][k]).collect();
            colour.rgb_se(&se)
        })
        .collect();
    let albedo_rgb = colour.rgb(&p.rd_total);
    let r99_mm: [f64; 3] = std::array::from_fn(|c| {
        radius_of_energy(
            &p.r_edges_mm,
            rd_rgb.iter().map(|v| v[c]),
            0.99 * albedo_rgb[c],
        )
    });
    // Where the grid ends before 99 %, fit what there is (the bake warns).
    let r_fit = r99_mm.map(|r| if r.is_nan() { f64::INFINITY } else { r });
    let fit = fit_sum_of_gaussians(&p.r_edges_mm, &rd_rgb, r_fit, o)?;
    Ok(RgbProfile {
        xyz: colour.xyz(&p.rd_total),
        albedo_rgb,
        albedo_rgb_se: colour.rgb_se(&p.rd_total_se),
        rd_rgb_per_mm2: rd_rgb,
        rd_rgb_per_mm2_se: rd_rgb_se,
        r99_mm,
        fit,
    })
}
