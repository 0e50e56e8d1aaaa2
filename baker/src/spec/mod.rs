//! The YAML spec language, in two stages (ripgrep's low/high args): [`raw`] mirrors the file
//! with a location on every value; [`resolve`] (skin) and [`fiber`] validate ranges, apply
//! defaults and sweeps, check [`limits`] and [`names`], and produce model inputs. Nothing
//! downstream sees raw YAML, and nothing downstream rejects a spec the resolver accepted:
//! `baker validate` and `baker bake` share this code path.
//!
//! [`load_any`] reads a file once, decides its [`kind`] from its top-level keys and resolves it.

pub mod budget;
pub mod error;
pub mod fiber;
pub mod kind;
pub mod limits;
pub mod names;
pub mod raw;
pub mod resolve;
mod syntax;

use std::path::Path;

pub use error::{SpecError, SpecErrors};
pub use kind::SpecKind;
pub use limits::Limits;
pub use resolve::{load, load_str, ProfileSettings, ResolvedEntry, SkinSpec};

/// A resolved spec of either kind.
#[derive(Debug, Clone)]
pub enum Spec {
    Skin(SkinSpec),
    Fiber(fiber::FiberSpec),
}

impl Spec {
    /// The spec file as messages name it.
    pub fn file(&self) -> &str {
        match self {
            Spec::Skin(s) => &s.file,
            Spec::Fiber(s) => &s.file,
        }
    }

    pub fn kind(&self) -> SpecKind {
        match self {
            Spec::Skin(_) => SpecKind::Skin,
            Spec::Fiber(_) => SpecKind::Fiber,
        }
    }

    /// Every entry's name with the line it is defined on, in spec order.
    pub fn entries(&self) -> Vec<(&str, u64)> {
        match self {
            Spec::Skin(s) => s
                .entries
                .iter()
                .map(|e| (e.name.as_str(), e.line))
                .collect(),
            Spec::Fiber(s) => s.fibers.iter().map(|e| (e.name.as_str(), e.line)).collect(),
        }
    }

    pub fn limits(&self) -> &Limits {
        match self {
            Spec::Skin(s) => &s.limits,
            Spec::Fiber(s) => &s.limits,
        }
    }
}

/// Reads the spec text at `path` (bounded, BOM stripped; a directory or device is named as
/// such).
pub fn read(path: &Path) -> Result<String, SpecErrors> {
    crate::files::read_text(path, crate::files::MAX_SPEC_BYTES, "a spec file")
        .map_err(|e| SpecErrors(vec![SpecError::File(e)]))
}

/// Reads, classifies and resolves the spec at `path`.
pub fn load_any(path: &Path) -> Result<Spec, SpecErrors> {
    let file = path.display().to_string();
    let text = read(path)?;
    load_any_str(&file, &text, path.parent().unwrap_or(Path::new(".")))
}

/// Reads and resolves `path`, which must be a spec of kind `want` (the command's kind).
pub fn load_as(path: &Path, want: SpecKind) -> Result<Spec, SpecErrors> {
    let spec = load_any(path)?;
    if spec.kind() == want {
        return Ok(spec);
    }
    Err(SpecErrors(vec![SpecError::Invalid {
        file: path.display().to_string(),
        line: 1,
        column: 1,
        field: "spec".into(),
        message: format!(
            "is a {} spec; this command takes a {} spec",
            spec.kind().name(),
            want.name()
        ),
    }]))
}

/// [`load_any`] of spec text; files the spec names are relative to `dir`.
pub fn load_any_str(file: &str, text: &str, dir: &Path) -> Result<Spec, SpecErrors> {
    match kind::detect(file, text).map_err(|e| SpecErrors(vec![e]))? {
        SpecKind::Skin => load_str(file, text).map(Spec::Skin),
        SpecKind::Fiber => fiber::load_str(file, text, dir).map(Spec::Fiber),
    }
}

/// SHA-256 of bytes, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest as _;
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}
