//! Exports of baked tables to the parameters renderers already take (`baker export`).
//!
//! - [`skin`]: skin profile tables (`profiles.bkt`) → Christensen–Burley normalized diffusion
//!   ([`burley`]) and the documents of OpenPBR/MaterialX, Blender, Unreal, Unity HDRP, pbrt-v4
//!   and Mitsuba 3, one file per engine.
//! - [`fiber`]: fiber BCSDF tables (`.bcsdf`) → a fit of the Chiang et al. 2016 far-field model
//!   ([`chiang`]) and pbrt-v4, Mitsuba 3 and Blender Principled Hair parameters, one file per
//!   engine.
//!
//! Exporters return the document and what to tell the user ([`Export`]); the command line
//! (`cli/export.rs`) writes and prints. Every conversion cites its source next to the formula.

pub mod burley;
pub mod chiang;
pub mod fiber;
pub mod skin;
mod xml;

use std::path::PathBuf;

/// What `baker export` was asked: the table, the target and an optional entry (skin entry or
/// fiber variant).
#[derive(Debug, Clone)]
pub struct ExportRequest {
    /// The baked table (`profiles.bkt` or a `.bcsdf`).
    pub table: PathBuf,
    /// Target format name as given on the command line (`burley`, `mtlx`, `pbrt`, …).
    pub to: String,
    /// Skin entry or fiber variant; `None` = every entry (skin) or the first variant (fiber).
    pub entry: Option<String>,
}

/// The result of an export: the document and the messages that go with it.
#[derive(Debug, Clone, PartialEq)]
pub struct Export {
    /// The document, byte for byte what goes to the output file or stdout.
    pub text: String,
    /// The `--to` name of the target.
    pub target: &'static str,
    /// A line for stderr, printed before the document is written (fiber exports: the fit's
    /// error and parameters).
    pub summary: Option<String>,
    /// What the document holds ("3 entries"), for the line printed after it was written to a
    /// file: `baker export: {written} → FILE (TARGET)` (skin exports).
    pub written: Option<String>,
}
