//! Exports of baked tables to the parameters renderers already take (`baker export`).
//!
//! - [`skin`]: skin profile tables (`profiles.bkt`) → Christensen–Burley normalized diffusion
//!   ([`burley`]) and the documents of OpenPBR/MaterialX, Blender, Unreal, Unity HDRP, pbrt-v4
//!   and Mitsuba 3.
//! - [`hair`]: fiber BCSDF tables (`.bcsdf`) → a fit of the Chiang et al. 2016 far-field model
//!   ([`chiang`]) and pbrt-v4, Mitsuba 3 and Blender Principled Hair parameters.
//!
//! Every conversion cites its source next to the formula.

pub mod burley;
pub mod chiang;
pub mod hair;
pub mod skin;

use std::path::PathBuf;

/// What `baker export` was asked: the table, the target, an optional entry (skin entry or
/// fiber variant) and an optional output file (default: stdout).
#[derive(Debug, Clone)]
pub struct ExportRequest {
    /// The baked table (`profiles.bkt` or a `.bcsdf`).
    pub table: PathBuf,
    /// Target format name as given on the command line (`burley`, `mtlx`, `pbrt`, …).
    pub to: String,
    /// Skin entry or fiber variant; `None` = every entry (skin) or the first variant (fiber).
    pub entry: Option<String>,
    /// Output file; `None` = stdout.
    pub output: Option<PathBuf>,
}
