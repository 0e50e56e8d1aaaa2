//! `defaults:` under every entry and sweep: a field given in the entry wins, field by field,
//! and the per-layer maps (`water_fraction: {hypodermis: 0.6}`) merge layer by layer.

use super::raw::{RawLayerValues, RawParams};
use crate::spec::yaml::Spanned;

/// `over` on top of `base`, field by field (per-layer maps merge per layer).
pub(super) fn merge(base: &RawParams, over: &RawParams) -> RawParams {
    macro_rules! pick {
        ($($f:ident),*) => {
            RawParams { $($f: over.$f.clone().or_else(|| base.$f.clone()),)* ..merge_layers(base, over) }
        };
    }
    pick!(
        name,
        age,
        gender,
        skin_type,
        melanosome_fraction,
        location,
        xi,
        model,
        skin_type_melanin,
        blood_fraction_pd,
        blood_fraction_rd,
        blood_fraction_hd,
        oxygen_saturation,
        hemoglobin_g_per_l,
        bilirubin_g_per_l,
        carotene_blood_g_per_l,
        carotene_epidermis_g_per_l,
        eumelanin_g_per_l,
        pheomelanin_g_per_l,
        pheomelanin_absorption,
        hypodermis_absorption,
        dej_amplitude_um,
        dej_period_um,
        dej_phase_rad,
        rz_um,
        sebum_mg,
        sebum_volume_factor,
        collagen_pd,
        collagen_rd,
        freeze
    )
}

fn merge_layers(base: &RawParams, over: &RawParams) -> RawParams {
    let m = |b: &Option<Spanned<RawLayerValues>>, o: &Option<Spanned<RawLayerValues>>| match (b, o)
    {
        (Some(b), Some(o)) => {
            let (bv, ov) = (&b.value, &o.value);
            let v = RawLayerValues {
                stratum_corneum: ov
                    .stratum_corneum
                    .clone()
                    .or_else(|| bv.stratum_corneum.clone()),
                living_epidermis: ov
                    .living_epidermis
                    .clone()
                    .or_else(|| bv.living_epidermis.clone()),
                papillary_dermis: ov
                    .papillary_dermis
                    .clone()
                    .or_else(|| bv.papillary_dermis.clone()),
                reticular_dermis: ov
                    .reticular_dermis
                    .clone()
                    .or_else(|| bv.reticular_dermis.clone()),
                hypodermis: ov.hypodermis.clone().or_else(|| bv.hypodermis.clone()),
            };
            Some(Spanned::new(v, o.referenced, o.defined))
        }
        (b, o) => o.clone().or_else(|| b.clone()),
    };
    RawParams {
        water_fraction: m(&base.water_fraction, &over.water_fraction),
        thickness_mm: m(&base.thickness_mm, &over.thickness_mm),
        atrophy_per_decade: m(&base.atrophy_per_decade, &over.atrophy_per_decade),
        ..RawParams::default()
    }
}
