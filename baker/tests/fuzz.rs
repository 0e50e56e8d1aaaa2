//! Fuzzing (issue "hardening"), as proptest harnesses that CI runs: the YAML resolver and both
//! table readers get thousands of mutated inputs each, and must answer every one with a value
//! or a typed error — no panic, no abort, no hang (each input within 2 s).
//!
//! - Resolver: every spec of the repository's corpora (shipped, test, broken, hostile),
//!   mutated by bytes, lines and tokens (numbers swapped for extremes, names for path tricks),
//!   then `spec::load_any_str` and, when it resolves, `spec::budget::check`.
//! - Readers: baked-in-process `.bkt` and `.bcsdf` tables, mutated raw or re-encoded with
//!   consistent checksums around NaN, infinite and absurd values, then every reader call
//!   (`TableIndex`, `ProfileTable` with `verify`, lookups; `Bcsdf` with `verify`, `eval`,
//!   `sample`, `pdf`).
//!
//! CI runs 20,000 inputs per target; `BAKER_FUZZ_CASES=200000 cargo test --release -p baker
//! --test fuzz -- --nocapture` runs more and prints the count.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use proptest::prelude::*;

static RESOLVED: AtomicUsize = AtomicUsize::new(0);
static READ: AtomicUsize = AtomicUsize::new(0);

fn cases() -> u32 {
    std::env::var("BAKER_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000)
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The seed corpus: every spec in the repository (path, text).
fn seeds() -> &'static [(PathBuf, String)] {
    static SEEDS: std::sync::OnceLock<Vec<(PathBuf, String)>> = std::sync::OnceLock::new();
    SEEDS.get_or_init(|| {
        let mut v = Vec::new();
        for dir in [
            "specs",
            "tests/specs",
            "tests/specs/broken",
            "tests/specs/hostile",
            "tests/specs/bad",
        ] {
            let d = repo().join(dir);
            for e in std::fs::read_dir(&d).unwrap().flatten() {
                let p = e.path();
                if p.extension().is_some_and(|x| x == "yaml") {
                    if let Ok(t) = std::fs::read_to_string(&p) {
                        if t.len() < 200_000 {
                            v.push((p, t));
                        }
                    }
                }
            }
        }
        v.sort();
        assert!(v.len() > 100, "{} seeds", v.len());
        v
    })
}

const EXTREMES: [&str; 16] = [
    "0",
    "-1",
    "1e300",
    "-1e300",
    "1e-300",
    ".nan",
    ".inf",
    "-.inf",
    "4294967296",
    "1e12",
    "18446744073709551616",
    "0.5",
    "\"\"",
    "[]",
    "{}",
    "~",
];
const NAMES: [&str; 10] = [
    "../../x",
    "/tmp/baker_fuzz_escape/x",
    "\"\"",
    "..",
    "\"a\\0b\"",
    ".h",
    "con",
    "\"a/b\"",
    "\"é\"",
    "-x",
];
const SYMBOLS: &[u8] = b":{}[],-&*!#'\"\n\t .0123456789e|>%@`?";

#[derive(Debug, Clone)]
enum Edit {
    Flip(usize, u8),
    Insert(usize, u8),
    Delete(usize, usize),
    DupLine(usize),
    DropLine(usize),
    SwapLines(usize, usize),
    Number(usize, usize),
    Name(usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Flip(i, b)),
        (any::<usize>(), any::<usize>())
            .prop_map(|(i, k)| Edit::Insert(i, SYMBOLS[k % SYMBOLS.len()])),
        (any::<usize>(), 1usize..40).prop_map(|(i, n)| Edit::Delete(i, n)),
        any::<usize>().prop_map(Edit::DupLine),
        any::<usize>().prop_map(Edit::DropLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Edit::SwapLines(a, b)),
        (any::<usize>(), any::<usize>()).prop_map(|(i, k)| Edit::Number(i, k)),
        (any::<usize>(), any::<usize>()).prop_map(|(i, k)| Edit::Name(i, k)),
    ]
}

fn apply(text: &str, e: &Edit) -> String {
    let mut b = text.as_bytes().to_vec();
    let lines =
        |t: &[u8]| -> Vec<Vec<u8>> { t.split(|&c| c == b'\n').map(<[u8]>::to_vec).collect() };
    match *e {
        Edit::Flip(i, x) if !b.is_empty() => {
            let i = i % b.len();
            b[i] ^= x | 1;
        }
        Edit::Insert(i, x) => {
            let i = i % (b.len() + 1);
            b.insert(i, x);
        }
        Edit::Delete(i, n) if !b.is_empty() => {
            let i = i % b.len();
            b.drain(i..(i + n).min(b.len()));
        }
        Edit::DupLine(i) | Edit::DropLine(i) => {
            let mut l = lines(&b);
            let k = i % l.len();
            if matches!(e, Edit::DupLine(_)) {
                let x = l[k].clone();
                l.insert(k, x);
            } else {
                l.remove(k);
            }
            b = l.join(&b'\n');
        }
        Edit::SwapLines(x, y) => {
            let mut l = lines(&b);
            let n = l.len();
            l.swap(x % n, y % n);
            b = l.join(&b'\n');
        }
        Edit::Number(i, k) | Edit::Name(i, k) => {
            // The i-th number (or value after `name:`) replaced.
            let s = String::from_utf8_lossy(&b).to_string();
            let spans: Vec<(usize, usize)> = if matches!(e, Edit::Number(..)) {
                let mut v = Vec::new();
                let bytes = s.as_bytes();
                let mut j = 0;
                while j < bytes.len() {
                    if bytes[j].is_ascii_digit() {
                        let st = j;
                        while j < bytes.len() && (bytes[j].is_ascii_digit() || bytes[j] == b'.') {
                            j += 1;
                        }
                        v.push((st, j));
                    }
                    j += 1;
                }
                v
            } else {
                s.match_indices("name: ")
                    .map(|(st, m)| {
                        let a = st + m.len();
                        let end = s[a..].find([',', '}', '\n']).map_or(s.len(), |x| a + x);
                        (a, end)
                    })
                    .collect()
            };
            if spans.is_empty() {
                return s;
            }
            let (a, z) = spans[i % spans.len()];
            let rep = if matches!(e, Edit::Number(..)) {
                EXTREMES[k % EXTREMES.len()]
            } else {
                NAMES[k % NAMES.len()]
            };
            return format!("{}{rep}{}", &s[..a], &s[z..]);
        }
        _ => {}
    }
    String::from_utf8_lossy(&b).to_string()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn the_resolver_answers_every_mutated_spec(seed in any::<usize>(), edits in prop::collection::vec(edit(), 1..6)) {
        let (path, text) = &seeds()[seed % seeds().len()];
        let mut t = text.clone();
        for e in &edits {
            t = apply(&t, e);
        }
        let dir = path.parent().unwrap();
        let t0 = Instant::now();
        if let Ok(spec) = baker::spec::load_any_str("fuzz.yaml", &t, dir) {
            let _ = baker::spec::budget::check(&spec, &baker::spec::budget::Overrides { threads: 2, ..Default::default() });
        }
        RESOLVED.fetch_add(1, Ordering::Relaxed);
        prop_assert!(t0.elapsed() < Duration::from_secs(2), "{:?} took {:?}:\n{t}", path, t0.elapsed());
        prop_assert!(!Path::new("/tmp/baker_fuzz_escape").exists());
    }
}

/// A small profile table and a small BCSDF table, baked by the library itself.
fn tables() -> &'static (Vec<u8>, Vec<u8>) {
    static T: std::sync::OnceLock<(Vec<u8>, Vec<u8>)> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(
            d.join("s.yaml"),
            "wavelengths: {list_nm: [450, 550, 650]}\nprofiles: {photons: 500, gaussians: 2}\n\
             entries:\n  - {name: a, age: 30, gender: female, skin_type: II, location: forearm, xi: 0.5}\n",
        )
        .unwrap();
        std::fs::write(
            d.join("f.yaml"),
            "bake: {resolution_deg: 30, photons_per_direction: 256}\nfibers:\n  - {name: t, type: polyester, section: {shape: trilobal}, sweep: {dyes: [disperse_red_1], depth_of_shade_percent: [1], undyed: true}}\n",
        )
        .unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_baker"))
            .args(["bake", "s.yaml", "f.yaml", "--out", "out", "-q"])
            .current_dir(d)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            std::fs::read(d.join("out/s/profiles.bkt")).unwrap(),
            std::fs::read(d.join("out/f/t/section-00.bcsdf")).unwrap(),
        )
    })
}

/// Re-encodes a table's directory JSON with one value replaced (lengths and checksums kept
/// consistent, so the readers' semantic checks are reached).
fn consistent(file: &[u8], k: usize, value: serde_json::Value) -> Vec<u8> {
    let u64_at = |o: usize| u64::from_le_bytes(file[o..o + 8].try_into().unwrap()) as usize;
    let dc = u64_at(16);
    let Ok(json) = zstd::bulk::decompress(&file[48..48 + dc], u64_at(24)) else {
        return file.to_vec();
    };
    let Ok(mut dir) = serde_json::from_slice::<serde_json::Value>(&json) else {
        return file.to_vec();
    };
    // The k-th leaf of the directory (modulo their count).
    fn count(v: &serde_json::Value) -> usize {
        match v {
            serde_json::Value::Object(m) => m.values().map(count).sum(),
            serde_json::Value::Array(a) => a.iter().map(count).sum(),
            _ => 1,
        }
    }
    fn replace(v: &mut serde_json::Value, k: &mut usize, value: &serde_json::Value) -> bool {
        match v {
            serde_json::Value::Object(m) => m.values_mut().any(|x| replace(x, k, value)),
            serde_json::Value::Array(a) => a.iter_mut().any(|x| replace(x, k, value)),
            leaf => {
                if *k == 0 {
                    *leaf = value.clone();
                    return true;
                }
                *k -= 1;
                false
            }
        }
    }
    let mut i = k % count(&dir).max(1);
    replace(&mut dir, &mut i, &value);
    let json = serde_json::to_vec(&dir).unwrap();
    let frame = zstd::bulk::compress(&json, 1).unwrap();
    let payload = &file[48 + dc..];
    let mut out = file[..16].to_vec();
    out.extend_from_slice(&(frame.len() as u64).to_le_bytes());
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&formats::table::crc32(&json).to_le_bytes());
    out.extend_from_slice(&file[44..48]);
    out.extend_from_slice(&frame);
    out.extend_from_slice(payload);
    out
}

#[derive(Debug, Clone)]
enum Damage {
    Bytes(Vec<(usize, u8)>),
    Truncate(usize),
    Json(usize, u8),
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        prop::collection::vec((any::<usize>(), any::<u8>()), 1..8).prop_map(Damage::Bytes),
        any::<usize>().prop_map(Damage::Truncate),
        (any::<usize>(), any::<u8>()).prop_map(|(k, v)| Damage::Json(k, v)),
    ]
}

fn damaged(file: &[u8], d: &Damage) -> Vec<u8> {
    match d {
        Damage::Bytes(v) => {
            let mut b = file.to_vec();
            for &(i, x) in v {
                let n = b.len();
                b[i % n] ^= x | 1;
            }
            b
        }
        Damage::Truncate(i) => file[..i % file.len()].to_vec(),
        Damage::Json(k, v) => {
            let value = match v % 8 {
                0 => serde_json::json!(f64::MAX),
                1 => serde_json::json!(-1),
                2 => serde_json::json!(u64::MAX),
                3 => serde_json::json!("NaN"),
                4 => serde_json::json!(null),
                5 => serde_json::json!([]),
                6 => serde_json::json!(1e300),
                _ => serde_json::json!(0),
            };
            consistent(file, *k, value)
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn the_readers_answer_every_damaged_table(which in 0usize..2, d in damage(), q in prop::collection::vec(-1.0f64..1.0, 8)) {
        let (bkt, bcsdf) = tables();
        let t0 = Instant::now();
        if which == 0 {
            let b = damaged(bkt, &d);
            let _ = formats::TableIndex::from_bytes(b.clone()).map(|t| t.verify());
            if let Ok(t) = formats::ProfileTable::from_bytes(b) {
                let _ = t.verify();
                for e in t.entries().iter().map(|e| e.name.clone()).collect::<Vec<_>>() {
                    let _ = t.rd_rgb(&e, q[0].abs() * 10.0);
                    let _ = t.albedo_rgb(&e);
                    let _ = t.gaussians(&e);
                }
            }
        } else {
            let b = damaged(bcsdf, &d);
            if let Ok(t) = formats::Bcsdf::from_bytes(b) {
                let _ = t.verify();
                let wi = [q[0], q[1], q[2]];
                let wo = [q[3], q[4], q[5]];
                for v in 0..3 {
                    let _ = t.eval(wi, wo, v);
                    let _ = t.pdf(wi, wo, v);
                    let _ = t.sample(wi, v, q[6].abs(), q[7].abs());
                }
                let _ = t.albedo(wi, 0);
            }
        }
        READ.fetch_add(1, Ordering::Relaxed);
        prop_assert!(t0.elapsed() < Duration::from_secs(2));
    }
}

#[test]
fn zz_report_counts() {
    // Runs after the others in name order when single-threaded; a report, not a check.
    eprintln!(
        "fuzz: {} specs resolved, {} tables read (this process)",
        RESOLVED.load(Ordering::Relaxed),
        READ.load(Ordering::Relaxed)
    );
}
