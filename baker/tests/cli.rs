//! End-to-end tests of the `baker` binary: spec errors, `optics` outputs, `bake`.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{baker, baker_in, repo, stderr};

/// A bad spec exits non-zero and names file:line:column, the field and the allowed values.
#[track_caller]
fn rejects(spec: &str, expect: &[&str]) {
    for cmd in ["validate", "optics"] {
        let o = baker(&[cmd, spec]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{cmd} {spec} should fail with exit code 2"
        );
        let e = stderr(&o);
        for needle in expect {
            assert!(
                e.contains(needle),
                "{cmd} {spec}: {needle:?} missing from:\n{e}"
            );
        }
        assert!(
            o.stdout.is_empty(),
            "nothing printed on stdout for a bad spec"
        );
    }
}

#[test]
fn typo_names_the_unknown_field_and_its_line() {
    rejects(
        "tests/specs/bad/typo.yaml",
        &[
            "tests/specs/bad/typo.yaml:3:5",
            "agee: unknown field; did you mean \"age\"?",
            "age",
        ],
    );
}

#[test]
fn negative_age_names_the_allowed_range() {
    rejects(
        "tests/specs/bad/negative_age.yaml",
        &["negative_age.yaml:3:", "age = -5", "[18, 90]"],
    );
}

#[test]
fn xi_above_one_names_the_allowed_range() {
    rejects(
        "tests/specs/bad/xi_out_of_range.yaml",
        &["xi_out_of_range.yaml:7:", "xi = 1.5", "[0, 1]"],
    );
}

#[test]
fn unknown_skin_type_lists_the_types() {
    rejects(
        "tests/specs/bad/unknown_skin_type.yaml",
        &[
            "unknown_skin_type.yaml:5:",
            "skin_type = VII",
            "I, II, III, IV, V, VI",
        ],
    );
}

#[test]
fn missing_spec_file_is_an_error() {
    let o = baker(&["validate", "tests/specs/does_not_exist.yaml"]);
    assert_ne!(o.status.code(), Some(0));
    assert!(stderr(&o).contains("does_not_exist.yaml"));
}

#[test]
fn validate_lists_every_entry_of_the_default_spec() {
    let o = baker(&["validate", "tests/specs/optics_examples.yaml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(out.contains("ok, 109 entries"), "{out}");
    assert!(out.contains("female_forearm_typeVI_age80_xi0.5"));
}

#[test]
fn optics_json_is_a_valid_document_with_named_layers() {
    let o = baker(&["optics", "tests/specs/optics_examples.yaml", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc = formats::OpticsDocument::from_json(std::str::from_utf8(&o.stdout).unwrap()).unwrap();
    assert_eq!(doc.lambda_nm.len(), 31);
    assert_eq!(doc.entries.len(), 109);
    let e = doc.entry("fig35_female_type2_age30").unwrap();
    let names: Vec<&str> = e.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "stratum corneum",
            "living epidermis",
            "papillary dermis",
            "reticular dermis",
            "hypodermis"
        ]
    );
    assert_eq!(e.inputs["age_years"], 30.0);
    assert_eq!(e.inputs["gender"], "female");
    assert!(e.surface.beckmann_m > 0.0 && e.junction.amplitude_mm > 0.0);
}

#[test]
fn optics_single_entry_csv_plot_and_mci() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let out = format!("{d}/optics");
    let (csv, plots, mci) = (
        out.clone(),
        out.clone(),
        format!("{out}/fig35_female_type2_age30_550nm.mci"),
    );
    let o = baker(&[
        "optics",
        "tests/specs/optics_examples.yaml",
        "--entry",
        "fig35_female_type2_age30",
        "--csv",
        "--plots",
        "--mci",
        "550",
        "-o",
        &out,
        "--photons",
        "20000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(format!("{csv}/fig35_female_type2_age30.csv")).unwrap();
    let rows: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(rows.len(), 32, "header + 31 wavelengths");
    assert!(rows[0].starts_with("lambda_nm,mua_stratum_corneum_per_mm,musp_stratum_corneum_per_mm"));
    for suffix in ["mua", "musp"] {
        let png = std::fs::read(format!("{plots}/fig35_female_type2_age30_{suffix}.png")).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert!(png.len() > 10_000, "a real plot, not an empty image");
    }
    // MCML reads: version, runs, output name, photons, dz dr, nz nr na, layers, n above,
    // one line per layer (n mua mus g d, cm units), n below.
    let mci = std::fs::read_to_string(&mci).unwrap();
    let data: Vec<Vec<f64>> = mci
        .lines()
        .map(|l| l.split('#').next().unwrap().trim())
        .filter(|l| !l.is_empty())
        .filter_map(|l| {
            l.split_whitespace()
                .map(|t| t.parse::<f64>().ok())
                .collect::<Option<Vec<f64>>>()
        })
        .collect();
    assert_eq!(data[2], [20000.0]);
    assert_eq!(data[5], [5.0], "5 layers");
    let layers = &data[7..12];
    assert!(
        (layers[0][0] - 1.53).abs() < 1e-12 && (layers[0][4] - 0.002).abs() < 1e-9,
        "SC: n 1.53, 20 µm"
    );
    assert!(layers
        .iter()
        .all(|l| l.len() == 5 && l[3] == 0.0 && l[1] > 0.0 && l[2] > 0.0));
    assert_eq!(data[12], [1.44]);
}

#[test]
fn mci_off_grid_wavelength_is_a_clear_error() {
    let o = baker(&[
        "optics",
        "tests/specs/optics_examples.yaml",
        "--entry",
        "fig35_female_type2_age30",
        "--mci",
        "555",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not on the spec's wavelength grid"));
}

#[test]
fn unknown_entry_suggests_the_nearest_entries_not_all_109() {
    let o = baker(&[
        "optics",
        "tests/specs/optics_examples.yaml",
        "--entry",
        "nobody",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("none of the 109 entries is close"), "{e}");
    assert!(!e.contains("fig35_female_type2_age30"), "{e}");
    let o = baker(&[
        "optics",
        "tests/specs/optics_examples.yaml",
        "--entry",
        "fig35_female_type2_age3",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("did you mean \"fig35_female_type2_age30\"? (109 entries;"),
        "{e}"
    );
}

#[test]
fn bake_writes_the_optics_document_and_csvs_atomically() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = baker(&[
        "bake",
        "tests/specs/optics_examples.yaml",
        "--optics-only",
        "--out",
        out,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json = std::fs::read_to_string(dir.path().join("optics_examples/optics.json")).unwrap();
    let doc = formats::OpticsDocument::from_json(&json).unwrap();
    assert_eq!(doc.entries.len(), 109);
    let csvs = std::fs::read_dir(dir.path().join("optics_examples/optics"))
        .unwrap()
        .count();
    assert_eq!(csvs, 109);
    let leftovers: Vec<_> = walk(dir.path())
        .into_iter()
        .filter(|p| p.to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn bake_with_a_bad_spec_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = baker(&[
        "bake",
        "tests/specs/optics_examples.yaml",
        "tests/specs/bad/typo.yaml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists(), "nothing is written when any spec is invalid");
}

fn walk(p: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(p).unwrap().flatten() {
        let path = e.path();
        if path.is_dir() {
            out.extend(walk(&path));
        } else {
            out.push(path);
        }
    }
    out
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn mc_json_has_every_documented_key() {
    let v = json(&baker(&[
        "mc",
        "tests/stacks/mcml_benchmark.json",
        "--photons",
        "20000",
        "--seed",
        "3",
        "--json",
    ]));
    for key in [
        "rsp",
        "rd",
        "rd_unscattered",
        "tt",
        "absorbed",
        "r_mm",
        "rd_r_per_mm2",
        "rsp_se",
        "rd_se",
        "rd_unscattered_se",
        "tt_se",
        "absorbed_se",
        "rd_r_per_mm2_se",
        "photons",
        "threads",
        "photons_per_s",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["photons"], 20000);
    assert_eq!(v["r_mm"].as_array().unwrap().len(), 100);
    // Same seed, different thread count: identical numbers.
    let w = json(&baker(&[
        "mc",
        "tests/stacks/mcml_benchmark.json",
        "--photons",
        "20000",
        "--seed",
        "3",
        "--threads",
        "1",
        "--json",
    ]));
    assert_eq!(v["rd"], w["rd"]);
    assert_eq!(v["rd_r_per_mm2"], w["rd_r_per_mm2"]);
}

#[test]
fn mc_takes_a_skin_spec_entry_and_a_wavelength() {
    let v = json(&baker(&[
        "mc",
        "--spec",
        "tests/specs/optics_examples.yaml",
        "--entry",
        "fig35_female_type2_age30",
        "--lambda-nm",
        "550",
        "--photons",
        "5000",
        "--json",
    ]));
    assert_eq!(v["absorbed"].as_array().unwrap().len(), 5);
    assert!((v["rsp"].as_f64().unwrap() - ((1.53f64 - 1.0) / 2.53).powi(2)).abs() < 1e-12);
}

#[test]
fn mc_rejects_a_bad_stack_with_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.json");
    std::fs::write(&p, r#"{"n_above": 1, "n_below": 1, "layers": [{"d_mm": 0.1, "eta": 1.4, "mua_per_mm": -1, "mus_per_mm": 1, "g": 0}]}"#).unwrap();
    let o = baker(&["mc", p.to_str().unwrap(), "--photons", "10"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("mua_per_mm = -1"), "{}", stderr(&o));
}

/// `--mci-in` runs every run of an MCML input file and writes MCML's `.mco` format; the file has
/// MCML's sections in CONV's order with the right number of values, and is self-consistent.
#[test]
fn mc_reads_mci_and_writes_mco() {
    let dir = tempfile::tempdir().unwrap();
    let mci = dir.path().join("two_runs.mci");
    std::fs::copy(repo().join("tests/stacks/two_runs.mci"), &mci).unwrap();
    // Run in the folder: MCML's output names are relative to the current directory.
    let o = baker_in(dir.path(), &["mc", "--mci-in", "two_runs.mci", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(dir.path().join("bench.mco")).unwrap();
    assert!(text.starts_with("A1 \t# Version number of the file format."));
    // Values of each section: the data lines after its keyword, up to the next keyword.
    let keys = [
        "InParm", "RAT", "A_l", "A_z", "Rd_r", "Rd_a", "Tt_r", "Tt_a", "A_rz", "Rd_ra", "Tt_ra",
    ];
    let mut sections: Vec<(String, Vec<f64>)> = Vec::new();
    for line in text.lines() {
        let first = line.split_whitespace().next().unwrap_or("");
        if keys.contains(&first) {
            sections.push((first.to_string(), Vec::new()));
        } else if !line.starts_with('#') && !line.trim().is_empty() {
            if let Some(s) = sections.last_mut() {
                let data = line.split('#').next().unwrap();
                s.1.extend(
                    data.split_whitespace()
                        .filter_map(|t| t.parse::<f64>().ok()),
                );
            }
        }
    }
    let names: Vec<&str> = sections.iter().map(|s| s.0.as_str()).collect();
    assert_eq!(names, keys);
    let get = |k: &str| &sections.iter().find(|s| s.0 == k).unwrap().1;
    let (nz, nr, na) = (10usize, 50usize, 10usize);
    assert_eq!(get("A_z").len(), nz);
    assert_eq!(get("Rd_r").len(), nr);
    assert_eq!(get("Rd_a").len(), na);
    assert_eq!(get("A_rz").len(), nr * nz);
    assert_eq!(get("Rd_ra").len(), nr * na);
    assert_eq!(get("Tt_ra").len(), nr * na);
    let rat = get("RAT");
    assert!(
        (rat.iter().sum::<f64>() - 1.0).abs() < 1e-5,
        "Rsp + Rd + A + Tt = {}",
        rat.iter().sum::<f64>()
    );
    // Σ Rd_r·2πr·dr over the grid (the last bin holds the overflow) equals Rd.
    let dr = 0.002;
    let rd: f64 = get("Rd_r")
        .iter()
        .enumerate()
        .map(|(i, x)| x * 2.0 * std::f64::consts::PI * dr * dr * (i as f64 + 0.5))
        .sum();
    assert!(
        (rd - rat[1]).abs() < 2e-4 * rat[1].max(1e-3) + 1e-5,
        "∫Rd_r = {rd}, Rd = {}",
        rat[1]
    );
    // Σ A_z·dz over the depth grid (the last bin holds what lies deeper) equals A, to the
    // five digits MCML prints.
    let dz = 0.002;
    let a: f64 = get("A_z").iter().sum::<f64>() * dz;
    assert!(
        (a - rat[2]).abs() < 2e-4 * rat[2] + 1e-6,
        "∫A_z = {a}, A = {}",
        rat[2]
    );
    // Benchmark slab, 20,000 photons: Rd and Tt near van de Hulst's values.
    assert!((rat[1] - 0.09739).abs() < 0.01 && (rat[3] - 0.66096).abs() < 0.01);
    // As in MCML, Rsp is the analytic specular reflectance; light reflected back without
    // scattering counts in Rd.
    let two = std::fs::read_to_string(dir.path().join("two.mco")).unwrap();
    let rsp: f64 = two
        .lines()
        .skip_while(|l| !l.starts_with("RAT"))
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (rsp - ((1.37f64 - 1.0) / 2.37).powi(2)).abs() < 1e-6,
        "Rsp {rsp}"
    );
}

#[test]
fn issue4_closed_stdout_ends_quietly() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_baker"))
        .args(["optics", "tests/specs/optics_examples.yaml"])
        .current_dir(repo())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away, as with `| head`
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}

/// MCML 2.0's own numbers for its stock samples (tests/stacks/mcml2/README.md: MCML 2.0 built
/// from the public source, seed 1): output name, Rd, SE(Rd), A, SE(A).
const MCML2_SAMPLES: [(&str, &str, f64, f64, f64, f64); 3] = [
    (
        "sample1.mci",
        "sample1a.mco",
        0.0972139,
        0.000234288,
        0.241819,
        0.00018808,
    ),
    (
        "sample1.mci",
        "sample1b.mco",
        0.220348,
        0.000916117,
        0.739652,
        0.000916116,
    ),
    (
        "sample2.mci",
        "sample2.mco",
        0.237859,
        0.000311708,
        0.641547,
        0.000293194,
    ),
];

/// `baker mc --mci-in` reads stock MCML 2.0 files (media list, layers naming media) and gives
/// Rd and A within 3 combined SEs of MCML 2.0's run of the same files (sample 2 with a tenth
/// of its photons). The outputs land in the current directory, not beside the input.
#[test]
fn mc_reads_stock_mcml2_inputs_like_mcml() {
    let dir = tempfile::tempdir().unwrap();
    let inputs = dir.path().join("inputs");
    std::fs::create_dir(&inputs).unwrap();
    let mut results: Vec<(String, serde_json::Value)> = Vec::new();
    for (mci, photons) in [("sample1.mci", None), ("sample2.mci", Some("100000"))] {
        std::fs::copy(
            repo().join("tests/stacks/mcml2").join(mci),
            inputs.join(mci),
        )
        .unwrap();
        let input = format!("inputs/{mci}");
        let mut args = vec!["mc", "--mci-in", &input, "--json", "-q"];
        if let Some(n) = photons {
            args.extend(["--photons", n]);
        }
        let o = baker_in(dir.path(), &args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).is_empty(), "-q: {}", stderr(&o));
        for line in String::from_utf8_lossy(&o.stdout).lines() {
            results.push((mci.to_string(), serde_json::from_str(line).unwrap()));
        }
    }
    assert_eq!(results.len(), MCML2_SAMPLES.len());
    for ((mci, v), (want_mci, out, rd, rd_se, a, a_se)) in results.iter().zip(MCML2_SAMPLES) {
        assert_eq!(mci, want_mci);
        assert!(
            dir.path().join(out).is_file(),
            "{out} not in the current directory"
        );
        assert!(!inputs.join(out).exists(), "{out} written beside the input");
        let f = |k: &str| v[k].as_f64().unwrap();
        for (what, xb, sb, xm, sm) in [
            ("Rd", f("rd"), f("rd_se"), rd, rd_se),
            ("A", f("absorbed_total"), f("absorbed_total_se"), a, a_se),
        ] {
            let bound = 3.0 * sb.hypot(sm);
            assert!(
                (xb - xm).abs() <= bound,
                "{out} {what}: baker {xb} ± {sb}, MCML {xm} ± {sm}"
            );
        }
    }
}

/// `-o DIR` puts the runs' outputs in DIR (created); a name that would leave it is refused
/// naming the file and line; `-o` works for a stack too (a file, or a folder for baker.mco).
#[test]
fn mc_out_folder_holds_the_outputs_and_escapes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(repo().join("tests/stacks/mcml2/sample1.mci")).unwrap();
    let small = text
        .replace("1000000\t10:00", "2000\t10:00")
        .replace("100000\t10:00", "2000");
    std::fs::write(dir.path().join("s.mci"), &small).unwrap();
    let o = baker_in(dir.path(), &["mc", "--mci-in", "s.mci", "-o", "res/deep"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for out in ["sample1a.mco", "sample1b.mco"] {
        assert!(dir.path().join("res/deep").join(out).is_file());
        assert!(!dir.path().join(out).exists());
    }
    let line = small
        .lines()
        .position(|l| l.starts_with("sample1b.mco"))
        .unwrap()
        + 1;
    for bad in ["../escape.mco", "/tmp/escape.mco"] {
        std::fs::write(
            dir.path().join("bad.mci"),
            small.replace("sample1b.mco", bad),
        )
        .unwrap();
        for args in [vec![], vec!["-o", "res"]] {
            let mut a = vec!["mc", "--mci-in", "bad.mci"];
            a.extend(args);
            let o = baker_in(dir.path(), &a);
            assert_eq!(o.status.code(), Some(2));
            let e = stderr(&o);
            assert!(
                e.contains(&format!("bad.mci: line {line}:")) && e.contains(bad),
                "{e}"
            );
        }
    }
    assert!(
        !dir.path().join("escape.mco").exists() && !dir.path().join("res/sample1a.mco").exists()
    );
    let stack = repo().join("tests/stacks/mcml_benchmark.json");
    let stack = stack.to_str().unwrap();
    let o = baker_in(
        dir.path(),
        &["mc", stack, "--photons", "2000", "-o", "res", "-q"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.path().join("res/baker.mco").is_file());
    let o = baker_in(
        dir.path(),
        &["mc", stack, "--photons", "2000", "--out", "x.mco"],
    );
    assert!(o.status.success() && dir.path().join("x.mco").is_file());
}
