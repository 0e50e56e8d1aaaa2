//! Layout mistakes the YAML parser reports in its own terms, reported where they are: a tab in
//! indentation, a key indented deeper or shallower than its siblings, a key folded into the
//! value of the line above.

use super::doc::{display, Doc};
use super::{is_parser_error, is_type_error, Diagnosis};

impl Doc {
    /// A tab in indentation: reported on the first such line from the error on.
    pub(super) fn tab(&self, line: u64, m: &str) -> Option<Diagnosis> {
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

    /// A key indented deeper or shallower than its siblings, as the parser reports it.
    pub(super) fn indentation(&self, line: u64, m: &str) -> Option<Diagnosis> {
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
    pub(super) fn over_indented_value(&self, line: u64, column: u64, m: &str) -> Option<Diagnosis> {
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
}
