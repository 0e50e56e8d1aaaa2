//! What a bake of a resolved spec will cost — photon packets and memory — checked against the
//! spec's [`Limits`](super::Limits) before anything is traced. `baker validate`, `baker plan` and `baker bake`
//! all call [`check`]; the bake passes its flags (`--photons`, `--threads`, `--no-reuse`), so
//! a flag that makes a spec too expensive is reported like a spec value.
//!
//! # The memory bound
//!
//! An upper bound on the bake's peak heap, from the sizes the bake allocates (`baker plan`
//! prints it; `limits.memory_gib` caps it). With E entries, λ wavelengths, R radial bins, G
//! simulation groups of at most g entries and T threads:
//!
//! - skin: 96 MiB (program, HDF5, thread stacks) + 3 × E·λ·(2R + 12)·8 B (spectral profiles,
//!   the tables built from them and their encoded bytes) + 2 × 16·T batches × g·R·16 B (the
//!   tallies of the batches a simulation has in flight, and their reduction);
//! - fiber, the largest entry (entries are baked one after another): 96 MiB + 3 × one work
//!   unit's results (u directions × S sections × V·C channels × B bins × 8 B, with their cache
//!   encoding) + 2T × 18 × B·V·C·8 B (the batch tallies of the slices being traced) + 8192 ×
//!   V·C·8 B (absorption table) + the encoded tables (stored directions × tables × V·C × B ×
//!   2 or 4 B).
//!
//! Against the peak resident set (`/usr/bin/time -v`, 2 threads; the photon count does not
//! change memory): `specs/fitzpatrick.yaml` bound 0.12 GiB, measured 110 MiB; `specs/fibers.yaml`
//! bound 0.34 GiB, measured 292 MiB.

use super::check::{count_text, over_limit_message};
use super::error::{SpecError, SpecErrors};
use super::fiber::FiberSpec;
use super::limits::BASE_BYTES;
pub use super::limits::{skin_floor_bytes, GIB};
use super::{SkinSpec, Spec};
use crate::fiber::tracer::shared::MAX_SHARED;
use crate::spec::skin::profiles::{BOOST_PILOT_MAX, MAX_SHARE, NOISE_PILOT_MAX};

/// What the bake's flags change about its cost.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    /// `--photons`: per wavelength and simulation (skin), per direction (fiber).
    pub photons: Option<u64>,
    /// Worker threads the bake runs (`--threads`, default every core).
    pub threads: usize,
    /// `--no-reuse`: one simulation per skin entry.
    pub no_reuse: bool,
    /// `--optics-only`: no transport at all.
    pub optics_only: bool,
}

impl Overrides {
    /// No flags, every core of this machine.
    pub fn none() -> Overrides {
        Overrides {
            threads: rayon::current_num_threads(),
            ..Overrides::default()
        }
    }
}

/// The cost of a bake.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Cost {
    /// Photon packets traced, at most (skin: with every wavelength boosted to the cap).
    pub photons: f64,
    /// Upper bound of the peak heap, bytes ([module docs](self)).
    pub memory_bytes: f64,
}

/// The cost of baking `spec` with `o`; an error if it is over the spec's limits.
pub fn check(spec: &Spec, o: &Overrides) -> Result<Cost, SpecErrors> {
    let (cost, at, file, limits) = match spec {
        Spec::Skin(s) => (skin_cost(s, o), s.photons_at, &s.file, &s.limits),
        Spec::Fiber(s) => (fiber_cost(s, o), s.photons_at, &s.file, &s.limits),
    };
    let mut errors = Vec::new();
    let flag = o
        .photons
        .map_or(String::new(), |p| format!(" (with --photons {p})"));
    if cost.photons > limits.photons {
        errors.push(over(
            file,
            at,
            match spec {
                Spec::Skin(_) => "profiles.photons",
                Spec::Fiber(_) => "bake.photons_per_direction",
            },
            format!(
                "the bake traces up to {:.3e} photon packets{flag}",
                cost.photons
            ),
            "photons",
            format!("{:.3e}", limits.photons),
        ));
    }
    if cost.memory_bytes > limits.memory_gib * GIB {
        errors.push(over(
            file,
            (1, 1),
            "spec",
            format!(
                "the bake needs up to {:.1} GiB of memory{flag} on {} thread(s)",
                cost.memory_bytes / GIB,
                o.threads
            ),
            "memory_gib",
            format!("{} GiB", limits.memory_gib),
        ));
    }
    // The process's own address-space limit (`ulimit -v`, a batch system's memory limit): a
    // bake that cannot fit is refused now rather than aborted by a failed allocation later.
    if let Some(avail) = address_space_bytes().map(|b| 0.75 * b) {
        if cost.memory_bytes > avail && cost.memory_bytes <= limits.memory_gib * GIB {
            errors.push(SpecError::Invalid {
                file: file.to_string(),
                line: 1,
                column: 1,
                field: "spec".into(),
                message: format!(
                    "the bake needs up to {:.1} GiB of memory{flag} on {} thread(s), but this \
                     process may use {:.1} GiB (its address-space limit, `ulimit -v`, with room \
                     for the program); ask for less or run with a higher limit",
                    cost.memory_bytes / GIB,
                    o.threads,
                    avail / GIB
                ),
            });
        }
    }
    if errors.is_empty() {
        Ok(cost)
    } else {
        Err(SpecErrors(errors))
    }
}

/// The soft address-space limit of this process, bytes (`None`: unlimited).
fn address_space_bytes() -> Option<f64> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes one rlimit struct.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } == 0;
    (ok && r.rlim_cur != libc::RLIM_INFINITY).then_some(r.rlim_cur as f64)
}

fn over(
    file: &str,
    at: (u64, u64),
    field: &str,
    what: String,
    name: &str,
    limit: String,
) -> SpecError {
    SpecError::Invalid {
        file: file.to_string(),
        line: at.0,
        column: at.1,
        field: field.to_string(),
        message: over_limit_message(&what, name, &limit),
    }
}

fn skin_cost(s: &SkinSpec, o: &Overrides) -> Cost {
    let p = &s.profiles;
    let e = s.entries.len() as f64;
    let nl = s.wavelengths.len() as f64;
    let nr = crate::transport::RadialBins::fine_then_log_count(
        p.dr_min_mm,
        p.growth,
        p.r_max_mm,
        s.limits.radial_bins,
    ) as f64;
    let (groups, largest) = if o.no_reuse {
        (s.entries.len(), 1)
    } else {
        (s.groups, s.largest_group)
    };
    let photons_each = o.photons.unwrap_or(p.photons) as f64;
    // At most: a noise target's cap per wavelength and its pilots, or the boost's factor and
    // its pilots.
    let (most, pilots) = if p.noise_target > 0.0 {
        (MAX_SHARE as f64, NOISE_PILOT_MAX as f64)
    } else if p.max_photon_boost > 1 {
        (p.max_photon_boost as f64, BOOST_PILOT_MAX as f64)
    } else {
        (1.0, 0.0)
    };
    let photons = if o.optics_only {
        0.0
    } else {
        groups as f64 * nl * (photons_each * most + pilots)
    };
    let t = o.threads.max(1) as f64;
    let in_flight = 2.0 * 16.0 * t * largest as f64 * (nr + 3.0) * 16.0;
    Cost {
        photons,
        memory_bytes: skin_floor_bytes(e, nl, nr) + if o.optics_only { 0.0 } else { in_flight },
    }
}

fn fiber_cost(s: &FiberSpec, o: &Overrides) -> Cost {
    let st = &s.bake;
    let first = st.batches_for(o.photons.unwrap_or(st.photons)) * st.batch;
    // Adaptive allocation may trace a direction up to its cap: the budget counts the cap.
    let per_direction = match st.target {
        Some(_) => first.max(st.batches_for(st.max_photons) * st.batch),
        None => first,
    };
    let grid_bins = ((180.0 / st.res_deg).round() * (360.0 / st.res_deg).round()).max(1.0);
    let t = o.threads.max(1) as f64;
    let value_bytes = match st.precision {
        formats::Precision::F16 => 2.0,
        formats::Precision::F32 => 4.0,
    };
    let mut photons = 0.0;
    let mut memory: f64 = 0.0;
    for e in &s.fibers {
        let sections = e.population.len() as f64;
        let stored = e.stored_directions as f64;
        photons += stored * sections * per_direction as f64;
        let nch = (e.variants.len() * st.channels_per_variant()) as f64;
        let per_slice = nch * grid_bins * 8.0;
        // Directions sharing their photons are traced a φ column (at most every θ row) at a
        // time, and a unit of columns may end up to a column past `unit_len`.
        let column = match e.estimators.share_theta > 1 {
            true => (180.0 / st.res_deg).round().max(1.0),
            false => 1.0,
        };
        let unit_dirs = crate::fiber::slices::unit_len(e.stored_directions) + column as usize - 1;
        let unit = unit_dirs as f64 * sections * per_slice;
        let tables = stored
            * (sections + f64::from(u8::from(sections > 1.0)))
            * nch
            * grid_bins
            * value_bytes;
        // A step's batches hold every slice of a window sharing its photons, in f32, twice
        // over in the first pass (its reflection pass apart), and one more batch per thread
        // is being traced; the columns being traced (at most a unit's) hold every slice's sums
        // (the channels and four error arrays per bin).
        let share = e.estimators.share_theta.clamp(1, MAX_SHARED as u32) as usize;
        let step = crate::fiber::slices::step_batches(grid_bins as usize, nch as usize, share);
        let batch_bytes = per_slice / 2.0 * share as f64;
        let sums = unit_dirs as f64 * (per_slice + 4.0 * grid_bins * 8.0);
        let in_flight = (2.0 * step as f64 + t) * batch_bytes + sums;
        memory = memory.max(3.0 * unit + in_flight + 8192.0 * nch * 8.0 + tables);
    }
    Cost {
        photons,
        memory_bytes: BASE_BYTES + memory,
    }
}

impl Cost {
    /// `1.2e10 photon packets, memory ≤ 0.4 GiB`.
    pub fn describe(&self) -> String {
        format!(
            "{} photon packets, memory ≤ {:.2} GiB",
            if self.photons < 1e6 {
                count_text(self.photons as u64)
            } else {
                format!("{:.3e}", self.photons)
            },
            self.memory_bytes / GIB
        )
    }
}
