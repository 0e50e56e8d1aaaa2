//! YAML syntax and type errors as a user needs them: moved to the line that is actually wrong
//! (an unclosed bracket, a tab, a mis-indented key, the second of two equal keys), naming the
//! field by its path (`fibers.diameter_um`, `water_fraction.hypodermis`) and saying what it allows.
//!
//! What a field allows is not kept in a second table here, which could drift from the checks.
//! Instead the offending value is replaced by probes (`.nan`, a huge number, a map with an
//! unknown key, a one-element list) and the spec is checked again; the resolver's own range or
//! choice for that line (or serde's list of known keys) is the answer.

use super::error::SpecError;

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

/// serde-saphyr's message without its "error: line L column C:" prefix, source snippet and
/// advice to programmers (we print file:line:column ourselves).
pub(super) fn clean(message: &str) -> String {
    let mut m = message.lines().next().unwrap_or(message).trim();
    m = m.strip_prefix("error:").unwrap_or(m).trim();
    if let Some(rest) = m.strip_prefix("line ") {
        if let Some((_, after)) = rest.split_once(": ") {
            m = after;
        }
    }
    humane(m.split(", set DuplicateKeyPolicy").next().unwrap_or(m))
}

/// serde-saphyr's messages that name its own options or types, in the words of a spec's
/// author.
pub(super) fn humane(m: &str) -> String {
    if let Some(rest) = m.strip_prefix("non-finite float ") {
        let v = rest.split(" rejected").next().unwrap_or(rest);
        return format!("{v} is not a finite number");
    }
    if m.starts_with("multiple YAML documents detected") {
        return "a spec is one YAML document; a second one starts here (`---`)".into();
    }
    if m.contains("recursive references require") {
        return "an alias refers to the node that defines it (a recursive reference)".into();
    }
    if m.starts_with("recursion limit exceeded") {
        return "nested too deeply (lists and maps inside each other, more than 64 levels)".into();
    }
    if let Some(rest) = m.strip_prefix("budget breached: ") {
        let what = rest.split([' ', '{']).next().unwrap_or(rest);
        let why = match what {
            "Nodes" => {
                "more than 250,000 values (aliases expanded): an alias bomb or a far too large spec"
            }
            "Aliases" | "AliasAnchorRatio" => "too many aliases (`*name`) for a spec",
            "Anchors" => "too many anchors (`&name`) for a spec",
            "Depth" => "nested too deeply (more than 64 levels)",
            "Events" => "more than 1,000,000 YAML events: a far too large spec",
            "Documents" => "too many YAML documents",
            "ScalarBytes" | "TotalScalarBytes" => "more than 64 MiB of text values",
            _ => "over the YAML reader's safety limits",
        };
        return format!("the spec is {why}");
    }
    m.to_string()
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

/// A field path as messages name it: `entries`, `sweeps` and `defaults` are left out
/// (`age`, not `entries.age`), as the resolver does.
fn display(path: &[String]) -> String {
    let skip = path.len() > 1
        && matches!(
            path.first().map(String::as_str),
            Some("entries" | "sweeps" | "defaults")
        );
    path[usize::from(skip)..].join(".")
}

/// A value's place in the text: chars `start..end` of `line`, or whole lines
/// `line..=last` (a block value).
struct Span {
    line: u64,
    start: usize,
    end: usize,
    last: Option<u64>,
}

/// The spec text as lines of chars.
struct Doc {
    lines: Vec<Vec<char>>,
}

fn is_key_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

impl Doc {
    fn new(text: &str) -> Self {
        Self {
            lines: text.lines().map(|l| l.chars().collect()).collect(),
        }
    }

    /// Line `n` (1-based), empty past the end.
    fn get(&self, n: u64) -> &[char] {
        n.checked_sub(1)
            .and_then(|i| self.lines.get(i as usize))
            .map_or(&[], Vec::as_slice)
    }

    fn blank(&self, n: u64) -> bool {
        let l = self.get(n);
        let first = l.iter().find(|c| !c.is_whitespace());
        matches!(first, None | Some('#'))
    }

    /// The key starting at char `i` of `l` (`age` in `age: 30`), if one does.
    fn key_at(l: &[char], i: usize) -> Option<String> {
        let end = i + l.get(i..)?.iter().take_while(|c| is_key_char(**c)).count();
        let ok = end > i && l.get(end) == Some(&':') && l.get(end + 1).is_none_or(|c| *c == ' ');
        ok.then(|| l[i..end].iter().collect())
    }

    /// Where the content of line `n` starts, past indentation and `- ` list markers.
    fn content_start(&self, n: u64) -> usize {
        let l = self.get(n);
        let mut i = l.iter().take_while(|c| **c == ' ').count();
        while l.get(i) == Some(&'-') && l.get(i + 1).is_none_or(|c| *c == ' ') {
            i += 1;
            i += l[i..].iter().take_while(|c| **c == ' ').count();
        }
        i
    }

    /// The key path of the value at `line`:`column`: block parents by indentation, then the
    /// keys of flow maps open on the line before the column.
    fn path(&self, line: u64, column: u64) -> Vec<String> {
        let l = self.get(line);
        let upto = (column.max(1) - 1) as usize;
        let mut stack: Vec<Option<String>> = vec![None];
        let mut i = 0;
        let mut quote: Option<char> = None;
        while i < upto.min(l.len()) {
            let c = l[i];
            if let Some(q) = quote {
                if c == q {
                    quote = None;
                }
                i += 1;
                continue;
            }
            match c {
                '"' | '\'' => quote = Some(c),
                '#' if i == 0 || l[i - 1] == ' ' => break,
                '{' | '[' => stack.push(None),
                '}' | ']' if stack.len() > 1 => {
                    stack.pop();
                }
                ',' => *stack.last_mut().unwrap() = None,
                _ if is_key_char(c) && (i == 0 || !is_key_char(l[i - 1])) => {
                    if let Some(k) = Self::key_at(l, i) {
                        i += k.chars().count();
                        *stack.last_mut().unwrap() = Some(k);
                        continue;
                    }
                }
                _ => {}
            }
            i += 1;
        }
        let word_start = upto == 0 || l.get(upto - 1).is_none_or(|c| !is_key_char(*c));
        if let Some(k) = Self::key_at(l, upto).filter(|_| word_start) {
            *stack.last_mut().unwrap() = Some(k);
        }
        let mut path: Vec<String> = stack.into_iter().flatten().collect();
        // Block parents: each nearest line above that starts with a key, less indented.
        let mut indent = self.content_start(line);
        let mut n = line;
        while indent > 0 && n > 1 {
            n -= 1;
            if self.blank(n) {
                continue;
            }
            let ki = self.content_start(n);
            if ki < indent {
                if let Some(k) = Self::key_at(self.get(n), ki) {
                    path.insert(0, k);
                }
                indent = ki;
            }
        }
        path
    }

    /// The field at `line`:`column` as messages name it.
    fn field(&self, line: u64, column: u64) -> Option<String> {
        let p = self.path(line, column);
        let d = display(&p);
        (!d.is_empty()).then_some(d)
    }

    /// A tab in indentation: reported on the first such line from the error on.
    fn tab(&self, line: u64, m: &str) -> Option<Diagnosis> {
        let indented_with_tab = |n: u64| {
            self.get(n)
                .iter()
                .take_while(|c| c.is_whitespace() || **c == '-')
                .any(|c| *c == '\t')
        };
        let total = self.lines.len() as u64;
        let near = (line.max(1)..=line + 1).find(|&n| n <= total && indented_with_tab(n));
        // Tabs are legal inside flow collections: blame one only for a parser error.
        if !m.contains("tab") && !is_parser_error(m) {
            return None;
        }
        let n = match near {
            Some(n) => n,
            None => (1..=total).find(|&n| indented_with_tab(n))?,
        };
        let l = self.get(n);
        let start = l.iter().take_while(|c| c.is_whitespace()).count();
        let field = Self::key_at(l, start)
            .map(|_| self.field(n, start as u64 + 1))
            .unwrap_or_default()
            .map_or(String::new(), |f| format!("{f}: "));
        Some(Diagnosis {
            line: n,
            column: 1,
            message: format!(
                "{field}indented with a tab; allowed: spaces only (YAML forbids tabs in indentation)"
            ),
        })
    }

    /// The line of the first `key` in the block that holds `line`:`column` (duplicate keys).
    fn first_occurrence(&self, line: u64, column: u64, key: &str) -> Option<u64> {
        let l = self.get(line);
        let col = (column.max(1) - 1) as usize;
        // Same line (flow maps): an earlier `key:`.
        let same = (0..col.min(l.len())).any(|i| {
            (i == 0 || !is_key_char(l[i - 1])) && Self::key_at(l, i).as_deref() == Some(key)
        });
        if same {
            return Some(line);
        }
        let indent = self.content_start(line);
        let mut n = line;
        while n > 1 {
            n -= 1;
            if self.blank(n) {
                continue;
            }
            let ki = self.content_start(n);
            if ki == indent && Self::key_at(self.get(n), ki).as_deref() == Some(key) {
                return Some(n);
            }
            // A list item marker at this indentation starts another block; a smaller one
            // leaves it.
            let dash = self.get(n).iter().take_while(|c| **c == ' ').count();
            if ki < indent || (ki == indent && dash < ki) {
                return None;
            }
        }
        None
    }

    /// The innermost `[` or `{` still open at `line`:`column` (that character included).
    fn unclosed(&self, line: u64, column: u64) -> Option<(u64, u64, char)> {
        let mut stack: Vec<(u64, u64, char)> = Vec::new();
        for n in 1..=line.min(self.lines.len() as u64) {
            let l = self.get(n);
            let end = if n == line {
                (column.max(1) as usize).min(l.len())
            } else {
                l.len()
            };
            let mut quote: Option<char> = None;
            let mut prev: Option<char> = None;
            for (i, &c) in l[..end].iter().enumerate() {
                if let Some(q) = quote {
                    if c == q {
                        quote = None;
                    }
                    continue;
                }
                let token_start = matches!(prev, None | Some(':' | ',' | '[' | '{' | '-'));
                match c {
                    ' ' | '\t' => continue,
                    '#' if i == 0 || l[i - 1] == ' ' => break,
                    '"' | '\'' if token_start => quote = Some(c),
                    '[' | '{' if token_start || !stack.is_empty() => {
                        stack.push((n, i as u64 + 1, c))
                    }
                    ']' | '}' if !stack.is_empty() => {
                        stack.pop();
                    }
                    _ => {}
                }
                prev = Some(c);
            }
        }
        stack.pop()
    }

    /// A key indented deeper or shallower than its siblings, as the parser reports it.
    fn indentation(&self, line: u64, m: &str) -> Option<Diagnosis> {
        let deeper = m.contains("mapping values are not allowed");
        let shallower =
            m.contains("did not find expected '-'") || m.contains("did not find expected key");
        if !deeper && !shallower {
            return None;
        }
        let l = self.get(line);
        let ci = self.content_start(line);
        let key = Self::key_at(l, ci)?;
        let prev = (1..line).rev().find(|&n| !self.blank(n))?;
        let pi = self.content_start(prev);
        let pkey = Self::key_at(self.get(prev), pi)?;
        // Named as a sibling of the line above, where it belongs.
        let mut path = self.path(prev, pi as u64 + 1);
        path.pop();
        path.push(key);
        let field = display(&path);
        let message = if deeper && ci > pi {
            format!(
                "{field}: indented deeper than `{pkey}` on line {prev}, so YAML reads it as part \
                 of {pkey}'s value; allowed: {pi} spaces like its siblings"
            )
        } else if shallower && ci < pi {
            format!(
                "{field}: indented less than `{pkey}` on line {prev} but more than the block \
                 around it; allowed: {pi} spaces like its siblings, or an enclosing block's \
                 indentation"
            )
        } else {
            return None;
        };
        Some(Diagnosis {
            line,
            column: ci as u64 + 1,
            message,
        })
    }

    /// `key: value` followed by a deeper `other: …` line: YAML folds the second line into
    /// the first value (`age: 30` + `  gender: female` reads as age = "30 gender: female").
    fn over_indented_value(&self, line: u64, column: u64, m: &str) -> Option<Diagnosis> {
        if !is_type_error(m) {
            return None;
        }
        let l = self.get(line);
        let col = (column.max(1) - 1) as usize;
        let ki = self.content_start(line);
        let key = Self::key_at(l, col).or_else(|| Self::key_at(l, ki))?;
        let next = (line + 1..=self.lines.len() as u64).find(|&n| !self.blank(n))?;
        let ni = self.content_start(next);
        let nkey = Self::key_at(self.get(next), ni)?;
        let value_on_line = l.len() > ki + key.chars().count() + 1;
        if ni <= ki || !value_on_line {
            return None;
        }
        let field = self.field(line, ki as u64 + 1).unwrap_or(key.clone());
        let parent = field
            .rsplit_once('.')
            .map_or(String::new(), |(p, _)| format!("{p}."));
        Some(Diagnosis {
            line: next,
            column: ni as u64 + 1,
            message: format!(
                "{parent}{nkey}: indented deeper than `{key}` on line {line}, so YAML reads it \
                 as part of {key}'s value ({m}); allowed: {ki} spaces like its siblings"
            ),
        })
    }

    /// The value of the key at, or the value starting at, `line`:`column`.
    fn value_span(&self, line: u64, column: u64) -> Option<Span> {
        let l = self.get(line);
        let mut i = (column.max(1) - 1) as usize;
        if let Some(k) = Self::key_at(l, i) {
            i += k.chars().count() + 1;
            i += l[i.min(l.len())..]
                .iter()
                .take_while(|c| **c == ' ')
                .count();
        }
        let rest_is_empty = l.get(i..).is_none_or(|r| r.is_empty() || r[0] == '#');
        if rest_is_empty || i == self.content_start(line) && i > 0 {
            // A block value: the following (or this) lines indented deeper than the key.
            let (first, indent) = if rest_is_empty {
                let n = (line + 1..=self.lines.len() as u64).find(|&n| !self.blank(n))?;
                let ind = self.get(n).iter().take_while(|c| **c == ' ').count();
                (ind > self.content_start(line)).then_some((n, ind))?
            } else {
                (line, l.iter().take_while(|c| **c == ' ').count())
            };
            let mut last = first;
            for n in first + 1..=self.lines.len() as u64 {
                if self.blank(n) {
                    continue;
                }
                if self.get(n).iter().take_while(|c| **c == ' ').count() < indent {
                    break;
                }
                last = n;
            }
            return Some(Span {
                line: first,
                start: indent,
                end: 0,
                last: Some(last),
            });
        }
        let end = match l[i] {
            open @ ('[' | '{') => {
                let close = if open == '[' { ']' } else { '}' };
                let mut depth = 0;
                let mut end = None;
                for (j, &c) in l.iter().enumerate().skip(i) {
                    if c == open {
                        depth += 1;
                    } else if c == close {
                        depth -= 1;
                        if depth == 0 {
                            end = Some(j + 1);
                            break;
                        }
                    }
                }
                end?
            }
            q @ ('"' | '\'') => i + 1 + l[i + 1..].iter().position(|c| *c == q)? + 1,
            _ => {
                let in_flow = self.unclosed(line, i as u64 + 1).is_some();
                let stop = |j: usize| {
                    let c = l[j];
                    (in_flow && matches!(c, ',' | '}' | ']')) || (c == '#' && l[j - 1] == ' ')
                };
                let e = (i + 1..l.len()).find(|&j| stop(j)).unwrap_or(l.len());
                i + l[i..e]
                    .iter()
                    .collect::<String>()
                    .trim_end()
                    .chars()
                    .count()
            }
        };
        Some(Span {
            line,
            start: i,
            end,
            last: None,
        })
    }

    /// The text with `span` replaced by `probe`.
    fn replace(&self, span: &Span, probe: &str) -> String {
        let mut out = String::new();
        for (k, l) in self.lines.iter().enumerate() {
            let n = k as u64 + 1;
            match span.last {
                Some(_) if n == span.line => {
                    out.extend(std::iter::repeat_n(' ', span.start));
                    out.push_str(probe);
                    out.push('\n');
                }
                Some(last) if n > span.line && n <= last => {}
                None if n == span.line => {
                    out.extend(&l[..span.start]);
                    out.push_str(probe);
                    out.extend(&l[span.end..]);
                    out.push('\n');
                }
                _ => {
                    out.extend(l);
                    out.push('\n');
                }
            }
        }
        out
    }

    /// The text with `name: <probe>` inserted before the key at `line`:`column`, and the line
    /// the probe is on; `.nan` probes the value.
    fn insert_probe(&self, line: u64, column: u64, name: &str) -> Option<(String, u64)> {
        let col = (column.max(1) - 1) as usize;
        let l = self.get(line);
        Self::key_at(l, col)?;
        let in_flow = self
            .unclosed(line, column)
            .is_some_and(|(ol, _, _)| ol == line);
        let mut out = String::new();
        for (k, text) in self.lines.iter().enumerate() {
            if k as u64 + 1 == line {
                out.extend(&text[..col]);
                if in_flow {
                    out.push_str(&format!("{name}: .nan, "));
                } else {
                    out.push_str(&format!("{name}: .nan\n"));
                    out.extend(std::iter::repeat_n(' ', col));
                }
                out.extend(&text[col..]);
            } else {
                out.extend(text);
            }
            out.push('\n');
        }
        Some((out, line))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_follow_indentation_and_flow_maps() {
        let d = Doc::new(
            "fibers:\n  - name: a\n    section: {shape: silk, ratio: 2}\n    bake:\n      seed: x\n",
        );
        assert_eq!(d.path(3, 35), ["fibers", "section", "ratio"]);
        assert_eq!(d.path(3, 5), ["fibers", "section"]);
        assert_eq!(d.path(5, 13), ["fibers", "bake", "seed"]);
        assert_eq!(display(&["entries".into(), "age".into()]), "age");
    }

    #[test]
    fn unclosed_brackets_are_found_where_they_open() {
        let d = Doc::new("a: [1, 2\nb: {c: [x]\nd: 1\n");
        assert_eq!(d.unclosed(3, 2), Some((2, 4, '{')));
        let d = Doc::new("name: type{skin_type}\nx: 1\n");
        assert_eq!(d.unclosed(2, 1), None);
    }

    #[test]
    fn values_are_spanned_inline_and_in_blocks() {
        let d = Doc::new("a:\n  b: {c: 12, d: x}\n  e:\n    - 1\n    - 2\n  f: 3\n");
        let s = d.value_span(2, 10).unwrap();
        assert_eq!((s.line, s.start, s.end), (2, 9, 11));
        let s = d.value_span(3, 3).unwrap();
        assert_eq!((s.line, s.last), (4, Some(5)));
        assert_eq!(
            d.replace(&s, ".nan"),
            "a:\n  b: {c: 12, d: x}\n  e:\n    .nan\n  f: 3\n"
        );
    }

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
            0 => super::super::resolve::load_str("s.yaml", t).err(),
            _ => super::super::fiber::load_str("f.yaml", t, dir).err(),
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
