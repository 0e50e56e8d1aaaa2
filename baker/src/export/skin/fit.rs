//! One entry of a skin table with its per-channel Christensen–Burley fit, and the quantities
//! the engines derive from it.

use anyhow::Context as _;
use formats::{ProfileTable, TableIndex};

use super::DEFAULT_ETA;
use crate::export::burley::{self, BurleyFit};

/// One table entry with its Burley fit.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinFit {
    pub name: String,
    /// The table's total diffuse reflectance per channel (linear sRGB).
    pub albedo_rgb: [f64; 3],
    /// 99 % radius per channel, mm (NaN: the grid ends first; then every bin is fitted).
    pub r99_mm: [f64; 3],
    pub burley: [BurleyFit; 3],
    /// The six-Gaussian fit error stored in the table (NaN if it holds none).
    pub gaussian_error_rgb: [f64; 3],
    /// Refractive index of the skin surface (`surface/eta`).
    pub eta: f64,
    /// Normal-incidence Fresnel reflectance of the surface (`surface/f0`, else from `eta`).
    pub f0: f64,
}

impl SkinFit {
    /// Fitted surface albedo A per channel.
    pub fn a_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| f.a)
    }

    /// Fitted shape d per channel, mm.
    pub fn d_mm_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| f.d_mm)
    }

    pub fn burley_error_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| f.error)
    }

    /// C = A/(1 − F0), clamped to \[0, 1\]: the albedo of the light that crossed the surface,
    /// what layered models call their subsurface colour (OpenPBR, "Subsurface").
    pub fn albedo_below_interface_rgb(&self) -> [f64; 3] {
        self.a_rgb().map(|a| (a / (1.0 - self.f0)).clamp(0.0, 1.0))
    }

    /// Volume mean free path ℓ = d·s_perpendicular(A) per channel, mm ([`burley::volume_mfp_mm`]).
    pub fn volume_mfp_mm_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| burley::volume_mfp_mm(f.a, f.d_mm))
    }
}

/// Fits entry `name` of a table (`index` is the same file, for the arrays `ProfileTable` does
/// not decode: `r99_mm`, `surface/eta`, `surface/f0`).
pub fn fit_entry(table: &ProfileTable, index: &TableIndex, name: &str) -> anyhow::Result<SkinFit> {
    let data = table
        .data(name)
        .with_context(|| format!("entry {name:?}"))?;
    let f64s = |q: &str| -> anyhow::Result<Option<Vec<f64>>> {
        let full = format!("{name}/{q}");
        Ok(index
            .array(&full)
            .with_context(|| full.clone())?
            .and_then(|a| a.as_f64().map(<[f64]>::to_vec)))
    };
    // The table's own r99 (FORMAT.md); recomputed the same way if an older table lacks it.
    let r99_mm: [f64; 3] = match f64s("r99_mm")? {
        Some(v) if v.len() == 3 => [v[0], v[1], v[2]],
        _ => std::array::from_fn(|c| {
            crate::transport::radial::radius_of_energy(
                &data.r_edges_mm,
                data.rd_rgb_per_mm2.iter().map(|v| v[c]),
                0.99 * data.albedo_rgb[c],
            )
        }),
    };
    let scalar =
        |q: &str| -> anyhow::Result<Option<f64>> { Ok(f64s(q)?.and_then(|v| v.first().copied())) };
    let eta = scalar("surface/eta")?
        .filter(|e| e.is_finite() && *e >= 1.0)
        .unwrap_or(DEFAULT_ETA);
    // Fresnel at normal incidence, ((η − 1)/(η + 1))², when the table does not store it.
    let f0 = scalar("surface/f0")?
        .filter(|f| (0.0..1.0).contains(f))
        .unwrap_or(((eta - 1.0) / (eta + 1.0)).powi(2));
    let fit = burley::fit_rgb(&data.r_edges_mm, &data.rd_rgb_per_mm2, r99_mm)
        .with_context(|| format!("Burley fit of entry {name:?}"))?;
    Ok(SkinFit {
        name: name.to_string(),
        albedo_rgb: data.albedo_rgb,
        r99_mm,
        burley: fit,
        gaussian_error_rgb: data.gaussians.error_rgb,
        eta,
        f0,
    })
}
