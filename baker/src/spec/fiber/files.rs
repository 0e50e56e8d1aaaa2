//! Files a fiber spec names (section outlines and masks, dye spectra): relative to the spec's
//! folder, and reported, when missing or a folder, against the line that names them with what
//! they should contain.

use std::path::{Path, PathBuf};

use super::FiberCx;
use crate::spec::check::loc;
use crate::spec::yaml::Spanned;

impl FiberCx {
    /// The file a spec names, relative to the spec's folder; a missing one is reported with
    /// what it should contain.
    pub(super) fn data_file(
        &mut self,
        name: &Spanned<String>,
        field: &str,
        dir: &Path,
        what: &str,
    ) -> Option<PathBuf> {
        let file = dir.join(&name.value);
        match std::fs::metadata(&file) {
            Ok(m) if !m.is_dir() => return Some(file),
            Ok(_) => {
                self.invalid(
                    loc(name),
                    field,
                    format!("{}: is a directory; expected {what}", file.display()),
                );
                return None;
            }
            Err(_) => {}
        }
        self.invalid(
            loc(name),
            field,
            format!(
                "{}: no such file (paths are relative to the spec's folder); expected {what}",
                file.display()
            ),
        );
        None
    }
}
