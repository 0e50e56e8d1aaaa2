//! Helpers shared by the integration tests that run the `baker` binary.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root: specs and fixtures are named relative to it.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Runs the `baker` binary in the repository root.
pub fn baker(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_baker"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("baker runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}
