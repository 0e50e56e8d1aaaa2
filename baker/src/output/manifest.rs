//! `manifest.json`: what a bake produced — entries with their parameters, and every file with
//! its size and SHA-256, so a pipeline can verify or cache outputs.

use std::path::Path;

use anyhow::Context;
use serde::Serialize;
use sha2::{Digest, Sha256};

#[derive(Debug, Serialize)]
pub struct ManifestFile {
    /// Relative to the manifest's directory, with `/` separators.
    pub path: String,
    pub bytes: u64,
    pub sha256: String,
    pub description: String,
}

/// Size and SHA-256 of `dir/rel`.
pub fn file_entry(dir: &Path, rel: &str, description: &str) -> anyhow::Result<ManifestFile> {
    let p = dir.join(rel);
    let bytes = std::fs::read(&p).with_context(|| format!("reading {}", p.display()))?;
    let digest = Sha256::digest(&bytes);
    Ok(ManifestFile {
        path: rel.to_string(),
        bytes: bytes.len() as u64,
        sha256: digest.iter().map(|b| format!("{b:02x}")).collect(),
        description: description.to_string(),
    })
}
