//! Writes the C header `include/baker_formats.h` from `src/lib.rs` with cbindgen.
//!
//! The header is committed so C users need no Rust tooling to read it; every build of this
//! crate regenerates it (and rewrites the file only when its text changed), so
//! `cargo build -p baker-formats-capi` followed by `git diff --exit-code
//! formats/capi/include/baker_formats.h` tells whether the committed copy is current. A copy
//! also goes to `$OUT_DIR/baker_formats.h`. Where the source tree is read-only the header is
//! left as it is, with a warning.

use std::path::PathBuf;

fn main() {
    let dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=cbindgen.toml");
    println!("cargo:rerun-if-changed=build.rs");

    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml"))
        .unwrap_or_else(|e| panic!("reading cbindgen.toml: {e}"));
    // Parsing the one source file (not `with_crate`) keeps cargo metadata out of the build.
    let bindings = cbindgen::Builder::new()
        .with_config(config)
        .with_src(dir.join("src/lib.rs"))
        .generate()
        .unwrap_or_else(|e| panic!("cbindgen could not generate baker_formats.h: {e}"));
    let mut text = Vec::new();
    bindings.write(&mut text);

    std::fs::write(out_dir.join("baker_formats.h"), &text).expect("writing OUT_DIR header");
    let committed = dir.join("include").join("baker_formats.h");
    if std::fs::read(&committed).ok().as_deref() != Some(&text[..]) {
        if let Err(e) = std::fs::create_dir_all(committed.parent().unwrap())
            .and_then(|()| std::fs::write(&committed, &text))
        {
            println!(
                "cargo:warning=could not update {}: {e} (the header in OUT_DIR is current)",
                committed.display()
            );
        }
    }
}
