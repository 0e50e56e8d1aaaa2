//! The spec text as its author wrote it, for diagnoses: the key path at a position, the span
//! of a value, the bracket left open, and copies of the text with a value replaced by a probe.

/// A field path as messages name it: `entries`, `sweeps` and `defaults` are left out
/// (`age`, not `entries.age`), as the resolver does.
pub(super) fn display(path: &[String]) -> String {
    let skip = path.len() > 1
        && matches!(
            path.first().map(String::as_str),
            Some("entries" | "sweeps" | "defaults")
        );
    path[usize::from(skip)..].join(".")
}

/// A value's place in the text: chars `start..end` of `line`, or whole lines
/// `line..=last` (a block value).
pub(super) struct Span {
    pub(super) line: u64,
    pub(super) start: usize,
    pub(super) end: usize,
    pub(super) last: Option<u64>,
}

/// The spec text as lines of chars.
pub(super) struct Doc {
    pub(super) lines: Vec<Vec<char>>,
}

pub(super) fn is_key_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

impl Doc {
    pub(super) fn new(text: &str) -> Self {
        Self {
            lines: text.lines().map(|l| l.chars().collect()).collect(),
        }
    }

    /// Line `n` (1-based), empty past the end.
    pub(super) fn get(&self, n: u64) -> &[char] {
        n.checked_sub(1)
            .and_then(|i| self.lines.get(i as usize))
            .map_or(&[], Vec::as_slice)
    }

    pub(super) fn blank(&self, n: u64) -> bool {
        let l = self.get(n);
        let first = l.iter().find(|c| !c.is_whitespace());
        matches!(first, None | Some('#'))
    }

    /// The key starting at char `i` of `l` (`age` in `age: 30`), if one does.
    pub(super) fn key_at(l: &[char], i: usize) -> Option<String> {
        let end = i + l.get(i..)?.iter().take_while(|c| is_key_char(**c)).count();
        let ok = end > i && l.get(end) == Some(&':') && l.get(end + 1).is_none_or(|c| *c == ' ');
        ok.then(|| l[i..end].iter().collect())
    }

    /// Where the content of line `n` starts, past indentation and `- ` list markers.
    pub(super) fn content_start(&self, n: u64) -> usize {
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
    pub(super) fn path(&self, line: u64, column: u64) -> Vec<String> {
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
    pub(super) fn field(&self, line: u64, column: u64) -> Option<String> {
        let p = self.path(line, column);
        let d = display(&p);
        (!d.is_empty()).then_some(d)
    }

    /// The line of the first `key` in the block that holds `line`:`column` (duplicate keys).
    pub(super) fn first_occurrence(&self, line: u64, column: u64, key: &str) -> Option<u64> {
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
    pub(super) fn unclosed(&self, line: u64, column: u64) -> Option<(u64, u64, char)> {
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

    /// The value of the key at, or the value starting at, `line`:`column`.
    pub(super) fn value_span(&self, line: u64, column: u64) -> Option<Span> {
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
    pub(super) fn replace(&self, span: &Span, probe: &str) -> String {
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
    pub(super) fn insert_probe(&self, line: u64, column: u64, name: &str) -> Option<(String, u64)> {
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
}
