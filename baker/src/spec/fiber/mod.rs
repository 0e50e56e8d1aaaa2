//! Fiber specs (`specs/fibers.yaml`, ch. 5): dyes and fiber entries, validated with
//! file:line:column like skin specs. [`raw`] mirrors the file; the resolver checks the spec's
//! dyes (`dyes`) and bake settings (`bake`), then each fiber (`resolve`): its surface
//! (`surface`), cross-section (`section`), dyeings (`dyeing`) and population of
//! cross-sections with their symmetries and table sizes (`population`). Section files (CSV
//! outlines, mask images) and dye spectra are read here, relative to the spec's folder
//! (`files`), so a bad file is reported against the line that names it.

mod dyeing;
mod dyes;
mod entry;
mod files;
mod population;
pub mod raw;
mod resolve;
mod schema;
mod section;
mod settings;
mod surface;

use std::collections::HashMap;
use std::ops::{Deref, DerefMut};
use std::path::Path;

use super::check::Ctx;
use super::error::{SpecError, SpecErrors};
use super::limits::Limits;
use super::yaml;
use crate::fiber::dye::Dye;
use crate::fiber::slices::BakeSettings;
use crate::fiber::Section;
pub use entry::{FiberEntry, SectionSource, SymmetryMode};
use raw::RawFiberSpec;
pub(super) use schema::refine as refine_schema;
pub use section::MEASURED_SIZE_FACTOR;
pub use settings::{
    choice_of, TableStorage, ZstdLevel, EXPECTED_EXITS, MAX_EXIT_DRAWS, MAX_SPLIT, SAMPLINGS,
};
pub use surface::MAX_BETA_DEG;

/// A validated fiber spec.
#[derive(Debug, Clone)]
pub struct FiberSpec {
    pub file: String,
    /// Presets plus the spec's own dyes.
    pub dyes: Vec<Dye>,
    pub fibers: Vec<FiberEntry>,
    pub bake: BakeSettings,
    /// How the tables store the traced values (`bake.quantise_to_se`).
    pub storage: TableStorage,
    pub limits: Limits,
    /// Where `bake.photons_per_direction` is set (line 1 when it is not).
    pub photons_at: (u64, u64),
    /// SHA-256 of the spec text as read (provenance in every table).
    pub sha256: String,
}

/// Validates fiber-spec text; files it names are looked up relative to `dir`.
pub fn load_str(file: &str, text: &str, dir: &Path) -> Result<FiberSpec, SpecErrors> {
    let raw: RawFiberSpec = yaml::parse(file, text, &|t| check_str(file, t, dir))?;
    resolve_raw(file, raw, dir).map(|s| FiberSpec {
        sha256: crate::files::sha256_hex(text.as_bytes()),
        ..s
    })
}

fn resolve_raw(file: &str, raw: RawFiberSpec, dir: &Path) -> Result<FiberSpec, SpecErrors> {
    let mut cx = FiberCx::new(file);
    let spec = cx.fiber_spec(raw, dir);
    cx.finish(spec)
}

/// Every error of fiber-spec text, parse errors undiagnosed (to probe what a field allows).
fn check_str(file: &str, text: &str, dir: &Path) -> Vec<SpecError> {
    match yaml::parse_plain::<RawFiberSpec>(file, text) {
        Ok(raw) => resolve_raw(file, raw, dir)
            .err()
            .map_or_else(Vec::new, |e| e.0),
        Err(e) => vec![e],
    }
}

/// The fiber resolver: the shared checks ([`Ctx`], reached through `Deref`), and the
/// sections read from files, by file and reading options (a file named by many fibers is read
/// and checked once).
struct FiberCx {
    cx: Ctx,
    read_sections: HashMap<String, Result<Section, String>>,
}

impl Deref for FiberCx {
    type Target = Ctx;
    fn deref(&self) -> &Ctx {
        &self.cx
    }
}

impl DerefMut for FiberCx {
    fn deref_mut(&mut self) -> &mut Ctx {
        &mut self.cx
    }
}

impl FiberCx {
    fn new(file: &str) -> FiberCx {
        FiberCx {
            cx: Ctx::new(file),
            read_sections: HashMap::new(),
        }
    }
}

/// What every fiber of a spec is resolved against: the dyes (presets and the spec's own), the
/// names of the spec's dyes that failed their checks (already reported, so a fiber naming one
/// is not told the name is unknown), the spec's folder, its bake settings and limits.
struct Scope<'a> {
    dyes: &'a [Dye],
    broken: &'a [String],
    dir: &'a Path,
    bake: &'a BakeSettings,
    limits: &'a Limits,
}
