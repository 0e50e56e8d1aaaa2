//! 4D BCSDF tables (§5.3.2, §5.5): for every stored incoming bin, one trace of the fiber lit
//! by a beam averaged over that bin, binned over the outgoing sphere for every channel of a
//! dye sweep at once ([`super::sweep`]).
//!
//! Variance reduction (the thesis shoots 16 M plain photons per direction), each switchable
//! in the spec's `bake:` block and each tested against plain tracing
//! (`baker/tests/fiber_references.rs`, `estimators_agree_with_plain_tracing`):
//! - **Stratified entry offsets**: photon j of a batch of n enters at (j + u)/n across the
//!   beam, so the beam is covered evenly.
//! - **Splitting at interfaces** (`split` for events met from outside: the R lobe and the
//!   entry; `exit_draws` for events met from inside: every exit lobe TT, TRT, … and the
//!   internal reflections): the event is drawn k times; every draw that leaves is followed
//!   at weight w/k, and the m draws that stay carry w·m/k together, which one of them
//!   (picked uniformly) carries on at the full weight w with probability m/k (Russian
//!   roulette). Unbiased: the expected weight of what leaves and of what goes on is plain
//!   tracing's, draw by draw. The lobe of a rough exit (6–17° Beckmann, many 2° bins) then
//!   gets k samples per photon where plain tracing gets one, while the path lives as long as
//!   a plain photon's. Exits through an edge on the convex hull are scored without a ray
//!   query ([`super::Section::leaves_freely`]).
//! - **Expected-value exit scoring** (`expected_exits: inside | all`, [`super::lobe`]): at an
//!   event met from inside whose exits leave the fiber for good, the exit lobe's first-facet
//!   part (a density: [`super::Surface::first_facet_pdf`]) is scored over a cone of bins in
//!   expectation, and the event's draws score the rest (exits through a second facet or
//!   outside the cone) and pick the continuation: ⌈exit_draws·(1 − covered)⌉ of them, at
//!   least one, where `covered` is the probability the expectation scored (the draw count
//!   depends only on the event's own quadrature offset, so each draw's weight 1/count keeps it
//!   unbiased). `all` also scores the first event's reflection lobe R in expectation, by a
//!   pass of its own launches at the points of a scrambled Sobol' set (R depends on the launch
//!   and the lobe's quadrature offset alone): a 16th of the photons' in the first pass, then
//!   the share the two passes' measured noise asks for (Neyman allocation, one launch per 64
//!   to one per photon: near grazing incidence most of the power is reflected); that event
//!   keeps its `split` draws for the entry. It pays where lobes cover few bins: at 2°,
//!   polyester (β ≈ 3°) and silk reach the thesis's noise faster with it, cotton (β ≈ 15°,
//!   windows of thousands of bins) slower (`validation/bench-runs/2026-12-05-fiber-ev-speed`).
//! - **Randomised Sobol' points** (`sampling: sobol`, [`crate::math::sampler`]): each batch one
//!   scrambled and shifted Sobol' point set over the launch (incidence within the bin, entry
//!   offset) and the first boundary events of every photon; each photon is exactly uniform,
//!   so every estimate stays unbiased, and batches stay independent for the errors.
//! - **Adaptive allocation** (`target_rel_se`, `max_photons_per_direction`): after the first
//!   `photons_per_direction`, groups of batches follow until the slice's median relative
//!   error reaches the target ([`NoiseTarget`]) or the cap, each as many batches as the
//!   error's 1/√batches decline says are still needed (at most 16). The check sees the batches merged
//!   in order, so the stopping point does not depend on the thread count; it uses the median
//!   over thousands of bins, a statistic nearly independent of any one bin's value, so the
//!   bias of a data-dependent stop is far below the noise.
//! - **Photons shared across θi** (`share_theta: k`, [`trace_group`],
//!   [`super::tracer::shared`]): the stored directions of one φ column are traced together,
//!   each batch of photons shared by a window of k neighbouring θ rows, the windows sliding
//!   one row at a time ([`Windows`]); the beams of one φi meet the fiber at the same points,
//!   so one walk inside serves every direction of the window whose entry lobe could have
//!   produced it, weighted by multiple importance sampling (balance heuristic over the
//!   window's entry densities). Each batch is an unbiased estimate for every direction it
//!   scores; a direction that reaches its target leaves its windows, the others go on.
//!
//! Standard errors come from the spread of independent batches (batch means), which is
//! valid for split, stratified and adaptively stopped estimators alike, and for batches whose
//! first-reflection share differs (independent, equal means: the spread's expectation is
//! still the sum of their variances).

use std::time::Instant;

use rayon::prelude::*;

use super::exit_bins::ExitBins;
use super::scratch;
use super::sweep::{ChannelKind, Channels};
use super::tracer::shared::{SharedExits, Windows, MAX_SHARED};
use super::tracer::{Draws, Exits, PhotonStats, Setup};
use super::{Fiber, Incident};
use crate::cancel::{Cancel, Cancelled};
use crate::math::avx2::avx2_dispatch;
use crate::math::rng::{batch_rng, uniform, BatchRng};
use crate::math::sampler::{PathSampler, Scramble};
use formats::{AngularGrid, Precision};
use rand_core::Rng;

/// Which first-facet exit lobes a bake scores in expectation ([`super::lobe`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExpectedExits {
    /// None: every exit is a draw.
    None,
    /// The exit lobes of events met from inside (TT, TRT, …) on each photon's main path
    /// (the plain branches a split event starts score theirs by their draw).
    Inside,
    /// Those and the reflection lobe R of the first event, scored by a pass of launches of
    /// its own ([`super::tracer`]'s `first_reflection`).
    All,
}

impl ExpectedExits {
    pub fn inside(self) -> bool {
        self != ExpectedExits::None
    }

    pub fn first_reflection(self) -> bool {
        self == ExpectedExits::All
    }
}

/// Where the photons of a batch take their uniform numbers ([`crate::math::sampler`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampling {
    /// Independent random numbers; the entry offset stratified (j + u)/n across the beam.
    Random,
    /// Each batch one randomised (scrambled, shifted) Sobol' point set over the launch and
    /// the first boundary events of every photon's main path.
    Sobol,
}

/// How a bake scores its photons: every estimator is unbiased, so these change the time and
/// the noise of a table, not what it estimates (`bake:` in a fiber spec, or a fiber's own
/// `estimators:`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Estimators {
    pub split: u32,
    pub exit_draws: u32,
    pub expected_exits: ExpectedExits,
    pub sampling: Sampling,
    pub share_theta: u32,
}

/// Settings of a bake (`bake:` in a fiber spec).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BakeSettings {
    /// Bin width of θ and φ, degrees (thesis: 2°).
    pub res_deg: f64,
    /// Photons launched per stored incoming direction (rounded up to whole batches); with a
    /// `target`, the first pass.
    pub photons: u64,
    /// Adaptive allocation: trace each direction on until its noise reaches this.
    pub target: Option<NoiseTarget>,
    /// The most photons a direction may use under `target`.
    pub max_photons: u64,
    pub seed: u64,
    /// Draws per boundary event of a photon's main path met from outside (1: plain tracing).
    pub split: u32,
    /// Draws per boundary event met from inside the fiber: every exit lobe is sampled this
    /// many times (1: plain tracing).
    pub exit_draws: u32,
    /// Photons per batch (one RNG stream, one term of the batch-means error).
    pub batch: u64,
    /// Where the photons' uniform numbers come from.
    pub sampling: Sampling,
    /// Which exit lobes are scored in expectation ([`super::lobe`]).
    pub expected_exits: ExpectedExits,
    /// Incoming directions of one azimuth and neighbouring elevations that share their
    /// photons ([`super::tracer::shared`]; 1: each traced alone). Left out of the written
    /// settings (and the cache keys) at 1.
    #[serde(skip_serializing_if = "is_one")]
    pub share_theta: u32,
    pub precision: Precision,
    /// Mantissa bits kept (bit rounding; the type's full width is lossless).
    pub keep_bits: u32,
    pub channels: ChannelKind,
    pub lambda_nm: Vec<f64>,
}

fn is_one(x: &u32) -> bool {
    *x == 1
}

impl Default for BakeSettings {
    fn default() -> Self {
        Self {
            res_deg: 2.0,
            photons: 1 << 20,
            seed: 1,
            target: None,
            max_photons: 1 << 24,
            split: 1,
            exit_draws: 1,
            batch: 4096,
            sampling: Sampling::Random,
            expected_exits: ExpectedExits::None,
            share_theta: 1,
            precision: Precision::F16,
            keep_bits: 10,
            channels: ChannelKind::Rgb,
            lambda_nm: (0..31).map(|i| 400.0 + 10.0 * i as f64).collect(),
        }
    }
}

impl BakeSettings {
    /// Batches traced per stored direction for `photons` asked for: whole batches, at least
    /// two (the per-bin standard error needs two).
    pub fn batches_for(&self, photons: u64) -> u64 {
        photons.div_ceil(self.batch).max(2)
    }

    /// Photons traced per stored direction: [`BakeSettings::batches_for`] whole batches.
    pub fn photons_per_direction(&self) -> u64 {
        self.batches_for(self.photons) * self.batch
    }

    /// The settings that choose the estimators (what a fiber's `estimators:` may set).
    pub fn estimators(&self) -> Estimators {
        Estimators {
            split: self.split,
            exit_draws: self.exit_draws,
            expected_exits: self.expected_exits,
            sampling: self.sampling,
            share_theta: self.share_theta,
        }
    }

    /// These settings with `e`'s estimators.
    pub fn with_estimators(&self, e: Estimators) -> BakeSettings {
        BakeSettings {
            split: e.split,
            exit_draws: e.exit_draws,
            expected_exits: e.expected_exits,
            sampling: e.sampling,
            share_theta: e.share_theta,
            ..self.clone()
        }
    }

    /// Draws per boundary event of a photon's main path.
    pub fn draws(&self) -> Draws {
        Draws {
            outside: self.split,
            inside: self.exit_draws.max(self.split),
        }
    }

    /// Channels per dye variant: 3 (RGB) or one per wavelength of `lambda_nm` (spectral).
    pub fn channels_per_variant(&self) -> usize {
        match self.channels {
            ChannelKind::Rgb => 3,
            ChannelKind::Spectral => self.lambda_nm.len(),
        }
    }
}

/// What adaptive allocation traces a direction to. Written (manifest, `fiber trace --json`)
/// as the spec spells it: `"thesis"` or the number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NoiseTarget {
    /// The thesis's noise for this slice: the median over the bins with f̂ ≥ 1 % of the
    /// slice's maximum of √((1 − p_b)/(N·p_b)), the relative standard error plain sampling
    /// with N = [`THESIS_PHOTONS`] gives bin b with share p_b of the scattered power (§5.3.2:
    /// "16 million photons per incoming direction").
    Thesis,
    /// A median relative standard error over the same bins.
    RelSe(f64),
}

impl serde::Serialize for NoiseTarget {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            NoiseTarget::Thesis => s.serialize_str("thesis"),
            NoiseTarget::RelSe(x) => s.serialize_f64(*x),
        }
    }
}

impl NoiseTarget {
    /// Whether a slice with noise `n` reaches the target.
    pub fn met_by(self, n: &Noise) -> bool {
        n.bins > 0 && n.median_rel_se <= self.rel_se(n)
    }

    /// The median relative error a slice with noise `n` must reach.
    pub fn rel_se(self, n: &Noise) -> f64 {
        match self {
            NoiseTarget::Thesis => n.thesis_rel_se,
            NoiseTarget::RelSe(x) => x,
        }
    }
}

/// Photons per incoming direction in the thesis (§5.3.2, Table 10's bakes).
pub const THESIS_PHOTONS: f64 = 16e6;

/// Serde for f64 values that are f32 values: written as f32 (lossless for them).
mod f32_values {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|&x| x as f32))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<f32>::deserialize(d)?
            .into_iter()
            .map(f64::from)
            .collect())
    }
}

/// Noise of a slice: relative standard error of the sampling density per bin, over bins
/// whose density exceeds 1 % of the slice's maximum.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Noise {
    pub median_rel_se: f64,
    pub p90_rel_se: f64,
    pub bins: usize,
    /// The thesis's noise over the same bins ([`NoiseTarget::Thesis`]).
    #[serde(default)]
    pub thesis_rel_se: f64,
}

/// One traced incoming bin.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SliceResult {
    /// Fractions of the intercepted power per channel and bin, `[channel][θo][Δφ]`: f32
    /// values (the tables store at most f32, and the noise is orders above its rounding), so
    /// the unit cache keeps 4 bytes per value (written as f32) and a resumed bake reads back
    /// exactly what a clean one computes.
    #[serde(with = "f32_values")]
    pub fraction: Vec<f64>,
    /// Λ(ωi) per channel and its standard error.
    pub albedo: Vec<f64>,
    pub albedo_se: Vec<f64>,
    /// Per bin: standard error (batch means) of variant 0's fraction averaged over its
    /// channels, `[θo][Δφ]` (the density whose noise [`Noise`] summarises).
    #[serde(default)]
    pub density_se: Vec<f64>,
    /// Per Δφ column: standard error (batch means) of the same density summed over θo.
    #[serde(default)]
    pub dphi_se: Vec<f64>,
    pub noise: Noise,
    pub launched: u64,
    pub intercepted: u64,
    pub lost_weight: f64,
    pub seconds: f64,
}

impl SliceResult {
    /// The normalised BCSDF f̂ = P/(Λ·ΔΩ), sr⁻¹, per channel (zero where Λ = 0).
    pub fn normalised(&self, grid: &AngularGrid) -> Vec<f64> {
        let bins = grid.bins();
        let mut out = vec![0.0; self.fraction.len()];
        let omega: Vec<f64> = (0..grid.n_theta).map(|t| grid.solid_angle(t)).collect();
        for (c, a) in self.albedo.iter().enumerate() {
            if *a <= 0.0 {
                continue;
            }
            for b in 0..bins {
                out[c * bins + b] = self.fraction[c * bins + b] / (a * omega[b / grid.n_phi]);
            }
        }
        out
    }
}

/// The incoming bin (θ row `it`, φ column `jp`) as an incident beam averaged over the bin.
pub fn incident_of_bin(grid: &AngularGrid, it: usize, jp: usize) -> Incident {
    let r = grid.res_deg;
    Incident::from_deg(grid.theta_centre_deg(it), grid.phi_centre_deg(jp)).with_spread_deg(r, r)
}

/// Stored incoming directions per work unit of a bake: a function of their number only, so
/// the units (and shards) do not depend on the machine.
pub fn unit_len(n_wi: usize) -> usize {
    n_wi.div_ceil(48).max(4)
}

/// Photons per launch of the first-reflection pass ([`ExpectedExits::All`]) in a direction's
/// first pass; after it, [`SliceSums::reflection_launches`] sets the share the two passes'
/// measured noise asks for. Measured at 2° (`validation/bench-runs/2026-12-06-fiber-
/// reflection-share`): silk's photons dominate its noise at every θi, so 64 and 16 give the
/// same noise per second there, while polyester near grazing incidence (most of the power
/// reflected) needs a launch per two photons.
const FIRST_REFLECTION_SHARE: u64 = 16;

/// The fewest photons per launch of the first-reflection pass after the first pass.
const MIN_REFLECTION_SHARE: u64 = 1;

/// The most photons per launch of the first-reflection pass after the first pass.
const MAX_REFLECTION_SHARE: u64 = 64;

/// What the tallies of one step's batches may hold ([`step_batches`]).
const STEP_BYTES: f64 = 256.0 * 1024.0 * 1024.0;

/// Batches traced in one step of `drive` before their tallies are merged in order: as many
/// as 256 MiB hold (`STEP_BYTES`; each batch's f32 tallies of `share` slices × `nch` channels ×
/// `bins`, twice over for the first-reflection pass tallied apart), between 16 and 128. A
/// step ends with the cores waiting for its last batch, about half a batch each, so more
/// batches per step idle less: 16 left 6 % of two cores idle tracing silk and cotton at 2°
/// (`validation/bench-runs/2026-12-07-fiber-steps`); a wide sweep's tallies keep it at 16.
/// From the spec alone, so the batches each slice gets do not depend on the thread count.
pub fn step_batches(bins: usize, nch: usize, share: usize) -> u64 {
    let per_batch = (bins * nch * share.max(1) * 4 * 2).max(1) as f64;
    ((STEP_BYTES / per_batch) as u64).clamp(16, 128)
}

/// Traces one incoming bin for every channel. Deterministic for a given seed whatever the
/// thread count (batches are merged in order). `cancel` is checked before every group of
/// batches.
pub fn trace_slice(
    fiber: &Fiber,
    inc: Incident,
    grid: &AngularGrid,
    channels: &Channels,
    s: &BakeSettings,
    seed: u64,
    cancel: &Cancel,
) -> Result<SliceResult, Cancelled> {
    let start = Instant::now();
    let job = SliceJob {
        setup: setup_of(fiber, inc, grid, s),
        grid,
        bins: ExitBins::new(grid, inc.phi_rad),
        channels,
        s,
        seed,
    };
    let mut r = drive(
        Windows::new(1, 1),
        grid,
        channels,
        s,
        cancel,
        start,
        |b, _, launches, apart| vec![job.trace_batch(b, launches[0], apart)],
    )?;
    Ok(r.pop().expect("one slice"))
}

/// Traces the incoming bins `incs` of one azimuth and consecutive elevations (in order) with
/// shared photons ([`super::tracer::shared`]): windows of `share_theta` of them
/// ([`Windows`]) trace a batch each in turn, seeded by `seeds[0]`. One result per bin, in
/// order, each as [`trace_slice`] gives it (the photons of the batches that scored it; the
/// group's seconds shared equally). Bins that cannot share (one alone, a smooth or cuticled
/// fiber, other azimuths, `share_theta` 1) are traced alone with their own `seeds`.
pub fn trace_group(
    fiber: &Fiber,
    incs: &[Incident],
    grid: &AngularGrid,
    channels: &Channels,
    s: &BakeSettings,
    seeds: &[u64],
    cancel: &Cancel,
) -> Result<Vec<SliceResult>, Cancelled> {
    let setups: Vec<Setup> = incs
        .iter()
        .map(|&inc| setup_of(fiber, inc, grid, s))
        .collect();
    if incs.len() < 2 || s.share_theta < 2 || !Setup::can_share(&setups) {
        return incs
            .iter()
            .zip(seeds)
            .map(|(&inc, &seed)| trace_slice(fiber, inc, grid, channels, s, seed, cancel))
            .collect();
    }
    let start = Instant::now();
    let job = GroupJob {
        setups,
        bins: ExitBins::new(grid, incs[0].phi_rad),
        grid,
        channels,
        s,
        seed: seeds[0],
    };
    drive(
        Windows::new(incs.len(), s.share_theta as usize),
        grid,
        channels,
        s,
        cancel,
        start,
        |b, members, launches, apart| job.trace_batch(b, members, launches, apart),
    )
}

/// A slice's tracer setup with the settings' expected-value scoring.
fn setup_of<'a>(
    fiber: &'a Fiber,
    inc: Incident,
    grid: &AngularGrid,
    s: &BakeSettings,
) -> Setup<'a> {
    Setup::new(fiber, inc).with_expected_exits(
        *grid,
        s.expected_exits.inside(),
        s.expected_exits.first_reflection(),
    )
}

/// The batches of the `windows.n` slices traced together: `batch(b, members, launches,
/// apart)` traces batch `b` for the slices `members` (in order; some of window b mod
/// `windows.count()`) and returns one score each, in order (`launches[i]` of slice i's
/// first-reflection pass, tallied apart when `apart`). Each step hands every slice an
/// allotment of batches: in the first pass the rest of its first `photons`, then, with a
/// target, the further batches the error's decline says it needs (none once it reaches the
/// target), never past the cap. The windows are visited in turn, each batch scoring the
/// window's slices that still have some of their allotment (a window without any is
/// skipped), at most [`step_batches`] per step; so a slice gets exactly its batches, from
/// every window it lies in, and one that reached its target gets no more (every batch is an
/// unbiased estimate of each slice it scores, so the batch-means error of batches traced by
/// different windows stays right: independent terms of one mean). The allotments come from
/// the batches merged in order, so which batches score which slices does not depend on the
/// thread count.
fn drive(
    windows: Windows,
    grid: &AngularGrid,
    channels: &Channels,
    s: &BakeSettings,
    cancel: &Cancel,
    start: Instant,
    batch: impl Fn(u64, &[usize], &[u64], bool) -> Vec<BatchScore> + Sync,
) -> Result<Vec<SliceResult>, Cancelled> {
    let (n, per_round) = (windows.n, windows.count() as u64);
    let step = step_batches(grid.bins(), channels.len(), windows.k) as usize;
    let first = s.batches_for(s.photons);
    let cap = match s.target {
        Some(_) => s.batches_for(s.max_photons).max(first),
        None => first,
    };
    let mut sums: Vec<SliceSums> = (0..n)
        .map(|_| SliceSums::new(grid, channels.len(), channels.per_variant()))
        .collect();
    let first_launches = match s.expected_exits.first_reflection() {
        true => (s.batch / FIRST_REFLECTION_SHARE).max(16),
        false => 0,
    };
    let mut launches = vec![first_launches; n];
    let (mut b0, mut first_pass) = (0, true);
    loop {
        // What each slice may still take in this step.
        let mut left: Vec<u64> = match first_pass {
            true => sums.iter().map(|x| first.saturating_sub(x.used)).collect(),
            false => {
                let Some(t) = s.target else { break };
                let more = |x: &SliceSums| match x.used < cap {
                    true => x.batches_to(grid, t).map_or(0, |m| m.min(cap - x.used)),
                    false => 0,
                };
                sums.iter().map(more).collect()
            }
        };
        if left.iter().all(|&l| l == 0) {
            break;
        }
        cancel.check()?;
        let mut todo: Vec<(u64, Vec<usize>)> = Vec::new();
        while todo.len() < step && left.iter().any(|&l| l > 0) {
            let w = windows.members((b0 % per_round) as usize);
            let members: Vec<usize> = w.filter(|&i| left[i] > 0).collect();
            if !members.is_empty() {
                members.iter().for_each(|&i| left[i] -= 1);
                todo.push((b0, members));
            }
            b0 += 1;
        }
        // The first pass tallies its reflection pass apart, to set the share that follows.
        let apart = first_pass && s.target.is_some() && first_launches > 0;
        let parts: Vec<(Vec<usize>, Vec<BatchScore>)> = todo
            .into_par_iter()
            .map(|(b, members)| {
                let part = batch(b, &members, &launches, apart);
                (members, part)
            })
            .collect();
        for (members, part) in parts {
            debug_assert_eq!(members.len(), part.len());
            for (&i, p) in members.iter().zip(part) {
                sums[i].add(&p);
                scratch::recycle(p.local);
                scratch::recycle(p.reflection);
            }
        }
        if first_pass && sums.iter().all(|x| x.used >= first) {
            first_pass = false;
            if apart {
                for (l, sum) in launches.iter_mut().zip(&sums) {
                    *l = sum.reflection_launches(grid, s.batch, first_launches);
                }
            }
        }
    }
    let mut out: Vec<SliceResult> = sums
        .into_iter()
        .map(|x| {
            let launched = x.used * s.batch;
            x.into_result(grid, launched, start)
        })
        .collect();
    for r in &mut out {
        r.seconds /= n as f64;
    }
    Ok(out)
}

/// Photon `j` of a batch of `n`: its uniform numbers (point `j` of the batch's scrambled
/// Sobol' set, or the random stream) and, without a point set, its stratified entry offset
/// (j + u)/n across the beam.
fn photon_sampler<'r>(
    rng: &'r mut BatchRng,
    scramble: Option<&'r Scramble>,
    j: u64,
    n: u64,
) -> (PathSampler<'r>, Option<f64>) {
    match scramble {
        Some(sc) => (PathSampler::sobol(rng, sc, j as u32), None),
        None => {
            let off = (j as f64 + uniform(rng.next_u64())) / n as f64;
            (PathSampler::random(rng), Some(off))
        }
    }
}

/// What every batch of one incoming bin shares.
struct SliceJob<'a> {
    setup: Setup<'a>,
    grid: &'a AngularGrid,
    /// The outgoing bins of the incoming azimuth.
    bins: ExitBins,
    channels: &'a Channels,
    s: &'a BakeSettings,
    seed: u64,
}

/// The scores of one batch: weight per bin and channel, `[bin][channel]` (`f32`, see
/// [`ChannelScore`]), and its photons.
struct BatchScore {
    local: Vec<f32>,
    /// Per channel: every weight the batch scored, summed in `f64` (its albedo before
    /// normalisation; see [`ChannelScore`]).
    total: Vec<f64>,
    /// When the batch tallies its first-reflection pass apart: that pass's part of `local`
    /// (same layout); empty otherwise.
    reflection: Vec<f32>,
    hits: u64,
    lost: f64,
    /// Σ g over the photons that met the fiber (their intercepted power).
    g_sum: f64,
}

impl SliceJob<'_> {
    /// Traces batch `b`: `s.batch` photons at stratified entry offsets, each exit binned for
    /// every channel at once, and `launches` of the first-reflection pass (tallied apart as
    /// well when `apart`).
    fn trace_batch(&self, b: u64, launches: u64, apart: bool) -> BatchScore {
        let (grid, channels, s) = (self.grid, self.channels, self.s);
        let mut rng = batch_rng(self.seed, b);
        let mut sc = ChannelScore::new(grid, &self.bins, channels);
        let (mut h, mut l, mut gsum) = (0u64, 0.0, 0.0);
        let n = s.batch;
        let scramble = (s.sampling == Sampling::Sobol).then(|| Scramble::draw(&mut rng));
        for j in 0..n {
            let (mut u, off) = photon_sampler(&mut rng, scramble.as_ref(), j, n);
            let st = self.setup.photon(&mut u, off, s.draws(), &mut sc);
            h += st.hit as u64;
            if st.hit {
                gsum += st.g;
            }
            l += st.lost;
        }
        // The first-reflection pass: launches of its own, each scoring the first event's
        // reflection lobe in expectation for the batch's n photons, at the points of one
        // scrambled Sobol' set over the launch and the lobe's quadrature offset (each point
        // uniform, so unbiased; the set's strata cut the pass's noise 1.2–2.3× against
        // independent points on polyester).
        let mut reflection = Vec::new();
        if launches > 0 {
            let mut own = apart.then(|| ChannelScore::new(grid, &self.bins, channels));
            let to = own.as_mut().unwrap_or(&mut sc);
            let scramble = Scramble::draw(&mut rng);
            let scale = n as f64 / launches as f64;
            for k in 0..launches {
                let mut u = PathSampler::sobol(&mut rng, &scramble, k as u32);
                self.setup.first_reflection(&mut u, None, scale, to);
            }
            if let Some(own) = own {
                let (local, total) = own.finish();
                sc.local.iter_mut().zip(&local).for_each(|(a, x)| *a += x);
                sc.add_total(&total);
                reflection = local;
            }
        }
        let (local, total) = sc.finish();
        BatchScore {
            local,
            total,
            reflection,
            hits: h,
            lost: l,
            g_sum: gsum,
        }
    }
}

/// What every batch of a group of slices sharing their photons shares ([`trace_group`]).
struct GroupJob<'a> {
    setups: Vec<Setup<'a>>,
    /// The outgoing bins of the group's incoming azimuth.
    bins: ExitBins,
    grid: &'a AngularGrid,
    channels: &'a Channels,
    s: &'a BakeSettings,
    seed: u64,
}

impl GroupJob<'_> {
    /// Batch `b` of the slices `members`: `s.batch` photons they share
    /// ([`Setup::photon_shared`]) at stratified entry offsets, then each one's own
    /// first-reflection pass (`launches[i]` launches, tallied apart as well when `apart`), as
    /// [`SliceJob::trace_batch`] does.
    fn trace_batch(
        &self,
        b: u64,
        members: &[usize],
        launches: &[u64],
        apart: bool,
    ) -> Vec<BatchScore> {
        let (grid, channels, s) = (self.grid, self.channels, self.s);
        let setups: Vec<&Setup> = members.iter().map(|&i| &self.setups[i]).collect();
        let launches: Vec<u64> = members.iter().map(|&i| launches[i]).collect();
        let k = setups.len();
        let mut rng = batch_rng(self.seed, b);
        let mut sc = ChannelScore::shared(grid, &self.bins, channels, k);
        let (mut hits, mut lost, mut gsum) = (0u64, vec![0.0; k], vec![0.0; k]);
        let n = s.batch;
        let scramble = (s.sampling == Sampling::Sobol).then(|| Scramble::draw(&mut rng));
        let mut stats = [PhotonStats::default(); MAX_SHARED];
        for j in 0..n {
            let (mut u, off) = photon_sampler(&mut rng, scramble.as_ref(), j, n);
            Setup::photon_shared(&setups, &mut u, off, s.draws(), &mut sc, &mut stats[..k]);
            hits += stats[0].hit as u64;
            for i in 0..k {
                if stats[i].hit {
                    gsum[i] += stats[i].g;
                }
                lost[i] += stats[i].lost;
            }
        }
        let (local, total) = sc.finish();
        let (nch, bins) = (channels.len(), grid.bins());
        let mut out: Vec<BatchScore> = (0..k)
            .map(|i| {
                let mut own: Vec<f32> = scratch::zeroed(bins * nch);
                for (bo, bl) in own.chunks_exact_mut(nch).zip(local.chunks_exact(k * nch)) {
                    bo.copy_from_slice(&bl[i * nch..(i + 1) * nch]);
                }
                BatchScore {
                    local: own,
                    total: total[i * nch..(i + 1) * nch].to_vec(),
                    reflection: Vec::new(),
                    hits,
                    lost: lost[i],
                    g_sum: gsum[i],
                }
            })
            .collect();
        scratch::recycle(local);
        // Each slice's first-reflection pass, as for a slice traced alone.
        for (i, o) in out.iter_mut().enumerate() {
            if launches[i] == 0 {
                continue;
            }
            let mut pass = ChannelScore::new(grid, &self.bins, channels);
            let scramble = Scramble::draw(&mut rng);
            let scale = n as f64 / launches[i] as f64;
            for l in 0..launches[i] {
                let mut u = PathSampler::sobol(&mut rng, &scramble, l as u32);
                setups[i].first_reflection(&mut u, None, scale, &mut pass);
            }
            let (local, total) = pass.finish();
            o.local.iter_mut().zip(&local).for_each(|(a, x)| *a += x);
            o.total.iter_mut().zip(&total).for_each(|(a, x)| *a += x);
            if apart {
                o.reflection = local;
            } else {
                scratch::recycle(local);
            }
        }
        out
    }
}

/// One batch's scores: weight per bin and channel, each exit weighted by every channel's
/// attenuation over its path ([`Channels::attenuations`], evaluated once per path length).
///
/// The batch's tallies are `f32` (the slice's sums over batches, the albedos and the error
/// estimates are `f64`): a sweep's exit adds a row of every variant's channels to each bin
/// its lobe covers, and the `[bin][channel]` array, 864 kB in `f64` for 20 RGB variants at
/// 6°, outgrew the 1 MiB second-level cache and made a 20-variant cotton sweep cost
/// 1.30–1.37× one variant; in `f32` (432 kB) 1.20–1.23×
/// (`validation/bench-runs/2026-12-06-fiber-f32-tallies`).
/// A bin's batch sum of n positive terms errs by at most (n − 1)·2⁻²⁴ of it and by about
/// √n·2⁻²⁴ in practice (6·10⁻⁵ for 10⁶ terms): far below the tables' per-bin noise (≥ 1 %
/// at the thesis's noise) and the rounding `quantise_to_se` adds to them; measured against
/// `f64` tallies at 2° and the thesis's settings, ≤ 1.1·10⁻⁶ per bin, ≤ 4.3·10⁻⁴ of its
/// standard error.
///
/// The albedos are summed apart in `f64`, once per exit (each exit's weights over the bins
/// it covers, times its row), so a white furnace still gives exactly one and no undyed
/// channel's albedo rounds above one.
struct ChannelScore<'a> {
    local: Vec<f32>,
    /// Per slice of a shared photon's group ([`crate::fiber::tracer::shared`]; one slice,
    /// weight 1, otherwise): the weight of what is scored, applied to its row of channels.
    weights: Vec<f64>,
    /// One path length's channel attenuations ([`Channels::attenuations`]).
    dye: Vec<f64>,
    /// `weights` ⊗ `dye`: slice-major, `[slice][channel]`.
    row: Vec<f64>,
    /// `row` in `f32`, as the tallies add it.
    row32: Vec<f32>,
    /// Per channel: Σ over the exits scored so far of (their weights) × (their row).
    total: Vec<f64>,
    /// Σ of the weights scored with the current `row` (not yet in `total`).
    pending: f64,
    last: f64,
    channels: &'a Channels,
    /// The outgoing bins of the incoming azimuth.
    bins: &'a ExitBins,
}

impl<'a> ChannelScore<'a> {
    fn new(grid: &AngularGrid, bins: &'a ExitBins, channels: &'a Channels) -> Self {
        Self::shared(grid, bins, channels, 1)
    }

    /// The scores of `slices` slices at once, `[bin][slice][channel]`.
    fn shared(
        grid: &AngularGrid,
        bins: &'a ExitBins,
        channels: &'a Channels,
        slices: usize,
    ) -> Self {
        let nch = channels.len() * slices;
        ChannelScore {
            local: scratch::zeroed(grid.bins() * nch),
            weights: vec![1.0; slices],
            dye: vec![0.0; channels.len()],
            row: vec![0.0; nch],
            row32: vec![0.0; nch],
            total: vec![0.0; nch],
            pending: 0.0,
            last: f64::NAN,
            channels,
            bins,
        }
    }

    /// Moves the weights scored with the current row into `total`.
    fn settle(&mut self) {
        if self.pending != 0.0 {
            for (t, r) in self.total.iter_mut().zip(&self.row) {
                *t += self.pending * r;
            }
            self.pending = 0.0;
        }
    }

    /// Adds another tally's per-channel totals.
    fn add_total(&mut self, total: &[f64]) {
        self.settle();
        self.total.iter_mut().zip(total).for_each(|(a, x)| *a += x);
    }

    /// The `[bin][channel]` tallies and the per-channel totals.
    fn finish(mut self) -> (Vec<f32>, Vec<f64>) {
        self.settle();
        (self.local, self.total)
    }
}

impl Exits for ChannelScore<'_> {
    #[inline]
    fn leave(&mut self, dir: [f64; 3], path_um: f64, w: f64) {
        let bin = self.bins.bin(dir);
        self.leave_bin(bin, path_um, w);
    }

    #[inline]
    fn leave_bin(&mut self, bin: u32, path_um: f64, w: f64) {
        if path_um != self.last {
            self.settle();
            self.channels.attenuations(path_um, &mut self.dye);
            let nc = self.dye.len();
            let rows = self
                .row
                .chunks_exact_mut(nc)
                .zip(self.row32.chunks_exact_mut(nc));
            for ((row, row32), &wk) in rows.zip(&self.weights) {
                for ((r, r32), &x) in row.iter_mut().zip(row32).zip(&self.dye) {
                    *r = wk * x;
                    *r32 = *r as f32;
                }
            }
            self.last = path_um;
        }
        self.pending += w;
        let nch = self.row.len();
        let b = bin as usize;
        add_scaled(
            &mut self.local[b * nch..(b + 1) * nch],
            w as f32,
            &self.row32,
        );
    }
}

impl SharedExits for ChannelScore<'_> {
    fn set_weights(&mut self, w: &[f64]) {
        if w != self.weights.as_slice() {
            self.settle();
            self.weights.copy_from_slice(w);
            self.last = f64::NAN;
        }
    }
}

avx2_dispatch! {
    /// `out += w·row`, element by element: a sweep's exit adds one such row (every
    /// variant's channels) per bin its lobe covers, the largest per-variant cost of a sweep.
    /// Under AVX2 in 8 lanes, otherwise 4; the same IEEE operations (no fused multiply-add),
    /// so the same bits.
    #[inline]
    fn add_scaled(out: &mut [f32], w: f32, row: &[f32]) => add_scaled_in
}

#[inline(always)]
fn add_scaled_in(out: &mut [f32], w: f32, row: &[f32]) {
    for (o, r) in out.iter_mut().zip(row) {
        *o += w * r;
    }
}

/// Batch scores merged in batch order, with the batch-means sums of the error estimates.
struct SliceSums {
    bins: usize,
    /// Δφ columns of the grid.
    n_phi: usize,
    nch: usize,
    per_variant: usize,
    /// `[bin][channel]`.
    sum: Vec<f64>,
    /// Per bin: Σ and Σ² over batches of the sampling density of variant 0.
    noise_s: Vec<f64>,
    noise_s2: Vec<f64>,
    /// Per Δφ column: Σ and Σ² over batches of that density summed over θo.
    dphi_s: Vec<f64>,
    dphi_s2: Vec<f64>,
    /// Per channel: Σ and Σ² over batches of the albedo.
    alb_s: Vec<f64>,
    alb_s2: Vec<f64>,
    /// Per channel: Σ of the batches' totals (Λ before normalisation).
    alb_total: Vec<f64>,
    /// Per bin: Σ and Σ² over the batches that tallied it apart of the first-reflection
    /// pass's part of `noise_s`.
    refl_s: Vec<f64>,
    refl_s2: Vec<f64>,
    hits: u64,
    lost: f64,
    used: u64,
    gtot: f64,
}

impl SliceSums {
    fn new(grid: &AngularGrid, nch: usize, per_variant: usize) -> Self {
        let bins = grid.bins();
        Self {
            bins,
            n_phi: grid.n_phi,
            nch,
            per_variant,
            sum: scratch::zeroed(bins * nch),
            noise_s: vec![0.0; bins],
            noise_s2: vec![0.0; bins],
            dphi_s: vec![0.0; grid.n_phi],
            dphi_s2: vec![0.0; grid.n_phi],
            alb_s: vec![0.0; nch],
            alb_s2: vec![0.0; nch],
            alb_total: vec![0.0; nch],
            refl_s: Vec::new(),
            refl_s2: Vec::new(),
            hits: 0,
            lost: 0.0,
            used: 0,
            gtot: 0.0,
        }
    }

    /// Adds the next batch (in batch order).
    fn add(&mut self, part: &BatchScore) {
        let (bins, nch, per_variant) = (self.bins, self.nch, self.per_variant);
        let (local, g) = (&part.local, part.g_sum);
        self.hits += part.hits;
        self.lost += part.lost;
        self.gtot += g;
        self.used += 1;
        // Normalise by the intercepted power Σg (the spread weights of the photons that
        // met the fiber), so Λ is exactly the fraction of that power which leaves.
        let hn = if g > 0.0 { g } else { 1.0 };
        // Bin b's sampling density of variant 0 in a batch's scores.
        let density = |local: &[f32], b: usize| {
            local[b * nch..b * nch + per_variant]
                .iter()
                .map(|&x| f64::from(x))
                .sum::<f64>()
                / (per_variant as f64 * hn)
        };
        for (a, &x) in self.sum.iter_mut().zip(local) {
            *a += f64::from(x);
        }
        // Batch means: the sampling density of variant 0 (per bin and per Δφ column) and
        // every channel's albedo.
        let mut col = vec![0.0; self.n_phi];
        for b in 0..bins {
            let x = density(local, b);
            self.noise_s[b] += x;
            self.noise_s2[b] += x * x;
            col[b % self.n_phi] += x;
        }
        for (j, x) in col.into_iter().enumerate() {
            self.dphi_s[j] += x;
            self.dphi_s2[j] += x * x;
        }
        if !part.reflection.is_empty() {
            self.refl_s.resize(bins, 0.0);
            self.refl_s2.resize(bins, 0.0);
            for b in 0..bins {
                let x = density(&part.reflection, b);
                self.refl_s[b] += x;
                self.refl_s2[b] += x * x;
            }
        }
        for (c, &t) in part.total.iter().enumerate() {
            self.alb_total[c] += t;
            let a = t / hn;
            self.alb_s[c] += a;
            self.alb_s2[c] += a * a;
        }
    }

    /// Fractions, albedos and their errors, and the noise of the slice.
    fn into_result(mut self, grid: &AngularGrid, launched: u64, start: Instant) -> SliceResult {
        let (bins, nch) = (self.bins, self.nch);
        let nbf = self.used as f64;
        let hn = if self.gtot > 0.0 { self.gtot } else { 1.0 };
        let mut fraction = vec![0.0; nch * bins];
        for b in 0..bins {
            for c in 0..nch {
                let x = self.sum[b * nch + c] / hn;
                fraction[c * bins + b] = f64::from(x as f32);
            }
        }
        // Λ from the batches' f64 totals: a white furnace gives exactly one, not one plus
        // the tallies' or the fractions' f32 rounding.
        let albedo = self.alb_total.iter().map(|t| t / hn).collect();
        let albedo_se = (0..nch)
            .map(|c| batch_se(self.alb_s[c], self.alb_s2[c], nbf))
            .collect();
        let density_se = (0..bins)
            .map(|b| batch_se(self.noise_s[b], self.noise_s2[b], nbf))
            .collect();
        let dphi_se = (0..self.n_phi)
            .map(|j| batch_se(self.dphi_s[j], self.dphi_s2[j], nbf))
            .collect();
        let noise = self.noise(grid, nbf);
        scratch::recycle(std::mem::take(&mut self.sum));
        SliceResult {
            fraction,
            albedo,
            albedo_se,
            density_se,
            dphi_se,
            noise,
            launched,
            intercepted: self.hits,
            lost_weight: self.lost,
            seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// `None` when the batches so far reach `target` ([`BakeSettings::target`]); otherwise
    /// the further batches that the error's 1/√batches decline says reach it (at least one).
    fn batches_to(&self, grid: &AngularGrid, target: NoiseTarget) -> Option<u64> {
        let n = self.noise(grid, self.used as f64);
        if target.met_by(&n) {
            return None;
        }
        let ratio = n.median_rel_se / target.rel_se(&n);
        let more = self.used as f64 * (ratio * ratio - 1.0);
        Some(if more.is_finite() {
            more.ceil().max(1.0) as u64
        } else {
            u64::MAX
        })
    }

    /// Launches of the first-reflection pass per batch for the batches after the first pass,
    /// which ran `launches` per batch and tallied that pass apart: Neyman allocation of two
    /// independent estimators of equal cost per unit (a launch costs about a photon: 7.7 and
    /// 7.2 µs on silk, 3.3 and 6.6 µs on polyester). With A_r and A_p the two passes' shares
    /// of Σ_b var_b / mean_b² over the noise's bins, the share s = √(A_r·s₀/A_p) minimises
    /// the error at equal work; rounded to a power of two (the Sobol' set stays a net)
    /// between batch/[`MAX_REFLECTION_SHARE`] and batch/[`MIN_REFLECTION_SHARE`].
    fn reflection_launches(&self, grid: &AngularGrid, batch: u64, launches: u64) -> u64 {
        let nbf = self.used as f64;
        let (mut a, mut a_r) = (0.0, 0.0);
        for b in self.kept_bins(grid, nbf) {
            let m = self.noise_s[b] / nbf;
            a += batch_var(self.noise_s[b], self.noise_s2[b], nbf) / (m * m);
            a_r += batch_var(self.refl_s[b], self.refl_s2[b], nbf) / (m * m);
        }
        let a_p = (a - a_r).max(1e-3 * a);
        let s0 = launches as f64 / batch as f64;
        let share = (a_r * s0 / a_p).sqrt();
        let lo = (batch / MAX_REFLECTION_SHARE).max(16);
        let hi = (batch / MIN_REFLECTION_SHARE).max(lo);
        if share.is_nan() || share <= 0.0 {
            return lo;
        }
        let m = (2f64.powf((share * batch as f64).log2().round())) as u64;
        m.clamp(lo, hi)
    }

    /// The bins the noise is taken over: density ≥ 1 % of the maximum (per steradian).
    fn kept_bins(&self, grid: &AngularGrid, nbf: f64) -> Vec<usize> {
        let dens: Vec<f64> = (0..self.bins)
            .map(|b| self.noise_s[b] / nbf / grid.solid_angle(b / grid.n_phi))
            .collect();
        let dmax = dens.iter().copied().fold(0.0, f64::max);
        (0..self.bins)
            .filter(|&b| dmax > 0.0 && dens[b] >= 0.01 * dmax)
            .collect()
    }

    /// Noise over bins with density ≥ 1 % of the maximum (density per steradian), and the
    /// thesis's noise over the same bins ([`NoiseTarget::Thesis`]).
    fn noise(&self, grid: &AngularGrid, nbf: f64) -> Noise {
        let (noise_s, noise_s2) = (&self.noise_s, &self.noise_s2);
        let kept = self.kept_bins(grid, nbf);
        let mut rel: Vec<f64> = (kept.iter())
            .map(|&b| batch_se(noise_s[b], noise_s2[b], nbf) / (noise_s[b] / nbf))
            .collect();
        let total: f64 = noise_s.iter().sum();
        let mut thesis: Vec<f64> = (kept.iter())
            .map(|&b| {
                let p = noise_s[b] / total;
                ((1.0 - p) / (THESIS_PHOTONS * p)).sqrt()
            })
            .collect();
        Noise {
            median_rel_se: quantile(&mut rel, 0.5),
            p90_rel_se: quantile(&mut rel, 0.9),
            bins: rel.len(),
            thesis_rel_se: quantile(&mut thesis, 0.5),
        }
    }
}

/// The `p` quantile of `v` (nearest rank; sorts `v`), 0 when empty.
fn quantile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        0.0
    } else {
        v[((v.len() - 1) as f64 * p).round() as usize]
    }
}

/// Variance of one batch mean, from `nbf` batch means with sums `s` and `s2`.
fn batch_var(s: f64, s2: f64, nbf: f64) -> f64 {
    let m = s / nbf;
    (s2 / nbf - m * m).max(0.0)
}

/// Standard error of the mean of `nbf` batch means with sums `s` and `s2`.
fn batch_se(s: f64, s2: f64, nbf: f64) -> f64 {
    (batch_var(s, s2, nbf) / (nbf - 1.0)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sums of `batches` batches of a one-channel slice on a 30° grid: every bin's photon part
    /// `1 + sp·z` and reflection part `1 + sr·z'` (z, z' = ±1 alternating, independent
    /// patterns), the reflection part tallied apart.
    fn sums(sp: f64, sr: f64, batches: usize) -> (AngularGrid, SliceSums) {
        let grid = AngularGrid::new(30.0).unwrap();
        let mut sums = SliceSums::new(&grid, 1, 1);
        for k in 0..batches {
            let zp = if k % 2 == 0 { 1.0 } else { -1.0 };
            let zr = if (k / 2) % 2 == 0 { 1.0 } else { -1.0 };
            let (sp, sr) = (sp as f32, sr as f32);
            let reflection = vec![1.0 + sr * zr; grid.bins()];
            let local: Vec<f32> = reflection.iter().map(|r| r + 1.0 + sp * zp).collect();
            sums.add(&BatchScore {
                total: vec![local.iter().map(|&x| f64::from(x)).sum()],
                local,
                reflection,
                hits: 1,
                lost: 0.0,
                g_sum: 1.0,
            });
        }
        (grid, sums)
    }

    /// Neyman allocation: s = √(A_r·s₀/A_p), rounded to a power of two and clamped.
    #[test]
    fn reflection_share_follows_the_two_passes_noise() {
        // Equal noise at s₀ = 1/16: s = 1/4.
        let (g, s) = sums(0.2, 0.2, 8);
        assert_eq!(s.reflection_launches(&g, 4096, 256), 1024);
        // The reflection pass 4× noisier (16× the variance): s = 1, the most.
        let (g, s) = sums(0.05, 0.2, 8);
        assert_eq!(s.reflection_launches(&g, 4096, 256), 4096);
        // The reflection pass noiseless: the fewest, a launch per 64 photons.
        let (g, s) = sums(0.2, 0.0, 8);
        assert_eq!(s.reflection_launches(&g, 4096, 256), 64);
        // The photons' noise 4× the reflection's: s = √(1/16 / 16) = 1/16.
        let (g, s) = sums(0.4, 0.1, 8);
        assert_eq!(s.reflection_launches(&g, 4096, 256), 256);
    }

    /// A step holds what 256 MiB of tallies hold, between 16 and 128 batches: 86 for the
    /// thesis's 2° tables (16,200 bins, RGB, 8 shared rows), 16 for a 20-variant sweep there,
    /// 128 at 6° for one slice.
    #[test]
    fn a_step_holds_what_its_tallies_allow() {
        assert_eq!(step_batches(16_200, 3, 8), 86);
        assert_eq!(step_batches(16_200, 60, 8), 16);
        assert_eq!(step_batches(1_800, 3, 1), 128);
        assert_eq!(step_batches(16_200, 3, 0), step_batches(16_200, 3, 1));
    }

    /// A column shared by sliding windows ([`drive`]): each batch reaches only directions of
    /// its window, every direction gets exactly its first pass (5 batches, not a whole
    /// number of rounds), a direction that reached its target gets nothing more, and none
    /// passes its cap (30: the first pass and whole steps of batches would pass it). Six
    /// directions, windows of four; each batch marks bin 0 with its direction's number, the
    /// last direction's alternating (so it never reaches the target and goes on alone to its
    /// cap, through windows whose other directions have left).
    #[test]
    fn window_batches_score_their_own_directions_until_each_leaves() {
        use super::super::sweep::Variant;
        let grid = AngularGrid::new(30.0).unwrap();
        let variant = Variant {
            name: "clear".into(),
            mua_per_um: vec![0.0],
        };
        let channels = Channels::new(&[variant], &[550.0], ChannelKind::Spectral, 100.0);
        let s = BakeSettings {
            res_deg: 30.0,
            batch: 64,
            photons: 5 * 64,
            target: Some(NoiseTarget::RelSe(1e-6)),
            max_photons: 30 * 64,
            ..BakeSettings::default()
        };
        let windows = Windows::new(6, 4);
        let last = windows.n - 1;
        let scored = std::sync::Mutex::new(vec![Vec::new(); windows.n]);
        let r = drive(
            windows,
            &grid,
            &channels,
            &s,
            &Cancel::NEVER,
            Instant::now(),
            |b, members, _, _| {
                members
                    .iter()
                    .map(|&i| {
                        let v = match (i == last, b % 2) {
                            (true, 0) => 10.0,
                            (true, _) => 12.0,
                            (false, _) => (i + 1) as f32,
                        };
                        scored.lock().unwrap()[i].push(b);
                        let mut local = vec![0.0f32; grid.bins()];
                        local[0] = v;
                        BatchScore {
                            total: vec![f64::from(v)],
                            local,
                            reflection: Vec::new(),
                            hits: 1,
                            lost: 0.0,
                            g_sum: 1.0,
                        }
                    })
                    .collect()
            },
        )
        .unwrap();
        let scored = scored.into_inner().unwrap();
        // The first pass: five batches per direction, within two rounds of the nine windows.
        let first_end = 2 * windows.count() as u64;
        for (i, r) in r.iter().enumerate() {
            let mut b = scored[i].clone();
            b.sort_unstable();
            b.dedup();
            assert_eq!(b.len(), scored[i].len(), "direction {i}: a batch twice");
            for &x in &b {
                let w = windows.members((x % windows.count() as u64) as usize);
                assert!(w.contains(&i), "direction {i}: batch {x} of window {w:?}");
            }
            assert_eq!(r.launched, b.len() as u64 * s.batch, "direction {i}");
            if i == last {
                assert_eq!(r.launched, s.max_photons, "direction {i} to its cap");
                assert!((10.0..=12.0).contains(&r.fraction[0]), "{}", r.fraction[0]);
            } else {
                // Its own marker alone, and no batch after the first pass.
                assert_eq!(r.fraction[0], (i + 1) as f64, "direction {i}");
                assert_eq!(b.len(), 5, "direction {i}");
                assert!(b.iter().all(|&x| x < first_end), "direction {i}: {b:?}");
            }
        }
    }

    /// The batches still needed follow the error's 1/√batches decline.
    #[test]
    fn batches_to_extrapolates_the_error() {
        // Relative error per batch 0.25/2 = 0.125; over 8 batches 0.125/√7 (batch means;
        // the batches' tallies are f32, so values f32 holds exactly).
        let (g, s) = sums(0.25, 0.0, 8);
        let now = s.noise(&g, 8.0).median_rel_se;
        assert!((now - 0.125 / 7f64.sqrt()).abs() < 1e-12, "{now}");
        assert_eq!(s.batches_to(&g, NoiseTarget::RelSe(now)), None);
        // Half the error: four times the batches, 24 more.
        assert_eq!(s.batches_to(&g, NoiseTarget::RelSe(0.5 * now)), Some(24));
        // Just short of it: one more.
        assert_eq!(s.batches_to(&g, NoiseTarget::RelSe(0.999 * now)), Some(1));
    }
}
