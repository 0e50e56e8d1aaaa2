//! The spec as written: serde structs that keep the location of every value and reject
//! unknown fields. Ranges and meaning are checked by the resolver ([`super`]).

use std::borrow::Cow;
use std::fmt;
use std::marker::PhantomData;

use crate::spec::yaml::Spanned;
use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::de::{self, IntoDeserializer, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};

/// A skin spec (thesis ch. 3): entries and sweeps of skin parameters, for layer optics and
/// diffusion profiles.
#[derive(Debug, Deserialize, Default, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSpec {
    /// Spec format version; 1 today.
    pub version: Option<Spanned<u32>>,
    /// The spectral grid: a range (`start_nm`, `stop_nm`, `step_nm`) or a list (`list_nm`);
    /// 400–700 nm every 10 nm by default.
    pub wavelengths: Option<Spanned<RawWavelengths>>,
    /// Values every entry and sweep starts from.
    pub defaults: Option<Spanned<RawParams>>,
    /// One entry per skin: a name and single values (on top of `defaults`).
    #[serde(default)]
    pub entries: Vec<Spanned<RawParams>>,
    /// Lists of values expanded to every combination, each entry named by the sweep's
    /// template (`fitz_{skin_type}_{age}`).
    #[serde(default)]
    pub sweeps: Vec<Spanned<RawParams>>,
    /// How diffusion profiles are baked (photons, seed, radial grid, Gaussian count).
    pub profiles: Option<Spanned<RawProfiles>>,
    /// Resource budgets: what the spec may ask for before the baker allocates it (raise one
    /// deliberately for a larger bake; README "Hostile input").
    pub limits: Option<Spanned<crate::spec::limits::RawLimits>>,
}

/// `profiles: {photons, seed, gaussians, radial: {dr_min_mm, growth, r_max_mm}}`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawProfiles {
    /// Photon packets per wavelength and shared simulation (a whole number; 4,000,000 by
    /// default).
    pub photons: Option<Spanned<f64>>,
    /// Random seed (a whole number; 1 by default).
    pub seed: Option<Spanned<f64>>,
    /// Gaussians in the sum-of-Gaussians fit of each profile (6 by default, for real-time
    /// renderers).
    pub gaussians: Option<Spanned<f64>>,
    /// Cheap wavelengths get up to this many times `photons` (a whole number; 1 by default;
    /// more needs `noise_target: 0`).
    pub max_photon_boost: Option<Spanned<f64>>,
    /// Relative standard error the RGB profile bins may relax to (0.01 by default; 0:
    /// `photons` at every wavelength).
    pub noise_target: Option<Spanned<f64>>,
    /// The radial grid of the profiles.
    pub radial: Option<Spanned<RawRadial>>,
}

/// The radial grid of the profiles: fine bins of `dr_min_mm`, then geometric growth.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawRadial {
    /// Width of the fine bins near the beam, mm (0.01 by default).
    pub dr_min_mm: Option<Spanned<f64>>,
    /// Each coarser bin is this many times wider than the one before (1.05 by default).
    pub growth: Option<Spanned<f64>>,
    /// Outer radius of the grid, mm (40 by default; above `dr_min_mm`).
    pub r_max_mm: Option<Spanned<f64>>,
}

/// `wavelengths: {start_nm, stop_nm, step_nm}` or `wavelengths: {list_nm: [...]}`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawWavelengths {
    /// First wavelength of the range, nm (400 by default).
    pub start_nm: Option<Spanned<f64>>,
    /// Last wavelength of the range, nm (700 by default; not below `start_nm`).
    pub stop_nm: Option<Spanned<f64>>,
    /// Step of the range, nm (10 by default).
    pub step_nm: Option<Spanned<f64>>,
    /// Wavelengths, nm, rising; instead of the range.
    pub list_nm: Option<Spanned<Vec<Spanned<f64>>>>,
}

/// One value, or a list of values to sweep over (lists are allowed in `sweeps` only).
#[derive(Debug, Clone)]
pub enum OneOrMany<T> {
    One(T),
    Many(Vec<Spanned<T>>),
}

/// The value's schema, or a list of such values.
impl<T: JsonSchema> JsonSchema for OneOrMany<T> {
    fn inline_schema() -> bool {
        true
    }
    fn schema_name() -> Cow<'static, str> {
        format!("OneOrMany_{}", T::schema_name()).into()
    }
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let one = g.subschema_for::<T>();
        json_schema!({ "anyOf": [one, { "type": "array", "items": one }] })
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for OneOrMany<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = OneOrMany<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a value or a list of values")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some(v) = seq.next_element::<Spanned<T>>()? {
                    out.push(v);
                }
                Ok(OneOrMany::Many(out))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(OneOrMany::One)
            }
            fn visit_string<E: de::Error>(self, v: String) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(OneOrMany::One)
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(OneOrMany::One)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(OneOrMany::One)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(OneOrMany::One)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(OneOrMany::One)
            }
        }
        d.deserialize_any(V(PhantomData))
    }
}

/// A scalar written either as a number or as text (skin types: `II` or `2`).
#[derive(Debug, Clone, PartialEq)]
pub enum Token {
    Text(String),
    Number(f64),
}

impl fmt::Display for Token {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Token::Text(s) => write!(f, "{s}"),
            Token::Number(x) => write!(f, "{x}"),
        }
    }
}

/// Text or a number, as [`Token`]'s `Deserialize` takes it.
impl JsonSchema for Token {
    fn inline_schema() -> bool {
        true
    }
    fn schema_name() -> Cow<'static, str> {
        "Token".into()
    }
    fn json_schema(_: &mut SchemaGenerator) -> Schema {
        json_schema!({ "type": ["string", "number"] })
    }
}

impl<'de> Deserialize<'de> for Token {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Token;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a name or a number")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Token, E> {
                Ok(Token::Text(v.to_string()))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Token, E> {
                Ok(Token::Number(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Token, E> {
                Ok(Token::Number(v as f64))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Token, E> {
                Ok(Token::Number(v))
            }
        }
        d.deserialize_any(V)
    }
}

pub type Sweepable<T> = Option<Spanned<OneOrMany<T>>>;
pub type Scalar<T> = Option<Spanned<T>>;

/// Parameters of an entry, a sweep or the `defaults` block.
#[derive(Debug, Deserialize, Default, Clone, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawParams {
    /// Entry name; in a sweep, a template with `{field}` placeholders.
    pub name: Scalar<String>,
    /// Age, years.
    pub age: Sweepable<f64>,
    /// Gender (sebum production, §3.4.2).
    pub gender: Sweepable<String>,
    /// Fitzpatrick skin type, I–VI (or 1–6); or give `melanosome_fraction`.
    pub skin_type: Sweepable<Token>,
    /// Melanosome volume fraction ϑm of the epidermis at age 30, in place of `skin_type`.
    pub melanosome_fraction: Sweepable<f64>,
    /// Body location (its layer thicknesses, Table 1).
    pub location: Sweepable<String>,
    /// Exposure to external aging agents ξ (Eq. 4): 0 none, 1 most.
    pub xi: Sweepable<f64>,
    /// Layer model: five layers (stratum corneum, living epidermis, papillary and reticular
    /// dermis, hypodermis; the default) or three.
    pub model: Sweepable<String>,
    // Overrides of biophysical parameters.
    /// How a skin type becomes melanin: the values of the thesis caption or of Fig. 40.
    pub skin_type_melanin: Scalar<String>,
    /// Blood volume fraction of the papillary dermis at age 30.
    pub blood_fraction_pd: Scalar<f64>,
    /// Blood volume fraction of the reticular dermis at age 30.
    pub blood_fraction_rd: Scalar<f64>,
    /// Blood volume fraction of the hypodermis.
    pub blood_fraction_hd: Scalar<f64>,
    /// Oxygen saturation of the blood, fraction.
    pub oxygen_saturation: Scalar<f64>,
    /// Hemoglobin concentration of whole blood, g/L.
    pub hemoglobin_g_per_l: Scalar<f64>,
    /// Bilirubin concentration of the blood, g/L (0 switches it off).
    pub bilirubin_g_per_l: Scalar<f64>,
    /// β-carotene concentration of the blood, g/L.
    pub carotene_blood_g_per_l: Scalar<f64>,
    /// β-carotene concentration of the epidermis, g/L.
    pub carotene_epidermis_g_per_l: Scalar<f64>,
    /// Eumelanin concentration inside the melanosomes, g/L.
    pub eumelanin_g_per_l: Scalar<f64>,
    /// Pheomelanin concentration inside the melanosomes, g/L.
    pub pheomelanin_g_per_l: Scalar<f64>,
    /// Pheomelanin absorption spectrum: the thesis's fit or the measured one.
    pub pheomelanin_absorption: Scalar<String>,
    /// What absorbs in the hypodermis: blood (and water), or water only.
    pub hypodermis_absorption: Scalar<String>,
    /// Water volume fraction of each layer.
    pub water_fraction: Scalar<RawLayerValues>,
    /// Thickness of each layer at age 30, mm.
    pub thickness_mm: Scalar<RawLayerValues>,
    /// Relative thinning of each layer per decade past 30.
    pub atrophy_per_decade: Scalar<RawLayerValues>,
    /// Amplitude of the dermal–epidermal junction's undulation at age 30, µm.
    pub dej_amplitude_um: Scalar<f64>,
    /// Period of the dermal–epidermal junction's undulation, µm.
    pub dej_period_um: Scalar<f64>,
    /// Phases of the junction's undulation along x and y, radians (two finite numbers).
    pub dej_phase_rad: Scalar<[f64; 2]>,
    /// Surface roughness Rz, µm.
    pub rz_um: Scalar<f64>,
    /// Sebum on the surface, mg.
    pub sebum_mg: Scalar<f64>,
    /// Volume of the sebum film per mg of sebum.
    pub sebum_volume_factor: Scalar<f64>,
    /// Collagen fibre diameters of the papillary dermis.
    pub collagen_pd: Scalar<RawCollagen>,
    /// Collagen fibre diameters of the reticular dermis.
    pub collagen_rd: Scalar<RawCollagen>,
    /// Aging processes held at their age-30 values.
    pub freeze: Scalar<Vec<Spanned<String>>>,
}

/// Per-layer values, keyed by layer (`living_epidermis: 0.08`).
#[derive(Debug, Deserialize, Default, Clone, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawLayerValues {
    /// The stratum corneum's value.
    pub stratum_corneum: Scalar<f64>,
    /// The living epidermis's value.
    pub living_epidermis: Scalar<f64>,
    /// The papillary dermis's value.
    pub papillary_dermis: Scalar<f64>,
    /// The reticular dermis's value.
    pub reticular_dermis: Scalar<f64>,
    /// The hypodermis's value.
    pub hypodermis: Scalar<f64>,
}

impl RawLayerValues {
    /// In [`crate::skin::SkinLayer::ALL`] order.
    pub fn as_array(&self) -> [&Scalar<f64>; 5] {
        [
            &self.stratum_corneum,
            &self.living_epidermis,
            &self.papillary_dermis,
            &self.reticular_dermis,
            &self.hypodermis,
        ]
    }
}

/// Collagen diameter distributions at 30 and 80 years (Eqs. 8–9).
#[derive(Debug, Deserialize, Clone, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawCollagen {
    /// The distribution at 30 years.
    pub at_30: Spanned<RawSkewNormal>,
    /// The distribution at 80 years.
    pub at_80: Spanned<RawSkewNormal>,
}

/// A skew-normal distribution of collagen fibre diameters.
#[derive(Debug, Deserialize, Clone, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSkewNormal {
    /// Location, µm.
    pub location_um: Spanned<f64>,
    /// Scale, µm.
    pub scale_um: Spanned<f64>,
    /// Shape (skewness parameter; 0 is a normal distribution).
    pub shape: Spanned<f64>,
}
