//! The broken-spec corpus (`tests/specs/broken/`, issue "production pipelines"): every file is
//! rejected by `baker validate` and `baker bake` with exit code 2 (a spec error), an error that
//! names `file:line`, the field and what the field allows, nothing on stdout, and `--out`
//! left exactly as it was.
//!
//! The expected line, field and allowed values of each file are in
//! `tests/specs/broken/expected.json`; the first line of each file says what is broken.
//! Spec errors are found before any transport starts: `validate` runs first, and `bake` only
//! when `validate` rejected the spec, so a case that stops failing cannot start a bake. Both
//! share one validator: their messages must be identical (issue "hardening").

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::SystemTime;

use common::{baker, repo, stderr};

const DIR: &str = "tests/specs/broken";

/// Exit code of a user error (bad spec, bad flags); 1 is left to failures while baking.
const SPEC_ERROR_EXIT: i32 = 2;

#[derive(Debug, serde::Deserialize)]
struct Case {
    file: String,
    line: u64,
    /// The field as the message names it: the message starts with it.
    field: String,
    /// Part of the same message saying what the field allows.
    allowed: String,
}

#[derive(Debug, serde::Deserialize)]
struct Expected {
    cases: Vec<Case>,
}

fn cases() -> Vec<Case> {
    let text = std::fs::read_to_string(repo().join(DIR).join("expected.json")).unwrap();
    serde_json::from_str::<Expected>(&text).unwrap().cases
}

/// Every file under `dir` with its bytes and modification time, and every folder.
type Snapshot = BTreeMap<PathBuf, Option<(Vec<u8>, SystemTime)>>;

fn snapshot(dir: &Path) -> Snapshot {
    fn walk(root: &Path, dir: &Path, out: &mut Snapshot) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().to_path_buf();
            if p.is_dir() {
                out.insert(rel, None);
                walk(root, &p, out);
            } else {
                let m = std::fs::metadata(&p).unwrap().modified().unwrap();
                out.insert(rel, Some((std::fs::read(&p).unwrap(), m)));
            }
        }
    }
    let mut out = Snapshot::new();
    walk(dir, dir, &mut out);
    out
}

/// An output folder as a pipeline leaves it: a sentinel and an earlier bake of this spec.
fn existing_out(root: &Path, stem: &str) -> PathBuf {
    let out = root.join("out");
    std::fs::create_dir_all(out.join(stem)).unwrap();
    std::fs::write(out.join("sentinel.txt"), "left by an earlier step\n").unwrap();
    std::fs::write(
        out.join(stem).join("profiles.bkt"),
        b"BKT\0earlier table\x01\x02",
    )
    .unwrap();
    std::fs::write(out.join(stem).join("manifest.json"), "{\"entries\": []}\n").unwrap();
    out
}

/// What is wrong with `o` as the answer to `case` (empty: nothing).
fn problems(cmd: &str, spec: &str, case: &Case, o: &Output) -> Vec<String> {
    let mut p = Vec::new();
    let err = stderr(o);
    if o.status.code() != Some(SPEC_ERROR_EXIT) {
        p.push(format!(
            "exit code {:?}, expected {SPEC_ERROR_EXIT}",
            o.status.code()
        ));
    }
    if !o.stdout.is_empty() {
        p.push(format!(
            "stdout not empty: {}",
            String::from_utf8_lossy(&o.stdout)
        ));
    }
    // The error at file:line:column whose message starts with the field and says what is
    // allowed.
    let at = format!("{spec}:{}:", case.line);
    let found = err.lines().any(|l| {
        let Some(rest) = l.trim_start().strip_prefix(&at) else {
            return false;
        };
        let Some((col, msg)) = rest.split_once(": ") else {
            return false;
        };
        let after = msg.strip_prefix(&case.field).and_then(|r| r.chars().next());
        col.chars().all(|c| c.is_ascii_digit())
            && matches!(after, Some(':' | ' ' | ','))
            && msg.contains(&case.allowed)
    });
    if !found {
        p.push(format!(
            "no error line `{at}COL: {} …{}…`",
            case.field, case.allowed
        ));
    }
    p.into_iter()
        .map(|m| format!("{cmd} {spec}: {m}\n--- stderr:\n{err}"))
        .collect()
}

#[test]
fn every_broken_spec_names_file_line_field_and_allowed_values_and_touches_nothing() {
    let cases = cases();
    let mut failures = Vec::new();
    for case in &cases {
        let spec = format!("{DIR}/{}", case.file);
        let o = baker(&["validate", &spec]);
        let bad = problems("validate", &spec, case, &o);
        let accepted = o.status.success();
        failures.extend(bad);
        if accepted {
            // Baking an accepted spec would start a real bake.
            continue;
        }
        let tmp = tempfile::tempdir().unwrap();
        let stem = Path::new(&case.file).file_stem().unwrap().to_str().unwrap();
        let out = existing_out(tmp.path(), stem);
        let before = snapshot(tmp.path());
        let ob = baker(&["bake", &spec, "--out", out.to_str().unwrap()]);
        failures.extend(problems("bake", &spec, case, &ob));
        // One validator: bake rejects with validate's very words.
        if stderr(&ob) != stderr(&o) {
            failures.push(format!(
                "{spec}: validate and bake disagree:\n--- validate\n{}--- bake\n{}",
                stderr(&o),
                stderr(&ob)
            ));
        }
        let after = snapshot(tmp.path());
        if after != before {
            let changed: Vec<_> = before
                .keys()
                .chain(after.keys())
                .filter(|k| before.get(*k) != after.get(*k))
                .collect();
            failures.push(format!("bake {spec}: --out changed: {changed:?}"));
        }
    }
    assert!(
        failures.is_empty(),
        "{} problem(s):\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

#[test]
fn the_corpus_covers_skin_and_fiber_specs_and_says_what_each_file_breaks() {
    let cases = cases();
    let listed: Vec<&str> = cases.iter().map(|c| c.file.as_str()).collect();
    let mut files: Vec<String> = std::fs::read_dir(repo().join(DIR))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|f| f.ends_with(".yaml"))
        .collect();
    files.sort();
    for f in &files {
        assert!(listed.contains(&f.as_str()), "{f} is not in expected.json");
        let text = std::fs::read_to_string(repo().join(DIR).join(f)).unwrap();
        assert!(
            text.starts_with("# Broken: ") && text.lines().next().unwrap().contains("Error: "),
            "{f}: the first line must say what is broken and what the error contains"
        );
    }
    for c in &cases {
        assert!(files.contains(&c.file), "{} is listed but missing", c.file);
    }
    let fibers = files.iter().filter(|f| f.starts_with("fiber_")).count();
    assert!(files.len() >= 30, "{} cases", files.len());
    assert!(fibers >= 10 && files.len() - fibers >= 10);
    for kind in ["syntax", "type", "range", "unknown", "conflict", "missing"] {
        assert!(
            files.iter().any(|f| f.contains(&format!("_{kind}_"))),
            "no {kind} case"
        );
    }
}
