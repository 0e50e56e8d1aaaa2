//! The data rows of the comma-separated texts the baker reads (polygon outlines, dye spectra,
//! the shipped spectral tables and dye presets), split by the `csv` crate.
//!
//! The dialect, the same for every reader: `,` between fields, `"` quotes, lines that start
//! with `#` (also after blanks) are comments, fields are trimmed of surrounding whitespace,
//! rows may have any number of fields (each reader checks its own), `\n` or `\r\n` ends a
//! row. Blank lines are not rows; a row says whether one came before it (the polygon outline
//! starts a hole there).

use csv::StringRecord;

/// One data row of [`rows`].
#[derive(Debug, Clone)]
pub struct Row {
    /// Line of the row in the text, from 1.
    pub line: usize,
    /// The fields, trimmed.
    pub fields: StringRecord,
    /// Whether a blank (or whitespace-only) line comes between the previous row (or the start
    /// of the text) and this one.
    pub after_blank: bool,
}

impl Row {
    /// Field `i` (from 0), or `""` past the end.
    pub fn get(&self, i: usize) -> &str {
        self.fields.get(i).unwrap_or("")
    }

    /// Number of fields.
    pub fn len(&self) -> usize {
        self.fields.len()
    }

    /// Whether the row has no fields (never, for a row of [`rows`]).
    pub fn is_empty(&self) -> bool {
        self.fields.is_empty()
    }

    /// Field `i` (from 0) as a number; the error names the column (from 1) and `what` it
    /// holds, and shows what is there.
    pub fn number(&self, i: usize, what: &str) -> Result<f64, String> {
        let f = self.get(i);
        f.parse::<f64>().map_err(|_| {
            format!(
                "column {} ({what}): expected a number, got {}",
                i + 1,
                shown(f)
            )
        })
    }

    /// The row as written (fields joined by `,`), for messages; long rows are cut.
    pub fn text(&self) -> String {
        shown(&self.fields.iter().collect::<Vec<_>>().join(","))
    }
}

/// A field or row for a message: quoted, cut after 60 characters.
pub fn shown(s: &str) -> String {
    const MAX: usize = 60;
    match s.char_indices().nth(MAX) {
        Some((at, _)) => format!("{:?}…", &s[..at]),
        None => format!("{s:?}"),
    }
}

/// Why the text cannot be split into rows (an unreadable quoted field).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowError {
    /// Line, from 1 (0 when unknown).
    pub line: usize,
    pub message: String,
}

/// The data rows of `text`, in order (the dialect in the module's documentation). Rows are
/// produced one at a time, so a reader can stop at its row limit before it stores more.
pub fn rows(text: &str) -> Rows<'_> {
    let reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    Rows {
        text,
        reader,
        pos: 0,
        line: 1,
        blank: false,
        done: false,
    }
}

/// Iterator of [`rows`].
///
/// The reader's own record positions are where its scan began (before skipped comments and
/// empty lines), so the line of a row, and the blank lines before it, come from the text
/// consumed since the previous row.
pub struct Rows<'a> {
    text: &'a str,
    reader: csv::Reader<&'a [u8]>,
    /// Byte of `text` where the reader stopped after the previous row.
    pos: usize,
    /// Line (from 1) of byte `pos`.
    line: usize,
    /// A blank line since the last row returned.
    blank: bool,
    done: bool,
}

impl Rows<'_> {
    /// The line of the row read from `text[self.pos..end]`; notes blank lines before it, and
    /// moves `pos` and `line` to `end`.
    fn consume(&mut self, end: usize) -> usize {
        let end = if self.text.is_char_boundary(end) {
            end
        } else {
            self.pos
        };
        let span = &self.text[self.pos..end];
        // At the start of a line, the first piece is a whole line; otherwise it is the end of
        // the previous row's line (the `\n` of a `\r\n`).
        let at_line_start = self.pos == 0 || self.text[..self.pos].ends_with('\n');
        let mut line = self.line;
        for (k, piece) in span.split('\n').enumerate() {
            let piece = piece.strip_suffix('\r').unwrap_or(piece);
            if piece.is_empty() {
                self.blank |= k > 0 || at_line_start;
            } else if !piece.starts_with('#') {
                line = self.line + k;
                break;
            }
        }
        self.line += span.bytes().filter(|&b| b == b'\n').count();
        self.pos = end;
        line
    }
}

impl Iterator for Rows<'_> {
    type Item = Result<Row, RowError>;

    fn next(&mut self) -> Option<Self::Item> {
        while !self.done {
            let mut fields = StringRecord::new();
            match self.reader.read_record(&mut fields) {
                Ok(true) => {}
                Ok(false) => {
                    self.done = true;
                    break;
                }
                Err(e) => {
                    self.done = true;
                    let end = e
                        .position()
                        .map_or(self.pos, |p| p.byte() as usize)
                        .clamp(self.pos, self.text.len());
                    return Some(Err(RowError {
                        line: self.consume(end),
                        message: e.to_string(),
                    }));
                }
            }
            let end = (self.reader.position().byte() as usize).min(self.text.len());
            let line = self.consume(end);
            let first = fields.get(0).unwrap_or("");
            if fields.len() == 1 && first.is_empty() {
                // Whitespace only.
                self.blank = true;
                continue;
            }
            if first.starts_with('#') {
                // A comment after blanks.
                continue;
            }
            return Some(Ok(Row {
                line,
                fields,
                after_blank: std::mem::take(&mut self.blank),
            }));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines_and_fields(text: &str) -> Vec<(usize, bool, Vec<String>)> {
        rows(text)
            .map(|r| {
                let r = r.unwrap();
                let f = r.fields.iter().map(str::to_string).collect();
                (r.line, r.after_blank, f)
            })
            .collect()
    }

    #[test]
    fn comments_blanks_and_trimming() {
        let text = "# head\nx,y\n 1 , 2 \n\n  # indented\n3,4\r\n   \r\nhole\n5,\"6\"\n# tail";
        let v = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        assert_eq!(
            lines_and_fields(text),
            vec![
                (2, false, v(&["x", "y"])),
                (3, false, v(&["1", "2"])),
                (6, true, v(&["3", "4"])),
                (8, true, v(&["hole"])),
                (9, false, v(&["5", "6"])),
            ]
        );
    }

    #[test]
    fn a_quoted_line_break_is_not_a_blank_line() {
        let got = lines_and_fields("a,\"b\n\nc\"\nd\n");
        assert_eq!(got.len(), 2);
        assert_eq!((got[0].0, got[0].1), (1, false));
        assert_eq!(got[0].2[1], "b\n\nc");
        assert_eq!((got[1].0, got[1].1), (4, false));
    }

    #[test]
    fn numbers_name_the_column() {
        let r = rows("1,x\n").next().unwrap().unwrap();
        assert_eq!(r.number(0, "x_um"), Ok(1.0));
        let e = r.number(1, "y_um").unwrap_err();
        assert_eq!(e, "column 2 (y_um): expected a number, got \"x\"");
        assert!(shown(&"é".repeat(100)).ends_with("\"…"));
    }
}
