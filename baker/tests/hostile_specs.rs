//! The hostile-spec corpus (`tests/specs/hostile/`, issue "hardening"): every case through
//! both `baker validate` and `baker bake`, each under a 4 GiB address-space limit and a 60 s
//! timeout. For every case and both commands:
//!
//! - no panic, no abort, no death by a signal, no hang;
//! - the exit code the corpus expects (2 for spec errors, with `file:line:column`), the same for
//!   both commands, with the same message;
//! - the words the corpus expects in the message;
//! - nothing created outside `--out` (the working folder, the corpus copy and the escape
//!   folder the path-trick names aim at are compared before and after), no partial file under
//!   `--out`, and nothing at all under `--out` when the spec is rejected.
//!
//! Auxiliary files too large to commit are generated here (`aux: gen:…`), FIFOs and folders
//! made (`fifo:…`, `dir:…`).

use std::collections::BTreeMap;
use std::io::Write as _;
use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

const DIR: &str = "tests/specs/hostile";
const TIMEOUT: Duration = Duration::from_secs(60);
const ADDRESS_SPACE: u64 = 4 << 30;

#[derive(Debug, Clone, serde::Deserialize)]
struct Case {
    case: String,
    spec: String,
    exit: i32,
    contains: Vec<String>,
    #[serde(default)]
    aux: Option<String>,
    /// A file-level error (unreadable, too large): no line to name.
    #[serde(default)]
    no_line: bool,
}

#[derive(Debug, serde::Deserialize)]
struct Corpus {
    escape_dir: PathBuf,
    cases: Vec<Case>,
}

fn corpus() -> Corpus {
    let text = std::fs::read_to_string(repo().join(DIR).join("expected.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// A circle outline of `n` vertices, radius `r_um`, as polygon CSV.
fn circle_csv(n: usize, r_um: f64, swap_at: Option<usize>) -> String {
    let mut v: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            (r_um * a.cos(), r_um * a.sin())
        })
        .collect();
    if let Some(k) = swap_at {
        v.swap(k, k + 1);
    }
    let mut s = String::from("x_um,y_um\n");
    for (x, y) in v {
        s.push_str(&format!("{x},{y}\n"));
    }
    s
}

/// Makes an auxiliary file of the corpus in `dir`.
fn make_aux(dir: &Path, aux: &str) {
    let (kind, name) = aux.split_once(':').unwrap();
    let p = dir.join(name);
    if p.exists() {
        return;
    }
    match kind {
        "dir" => std::fs::create_dir_all(&p).unwrap(),
        "fifo" => {
            let c = std::ffi::CString::new(p.to_str().unwrap()).unwrap();
            // SAFETY: a valid NUL-terminated path.
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        }
        "gen" if name.ends_with(".png") => {
            // 4096² pixels of random noise: one huge outline with millions of holes.
            let mut z = 0x5eed_u64;
            let img = image::GrayImage::from_fn(4096, 4096, |_, _| {
                z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
                let mut x = z;
                x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
                image::Luma([if (x ^ (x >> 31)) & 1 == 0 { 0 } else { 255 }])
            });
            img.save(&p).unwrap();
        }
        "gen" => {
            let text = match name {
                "poly_200k.csv" => circle_csv(200_001, 5.0, None),
                "poly_cross_25k.csv" => circle_csv(25_000, 5.0, Some(12_345)),
                "poly_ok_50k.csv" => circle_csv(50_000, 5.0, None),
                "huge_spec.yaml" => {
                    let line = "# padding of a spec that is far too large\n";
                    line.repeat((17 << 20) / line.len() + 1)
                }
                "many_nodes.yaml" => format!(
                    "wavelengths: {{list_nm: [{}]}}\nentries: []\n",
                    vec!["550"; 300_000].join(", ")
                ),
                "long_name.yaml" => format!(
                    "entries:\n  - {{name: {}, age: 30, gender: female, skin_type: II, \
                     location: forearm, xi: 0.5}}\n",
                    "a".repeat(1_000_000)
                ),
                other => panic!("no generator for {other}"),
            };
            std::fs::write(&p, text).unwrap();
        }
        other => panic!("unknown aux kind {other}"),
    }
}

/// Every regular file and folder under `dir` (FIFOs listed, not read), with bytes.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            let rel = p.strip_prefix(dir).unwrap().to_path_buf();
            let ft = e.file_type().unwrap();
            if ft.is_dir() {
                out.insert(rel, None);
                stack.push(p);
            } else if ft.is_file() {
                out.insert(rel, Some(std::fs::read(&p).unwrap()));
            } else {
                out.insert(rel, Some(b"<special>".to_vec()));
            }
        }
    }
    out
}

struct Run {
    code: Option<i32>,
    signal: Option<i32>,
    stderr: String,
    seconds: f64,
}

/// Runs `baker args` in `cwd` under the address-space limit, killing it after [`TIMEOUT`].
fn run(cwd: &Path, args: &[&str]) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_baker"));
    cmd.args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            let lim = libc::rlimit {
                rlim_cur: ADDRESS_SPACE,
                rlim_max: ADDRESS_SPACE,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let t0 = Instant::now();
    let mut child = cmd.spawn().unwrap();
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        std::io::Read::read_to_end(&mut err, &mut s).ok();
        s
    });
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t0.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let stderr = String::from_utf8_lossy(&reader.join().unwrap()).to_string();
    use std::os::unix::process::ExitStatusExt as _;
    Run {
        code: status.and_then(|s| s.code()),
        signal: status.map_or(Some(libc::SIGKILL), |s| s.signal()),
        stderr,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// `file:line:column:` somewhere in the message.
fn names_a_line(stderr: &str) -> bool {
    stderr.lines().any(|l| {
        let mut parts = l.trim().splitn(4, ':');
        let (_, line, col) = (parts.next(), parts.next(), parts.next());
        matches!((line, col), (Some(a), Some(b)) if a.parse::<u64>().is_ok() && b.trim().parse::<u64>().is_ok())
    })
}

#[test]
fn every_hostile_spec_is_refused_or_baked_safely_by_validate_and_bake() {
    let c = corpus();
    assert!(
        c.cases.len() >= 100,
        "the corpus has {} cases",
        c.cases.len()
    );
    let tmp = tempfile::tempdir().unwrap();
    let specs = tmp.path().join("specs");
    std::fs::create_dir_all(&specs).unwrap();
    for e in std::fs::read_dir(repo().join(DIR)).unwrap().flatten() {
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), specs.join(e.file_name())).unwrap();
        }
    }
    for k in &c.cases {
        if let Some(a) = &k.aux {
            make_aux(&specs, a);
        }
    }
    let _ = std::fs::remove_dir_all(&c.escape_dir);
    let before = snapshot(&specs);

    let problems = std::sync::Mutex::new(Vec::<String>::new());
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(k) = c.cases.get(i) else { break };
                let found = check_case(
                    k,
                    &specs,
                    &tmp.path().join("run").join(&k.case),
                    &c.escape_dir,
                );
                problems.lock().unwrap().extend(found);
            });
        }
    });
    let mut problems = problems.into_inner().unwrap();
    if snapshot(&specs) != before {
        problems.push("the corpus folder (the specs' own folder) was changed".into());
    }
    if c.escape_dir.exists() {
        problems.push(format!("{} was created", c.escape_dir.display()));
    }
    let mut report = std::fs::File::create(
        Path::new(env!("CARGO_TARGET_TMPDIR")).join("hostile_specs_report.txt"),
    )
    .unwrap();
    for p in &problems {
        writeln!(report, "{p}\n").unwrap();
    }
    assert!(
        problems.is_empty(),
        "{} problem(s):\n\n{}",
        problems.len(),
        problems.join("\n\n")
    );
}

/// Both commands on one case; the problems found.
fn check_case(k: &Case, specs: &Path, work: &Path, escape: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    // Deep, so that `../../../x` from `out` still lands inside `work`, where it is seen.
    let cwd = work.join("a/b/c/d");
    std::fs::create_dir_all(&cwd).unwrap();
    let spec = if k.spec.starts_with('/') {
        PathBuf::from(&k.spec)
    } else if k.spec == "." {
        specs.to_path_buf()
    } else {
        specs.join(&k.spec)
    };
    let spec_s = spec.to_str().unwrap().to_string();
    let mut messages = Vec::new();
    for cmd in ["validate", "bake"] {
        let out = cwd.join("out");
        let mut args = vec![cmd, spec_s.as_str()];
        if cmd == "bake" {
            args.extend(["--out", "out", "-q", "--threads", "2"]);
        }
        let r = run(&cwd, &args);
        let tag = format!("{} ({}) `baker {cmd}`", k.case, k.spec);
        let bad_words = [
            "panicked",
            "memory allocation of",
            "RUST_BACKTRACE",
            "stack backtrace",
        ];
        if r.code.is_none() {
            problems.push(format!(
                "{tag}: no exit code (signal {:?}, {:.1} s: a hang or an abort)\n{}",
                r.signal, r.seconds, r.stderr
            ));
            continue;
        }
        if let Some(w) = bad_words.iter().find(|w| r.stderr.contains(*w)) {
            problems.push(format!("{tag}: stderr holds {w:?}\n{}", r.stderr));
        }
        if r.code != Some(k.exit) {
            problems.push(format!(
                "{tag}: exit {:?}, expected {}\n{}",
                r.code, k.exit, r.stderr
            ));
        }
        for w in &k.contains {
            if !r.stderr.contains(w.as_str()) {
                problems.push(format!("{tag}: the message lacks {w:?}\n{}", r.stderr));
            }
        }
        if k.exit == 2 && !k.no_line && !names_a_line(&r.stderr) {
            problems.push(format!(
                "{tag}: the message names no file:line:column\n{}",
                r.stderr
            ));
        }
        // Nothing outside `out`; nothing in `out` unless the bake succeeded, and no partial file.
        let here = snapshot(work);
        for p in here.keys() {
            let inside_out = p.starts_with("a/b/c/d/out");
            let is_parent = Path::new("a/b/c/d").starts_with(p);
            if !inside_out && !is_parent {
                problems.push(format!("{tag}: created {} outside --out", p.display()));
            }
            let name = p.to_string_lossy();
            if name.contains(".partial-") || name.contains(".tmp-") {
                problems.push(format!("{tag}: left a partial file {name}"));
            }
        }
        // A rejected spec writes nothing; a bake that fails later keeps only the cache of the
        // units it finished.
        if r.code != Some(0) && out.exists() {
            let files: Vec<_> = snapshot(&out)
                .into_keys()
                .filter(|p| r.code == Some(2) || !p.starts_with(".cache"))
                .collect();
            if !files.is_empty() {
                problems.push(format!("{tag}: a failed run left {files:?} under --out"));
            }
        }
        if escape.exists() {
            problems.push(format!("{tag}: created {}", escape.display()));
            let _ = std::fs::remove_dir_all(escape);
        }
        messages.push(r.stderr);
    }
    // One validator: the same verdict and, for a spec error, the same message.
    if messages.len() == 2 && k.exit == 2 && messages[0] != messages[1] {
        problems.push(format!(
            "{}: validate and bake disagree:\n--- validate\n{}--- bake\n{}",
            k.case, messages[0], messages[1]
        ));
    }
    let _ = std::fs::remove_dir_all(work);
    problems
}
