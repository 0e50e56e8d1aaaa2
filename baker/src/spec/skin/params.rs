//! The model inputs of one entry: its required fields (age, gender, location, ξ, melanin as
//! a skin type or a melanosome fraction, model), then its overrides ([`super::overrides`]).

use super::cx::SkinCx;
use super::raw::{RawParams, Token};
use super::sweep::Point;
use super::types::AGE_RANGE_YEARS;
use crate::skin::{BodyLocation, Gender, MelaninInput, ModelKind, SkinParams, SkinType};
use crate::spec::check::{loc, Bounds};
use crate::spec::yaml::Spanned;

/// `gender:` (sebum production, §3.4.2).
pub(in crate::spec) const GENDERS: [(&str, Gender); 2] =
    [("female", Gender::Female), ("male", Gender::Male)];
/// `location:`, the body sites the model has thicknesses for (Table 1).
pub(in crate::spec) const LOCATIONS: [(&str, BodyLocation); 4] = [
    ("face", BodyLocation::Face),
    ("forearm", BodyLocation::Forearm),
    ("back_of_hand", BodyLocation::BackOfHand),
    ("palm", BodyLocation::Palm),
];
/// `model:` (five-layer by default).
pub(in crate::spec) const MODELS: [(&str, ModelKind); 2] = [
    ("five_layer", ModelKind::FiveLayer),
    ("three_layer", ModelKind::ThreeLayer),
];
/// `xi`, exposure to external aging agents ξ (Eq. 4), 0–1.
pub(in crate::spec) const XI: Bounds = Bounds::closed(0.0, 1.0);
/// `melanosome_fraction` ϑm at age 30, in place of a skin type (Table 2: up to 50 %).
pub(in crate::spec) const MELANOSOME_FRACTION: Bounds = Bounds::closed(0.0, 0.5);

impl SkinCx {
    /// Builds the model inputs of one point; records errors and returns None if any.
    pub(super) fn params(
        &mut self,
        p: &RawParams,
        pt: &Point,
        at: (u64, u64),
    ) -> Option<SkinParams> {
        let before = self.errors.len();
        let age = match &pt.age {
            Some(a) => self.in_range("age", a, AGE_RANGE_YEARS.0, AGE_RANGE_YEARS.1, false),
            None => {
                self.invalid(at, "age", "missing (years, 18–90)");
                None
            }
        };
        let gender = match &pt.gender {
            Some(g) => self.choice("gender", g, &GENDERS),
            None => {
                self.invalid(at, "gender", "missing (female or male)");
                None
            }
        };
        let location = match &pt.location {
            Some(l) => self.choice("location", l, &LOCATIONS),
            None => {
                self.invalid(
                    at,
                    "location",
                    "missing (face, forearm, back_of_hand or palm)",
                );
                None
            }
        };
        let xi = match &pt.xi {
            Some(x) => self.in_bounds("xi", x, XI),
            None => {
                self.invalid(at, "xi", "missing (exposure to external aging agents, 0–1)");
                None
            }
        };
        let melanin = match (&pt.skin_type, &pt.melanosome_fraction) {
            (Some(t), None) => self.skin_type(t).map(MelaninInput::SkinType),
            (None, Some(f)) => self
                .in_bounds("melanosome_fraction", f, MELANOSOME_FRACTION)
                .map(MelaninInput::MelanosomeFraction),
            (Some(t), Some(f)) => {
                self.invalid(
                    loc(f),
                    "melanosome_fraction",
                    format!(
                        "give skin_type (line {}) or melanosome_fraction, not both",
                        loc(t).0
                    ),
                );
                None
            }
            (None, None) => {
                self.invalid(
                    at,
                    "skin_type",
                    "missing: give skin_type (I–VI) or melanosome_fraction (0–0.5)",
                );
                None
            }
        };
        let model = match &pt.model {
            Some(m) => self.choice("model", m, &MODELS),
            None => Some(ModelKind::FiveLayer),
        };
        let (Some(age), Some(gender), Some(location), Some(xi), Some(melanin), Some(model)) =
            (age, gender, location, xi, melanin, model)
        else {
            return None;
        };
        let mut s = SkinParams::new(age, gender, location, melanin, xi);
        s.model = model;
        self.overrides(p, &mut s);
        (self.errors.len() == before).then_some(s)
    }

    fn skin_type(&mut self, t: &Spanned<Token>) -> Option<SkinType> {
        let found = match &t.value {
            Token::Text(s) => SkinType::ALL
                .iter()
                .find(|k| k.roman() == s.as_str())
                .copied(),
            Token::Number(x)
                if x.fract() == 0.0 && (1.0..=SkinType::ALL.len() as f64).contains(x) =>
            {
                Some(SkinType::ALL[*x as usize - 1])
            }
            Token::Number(_) => None,
        };
        if found.is_none() {
            let near = match &t.value {
                Token::Text(s) => crate::suggest::suffix(s, &SkinType::ALL.map(|k| k.roman())),
                Token::Number(_) => String::new(),
            };
            self.out_of_range(
                loc(t),
                "skin_type",
                t.value.to_string(),
                format!("one of I, II, III, IV, V, VI (or 1–6){near}"),
            );
        }
        found
    }
}
