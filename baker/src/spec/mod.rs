//! The YAML spec language, of two kinds decided by the top-level keys ([`kind`]): [`skin`]
//! (`entries:`, `wavelengths:`, `profiles:` …) and [`fiber`] (`fibers:`, `dyes:`, `bake:` …).
//! Each kind has two stages of its own (ripgrep's low/high args): `raw` mirrors the file with
//! a location on every value; the resolver validates ranges, applies defaults and sweeps,
//! checks [`limits`] and [`names`], and produces model inputs. The checking helpers both
//! kinds use are in one place (`check`), as are reading YAML (`yaml`) and turning its errors
//! into a user's terms (`syntax`). Nothing downstream sees raw YAML, and nothing downstream
//! rejects a spec the resolver accepted: `baker validate` and `baker bake` share this code
//! path.
//!
//! [`load_any`] reads a file once, decides its [`kind`] from its top-level keys and resolves it.

pub mod budget;
mod check;
pub mod error;
pub mod fiber;
pub mod kind;
pub mod limits;
pub mod names;
pub mod schema;
pub mod skin;
mod syntax;
pub mod templates;
mod yaml;

use std::path::Path;

pub use crate::files::sha256_hex;
pub use error::{SpecError, SpecErrors};
pub use fiber::{FiberEntry, FiberSpec};
pub use kind::SpecKind;
pub use limits::Limits;
pub use skin::{load_str, ProfileSettings, ResolvedEntry, SkinSpec};

/// A resolved spec of either kind.
#[derive(Debug, Clone)]
pub enum Spec {
    Skin(SkinSpec),
    Fiber(FiberSpec),
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
        SpecKind::Skin => skin::load_str(file, text).map(Spec::Skin),
        SpecKind::Fiber => fiber::load_str(file, text, dir).map(Spec::Fiber),
    }
}

/// Reads and validates the skin spec at `path` (a fiber spec is an error that says so).
pub fn load(path: &Path) -> Result<SkinSpec, SpecErrors> {
    match load_as(path, SpecKind::Skin)? {
        Spec::Skin(s) => Ok(s),
        Spec::Fiber(_) => unreachable!("load_as checked the kind"),
    }
}

/// Reads and validates the fiber spec at `path` (a skin spec is an error that says so).
pub fn load_fiber(path: &Path) -> Result<FiberSpec, SpecErrors> {
    match load_as(path, SpecKind::Fiber)? {
        Spec::Fiber(s) => Ok(s),
        Spec::Skin(_) => unreachable!("load_as checked the kind"),
    }
}
