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
    /// non-empty line is `lambda_nm,v1,v2,…`; `column` picks the value column (1 = first after λ).
    pub fn parse_csv(name: &str, text: &str, column: usize) -> Result<Self, SpectralTableError> {
        let mut lambda_nm = Vec::new();
        let mut value = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let err = |message: String| SpectralTableError::Parse {
                file: name.to_string(),
                line: i + 1,
                message,
            };
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            if fields.len() <= column {
                return Err(err(format!("expected at least {} columns", column + 1)));
            }
            let l: f64 = fields[0]
                .parse()
                .map_err(|_| err(format!("bad wavelength {:?}", fields[0])))?;
            let v: f64 = fields[column]
                .parse()
                .map_err(|_| err(format!("bad value {:?}", fields[column])))?;
            if let Some(&prev) = lambda_nm.last() {
                if l <= prev {
                    return Err(err(format!("wavelengths must increase ({l} after {prev})")));
                }
            }
            if !v.is_finite() {
                return Err(err(format!("non-finite value {v}")));
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
}
