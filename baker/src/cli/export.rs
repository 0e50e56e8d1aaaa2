//! `baker export TABLE --to FORMAT [--entry NAME] [-o FILE]`.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::error::UsageError;

use crate::export::{Export, ExportRequest};

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A baked table: `out/<spec>/profiles.bkt` (skin) or `out/fibers/<entry>/*.bcsdf` (fiber).
    pub table: PathBuf,
    /// Target. Skin: burley, mtlx (OpenPBR/MaterialX), blender, unreal, unity, pbrt, mitsuba.
    /// Fiber: chiang, pbrt, mitsuba, blender, mtlx. `unreal` writes an editor script and, with
    /// `-o X.py`, `X.json` beside it; `unity` writes a folder of assets (`-o DIR`).
    #[arg(long = "to")]
    pub to: String,
    /// Skin entry to export (repeatable; default: every entry) or fiber dye variant (one;
    /// default: the first).
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Skin `--to blender` only: the Principled BSDF's Subsurface Method, burley, random-walk
    /// or random-walk-skin (default).
    #[arg(long = "method", value_name = "METHOD")]
    pub method: Option<String>,
    /// Output file, written atomically (default, or `-`: standard output); a folder for
    /// `--to unity`.
    #[arg(short = 'o', long = "out", alias = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// No summary or "wrote" line on stderr (errors still go there).
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(a: ExportArgs) -> anyhow::Result<()> {
    let req = ExportRequest {
        table: a.table,
        to: a.to,
        entries: a.entries,
        method: a.method,
    };
    let head = read_head(&req.table)?;
    let export = if head == formats::table::MAGIC {
        crate::export::skin::export(&req)?
    } else if head == formats::bcsdf::MAGIC {
        crate::export::fiber::export(&req)?
    } else {
        return Err(UsageError(format!(
            "{}: not a baker table (expected profiles.bkt or a .bcsdf file)",
            req.table.display()
        ))
        .into());
    };
    emit(&export, a.output.as_deref(), a.quiet)
}

/// The first 8 bytes of `table` (the file magic), zero-filled if it is shorter.
fn read_head(table: &Path) -> anyhow::Result<[u8; 8]> {
    use std::io::Read as _;
    let mut head = [0u8; 8];
    // A table is a regular file: a directory or device is named as such, not opened.
    match std::fs::metadata(table) {
        Ok(m) if m.is_file() => {}
        Ok(m) => {
            return Err(UsageError(format!(
                "{}: is {}; expected a baked table (profiles.bkt or a .bcsdf file)",
                table.display(),
                crate::files::special_kind(&m.file_type()).unwrap_or("not a regular file")
            ))
            .into())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(UsageError(format!("{}: no such file", table.display())).into());
        }
        Err(e) => {
            return Err(UsageError(format!("{}: {e}", table.display())).into());
        }
    }
    let mut f = std::fs::File::open(table)
        .map_err(|e| anyhow::anyhow!("cannot open {}: {e}", table.display()))?;
    let _ = f.read(&mut head)?;
    Ok(head)
}

/// Prints the export's summary to stderr, then writes its documents ([`layout::write`]: to
/// `output`, atomically, or stdout; a side file beside the file; or a folder), then confirms a
/// file write where the export says what it wrote.
fn emit(export: &Export, output: Option<&Path>, quiet: bool) -> anyhow::Result<()> {
    use crate::export::layout::{self, Written};
    if let Some(line) = export.summary.as_ref().filter(|_| !quiet) {
        eprintln!("{line}");
    }
    let written = layout::write(export, output)?;
    if quiet {
        return Ok(());
    }
    let what = export.written.as_deref();
    match written {
        Written::Stream {
            side_skipped: Some(side),
        } => {
            eprintln!("baker export: {side} not written (a side file needs -o FILE to sit beside)")
        }
        Written::Stream { side_skipped: None } => {}
        Written::File { main, side } => {
            if let Some(what) = what {
                let side = side.map_or(String::new(), |s| format!(" and {}", s.display()));
                eprintln!(
                    "baker export: {what} → {}{side} ({})",
                    main.display(),
                    export.target
                );
            }
        }
        Written::Folder { dir, files } => eprintln!(
            "baker export: {} → {} ({files} files, {})",
            what.unwrap_or("the export"),
            dir.display(),
            export.target
        ),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_export_writes_nothing() {
        // An unknown target and an unknown entry: usage errors, and no file.
        let dir = tempfile::tempdir().unwrap();
        let table = crate::export::skin::tests::synthetic_table(dir.path());
        let out = dir.path().join("x");
        for (to, entry) in [("povray", None), ("unreal", Some("typeIV"))] {
            let e = run(ExportArgs {
                table: table.clone(),
                to: to.into(),
                entries: entry.map(str::to_string).into_iter().collect(),
                method: None,
                output: Some(out.clone()),
                quiet: true,
            })
            .unwrap_err();
            assert!(!out.exists(), "{to}: {e:#}");
        }
    }
}
