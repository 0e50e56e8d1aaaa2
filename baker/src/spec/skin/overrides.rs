//! An entry's biophysical overrides of the model's defaults: concentrations and fractions
//! (ranges cite the table that motivates them), absorption variants, per-layer values, the
//! dermal–epidermal junction, the surface, collagen and what is frozen with age.

use super::cx::SkinCx;
use super::raw::{RawCollagen, RawLayerValues, RawParams, RawSkewNormal, Scalar};
use crate::skin::params::{CollagenAging, SkewNormal};
use crate::skin::{
    Freeze, HypodermisAbsorption, PheomelaninAbsorption, SkinLayer, SkinParams, SkinTypeMelanin,
};
use crate::spec::check::{loc, Bounds};
use crate::spec::yaml::Spanned;

/// A number an entry may override: its field, where the spec gives it, the range it must be
/// in (`open_lo`: the lower bound excluded) and the model input it sets.
pub(in crate::spec) struct Range {
    pub(in crate::spec) field: &'static str,
    given: fn(&RawParams) -> &Scalar<f64>,
    pub(in crate::spec) lo: f64,
    pub(in crate::spec) hi: f64,
    pub(in crate::spec) open_lo: bool,
    value: fn(&mut SkinParams) -> &mut f64,
}

impl Range {
    pub(in crate::spec) const fn bounds(&self) -> Bounds {
        Bounds {
            lo: self.lo,
            hi: self.hi,
            open_lo: self.open_lo,
            whole: false,
        }
    }
}

/// `field => model input, lo, hi, open_lo`.
macro_rules! range {
    ($field:ident => $value:ident, $lo:expr, $hi:expr, $open_lo:expr) => {
        Range {
            field: stringify!($field),
            given: |p| &p.$field,
            lo: $lo,
            hi: $hi,
            open_lo: $open_lo,
            value: |s| &mut s.$value,
        }
    };
}

/// Blood, bilirubin, carotene and melanin.
pub(in crate::spec) const BLOOD_AND_PIGMENTS: [Range; 10] = [
    // Table 2: ϑHb in [0.1, 20] % in the dermis.
    range!(blood_fraction_pd => blood_fraction_pd, 0.001, 0.2, false),
    range!(blood_fraction_rd => blood_fraction_rd, 0.001, 0.2, false),
    range!(blood_fraction_hd => blood_fraction_hd, 0.0, 0.2, false),
    range!(oxygen_saturation => oxygen_saturation, 0.0, 1.0, false),
    range!(hemoglobin_g_per_l => hemoglobin_g_per_l, 0.0, 300.0, true),
    // Table 2: bilirubin [0.05, 3] g/L; 0 allowed to switch it off.
    range!(bilirubin_g_per_l => bilirubin_g_per_l, 0.0, 3.0, false),
    range!(carotene_blood_g_per_l => carotene_blood_g_per_l, 0.0, 0.01, false),
    range!(carotene_epidermis_g_per_l => carotene_epidermis_g_per_l, 0.0, 0.01, false),
    range!(eumelanin_g_per_l => eumelanin_g_per_l, 0.0, 200.0, false),
    range!(pheomelanin_g_per_l => pheomelanin_g_per_l, 0.0, 200.0, false),
];

/// The dermal–epidermal junction's amplitude (at 30 years) and period.
pub(in crate::spec) const JUNCTION: [Range; 2] = [
    range!(dej_amplitude_um => dej_amplitude_at_30_um, 0.0, 200.0, false),
    range!(dej_period_um => dej_period_um, 10.0, 2000.0, false),
];

/// `skin_type_melanin`: how a skin type becomes melanin (the caption's or Fig. 40's values).
pub(in crate::spec) const SKIN_TYPE_MELANIN: [(&str, SkinTypeMelanin); 2] = [
    ("caption", SkinTypeMelanin::Caption),
    ("figure40", SkinTypeMelanin::Figure40),
];
/// `pheomelanin_absorption`: the thesis's fit or the measured spectrum.
pub(in crate::spec) const PHEOMELANIN_ABSORPTION: [(&str, PheomelaninAbsorption); 2] = [
    ("thesis_fit", PheomelaninAbsorption::ThesisFit),
    ("measured", PheomelaninAbsorption::Measured),
];
/// `hypodermis_absorption`: blood and water, or water only.
pub(in crate::spec) const HYPODERMIS_ABSORPTION: [(&str, HypodermisAbsorption); 2] = [
    ("blood", HypodermisAbsorption::Blood),
    ("water_only", HypodermisAbsorption::WaterOnly),
];
/// Sets one flag of a [`Freeze`].
type FreezeFlag = fn(&mut Freeze);

/// `freeze:`, the aging processes that can be held at their age-30 values.
pub(in crate::spec) const FREEZABLE: [(&str, FreezeFlag); 6] = [
    ("thickness", |f| f.thickness = true),
    ("melanin", |f| f.melanin = true),
    ("hemoglobin", |f| f.hemoglobin = true),
    ("surface", |f| f.surface = true),
    ("collagen", |f| f.collagen = true),
    ("junction", |f| f.junction = true),
];

/// Per-layer water volume fraction (Table 2).
pub(in crate::spec) const WATER_FRACTION: Bounds = Bounds::closed(0.0, 0.95);
/// Per-layer thickness at 30 years, mm.
pub(in crate::spec) const THICKNESS_MM: Bounds = Bounds::above(0.0, 100.0);
/// Per-layer relative thinning per decade past 30.
pub(in crate::spec) const ATROPHY_PER_DECADE: Bounds = Bounds::closed(0.0, 0.5);
/// Surface roughness Rz, µm.
pub(in crate::spec) const RZ_UM: Bounds = Bounds::above(0.0, 1000.0);
/// Sebum on the surface, mg.
pub(in crate::spec) const SEBUM_MG: Bounds = Bounds::closed(0.0, 10.0);
/// Volume of the sebum film per mg.
pub(in crate::spec) const SEBUM_VOLUME_FACTOR: Bounds = Bounds::above(0.0, 10.0);
/// Collagen fibre diameter distribution (Eqs. 8–9): location and scale, µm; shape.
pub(in crate::spec) const COLLAGEN_LOCATION_UM: Bounds = Bounds::closed(0.5, 40.0);
pub(in crate::spec) const COLLAGEN_SCALE_UM: Bounds = Bounds::closed(0.05, 40.0);
pub(in crate::spec) const COLLAGEN_SHAPE: Bounds = Bounds::closed(-20.0, 20.0);

impl SkinCx {
    /// Biophysical overrides; ranges cite the table that motivates them.
    pub(super) fn overrides(&mut self, p: &RawParams, s: &mut SkinParams) {
        self.choose(
            "skin_type_melanin",
            &p.skin_type_melanin,
            &SKIN_TYPE_MELANIN,
            &mut s.skin_type_melanin,
        );
        self.ranges(p, s, &BLOOD_AND_PIGMENTS);
        self.choose(
            "pheomelanin_absorption",
            &p.pheomelanin_absorption,
            &PHEOMELANIN_ABSORPTION,
            &mut s.pheomelanin_absorption,
        );
        self.choose(
            "hypodermis_absorption",
            &p.hypodermis_absorption,
            &HYPODERMIS_ABSORPTION,
            &mut s.hypodermis_absorption,
        );
        self.layer_values(
            "water_fraction",
            &p.water_fraction,
            &mut s.water_fraction,
            WATER_FRACTION,
        );
        self.layer_values(
            "thickness_mm",
            &p.thickness_mm,
            &mut s.thickness_at_30_mm,
            THICKNESS_MM,
        );
        self.layer_values(
            "atrophy_per_decade",
            &p.atrophy_per_decade,
            &mut s.atrophy_per_decade,
            ATROPHY_PER_DECADE,
        );
        self.ranges(p, s, &JUNCTION);
        self.surface(p, s);
        if let Some(c) = &p.collagen_pd {
            s.collagen_pd = self.collagen("collagen_pd", &c.value);
        }
        if let Some(c) = &p.collagen_rd {
            s.collagen_rd = self.collagen("collagen_rd", &c.value);
        }
        if let Some(list) = &p.freeze {
            s.freeze = self.freeze(list);
        }
    }

    /// Each number of `table` the entry gives, range-checked into its model input.
    fn ranges(&mut self, p: &RawParams, s: &mut SkinParams, table: &[Range]) {
        for r in table {
            let current = *(r.value)(s);
            *(r.value)(s) = self.opt_range(r.field, (r.given)(p), r.lo, r.hi, r.open_lo, current);
        }
    }

    /// The option `v` names, if given and one of `options`, into `out`.
    fn choose<T: Copy>(
        &mut self,
        field: &str,
        v: &Scalar<String>,
        options: &[(&str, T)],
        out: &mut T,
    ) {
        if let Some(v) = v {
            if let Some(m) = self.choice(field, v, options) {
                *out = m;
            }
        }
    }

    /// The junction's phase and the surface: roughness and sebum.
    fn surface(&mut self, p: &RawParams, s: &mut SkinParams) {
        if let Some(ph) = &p.dej_phase_rad {
            if ph.value.iter().all(|x| x.is_finite()) {
                s.dej_phase_rad = ph.value;
            } else {
                self.out_of_range(
                    loc(ph),
                    "dej_phase_rad",
                    format!("{:?}", ph.value),
                    "two finite numbers".into(),
                );
            }
        }
        if let Some(v) = &p.rz_um {
            s.rz_um = self.in_bounds("rz_um", v, RZ_UM);
        }
        if let Some(v) = &p.sebum_mg {
            s.sebum_mg = self.in_bounds("sebum_mg", v, SEBUM_MG);
        }
        s.sebum_volume_factor = self.opt_bounds(
            "sebum_volume_factor",
            &p.sebum_volume_factor,
            SEBUM_VOLUME_FACTOR,
            s.sebum_volume_factor,
        );
    }

    fn layer_values(
        &mut self,
        field: &str,
        raw: &Option<Spanned<RawLayerValues>>,
        out: &mut [f64; 5],
        range: Bounds,
    ) {
        let Some(raw) = raw else { return };
        for (layer, v) in SkinLayer::ALL.iter().zip(raw.value.as_array()) {
            if let Some(v) = v {
                let name = format!("{field}.{}", layer.key());
                if let Some(x) = self.in_bounds(&name, v, range) {
                    out[layer.index()] = x;
                }
            }
        }
    }

    fn collagen(&mut self, field: &str, c: &RawCollagen) -> CollagenAging {
        let mut one = |age: &str, s: &Spanned<RawSkewNormal>| SkewNormal {
            location_um: self
                .in_bounds(
                    &format!("{field}.{age}.location_um"),
                    &s.value.location_um,
                    COLLAGEN_LOCATION_UM,
                )
                .unwrap_or(1.0),
            scale_um: self
                .in_bounds(
                    &format!("{field}.{age}.scale_um"),
                    &s.value.scale_um,
                    COLLAGEN_SCALE_UM,
                )
                .unwrap_or(1.0),
            shape: self
                .in_bounds(
                    &format!("{field}.{age}.shape"),
                    &s.value.shape,
                    COLLAGEN_SHAPE,
                )
                .unwrap_or(0.0),
        };
        CollagenAging {
            at_30: one("at_30", &c.at_30),
            at_80: one("at_80", &c.at_80),
        }
    }

    fn freeze(&mut self, list: &Spanned<Vec<Spanned<String>>>) -> Freeze {
        let mut f = Freeze::default();
        for item in &list.value {
            match FREEZABLE.iter().find(|(k, _)| *k == item.value) {
                Some((_, set)) => set(&mut f),
                None => self.out_of_range(
                    loc(item),
                    "freeze",
                    format!("{:?}", item.value),
                    format!(
                        "{}{}",
                        FREEZABLE.map(|(k, _)| k).join(", "),
                        crate::suggest::suffix(&item.value, &FREEZABLE.map(|(k, _)| k))
                    ),
                ),
            }
        }
        f
    }
}
