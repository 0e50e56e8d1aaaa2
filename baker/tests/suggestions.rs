//! "Did you mean …?" (issue 20): a misspelt entry name, field, choice or dye gets the nearest
//! names, and never the whole list of names.

mod common;

use common::{baker, stderr};

/// Exit code of a user error.
const USAGE: i32 = 2;

/// stderr of a run that must fail as a user error.
fn refused(args: &[&str]) -> String {
    let o = baker(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(USAGE), "{args:?}: {err}");
    assert!(o.stdout.is_empty(), "{args:?}: stdout not empty");
    err
}

/// `err` suggests `near` (in one of its "did you mean" lists) and names none of `far` (names a
/// wall of names would hold).
fn suggests(err: &str, near: &str, far: &[&str]) {
    let mut offers = err.split("did you mean ").skip(1).peekable();
    assert!(offers.peek().is_some(), "no suggestion: {err}");
    let offered = offers.any(|after| {
        let list = after.split('?').next().unwrap();
        list.contains(&format!("\"{near}\""))
    });
    assert!(offered, "{near} not suggested: {err}");
    for f in far {
        assert!(!err.contains(f), "{f} listed: {err}");
    }
}

/// Entries of specs/fitzpatrick.yaml that no typo below is near.
const FAR: [&str; 3] = ["typeI_age20_xi0", "typeVI_age80_xi1", "typeV_age70_xi0.5"];

#[test]
fn misspelt_entry_names_get_the_nearest_names_and_a_count() {
    let spec = "specs/fitzpatrick.yaml";
    for args in [
        vec![
            "bake",
            spec,
            "--entry",
            "typeIII_age3O",
            "--out",
            "/nonexistent/x",
        ],
        vec!["optics", spec, "--entry", "typeIII_age3O"],
        vec![
            "mc",
            "--spec",
            spec,
            "--entry",
            "typeIII_age3O",
            "--lambda-nm",
            "550",
        ],
        vec!["plan", spec, "--entry", "typeIII_age3O"],
    ] {
        let err = refused(&args);
        assert!(
            err.contains("no entry named \"typeIII_age3O\" in specs/fitzpatrick.yaml; did you mean \"typeIII_age30_xi0\""),
            "{args:?}: {err}"
        );
        assert!(
            err.contains("(126 entries; `baker validate specs/fitzpatrick.yaml` lists them)"),
            "{args:?}: {err}"
        );
        suggests(&err, "typeIII_age30_xi1", &FAR);
    }
    // Nothing close: the count and how to list them, no names.
    let err = refused(&["optics", spec, "--entry", "nobody_at_all"]);
    assert!(
        err.contains(
            "none of the 126 entries is close; `baker validate specs/fitzpatrick.yaml` lists them"
        ),
        "{err}"
    );
    assert!(!err.contains("typeI"), "{err}");
    // A fiber spec's few entries are listed whole.
    let err = refused(&[
        "fiber",
        "trace",
        "specs/fibers.yaml",
        "--entry",
        "polyster",
        "--theta-i",
        "0",
    ]);
    suggests(&err, "polyester", &[]);
    assert!(
        err.contains("allowed: polyester, polyester_trilobal, silk"),
        "{err}"
    );
}

/// `baker validate` of `yaml` (written to a temporary spec).
fn validate(yaml: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("spec.yaml");
    std::fs::write(&p, yaml).unwrap();
    refused(&["validate", p.to_str().unwrap()])
}

#[test]
fn misspelt_fields_choices_and_dyes_get_the_nearest_names() {
    let err = validate(
        "version: 1\nentries:\n  - {name: a, age: 30, gender: female, location: forearm, xi: 0, skin_tpye: II}\n",
    );
    assert!(err.contains(":3:"), "{err}");
    assert!(
        err.contains("skin_tpye: unknown field; did you mean \"skin_type\"?"),
        "{err}"
    );
    assert!(
        err.contains("(33 fields here; specs/README.md, \"Skin specs\", lists them)"),
        "{err}"
    );
    suggests(
        &err,
        "skin_type",
        &["sebum_volume_factor", "collagen_rd", "melanosome_fraction"],
    );

    let err = validate(
        "version: 1\nentries:\n  - {name: a, age: 30, gender: femle, location: back_of_hnd, xi: 0, skin_type: II}\n",
    );
    suggests(&err, "female", &[]);
    suggests(&err, "back_of_hand", &[]);

    // One typo per spec: an unknown fiber type stops the entry's resolution before its
    // section and dye are looked at.
    for (typo, near) in [
        (
            "type: cottn, section: {shape: trilobal}, dye: disperse_red_1",
            "cotton",
        ),
        (
            "type: cotton, section: {shape: trilobl}, dye: disperse_red_1",
            "trilobal",
        ),
        (
            "type: cotton, section: {shape: trilobal}, dye: disperse_rd_1",
            "disperse_red_1",
        ),
    ] {
        let err = validate(&format!(
            "version: 1\nfibers:\n  - {{name: a, {typo}, depth_of_shade_percent: 1}}\n"
        ));
        suggests(&err, near, &[]);
    }
}
