//! End-to-end tests of the `baker` binary: spec errors, `optics` outputs, `bake`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn baker(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_baker"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("baker runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

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
            "unknown field `agee`",
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
    let o = baker(&["validate", "specs/fitzpatrick.yaml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(out.contains("ok, 109 entries"), "{out}");
    assert!(out.contains("female_forearm_typeVI_age80_xi0.5"));
}

#[test]
fn optics_json_is_a_valid_document_with_named_layers() {
    let o = baker(&["optics", "specs/fitzpatrick.yaml", "--json"]);
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
    let (csv, plots, mci) = (
        format!("{d}/csv"),
        format!("{d}/plots"),
        format!("{d}/run.mci"),
    );
    let o = baker(&[
        "optics",
        "specs/fitzpatrick.yaml",
        "--entry",
        "fig35_female_type2_age30",
        "--csv",
        &csv,
        "--plot",
        &plots,
        "--mci",
        "550",
        "--mci-out",
        &mci,
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
        "specs/fitzpatrick.yaml",
        "--entry",
        "fig35_female_type2_age30",
        "--mci",
        "555",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not on the spec's wavelength grid"));
}

#[test]
fn unknown_entry_lists_the_entries() {
    let o = baker(&["optics", "specs/fitzpatrick.yaml", "--entry", "nobody"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("fig35_female_type2_age30"));
}

#[test]
fn bake_writes_the_optics_document_and_csvs_atomically() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = baker(&["bake", "specs/fitzpatrick.yaml", "--out", out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json = std::fs::read_to_string(dir.path().join("fitzpatrick/optics.json")).unwrap();
    let doc = formats::OpticsDocument::from_json(&json).unwrap();
    assert_eq!(doc.entries.len(), 109);
    let csvs = std::fs::read_dir(dir.path().join("fitzpatrick/optics"))
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
        "specs/fitzpatrick.yaml",
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
