//! Sweeps: lists of values for the sweepable fields (`age: [20, 50, 80]`), expanded to their
//! Cartesian product of entries, each named by the sweep's template (`fitz_{skin_type}_{age}`).
//! Lists are only allowed in `sweeps`; a swept value is listed once, and the template names
//! every field the sweep varies.

use super::cx::SkinCx;
use super::raw::{OneOrMany, RawParams, Token};
use crate::spec::check::loc;
use crate::spec::yaml::Spanned;

/// One point of a sweep: each sweepable field with the location it came from.
#[derive(Clone, Default)]
pub(super) struct Point {
    pub(super) age: Option<Spanned<f64>>,
    pub(super) gender: Option<Spanned<String>>,
    pub(super) skin_type: Option<Spanned<Token>>,
    pub(super) melanosome_fraction: Option<Spanned<f64>>,
    pub(super) location: Option<Spanned<String>>,
    pub(super) xi: Option<Spanned<f64>>,
    pub(super) model: Option<Spanned<String>>,
}

impl SkinCx {
    pub(super) fn reject_lists(&mut self, p: &RawParams, block: &str) {
        let lists = [
            ("age", is_many(&p.age)),
            ("gender", is_many(&p.gender)),
            ("skin_type", is_many(&p.skin_type)),
            ("melanosome_fraction", is_many(&p.melanosome_fraction)),
            ("location", is_many(&p.location)),
            ("xi", is_many(&p.xi)),
            ("model", is_many(&p.model)),
        ];
        for (field, at) in lists {
            if let Some(at) = at {
                self.invalid(
                    at,
                    field,
                    format!("a list of values is only allowed in `sweeps`, not in `{block}`"),
                );
            }
        }
    }

    /// A swept value listed twice would bake the same entry twice under one name.
    pub(super) fn reject_repeats(&mut self, p: &RawParams) {
        self.repeats("age", &p.age);
        self.repeats("gender", &p.gender);
        self.repeats("skin_type", &p.skin_type);
        self.repeats("melanosome_fraction", &p.melanosome_fraction);
        self.repeats("location", &p.location);
        self.repeats("xi", &p.xi);
        self.repeats("model", &p.model);
    }

    fn repeats<T: PartialEq + std::fmt::Display>(
        &mut self,
        field: &str,
        v: &Option<Spanned<OneOrMany<T>>>,
    ) {
        let Some(Spanned {
            value: OneOrMany::Many(list),
            ..
        }) = v
        else {
            return;
        };
        for (i, x) in list.iter().enumerate() {
            if let Some(first) = list[..i].iter().find(|y| y.value == x.value) {
                self.invalid(
                    loc(x),
                    field,
                    format!(
                        "{} is listed twice (first on line {}); allowed: each swept value once",
                        x.value,
                        loc(first).0
                    ),
                );
            }
        }
    }

    pub(super) fn check_template(&mut self, template: &Spanned<String>, p: &RawParams) {
        let swept = [
            ("age", count(&p.age)),
            ("gender", count(&p.gender)),
            ("skin_type", count(&p.skin_type)),
            ("melanosome_fraction", count(&p.melanosome_fraction)),
            ("location", count(&p.location)),
            ("xi", count(&p.xi)),
            ("model", count(&p.model)),
        ];
        for (field, n) in swept {
            if n > 1 && !template.value.contains(&format!("{{{field}}}")) {
                self.invalid(
                    loc(template),
                    "name",
                    format!("the sweep varies {field}, so its name template needs {{{field}}} to keep entry names unique"),
                );
            }
        }
    }
}

fn is_many<T>(v: &Option<Spanned<OneOrMany<T>>>) -> Option<(u64, u64)> {
    match v {
        Some(s) if matches!(s.value, OneOrMany::Many(_)) => Some(loc(s)),
        _ => None,
    }
}

fn count<T>(v: &Option<Spanned<OneOrMany<T>>>) -> usize {
    match v {
        Some(Spanned {
            value: OneOrMany::Many(m),
            ..
        }) => m.len(),
        _ => 1,
    }
}

/// The values of a sweepable field, each with its own location.
fn values<T: Clone>(v: &Option<Spanned<OneOrMany<T>>>) -> Vec<Option<Spanned<T>>> {
    match v {
        None => vec![None],
        Some(s) => match &s.value {
            OneOrMany::One(x) => vec![Some(Spanned::new(x.clone(), s.referenced, s.defined))],
            OneOrMany::Many(list) if list.is_empty() => vec![None],
            OneOrMany::Many(list) => list.iter().cloned().map(Some).collect(),
        },
    }
}

pub(super) fn single_point(p: &RawParams) -> Point {
    expand(p).into_iter().next().unwrap_or_default()
}

/// How many points [`expand`] gives, without building them (saturating).
pub(super) fn point_count(p: &RawParams) -> u64 {
    [
        count(&p.age),
        count(&p.gender),
        count(&p.skin_type),
        count(&p.melanosome_fraction),
        count(&p.location),
        count(&p.xi),
        count(&p.model),
    ]
    .iter()
    .fold(1u64, |a, &n| a.saturating_mul(n.max(1) as u64))
}

/// Cartesian product of the sweepable fields, in the order they are declared.
pub(super) fn expand(p: &RawParams) -> Vec<Point> {
    let mut points = vec![Point::default()];
    macro_rules! product {
        ($field:ident) => {{
            let vals = values(&p.$field);
            let mut next = Vec::with_capacity(points.len() * vals.len());
            for pt in &points {
                for v in &vals {
                    let mut q = pt.clone();
                    q.$field = v.clone();
                    next.push(q);
                }
            }
            points = next;
        }};
    }
    product!(age);
    product!(gender);
    product!(skin_type);
    product!(melanosome_fraction);
    product!(location);
    product!(xi);
    product!(model);
    points
}

pub(super) fn fill_template(template: &str, pt: &Point) -> String {
    let mut name = template.to_string();
    let mut put = |key: &str, v: Option<String>| {
        if let Some(v) = v {
            name = name.replace(&format!("{{{key}}}"), &v);
        }
    };
    put("age", pt.age.as_ref().map(|v| v.value.to_string()));
    put("gender", pt.gender.as_ref().map(|v| v.value.clone()));
    put(
        "skin_type",
        pt.skin_type.as_ref().map(|v| v.value.to_string()),
    );
    put(
        "melanosome_fraction",
        pt.melanosome_fraction.as_ref().map(|v| v.value.to_string()),
    );
    put("location", pt.location.as_ref().map(|v| v.value.clone()));
    put("xi", pt.xi.as_ref().map(|v| v.value.to_string()));
    put("model", pt.model.as_ref().map(|v| v.value.clone()));
    name
}
