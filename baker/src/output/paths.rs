//! Every path a bake writes is built here, inside its output root (`--out`), and checked to
//! stay there.
//!
//! - [`OutRoot::open`] takes the root: an existing directory, or a new one (never a file or a
//!   device, which are named as what they are).
//! - [`OutRoot::join`] builds a path from names: each component must be a plain name (no
//!   separator, `.`, `..`, NUL or leading dot unless the caller asks for a hidden file). Entry
//!   names are already checked by the spec resolver ([`crate::spec::names`]); this is the
//!   second line of defence.
//! - [`OutRoot::contain`] resolves a path's existing ancestors (symbolic links included) and
//!   rejects any that leads outside the root.
//! - [`Staged`] is a spec's output folder being written: everything goes into a fresh hidden
//!   sibling folder, which replaces the finished folder in one rename when the bake is done.
//!   An interrupted or failed bake leaves the previous result exactly as it was.

use std::fs;
use std::io;
use std::path::{Component, Path, PathBuf};

use crate::files::Shown;

/// An output root: where a command may write.
#[derive(Debug, Clone)]
pub struct OutRoot {
    /// As the user gave it (for messages).
    given: PathBuf,
    /// Canonical (symbolic links resolved).
    root: PathBuf,
}

fn err(m: String) -> io::Error {
    io::Error::other(m)
}

/// `Ok` if `name` can be one component of an output path; `hidden` allows a leading dot (the
/// baker's own `.cache`, `.baked`).
pub fn check_component(name: &str, hidden: bool) -> Result<(), String> {
    let plain = !name.is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\', '\0'])
        && !name.chars().any(char::is_control)
        && (hidden || !name.starts_with('.'));
    if plain {
        Ok(())
    } else {
        Err(format!("{name:?} is not a plain file name"))
    }
}

impl OutRoot {
    /// The root at `dir`, created if it does not exist.
    pub fn open(dir: &Path) -> io::Result<OutRoot> {
        match fs::metadata(dir) {
            Ok(m) if m.is_dir() => {}
            Ok(m) => {
                let what = crate::files::special_kind(&m.file_type()).unwrap_or("a file");
                let what = if what == "not a regular file" {
                    "a file"
                } else {
                    what
                };
                return Err(err(format!(
                    "output folder {} is {what}, not a folder",
                    Shown(dir)
                )));
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                fs::create_dir_all(dir)
                    .map_err(|e| err(format!("cannot create output folder {}: {e}", Shown(dir))))?;
            }
            Err(e) => return Err(err(format!("output folder {}: {e}", Shown(dir)))),
        }
        let root = fs::canonicalize(dir)?;
        Ok(OutRoot {
            given: dir.to_path_buf(),
            root,
        })
    }

    /// The root as the user gave it.
    pub fn given(&self) -> &Path {
        &self.given
    }

    /// The root with symbolic links resolved.
    pub fn canonical(&self) -> &Path {
        &self.root
    }

    /// `rel` (components separated by `/`) under the root, each component checked.
    pub fn join(&self, rel: &str) -> io::Result<PathBuf> {
        join_checked(&self.given, rel, false)
    }

    /// As [`OutRoot::join`], allowing hidden components (the baker's own files).
    pub fn join_hidden(&self, rel: &str) -> io::Result<PathBuf> {
        join_checked(&self.given, rel, true)
    }

    /// Errors if `p`, or the nearest of its ancestors that exists, resolves outside the root
    /// (a symbolic link inside the output folder that points elsewhere).
    pub fn contain(&self, p: &Path) -> io::Result<()> {
        let mut q = p;
        loop {
            match fs::canonicalize(q) {
                Ok(c) => {
                    return if c.starts_with(&self.root) {
                        Ok(())
                    } else {
                        Err(err(format!(
                            "{} leads outside the output folder {} (to {}); refusing to write \
                             there",
                            Shown(p),
                            Shown(&self.given),
                            Shown(&c)
                        )))
                    };
                }
                Err(_) => match q.parent() {
                    Some(parent) if !parent.as_os_str().is_empty() => q = parent,
                    _ => return Ok(()),
                },
            }
        }
    }
}

/// `base` joined with the checked components of `rel`.
fn join_checked(base: &Path, rel: &str, hidden: bool) -> io::Result<PathBuf> {
    let mut p = base.to_path_buf();
    for c in rel.split('/') {
        check_component(c, hidden)
            .map_err(|m| err(format!("output path {rel:?}: {m}; refusing to write it")))?;
        p.push(c);
    }
    // Defence in depth: what was pushed is only normal components.
    debug_assert!(Path::new(rel)
        .components()
        .all(|c| matches!(c, Component::Normal(_))));
    Ok(p)
}

/// A spec's output folder being written ([module docs](self)).
#[derive(Debug)]
pub struct Staged {
    root: OutRoot,
    /// The finished folder, e.g. `out/fitzpatrick`.
    target: PathBuf,
    /// Where this bake writes until [`Staged::commit`].
    dir: PathBuf,
    committed: bool,
}

/// Names a staging folder of `target` starts with.
fn staging_prefix(target: &Path) -> String {
    format!(
        ".{}.partial-",
        target
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default()
    )
}

impl Staged {
    /// Starts writing the folder `rel` of `root` (`fitzpatrick`, `fitzpatrick/subset`).
    /// Staging folders left by killed bakes of the same target are removed first.
    pub fn begin(root: &OutRoot, rel: &str) -> io::Result<Staged> {
        let target = root.join(rel)?;
        match fs::symlink_metadata(&target) {
            Ok(m) if m.is_dir() => {}
            Ok(m) => {
                let what = crate::files::special_kind(&m.file_type()).unwrap_or("a file");
                let what = if m.file_type().is_symlink() {
                    "a symbolic link"
                } else {
                    what
                };
                return Err(err(format!(
                    "{} is {what}, not a folder; move it away or choose another --out",
                    Shown(&target)
                )));
            }
            Err(_) => {}
        }
        let parent = target.parent().expect("joined paths have a parent");
        fs::create_dir_all(parent)?;
        root.contain(parent)?;
        let prefix = staging_prefix(&target);
        if let Ok(rd) = fs::read_dir(parent) {
            for e in rd.flatten() {
                let name = e.file_name().to_string_lossy().to_string();
                let stale = name
                    .strip_prefix(&prefix)
                    .and_then(|pid| pid.parse::<u32>().ok())
                    .is_some_and(|pid| !process_alive(pid));
                if stale {
                    let _ = fs::remove_dir_all(e.path());
                }
            }
        }
        let dir = parent.join(format!("{prefix}{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir(&dir)?;
        Ok(Staged {
            root: root.clone(),
            target,
            dir,
            committed: false,
        })
    }

    /// The finished folder this bake replaces.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The folder being written (paths in messages should name [`Staged::target`]).
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// `rel` inside the staging folder, its parent folders created.
    pub fn path(&self, rel: &str) -> io::Result<PathBuf> {
        let p = join_checked(&self.dir, rel, rel == super::STAMP_FILE)?;
        if let Some(parent) = p.parent() {
            fs::create_dir_all(parent)?;
            self.root.contain(parent)?;
        }
        Ok(p)
    }

    /// Puts the new folder in place of the finished one. Top-level items of the old folder
    /// for which `keep` is true (things the previous bake did not write, such as `subset/`
    /// or a user's notes) are moved into the new folder first; everything else of the old
    /// result goes.
    pub fn commit(mut self, keep: impl Fn(&str) -> bool) -> io::Result<()> {
        if let Ok(rd) = fs::read_dir(&self.target) {
            for e in rd.flatten() {
                let name = e.file_name().to_string_lossy().to_string();
                if keep(&name) && !self.dir.join(&name).exists() {
                    fs::rename(e.path(), self.dir.join(&name))?;
                }
            }
        }
        sync_dir(&self.dir);
        if self.target.exists() {
            if !exchange(&self.dir, &self.target)? {
                // No atomic exchange here: move the old folder aside, then the new one in.
                let old = self.dir.with_extension("old");
                fs::rename(&self.target, &old)?;
                fs::rename(&self.dir, &self.target)?;
                let _ = fs::remove_dir_all(&old);
                self.committed = true;
                return Ok(());
            }
            // `dir` now holds the old result.
            let _ = fs::remove_dir_all(&self.dir);
        } else {
            fs::rename(&self.dir, &self.target)?;
        }
        if let Some(p) = self.target.parent() {
            sync_dir(p);
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staged {
    /// An uncommitted bake (failed, interrupted) leaves nothing behind.
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.dir);
        }
    }
}

fn sync_dir(p: &Path) {
    if let Ok(f) = fs::File::open(p) {
        let _ = f.sync_all();
    }
}

/// Atomically swaps two folders (Linux `renameat2(RENAME_EXCHANGE)`); `Ok(false)` where the
/// system or file system cannot.
fn exchange(a: &Path, b: &Path) -> io::Result<bool> {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::ffi::OsStrExt as _;
        let ca = std::ffi::CString::new(a.as_os_str().as_bytes())?;
        let cb = std::ffi::CString::new(b.as_os_str().as_bytes())?;
        // SAFETY: two valid NUL-terminated paths; no memory is shared with the kernel after
        // the call returns.
        let r = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                ca.as_ptr(),
                libc::AT_FDCWD,
                cb.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if r == 0 {
            return Ok(true);
        }
        let e = io::Error::last_os_error();
        match e.raw_os_error() {
            Some(libc::EINVAL) | Some(libc::ENOSYS) | Some(libc::EOPNOTSUPP) => Ok(false),
            _ => Err(e),
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (a, b);
        Ok(false)
    }
}

/// Whether process `pid` is running (a staging folder of a live bake is not stale).
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    // SAFETY: signal 0 only checks that the process exists.
    let r = unsafe { libc::kill(pid as libc::pid_t, 0) };
    r == 0 || io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_stay_inside_the_root() {
        let dir = tempfile::tempdir().unwrap();
        let root = OutRoot::open(&dir.path().join("out")).unwrap();
        assert!(root.join("spec/a.csv").is_ok());
        for bad in [
            "../x",
            "spec/../../x",
            "/abs",
            "a//b",
            ".hidden",
            "a\0b",
            "",
        ] {
            assert!(root.join(bad).is_err(), "{bad:?}");
        }
        assert!(root.join_hidden(".cache/x").is_ok());
        // A link inside the root that points outside it.
        std::os::unix::fs::symlink(dir.path(), dir.path().join("out/escape")).unwrap();
        let p = root.join("escape/x/y.csv").unwrap();
        assert!(root.contain(&p).is_err());
        // The root must be a folder.
        std::fs::write(dir.path().join("file"), b"").unwrap();
        let e = OutRoot::open(&dir.path().join("file"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a file, not a folder"), "{e}");
        let e = OutRoot::open(Path::new("/dev/null"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a character device, not a folder"), "{e}");
    }

    #[test]
    fn staged_folders_replace_in_one_step_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let root = OutRoot::open(dir.path()).unwrap();
        let s = Staged::begin(&root, "spec").unwrap();
        std::fs::write(s.path("a.txt").unwrap(), b"1").unwrap();
        s.commit(|_| false).unwrap();
        assert_eq!(std::fs::read(dir.path().join("spec/a.txt")).unwrap(), b"1");
        std::fs::write(dir.path().join("spec/notes.txt"), b"mine").unwrap();
        // A failed bake: dropped without commit, the finished folder is untouched.
        let s = Staged::begin(&root, "spec").unwrap();
        std::fs::write(s.path("a.txt").unwrap(), b"2").unwrap();
        drop(s);
        assert_eq!(std::fs::read(dir.path().join("spec/a.txt")).unwrap(), b"1");
        // A finished one replaces it and keeps what `keep` names.
        let s = Staged::begin(&root, "spec").unwrap();
        std::fs::write(s.path("b/c.txt").unwrap(), b"3").unwrap();
        s.commit(|n| n == "notes.txt").unwrap();
        assert!(!dir.path().join("spec/a.txt").exists());
        assert_eq!(
            std::fs::read(dir.path().join("spec/b/c.txt")).unwrap(),
            b"3"
        );
        assert_eq!(
            std::fs::read(dir.path().join("spec/notes.txt")).unwrap(),
            b"mine"
        );
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        assert_eq!(names, ["spec"]);
    }
}
