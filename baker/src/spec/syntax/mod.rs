//! YAML syntax and type errors as a user needs them: moved to the line that is actually wrong
//! (an unclosed bracket, a tab, a mis-indented key, the second of two equal keys), naming the
//! field by its path (`fibers.diameter_um`, `water_fraction.hypodermis`) and saying what it allows.
//!
//! What a field allows is not kept in a second table here, which could drift from the checks.
//! Instead the offending value is replaced by probes (`.nan`, a huge number, a map with an
//! unknown key, a one-element list) and the spec is checked again; the resolver's own range or
//! choice for that line (or serde's list of known keys) is the answer.

mod doc;
mod layout;
mod messages;

pub(in crate::spec) use messages::clean;

use super::error::SpecError;
use doc::{display, Doc};

/// Checks spec text with no diagnosis: serde-saphyr's parse error as is, else the resolver's
/// errors. Used on probed copies of the spec.
pub(super) type Check<'a> = &'a dyn Fn(&str) -> Vec<SpecError>;

/// Where a syntax or type error is reported and what it says.
#[derive(Debug, PartialEq)]
pub(super) struct Diagnosis {
    pub line: u64,
    pub column: u64,
    pub message: String,
}

/// Values tried in place of a badly typed value, in order. `.nan` fails every range and every
/// choice; `__probe__` is text where only text deserializes; the numbers fit integer fields;
/// the map lists its known keys; the list probes the elements of list fields.
const PROBES: [&str; 6] = [
    ".nan",
    "__probe__",
    "-1e300",
    "999999999",
    "{__probe__: 0}",
    "[.nan]",
];

/// Turns serde-saphyr's message at `line`:`column` (1-based) into a [`Diagnosis`].
pub(super) fn diagnose(
    text: &str,
    line: u64,
    column: u64,
    message: &str,
    check: Check,
) -> Diagnosis {
    let doc = Doc::new(text);
    let m = clean(message);
    let at = |line: u64, column: u64, message: String| Diagnosis {
        line,
        column,
        message,
    };
    if let Some(d) = doc.tab(line, &m) {
        return d;
    }
    if let Some(key) = m.strip_prefix("duplicate mapping key: ") {
        let key = key.split(',').next().unwrap_or(key).trim();
        let first = doc
            .first_occurrence(line, column, key)
            .map_or(String::new(), |l| format!(" (first on line {l})"));
        return at(
            line,
            column,
            format!(
                "{}: given twice in the same block{first}; allowed: each field once",
                doc.field(line, column).unwrap_or_else(|| key.to_string())
            ),
        );
    }
    if is_parser_error(&m) {
        if let Some(d) = doc.indentation(line, &m) {
            return d;
        }
        if let Some((ol, oc, open)) = doc.unclosed(line, column) {
            let (kind, close) = if open == '[' {
                ("list", ']')
            } else {
                ("map", '}')
            };
            let field = doc
                .field(ol, oc)
                .map_or(String::new(), |f| format!("{f}: "));
            return at(
                ol,
                oc,
                format!(
                    "{field}the {kind} opened with `{open}` is never closed; expected `{close}` \
                     (the parser stopped at line {line}: {m})"
                ),
            );
        }
    }
    if let Some(d) = doc.over_indented_value(line, column, &m) {
        return d;
    }
    if let Some(name) = missing_field(&m) {
        let parent = doc.path(line, column);
        let parent = &parent[..parent.len().saturating_sub(1)];
        let mut path: Vec<String> = parent.to_vec();
        path.push(name.to_string());
        let allowed = doc
            .insert_probe(line, column, name)
            .and_then(|(probed, l)| allowed_from(&check, &probed, l))
            .map_or(String::new(), |a| format!("; allowed: {a}"));
        return at(
            line,
            column,
            format!("{}: missing{allowed}", display(&path)),
        );
    }
    if let Some(u) = messages::unknown_field(&m, doc.field(line, column), reference(text)) {
        return at(line, column, u);
    }
    if m.contains("unknown field") {
        return at(line, column, m);
    }
    let field = doc.field(line, column);
    let allowed = if is_type_error(&m) {
        doc.value_span(line, column)
            .and_then(|span| {
                PROBES.iter().find_map(|p| {
                    let probed = doc.replace(&span, p);
                    let a = allowed_from(&check, &probed, span.line)?;
                    Some(if p.starts_with('[') {
                        format!("a list, each {a}")
                    } else {
                        a
                    })
                })
            })
            .or_else(|| m.contains("bool").then(|| "true or false".to_string()))
    } else {
        None
    };
    let mut out = match field {
        Some(f) => format!("{f}: {m}"),
        None => m,
    };
    if let Some(a) = allowed {
        out.push_str(&format!("; allowed: {a}"));
    }
    at(line, column, out)
}

/// The YAML parser (not serde) rejected the text.
fn is_parser_error(m: &str) -> bool {
    [
        "while ",
        "did not find expected",
        "unclosed",
        "not allowed in this context",
        "illegal placement",
        "end of stream",
        "unexpected end",
        "could not find expected",
    ]
    .iter()
    .any(|p| m.contains(p))
}

/// A value of the wrong type (serde or a scalar parser).
fn is_type_error(m: &str) -> bool {
    [
        "invalid type",
        "invalid value",
        "invalid floating",
        "invalid u",
        "invalid i",
        "invalid bool",
        "expected mapping",
        "expected sequence",
        "expected string scalar",
        "expected a ",
        "is not a finite number",
    ]
    .iter()
    .any(|p| m.contains(p))
}

/// Where the fields of a spec of the kind `text` is are documented.
fn reference(text: &str) -> &'static str {
    match super::kind::detect("", text) {
        Ok(super::SpecKind::Fiber) => "specs/README.md, \"Fiber specs\",",
        _ => "specs/README.md, \"Skin specs\",",
    }
}

fn missing_field(m: &str) -> Option<&str> {
    let rest = m.strip_prefix("missing field `")?;
    rest.split('`').next()
}

/// What the resolver says `line` of `probed` allows.
fn allowed_from(check: &Check, probed: &str, line: u64) -> Option<String> {
    check(probed).into_iter().find_map(|e| match e {
        SpecError::OutOfRange {
            line: l, allowed, ..
        } if l == line => Some(allowed),
        SpecError::Syntax {
            line: l, message, ..
        } if l == line && is_probe_unknown(&clean(&message)) => {
            let m = clean(&message);
            let keys = m.split_once("expected ")?.1;
            let keys = keys.strip_prefix("one of ").unwrap_or(keys);
            Some(format!("a map with keys {}", keys.replace('`', "")))
        }
        _ => None,
    })
}

fn is_probe_unknown(m: &str) -> bool {
    m.starts_with("unknown field") && m.contains("__probe__")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small edits of valid specs (a tab, an indent, a dedent, a stray bracket or colon, a
    /// lost character, a repeated line) never panic, and every error points into the file.
    #[test]
    fn mutated_specs_are_diagnosed_without_panics() {
        let skin = "version: 1\nwavelengths: {start_nm: 400, stop_nm: 700, step_nm: 50}\n\
                    defaults:\n  gender: female\n  location: forearm\nprofiles:\n  photons: 1000\n  \
                    radial: {dr_min_mm: 0.01, growth: 1.05, r_max_mm: 40}\nentries:\n  - name: a\n    \
                    age: 30\n    skin_type: II\n    xi: 0.5\n    water_fraction:\n      \
                    hypodermis: 0.6\n    freeze: [thickness]\nsweeps:\n  - name: \"t{skin_type}\"\n    \
                    age: 40\n    skin_type: [I, VI]\n    xi: 1\n";
        let fiber = "version: 1\nbake:\n  resolution_deg: 6\n  precision: f16\n  \
                     lambda_nm: {start: 400, end: 700, step: 10}\ndyes:\n  - name: d\n    \
                     class: reactive\n    bands: [{peak_nm: 490, fwhm_nm: 110, \
                     peak_eps_l_per_mg_cm: 0.0158}]\nfibers:\n  - name: a\n    type: polyester\n    \
                     section: {shape: circle}\n    roughness: {ra_nm: 20, l_nm: 400}\n    sweep:\n      \
                     dyes: [d]\n      depth_of_shade_percent: [1, 2]\n";
        let dir = std::path::Path::new(".");
        let load = |kind: usize, t: &str| match kind {
            0 => crate::spec::skin::load_str("s.yaml", t).err(),
            _ => crate::spec::fiber::load_str("f.yaml", t, dir).err(),
        };
        for (kind, text) in [skin, fiber].into_iter().enumerate() {
            assert!(load(kind, text).is_none(), "{text}");
            let lines: Vec<&str> = text.lines().collect();
            for i in 0..lines.len() {
                let l = lines[i];
                let edits = [
                    format!("\t{l}"),
                    format!(" {l}"),
                    l.get(2..).unwrap_or("").to_string(),
                    format!("{l} ["),
                    format!("{l}: x"),
                    format!("{l}}}"),
                    l.get(..l.len().saturating_sub(1)).unwrap_or("").to_string(),
                    format!("{l}\n{l}"),
                ];
                for e in edits {
                    let mut m = lines.clone();
                    m[i] = &e;
                    let t = m.join("\n") + "\n";
                    let n = t.lines().count() as u64;
                    for err in load(kind, &t).map_or(Vec::new(), |e| e.0) {
                        let (line, msg) = match &err {
                            SpecError::Syntax { line, message, .. }
                            | SpecError::Invalid { line, message, .. } => (*line, message.clone()),
                            SpecError::OutOfRange { line, allowed, .. } => (*line, allowed.clone()),
                            SpecError::File(_) => (1, String::from("io")),
                        };
                        assert!(
                            (1..=n + 1).contains(&line) && !msg.is_empty(),
                            "{err}\nin:\n{t}"
                        );
                    }
                }
            }
        }
    }
}
