//! The bake as a build tool (issue 9): unit cache, JSON progress, crash safety, shards.
//!
//! - an unchanged re-run does no transport; an edited entry re-bakes only its units (from the
//!   JSON events);
//! - SIGKILL at 20 points of a bake never leaves a table the `formats` readers accept unless
//!   it is complete, and the resumed bake's tables equal an uninterrupted bake byte for byte;
//! - `--shard I/N` + `baker merge` equals one bake byte for byte, N ∈ {1, 3, 4}, skin and fiber.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{baker_in as baker, events, tree};

use common::SMALL_SKIN_SPEC as SKIN;

const FIBER: &str = "version: 1
bake: {resolution_deg: 15, photons_per_direction: 2048, seed: 5}
fibers:
  - {name: trilobal, type: polyester, section: {shape: trilobal}}
  - {name: silk, type: silk, section: {shape: silk}, seed: 2, sections: 2}
";

fn units_with(ev: &[serde_json::Value], kind: &str) -> Vec<String> {
    ev.iter()
        .filter(|e| e["event"] == kind)
        .map(|e| e["unit"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn rerun_is_free_and_an_edit_rebakes_only_its_units() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("skin.yaml"), SKIN).unwrap();
    let bake = |d: &Path| {
        baker(
            d,
            &["bake", "skin.yaml", "--out", "out", "--progress", "json"],
        )
    };
    let first = bake(d);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let ev = events(&first.stderr);
    let computed = units_with(&ev, "unit_finished");
    assert!(!computed.is_empty() && units_with(&ev, "cache_hit").is_empty());
    let before = tree(&d.join("out"));

    // Unchanged: nothing to do (the outputs are verified against the manifest's SHA-256).
    let t0 = Instant::now();
    let again = bake(d);
    let seconds = t0.elapsed().as_secs_f64();
    assert!(again.status.success());
    let ev = events(&again.stderr);
    assert_eq!(units_with(&ev, "unit_started"), Vec::<String>::new());
    assert!(ev.iter().any(|e| e["event"] == "up_to_date"));
    assert_eq!(tree(&d.join("out")), before);
    // An output deleted: rebuilt from the cache, no transport, identical bytes.
    std::fs::remove_file(d.join("out/skin/profiles.bkt")).unwrap();
    let again = bake(d);
    assert!(again.status.success());
    let ev = events(&again.stderr);
    assert_eq!(units_with(&ev, "unit_started"), Vec::<String>::new());
    let mut hits = units_with(&ev, "cache_hit");
    hits.sort();
    // Every unit but the pilot runs, which only choose the packets of main runs to compute.
    let mut all: Vec<String> = computed
        .iter()
        .filter(|u| !u.contains("/pilot/"))
        .cloned()
        .collect();
    all.sort();
    assert_eq!(hits, all);
    assert_eq!(tree(&d.join("out")), before);
    let summary = ev.iter().find(|e| e["event"] == "summary").unwrap();
    assert_eq!(summary["units_computed"], 0);
    eprintln!("unchanged re-run: {seconds:.2} s");

    // Edit one entry (mid80 is alone in its scattering group: age 80 changes the layers).
    std::fs::write(
        d.join("skin.yaml"),
        SKIN.replace("skin_type: III, age: 80", "skin_type: III, age: 70"),
    )
    .unwrap();
    let edited = bake(d);
    assert!(edited.status.success());
    let ev = events(&edited.stderr);
    let started = units_with(&ev, "unit_started");
    assert!(!started.is_empty());
    // mid80 is the third entry and alone in group 1 (light30 and dark30 share group 0).
    for u in &started {
        assert!(
            u.contains("group1/") || u.ends_with("fit/mid80"),
            "unit {u} re-baked although its entry did not change"
        );
    }
    for u in units_with(&ev, "cache_hit") {
        assert!(!u.contains("group1/") && !u.ends_with("fit/mid80"), "{u}");
    }
    assert!(started.iter().any(|u| u.ends_with("fit/mid80")));

    // `plan` agrees: everything is cached now; --force recomputes all.
    let plan = baker(d, &["plan", "skin.yaml", "--out", "out", "--json"]);
    let p: serde_json::Value = serde_json::from_slice(&plan.stdout).unwrap();
    assert_eq!(p["cached"], p["total"]);
    let forced = baker(
        d,
        &[
            "bake",
            "skin.yaml",
            "--out",
            "out",
            "--progress",
            "json",
            "--force",
        ],
    );
    assert!(units_with(&events(&forced.stderr), "cache_hit").is_empty());
}

/// Tables under `out` that a `formats` reader accepts, with their bytes.
fn accepted_tables(out: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v = Vec::new();
    for (rel, bytes) in tree(out) {
        let name = rel.to_string_lossy().to_string();
        let ok = if name.ends_with(".bkt") || bytes.starts_with(b"BAKERTBL") {
            formats::TableFile::from_bytes(&bytes).is_ok()
        } else if name.ends_with(".bcsdf") || bytes.starts_with(b"BAKERFIB") {
            formats::Bcsdf::from_bytes(bytes.clone())
                .map(|t| (0..t.dir.n_wi()).all(|i| t.decode(i).is_ok()))
                .unwrap_or(false)
        } else {
            false
        };
        if ok {
            v.push((rel, bytes));
        }
    }
    v
}

#[test]
fn sigkill_at_any_moment_leaves_no_partial_table_and_resumes_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("skin.yaml"), SKIN).unwrap();
    std::fs::write(d.join("fib.yaml"), FIBER).unwrap();
    let args = ["bake", "skin.yaml", "fib.yaml", "--threads", "2", "-q"];
    // Reference: one uninterrupted bake, timed.
    let t0 = Instant::now();
    let r = baker(d, &[&args[..], &["--out", "ref"]].concat());
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let total = t0.elapsed();
    let reference = tree(&d.join("ref"));
    // 20 kills spread over the bake (a fixed schedule: reproducible), each resuming the last.
    for k in 0..20u32 {
        let delay = total.mul_f64(0.05 + 0.9 * f64::from(k) / 19.0) / 2;
        let mut child = Command::new(env!("CARGO_BIN_EXE_baker"))
            .args(args)
            .args(["--out", "out"])
            .current_dir(d)
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(delay.max(Duration::from_millis(20)));
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        for (rel, bytes) in accepted_tables(&d.join("out")) {
            assert_eq!(
                Some(&bytes),
                reference.get(&rel),
                "kill {k}: {} is accepted by the reader but is not the complete table",
                rel.display()
            );
        }
    }
    // SIGINT: the running units finish, the bake says how to resume and exits with 130.
    std::fs::remove_dir_all(d.join("out")).unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_baker"))
        .args([
            "bake",
            "skin.yaml",
            "fib.yaml",
            "--threads",
            "2",
            "--progress",
            "json",
        ])
        .args(["--out", "out"])
        .current_dir(d)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(total / 3);
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let o = child.wait_with_output().unwrap();
    let ev = events(&o.stderr);
    if o.status.code() == Some(130) {
        let int = ev
            .iter()
            .find(|e| e["event"] == "interrupted")
            .expect("interrupted event");
        assert!(int["resume"].as_str().unwrap().contains("bake"));
        assert!(ev.iter().all(|e| e["event"] != "summary"));
    } else {
        // The bake was already finished when the signal came.
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let resumed = baker(d, &[&args[..], &["--out", "out"]].concat());
    assert!(resumed.status.success());
    let after = tree(&d.join("out"));
    // Temporary files of killed writers may remain (never under a table's name); the
    // tables themselves are identical.
    let tables = |t: &BTreeMap<PathBuf, Vec<u8>>| -> BTreeMap<PathBuf, Vec<u8>> {
        t.iter()
            .filter(|(p, _)| !p.file_name().unwrap().to_string_lossy().starts_with('.'))
            .map(|(p, b)| (p.clone(), b.clone()))
            .collect()
    };
    let reference = tables(&reference);
    assert_eq!(
        tables(&after).keys().collect::<Vec<_>>(),
        reference.keys().collect::<Vec<_>>()
    );
    assert!(
        tables(&after) == reference,
        "resumed tables differ from the reference"
    );
}

#[test]
fn shards_merge_to_the_single_machine_bake() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("skin.yaml"), SKIN).unwrap();
    std::fs::write(d.join("fib.yaml"), FIBER).unwrap();
    let r = baker(
        d,
        &["bake", "skin.yaml", "fib.yaml", "--out", "local", "-q"],
    );
    assert!(r.status.success());
    let local = tree(&d.join("local"));
    for n in [1usize, 3, 4] {
        let mut dirs = Vec::new();
        for i in 1..=n {
            let dir = format!("n{n}-s{i}");
            let shard = format!("{i}/{n}");
            let r = baker(
                d,
                &[
                    "bake",
                    "skin.yaml",
                    "fib.yaml",
                    "--out",
                    &dir,
                    "--shard",
                    &shard,
                    "-q",
                ],
            );
            assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
            // A shard writes units and its manifest, no tables.
            assert!(tree(&d.join(&dir))
                .keys()
                .all(|p| p == Path::new("shard.json")));
            dirs.push(dir);
        }
        let merged = format!("merged{n}");
        let mut args = vec!["merge"];
        args.extend(dirs.iter().map(String::as_str));
        args.extend(["-o", &merged, "-q"]);
        let r = baker(d, &args);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        assert!(
            tree(&d.join(&merged)) == local,
            "N = {n}: merged tables differ"
        );
        // A missing shard is an error naming it.
        if n > 1 {
            let r = baker(d, &["merge", &dirs[0], "-o", "partial", "-q"]);
            assert_eq!(r.status.code(), Some(2));
            assert!(String::from_utf8_lossy(&r.stderr).contains("missing"));
        }
    }
}
