//! The spec as written: serde structs that keep the location of every value and reject
//! unknown fields. Ranges and meaning are checked by the resolver ([`super`]).

use std::fmt;
use std::marker::PhantomData;

use crate::spec::yaml::Spanned;
use serde::de::{self, IntoDeserializer, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};

/// A whole spec file.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RawSpec {
    /// Spec format version; 1 today.
    pub version: Option<Spanned<u32>>,
    pub wavelengths: Option<Spanned<RawWavelengths>>,
    /// Values every entry and sweep starts from.
    pub defaults: Option<Spanned<RawParams>>,
    #[serde(default)]
    pub entries: Vec<Spanned<RawParams>>,
    #[serde(default)]
    pub sweeps: Vec<Spanned<RawParams>>,
    /// How diffusion profiles are baked (photons, seed, radial grid, Gaussian count).
    pub profiles: Option<Spanned<RawProfiles>>,
    /// Resource budgets ([`crate::spec::limits`]).
    pub limits: Option<Spanned<crate::spec::limits::RawLimits>>,
}

/// `profiles: {photons, seed, gaussians, radial: {dr_min_mm, growth, r_max_mm}}`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawProfiles {
    pub photons: Option<Spanned<f64>>,
    pub seed: Option<Spanned<f64>>,
    pub gaussians: Option<Spanned<f64>>,
    pub max_photon_boost: Option<Spanned<f64>>,
    pub noise_target: Option<Spanned<f64>>,
    pub radial: Option<Spanned<RawRadial>>,
}

/// The radial grid of the profiles: fine bins of `dr_min_mm`, then geometric growth.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRadial {
    pub dr_min_mm: Option<Spanned<f64>>,
    pub growth: Option<Spanned<f64>>,
    pub r_max_mm: Option<Spanned<f64>>,
}

/// `wavelengths: {start_nm, stop_nm, step_nm}` or `wavelengths: {list_nm: [...]}`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawWavelengths {
    pub start_nm: Option<Spanned<f64>>,
    pub stop_nm: Option<Spanned<f64>>,
    pub step_nm: Option<Spanned<f64>>,
    pub list_nm: Option<Spanned<Vec<Spanned<f64>>>>,
}

/// One value, or a list of values to sweep over (lists are allowed in `sweeps` only).
#[derive(Debug, Clone)]
pub enum OneOrMany<T> {
    One(T),
    Many(Vec<Spanned<T>>),
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
#[derive(Debug, Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawParams {
    /// Entry name; in a sweep, a template with `{field}` placeholders.
    pub name: Scalar<String>,
    pub age: Sweepable<f64>,
    pub gender: Sweepable<String>,
    pub skin_type: Sweepable<Token>,
    pub melanosome_fraction: Sweepable<f64>,
    pub location: Sweepable<String>,
    pub xi: Sweepable<f64>,
    pub model: Sweepable<String>,
    // Overrides of biophysical parameters.
    pub skin_type_melanin: Scalar<String>,
    pub blood_fraction_pd: Scalar<f64>,
    pub blood_fraction_rd: Scalar<f64>,
    pub blood_fraction_hd: Scalar<f64>,
    pub oxygen_saturation: Scalar<f64>,
    pub hemoglobin_g_per_l: Scalar<f64>,
    pub bilirubin_g_per_l: Scalar<f64>,
    pub carotene_blood_g_per_l: Scalar<f64>,
    pub carotene_epidermis_g_per_l: Scalar<f64>,
    pub eumelanin_g_per_l: Scalar<f64>,
    pub pheomelanin_g_per_l: Scalar<f64>,
    pub pheomelanin_absorption: Scalar<String>,
    pub hypodermis_absorption: Scalar<String>,
    pub water_fraction: Scalar<RawLayerValues>,
    pub thickness_mm: Scalar<RawLayerValues>,
    pub atrophy_per_decade: Scalar<RawLayerValues>,
    pub dej_amplitude_um: Scalar<f64>,
    pub dej_period_um: Scalar<f64>,
    pub dej_phase_rad: Scalar<[f64; 2]>,
    pub rz_um: Scalar<f64>,
    pub sebum_mg: Scalar<f64>,
    pub sebum_volume_factor: Scalar<f64>,
    pub collagen_pd: Scalar<RawCollagen>,
    pub collagen_rd: Scalar<RawCollagen>,
    pub freeze: Scalar<Vec<Spanned<String>>>,
}

/// Per-layer values, keyed by layer (`living_epidermis: 0.08`).
#[derive(Debug, Deserialize, Default, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawLayerValues {
    pub stratum_corneum: Scalar<f64>,
    pub living_epidermis: Scalar<f64>,
    pub papillary_dermis: Scalar<f64>,
    pub reticular_dermis: Scalar<f64>,
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
#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawCollagen {
    pub at_30: Spanned<RawSkewNormal>,
    pub at_80: Spanned<RawSkewNormal>,
}

#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawSkewNormal {
    pub location_um: Spanned<f64>,
    pub scale_um: Spanned<f64>,
    pub shape: Spanned<f64>,
}
