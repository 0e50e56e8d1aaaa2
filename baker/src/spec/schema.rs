//! JSON Schemas (draft 2020-12) of the two spec kinds, for editors (the VS Code YAML extension
//! reads the `# yaml-language-server: $schema=…` line every shipped spec starts with) and for an
//! independent check of the specs (`validation/check_schema.py`).
//!
//! The structure is derived from the raw spec types with schemars: fields, which are required,
//! unknown fields denied (`additionalProperties: false` where serde denies them), descriptions
//! from their doc comments. [`super::skin`] and [`super::fiber`] then add what their resolvers
//! check that a schema can state, from the resolvers' own constants: ranges, enumerated names,
//! fields that exclude or need each other. What a schema cannot state (that a file exists, that
//! names are unique across a list, that one value is above another, that a resolution divides
//! 180°) is left to `baker validate`. A value the baker accepts is never refused: the schema
//! may be looser than the baker, never stricter.

use schemars::generate::SchemaSettings;
use schemars::JsonSchema;
use serde_json::{json, Map, Value};

use super::check::Bounds;
use super::kind::SpecKind;

/// Where the schema of `kind` is committed, relative to the repository root (and where the
/// shipped specs' `$schema` lines point).
pub fn committed_path(kind: SpecKind) -> &'static str {
    match kind {
        SpecKind::Skin => "specs/schema/skin.schema.json",
        SpecKind::Fiber => "specs/schema/fiber.schema.json",
    }
}

/// The JSON Schema of specs of `kind`.
pub fn json_schema(kind: SpecKind) -> Value {
    match kind {
        SpecKind::Skin => {
            let mut root = derived::<super::skin::raw::RawSpec>(kind);
            super::skin::refine_schema(&mut root);
            root
        }
        SpecKind::Fiber => {
            let mut root = derived::<super::fiber::raw::RawFiberSpec>(kind);
            super::fiber::refine_schema(&mut root);
            root
        }
    }
}

/// [`json_schema`] as the committed file holds it: pretty-printed, with a final newline.
pub fn text(kind: SpecKind) -> String {
    let mut s = serde_json::to_string_pretty(&json_schema(kind)).expect("a JSON value prints");
    s.push('\n');
    s
}

/// The schema schemars derives from `T`, with an id and title.
fn derived<T: JsonSchema>(kind: SpecKind) -> Value {
    let root = SchemaSettings::draft2020_12()
        .into_generator()
        .into_root_schema_for::<T>();
    let mut v = root.to_value();
    let o = v.as_object_mut().expect("a root schema is an object");
    o.insert("title".into(), json!(format!("baker {} spec", kind.name())));
    v
}

/// The definition `name` of `root` (a struct of the raw spec).
pub(super) fn def<'a>(root: &'a mut Value, name: &str) -> &'a mut Value {
    root.pointer_mut(&format!("/$defs/{name}"))
        .unwrap_or_else(|| panic!("the schema has no definition {name}"))
}

/// Property `name` of the object schema `obj`.
pub(super) fn prop<'a>(obj: &'a mut Value, name: &str) -> &'a mut Value {
    obj.pointer_mut(&format!("/properties/{name}"))
        .unwrap_or_else(|| panic!("the schema has no property {name}"))
}

/// Calls `f` on every scalar schema of `s`: through `anyOf`/`oneOf` and into array items (a
/// value or a list of values, a list of numbers), so a bound or set of names reaches each value
/// however the field is written.
pub(super) fn each_scalar(s: &mut Value, f: &mut dyn FnMut(&mut Map<String, Value>)) {
    let Some(o) = s.as_object_mut() else { return };
    for key in ["anyOf", "oneOf"] {
        if let Some(Value::Array(alts)) = o.get_mut(key) {
            for a in alts {
                each_scalar(a, f);
            }
        }
    }
    if let Some(items) = o.get_mut("items") {
        each_scalar(items, f);
    }
    if o.contains_key("type") && !has_type(o, "array") && !has_type(o, "object") {
        f(o);
    }
}

/// Whether schema `o`'s `type` is or includes `t`.
pub(super) fn has_type(o: &Map<String, Value>, t: &str) -> bool {
    match o.get("type") {
        Some(Value::String(s)) => s == t,
        Some(Value::Array(a)) => a.iter().any(|x| x == t),
        _ => false,
    }
}

/// Bounds `b` on every number of `s`; a whole-number bound makes the number an integer (which
/// JSON Schema reads by value: 4000000.0 is one).
pub(super) fn bound(s: &mut Value, b: Bounds) {
    let mut found = false;
    each_scalar(s, &mut |o| {
        if !has_type(o, "number") {
            return;
        }
        found = true;
        let lo = if b.open_lo {
            "exclusiveMinimum"
        } else {
            "minimum"
        };
        o.insert(lo.into(), json!(b.lo));
        o.insert("maximum".into(), json!(b.hi));
        if b.whole {
            retype(o, "number", "integer");
            o.remove("format"); // schemars' "double", of the f64 the count is read as
        }
    });
    assert!(found, "a bound on a schema without numbers: {s}");
}

/// `from` in `o`'s `type` replaced by `to`.
fn retype(o: &mut Map<String, Value>, from: &str, to: &str) {
    match o.get_mut("type") {
        Some(Value::String(s)) if s == from => *s = to.into(),
        Some(Value::Array(a)) => a
            .iter_mut()
            .filter(|x| *x == from)
            .for_each(|x| *x = json!(to)),
        _ => {}
    }
}

/// Every text of `s` one of `names` (null stays allowed where the field may be null: the
/// baker reads it as absent).
pub(super) fn names(s: &mut Value, names: &[&str]) {
    let mut found = false;
    each_scalar(s, &mut |o| {
        if !has_type(o, "string") {
            return;
        }
        found = true;
        let mut allowed: Vec<Value> = names.iter().map(|n| json!(n)).collect();
        if has_type(o, "null") {
            allowed.push(Value::Null);
        }
        o.insert("enum".into(), Value::Array(allowed));
    });
    assert!(found, "names on a schema without text: {s}");
}

/// The names of a resolver's table of options.
pub(super) fn keys<T>(options: &[(&'static str, T)]) -> Vec<&'static str> {
    options.iter().map(|(k, _)| *k).collect()
}

/// Adds `constraint` to the `allOf` of schema `s`.
pub(super) fn all_of(s: &mut Value, constraint: Value) {
    let o = s.as_object_mut().expect("an object schema");
    match o.get_mut("allOf") {
        Some(Value::Array(a)) => a.push(constraint),
        _ => {
            o.insert("allOf".into(), json!([constraint]));
        }
    }
}

/// A text field that takes any scalar: serde-saphyr reads a plain `123` or `true` as the text
/// it is written as, where a YAML 1.2 loader gives a number or a boolean.
pub(super) fn any_scalar_text(s: &mut Value) {
    each_scalar(s, &mut |o| {
        if has_type(o, "string") {
            let mut t = vec![json!("string"), json!("number"), json!("boolean")];
            if has_type(o, "null") {
                t.push(json!("null"));
            }
            o.insert("type".into(), Value::Array(t));
        }
    });
}

/// `fields` all given: present, not null, not an empty list (which the baker reads as absent).
pub(super) fn given(fields: &[&str]) -> Value {
    let present = json!({ "not": { "anyOf": [
        { "type": "null" },
        { "type": "array", "maxItems": 0 }
    ] } });
    let props: Map<String, Value> = fields
        .iter()
        .map(|f| (f.to_string(), present.clone()))
        .collect();
    json!({ "type": "object", "required": fields, "properties": props })
}

/// `a` and `b` exclude each other.
pub(super) fn not_both(a: &str, b: &str) -> Value {
    json!({ "not": given(&[a, b]) })
}

/// What both kinds share: `version` (1; serde-saphyr reads a quoted "1" as the number too)
/// and the bounds of `limits:`.
pub(super) fn shared(root: &mut Value) {
    let v = prop(root, "version");
    let description = v["description"].clone();
    *v = json!({ "description": description, "enum": [1, "1", null] });
    let limits = def(root, "RawLimits");
    for (name, b) in super::limits::LIMIT_BOUNDS {
        bound(prop(limits, name), b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The property `path` (slash-separated, through `properties`) of definition `name`.
    fn at<'a>(root: &'a Value, name: &str, path: &str) -> &'a Value {
        let p = format!("/$defs/{name}/properties/{path}").replace('.', "/properties/");
        root.pointer(&p).unwrap_or_else(|| panic!("no {p}"))
    }

    #[test]
    fn bounds_and_names_come_from_the_resolvers() {
        let skin = json_schema(SpecKind::Skin);
        let age = at(&skin, "RawParams", "age").to_string();
        let (lo, hi) = super::super::skin::AGE_RANGE_YEARS;
        assert!(age.contains(&format!("\"minimum\":{lo:?}")), "{age}");
        assert!(age.contains(&format!("\"maximum\":{hi:?}")), "{age}");
        // A whole-number bound is an integer, from 1.
        let photons = at(&skin, "RawProfiles", "photons");
        assert_eq!(photons["type"], json!(["integer", "null"]), "{photons}");
        assert_eq!(photons["minimum"], json!(1.0));
        // An open lower bound is exclusive.
        let dr = at(&skin, "RawRadial", "dr_min_mm");
        assert_eq!(dr["exclusiveMinimum"], json!(0.0), "{dr}");
        assert!(dr.get("minimum").is_none());
        let gender = at(&skin, "RawParams", "gender").to_string();
        assert!(gender.contains(r#"["female","male"]"#), "{gender}");
        let fiber = json_schema(SpecKind::Fiber);
        let ty = at(&fiber, "RawFiber", "type").to_string();
        for t in crate::fiber::material::TABLE_9 {
            assert!(ty.contains(&format!("\"{}\"", t.name)), "{ty}");
        }
        let limits = at(&fiber, "RawLimits", "memory_gib");
        assert_eq!(limits["exclusiveMinimum"], json!(0.0), "{limits}");
    }

    #[test]
    fn unknown_fields_are_denied_everywhere() {
        for kind in [SpecKind::Skin, SpecKind::Fiber] {
            let root = json_schema(kind);
            assert_eq!(root["additionalProperties"], json!(false));
            for (name, d) in root["$defs"].as_object().unwrap() {
                assert_eq!(d["additionalProperties"], json!(false), "{name}");
            }
        }
    }

    #[test]
    fn a_spanned_value_is_described_as_its_value() {
        let fiber = json_schema(SpecKind::Fiber);
        // `RawFiber.name` is a `Spanned<String>`: text (or a scalar serde-saphyr reads as
        // text), required, with its doc comment.
        let name = at(&fiber, "RawFiber", "name");
        assert_eq!(
            name["type"],
            json!(["string", "number", "boolean"]),
            "{name}"
        );
        assert!(name["description"].as_str().unwrap().contains("Entry name"));
        let req = &fiber["$defs"]["RawFiber"]["required"];
        assert_eq!(req, &json!(["name", "type"]), "{req}");
    }
}
