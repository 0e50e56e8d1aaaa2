//! Every command in README.md's fenced `sh` and `python` blocks runs, in order, in a fresh
//! folder holding a copy of `specs/`, so the README cannot go stale.
//!
//! What it does with each command:
//! - `baker ARGS` and `cargo run --release -p baker -- ARGS` run this build's `baker` (the
//!   leading `apt-get … &&` of the set-up commands is dropped: the machine has HDF5 already);
//! - `bake` runs with small settings so the test stays quick in a debug build: `--photons
//!   2000` everywhere, and the default specs baked for one entry each (`SMALL_ENTRIES`);
//! - `cargo test --workspace` is this test's own command and is not run again; `cargo install
//!   --path baker` is checked to name the crate with the `baker` binary instead of building it;
//! - `python` blocks run with `python3` when it has h5py; with `BAKER_README_PYTHON=require`
//!   (CI) a missing h5py fails the test instead of skipping them.
//!
//! Then every file the quick start promises must exist. Inline code in the prose and tables is
//! syntax with placeholders (`SPEC…`) and is not run.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Photons per simulation or direction for every bake the README runs.
const SMALL_PHOTONS: &str = "2000";
/// One entry of each default spec: the set-up bake, cut to seconds.
const SMALL_ENTRIES: [(&str, &str); 2] = [
    ("specs/fitzpatrick.yaml", "typeIII_age50_xi0.5"),
    ("specs/fibers.yaml", "polyester"),
];
/// What the quick start says it writes.
const QUICKSTART_FILES: [&str; 12] = [
    "out/quickstart/profiles.h5",
    "out/quickstart/profiles.bkt",
    "out/quickstart/profiles_rgb.exr",
    "out/quickstart/preview",
    "out/quickstart/optics.json",
    "out/quickstart/manifest.json",
    "out/quickstart/skin_blender.py",
    "out/quickstart-fiber/polyester/section-00.bcsdf",
    "out/quickstart-fiber/polyester/polyester.h5",
    "out/quickstart-fiber/preview",
    "out/quickstart-fiber/manifest.json",
    "out/quickstart-fiber/polyester.pbrt",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The fenced blocks of `text` with their info string (`sh`, `python`, …).
fn blocks(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut cur: Option<(String, String)> = None;
    for line in text.lines() {
        match (&mut cur, line.strip_prefix("```")) {
            (None, Some(info)) => cur = Some((info.trim().to_string(), String::new())),
            (Some(_), Some(_)) => out.push(cur.take().unwrap()),
            (Some((_, body)), None) => {
                body.push_str(line);
                body.push('\n');
            }
            (None, None) => {}
        }
    }
    out
}

/// Shell lines of a block, with `\` continuations joined.
fn lines(body: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut acc = String::new();
    for l in body.lines() {
        let l = l.trim_end();
        if let Some(head) = l.strip_suffix('\\') {
            acc.push_str(head);
            continue;
        }
        acc.push_str(l);
        let t = acc.trim().to_string();
        acc.clear();
        if !t.is_empty() && !t.starts_with('#') {
            out.push(t);
        }
    }
    out
}

/// A README command as `baker` arguments, or `None` for the commands not run (see the module
/// docs); panics on a command the test does not know, so a new kind of line gets a rule.
fn baker_args(line: &str) -> Option<Vec<String>> {
    let line = match line.rsplit_once(" && ") {
        Some((head, tail)) if head.starts_with("apt-get ") => tail,
        _ => line,
    };
    let words: Vec<String> = line.split_whitespace().map(str::to_string).collect();
    if line == "cargo test --workspace" {
        return None;
    }
    if line == "cargo install --path baker" {
        let toml = std::fs::read_to_string(root().join("baker/Cargo.toml")).unwrap();
        assert!(
            toml.contains("name = \"baker\"\npath = \"src/main.rs\""),
            "no baker binary"
        );
        return None;
    }
    if line == "bash validation/make_gallery.sh" {
        // The gallery renders in Blender and Mitsuba (minutes): CI runs its parts' quick modes.
        assert!(
            root().join("validation/make_gallery.sh").exists(),
            "no gallery script"
        );
        return None;
    }
    if let Some(rest) = line.strip_prefix("cargo run --release -p baker -- ") {
        return Some(rest.split_whitespace().map(str::to_string).collect());
    }
    assert_eq!(
        words[0], "baker",
        "README command the test has no rule for: {line}"
    );
    Some(words[1..].to_vec())
}

/// `args` with the small settings of a bake.
fn small(mut args: Vec<String>) -> Vec<String> {
    if args[0] != "bake" {
        return args;
    }
    match args.iter().position(|a| a == "--photons") {
        Some(i) => args[i + 1] = SMALL_PHOTONS.into(),
        None => args.extend(["--photons".into(), SMALL_PHOTONS.into()]),
    }
    for (spec, entry) in SMALL_ENTRIES {
        if args.iter().any(|a| a == spec) {
            args.extend(["--entry".into(), entry.into()]);
        }
    }
    args
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let dest = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &dest);
        } else {
            std::fs::copy(e.path(), dest).unwrap();
        }
    }
}

fn python_with_h5py() -> bool {
    Command::new("python3")
        .args(["-c", "import h5py"])
        .status()
        .is_ok_and(|s| s.success())
}

#[test]
fn every_readme_command_runs_and_the_quick_start_writes_what_it_promises() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    copy_dir(&root().join("specs"), &d.join("specs"));
    let python = python_with_h5py();
    if !python {
        let required = std::env::var("BAKER_README_PYTHON").is_ok_and(|v| v == "require");
        assert!(
            !required,
            "BAKER_README_PYTHON=require, but python3 has no h5py"
        );
        eprintln!("readme: python3 has no h5py; the README's python blocks are skipped");
    }
    let mut ran = 0;
    for (info, body) in blocks(&readme) {
        match info.as_str() {
            "sh" => {
                for line in lines(&body) {
                    let Some(args) = baker_args(&line) else {
                        continue;
                    };
                    let args = small(args);
                    let o = Command::new(env!("CARGO_BIN_EXE_baker"))
                        .args(&args)
                        .current_dir(d)
                        .output()
                        .unwrap();
                    assert!(
                        o.status.success(),
                        "README command `{line}` (run as `baker {}`) failed: {}",
                        args.join(" "),
                        String::from_utf8_lossy(&o.stderr)
                    );
                    ran += 1;
                }
            }
            "python" if python => {
                let o = Command::new("python3")
                    .args(["-c", &body])
                    .current_dir(d)
                    .output()
                    .unwrap();
                assert!(
                    o.status.success(),
                    "README python block failed:\n{body}\n{}",
                    String::from_utf8_lossy(&o.stderr)
                );
                ran += 1;
            }
            _ => {}
        }
    }
    assert!(
        ran >= 8,
        "only {ran} README commands found: is the parser broken?"
    );
    for f in QUICKSTART_FILES {
        assert!(
            readme.contains(f.rsplit('/').next().unwrap()),
            "README does not name {f}"
        );
        assert!(
            d.join(f).exists(),
            "the quick start promises {f}; it was not written"
        );
    }
}

#[test]
fn the_parser_finds_commands_and_rejects_unknown_ones() {
    let text =
        "x\n```sh\nbaker bake a.yaml \\\n  --entry b\n# note\n```\n```python\nprint(1)\n```\n";
    let b = blocks(text);
    assert_eq!(b.len(), 2);
    assert_eq!(lines(&b[0].1), ["baker bake a.yaml   --entry b"]);
    assert_eq!(
        small(baker_args("baker bake specs/fibers.yaml").unwrap()),
        [
            "bake",
            "specs/fibers.yaml",
            "--photons",
            "2000",
            "--entry",
            "polyester"
        ]
    );
    assert!(baker_args("cargo test --workspace").is_none());
    assert!(std::panic::catch_unwind(|| baker_args("rm -rf /")).is_err());
}
