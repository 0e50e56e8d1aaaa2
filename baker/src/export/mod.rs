//! Exports of baked tables to the parameters renderers already take (`baker export`).
//!
//! - [`skin`]: skin profile tables (`profiles.bkt`) → Christensen–Burley normalized diffusion
//!   ([`burley`]) and the documents of OpenPBR/MaterialX, Blender, Unreal, Unity HDRP, pbrt-v4
//!   and Mitsuba 3, one file per engine.
//! - [`fiber`]: fiber BCSDF tables (`.bcsdf`) → a fit of the Chiang et al. 2016 far-field model
//!   ([`chiang`]) and pbrt-v4, Mitsuba 3, Blender Principled Hair and MaterialX
//!   `chiang_hair_bsdf` parameters, one file per engine.
//!
//! Exporters return the document and what to tell the user ([`Export`]); [`layout::write`]
//! puts the documents on disk and the command line (`cli/export.rs`) prints. Every conversion cites its source next to the formula.

pub mod burley;
pub mod chiang;
pub mod fiber;
pub mod layout;
pub mod skin;
mod xml;

use std::path::{Path, PathBuf};

use crate::error::UsageError;

/// What `baker export` was asked: the table, the target and the entries (skin entries, or one
/// fiber variant; none: every skin entry, the first variant).
#[derive(Debug, Clone)]
pub struct ExportRequest {
    /// The baked table (`profiles.bkt` or a `.bcsdf`).
    pub table: PathBuf,
    /// Target format name as given on the command line (`burley`, `mtlx`, `pbrt`, …).
    pub to: String,
    /// Skin entries or one fiber variant; empty = every entry (skin) or the first variant.
    pub entries: Vec<String>,
    /// `--method` as given: the Subsurface Method of a skin export `--to blender`
    /// ([`skin::blender::Method`]); `None` = its default. Any other export refuses it.
    pub method: Option<String>,
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
    /// Where the documents go: one file (most targets), a file and a side file (Unreal: the
    /// editor script and its JSON), or a folder (Unity: one `.asset` per entry) ([`layout`]).
    pub layout: Layout,
}

/// How an export's documents reach the disk ([`layout::write`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Layout {
    /// [`Export::text`] alone: to `-o FILE`, or standard output.
    #[default]
    File,
    /// [`Export::text`] to `-o FILE` (or standard output), and `text` here beside it, at FILE
    /// with its extension replaced by `ext` (only with `-o`).
    WithSide {
        ext: &'static str,
        text: String,
        /// What the side file is ("the profiles' fields as JSON"), for messages.
        what: &'static str,
    },
    /// A folder (`-o DIR`, required) holding `files` (plain names, contents), written into a
    /// staging folder and renamed into place. `index` is one of the files, a JSON document
    /// whose `"format"` is `format` and whose `"files"` lists every file: a folder holding
    /// such an index and nothing else may be replaced; any other existing folder is refused.
    /// [`Export::text`] is the index.
    Folder {
        files: Vec<(String, String)>,
        index: String,
        format: &'static str,
    },
}

/// The `--to` values of fiber tables.
pub const FIBER_TARGETS: [&str; 5] = ["chiang", "pbrt", "mitsuba", "blender", "mtlx"];

/// The tables of one kind: its name, what its file is, and its `--to` values.
pub(crate) struct TableKind<'a> {
    pub name: &'a str,
    pub file: &'a str,
    pub targets: &'a [&'a str],
}

/// `--to` naming no target of `this` kind of table: a target of the `other` kind only is
/// named as such; otherwise the nearest targets ([`crate::suggest`]) and the list.
pub(crate) fn unknown_target(
    req: &ExportRequest,
    this: &TableKind,
    other: &TableKind,
) -> UsageError {
    let to = &req.to;
    let table = req.table.display();
    if other.targets.contains(&to.as_str()) {
        return UsageError(format!(
            "--to {to:?} is a {} export target, and {table} is a {} table ({}); {} targets: {}",
            other.name,
            this.name,
            this.file,
            this.name,
            this.targets.join(", ")
        ));
    }
    UsageError(format!(
        "--to {to:?} is not a {} export target; {}",
        this.name,
        crate::suggest::advice(to, this.targets, "targets", "")
    ))
}

/// `--entry` naming no entry (skin, `what` = ("entry", "entries")) or variant (fiber) of the
/// table: the nearest names and, for a long list, the manifest that lists them.
pub(crate) fn unknown_entry(
    req: &ExportRequest,
    what: (&str, &str),
    name: &str,
    names: &[&str],
) -> UsageError {
    let listed_by = match manifest_near(&req.table) {
        Some(m) => format!("{} lists them", m.display()),
        None => "the bake's manifest.json lists them".to_string(),
    };
    UsageError(format!(
        "no {} named {name:?} in {}; {}",
        what.0,
        req.table.display(),
        crate::suggest::advice(name, names, what.1, &listed_by)
    ))
}

/// The `manifest.json` of the bake that wrote `table`: beside it (skin) or one folder up
/// (fiber tables lie in `<entry>/`).
fn manifest_near(table: &Path) -> Option<PathBuf> {
    table
        .ancestors()
        .skip(1)
        .take(2)
        .map(|d| d.join("manifest.json"))
        .find(|m| m.is_file())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(table: &str, to: &str) -> ExportRequest {
        ExportRequest {
            table: PathBuf::from(table),
            to: to.into(),
            entries: Vec::new(),
            method: None,
        }
    }

    fn message(r: anyhow::Result<Export>) -> String {
        let e = r.unwrap_err();
        e.downcast_ref::<UsageError>()
            .unwrap_or_else(|| panic!("not a usage error: {e:#}"))
            .0
            .clone()
    }

    #[test]
    fn misspelt_and_mismatched_targets() {
        // The target is checked before the table is read: no table is needed.
        let m = message(skin::export(&req("p.bkt", "blendr")));
        assert!(m.contains("did you mean \"blender\"?"), "{m}");
        let m = message(skin::export(&req("p.bkt", "chiang")));
        assert!(
            m.contains("\"chiang\" is a fiber export target, and p.bkt is a skin table"),
            "{m}"
        );
        assert!(m.contains("skin targets: burley, mtlx, blender"), "{m}");
        let m = message(fiber::export(&req("a.bcsdf", "burley")));
        assert!(m.contains("\"burley\" is a skin export target"), "{m}");
        assert!(
            m.contains("fiber targets: chiang, pbrt, mitsuba, blender, mtlx"),
            "{m}"
        );
        let m = message(fiber::export(&req("a.bcsdf", "chaing")));
        assert!(m.contains("did you mean \"chiang\"?"), "{m}");
        // A target of both kinds is no mismatch.
        let m = message(fiber::export(&req("a.bcsdf", "pbrtv4")));
        assert!(
            m.contains("not a fiber export target; did you mean \"pbrt\"?"),
            "{m}"
        );
    }

    #[test]
    fn a_misspelt_entry_of_a_large_table_is_not_answered_with_every_name() {
        let names: Vec<String> = (0..40).map(|i| format!("dye{i}@1%")).collect();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let m = unknown_entry(
            &req("/nowhere/a.bcsdf", "chiang"),
            ("variant", "variants"),
            "dye17@1 %",
            &refs,
        )
        .0;
        assert!(
            m.starts_with(
                "no variant named \"dye17@1 %\" in /nowhere/a.bcsdf; did you mean \"dye17@1%\""
            ),
            "{m}"
        );
        assert!(
            m.contains("(40 variants; the bake's manifest.json lists them)"),
            "{m}"
        );
        assert!(!m.contains("dye39@1%"), "{m}");
    }
}
