//! Validated inputs of the skin model: high-level descriptors plus every biophysical parameter,
//! each defaulted from the thesis and overridable from a spec.

use serde::Serialize;

/// The five layers of the full model (§3.4.1), top to bottom.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SkinLayer {
    StratumCorneum,
    LivingEpidermis,
    PapillaryDermis,
    ReticularDermis,
    Hypodermis,
}

impl SkinLayer {
    pub const ALL: [SkinLayer; 5] = [
        SkinLayer::StratumCorneum,
        SkinLayer::LivingEpidermis,
        SkinLayer::PapillaryDermis,
        SkinLayer::ReticularDermis,
        SkinLayer::Hypodermis,
    ];

    /// Name used in every output (`--json`, CSV, `.mci` comments).
    pub fn display_name(self) -> &'static str {
        match self {
            SkinLayer::StratumCorneum => "stratum corneum",
            SkinLayer::LivingEpidermis => "living epidermis",
            SkinLayer::PapillaryDermis => "papillary dermis",
            SkinLayer::ReticularDermis => "reticular dermis",
            SkinLayer::Hypodermis => "hypodermis",
        }
    }

    /// Key used in specs (`thickness_mm: {living_epidermis: 0.08}`).
    pub fn key(self) -> &'static str {
        match self {
            SkinLayer::StratumCorneum => "stratum_corneum",
            SkinLayer::LivingEpidermis => "living_epidermis",
            SkinLayer::PapillaryDermis => "papillary_dermis",
            SkinLayer::ReticularDermis => "reticular_dermis",
            SkinLayer::Hypodermis => "hypodermis",
        }
    }

    pub fn index(self) -> usize {
        self as usize
    }

    /// Refractive index η, Table 1.
    pub fn eta(self) -> f64 {
        match self {
            SkinLayer::StratumCorneum => 1.53,
            SkinLayer::LivingEpidermis => 1.34,
            SkinLayer::PapillaryDermis => 1.395,
            SkinLayer::ReticularDermis => 1.39,
            SkinLayer::Hypodermis => 1.44,
        }
    }

    /// Water volume fraction f_H2O, Table 2 (and Table 4's caption).
    pub fn default_water_fraction(self) -> f64 {
        match self {
            SkinLayer::StratumCorneum => 0.05,
            SkinLayer::LivingEpidermis => 0.2,
            SkinLayer::PapillaryDermis => 0.5,
            SkinLayer::ReticularDermis => 0.7,
            SkinLayer::Hypodermis => 0.7,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Gender {
    Female,
    Male,
}

/// Body locations with their own layer thicknesses (Table 1; Table 4 rows 42).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BodyLocation {
    Face,
    Forearm,
    BackOfHand,
    Palm,
}

impl BodyLocation {
    /// SkinLayer thicknesses at the reference age of 30, mm, in [`SkinLayer::ALL`] order.
    /// Face and forearm: Table 1 (Table 4 uses the same values for both). Back of hand and
    /// palm: Table 4 rows 42-Left and 42-Right.
    pub fn thickness_at_30_mm(self) -> [f64; 5] {
        match self {
            BodyLocation::Face | BodyLocation::Forearm => [0.02, 0.08, 0.18, 1.82, 5.9],
            BodyLocation::BackOfHand => [0.029, 0.08, 0.06, 0.65, 5.9],
            BodyLocation::Palm => [0.173, 0.48, 0.08, 0.80, 5.9],
        }
    }

    /// Linear thickness loss per decade after 30, as a fraction of the age-30 thickness.
    ///
    /// Table 1: SC n.a. (0), LE 6.4 %, PD and RD 6–16 % (6 % reproduces Table 4's 55- and
    /// 80-year columns), HD 0 (Table 4 keeps 5.9 mm at every age; Table 1's 30–50 % is a spec
    /// option). The palm (row 42-Right) ages at its own rates, chosen inside Table 1's ranges
    /// where one is given, so that row reproduces; see DECISIONS.md.
    pub fn atrophy_per_decade(self) -> [f64; 5] {
        match self {
            BodyLocation::Palm => [0.0, 0.054, 0.075, 0.0625, 0.0],
            _ => [0.0, 0.064, 0.06, 0.06, 0.0],
        }
    }
}

/// Fitzpatrick skin type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum SkinType {
    I,
    II,
    III,
    IV,
    V,
    VI,
}

impl SkinType {
    pub const ALL: [SkinType; 6] = [
        SkinType::I,
        SkinType::II,
        SkinType::III,
        SkinType::IV,
        SkinType::V,
        SkinType::VI,
    ];

    pub fn roman(self) -> &'static str {
        match self {
            SkinType::I => "I",
            SkinType::II => "II",
            SkinType::III => "III",
            SkinType::IV => "IV",
            SkinType::V => "V",
            SkinType::VI => "VI",
        }
    }
}

/// How a skin type becomes a melanosome fraction ϑm at age 30.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SkinTypeMelanin {
    /// Inside the Fig. 40 caption's range: the value Table 4 uses most for the type where one
    /// falls in the range (I 2 %, II 3 % as in Fig. 35, III 7 %, IV 15 %), else the range's
    /// midpoint (V 30 %), and VI 35 % (the caption's lower bound, Table 2's upper bound).
    Caption,
    /// Table 4 row 40, the values used to render Fig. 40 itself: 1, 3, 5, 10, 20, 30 %
    /// (IV–VI lie outside the caption's own ranges).
    Figure40,
}

impl SkinTypeMelanin {
    pub fn fraction(self, t: SkinType) -> f64 {
        let table = match self {
            SkinTypeMelanin::Caption => [0.02, 0.03, 0.07, 0.15, 0.30, 0.35],
            SkinTypeMelanin::Figure40 => [0.01, 0.03, 0.05, 0.10, 0.20, 0.30],
        };
        table[t as usize]
    }
}

/// The melanin input of an entry: a type, or an explicit fraction (never both).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MelaninInput {
    SkinType(SkinType),
    MelanosomeFraction(f64),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// Five layers, §3.4.
    FiveLayer,
    /// The simplified three-layer model, §3.6.1.
    ThreeLayer,
}

/// Hypodermis absorption: Table 6 (water only) or Table 2 / Table 4 caption (5 % blood).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HypodermisAbsorption {
    /// Dermal formula of Table 6 with ϑHb = 5 % (Table 2, Table 4 caption). Default.
    Blood,
    /// μa = water only, as Table 6 writes it.
    WaterOnly,
}

/// Pheomelanin absorption inside melanosomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PheomelaninAbsorption {
    /// Table 5's power law 2.9·10¹⁴ λ^-4.75 mm⁻¹ at full strength, as Table 6 adds it. Default.
    ThesisFit,
    /// Sarna & Swartz's measured pheomelanin extinction at the caption's 12 g/L.
    Measured,
}

/// Aging processes held at their age-30 values, to isolate one effect as Table 4 does with its
/// "c" entries (Figs. 37, 38, 43).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Freeze {
    pub thickness: bool,
    pub melanin: bool,
    pub hemoglobin: bool,
    pub surface: bool,
    pub collagen: bool,
    pub junction: bool,
}

/// Skew-normal distribution of collagen fiber diameters (Eq. 8): location, scale in µm, shape ζ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SkewNormal {
    pub location_um: f64,
    pub scale_um: f64,
    pub shape: f64,
}

/// Collagen diameter distributions at 30 and 80 years; linear in between (§3.4.4).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CollagenAging {
    pub at_30: SkewNormal,
    pub at_80: SkewNormal,
}

/// Every input of the model, validated and with units applied.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkinParams {
    pub age_years: f64,
    pub gender: Gender,
    pub location: BodyLocation,
    /// Exposure to external aging agents ξ ∈ [0, 1] (Eq. 4).
    pub xi: f64,
    pub melanin: MelaninInput,
    pub skin_type_melanin: SkinTypeMelanin,
    pub model: ModelKind,
    /// ϑHb of the papillary dermis at age 30 (volume fraction of whole blood).
    pub blood_fraction_pd: f64,
    /// ϑHb of the reticular dermis at age 30.
    pub blood_fraction_rd: f64,
    /// ϑHb of the hypodermis (constant with age, Table 4 caption).
    pub blood_fraction_hd: f64,
    /// Oxy/(oxy + deoxy) hemoglobin, Table 4 caption: 75 %.
    pub oxygen_saturation: f64,
    /// Hemoglobin in whole blood, g/L (Table 4 caption: 150).
    pub hemoglobin_g_per_l: f64,
    /// Bilirubin in blood, g/L (Table 4 caption: 0.05).
    pub bilirubin_g_per_l: f64,
    /// β-carotene in blood (dermis), g/L (Table 2: 7.0e-5).
    pub carotene_blood_g_per_l: f64,
    /// β-carotene in the epidermis, g/L (Table 2: 2.1e-4).
    pub carotene_epidermis_g_per_l: f64,
    /// Eumelanin in melanosomes, g/L (Table 4 caption: 80; reported, used by no formula of
    /// Table 6, whose melanin fits are already per melanosome volume).
    pub eumelanin_g_per_l: f64,
    /// Pheomelanin in melanosomes, g/L (Table 4 caption: 12; used by the `measured` option).
    pub pheomelanin_g_per_l: f64,
    pub pheomelanin_absorption: PheomelaninAbsorption,
    pub hypodermis_absorption: HypodermisAbsorption,
    /// f_H2O per layer.
    pub water_fraction: [f64; 5],
    /// Thickness at age 30 per layer, mm.
    pub thickness_at_30_mm: [f64; 5],
    /// Linear thickness loss per decade, fraction of the age-30 value.
    pub atrophy_per_decade: [f64; 5],
    /// Peak amplitude A of Eq. 1 at age ≤ 30, µm.
    pub dej_amplitude_at_30_um: f64,
    /// Spatial period of Eq. 1 along x and y, µm.
    pub dej_period_um: f64,
    /// Phases φx, φy of Eq. 1, rad.
    pub dej_phase_rad: [f64; 2],
    /// Rz at this age, µm, when given explicitly (else Fig. 33 / Table 4).
    pub rz_um: Option<f64>,
    /// Sebum production at this age, mg lipid / 10 cm² / 3 h, when given explicitly.
    pub sebum_mg: Option<f64>,
    /// κ in V_s = κ·s·l² (Appendix 3.8), calibrated to Table 4's m column.
    pub sebum_volume_factor: f64,
    /// Collagen diameters of the papillary dermis (Eqs. 8–9).
    pub collagen_pd: CollagenAging,
    /// Collagen diameters of the reticular dermis (Eqs. 8–9).
    pub collagen_rd: CollagenAging,
    pub freeze: Freeze,
}

/// Default collagen distributions. Fig. 39 draws them without numbers; these are chosen so the
/// adult reticular dermis has Jacques' measured dermal Mie exponent (b ≈ 0.56, Jacques 2013)
/// and fibers grow thicker, more spread and more skewed with age (§3.4.4). See DECISIONS.md.
pub const COLLAGEN_PD_DEFAULT: CollagenAging = CollagenAging {
    at_30: SkewNormal {
        location_um: 3.0,
        scale_um: 1.5,
        shape: 0.0,
    },
    at_80: SkewNormal {
        location_um: 4.5,
        scale_um: 3.0,
        shape: 3.0,
    },
};
pub const COLLAGEN_RD_DEFAULT: CollagenAging = CollagenAging {
    at_30: SkewNormal {
        location_um: 10.0,
        scale_um: 3.0,
        shape: 0.0,
    },
    at_80: SkewNormal {
        location_um: 13.0,
        scale_um: 5.0,
        shape: 3.0,
    },
};

impl SkinParams {
    /// The thesis defaults for a person; every other field can then be overridden.
    pub fn new(
        age_years: f64,
        gender: Gender,
        location: BodyLocation,
        melanin: MelaninInput,
        xi: f64,
    ) -> Self {
        Self {
            age_years,
            gender,
            location,
            xi,
            melanin,
            skin_type_melanin: SkinTypeMelanin::Caption,
            model: ModelKind::FiveLayer,
            // Table 4: 6 % / 4.5 % in rows 37, 40, 42, 43 (the face rows 29 and 41 use other
            // values, given there as overrides).
            blood_fraction_pd: 0.06,
            blood_fraction_rd: 0.045,
            blood_fraction_hd: 0.05,
            oxygen_saturation: 0.75,
            hemoglobin_g_per_l: 150.0,
            bilirubin_g_per_l: 0.05,
            carotene_blood_g_per_l: 7.0e-5,
            carotene_epidermis_g_per_l: 2.1e-4,
            eumelanin_g_per_l: 80.0,
            pheomelanin_g_per_l: 12.0,
            pheomelanin_absorption: PheomelaninAbsorption::ThesisFit,
            hypodermis_absorption: HypodermisAbsorption::Blood,
            water_fraction: SkinLayer::ALL.map(SkinLayer::default_water_fraction),
            thickness_at_30_mm: location.thickness_at_30_mm(),
            atrophy_per_decade: location.atrophy_per_decade(),
            // Table 4 caption: rete ridges of 100 µm at 30; Eq. 1's amplitude is half of it.
            dej_amplitude_at_30_um: 50.0,
            dej_period_um: 100.0,
            dej_phase_rad: [0.0, 0.0],
            rz_um: None,
            sebum_mg: None,
            sebum_volume_factor: 1.41,
            collagen_pd: COLLAGEN_PD_DEFAULT,
            collagen_rd: COLLAGEN_RD_DEFAULT,
            freeze: Freeze::default(),
        }
    }

    /// ϑm at age 30 (before Eq. 3).
    pub fn melanosome_fraction_at_30(&self) -> f64 {
        match self.melanin {
            MelaninInput::SkinType(t) => self.skin_type_melanin.fraction(t),
            MelaninInput::MelanosomeFraction(f) => f,
        }
    }
}
