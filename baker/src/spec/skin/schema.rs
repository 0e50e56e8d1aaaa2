//! What the skin resolver checks that a JSON Schema can state ([`crate::spec::schema`]), from
//! the resolver's own constants: ranges, names, required fields (unless `defaults` gives them),
//! fields that exclude each other, lists only in `sweeps`, sweep templates that name every
//! swept field.

use serde_json::{json, Value};

use super::overrides::{
    ATROPHY_PER_DECADE, BLOOD_AND_PIGMENTS, COLLAGEN_LOCATION_UM, COLLAGEN_SCALE_UM,
    COLLAGEN_SHAPE, FREEZABLE, HYPODERMIS_ABSORPTION, JUNCTION, PHEOMELANIN_ABSORPTION, RZ_UM,
    SEBUM_MG, SEBUM_VOLUME_FACTOR, SKIN_TYPE_MELANIN, THICKNESS_MM, WATER_FRACTION,
};
use super::params::{GENDERS, LOCATIONS, MELANOSOME_FRACTION, MODELS, XI};
use super::{profiles, wavelengths, AGE_RANGE_YEARS};
use crate::skin::{SkinLayer, SkinType};
use crate::spec::check::Bounds;
use crate::spec::schema::{
    all_of, any_scalar_text, bound, def, each_scalar, given, has_type, keys, names, not_both, prop,
    shared,
};

/// Fields every entry needs, from itself or `defaults` (`params`).
const REQUIRED: [&str; 4] = ["age", "gender", "location", "xi"];
/// Melanin: a skin type or a melanosome fraction, not both.
const MELANIN: [&str; 2] = ["skin_type", "melanosome_fraction"];

pub(in crate::spec) fn refine(root: &mut Value) {
    shared(root);
    params(def(root, "RawParams"));
    let sn = def(root, "RawSkewNormal");
    bound(prop(sn, "location_um"), COLLAGEN_LOCATION_UM);
    bound(prop(sn, "scale_um"), COLLAGEN_SCALE_UM);
    bound(prop(sn, "shape"), COLLAGEN_SHAPE);
    profile_settings(root);
    let w = def(root, "RawWavelengths");
    for f in ["start_nm", "stop_nm", "list_nm"] {
        bound(prop(w, f), wavelengths::LAMBDA_NM);
    }
    bound(prop(w, "step_nm"), wavelengths::STEP_NM);
    prop(w, "list_nm")["minItems"] = json!(1);
    for r in ["start_nm", "stop_nm", "step_nm"] {
        all_of(w, not_both("list_nm", r));
    }
    blocks(root);
}

/// An entry's fields (`params`, `overrides`).
fn params(p: &mut Value) {
    bound(
        prop(p, "age"),
        Bounds::closed(AGE_RANGE_YEARS.0, AGE_RANGE_YEARS.1),
    );
    bound(prop(p, "xi"), XI);
    bound(prop(p, "melanosome_fraction"), MELANOSOME_FRACTION);
    names(prop(p, "gender"), &keys(&GENDERS));
    names(prop(p, "location"), &keys(&LOCATIONS));
    names(prop(p, "model"), &keys(&MODELS));
    names(prop(p, "skin_type_melanin"), &keys(&SKIN_TYPE_MELANIN));
    names(
        prop(p, "pheomelanin_absorption"),
        &keys(&PHEOMELANIN_ABSORPTION),
    );
    names(
        prop(p, "hypodermis_absorption"),
        &keys(&HYPODERMIS_ABSORPTION),
    );
    names(prop(p, "freeze"), &keys(&FREEZABLE));
    any_scalar_text(prop(p, "name"));
    // `skin_type`: a roman numeral, or its number (`params::skin_type`).
    let romans: Vec<&str> = SkinType::ALL.iter().map(|t| t.roman()).collect();
    each_scalar(prop(p, "skin_type"), &mut |o| {
        if !has_type(o, "string") {
            return; // null: absent
        }
        o.remove("type");
        o.insert(
            "anyOf".into(),
            json!([
                { "enum": romans },
                { "type": "integer", "minimum": 1, "maximum": SkinType::ALL.len() }
            ]),
        );
    });
    for r in BLOOD_AND_PIGMENTS.iter().chain(&JUNCTION) {
        bound(prop(p, r.field), r.bounds());
    }
    for (field, b) in [("rz_um", RZ_UM), ("sebum_mg", SEBUM_MG)] {
        bound(prop(p, field), b);
    }
    bound(prop(p, "sebum_volume_factor"), SEBUM_VOLUME_FACTOR);
    for (field, b) in [
        ("water_fraction", WATER_FRACTION),
        ("thickness_mm", THICKNESS_MM),
        ("atrophy_per_decade", ATROPHY_PER_DECADE),
    ] {
        layer_bounds(prop(p, field), b);
    }
    // A swept value listed twice would bake one entry twice (`sweep::reject_repeats`).
    for f in swept(p) {
        each_list(prop(p, &f), &mut |l| {
            l.insert("uniqueItems".into(), json!(true));
        });
    }
    all_of(p, not_both(MELANIN[0], MELANIN[1]));
}

/// Bounds `b` on each layer of a per-layer map (one definition shared by the three maps, so
/// the bounds sit beside its reference).
fn layer_bounds(field: &mut Value, b: Bounds) {
    let layers: serde_json::Map<String, Value> = SkinLayer::ALL
        .iter()
        .map(|l| {
            let mut s = json!({ "type": ["number", "null"] });
            bound(&mut s, b);
            (l.key().to_string(), s)
        })
        .collect();
    let r = field
        .pointer_mut("/anyOf/0")
        .filter(|r| r.get("$ref").is_some())
        .expect("a per-layer map is a reference or null");
    r["properties"] = Value::Object(layers);
}

/// The fields of `p` that take a list (the sweepable ones: [`super::raw::OneOrMany`]).
fn swept(p: &Value) -> Vec<String> {
    let props = p["properties"]
        .as_object()
        .expect("RawParams has properties");
    props
        .iter()
        .filter(|(_, s)| {
            s.pointer("/anyOf/0/anyOf/1/type")
                .is_some_and(|t| t == "array")
        })
        .map(|(k, _)| k.clone())
        .collect()
}

/// Calls `f` on every list schema inside `s` (through `anyOf`).
fn each_list(s: &mut Value, f: &mut dyn FnMut(&mut serde_json::Map<String, Value>)) {
    let Some(o) = s.as_object_mut() else { return };
    if let Some(Value::Array(alts)) = o.get_mut("anyOf") {
        for a in alts {
            each_list(a, f);
        }
    }
    if o.get("type").is_some_and(|t| t == "array") {
        f(o);
    }
}

/// `profiles:` and its radial grid (`profiles`).
fn profile_settings(root: &mut Value) {
    let p = def(root, "RawProfiles");
    bound(prop(p, "photons"), profiles::PHOTONS);
    bound(prop(p, "seed"), profiles::SEED);
    bound(prop(p, "gaussians"), profiles::GAUSSIANS);
    bound(prop(p, "max_photon_boost"), profiles::MAX_PHOTON_BOOST);
    bound(prop(p, "noise_target"), profiles::NOISE_TARGET);
    // A boost needs `noise_target: 0` (the default target is not 0).
    all_of(
        p,
        json!({
            "if": {
                "allOf": [given(&["max_photon_boost"])],
                "properties": { "max_photon_boost": { "exclusiveMinimum": 1 } }
            },
            "then": {
                "required": ["noise_target"],
                "properties": { "noise_target": { "const": 0 } }
            }
        }),
    );
    let r = def(root, "RawRadial");
    bound(prop(r, "dr_min_mm"), profiles::DR_MIN_MM);
    bound(prop(r, "growth"), profiles::GROWTH);
    bound(prop(r, "r_max_mm"), profiles::R_MAX_MM);
}

/// `defaults`, `entries` and `sweeps` (`resolve`): names, lists only in sweeps, templates that
/// name each swept field, and what every entry needs, from itself or from `defaults`.
fn blocks(root: &mut Value) {
    let fields = swept(def(root, "RawParams"));
    let no_lists: serde_json::Map<String, Value> = fields
        .iter()
        .map(|f| (f.clone(), json!({ "not": { "type": "array" } })))
        .collect();
    let d = prop(root, "defaults")
        .pointer_mut("/anyOf/0")
        .expect("defaults: a reference or null");
    d["properties"] = Value::Object(no_lists.clone());
    d["not"] = given(&["name"]);
    let e = &mut prop(root, "entries")["items"];
    e["properties"] = Value::Object(no_lists);
    e["required"] = json!(["name"]);
    let s = &mut prop(root, "sweeps")["items"];
    s["required"] = json!(["name"]);
    for f in &fields {
        all_of(
            s,
            json!({
                "if": {
                    "required": [f],
                    "properties": { (f.as_str()): { "type": "array", "minItems": 2 } }
                },
                "then": { "properties": { "name": { "pattern": format!("\\{{{f}\\}}") } } }
            }),
        );
    }
    let in_each = |constraint: Value| {
        json!({ "properties": {
            "entries": { "items": constraint.clone() },
            "sweeps": { "items": constraint }
        } })
    };
    let defaults_give = |fields: &[&str]| json!({ "required": ["defaults"], "properties": { "defaults": given(fields) } });
    for f in REQUIRED {
        all_of(
            root,
            json!({ "if": defaults_give(&[f]), "else": in_each(json!({ "required": [f] })) }),
        );
    }
    let melanin_given = json!({ "anyOf": [
        defaults_give(&MELANIN[..1]), defaults_give(&MELANIN[1..])
    ] });
    let either = json!({ "anyOf": [{ "required": [MELANIN[0]] }, { "required": [MELANIN[1]] }] });
    all_of(
        root,
        json!({ "if": melanin_given, "else": in_each(either) }),
    );
    for (d, e) in [(MELANIN[0], MELANIN[1]), (MELANIN[1], MELANIN[0])] {
        all_of(
            root,
            json!({ "if": defaults_give(&[d]), "then": in_each(json!({ "not": given(&[e]) })) }),
        );
    }
}
