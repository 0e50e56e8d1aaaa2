//! Helpers shared by the integration tests that run the `baker` binary (each test file uses
//! some of them).
#![allow(dead_code)]

pub mod cylinder;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// A small skin spec: three entries in two simulation groups, two wavelengths, 3,000 photons.
pub const SMALL_SKIN_SPEC: &str = "version: 1
wavelengths: {start_nm: 450, stop_nm: 650, step_nm: 100}
defaults: {model: five_layer, gender: female, location: forearm}
profiles: {photons: 3000, seed: 11}
entries:
  - {name: light30, skin_type: I, age: 30, xi: 0}
  - {name: dark30, skin_type: VI, age: 30, xi: 0}
  - {name: mid80, skin_type: III, age: 80, xi: 1}
";

/// The repository root: specs and fixtures are named relative to it.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The data rows of a fixture CSV under the repository root (the baker's CSV dialect:
/// `#` comment lines), without its column-name row.
pub fn fixture_rows(rel: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(repo().join(rel)).unwrap();
    baker::files::csv_rows::rows(&text)
        .skip(1)
        .map(|r| r.unwrap().fields.iter().map(str::to_string).collect())
        .collect()
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

/// Runs the `baker` binary in `dir`.
pub fn baker_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_baker"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .expect("baker runs")
}

/// Writes `yaml` to `dir/<name>.yaml`, bakes it quietly with `threads` worker threads into
/// `dir/out-<name>-<threads>` (the bake must succeed) and returns the spec's output folder.
pub fn bake_spec(dir: &Path, name: &str, yaml: &str, threads: usize) -> PathBuf {
    let spec = dir.join(format!("{name}.yaml"));
    std::fs::write(&spec, yaml).unwrap();
    let out = dir.join(format!("out-{name}-{threads}"));
    let o = baker_in(
        dir,
        &[
            "bake",
            "--quiet",
            "--threads",
            &threads.to_string(),
            "--out",
            out.to_str().unwrap(),
            spec.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    out.join(name)
}

/// Every file under `dir` (relative path → bytes), leaving out the cache, wall-clock
/// `timing.json` and the private staging folder of a bake that was killed
/// (`.<spec>.partial-<pid>`: never a final name; the next bake removes it).
pub fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        // A bake killed early may not have created the directory yet.
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().to_string();
            if name == ".cache" || name == "timing.json" || name.contains(".partial-") {
                continue;
            }
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

/// JSON events of a `--progress json` run.
pub fn events(stderr: &[u8]) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(stderr)
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}
