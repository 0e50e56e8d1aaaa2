//! The bake of a fiber spec: every entry's 4D BCSDF tables (thesis §5.3.2, §5.5).
//!
//! Into `OUT/<spec stem>/`:
//! - `<entry>/section-NN.bcsdf`, one per seeded cross-section, and `<entry>/average.bcsdf`
//!   (projected-area weighted average, Fig. 64) when there are several: the streaming tables
//!   (layout in formats/FORMAT.md and `formats::bcsdf`);
//! - `<entry>/<entry>.h5`: the same numbers, one group per table, chunked per incoming
//!   direction, shuffle + deflate, axes as dimension scales, plus the sampling CDFs;
//! - `preview/<entry>.png` (θo × Δφ slices of f on a log scale with axes and a colour bar, the
//!   layout of Table 8: θi ∈ {0°, −45°, −80°} × fiber rotations φi ∈ {0°, 90°}) and `preview/<entry>.exr` (linear RGB f in sr⁻¹, same grid);
//! - `manifest.json`: settings, symmetry, noise, sizes and SHA-256 of every file, and
//!   `timing.json`.

mod entry;
mod gamut;
mod preview;
mod probe;
mod setup;
mod tables;
pub mod thesis;

pub use probe::{trace_direction, DirectionTrace};

use std::time::Instant;

pub use entry::EntryReport;
use setup::entry_setup;

use super::manifest::{self, Kind, Manifest, Timing};
use crate::bake::job::Job;
use crate::fiber::slices::BakeSettings;
use crate::files::Shown;
use crate::output::manifest::file_entry;
use crate::pipeline::{Cache, UnitInfo};
use crate::spec::fiber::{FiberEntry, FiberSpec};

/// Bakes every selected entry of a fiber spec into the job's destination (`None` for a
/// shard: units only).
pub fn bake(job: &Job, spec: &FiberSpec) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let a = job.req;
    let selected = || spec.fibers.iter().filter(|e| a.selects(&e.name));
    job.runner.events.emit(
        serde_json::json!({"event": "bake_started", "spec": job.path,
        "kind": "fiber", "entries": selected().count()}),
    );
    let mut settings = spec.bake.clone();
    if let Some(p) = a.photons {
        settings.photons = p;
        let traced = settings.photons_per_direction();
        if traced != p {
            job.runner.events.notice(format!(
                "--photons {p}: a fiber direction traces whole batches of {} photons, at least \
                 two, so {}: {traced} photons per direction",
                settings.batch,
                crate::files::Shown(job.path)
            ));
        }
    }
    let mut reports = Vec::new();
    let mut files = Vec::new();
    let mut timing = Vec::new();
    // Work units are numbered across the spec's entries (sharding uses the number).
    let mut unit_index = 0usize;
    for e in selected() {
        let st = e.settings(&settings);
        if let Some((r, f)) = entry::bake_entry(job, spec, e, &st, &mut unit_index)? {
            timing.push(serde_json::json!({"entry": r.name, "seconds": r.seconds,
                "photons": r.photons.total, "photons_per_s": r.photons_per_s}));
            reports.push(r);
            files.extend(f);
        }
    }
    let Some(d) = job.out else {
        return Ok(());
    };
    let dir = d.staged.dir();
    let m = Manifest {
        kind: Kind::Fiber,
        spec_file: spec.file.clone(),
        spec_sha256: spec.sha256.clone(),
        settings: settings_json(&settings, &spec.storage)?,
        entries: serde_json::to_value(&reports)?,
        files: files
            .iter()
            .map(|(rel, desc)| file_entry(dir, rel, desc))
            .collect::<anyhow::Result<_>>()?,
        warnings: vec![],
    };
    let t = Timing {
        seconds: t0.elapsed().as_secs_f64(),
        phases: vec![],
        threads: a.thread_count(),
        photons: reports.iter().map(|r| r.photons.total).sum(),
        entries: timing,
    };
    manifest::write(job, m, t)?;
    job.runner.events.say(format!(
        "baked {}: {} fibers → {} ({:.1} s)",
        job.path.display(),
        reports.len(),
        Shown(d.staged.target()),
        t0.elapsed().as_secs_f64()
    ));
    Ok(())
}

/// The manifest's `settings`: the bake's and the tables' storage settings in one object.
fn settings_json(
    st: &BakeSettings,
    storage: &crate::spec::fiber::TableStorage,
) -> anyhow::Result<serde_json::Value> {
    let mut v = serde_json::to_value(st)?;
    if let (Some(m), serde_json::Value::Object(s)) =
        (v.as_object_mut(), serde_json::to_value(storage)?)
    {
        m.extend(s);
    }
    Ok(v)
}

/// `baker plan`'s calibration of entry `e`: seconds per photon on one thread, from a few
/// photons traced at stored directions spread over the entry's (section 0), and the
/// seconds the calibration took.
pub fn calibrate_entry(e: &FiberEntry, st: &BakeSettings) -> anyhow::Result<(f64, f64)> {
    let t0 = Instant::now();
    let setup = entry_setup(e, st)?;
    let n_wi = setup.stored.len();
    let picks: Vec<usize> = [0, n_wi / 2, n_wi.saturating_sub(1)].into();
    let (mut photons, mut seconds) = (0u64, 0.0);
    for &i in &picks {
        let b = setup.stored[i];
        let inc = crate::fiber::slices::incident_of_bin(
            &setup.grid,
            b / setup.grid.n_phi,
            b % setup.grid.n_phi,
        );
        let mut cal = st.clone();
        cal.photons = st.photons.min(4096);
        loop {
            let t = Instant::now();
            let r = crate::fiber::slices::trace_slice(
                &setup.fibers[0],
                inc,
                &setup.grid,
                &setup.channels,
                &cal,
                st.seed ^ 0xca1b ^ b as u64,
                &crate::cancel::Cancel::NEVER,
            )?;
            let s = t.elapsed().as_secs_f64();
            if s >= 0.02 || cal.photons >= st.photons {
                photons += r.launched;
                seconds += s;
                break;
            }
            cal.photons = (cal.photons * 4).min(st.photons);
        }
    }
    Ok((seconds / photons.max(1) as f64, t0.elapsed().as_secs_f64()))
}

/// `baker plan`: the entry's units, numbered from `*unit_index`; with `cost` (seconds per
/// photon on one thread, and the threads) their estimated seconds.
pub fn plan_entry(
    stem: &str,
    e: &FiberEntry,
    st: &BakeSettings,
    cache: &Cache,
    unit_index: &mut usize,
    cost: Option<(f64, usize)>,
) -> anyhow::Result<Vec<UnitInfo>> {
    let setup = entry_setup(e, st)?;
    let mut out = Vec::new();
    for chunk in &setup.units(st.share_theta) {
        let prefix = format!("{stem}/{}", e.name);
        let (id, key) = setup::unit_id_key(&prefix, chunk, &setup.stored, &setup.key_base);
        let cached = cache.path(&key).exists();
        let traced = (chunk.len() * setup.fibers.len()) as u64 * st.photons_per_direction();
        out.push(UnitInfo {
            id,
            key: key.hex(),
            index: Some(*unit_index),
            photons: (chunk.len() * setup.fibers.len()) as u64 * st.photons,
            cached,
            kind: "fiber",
            // A unit traces its directions in parallel (the sections of each in turn).
            estimate_s: cost.map(|(c, threads)| {
                let usable = chunk.len().clamp(1, threads.max(1));
                if cached {
                    0.0
                } else {
                    traced as f64 * c / usable as f64
                }
            }),
        });
        *unit_index += 1;
    }
    Ok(out)
}
