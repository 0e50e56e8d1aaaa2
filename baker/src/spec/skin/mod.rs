//! Skin specs (`specs/fitzpatrick.yaml`, ch. 3): entries and sweeps of skin parameters, for
//! layer optics and diffusion profiles. [`raw`] mirrors the file; the resolver merges
//! `defaults` into every entry and sweep (`merge`), expands sweeps (`sweep`), range-checks
//! every value with its location (`params`, `overrides`, `wavelengths`, `profiles`) and
//! evaluates each entry's model once (`resolve`).

mod cx;
mod merge;
mod overrides;
mod params;
pub mod profiles;
pub mod raw;
mod resolve;
mod schema;
mod sweep;
mod types;
mod wavelengths;

use super::error::{SpecError, SpecErrors};
use super::yaml;
use cx::SkinCx;
pub use profiles::{ProfileSettings, DEFAULT_PROFILE_PHOTONS};
use raw::RawSpec;
pub(super) use schema::refine as refine_schema;
pub use types::{ResolvedEntry, SkinSpec, AGE_RANGE_YEARS, LAMBDA_RANGE_NM};

/// Validates spec text; `file` names it in messages.
pub fn load_str(file: &str, text: &str) -> Result<SkinSpec, SpecErrors> {
    let raw: RawSpec = yaml::parse(file, text, &|t| check_str(file, t))?;
    resolve_raw(file, raw).map(|s| SkinSpec {
        sha256: crate::files::sha256_hex(text.as_bytes()),
        ..s
    })
}

fn resolve_raw(file: &str, raw: RawSpec) -> Result<SkinSpec, SpecErrors> {
    let mut cx = SkinCx::new(file);
    let spec = cx.resolve(raw);
    cx.dedup();
    cx.finish(spec)
}

/// Every error of spec text, parse errors undiagnosed ([`super::syntax::Check`]).
fn check_str(file: &str, text: &str) -> Vec<SpecError> {
    match yaml::parse_plain::<RawSpec>(file, text) {
        Ok(raw) => resolve_raw(file, raw).err().map_or_else(Vec::new, |e| e.0),
        Err(e) => vec![e],
    }
}
