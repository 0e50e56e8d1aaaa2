//! Putting an export's documents on disk ([`Layout`]): one file, a file with its side file, or
//! a folder.
//!
//! | layout | `-o FILE` / `-o DIR` | no `-o`, `-o -`, a device or FIFO |
//! |---|---|---|
//! | [`Layout::File`] | FILE, atomically ([`crate::output::atomic`]) | the document, as a stream |
//! | [`Layout::WithSide`] | the side file at FILE with its extension replaced, then FILE, each atomically | the document only (the side file needs a file name to sit beside) |
//! | [`Layout::Folder`] | every file into a hidden staging folder next to DIR, renamed over DIR when all are written ([`crate::output::paths::Staged`]) | a usage error: a folder needs a name |
//!
//! A folder export replaces an existing DIR only if DIR is empty or was written by the same
//! kind of export: it holds the index (`"format"` matching) and nothing that index does not
//! list (a file the user put there stops the export, named). So a re-export updates the assets
//! in place (same names and `.meta` GUIDs) and never deletes anything it did not write.

use std::path::{Path, PathBuf};

use anyhow::Context as _;

use super::{Export, Layout};
use crate::error::UsageError;
use crate::files::Shown;
use crate::output::atomic::{self, Sink};

/// Where the documents of an export went.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Written {
    /// To standard output (or a stream): the main document only.
    Stream {
        /// A side file that was therefore not written: what it holds.
        side_skipped: Option<&'static str>,
    },
    /// To a file, and its side file if the layout has one.
    File {
        main: PathBuf,
        side: Option<PathBuf>,
    },
    /// A folder and the number of files in it.
    Folder { dir: PathBuf, files: usize },
}

/// Writes `export`'s documents to `output` (`None` or `-`: standard output), as its
/// [`Layout`] says ([module docs](self)).
pub fn write(export: &Export, output: Option<&Path>) -> anyhow::Result<Written> {
    let output = output.filter(|p| p.as_os_str() != "-");
    match &export.layout {
        Layout::File => match output {
            None => to_stdout(&export.text, None),
            Some(path) => {
                atomic::write(path, export.text.as_bytes())
                    .with_context(|| format!("writing {}", Shown(path)))?;
                Ok(Written::File {
                    main: path.to_path_buf(),
                    side: None,
                })
            }
        },
        Layout::WithSide { ext, text, what } => {
            let Some(path) = output else {
                return to_stdout(&export.text, Some(what));
            };
            if atomic::target(path).with_context(|| format!("writing {}", Shown(path)))?
                != Sink::File
            {
                atomic::write(path, export.text.as_bytes())
                    .with_context(|| format!("writing {}", Shown(path)))?;
                return Ok(Written::Stream {
                    side_skipped: Some(what),
                });
            }
            let side = side_path(path, ext, export.target)?;
            atomic::write(&side, text.as_bytes())
                .with_context(|| format!("writing {}", Shown(&side)))?;
            atomic::write(path, export.text.as_bytes())
                .with_context(|| format!("writing {}", Shown(path)))?;
            Ok(Written::File {
                main: path.to_path_buf(),
                side: Some(side),
            })
        }
        Layout::Folder {
            files,
            index,
            format,
        } => {
            let Some(dir) = output else {
                return Err(UsageError(format!(
                    "--to {} writes a folder (one file per entry); give it with -o DIR",
                    export.target
                ))
                .into());
            };
            write_folder(dir, files, index, format, export.target)?;
            Ok(Written::Folder {
                dir: dir.to_path_buf(),
                files: files.len(),
            })
        }
    }
}

fn to_stdout(text: &str, side_skipped: Option<&'static str>) -> anyhow::Result<Written> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(Written::Stream { side_skipped })
}

/// `path` with its extension replaced by `ext`; an error if that is `path` itself.
fn side_path(path: &Path, ext: &str, target: &str) -> Result<PathBuf, UsageError> {
    let same = path
        .extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext));
    if same || path.file_name().is_none() {
        return Err(UsageError(format!(
            "-o {}: --to {target} writes the document there and a .{ext} side file beside it \
             (the same name with its extension replaced), which would be the same file; name \
             the output e.g. {}",
            Shown(path),
            Shown(&path.with_extension("py"))
        )));
    }
    Ok(path.with_extension(ext))
}

/// Writes `files` as the folder `dir` ([module docs](self)).
fn write_folder(
    dir: &Path,
    files: &[(String, String)],
    index: &str,
    format: &str,
    target: &str,
) -> anyhow::Result<()> {
    use crate::output::paths::{OutRoot, Staged};
    debug_assert!(files.iter().any(|(n, _)| n == index));
    check_replaceable(dir, index, format, target)?;
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .filter(|n| n != "." && n != "..")
        .ok_or_else(|| {
            UsageError(format!(
                "-o {}: --to {target} needs a folder name (e.g. -o out/unity_profiles)",
                Shown(dir)
            ))
        })?;
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let root = OutRoot::open(parent)?;
    let staged = Staged::begin(&root, &name)?;
    for (file, text) in files {
        let p = staged.path(file)?;
        std::fs::write(&p, text).with_context(|| format!("writing {}", Shown(&p)))?;
    }
    // Everything DIR held is in the index (checked above): nothing of the user's is dropped.
    staged
        .commit(|_| false)
        .with_context(|| format!("replacing {}", Shown(dir)))?;
    Ok(())
}

/// `Ok` if `dir` does not exist, is an empty folder, or is a folder this kind of export wrote
/// and holds nothing else; otherwise a usage error naming what is in the way.
fn check_replaceable(dir: &Path, index: &str, format: &str, target: &str) -> anyhow::Result<()> {
    let meta = match std::fs::symlink_metadata(dir) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(anyhow::anyhow!("{}: {e}", Shown(dir))),
    };
    if !meta.is_dir() {
        let what = if meta.file_type().is_symlink() {
            "a symbolic link"
        } else {
            crate::files::special_kind(&meta.file_type()).unwrap_or("a file")
        };
        return Err(UsageError(format!(
            "-o {}: is {what}; --to {target} writes a folder (choose a new name)",
            Shown(dir)
        ))
        .into());
    }
    let present: Vec<String> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", Shown(dir)))?
        .map(|e| e.map(|e| e.file_name().to_string_lossy().to_string()))
        .collect::<Result<_, _>>()?;
    if present.is_empty() {
        return Ok(());
    }
    let refuse = |why: String| -> anyhow::Error {
        UsageError(format!(
            "-o {}: the folder exists and {why}; --to {target} replaces only a folder it wrote \
             itself (an empty one, or one holding its {index} and the files that lists). \
             Choose a new folder, or move the folder away",
            Shown(dir)
        ))
        .into()
    };
    let old = std::fs::read_to_string(dir.join(index))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok());
    let Some(old) = old.filter(|o| o["format"] == format) else {
        return Err(refuse(format!(
            "holds no {index} of a baker export --to {target}"
        )));
    };
    let listed: Vec<&str> = old["files"]
        .as_array()
        .map(|a| a.iter().filter_map(|f| f.as_str()).collect())
        .unwrap_or_default();
    // Unity writes a `.meta` next to every file it imports; those of listed files are ours.
    let ours = |n: &str| {
        listed.contains(&n) || n.strip_suffix(".meta").is_some_and(|f| listed.contains(&f))
    };
    if let Some(stranger) = present.iter().find(|n| !ours(n)) {
        return Err(refuse(format!(
            "holds {stranger:?}, which the previous export did not write"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder_export(files: &[(&str, &str)]) -> Export {
        Export {
            text: files[0].1.to_string(),
            target: "unity",
            summary: None,
            written: None,
            layout: Layout::Folder {
                files: files
                    .iter()
                    .map(|(a, b)| (a.to_string(), b.to_string()))
                    .collect(),
                index: "index.json".into(),
                format: "test-format",
            },
        }
    }

    fn index(files: &[&str]) -> String {
        serde_json::json!({"format": "test-format", "files": files}).to_string()
    }

    #[test]
    fn a_folder_replaces_only_what_it_wrote() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("profiles");
        let first = index(&["index.json", "a.asset"]);
        let e = folder_export(&[("index.json", &first), ("a.asset", "A1")]);
        assert_eq!(
            write(&e, Some(&dir)).unwrap(),
            Written::Folder {
                dir: dir.clone(),
                files: 2
            }
        );
        assert_eq!(std::fs::read_to_string(dir.join("a.asset")).unwrap(), "A1");
        // Unity adds .meta files of what it imported: still ours. A re-export replaces.
        std::fs::write(dir.join("a.asset.meta"), "guid").unwrap();
        let second = index(&["index.json", "b.asset"]);
        let e2 = folder_export(&[("index.json", &second), ("b.asset", "B")]);
        write(&e2, Some(&dir)).unwrap();
        assert!(!dir.join("a.asset").exists() && dir.join("b.asset").exists());
        // A file the user put there stops the export, and nothing changes.
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        let m = format!("{:#}", write(&e, Some(&dir)).unwrap_err());
        assert!(
            m.contains("\"notes.txt\", which the previous export did not write"),
            "{m}"
        );
        assert!(dir.join("b.asset").exists() && dir.join("notes.txt").exists());
        // A folder that is not an export of this kind is refused; an empty one is taken.
        let other = tmp.path().join("other");
        std::fs::create_dir(&other).unwrap();
        std::fs::write(other.join("x"), "x").unwrap();
        let m = format!("{:#}", write(&e, Some(&other)).unwrap_err());
        assert!(
            m.contains("holds no index.json of a baker export --to unity"),
            "{m}"
        );
        assert!(!other.join("a.asset").exists());
        std::fs::remove_file(other.join("x")).unwrap();
        write(&e, Some(&other)).unwrap();
        assert!(other.join("a.asset").exists());
        // A folder needs a name.
        let m = format!("{:#}", write(&e, None).unwrap_err());
        assert!(m.contains("give it with -o DIR"), "{m}");
        // No staging folders are left behind.
        let left: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .filter(|n| n.starts_with('.'))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    #[test]
    fn a_side_file_sits_beside_the_document() {
        let tmp = tempfile::tempdir().unwrap();
        let e = Export {
            text: "script".into(),
            target: "unreal",
            summary: None,
            written: None,
            layout: Layout::WithSide {
                ext: "json",
                text: "{}".into(),
                what: "the JSON",
            },
        };
        let py = tmp.path().join("skin.py");
        let w = write(&e, Some(&py)).unwrap();
        let json = tmp.path().join("skin.json");
        assert_eq!(
            w,
            Written::File {
                main: py.clone(),
                side: Some(json.clone())
            }
        );
        assert_eq!(std::fs::read_to_string(&json).unwrap(), "{}");
        assert_eq!(std::fs::read_to_string(&py).unwrap(), "script");
        // -o X.json would put both documents in one file.
        let m = write(&e, Some(&json)).unwrap_err().to_string();
        assert!(m.contains("which would be the same file"), "{m}");
        // A device gets the document only.
        let w = write(&e, Some(Path::new("/dev/null"))).unwrap();
        assert_eq!(
            w,
            Written::Stream {
                side_skipped: Some("the JSON")
            }
        );
    }
}
