//! The stamp of a bake: what determines a spec's outputs. Equal stamps and intact files make a
//! bake a no-op.

use std::path::Path;

use anyhow::Context;

use crate::bake::request::Request;
use crate::files::sha256_hex;
use crate::output::{atomic, STAMP_FILE};
use crate::spec::Spec;

/// What determines a spec's outputs: the spec's bytes (`spec_sha256`), this executable's bytes
/// (code and data tables), the engine version and the flags that change outputs. Equal stamps
/// and intact files (checked against the manifest's SHA-256) make a bake a no-op.
pub fn stamp(a: &Request, spec: &Path, spec_sha256: &str) -> String {
    static EXE: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    let exe = EXE.get_or_init(|| {
        std::env::current_exe()
            .ok()
            .and_then(|p| std::fs::read(p).ok())
            .map(|b| crate::pipeline::digest_of(&sha256_hex(&b)))
            .map(|d| sha256_hex(&d))
            .unwrap_or_default()
    });
    sha256_hex(&crate::pipeline::digest_of(&(
        spec_sha256,
        spec,
        exe,
        crate::pipeline::ENGINE_VERSION,
        a.photons,
        &a.entries,
        a.no_reuse,
        a.optics_only,
        a.plots,
    )))
}

/// Whether `dir` holds the outputs of `stamp`, every file of its manifest intact.
pub fn up_to_date(dir: &Path, stamp: &str) -> bool {
    // Only regular files count (a FIFO or device planted there is not an output).
    let regular = |p: &Path| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_file());
    if !regular(&dir.join(STAMP_FILE)) || !regular(&dir.join("manifest.json")) {
        return false;
    }
    let Ok(s) = std::fs::read_to_string(dir.join(STAMP_FILE)) else {
        return false;
    };
    if s.trim() != stamp {
        return false;
    }
    let Ok(m) = std::fs::read_to_string(dir.join("manifest.json")) else {
        return false;
    };
    let Ok(m) = serde_json::from_str::<serde_json::Value>(&m) else {
        return false;
    };
    let Some(files) = m["files"].as_array() else {
        return false;
    };
    files.iter().all(|f| {
        let (Some(rel), Some(sha)) = (f["path"].as_str(), f["sha256"].as_str()) else {
            return false;
        };
        rel.split('/')
            .all(|c| crate::output::paths::check_component(c, false).is_ok())
            && regular(&dir.join(rel))
            && std::fs::read(dir.join(rel)).is_ok_and(|b| sha256_hex(&b) == sha)
    })
}

/// Records `stamp` once every output of the spec is written.
pub fn write_stamp(dir: &Path, stamp: &str) -> anyhow::Result<()> {
    let p = dir.join(STAMP_FILE);
    atomic::write(&p, stamp.as_bytes()).with_context(|| format!("writing {}", p.display()))
}

/// The SHA-256 of a spec's bytes, of either kind.
pub fn spec_sha(spec: &Spec) -> &str {
    match spec {
        Spec::Skin(s) => &s.sha256,
        Spec::Fiber(s) => &s.sha256,
    }
}
