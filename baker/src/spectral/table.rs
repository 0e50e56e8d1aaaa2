//! A sampled spectrum read from one of the embedded CSV tables.

use thiserror::Error;

/// Why a spectral CSV table cannot be read.
#[derive(Debug, Error)]
pub enum SpectralTableError {
    #[error("{file}:{line}: {message}")]
    Parse {
        file: String,
        line: usize,
        message: String,
    },
    #[error("{file}: no data rows")]
    Empty { file: String },
}

/// Samples (λ in nm, value) with linear interpolation between them.
#[derive(Debug, Clone)]
pub struct SpectralTable {
    /// File the table came from, for messages.
    pub name: String,
    lambda_nm: Vec<f64>,
    value: Vec<f64>,
}

impl SpectralTable {
    /// Parses `text`: lines starting with `#` are the header (source, units); every other
    /// non-empty line is `lambda_nm,v1,v2,…` (the dialect of [`crate::files::csv_rows`]);
    /// `column` picks the value column (1 = first after λ).
    pub fn parse_csv(name: &str, text: &str, column: usize) -> Result<Self, SpectralTableError> {
        let mut lambda_nm = Vec::new();
        let mut value = Vec::new();
        for row in crate::files::csv_rows::rows(text) {
            let row = row.map_err(|e| SpectralTableError::Parse {
                file: name.to_string(),
                line: e.line,
                message: e.message,
            })?;
            let err = |message: String| SpectralTableError::Parse {
                file: name.to_string(),
                line: row.line,
                message,
            };
            if row.len() <= column {
                return Err(err(format!(
                    "expected at least {} columns (lambda_nm and value column {}), got {}",
                    column + 1,
                    column + 1,
                    row.len()
                )));
            }
            let l = row.number(0, "lambda_nm").map_err(err)?;
            let v = row.number(column, "value").map_err(err)?;
            if let Some(&prev) = lambda_nm.last() {
                if l <= prev {
                    return Err(err(format!(
                        "column 1 (lambda_nm): wavelengths must increase ({l} after {prev})"
                    )));
                }
            }
            if !v.is_finite() {
                return Err(err(format!(
                    "column {} (value): non-finite value {v}",
                    column + 1
                )));
            }
            lambda_nm.push(l);
            value.push(v);
        }
        if lambda_nm.is_empty() {
            return Err(SpectralTableError::Empty {
                file: name.to_string(),
            });
        }
        Ok(Self {
            name: name.to_string(),
            lambda_nm,
            value,
        })
    }

    /// Covered range, nm.
    pub fn range_nm(&self) -> (f64, f64) {
        (self.lambda_nm[0], *self.lambda_nm.last().unwrap())
    }

    /// Linear interpolation at `lambda_nm`. Outside the table, the end value is held; callers
    /// keep spec wavelengths inside [`Self::range_nm`] (the spec validator enforces it).
    pub fn at(&self, lambda_nm: f64) -> f64 {
        let x = &self.lambda_nm;
        if lambda_nm <= x[0] {
            return self.value[0];
        }
        if lambda_nm >= x[x.len() - 1] {
            return self.value[x.len() - 1];
        }
        let j = x.partition_point(|&v| v <= lambda_nm); // x[j-1] <= λ < x[j]
        let (x0, x1) = (x[j - 1], x[j]);
        let t = (lambda_nm - x0) / (x1 - x0);
        self.value[j - 1] * (1.0 - t) + self.value[j] * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_linearly_and_holds_ends() {
        let t = SpectralTable::parse_csv("t", "# header\n400,1,10\n410,3,30\n", 2).unwrap();
        assert_eq!(t.at(405.0), 20.0);
        assert_eq!(t.at(390.0), 10.0);
        assert_eq!(t.at(420.0), 30.0);
    }

    #[test]
    fn rejects_unsorted_rows_with_line_number() {
        let e = SpectralTable::parse_csv("t", "400,1\n390,2\n", 1).unwrap_err();
        assert!(e.to_string().contains("t:2"), "{e}");
    }

    #[test]
    fn malformed_rows_name_line_and_column() {
        let text = "# header\n400,1,10\n410,3\n";
        let e = SpectralTable::parse_csv("t", text, 2).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t:3: expected at least 3 columns (lambda_nm and value column 3), got 2"
        );
        let e = SpectralTable::parse_csv("t", "# h\n\n400,1\n410,x\n", 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t:4: column 2 (value): expected a number, got \"x\""
        );
        let e = SpectralTable::parse_csv("t", "4OO,1\n", 1).unwrap_err();
        assert!(
            e.to_string().starts_with("t:1: column 1 (lambda_nm)"),
            "{e}"
        );
    }
}
