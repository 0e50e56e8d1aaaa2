//! `manifest.json`: what a bake produced — entries with their parameters, and every file with
//! its size and SHA-256, so a pipeline can verify or cache outputs.

use std::path::Path;

use anyhow::Context;
use serde::Serialize;

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
    Ok(ManifestFile {
        path: rel.to_string(),
        bytes: bytes.len() as u64,
        sha256: crate::files::sha256_hex(&bytes),
        description: description.to_string(),
    })
}

/// SHA-256 of a spec file, hex (empty if it cannot be read).
pub fn spec_sha256(spec_file: &str) -> String {
    file_entry(Path::new(""), spec_file, "")
        .map(|f| f.sha256)
        .unwrap_or_default()
}

/// Creation time for provenance, UTC, ISO 8601 — only when `SOURCE_DATE_EPOCH` is set (the
/// reproducible-builds convention): without it tables carry no timestamp, so an unchanged
/// bake gives byte-identical files.
pub fn created_utc() -> Option<String> {
    let secs: i64 = std::env::var("SOURCE_DATE_EPOCH")
        .ok()?
        .trim()
        .parse()
        .ok()?;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Civil date from days since 1970-01-01 (H. Hinnant, "chrono-compatible low-level date
    // algorithms", days_from_civil inverse).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    Some(format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    ))
}

#[cfg(test)]
mod tests {
    #[test]
    fn source_date_epoch_formats_as_utc() {
        // 2026-11-23T12:34:56Z = 1795437296 s (date -u -d @1795437296).
        std::env::set_var("SOURCE_DATE_EPOCH", "1795437296");
        assert_eq!(
            super::created_utc().as_deref(),
            Some("2026-11-23T12:34:56Z")
        );
        std::env::remove_var("SOURCE_DATE_EPOCH");
    }
}
