//! Which kind of spec a file is, decided from its parsed top-level keys (not from how the text
//! looks: a byte-order mark, flow or JSON style and comments are all fine).

use super::error::SpecError;

/// Skin (ch. 3: entries → optics and diffusion profiles) or fiber (ch. 5: fibers → BCSDFs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpecKind {
    Skin,
    Fiber,
}

impl SpecKind {
    pub fn name(self) -> &'static str {
        match self {
            SpecKind::Skin => "skin",
            SpecKind::Fiber => "fiber",
        }
    }
}

/// Top-level keys only a skin spec has.
pub const SKIN_KEYS: [&str; 5] = ["wavelengths", "defaults", "entries", "sweeps", "profiles"];
/// Top-level keys only a fiber spec has.
pub const FIBER_KEYS: [&str; 3] = ["dyes", "fibers", "bake"];
/// Keys both kinds take.
pub const SHARED_KEYS: [&str; 2] = ["version", "limits"];

/// The kind of spec `text` is. A YAML error is left to the kind's own parser (which reports it
/// with the field and what it allows); only a text with keys of both kinds, or of neither, is
/// an error here.
pub fn detect(file: &str, text: &str) -> Result<SpecKind, SpecError> {
    match super::yaml::top_level_keys(text) {
        Ok(keys) => classify(file, &keys),
        // Over the parser's budgets (an alias bomb, deep nesting): that is the error, whatever
        // the kind.
        Err(e) if is_budget(&e.to_string()) => {
            let (line, column) = e
                .location()
                .map(|l| (l.line(), l.column()))
                .unwrap_or((1, 1));
            Err(SpecError::Syntax {
                file: file.to_string(),
                line,
                column,
                message: super::syntax::clean(&e.to_string()),
            })
        }
        // Not a mapping, or broken YAML: there are no keys to go by.
        Err(_) => Ok(guess_unparsed(text)),
    }
}

/// The kind whose parser reports a text that is not a YAML mapping: the skin parser gives the
/// precise message, unless the text names a fiber key at the start of a line (so a fiber spec
/// with a typo still gets the fiber parser's message). The one place the kind is read from the
/// text rather than from parsed keys: there are none.
fn guess_unparsed(text: &str) -> SpecKind {
    let fiberish = text.lines().any(|l| {
        let l = l.trim_start_matches(['{', ' ', '"', '\'', '\u{feff}']);
        FIBER_KEYS.iter().any(|k| {
            l.strip_prefix(k)
                .is_some_and(|r| r.trim_start_matches(['"', '\'']).starts_with(':'))
        })
    });
    if fiberish {
        SpecKind::Fiber
    } else {
        SpecKind::Skin
    }
}

/// What both kinds take, for messages about a spec that is neither or both.
fn both_kinds() -> String {
    format!(
        "a skin spec has {} (with {}); a fiber spec has {} (with {})",
        SKIN_KEYS.join(", "),
        SHARED_KEYS.join(", "),
        FIBER_KEYS.join(", "),
        SHARED_KEYS.join(", ")
    )
}

/// The kind of a spec with top-level `keys`.
fn classify(file: &str, keys: &[String]) -> Result<SpecKind, SpecError> {
    let of = |set: &[&str]| -> Vec<&str> {
        keys.iter()
            .map(String::as_str)
            .filter(|k| set.contains(k))
            .collect()
    };
    let (skin, fiber) = (of(&SKIN_KEYS), of(&FIBER_KEYS));
    let invalid = |message: String| SpecError::Invalid {
        file: file.to_string(),
        line: 1,
        column: 1,
        field: "spec".into(),
        message,
    };
    match (skin.is_empty(), fiber.is_empty()) {
        (false, true) => Ok(SpecKind::Skin),
        (true, false) => Ok(SpecKind::Fiber),
        (false, false) => Err(invalid(format!(
            "mixes skin keys ({}) and fiber keys ({}); a spec is one kind: {}",
            skin.join(", "),
            fiber.join(", "),
            both_kinds()
        ))),
        (true, true) => {
            let unknown: Vec<&str> = keys
                .iter()
                .map(String::as_str)
                .filter(|k| !SHARED_KEYS.contains(k))
                .collect();
            if let Some(kind) = nearest_kind(&unknown) {
                return Ok(kind);
            }
            Err(invalid(if keys.is_empty() {
                format!("is empty: {}", both_kinds())
            } else if unknown.is_empty() {
                format!("has no entries or fibers: {}", both_kinds())
            } else {
                format!(
                    "is neither a skin nor a fiber spec (top-level keys: {}): {}",
                    unknown.join(", "),
                    both_kinds()
                )
            }))
        }
    }
}

/// A misspelt key (`entry:`, `fiber:`): the kind it is closest to, whose parser then points at
/// the line and lists that kind's keys; `None` when no key is close to either kind's.
fn nearest_kind(unknown: &[&str]) -> Option<SpecKind> {
    let near = |set: &[&str]| {
        unknown
            .iter()
            .flat_map(|u| set.iter().map(move |k| strsim::jaro_winkler(u, k)))
            .fold(0.0f64, f64::max)
    };
    let (skin_s, fiber_s) = (near(&SKIN_KEYS), near(&FIBER_KEYS));
    (skin_s.max(fiber_s) >= 0.85).then_some(if fiber_s > skin_s {
        SpecKind::Fiber
    } else {
        SpecKind::Skin
    })
}

/// A serde-saphyr error that is a breached safety budget, not a syntax or type error.
fn is_budget(m: &str) -> bool {
    m.contains("budget breached") || m.contains("recursion limit exceeded")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_by_keys_in_any_style() {
        let k = |t: &str| detect("s.yaml", t);
        assert_eq!(k("fibers:\n  - name: a\n"), Ok(SpecKind::Fiber));
        assert_eq!(k("\u{feff}# c\nfibers: []\n"), Ok(SpecKind::Fiber));
        assert_eq!(k("{\"fibers\": [{\"name\": \"a\"}]}"), Ok(SpecKind::Fiber));
        assert_eq!(k("{version: 1, bake: {}, fibers: []}"), Ok(SpecKind::Fiber));
        assert_eq!(k("  # indented comment\nentries: []\n"), Ok(SpecKind::Skin));
        assert_eq!(k("{entries: [{name: a}]}"), Ok(SpecKind::Skin));
        // Broken YAML goes to the parser of the kind it looks like.
        assert_eq!(k("fibers:\n  - [\n"), Ok(SpecKind::Fiber));
        assert_eq!(k("entries: [\n"), Ok(SpecKind::Skin));
        // A misspelt key goes to the parser of the kind it is closest to.
        assert_eq!(k("entry:\n  - name: a\n"), Ok(SpecKind::Skin));
        assert_eq!(k("fiber:\n  - name: a\n"), Ok(SpecKind::Fiber));
        for bad in [
            "entries: []\nfibers: []\n",
            "colour: red\n",
            "version: 1\n",
            "",
        ] {
            let e = k(bad).unwrap_err().to_string();
            assert!(
                e.contains("a skin spec has") && e.contains("a fiber spec has"),
                "{e}"
            );
        }
    }
}
