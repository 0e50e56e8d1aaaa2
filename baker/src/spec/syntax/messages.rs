//! serde-saphyr's messages in the words of a spec's author: its "error: line L column C:"
//! prefix, source snippet and advice to programmers dropped, and the messages that name its
//! own options or types replaced.

/// serde-saphyr's message without its "error: line L column C:" prefix, source snippet and
/// advice to programmers (we print file:line:column ourselves).
pub(in crate::spec) fn clean(message: &str) -> String {
    let mut m = message.lines().next().unwrap_or(message).trim();
    m = m.strip_prefix("error:").unwrap_or(m).trim();
    if let Some(rest) = m.strip_prefix("line ") {
        if let Some((_, after)) = rest.split_once(": ") {
            m = after;
        }
    }
    humane(m.split(", set DuplicateKeyPolicy").next().unwrap_or(m))
}

/// How a serde-saphyr message is recognised.
enum Pattern {
    Starts(&'static str),
    Contains(&'static str),
}

impl Pattern {
    fn matches(&self, m: &str) -> bool {
        match self {
            Pattern::Starts(p) => m.starts_with(p),
            Pattern::Contains(p) => m.contains(p),
        }
    }
}

/// Messages replaced whole, tried in order: serde-saphyr's, and what a spec's author reads.
const REPLACED: [(Pattern, &str); 3] = [
    (
        Pattern::Starts("multiple YAML documents detected"),
        "a spec is one YAML document; a second one starts here (`---`)",
    ),
    (
        Pattern::Contains("recursive references require"),
        "an alias refers to the node that defines it (a recursive reference)",
    ),
    (
        Pattern::Starts("recursion limit exceeded"),
        "nested too deeply (lists and maps inside each other, more than 64 levels)",
    ),
];

/// serde-saphyr's safety budgets (`budget breached: <name> …`), as what the spec is.
const BUDGETS: [(&[&str], &str); 7] = [
    (
        &["Nodes"],
        "more than 250,000 values (aliases expanded): an alias bomb or a far too large spec",
    ),
    (
        &["Aliases", "AliasAnchorRatio"],
        "too many aliases (`*name`) for a spec",
    ),
    (&["Anchors"], "too many anchors (`&name`) for a spec"),
    (&["Depth"], "nested too deeply (more than 64 levels)"),
    (
        &["Events"],
        "more than 1,000,000 YAML events: a far too large spec",
    ),
    (&["Documents"], "too many YAML documents"),
    (
        &["ScalarBytes", "TotalScalarBytes"],
        "more than 64 MiB of text values",
    ),
];

/// A budget [`BUDGETS`] does not name.
const OTHER_BUDGET: &str = "over the YAML reader's safety limits";

/// serde-saphyr's messages that name its own options or types, in the words of a spec's
/// author.
fn humane(m: &str) -> String {
    if let Some(rest) = m.strip_prefix("non-finite float ") {
        let v = rest.split(" rejected").next().unwrap_or(rest);
        return format!("{v} is not a finite number");
    }
    if let Some((_, words)) = REPLACED.iter().find(|(p, _)| p.matches(m)) {
        return (*words).to_string();
    }
    if let Some(rest) = m.strip_prefix("budget breached: ") {
        let what = rest.split([' ', '{']).next().unwrap_or(rest);
        let why = BUDGETS
            .iter()
            .find(|(names, _)| names.contains(&what))
            .map_or(OTHER_BUDGET, |(_, why)| why);
        return format!("the spec is {why}");
    }
    m.to_string()
}

/// serde's "unknown field `x`, expected one of a, b, …" as the field (`field`, else the
/// name in the message), the nearest known fields ([`crate::suggest`]) and, for a long list,
/// its length and `reference` (where the fields are documented) instead of the list.
pub(super) fn unknown_field(m: &str, field: Option<String>, reference: &str) -> Option<String> {
    let rest = m.strip_prefix("unknown field `")?;
    let (name, rest) = rest.split_once('`')?;
    let known: Vec<&str> = rest
        .split_once("expected ")
        .map_or("", |(_, k)| k)
        .trim_start_matches("one of ")
        .split(", ")
        .flat_map(|k| k.split(" or "))
        .map(|k| k.trim().trim_matches('`'))
        .filter(|k| !k.is_empty())
        .collect();
    let field = field.unwrap_or_else(|| name.to_string());
    if known.is_empty() {
        return Some(format!("{field}: unknown field; this map takes no fields"));
    }
    let listed_by = format!("{reference} lists them");
    Some(format!(
        "{field}: unknown field; {}",
        crate::suggest::advice(name, &known, "fields here", &listed_by)
    ))
}
