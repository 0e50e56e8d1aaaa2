//! The YAML spec language, in two stages (ripgrep's low/high args): [`raw`] mirrors the file
//! with a location on every value; [`resolve`] validates ranges, applies defaults and sweeps,
//! and produces model inputs. Nothing downstream sees raw YAML.

pub mod error;
pub mod fiber;
pub mod raw;
pub mod resolve;
mod syntax;

pub use error::{SpecError, SpecErrors};
pub use resolve::{load, load_str, ProfileSettings, ResolvedEntry, SkinSpec};
