//! Resource budgets: what a spec may ask for before the baker allocates it.
//!
//! Every size a spec controls is computed from the spec before anything of that size is
//! allocated, and checked against a limit. The defaults are far above the shipped specs and
//! far below what would abort the process on a workstation; a spec that needs more raises them
//! deliberately in a top-level `limits:` block (both spec kinds):
//!
//! ```yaml
//! limits:
//!   wavelengths: 1000      # per spec (skin) or per `bake.lambda_nm` (fiber)
//!   memory_gib: 64
//! ```
//!
//! | limit | default | what it bounds | the shipped specs need |
//! |---|---|---|---|
//! | `wavelengths` | 471 | wavelengths of a skin spec or of a fiber bake's spectrum (1 nm steps over 360–830 nm) | 31 |
//! | `radial_bins` | 4096 | radial bins of the skin profiles (`profiles.radial`), counted before the grid is built | 129 |
//! | `entries` | 10,000 | entries of a skin spec, sweeps expanded (counted before they are); cross-sections of a fiber spec (Σ `sections`) | 126 |
//! | `photons` | 1e11 | photon packets a bake traces (skin: groups × wavelengths × photons × boost; fiber: directions × sections × photons): about a day on 2 cores | 7.4e8 (`fitzpatrick.yaml`; `fibers-thesis.yaml` raises it to 1e13 for its 3.0e12) |
//! | `variants` | 1024 | dyeings of one fiber entry (sweep dyes × depths of shade, + undyed) | 7 |
//! | `table_gib` | 8 | one fiber entry's tables, uncompressed f32 (stored directions × tables × channels × bins × 4 B) | 0.4 (silk; `fibers-thesis.yaml` raises it to 32 for cotton's 23.5) |
//! | `mask_pixels` | 16,777,216 | pixels of a mask image (4096²), from its header before it is decoded | — |
//! | `polygon_vertices` | 100,000 | vertices of a polygon section (CSV rows or mask outline) | — |
//! | `memory_gib` | 16 | the bake's memory bound ([`super::budget`]), as `baker plan` prints it | 0.34 (`fibers-thesis.yaml` raises it to 32 for its 14.6) |
//!
//! The process's own address-space limit (`ulimit -v`) is a limit too: a bake whose memory
//! bound does not fit in 75 % of it is refused before it starts.

use super::check::{count_text, num, Bounds, Ctx};
use super::yaml::Spanned;

/// The limits of one spec (defaults, raised by its `limits:` block).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Limits {
    pub wavelengths: u64,
    pub radial_bins: u64,
    pub entries: u64,
    pub photons: f64,
    pub variants: u64,
    pub table_gib: f64,
    pub mask_pixels: u64,
    pub polygon_vertices: u64,
    pub memory_gib: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            wavelengths: 471,
            radial_bins: 4096,
            entries: 10_000,
            photons: 1e11,
            variants: 1024,
            table_gib: 8.0,
            mask_pixels: crate::fiber::section::mask::DEFAULT_MAX_PIXELS,
            polygon_vertices: crate::fiber::section::mask::DEFAULT_MAX_VERTICES,
            memory_gib: 16.0,
        }
    }
}

/// What each limit may be set to: a count from 1 (a real number for photons and sizes in GiB),
/// each with a ceiling of its own so that no limit can make a size overflow the arithmetic that
/// checks it.
pub(super) const LIMIT_BOUNDS: [(&str, Bounds); 9] = [
    ("wavelengths", Bounds::whole(1.0, 1e6)),
    ("radial_bins", Bounds::whole(1.0, 1e6)),
    ("entries", Bounds::whole(1.0, 1e7)),
    ("photons", Bounds::closed(1.0, 1e18)),
    ("variants", Bounds::whole(1.0, 1e6)),
    ("table_gib", Bounds::above(0.0, 1e6)),
    ("mask_pixels", Bounds::whole(1.0, 1e10)),
    ("polygon_vertices", Bounds::whole(1.0, 1e8)),
    ("memory_gib", Bounds::above(0.0, 1e6)),
];

/// The bounds of limit `name` ([`LIMIT_BOUNDS`]).
fn limit_bounds(name: &str) -> Bounds {
    LIMIT_BOUNDS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, b)| *b)
        .expect("every limit is in LIMIT_BOUNDS")
}

/// `limits:` as written: resource budgets, each raising (or lowering) a default.
#[derive(Debug, serde::Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawLimits {
    /// Wavelengths of a skin spec or of a fiber bake's spectrum (471 by default).
    pub wavelengths: Option<Spanned<f64>>,
    /// Radial bins of the skin profiles (4096 by default).
    pub radial_bins: Option<Spanned<f64>>,
    /// Entries of a skin spec, sweeps expanded; cross-sections of a fiber spec (10,000 by
    /// default).
    pub entries: Option<Spanned<f64>>,
    /// Photon packets a bake traces (1e11 by default).
    pub photons: Option<Spanned<f64>>,
    /// Dyeings of one fiber entry (1024 by default).
    pub variants: Option<Spanned<f64>>,
    /// One fiber entry's tables, uncompressed f32, GiB (8 by default).
    pub table_gib: Option<Spanned<f64>>,
    /// Pixels of a mask image (4096² by default).
    pub mask_pixels: Option<Spanned<f64>>,
    /// Vertices of a polygon section (100,000 by default).
    pub polygon_vertices: Option<Spanned<f64>>,
    /// The bake's memory bound, GiB (16 by default).
    pub memory_gib: Option<Spanned<f64>>,
}

/// How many wavelengths `start_nm..=stop_nm` in steps of `step_nm` gives, as
/// [`crate::spectral::WavelengthGrid::uniform`] counts them, in f64 so no step can overflow the
/// count (both kinds count before any wavelength is built).
pub(super) fn wavelength_count(start_nm: f64, stop_nm: f64, step_nm: f64) -> f64 {
    ((stop_nm - start_nm) / step_nm + 1e-9).floor() + 1.0
}

impl Ctx {
    /// The limits of a spec: defaults, each raised (or lowered) by `limits:`. Each limit has a
    /// ceiling of its own, so no limit can make a size overflow the arithmetic that checks it.
    pub(super) fn limits(&mut self, raw: Option<&Spanned<RawLimits>>) -> Limits {
        let mut l = Limits::default();
        let Some(raw) = raw else { return l };
        let r = &raw.value;
        let whole = [
            ("wavelengths", &r.wavelengths, &mut l.wavelengths),
            ("radial_bins", &r.radial_bins, &mut l.radial_bins),
            ("entries", &r.entries, &mut l.entries),
            ("variants", &r.variants, &mut l.variants),
            ("mask_pixels", &r.mask_pixels, &mut l.mask_pixels),
            (
                "polygon_vertices",
                &r.polygon_vertices,
                &mut l.polygon_vertices,
            ),
        ];
        for (name, v, out) in whole {
            let b = limit_bounds(name);
            if let Some(n) = self.whole(&format!("limits.{name}"), v, b.lo, b.hi) {
                *out = n;
            }
        }
        let real = [
            ("photons", &r.photons, &mut l.photons),
            ("table_gib", &r.table_gib, &mut l.table_gib),
            ("memory_gib", &r.memory_gib, &mut l.memory_gib),
        ];
        for (name, v, out) in real {
            *out = self.opt_bounds(&format!("limits.{name}"), v, limit_bounds(name), *out);
        }
        l
    }

    /// Records that `start_nm..=stop_nm` in steps of `step_nm` (the value at `at`) gives `n`
    /// wavelengths, over `limits.wavelengths`.
    pub(super) fn too_many_wavelengths(
        &mut self,
        at: (u64, u64),
        field: &str,
        (start_nm, stop_nm, step_nm): (f64, f64, f64),
        n: f64,
        limits: &Limits,
    ) {
        self.over_limit(
            at,
            field,
            format!(
                "{}–{} nm in steps of {} nm gives {} wavelengths",
                num(start_nm),
                num(stop_nm),
                num(step_nm),
                if n < 1e15 {
                    count_text(n as u64)
                } else {
                    format!("{n:.3e}")
                }
            ),
            "wavelengths",
            count_text(limits.wavelengths),
        );
    }
}

/// The program itself (code, HDF5, thread stacks, allocator): what a tiny bake's peak resident
/// set measures (79 MB for `tests/specs/profiles_small.yaml`), with room.
pub const BASE_BYTES: f64 = 96.0 * 1024.0 * 1024.0;
/// Bytes in a GiB.
pub const GIB: f64 = (1u64 << 30) as f64;

/// The part of a skin bake's memory bound that does not depend on how entries group: the
/// program, the spectral profiles of `entries` × `wavelengths` × `radial_bins` and the tables
/// built from them (and their layer optics). The resolver checks it before it evaluates any
/// entry, so a spec that cannot fit is refused at once.
pub fn skin_floor_bytes(entries: f64, wavelengths: f64, radial_bins: f64) -> f64 {
    BASE_BYTES + 3.0 * entries * wavelengths * (2.0 * radial_bins + 12.0) * 8.0
}
