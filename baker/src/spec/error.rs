//! Spec errors: each names the file, line, column, field, offending value and what is allowed.

use std::fmt;

use thiserror::Error;

#[derive(Debug, Clone, Error, PartialEq)]
pub enum SpecError {
    /// The spec file itself cannot be read (missing, a directory, too large, not text).
    #[error("{0}")]
    File(crate::files::FileError),
    /// A YAML syntax error, an unknown field or a wrong type, as the parser reports it.
    #[error("{file}:{line}:{column}: {message}")]
    Syntax {
        file: String,
        line: u64,
        column: u64,
        message: String,
    },
    #[error("{file}:{line}:{column}: {field} = {value} is out of range; allowed: {allowed}")]
    OutOfRange {
        file: String,
        line: u64,
        column: u64,
        field: String,
        value: String,
        allowed: String,
    },
    #[error("{file}:{line}:{column}: {field}: {message}")]
    Invalid {
        file: String,
        line: u64,
        column: u64,
        field: String,
        message: String,
    },
}

/// All errors found in one spec, reported together.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecErrors(pub Vec<SpecError>);

impl fmt::Display for SpecErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.0.len();
        writeln!(f, "{n} error{} in spec:", if n == 1 { "" } else { "s" })?;
        for e in &self.0 {
            writeln!(f, "  {e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for SpecErrors {}
