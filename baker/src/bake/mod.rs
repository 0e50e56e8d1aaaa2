//! `baker bake` as a library: a [`Request`] in, every product of every entry of its specs out.
//!
//! Skin and fiber bakes are two implementations of the same steps, so a behaviour added to
//! one cannot be missed in the other:
//!
//! 1. **resolve**: [`load_checked`] parses and resolves the spec and checks its cost;
//! 2. **destination**: [`destination`] decides where the outputs go (the spec's folder, or
//!    `subset/` beside a finished bake) and stages them; [`stamp`] skips an up-to-date bake;
//! 3. **units**: [`skin`] and [`fiber`] plan their work units and run them through the
//!    cache ([`crate::pipeline::Runner`]); a shard stops here;
//! 4. **assemble**: the tables, previews and [`manifest`] (one writer for both kinds, with
//!    `timing.json`), then the staged folder is put in place and its units recorded as roots
//!    ([`shard::write_roots`]);
//! 5. **finish**: [`shard::finish`] writes a shard's manifest, reports and maps interruption.
//!
//! Progress and messages go to the request's [`crate::pipeline::Events`]; the library never
//! prints for itself.

pub mod destination;
pub mod estimate;
pub mod fiber;
pub mod gc;
pub mod job;
pub mod manifest;
pub mod merge;
pub mod plan;
pub mod request;
pub mod shard;
pub mod skin;
pub mod slurm;
pub mod stamp;

use std::path::Path;
use std::time::Instant;

pub use destination::{Destination, SUBSET_DIR};
pub use job::Job;
pub use request::Request;

use crate::error::UsageError;
use crate::files::Shown;
use crate::output::paths::OutRoot;
use crate::pipeline::{interrupt, Events, Key, Runner};
use crate::spec::{budget, names, Spec};

/// Bakes every spec of `req`, reporting to `events`.
pub fn run(req: &Request, events: Events) -> anyhow::Result<()> {
    if req.photons == Some(0) {
        return Err(UsageError("--photons must be at least 1".into()).into());
    }
    let overrides = req.overrides();
    // Validate every spec (entries, sizes, names, cost) before writing anything.
    let specs = req
        .specs
        .iter()
        .map(|p| load_checked(p, &overrides).map(|(s, _)| s))
        .collect::<anyhow::Result<Vec<_>>>()?;
    check_entries(req, &specs)?;
    check_kind_flags(req, &specs, &events)?;
    let root = OutRoot::open(&req.out).map_err(|e| UsageError(e.to_string()))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(req.thread_count())
        .build()?;
    interrupt::install();
    interrupt::set_silent(!events.human());
    let runner = req.runner(events);
    let t0 = Instant::now();
    let mut stems = Vec::new();
    let result = (|| -> anyhow::Result<()> {
        for (path, spec) in req.specs.iter().zip(&specs) {
            let stem = spec_stem(path)?;
            stems.push(stem.clone());
            if spec.entries().iter().any(|(n, _)| req.selects(n)) {
                pool.install(|| bake_one(req, &root, path, &stem, spec, &runner))?;
            }
        }
        Ok(())
    })();
    shard::finish(req, &runner, &stems, t0, result)
}

/// Skin-only flags on fiber specs: an error when no spec of the bake is a skin spec, a notice
/// when some are (the flag applies to those only).
fn check_kind_flags(req: &Request, specs: &[Spec], events: &Events) -> anyhow::Result<()> {
    let skin_only = [
        ("--optics-only", req.optics_only),
        ("--no-reuse", req.no_reuse),
        ("--plots", req.plots),
    ];
    let fibers: Vec<String> = req
        .specs
        .iter()
        .zip(specs)
        .filter(|(_, s)| matches!(s, Spec::Fiber(_)))
        .map(|(p, _)| Shown(p).to_string())
        .collect();
    for (flag, set) in skin_only {
        if !set || fibers.is_empty() {
            continue;
        }
        if fibers.len() == specs.len() {
            return Err(UsageError(format!(
                "{flag} applies to skin specs only; {} {} a fiber spec",
                fibers.join(", "),
                if fibers.len() == 1 { "is" } else { "are" }
            ))
            .into());
        }
        events.notice(format!(
            "{flag} applies to skin specs only; it is ignored for {}",
            fibers.join(", ")
        ));
    }
    Ok(())
}

/// With several specs an entry may live in any of them; each name asked for must exist.
pub fn check_entries<'a>(
    req: &Request,
    specs: impl IntoIterator<Item = &'a Spec>,
) -> anyhow::Result<()> {
    let names: Vec<&str> = specs
        .into_iter()
        .flat_map(|s| s.entries().into_iter().map(|(n, _)| n))
        .collect();
    for name in &req.entries {
        if !names.contains(&name.as_str()) {
            let files: Vec<String> = req.specs.iter().map(|p| p.display().to_string()).collect();
            let message = match files.as_slice() {
                [one] => crate::spec::names::unknown_entry(one, name, &names),
                _ => crate::suggest::no_entry(
                    name,
                    &files.join(", "),
                    &names,
                    "`baker validate SPEC` lists each spec's",
                ),
            };
            return Err(UsageError(message).into());
        }
    }
    Ok(())
}

/// One spec: its destination, the up-to-date check, the kind's bake, the commit.
fn bake_one(
    req: &Request,
    root: &OutRoot,
    path: &Path,
    stem: &str,
    spec: &Spec,
    runner: &Runner,
) -> anyhow::Result<()> {
    let first_unit = runner.used.lock().unwrap().len();
    let stamp = stamp::stamp(req, path, stamp::spec_sha(spec));
    let dest = if req.shard.is_some() {
        None
    } else {
        Some(destination::destination(
            req,
            root,
            stem,
            spec,
            &stamp,
            &runner.events,
        )?)
    };
    // Unchanged spec, flags and executable, outputs intact: nothing to do.
    if let Some(d) = &dest {
        if !req.force && stamp::up_to_date(d.staged.target(), &stamp) {
            runner
                .events
                .emit(serde_json::json!({"event": "up_to_date", "spec": path}));
            runner.events.say(format!(
                "{}: up to date ({})",
                path.display(),
                Shown(d.staged.target())
            ));
            return Ok(());
        }
    }
    let job = Job {
        req,
        path,
        stem,
        runner,
        out: dest.as_ref(),
        stamp: &stamp,
        first_unit,
    };
    match spec {
        Spec::Skin(s) => skin::bake(&job, s)?,
        Spec::Fiber(s) => fiber::bake(&job, s)?,
    }
    if let Some(d) = dest {
        let keys: Vec<Key> = runner.used.lock().unwrap()[first_unit..]
            .iter()
            .map(|(_, k)| *k)
            .collect();
        let rel = d.rel.clone();
        d.commit()?;
        // The finished output's units are live for `baker cache gc`.
        shard::write_roots(runner, root, &rel, &keys)?;
    }
    Ok(())
}

/// Loads a spec of either kind and checks what baking it with `o` costs; every problem is a
/// [`UsageError`] naming file:line.
pub fn load_checked(path: &Path, o: &budget::Overrides) -> anyhow::Result<(Spec, budget::Cost)> {
    let usage = |e: crate::spec::SpecErrors| UsageError(e.to_string().trim_end().to_string());
    let spec = crate::spec::load_any(path).map_err(usage)?;
    let cost = budget::check(&spec, o).map_err(usage)?;
    Ok((spec, cost))
}

/// The output folder name of a spec: its file stem, which must be a plain folder name.
pub fn spec_stem(path: &Path) -> anyhow::Result<String> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    names::check_stem(&stem).map_err(|m| {
        UsageError(format!(
            "{}: the spec's file name gives the output folder name {stem:?}, which {m}; rename \
             the spec file",
            Shown(path)
        ))
    })?;
    Ok(stem)
}
