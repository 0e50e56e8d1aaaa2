//! Where a bake of one spec goes, so that nothing finished is replaced by less, and what a
//! finished bake's manifest says about it.

use std::path::Path;

use anyhow::Context;

use super::stamp::spec_sha;
use crate::bake::request::Request;
use crate::files::Shown;
use crate::output::paths::{OutRoot, Staged};
use crate::pipeline::Events;
use crate::spec::Spec;

/// Where a bake of one spec goes. Nothing finished is replaced by less:
///
/// - a bake of part of a spec (some `--entry`s, fewer `--photons` than the spec asks for,
///   `--optics-only`) goes to `OUT/<stem>/subset/` when `OUT/<stem>/` holds a finished bake;
/// - a whole bake goes to `OUT/<stem>/subset/` when `OUT/<stem>/` holds a bake of the same spec
///   with more photons (`--photons` above the spec's);
/// - anything else (a first bake, a whole bake of a changed spec) to `OUT/<stem>/`;
/// - `--replace` always to `OUT/<stem>/`.
pub struct Destination {
    /// Relative to the output root, `/`-separated.
    pub rel: String,
    pub staged: Staged,
    /// What the folder held before (its manifest's top-level names), kept or replaced.
    pub previous: std::collections::BTreeSet<String>,
}

/// The subset folder's name inside a spec's output folder.
pub const SUBSET_DIR: &str = "subset";

pub fn destination(
    a: &Request,
    root: &OutRoot,
    stem: &str,
    spec: &Spec,
    // This bake's stamp: equal to the finished bake's, this is that bake again.
    stamp: &str,
    events: &Events,
) -> anyhow::Result<Destination> {
    let full_dir = root.join(stem)?;
    let selected = spec.entries().iter().filter(|(n, _)| a.selects(n)).count();
    let spec_photons = match spec {
        Spec::Skin(s) => s.profiles.photons,
        Spec::Fiber(s) => s.bake.photons,
    };
    let photons = a.photons.unwrap_or(spec_photons);
    let partial = selected < spec.entries().len() || photons < spec_photons || a.optics_only;
    let finished = manifest_summary(&full_dir);
    // The same spec and flags as the finished bake: this is that bake again (up to date, or
    // to repair).
    let same = std::fs::read_to_string(full_dir.join(crate::output::STAMP_FILE))
        .is_ok_and(|s| s.trim() == stamp);
    let bigger = !same
        && finished.as_ref().is_some_and(|m| {
            partial || (m.spec_sha256 == spec_sha(spec) && m.photons.is_some_and(|p| p > photons))
        });
    let subset = !a.replace && bigger;
    let rel = if subset {
        format!("{stem}/{SUBSET_DIR}")
    } else {
        stem.to_string()
    };
    if subset {
        let why = if partial {
            "part of the spec"
        } else {
            "fewer photons than the finished bake of the same spec"
        };
        events.say(format!(
            "{}: this bake is {why}, and {} holds a finished bake; writing to {} instead \
             (--replace writes over the finished bake)",
            spec.file(),
            Shown(&full_dir),
            Shown(&root.join(&rel)?),
        ));
    }
    let staged = Staged::begin(root, &rel)?;
    // What the target folder holds: the finished bake's, already read, unless this is a
    // subset.
    let previous = if subset {
        manifest_summary(staged.target())
    } else {
        finished
    }
    .map(|m| m.top_level)
    .unwrap_or_default();
    Ok(Destination {
        rel,
        staged,
        previous,
    })
}

/// What a finished bake's manifest says about it.
pub struct ManifestSummary {
    pub spec_sha256: String,
    pub photons: Option<u64>,
    /// First components of the paths of its files.
    pub top_level: std::collections::BTreeSet<String>,
    /// Keys of the work units it was assembled from.
    pub units: Vec<String>,
}

/// Reads `dir/manifest.json` (skin or fiber), if there is a readable one.
pub fn manifest_summary(dir: &Path) -> Option<ManifestSummary> {
    let text = crate::files::read_text(
        &dir.join("manifest.json"),
        crate::files::MAX_SPEC_BYTES,
        "a manifest",
    )
    .ok()?;
    let m: serde_json::Value = serde_json::from_str(&text).ok()?;
    let top_level = m["files"]
        .as_array()?
        .iter()
        .filter_map(|f| f["path"].as_str()?.split('/').next().map(str::to_string))
        .collect();
    let photons = m["settings"]["photons"].as_u64();
    Some(ManifestSummary {
        spec_sha256: m["spec_sha256"].as_str().unwrap_or_default().to_string(),
        photons,
        top_level,
        units: m["units"]
            .as_array()
            .map(|u| {
                u.iter()
                    .filter_map(|k| k.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default(),
    })
}

/// Top-level names a bake of either kind writes into a spec's folder.
const BAKE_FILES: [&str; 10] = [
    "manifest.json",
    "timing.json",
    crate::output::STAMP_FILE,
    "optics.json",
    "optics",
    "profiles.h5",
    "profiles.bkt",
    "profiles_rgb.exr",
    "preview",
    "plots",
];

impl Destination {
    /// Puts the finished bake in place; what the folder held that no bake wrote (a subset
    /// folder, a user's notes) is kept.
    pub fn commit(self) -> anyhow::Result<()> {
        let previous = self.previous;
        let target = self.staged.target().to_path_buf();
        self.staged
            .commit(|name| !BAKE_FILES.contains(&name) && !previous.contains(name))
            .with_context(|| format!("putting the bake in place at {}", Shown(&target)))
    }
}
