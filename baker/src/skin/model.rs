//! Assembles the layer stack of one entry: thicknesses, indices and spectral coefficients.

use serde::Serialize;
use thiserror::Error;

use super::absorption::{self, Chromophores};
use super::collagen;
use super::layers::{self, Junction};
use super::params::{ModelKind, SkinLayer, SkinParams};
use super::scattering;
use super::surface::{self, Surface};
use crate::spectral::WavelengthGrid;

#[derive(Debug, Error, PartialEq)]
pub enum ModelError {
    #[error(
        "the dermo-epidermal junction (amplitude {amplitude_um:.1} µm) does not fit between its \
         neighbours: living epidermis {d_le_um:.1} µm, papillary dermis {d_pd_um:.1} µm thick; \
         lower dej_amplitude_um below both"
    )]
    JunctionTooDeep {
        amplitude_um: f64,
        d_le_um: f64,
        d_pd_um: f64,
    },
    #[error("layer {layer} has no thickness left at age {age_years} ({d_mm} mm): lower its atrophy_per_decade")]
    LayerVanished {
        layer: &'static str,
        age_years: f64,
        d_mm: f64,
    },
}

/// One layer of the stack handed to transport and to users of other Monte Carlo tools.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LayerOptics {
    pub name: &'static str,
    pub d_mm: f64,
    pub eta: f64,
    pub mua_per_mm: Vec<f64>,
    pub musp_per_mm: Vec<f64>,
}

/// The intermediate parameters of Table 4, at the entry's age.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Intermediate {
    /// Five-layer thicknesses (SC, LE, PD, RD, HD), mm.
    pub thickness_mm: [f64; 5],
    /// ϑm of the living epidermis (Eq. 3).
    pub melanosome_fraction: f64,
    /// ϑHb of the papillary and reticular dermis (Eq. 4) and of the hypodermis.
    pub blood_fraction_pd: f64,
    pub blood_fraction_rd: f64,
    pub blood_fraction_hd: f64,
    /// Effective Mie exponent of the dermal layers between 500 and 700 nm (Eq. 9 summarised).
    pub gamma_effective_pd: f64,
    pub gamma_effective_rd: f64,
}

/// Everything the model says about one entry.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkinOptics {
    pub model: ModelKind,
    pub lambda_nm: Vec<f64>,
    pub layers: Vec<LayerOptics>,
    pub junction: Junction,
    pub surface: Surface,
    pub intermediate: Intermediate,
}

/// Evaluates the model for `p` on `grid`.
pub fn evaluate(p: &SkinParams, grid: &WavelengthGrid) -> Result<SkinOptics, ModelError> {
    let d = layers::thickness_mm(p);
    for layer in SkinLayer::ALL {
        let d_mm = d[layer.index()];
        if d_mm <= 0.0 {
            return Err(ModelError::LayerVanished {
                layer: layer.display_name(),
                age_years: p.age_years,
                d_mm,
            });
        }
    }
    let vm = super::chromophores::melanosome_fraction(p);
    let (v_pd, v_rd) = super::chromophores::dermal_blood_fractions(p);
    let c = Chromophores {
        melanosome_fraction: vm,
        oxygen_saturation: p.oxygen_saturation,
        hemoglobin_g_per_l: p.hemoglobin_g_per_l,
        bilirubin_g_per_l: p.bilirubin_g_per_l,
        carotene_blood_g_per_l: p.carotene_blood_g_per_l,
        carotene_epidermis_g_per_l: p.carotene_epidermis_g_per_l,
        pheomelanin_g_per_l: p.pheomelanin_g_per_l,
        pheomelanin: p.pheomelanin_absorption,
    };
    let f = p.water_fraction;
    let collagen_age = if p.freeze.collagen || p.model == ModelKind::ThreeLayer {
        super::REFERENCE_AGE_YEARS // §3.6.1: constant collagen in the simplified model
    } else {
        p.age_years
    };
    let w_pd = collagen::gamma_weights(&collagen::distribution_at(&p.collagen_pd, collagen_age));
    let w_rd = collagen::gamma_weights(&collagen::distribution_at(&p.collagen_rd, collagen_age));
    let lam = grid.lambda_nm();
    let spectrum = |f: &dyn Fn(f64) -> f64| lam.iter().map(|&l| f(l)).collect::<Vec<f64>>();

    let sc_mua = spectrum(&|l| absorption::mua_stratum_corneum(l, f[0]));
    let le_mua = spectrum(&|l| absorption::mua_living_epidermis(l, &c, f[1]));
    let pd_mua = spectrum(&|l| absorption::mua_dermis(l, &c, v_pd, f[2]));
    let rd_mua = spectrum(&|l| absorption::mua_dermis(l, &c, v_rd, f[3]));
    let hd_mua = spectrum(&|l| {
        absorption::mua_hypodermis(l, &c, p.hypodermis_absorption, p.blood_fraction_hd, f[4])
    });
    let epi_musp = spectrum(&scattering::musp_epidermis);
    let pd_musp = spectrum(&|l| scattering::musp_dermis(l, &w_pd));
    let rd_musp = spectrum(&|l| scattering::musp_dermis(l, &w_rd));
    let hd_musp = spectrum(&scattering::musp_hypodermis);

    let layer = |l: SkinLayer, d_mm: f64, mua: Vec<f64>, musp: Vec<f64>| LayerOptics {
        name: l.display_name(),
        d_mm,
        eta: l.eta(),
        mua_per_mm: mua,
        musp_per_mm: musp,
    };
    let (layers, junction) = match p.model {
        ModelKind::FiveLayer => {
            let j = layers::junction(p, d[0], d[1]);
            let a = j.amplitude_mm;
            if a > 0.0 && (a >= d[1] || a >= d[2]) {
                return Err(ModelError::JunctionTooDeep {
                    amplitude_um: a * 1e3,
                    d_le_um: d[1] * 1e3,
                    d_pd_um: d[2] * 1e3,
                });
            }
            let stack = vec![
                layer(SkinLayer::StratumCorneum, d[0], sc_mua, epi_musp.clone()),
                layer(SkinLayer::LivingEpidermis, d[1], le_mua, epi_musp),
                layer(SkinLayer::PapillaryDermis, d[2], pd_mua, pd_musp),
                layer(SkinLayer::ReticularDermis, d[3], rd_mua, rd_musp),
                layer(SkinLayer::Hypodermis, d[4], hd_mua, hd_musp),
            ];
            (stack, j)
        }
        ModelKind::ThreeLayer => {
            // §3.6.1: epidermis = LE chromophores over SC + LE thickness; dermis = RD
            // properties over PD + RD thickness; a flat junction.
            let mut j = layers::junction(p, d[0], d[1]);
            j.amplitude_mm = 0.0;
            let stack = vec![
                LayerOptics {
                    name: "epidermis",
                    d_mm: d[0] + d[1],
                    eta: SkinLayer::LivingEpidermis.eta(),
                    mua_per_mm: le_mua,
                    musp_per_mm: epi_musp,
                },
                LayerOptics {
                    name: "dermis",
                    d_mm: d[2] + d[3],
                    eta: SkinLayer::ReticularDermis.eta(),
                    mua_per_mm: rd_mua,
                    musp_per_mm: rd_musp,
                },
                layer(SkinLayer::Hypodermis, d[4], hd_mua, hd_musp),
            ];
            (stack, j)
        }
    };
    // The outer surface is stratum corneum in both models (§3.4.2).
    let surface: Surface = surface::surface(p, SkinLayer::StratumCorneum.eta());
    let x = 700.0 / scattering::LAMBDA_REF_NM;
    Ok(SkinOptics {
        model: p.model,
        lambda_nm: lam.to_vec(),
        layers,
        junction,
        surface,
        intermediate: Intermediate {
            thickness_mm: d,
            melanosome_fraction: vm,
            blood_fraction_pd: v_pd,
            blood_fraction_rd: v_rd,
            blood_fraction_hd: p.blood_fraction_hd,
            gamma_effective_pd: collagen::effective_gamma(&w_pd, x),
            gamma_effective_rd: collagen::effective_gamma(&w_rd, x),
        },
    })
}
