//! What the fiber resolver checks that a JSON Schema can state ([`crate::spec::schema`]), from
//! the resolver's own constants: ranges, names (fiber types, shapes, dye classes, the dye
//! presets), and fields that exclude or need each other.

use serde_json::{json, Value};

use super::dyes::{FWHM_NM, PEAK_EPS, PEAK_NM};
use super::resolve::{ETA, SECTIONS, SEED, SYMMETRY, VARIANT};
use super::section::{DIAMETER_UM, ELLIPSE, RATIO, SMOOTHING_PASSES, UM_PER_PX};
use super::settings::{
    CHANNELS, LAMBDA_NM, LAMBDA_STEP_NM, PHOTONS_PER_DIRECTION, PRECISIONS, RESOLUTION_DEG, SPLIT,
};
use super::surface::{CUTICLE_LENGTH_UM, CUTICLE_TILT_DEG, L_NM, MAX_BETA_DEG, RA_NM};
use crate::fiber::dye::{self, DyeClass};
use crate::fiber::material::TABLE_9;
use crate::fiber::section::generate::Shape;
use crate::fiber::slices::BakeSettings;
use crate::spec::check::Bounds;
use crate::spec::schema::{
    all_of, any_scalar_text, bound, def, each_scalar, given, keys, names, not_both, prop, shared,
};

pub(in crate::spec) fn refine(root: &mut Value) {
    shared(root);
    let presets: Vec<String> = dye::presets().into_iter().map(|d| d.name).collect();
    fiber(def(root, "RawFiber"), &presets);
    section(def(root, "RawSection"));
    let r = def(root, "RawRoughness");
    bound(prop(r, "ra_nm"), RA_NM);
    bound(prop(r, "l_nm"), L_NM);
    let c = def(root, "RawCuticle");
    bound(prop(c, "length_um"), CUTICLE_LENGTH_UM);
    bound(prop(c, "tilt_deg"), CUTICLE_TILT_DEG);
    dyes(root, &presets);
    bake(root);
    estimators(def(root, "RawEstimators"));
}

/// The estimator fields, of `bake:` or of a fiber's `estimators:`.
fn estimators(b: &mut Value) {
    bound(prop(b, "split"), SPLIT);
    bound(prop(b, "exit_draws"), super::settings::EXIT_DRAWS);
    names(
        prop(b, "expected_exits"),
        &keys(&super::settings::EXPECTED_EXITS),
    );
    names(prop(b, "sampling"), &keys(&super::settings::SAMPLINGS));
    bound(prop(b, "share_theta"), super::settings::SHARE_THETA);
}

/// Depth of shade, percent (§5.3.1's range of ζ).
fn depth_of_shade() -> Bounds {
    Bounds::closed(100.0 * dye::DOS_RANGE.0, 100.0 * dye::DOS_RANGE.1)
}

/// One fiber (`resolve`, `surface`, `dyeing`).
fn fiber(f: &mut Value, presets: &[String]) {
    any_scalar_text(prop(f, "name"));
    let types: Vec<&str> = TABLE_9.iter().map(|t| t.name).collect();
    names(prop(f, "type"), &types);
    bound(prop(f, "seed"), SEED);
    bound(prop(f, "variant"), VARIANT);
    bound(prop(f, "diameter_um"), DIAMETER_UM);
    bound(prop(f, "eta"), ETA);
    bound(prop(f, "beta_deg"), Bounds::closed(0.0, MAX_BETA_DEG));
    bound(prop(f, "depth_of_shade_percent"), depth_of_shade());
    bound(prop(f, "sections"), SECTIONS);
    names(prop(f, "symmetry"), &keys(&SYMMETRY));
    any_scalar_text(prop(f, "dye"));
    each_scalar(prop(f, "dye"), &mut |o| {
        o.insert("examples".into(), json!(presets));
    });
    all_of(f, not_both("beta_deg", "roughness"));
    all_of(f, not_both("dye", "sweep"));
    for (a, b) in [
        ("dye", "depth_of_shade_percent"),
        ("depth_of_shade_percent", "dye"),
    ] {
        all_of(f, json!({ "if": given(&[a]), "then": { "required": [b] } }));
    }
    // Several sections are seeded variants of a generated shape (not an ellipse).
    all_of(
        f,
        json!({
            "if": {
                "allOf": [given(&["sections"])],
                "properties": { "sections": { "exclusiveMinimum": 1 } }
            },
            "then": { "properties": { "section": { "anyOf": [
                { "type": "null" },
                { "required": ["shape"], "properties": { "shape": { "not": { "enum": [ELLIPSE, null] } } } }
            ] } } }
        }),
    );
}

/// A cross-section (`section`): exactly one source, the fields that belong to each.
fn section(s: &mut Value) {
    let mut shapes = keys(&Shape::ALL);
    shapes.push(ELLIPSE);
    names(prop(s, "shape"), &shapes);
    bound(prop(s, "ratio"), RATIO);
    bound(prop(s, "um_per_px"), UM_PER_PX);
    bound(prop(s, "smoothing_passes"), SMOOTHING_PASSES);
    any_scalar_text(prop(s, "polygon"));
    any_scalar_text(prop(s, "mask"));
    all_of(
        s,
        json!({ "oneOf": [given(&["shape"]), given(&["polygon"]), given(&["mask"])] }),
    );
    let rules = [
        json!({
            "if": { "not": given(&["mask"]) },
            "then": { "not": { "anyOf": [given(&["um_per_px"]), given(&["smoothing_passes"])] } }
        }),
        json!({ "if": given(&["mask"]), "then": given(&["um_per_px"]) }),
        json!({
            "if": { "required": ["shape"], "properties": { "shape": { "const": ELLIPSE } } },
            "then": given(&["ratio"])
        }),
        json!({
            "if": {
                "allOf": [given(&["shape"])],
                "properties": { "shape": { "not": { "const": ELLIPSE } } }
            },
            "then": { "not": given(&["ratio"]) }
        }),
    ];
    for r in rules {
        all_of(s, r);
    }
}

/// `dyes:` (`dyes`), the sweep's dyes (`dyeing`), and with no `dyes:` the preset names.
fn dyes(root: &mut Value, presets: &[String]) {
    let d = def(root, "RawDye");
    any_scalar_text(prop(d, "name"));
    prop(d, "name")["not"] = json!({ "enum": presets });
    names(prop(d, "class"), &keys(&DyeClass::ALL));
    prop(d, "bands")["minItems"] = json!(1);
    any_scalar_text(prop(d, "csv"));
    any_scalar_text(prop(d, "source"));
    all_of(d, json!({ "oneOf": [given(&["bands"]), given(&["csv"])] }));
    let b = def(root, "RawBand");
    bound(prop(b, "peak_nm"), PEAK_NM);
    bound(prop(b, "fwhm_nm"), FWHM_NM);
    bound(prop(b, "peak_eps_l_per_mg_cm"), PEAK_EPS);
    let sw = def(root, "RawSweep");
    bound(prop(sw, "depth_of_shade_percent"), depth_of_shade());
    for f in ["dyes", "depth_of_shade_percent"] {
        prop(sw, f)["uniqueItems"] = json!(true);
    }
    all_of(
        sw,
        json!({
            "if": { "not": { "required": ["undyed"], "properties": { "undyed": { "const": true } } } },
            "then": { "properties": {
                "dyes": { "minItems": 1 }, "depth_of_shade_percent": { "minItems": 1 }
            } }
        }),
    );
    // Without `dyes:` the dyes a fiber can name are the presets.
    let mut any = presets.iter().map(|p| json!(p)).collect::<Vec<_>>();
    any.push(Value::Null);
    all_of(
        root,
        json!({
            "if": { "not": given(&["dyes"]) },
            "then": { "properties": { "fibers": { "items": { "properties": {
                "dye": { "enum": any },
                "sweep": { "properties": { "dyes": { "items": { "enum": presets } } } }
            } } } } }
        }),
    );
}

/// A field written as a number within `b` or as `word` (or left out), keeping its
/// description.
fn number_or_word(p: &mut Value, b: Bounds, word: &str) {
    let mut number = json!({ "type": "number" });
    bound(&mut number, b);
    let description = p.get("description").cloned();
    *p = json!({ "anyOf": [number, { "const": word }, { "type": "null" }] });
    if let Some(d) = description {
        p["description"] = d;
    }
}

/// `bake:` (`settings`): keep_bits up to the mantissa bits of the precision, the default's
/// when none is given.
fn bake(root: &mut Value) {
    let b = def(root, "RawBake");
    bound(prop(b, "resolution_deg"), RESOLUTION_DEG);
    bound(prop(b, "photons_per_direction"), PHOTONS_PER_DIRECTION);
    bound(prop(b, "seed"), super::settings::SEED);
    estimators(b);
    bound(
        prop(b, "max_photons_per_direction"),
        super::settings::MAX_PHOTONS_PER_DIRECTION,
    );
    number_or_word(
        prop(b, "target_rel_se"),
        super::settings::TARGET_REL_SE,
        "thesis",
    );
    number_or_word(prop(b, "zstd_level"), super::settings::ZSTD_LEVEL, "auto");
    bound(prop(b, "quantise_to_se"), super::settings::QUANTISE_TO_SE);
    names(prop(b, "precision"), &keys(&PRECISIONS));
    names(prop(b, "channels"), &keys(&CHANNELS));
    let most = PRECISIONS.iter().map(|(_, p)| p.mantissa_bits()).max();
    bound(
        prop(b, "keep_bits"),
        Bounds::whole(0.0, f64::from(most.unwrap_or(0))),
    );
    for (name, p) in PRECISIONS {
        let keep = json!({ "properties": { "keep_bits": { "maximum": p.mantissa_bits() } } });
        let chosen =
            json!({ "required": ["precision"], "properties": { "precision": { "const": name } } });
        all_of(b, json!({ "if": chosen, "then": keep.clone() }));
        if p == BakeSettings::default().precision {
            all_of(
                b,
                json!({ "if": { "not": given(&["precision"]) }, "then": keep }),
            );
        }
    }
    let l = def(root, "RawLambda");
    bound(prop(l, "start"), LAMBDA_NM);
    bound(prop(l, "end"), LAMBDA_NM);
    bound(prop(l, "step"), LAMBDA_STEP_NM);
}
