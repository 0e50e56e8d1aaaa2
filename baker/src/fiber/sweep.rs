//! Dye × depth-of-shade × wavelength sweeps from one geometric trace.
//!
//! The walk of a photon does not depend on absorption (§5.3.1: the dye only absorbs), so a
//! photon leaving with path length ℓ inside the fiber contributes exp(−μa(λ)·ℓ) to every
//! wavelength of every variant. A channel is a fixed linear combination of such terms:
//! a wavelength (`exp(−μa ℓ)`), or linear sRGB under D65 (`Σλ M_cλ exp(−μa(λ) ℓ)`, the
//! CIE 1931 observer folded into one weight per wavelength, [`crate::spectral::ColourMap`]).
//!
//! Evaluating hundreds of exponentials per exiting photon would cost more than the walk, so
//! every channel is tabulated once over ℓ, with its exact derivative (Σ −μa·c·exp(−μa ℓ)),
//! and interpolated by the cubic Hermite polynomial between two grid points (one fused row of
//! all channels' values and derivatives per grid point). The cubic Hermite interpolant of
//! g(ℓ) over a step Δ errs by at most Δ⁴/384 · max|g⁗| (the Hermite error with two double
//! nodes a, b: g − H = g⁗(ξ)·(ℓ − a)²(ℓ − b)²/4!, and (ℓ − a)²(ℓ − b)² ≤ Δ⁴/16); for one
//! term exp(−μa ℓ) that is (μa Δ)⁴/384 of its value at the step's start, so every step
//! keeps μa·Δ ≤ 0.25 for each term that matters there (≤ 1.02·10⁻⁵ of the term, 1.3·10⁻⁵
//! of its value anywhere in the step; linear interpolation needed μa·Δ ≤ 0.02 for 5·10⁻⁵,
//! 12.5× the rows):
//! - up to about 16 bounding diameters the grid is uniform with Δ = 0.25/μa,max;
//! - beyond, it is geometric, Δ = ρ·ℓ with ρ = 0.25/50: a term with μa·ℓ ≤ 50 has
//!   μa·Δ ≤ 0.25, and one with μa·ℓ > 50 is below e⁻⁵⁰ < 2⁻⁷² of its coefficient at both ends
//!   of the step, its derivative below 50/ℓ of that (so is its interpolant). Long internal
//!   trapping paths (5 % of a dyed silk sweep's exits) are thus looked up, not evaluated
//!   term by term;
//! - paths beyond both (a few hundred diameters; the table is bounded) are evaluated exactly.
//!
//! The table (up to 16,384 rows) is built once per bake, its rows in parallel; a variant's R,
//! G and B share its μa(λ), so each row evaluates each variant's exponentials once, in a
//! loop that vectorises ([`exp_neg_f64`]), and sums up to four channels side by side. A
//! 20-variant RGB polyester sweep's table (12,437 rows × 60 channels, linear then) took 33 ms
//! of wall time with one libm `exp` per term and channel on one thread, 44–49 ms of CPU
//! (23–30 ms wall on two threads) with the shared exponentials, and 25 ms of CPU (13 ms wall)
//! with the loop that vectorises (validation/bench-runs/2026-12-06-fiber-sweep-table). The
//! cubic grid has a twelfth of the points, each row twice as wide: the 20-variant cotton
//! sweep's uniform part, which most exits read, is 914 rows (877 kB, within the core's 1 MiB
//! L2 cache) where the linear one was 8,192 rows (3.9 MB, read from L3 at each exit), and
//! linear interpolation's overestimate of the convex exp(−μa ℓ), up to 5·10⁻⁵ of a channel,
//! is now ≤ 1.3·10⁻⁵ (validation/bench-runs/2026-12-07-fiber-sweep-hermite).
//!
//! Cost: each exiting photon still adds one row of all channels, so a wide sweep costs more
//! than a single variant (measured: 20 variants × RGB of silk at 6°, 16,384 photons per
//! direction, 1.5× the CPU time of one variant; the rest of the difference is writing 20
//! variants' tables, validation/bench-runs/2026-12-05-fiber-speed). The alternative
//! not built yet: accumulate a per-bin histogram over ℓ (tent-weighted onto this grid, two
//! adds per photon whatever the sweep) and multiply it by the channel table at the end —
//! exactly the same interpolated result, at a cost independent of the number of variants.

use crate::math::avx2::avx2_dispatch;
use crate::math::exp::exp_neg_f64;
use crate::spectral::ColourMap;
use rayon::prelude::*;

/// One dyeing of the fiber: a name and μa per wavelength of the sweep, per µm.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    pub name: String,
    pub mua_per_um: Vec<f64>,
}

/// What each variant's channels are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ChannelKind {
    /// Linear sRGB (D65 white = 1) from the spectral result.
    Rgb,
    /// One channel per wavelength.
    Spectral,
}

/// μa·ℓ beyond which a term of a channel is dropped (exp(−50) < 2⁻⁷²).
const NEGLIGIBLE_MU_L: f64 = 50.0;
/// Largest number of ℓ grid points of each part of the table (uniform, geometric).
const MAX_TABLE: usize = 8192;
/// Largest number of values (grid points × channels × 2: value and derivative) of the whole
/// table: 64 MiB of f64.
const MAX_VALUES: usize = 1 << 23;
/// Largest μa·Δ of a step for a term that matters (interpolation error ≤ STEP_MU⁴/384 of
/// the term at the step's start).
const STEP_MU: f64 = 0.25;
/// Relative step ρ of the geometric part: STEP_MU / NEGLIGIBLE_MU_L.
const TAIL_RATIO: f64 = STEP_MU / NEGLIGIBLE_MU_L;

/// All channels of a sweep (variant-major), tabulated over path length.
#[derive(Clone)]
pub struct Channels {
    pub variants: Vec<String>,
    pub channel_names: Vec<String>,
    pub lambda_nm: Vec<f64>,
    pub kind: ChannelKind,
    /// Per channel: the terms (μa per µm, coefficient).
    terms: Vec<Vec<(f64, f64)>>,
    /// ℓ step and its inverse, µm.
    step_um: f64,
    inv_step: f64,
    /// `(len + tail.len()) × 2n` values; row i < len holds every channel's value, then every
    /// channel's derivative over ℓ (per µm), at ℓ = i·step, row len + j at ℓ = tail[j].
    table: Vec<f64>,
    len: usize,
    /// ℓ of the geometric part's points, µm: tail[j] = (len − 1)·step·(1 + ρ)^(j + 1).
    tail: Vec<f64>,
}

/// What the table is made of (its values follow from these), for cache keys and logs.
impl std::fmt::Debug for Channels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Channels")
            .field("variants", &self.variants)
            .field("channel_names", &self.channel_names)
            .field("lambda_nm", &self.lambda_nm)
            .field("kind", &self.kind)
            .field("terms", &self.terms)
            .field("step_um", &self.step_um)
            .field("len", &self.len)
            .field("tail_points", &self.tail.len())
            .field("tail_ratio", &TAIL_RATIO)
            .field("interpolation", &"cubic Hermite")
            .finish()
    }
}

impl Channels {
    /// Channels for `variants` (μa on `lambda_nm`), tabulated for paths up to about
    /// `typical_path_um` (longer ones are exact).
    pub fn new(
        variants: &[Variant],
        lambda_nm: &[f64],
        kind: ChannelKind,
        typical_path_um: f64,
    ) -> Self {
        let mut terms = Vec::new();
        let mut names = Vec::new();
        let cmap = (kind == ChannelKind::Rgb).then(|| ColourMap::new(lambda_nm));
        for v in variants {
            assert_eq!(v.mua_per_um.len(), lambda_nm.len());
            match &cmap {
                Some(cm) => {
                    for (c, name) in ["R", "G", "B"].iter().enumerate() {
                        terms.push(
                            v.mua_per_um
                                .iter()
                                .zip(&cm.rgb_weights)
                                .map(|(&m, w)| (m, w[c]))
                                .collect(),
                        );
                        names.push(name.to_string());
                    }
                }
                None => {
                    for (&m, &l) in v.mua_per_um.iter().zip(lambda_nm) {
                        terms.push(vec![(m, 1.0)]);
                        names.push(format!("{l}nm"));
                    }
                }
            }
        }
        let absorbing = || terms.iter().flatten().map(|t| t.0).filter(|&m| m > 0.0);
        let mu_max = absorbing().fold(0.0f64, f64::max);
        let mu_min = absorbing().fold(f64::INFINITY, f64::min);
        let n = terms.len();
        let rows_max = (MAX_VALUES / (2 * n).max(1)).clamp(4, 2 * MAX_TABLE);
        let (step_um, inv_step, len, tail) = if mu_max > 0.0 {
            let step = STEP_MU / mu_max;
            let len = ((typical_path_um / step).ceil() as usize + 2).clamp(2, rows_max / 2);
            // Geometric points until every absorbing term is negligible (μa,min·ℓ > 50).
            let l0 = (len - 1) as f64 * step;
            let want = ((NEGLIGIBLE_MU_L / mu_min / l0).ln() / TAIL_RATIO.ln_1p()).ceil();
            let k = (want.max(0.0) as usize + 1)
                .min(MAX_TABLE)
                .min(rows_max - len);
            let tail = (1..=k)
                .map(|j| l0 * (j as f64 * TAIL_RATIO.ln_1p()).exp())
                .collect();
            (step, 1.0 / step, len, tail)
        } else {
            // Nothing absorbs: every channel is the same at any ℓ, so every path reads row 0
            // (its values are `exact`'s sums, bit for bit): a step inverse of 0.
            (typical_path_um.max(1.0), 0.0, 2, Vec::new())
        };
        let points: Vec<f64> = (0..len)
            .map(|i| i as f64 * step_um)
            .chain(tail.iter().copied())
            .collect();
        let mut table = vec![0.0; points.len() * 2 * n];
        if n > 0 {
            let groups = Group::of(&terms);
            table
                .par_chunks_mut(2 * n)
                .zip(&points)
                .for_each_init(Vec::new, |e, (row, &l)| fill_row(&groups, l, row, e));
        }
        Self {
            variants: variants.iter().map(|v| v.name.clone()).collect(),
            channel_names: names[..n / variants.len().max(1)].to_vec(),
            lambda_nm: lambda_nm.to_vec(),
            kind,
            terms,
            step_um,
            inv_step,
            table,
            len,
            tail,
        }
    }

    /// Number of channels over all variants.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// Channels per variant.
    pub fn per_variant(&self) -> usize {
        self.channel_names.len()
    }

    /// Every channel's weight at path `path_um`, into `out`.
    #[inline]
    pub fn attenuations(&self, path_um: f64, out: &mut [f64]) {
        let x = path_um * self.inv_step;
        let (i, t, h) = if x + 1.0 < self.len as f64 {
            let i = x as usize;
            (i, x - i as f64, self.step_um)
        } else if let Some((j, t, h)) = self.in_tail(path_um) {
            (self.len - 1 + j, t, h)
        } else {
            for (o, t) in out.iter_mut().zip(&self.terms) {
                *o = exact(t, path_um);
            }
            return;
        };
        let n = self.terms.len();
        let rows = &self.table[2 * i * n..2 * (i + 2) * n];
        hermite(rows, t, h, out)
    }

    /// The geometric part's step holding `path_um` (0: from the uniform part's last point to
    /// tail[0]), the fraction along it and its length; `None` beyond the table.
    #[inline]
    fn in_tail(&self, path_um: f64) -> Option<(usize, f64, f64)> {
        let l0 = (self.len - 1) as f64 * self.step_um;
        let last = *self.tail.last()?;
        if !(path_um >= l0 && path_um < last) {
            return None;
        }
        let at = |j: usize| if j == 0 { l0 } else { self.tail[j - 1] };
        // ln's rounding can put ℓ one step off; the comparisons settle it.
        let mut j = ((path_um / l0).ln() / TAIL_RATIO.ln_1p()) as usize;
        j = j.min(self.tail.len() - 1);
        while j > 0 && path_um < at(j) {
            j -= 1;
        }
        while path_um >= at(j + 1) {
            j += 1;
        }
        let (a, b) = (at(j), at(j + 1));
        Some((j, (path_um - a) / (b - a), b - a))
    }

    /// Step of the path-length grid, µm.
    pub fn step_um(&self) -> f64 {
        self.step_um
    }
}

/// The cubic Hermite interpolant at fraction `t` of a step of length `h` µm, per channel, from
/// the step's two rows (`rows`: values then derivatives at its start, then at its end):
/// g(t) = h₀₀ g₀ + h₀₁ g₁ + h·(h₁₀ g′₀ + h₁₁ g′₁) with the Hermite basis h₀₀ = (1 + 2t)(1 − t)²,
/// h₀₁ = t²(3 − 2t), h₁₀ = t(1 − t)², h₁₁ = −t²(1 − t). At t = 0 it is g₀ exactly.
#[inline(always)]
fn hermite_in(rows: &[f64], t: f64, h: f64, out: &mut [f64]) {
    let n = out.len();
    let s = 1.0 - t;
    let (h00, h01) = ((1.0 + 2.0 * t) * s * s, t * t * (3.0 - 2.0 * t));
    let (h10, h11) = (h * t * s * s, -h * t * t * s);
    let (v0, rest) = rows.split_at(n);
    let (d0, rest) = rest.split_at(n);
    let (v1, d1) = rest.split_at(n);
    for ((((o, &v0), &d0), &v1), &d1) in out.iter_mut().zip(v0).zip(d0).zip(v1).zip(d1) {
        *o = h00 * v0 + h01 * v1 + (h10 * d0 + h11 * d1);
    }
}

avx2_dispatch! {
    /// [`hermite_in`], under AVX2 where the processor has it.
    fn hermite(rows: &[f64], t: f64, h: f64, out: &mut [f64]) => hermite_in
}

/// Consecutive channels whose terms share one list of μa (a variant's R, G and B): each row
/// evaluates those attenuations once for the whole group.
struct Group {
    /// The group's first channel.
    first: usize,
    /// μa per term, per µm.
    mua_per_um: Vec<f64>,
    /// Per channel of the group: its coefficient per term.
    coef: Vec<Vec<f64>>,
}

impl Group {
    fn of(terms: &[Vec<(f64, f64)>]) -> Vec<Group> {
        let mut groups: Vec<Group> = Vec::new();
        for (c, t) in terms.iter().enumerate() {
            let coef = t.iter().map(|x| x.1).collect();
            match groups.last_mut() {
                Some(g)
                    if g.mua_per_um.len() == t.len()
                        && g.mua_per_um
                            .iter()
                            .zip(t)
                            .all(|(m, x)| m.to_bits() == x.0.to_bits()) =>
                {
                    g.coef.push(coef)
                }
                _ => groups.push(Group {
                    first: c,
                    mua_per_um: t.iter().map(|x| x.0).collect(),
                    coef: vec![coef],
                }),
            }
        }
        groups
    }
}

avx2_dispatch! {
    /// One row of the table: every channel at path `l` µm, each the same sum of the same
    /// products [`exact`] forms (so the same bits), then every channel's derivative over ℓ (the
    /// sum of c·(−μa·exp(−μa ℓ))), with each group's attenuations evaluated once, in a loop
    /// that vectorises (4 lanes under AVX2, 2 otherwise; the same IEEE operations, no fused
    /// multiply-add, so the same bits on every x86-64).
    /// `e` holds a group's attenuations (reused from row to row).
    fn fill_row(groups: &[Group], l: f64, row: &mut [f64], e: &mut Vec<f64>) => fill_row_in
}

#[inline(always)]
fn fill_row_in(groups: &[Group], l: f64, row: &mut [f64], e: &mut Vec<f64>) {
    let n = row.len() / 2;
    let (values, slopes) = row.split_at_mut(n);
    for g in groups {
        // A plain loop over slices, not `extend` (whose fold was compiled apart, outside
        // the AVX2 function, and ran in 2 lanes).
        let k = g.mua_per_um.len();
        e.resize(2 * k, 0.0);
        let (e, de) = e.split_at_mut(k);
        for ((e, de), &m) in e.iter_mut().zip(de.iter_mut()).zip(&g.mua_per_um) {
            *e = attenuation(m * l);
            *de = -m * *e;
        }
        sum_channels(g, e, &mut values[g.first..g.first + g.coef.len()]);
        sum_channels(g, de, &mut slopes[g.first..g.first + g.coef.len()]);
    }
}

/// Σ_t coef[c][t]·e[t] for each channel c of group `g`, into `out`.
#[inline(always)]
fn sum_channels(g: &Group, e: &[f64], out: &mut [f64]) {
    // Up to four channels at once: each channel's sum runs in the same order from −0.0 as
    // `exact`'s `sum()` (the same bits), and the four independent chains overlap instead of
    // waiting on one add after another.
    for (coef, out) in g.coef.chunks(4).zip(out.chunks_mut(4)) {
        // A short chunk repeats its first channel in the unused lanes (not stored).
        let c: [&[f64]; 4] = std::array::from_fn(|j| &coef[j.min(coef.len() - 1)][..e.len()]);
        let mut acc = [-0.0_f64; 4];
        for (t, &e) in e.iter().enumerate() {
            acc[0] += c[0][t] * e;
            acc[1] += c[1][t] * e;
            acc[2] += c[2][t] * e;
            acc[3] += c[3][t] * e;
        }
        out.copy_from_slice(&acc[..out.len()]);
    }
}

/// exp(−x) for x = μa·ℓ ≥ 0, branch-free ([`exp_neg_f64`], within 4 ulp of the correctly
/// rounded value, exactly 1 at 0); 0 beyond [`NEGLIGIBLE_MU_L`], where it is below 2⁻⁷², far
/// under any stored precision (f32 keeps 24 bits of a channel's value).
#[inline(always)]
fn attenuation(x: f64) -> f64 {
    let e = exp_neg_f64(-x);
    if x > NEGLIGIBLE_MU_L {
        0.0
    } else {
        e
    }
}

/// Σ c·exp(−μa·ℓ) over a channel's terms ([`attenuation`]); the paths beyond the table (long
/// internal trapping in a deep sweep) are evaluated with it.
fn exact(terms: &[(f64, f64)], l: f64) -> f64 {
    terms.iter().map(|&(m, c)| c * attenuation(m * l)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without any absorber every path reads the table's first row, which holds `exact`'s
    /// sums bit for bit (at 0 and far beyond the typical path alike).
    #[test]
    fn channels_without_absorption_are_exact_at_any_path() {
        let lambda: Vec<f64> = (0..31).map(|i| 400.0 + 10.0 * i as f64).collect();
        let white = Variant {
            name: "white".into(),
            mua_per_um: vec![0.0; lambda.len()],
        };
        for kind in [ChannelKind::Rgb, ChannelKind::Spectral] {
            let ch = Channels::new(std::slice::from_ref(&white), &lambda, kind, 30.0);
            for l in [0.0, 12.5, 29.9, 30.0, 31.0, 4.0e3, 1e9] {
                let mut got = vec![f64::NAN; ch.len()];
                ch.attenuations(l, &mut got);
                for (c, t) in ch.terms.iter().enumerate() {
                    assert_eq!(got[c].to_bits(), exact(t, l).to_bits(), "{kind:?} ℓ {l}");
                }
            }
        }
    }

    /// 400–700 nm in 10 nm steps.
    fn test_lambda() -> Vec<f64> {
        (0..31).map(|i| 400.0 + 10.0 * i as f64).collect()
    }

    /// A variant on [`test_lambda`] with μa between k and 2k per µm, varying with λ.
    fn test_variant(name: &str, k: f64) -> Variant {
        Variant {
            name: name.into(),
            mua_per_um: test_lambda()
                .iter()
                .map(|l| k * (1.0 + ((l - 400.0) / 50.0).sin().abs()))
                .collect(),
        }
    }

    /// Every channel, at 20,000 paths through the uniform and the geometric part, within the
    /// cubic Hermite bound of the module's docs: 1.3·10⁻⁵ of Σ|c|·exp(−μa ℓ) over its terms
    /// (of its value for a wavelength). Linear interpolation on the same grid errs by up to
    /// (0.25)²/8 = 8·10⁻³, a wrong derivative by more: either fails it.
    #[test]
    fn hermite_channels_within_their_bound() {
        let (lambda, v) = (test_lambda(), test_variant);
        let vars = [v("light", 0.002), v("deep", 0.05)];
        for kind in [ChannelKind::Rgb, ChannelKind::Spectral] {
            let ch = Channels::new(&vars, &lambda, kind, 40.0);
            let end = *ch.tail.last().unwrap();
            let mut got = vec![f64::NAN; ch.len()];
            let mut worst = 0.0f64;
            for k in 0..20_000 {
                // Geometrically spaced from 0.01 µm to the table's end.
                let l = 0.01 * (end / 0.01).powf(k as f64 / 20_000.0);
                ch.attenuations(l, &mut got);
                for (c, t) in ch.terms.iter().enumerate() {
                    // Plus e⁻⁵⁰ of each coefficient: a term is cut to 0 at a grid point past
                    // μa·ℓ = 50, however large that makes its own relative error.
                    let scale: f64 = t.iter().map(|&(m, k)| k.abs() * (-m * l).exp()).sum();
                    let cut: f64 = t
                        .iter()
                        .map(|&(_, k)| k.abs() * (-NEGLIGIBLE_MU_L).exp())
                        .sum();
                    let excess = ((got[c] - exact(t, l)).abs() - 2.0 * cut).max(0.0);
                    let err = if excess > 0.0 { excess / scale } else { 0.0 };
                    worst = worst.max(err);
                    assert!(
                        err <= 1.3e-5,
                        "{kind:?} ℓ {l} channel {c}: relative error {err}"
                    );
                }
            }
            // The bound is close to reached, so the grid is no finer than it needs to be.
            assert!(worst > 2e-6, "{kind:?}: worst {worst}");
        }
    }

    #[test]
    fn interpolated_channels_match_exact_weights() {
        let (lambda, v) = (test_lambda(), test_variant);
        let vars = [v("white", 0.0), v("light", 0.001), v("deep", 0.04)];
        for kind in [ChannelKind::Rgb, ChannelKind::Spectral] {
            let ch = Channels::new(&vars, &lambda, kind, 300.0);
            // The uniform part (to 300 µm), the geometric part (to the light dye's e⁻⁵⁰ at
            // 50 / 0.001 µm), and beyond (exact).
            assert!(ch.in_tail(299.0).is_none() && ch.in_tail(2.0e5).is_none());
            assert!(ch.in_tail(310.0).is_some() && ch.in_tail(7.5e3).is_some());
            for &l in &[
                0.0, 0.37, 5.0, 42.4, 299.0, 310.0, 1500.0, 7.5e3, 2.0e5, 1e9,
            ] {
                let mut got = vec![f64::NAN; ch.len()];
                ch.attenuations(l, &mut got);
                for (c, t) in ch.terms.iter().enumerate() {
                    let want = exact(t, l);
                    assert!(
                        (got[c] - want).abs() <= 1e-4 * want.abs() + 1e-12,
                        "{kind:?} ℓ {l} channel {c}: {} vs {want}",
                        got[c]
                    );
                }
            }
            // The table holds exactly `exact`'s value at every grid point (the rows share each
            // group's exponentials but form the same products and sums), and the derivative
            // over ℓ beside it.
            let n = ch.len();
            let points = (0..ch.len)
                .map(|i| i as f64 * ch.step_um)
                .chain(ch.tail.clone());
            for (i, l) in points.enumerate() {
                for (c, t) in ch.terms.iter().enumerate() {
                    assert_eq!(ch.table[2 * i * n + c].to_bits(), exact(t, l).to_bits());
                    let slope: f64 = t.iter().map(|&(m, k)| -m * k * attenuation(m * l)).sum();
                    let got = ch.table[(2 * i + 1) * n + c];
                    assert!(
                        (got - slope).abs() <= 1e-12 * slope.abs() + 1e-300,
                        "{got} {slope}"
                    );
                }
            }
            // White: every channel is 1 at any path.
            let mut w = vec![0.0; ch.len()];
            ch.attenuations(77.0, &mut w);
            for x in &w[..ch.per_variant()] {
                assert!((x - 1.0).abs() < 1e-12);
            }
        }
    }
}
