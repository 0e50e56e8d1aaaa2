//! `baker schema skin|fiber` against the committed schemas (specs/schema/), so they cannot go
//! stale, and `--out` writing the same bytes.

use std::path::Path;
use std::process::Command;

fn baker() -> Command {
    Command::new(env!("CARGO_BIN_EXE_baker"))
}

fn repo() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

#[test]
fn committed_schemas_are_what_baker_schema_prints() {
    for kind in ["skin", "fiber"] {
        let file = format!("specs/schema/{kind}.schema.json");
        let out = baker().args(["schema", kind]).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let committed = std::fs::read(repo().join(&file)).unwrap_or_default();
        assert!(
            out.stdout == committed,
            "{file} is not what `baker schema {kind}` prints; regenerate it with\n  \
             cargo run -p baker -- schema {kind} -o {file}"
        );
    }
}

#[test]
fn out_writes_the_schema_to_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fiber.schema.json");
    std::fs::write(&path, "stale").unwrap();
    let st = baker()
        .args(["schema", "fiber", "-o"])
        .arg(&path)
        .status()
        .unwrap();
    assert!(st.success());
    let printed = baker().args(["schema", "fiber"]).output().unwrap().stdout;
    assert_eq!(std::fs::read(&path).unwrap(), printed);
    let v: serde_json::Value = serde_json::from_slice(&printed).unwrap();
    assert_eq!(
        v["$schema"], "https://json-schema.org/draft/2020-12/schema",
        "draft 2020-12"
    );
    // A directory is refused, not replaced.
    let st = baker()
        .args(["schema", "skin", "-o"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(!st.status.success());
}
