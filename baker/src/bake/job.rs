//! What the bake of one spec works with, whichever its kind.

use std::path::{Path, PathBuf};

use super::destination::Destination;
use super::request::Request;
use crate::pipeline::Runner;

/// What the bake of one spec works with, for either kind.
pub struct Job<'a> {
    pub req: &'a Request,
    /// The spec file as given.
    pub path: &'a Path,
    /// The spec's output folder name.
    pub stem: &'a str,
    pub runner: &'a Runner,
    /// Where the outputs go; `None` for a shard (units only).
    pub out: Option<&'a Destination>,
    /// Recorded once every output is written.
    pub stamp: &'a str,
    /// The first of this spec's entries in `runner.used`.
    pub first_unit: usize,
}

impl Job<'_> {
    /// The sorted keys of the units this spec's bake used.
    pub fn unit_keys(&self) -> Vec<String> {
        super::shard::unit_keys(self.runner, self.first_unit)
    }

    /// Path `rel` inside the folder being written (a shard writes no files).
    pub fn at(&self, rel: &str) -> anyhow::Result<PathBuf> {
        Ok(self
            .out
            .expect("a shard writes no files")
            .staged
            .path(rel)?)
    }

    /// The finished folder's name, for messages.
    pub fn shown(&self) -> PathBuf {
        self.out
            .map_or_else(PathBuf::new, |d| d.staged.target().to_path_buf())
    }
}
