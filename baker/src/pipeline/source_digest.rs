//! The source code a work unit's result depends on, found from the code itself, and its
//! digest: part of every cache key ([`super::KeyBuilder`]), so that a change to any code that
//! can alter a unit's result never reuses units cached by the old code.
//!
//! The build script (`baker/build.rs`) includes this file and runs [`unit_digests`] over the
//! sources it is built from; the crate compiles the digests in ([`super::code_digest`]).
//! Starting from the files that compute each kind of unit ([`UNIT_ROOTS`]), every path a file
//! names (`crate::…`, `super::…`, `self::…`, `formats::…` and relative `use` paths, brace
//! groups expanded) is resolved to the module file where the named item lives or is
//! re-exported, and that file is followed in turn. The digest covers the closure's files (path and bytes) and the workspace's
//! `Cargo.lock` (the dependencies' versions: random number generators and distributions
//! come from crates). An item reached through a re-export brings the whole re-exporting
//! `mod.rs` (and all it re-exports), so the closure errs on the large side.
//! Code reached without a path (a macro from another module) is not followed; none of the
//! physics modules does that.
//!
//! std and sha2 only: the build script compiles this file on its own.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The files whose code computes each kind of cached unit (relative to `baker/src`). Every
/// kind passed to [`super::KeyBuilder::new`] in the crate has a row (a test checks it).
pub const UNIT_ROOTS: &[(&str, &[&str])] = &[
    ("skin-pilot", &["profile/simulate.rs"]),
    ("skin-run", &["profile/simulate.rs"]),
    ("skin-fit", &["profile/rgb.rs"]),
    (
        "fiber-slices",
        &["bake/fiber/entry.rs", "bake/fiber/setup.rs"],
    ),
];

/// A crate whose sources a path can reach: its name in paths (`crate` for the file's own
/// crate) and its `src` folder.
#[derive(Debug, Clone)]
pub struct CrateSrc {
    pub name: String,
    pub src: PathBuf,
}

/// One source file: its crate (index into the crate list) and its path relative to `src`.
pub type FileId = (usize, String);

/// The module path of a file: `fiber/slices.rs` → [fiber, slices]; `fiber/mod.rs` and
/// `lib.rs` → [fiber] and [].
fn module_of(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel.split('/').map(str::to_string).collect();
    let last = parts.pop().unwrap_or_default();
    if last != "mod.rs" && last != "lib.rs" && last != "main.rs" {
        parts.push(last.trim_end_matches(".rs").to_string());
    }
    parts
}

/// The file of module `m` in `src`, if it exists (`m.rs`, else `m/mod.rs`; `lib.rs` for []).
fn file_of(src: &Path, m: &[String]) -> Option<String> {
    if m.is_empty() {
        return Some("lib.rs".to_string()).filter(|f| src.join(f).is_file());
    }
    let base = m.join("/");
    [format!("{base}.rs"), format!("{base}/mod.rs")]
        .into_iter()
        .find(|f| src.join(f).is_file())
}

/// The module file a path reaches, from module `start` along `segs` (it stops at the first
/// segment that is not a module: an item, defined or re-exported there), and how many
/// segments were modules.
fn resolve(src: &Path, start: &[String], segs: &[String]) -> (Option<String>, usize) {
    let mut m = start.to_vec();
    let mut file = file_of(src, &m);
    let mut depth = 0;
    for s in segs {
        let mut next = m.clone();
        next.push(s.clone());
        match file_of(src, &next) {
            Some(f) => {
                file = Some(f);
                m = next;
                depth += 1;
            }
            None => break,
        }
    }
    (file, depth)
}

/// Identifier characters.
fn ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Expands a `use` tree (`a::{b, c::{d, e}}`, `a::*`, `a as b`) into flat paths.
fn expand_use(tree: &str) -> Vec<Vec<String>> {
    fn parse(s: &[char], i: &mut usize, prefix: &[String], out: &mut Vec<Vec<String>>) {
        let mut path = prefix.to_vec();
        loop {
            while *i < s.len() && s[*i].is_whitespace() {
                *i += 1;
            }
            if *i >= s.len() {
                break;
            }
            if s[*i] == '{' {
                *i += 1;
                loop {
                    parse(s, i, &path, out);
                    while *i < s.len() && s[*i].is_whitespace() {
                        *i += 1;
                    }
                    if *i < s.len() && s[*i] == ',' {
                        *i += 1;
                        continue;
                    }
                    if *i < s.len() && s[*i] == '}' {
                        *i += 1;
                    }
                    return;
                }
            }
            let start = *i;
            while *i < s.len() && (ident_char(s[*i]) || s[*i] == '*') {
                *i += 1;
            }
            if *i == start {
                // `,`, `}` or the end: the path ends here.
                out.push(path);
                return;
            }
            let word: String = s[start..*i].iter().collect();
            if word == "as" {
                // `x as y`: skip the alias.
                while *i < s.len() && s[*i].is_whitespace() {
                    *i += 1;
                }
                while *i < s.len() && ident_char(s[*i]) {
                    *i += 1;
                }
                continue;
            }
            if word != "*" && word != "self" {
                path.push(word);
            }
            if s[*i..].starts_with(&[':', ':']) {
                *i += 2;
                continue;
            }
        }
        out.push(path);
    }
    let chars: Vec<char> = tree.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    parse(&chars, &mut i, &[], &mut out);
    out
}

/// `text` without its comments (`//…` to the end of the line, `/* … */` nested), string
/// literals kept: paths in doc links are not code.
fn strip_comments(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let (mut i, mut depth, mut in_str) = (0, 0usize, false);
    while i < c.len() {
        if depth == 0 && !in_str && c[i] == '"' && (i == 0 || c[i - 1] != '\\') {
            in_str = true;
        } else if in_str && c[i] == '\\' {
            out.push(c[i]);
            if let Some(&n) = c.get(i + 1) {
                out.push(n);
            }
            i += 2;
            continue;
        } else if in_str && c[i] == '"' {
            in_str = false;
        } else if !in_str && c[i] == '/' && c.get(i + 1) == Some(&'*') {
            depth += 1;
            i += 2;
            continue;
        } else if depth > 0 && c[i] == '*' && c.get(i + 1) == Some(&'/') {
            depth -= 1;
            i += 2;
            continue;
        } else if depth == 0 && !in_str && c[i] == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
            continue;
        }
        if depth == 0 {
            out.push(c[i]);
        }
        i += 1;
    }
    out
}

/// Paths named in the code of `text`: every `use` tree, and every `crate::…`, `super::…`,
/// `self::…` or `<crate name>::…` path elsewhere.
fn paths_in(text: &str, crate_names: &[String]) -> Vec<Vec<String>> {
    let stripped = strip_comments(text);
    let text: &str = &stripped;
    let mut out = Vec::new();
    // `use` statements (also `pub use`, `pub(crate) use`), up to their `;`.
    let mut rest = text;
    while let Some(k) = rest.find("use ") {
        let before_ok = k == 0 || !ident_char(rest[..k].chars().last().unwrap_or(' '));
        let after = &rest[k + 4..];
        let end = after.find(';').unwrap_or(after.len());
        if before_ok {
            out.extend(expand_use(&after[..end]));
        }
        rest = after;
    }
    // Qualified paths anywhere.
    let roots: Vec<String> = ["crate", "super", "self"]
        .iter()
        .map(|s| s.to_string())
        .chain(crate_names.iter().cloned())
        .collect();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        if !ident_char(chars[i]) || (i > 0 && (ident_char(chars[i - 1]) || chars[i - 1] == ':')) {
            i += 1;
            continue;
        }
        let start = i;
        while i < chars.len() && ident_char(chars[i]) {
            i += 1;
        }
        let word: String = chars[start..i].iter().collect();
        let qualified = chars.get(i) == Some(&':') && chars.get(i + 1) == Some(&':');
        if !qualified || !roots.contains(&word) {
            continue;
        }
        let mut path = vec![word];
        while chars.get(i) == Some(&':') && chars.get(i + 1) == Some(&':') {
            i += 2;
            let s = i;
            while i < chars.len() && ident_char(chars[i]) {
                i += 1;
            }
            if i == s {
                break;
            }
            path.push(chars[s..i].iter().collect());
        }
        out.push(path);
    }
    out
}

/// The files reached from `roots` (files of `crates[0]`), each as (crate index, path).
pub fn closure(crates: &[CrateSrc], roots: &[&str]) -> BTreeSet<(usize, String)> {
    reached(crates, roots).into_keys().collect()
}

/// The files reached from `roots`, each with the file whose path reached it first (`None`
/// for a root): why a file is in a closure.
pub fn reached(crates: &[CrateSrc], roots: &[&str]) -> BTreeMap<FileId, Option<FileId>> {
    let names: Vec<String> = crates.iter().skip(1).map(|c| c.name.clone()).collect();
    let mut seen: BTreeMap<FileId, Option<FileId>> = BTreeMap::new();
    let mut todo: Vec<(FileId, Option<FileId>)> =
        roots.iter().map(|r| ((0, r.to_string()), None)).collect();
    while let Some(((k, rel), from)) = todo.pop() {
        if seen.contains_key(&(k, rel.clone())) {
            continue;
        }
        seen.insert((k, rel.clone()), from);
        let src = &crates[k].src;
        let Ok(text) = std::fs::read_to_string(src.join(&rel)) else {
            continue;
        };
        let here = module_of(&rel);
        for p in paths_in(&text, &names) {
            let Some(first) = p.first() else { continue };
            let target = match first.as_str() {
                "crate" => Some((k, Vec::new(), &p[1..])),
                "self" => Some((k, here.clone(), &p[1..])),
                "super" => {
                    let ups = p.iter().take_while(|s| *s == "super").count();
                    let base = here[..here.len().saturating_sub(ups)].to_vec();
                    Some((k, base, &p[ups..]))
                }
                name => match crates.iter().position(|c| c.name == name) {
                    Some(j) if j > 0 => Some((j, Vec::new(), &p[1..])),
                    // A relative path: a child module of this one, if it is one.
                    _ => Some((k, here.clone(), &p[..])),
                },
            };
            if let Some((j, start, segs)) = target {
                let relative = j == k && !["crate", "self", "super"].contains(&first.as_str());
                let (file, depth) = resolve(&crates[j].src, &start, segs);
                // A relative path counts only when it names a child module (`std::…` does not).
                if let Some(f) = file.filter(|_| !relative || depth > 0) {
                    todo.push(((j, f), Some((k, rel.clone()))));
                }
            }
        }
    }
    seen
}

/// SHA-256 over the files (crate name, path and bytes, in order) and `extra` files.
pub fn digest(
    crates: &[CrateSrc],
    files: &BTreeSet<(usize, String)>,
    extra: &[PathBuf],
) -> [u8; 32] {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    for (k, rel) in files {
        let bytes = std::fs::read(crates[*k].src.join(rel)).unwrap_or_default();
        h.update(crates[*k].name.as_bytes());
        h.update([0]);
        h.update(rel.as_bytes());
        h.update([0]);
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    for p in extra {
        let bytes = std::fs::read(p).unwrap_or_default();
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    h.finalize().into()
}

/// Per unit kind: the digest of its code and the files it covers (`crate/path`).
pub fn unit_digests(
    crates: &[CrateSrc],
    extra: &[PathBuf],
) -> BTreeMap<String, ([u8; 32], Vec<String>)> {
    UNIT_ROOTS
        .iter()
        .map(|(kind, roots)| {
            let files = closure(crates, roots);
            let d = digest(crates, &files, extra);
            let names = files
                .iter()
                .map(|(k, rel)| format!("{}/{rel}", crates[*k].name))
                .collect();
            (kind.to_string(), (d, names))
        })
        .collect()
}

/// The crates as laid out in this workspace: `baker/src` and `formats/src`.
pub fn workspace_crates(baker_dir: &Path) -> Vec<CrateSrc> {
    vec![
        CrateSrc {
            name: "crate".into(),
            src: baker_dir.join("src"),
        },
        CrateSrc {
            name: "formats".into(),
            src: baker_dir.join("../formats/src"),
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn here() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }

    fn lock(baker_dir: &Path) -> Vec<PathBuf> {
        vec![baker_dir.join("../Cargo.lock")]
    }

    /// The digests compiled in are those of the sources as they are now: the build script
    /// ran on this code, so no cached unit of older code can match.
    #[test]
    fn compiled_digests_are_those_of_the_current_sources() {
        let d = unit_digests(&workspace_crates(&here()), &lock(&here()));
        assert_eq!(d.len(), UNIT_ROOTS.len());
        for (kind, (digest, files)) in &d {
            assert_eq!(&super::super::code_digest(kind), digest, "{kind}");
            assert_eq!(super::super::code_files(kind), files.as_slice(), "{kind}");
        }
    }

    /// The closures hold the physics each unit runs, and not the command line.
    #[test]
    fn closures_hold_the_code_each_unit_runs() {
        let d = unit_digests(&workspace_crates(&here()), &lock(&here()));
        let has = |kind: &str, f: &str| d[kind].1.iter().any(|x| x == f);
        for f in [
            "crate/transport/engine.rs",
            "crate/transport/junction.rs",
            "crate/transport/white.rs",
            "crate/transport/boundary.rs",
            "crate/transport/phase.rs",
            "crate/transport/radial.rs",
            "crate/math/rng.rs",
            "crate/profile/allocate.rs",
        ] {
            assert!(has("skin-run", f), "skin-run misses {f}");
        }
        for f in [
            "crate/fit/gaussians.rs",
            "crate/spectral/colour.rs",
            "crate/profile/rgb.rs",
        ] {
            assert!(has("skin-fit", f), "skin-fit misses {f}");
        }
        for f in [
            "crate/fiber/slices.rs",
            "crate/fiber/tracer/mod.rs",
            "crate/fiber/tracer/shared.rs",
            "crate/fiber/surface.rs",
            "crate/fiber/sweep.rs",
            "crate/fiber/section/polygon.rs",
            "crate/math/fresnel.rs",
            "crate/spectral/colour.rs",
            "formats/grid.rs",
        ] {
            assert!(has("fiber-slices", f), "fiber-slices misses {f}");
        }
        for (kind, (_, files)) in &d {
            assert!(
                !files.iter().any(|f| f.starts_with("crate/cli/")),
                "{kind}: {files:?}"
            );
        }
    }

    fn copy_dir(from: &Path, to: &Path) {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                copy_dir(&p, &to.join(e.file_name()));
            } else {
                std::fs::copy(&p, to.join(e.file_name())).unwrap();
            }
        }
    }

    /// Editing the command line changes no unit's digest; a constant of the fiber boundary
    /// changes the fiber units' digest, one of the transport the skin runs'; a changed lock
    /// file changes all. (The closures err on the large side, so a fiber change may also
    /// change skin digests: recomputation, never a stale unit.)
    #[test]
    fn a_changed_constant_changes_exactly_the_keys_that_depend_on_it() {
        let tmp = tempfile::tempdir().unwrap();
        let baker = tmp.path().join("baker");
        copy_dir(&here().join("src"), &baker.join("src"));
        copy_dir(
            &here().join("../formats/src"),
            &tmp.path().join("formats/src"),
        );
        std::fs::copy(here().join("../Cargo.lock"), tmp.path().join("Cargo.lock")).unwrap();
        let digests = || unit_digests(&workspace_crates(&baker), &lock(&baker));
        let before = digests();
        assert_eq!(
            before,
            unit_digests(&workspace_crates(&here()), &lock(&here()))
        );
        let edit = |rel: &str, from: &str, to: &str| {
            let p = baker.join("src").join(rel);
            let s = std::fs::read_to_string(&p).unwrap();
            assert!(s.contains(from), "{rel} holds {from}");
            std::fs::write(&p, s.replacen(from, to, 1)).unwrap();
        };
        edit("cli/mc.rs", "fn ", "fn  ");
        assert_eq!(digests(), before, "the command line is no unit's code");
        edit(
            "fiber/surface.rs",
            "const MAX_CAVITY_BOUNCES: usize = 8;",
            "const MAX_CAVITY_BOUNCES: usize = 9;",
        );
        let after = digests();
        assert_ne!(after["fiber-slices"].0, before["fiber-slices"].0);
        edit(
            "transport/engine.rs",
            "pub const ROULETTE_CHANCE: f64 = 0.1;",
            "pub const ROULETTE_CHANCE: f64 = 0.2;",
        );
        let skin = digests();
        assert_ne!(skin["skin-run"].0, after["skin-run"].0);
        assert_ne!(skin["skin-pilot"].0, after["skin-pilot"].0);
        std::fs::write(tmp.path().join("Cargo.lock"), "changed").unwrap();
        let locked = digests();
        for (kind, (d, _)) in &locked {
            assert_ne!(*d, skin[kind].0, "{kind} after a dependency change");
        }
    }

    /// Every kind of unit the crate keys has roots here.
    #[test]
    fn every_keyed_kind_has_roots() {
        fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
            for e in std::fs::read_dir(dir).unwrap().flatten() {
                let p = e.path();
                if p.is_dir() {
                    rs_files(&p, out);
                } else if p.extension().is_some_and(|x| x == "rs") {
                    out.push(p);
                }
            }
        }
        let mut files = Vec::new();
        rs_files(&here().join("src"), &mut files);
        let mut kinds = BTreeSet::new();
        for f in &files {
            let text = std::fs::read_to_string(f).unwrap();
            for part in text.split("KeyBuilder::new(\"").skip(1) {
                kinds.insert(part.split('"').next().unwrap().to_string());
            }
        }
        kinds.remove("test");
        kinds.retain(|k| !k.contains('{'));
        assert!(kinds.len() >= 4, "{kinds:?}");
        for k in &kinds {
            assert!(
                UNIT_ROOTS.iter().any(|(r, _)| r == k),
                "unit kind {k} has no roots"
            );
        }
    }

    #[test]
    #[ignore = "prints why each file is in each closure"]
    fn explain_closures() {
        let crates = workspace_crates(&here());
        for (kind, roots) in UNIT_ROOTS {
            for ((k, f), from) in reached(&crates, roots) {
                eprintln!("{kind}: {}/{f} <- {from:?}", crates[k].name);
            }
        }
    }

    #[test]
    fn comments_are_not_code() {
        let t = "let a = \"// x\"; // crate::b\n/* crate::c /* d */ */ crate::e::f";
        assert_eq!(strip_comments(t), "let a = \"// x\"; \n crate::e::f");
    }

    #[test]
    fn use_trees_expand() {
        assert_eq!(
            expand_use("crate::a::{b, c::{d as e, *}, self}"),
            vec![
                vec!["crate", "a", "b"],
                vec!["crate", "a", "c", "d"],
                vec!["crate", "a", "c"],
                vec!["crate", "a"],
            ]
        );
    }
}
