//! Absorption reuse ("white" Monte Carlo): trace the scattering once, keep each escaping
//! packet's per-layer path lengths, and apply any per-layer absorption afterwards, exactly:
//! a packet of weight w that travelled Li in layer i leaves with w·exp(−Σ μa,i·Li)
//! (microscopic Beer–Lambert; Sassaroli & Fantini 2004, Alerstam et al. 2008).
//!
//! Every stack sharing thicknesses, indices and scattering (e.g. the six skin types at one age
//! and wavelength) then costs one simulation.

use std::time::Instant;

use super::engine::{run_batches, trace, Exit, McOptions, Prepared, Scorer, Work};
use super::radial::RadialBins;
use super::stack::{Stack, StackError, MAX_LAYERS};
use super::tally::{McResult, RadialTally};
use crate::math::rng::batch_rng;
use crate::stats::Sums;

/// Per-layer absorption coefficients to apply to a white run, mm⁻¹.
pub type AbsorptionSet = Vec<f64>;

/// Escaping packets of a white run.
#[derive(Debug, Clone, Default)]
pub struct WhiteRun {
    pub photons: u64,
    pub layers: usize,
    pub rsp: f64,
    pub dr_mm: f64,
    pub nr: usize,
    /// 0: surface after scattering, 1: surface unscattered, 2: bottom.
    pub exit: Vec<u8>,
    pub r_mm: Vec<f64>,
    /// Packet weight at exit before absorption (roulette corrections included).
    pub weight: Vec<f64>,
    /// Path length in each layer, mm: `layers` values per packet.
    pub path_mm: Vec<f64>,
    pub scattering_events: u64,
    pub threads: usize,
    pub seconds: f64,
}

#[derive(Default)]
struct WhiteScorer {
    run: WhiteRun,
}

impl Scorer for WhiteScorer {
    fn absorb(&mut self, _layer: usize, _dw: f64, _pos: &[f64; 3]) {}
    fn escape(&mut self, e: &Exit) {
        self.run.exit.push(match (e.top, e.scattered) {
            (true, true) => 0,
            (true, false) => 1,
            (false, _) => 2,
        });
        self.run.r_mm.push(e.radius_mm());
        self.run.weight.push(e.weight);
        self.run.path_mm.extend_from_slice(e.path);
    }
    fn lost(&mut self, _weight: f64) {}
    fn photon_done(&mut self) {
        self.run.photons += 1;
    }
}

/// Traces `stack`'s scattering (its μa is ignored) with roulette against `mua_ref_per_mm`.
///
/// Any set of absorption coefficients can then be applied with [`WhiteRun::apply`]; sets close
/// to the reference have the lowest variance. Choose the smallest μa you will apply, per layer.
/// A semi-infinite layer needs a reference μa > 0, or packets could wander without end.
pub fn run_white(stack: &Stack, mua_ref_per_mm: &[f64], o: &McOptions) -> anyhow::Result<WhiteRun> {
    let mut p = Prepared::new(stack)?;
    p.set_random_entry(stack, o.random_entry);
    if mua_ref_per_mm.len() != p.nl {
        anyhow::bail!(
            "{} reference absorption coefficients for {} layers",
            mua_ref_per_mm.len(),
            p.nl
        );
    }
    let mut mua_ref = [0.0; MAX_LAYERS];
    for (i, &m) in mua_ref_per_mm.iter().enumerate() {
        if !(m.is_finite() && m >= 0.0) {
            anyhow::bail!("reference absorption of layer {i} must be finite and >= 0, got {m}");
        }
        mua_ref[i] = m;
    }
    if stack.layers.last().unwrap().d_mm.is_infinite() && mua_ref[p.nl - 1] <= 0.0 {
        return Err(StackError::OutOfRange {
            index: p.nl - 1,
            name: stack.layers[p.nl - 1].name.clone(),
            field: "reference mua_per_mm",
            value: 0.0,
            allowed: "> 0 for a semi-infinite layer in a white run",
        }
        .into());
    }
    let t0 = Instant::now();
    let mut all = WhiteRun {
        layers: p.nl,
        rsp: p.rsp,
        dr_mm: p.dr_mm,
        nr: p.nr,
        ..WhiteRun::default()
    };
    let threads = run_batches(
        64,
        o,
        |b, n| {
            let mut rng = batch_rng(o.seed, b);
            let mut s = WhiteScorer::default();
            let mut work = Work::default();
            for _ in 0..n {
                trace::<true, _>(&p, &mua_ref, &mut rng, &mut s, &mut work);
            }
            s.run.scattering_events = work.events;
            s.run
        },
        |r| {
            all.photons += r.photons;
            all.scattering_events += r.scattering_events;
            all.exit.extend(r.exit);
            all.r_mm.extend(r.r_mm);
            all.weight.extend(r.weight);
            all.path_mm.extend(r.path_mm);
        },
    )?;
    all.threads = threads;
    all.seconds = t0.elapsed().as_secs_f64();
    Ok(all)
}

impl WhiteRun {
    /// Reflectance, transmittance and Rd(r) for per-layer absorption `mua_per_mm`, with standard
    /// errors. Per-layer absorption is not resolved (`absorbed` is empty); the total absorbed is
    /// 1 − Rsp − Rd − Tt.
    pub fn apply(&self, mua_per_mm: &[f64]) -> McResult {
        assert_eq!(mua_per_mm.len(), self.layers, "one μa per layer");
        let mut t = RadialTally::new(0, self.nr);
        t.photons = self.photons;
        t.scattering_events = self.scattering_events;
        for (k, ((&exit, &r), &w0)) in self
            .exit
            .iter()
            .zip(&self.r_mm)
            .zip(&self.weight)
            .enumerate()
        {
            let path = &self.path_mm[k * self.layers..(k + 1) * self.layers];
            let tau: f64 = path.iter().zip(mua_per_mm).map(|(l, m)| l * m).sum();
            let w = w0 * (-tau).exp();
            match exit {
                0 => {
                    t.rd.add(w);
                    if let Some(b) = t.rd_r.get_mut((r / self.dr_mm) as usize) {
                        b.add(w);
                    }
                }
                1 => t.rd_unscattered.add(w),
                _ => t.tt.add(w),
            }
        }
        McResult::from_tally(&t, self.rsp, self.dr_mm, self.threads, self.seconds)
    }
}

/// What one absorption set of [`run_white_sets`] scores: sums over photons, with Σx² for
/// standard errors.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SetTally {
    /// Diffuse reflectance of scattered light, whole plane.
    pub rd: Sums,
    /// Light reflected back out by inner interfaces without scattering (a delta at r ≈ 0).
    pub rd_unscattered: Sums,
    pub tt: Sums,
    /// Scattered reflectance per annulus of the run's [`RadialBins`] (weight, not per area).
    pub rd_r: Vec<Sums>,
}

impl SetTally {
    pub(crate) fn new(nr: usize) -> Self {
        Self {
            rd: Sums::default(),
            rd_unscattered: Sums::default(),
            tt: Sums::default(),
            rd_r: vec![Sums::default(); nr],
        }
    }

    /// Scores an exit of weight `w` (absorption applied), in radial bin `bin`.
    #[inline]
    pub(crate) fn add(&mut self, e: &Exit, bin: Option<usize>, w: f64) {
        match (e.top, e.scattered) {
            (true, true) => {
                self.rd.add(w);
                if let Some(k) = bin {
                    self.rd_r[k].add(w);
                }
            }
            (true, false) => self.rd_unscattered.add(w),
            (false, _) => self.tt.add(w),
        }
    }

    pub(crate) fn merge(&mut self, o: &SetTally) {
        self.rd.merge(&o.rd);
        self.rd_unscattered.merge(&o.rd_unscattered);
        self.tt.merge(&o.tt);
        for (a, b) in self.rd_r.iter_mut().zip(&o.rd_r) {
            a.merge(b);
        }
    }
}

/// One white simulation applied to many absorption sets at once.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct WhiteSets {
    pub photons: u64,
    /// Specular reflectance at the surface (not part of the tallies).
    pub rsp: f64,
    pub sets: Vec<SetTally>,
    pub scattering_events: u64,
    /// Evaluations of the junction's height field (0 without one).
    #[serde(default)]
    pub junction_evals: u64,
    pub threads: usize,
    pub seconds: f64,
}

struct SetsScorer<'a> {
    mua: &'a [[f64; MAX_LAYERS]],
    bins: &'a RadialBins,
    sets: Vec<SetTally>,
    photons: u64,
}

impl Scorer for SetsScorer<'_> {
    fn absorb(&mut self, _layer: usize, _dw: f64, _pos: &[f64; 3]) {}
    fn escape(&mut self, e: &Exit) {
        let bin = if e.top && e.scattered {
            self.bins.index(e.radius_mm())
        } else {
            None
        };
        for (t, mua) in self.sets.iter_mut().zip(self.mua) {
            // Microscopic Beer–Lambert: the packet's weight under this set's absorption.
            t.add(e, bin, e.weight * beer_lambert(e.path, mua));
        }
    }
    fn lost(&mut self, _weight: f64) {}
    fn photon_done(&mut self) {
        self.photons += 1;
    }
}

/// exp(−Σᵢ μa,i·Li): the weight a packet that travelled `path_mm` keeps under absorption
/// `mua_per_mm` (microscopic Beer–Lambert).
#[inline(always)]
pub(crate) fn beer_lambert(path_mm: &[f64], mua_per_mm: &[f64]) -> f64 {
    let tau: f64 = path_mm.iter().zip(mua_per_mm).map(|(l, m)| l * m).sum();
    (-tau).exp()
}

/// Everything [`run_white_sets`] requires of its inputs: a valid stack, at least one set, one
/// finite μa ≥ 0 per layer in each, and μa > 0 in a semi-infinite last layer (else a packet
/// could walk forever). The spec resolver calls this too, so a spec that passes `validate`
/// never fails here.
pub fn check_sets(stack: &Stack, sets: &[AbsorptionSet]) -> Result<(), String> {
    stack.validate().map_err(|e| e.to_string())?;
    if sets.is_empty() {
        return Err("no absorption sets to apply".into());
    }
    let nl = stack.layers.len();
    for (s, set) in sets.iter().enumerate() {
        if set.len() != nl {
            return Err(format!(
                "absorption set {s} has {} values for {nl} layers",
                set.len()
            ));
        }
        for (i, &m) in set.iter().enumerate() {
            if !(m.is_finite() && m >= 0.0) {
                return Err(format!(
                    "absorption set {s}, layer {i}: μa must be finite and >= 0, got {m}"
                ));
            }
        }
    }
    let last = nl - 1;
    if stack.layers[last].d_mm.is_infinite() && sets.iter().any(|s| s[last] <= 0.0) {
        return Err(format!(
            "the {} is semi-infinite and needs μa > 0 (it has none: nothing would stop light in it)",
            stack.layers[last].name
        ));
    }
    Ok(())
}

/// Traces `stack`'s scattering once and scores every per-layer absorption set of `sets` on
/// `bins`, streaming (no per-packet storage): the cost of a set is a few multiplications per
/// escaping packet. Roulette plays against the per-layer minimum over `sets`, so no set loses
/// packets it would have kept. Deterministic for a given seed whatever the thread count.
pub fn run_white_sets(
    stack: &Stack,
    sets: &[AbsorptionSet],
    bins: &RadialBins,
    o: &McOptions,
) -> anyhow::Result<WhiteSets> {
    check_sets(stack, sets).map_err(anyhow::Error::msg)?;
    let mut p = Prepared::new(stack)?;
    p.set_random_entry(stack, o.random_entry);
    let mut mua = vec![[0.0; MAX_LAYERS]; sets.len()];
    let mut mua_ref = [f64::INFINITY; MAX_LAYERS];
    for (s, set) in sets.iter().enumerate() {
        for (i, &m) in set.iter().enumerate() {
            mua[s][i] = m;
            mua_ref[i] = mua_ref[i].min(m);
        }
    }
    let t0 = Instant::now();
    let mut all = WhiteSets {
        photons: 0,
        rsp: p.rsp,
        sets: vec![SetTally::new(bins.len()); sets.len()],
        scattering_events: 0,
        junction_evals: 0,
        threads: 0,
        seconds: 0.0,
    };
    let threads = run_batches(
        16,
        o,
        |b, n| {
            let mut rng = batch_rng(o.seed, b);
            let mut s = SetsScorer {
                mua: &mua,
                bins,
                sets: vec![SetTally::new(bins.len()); sets.len()],
                photons: 0,
            };
            let mut work = Work::default();
            for _ in 0..n {
                trace::<true, _>(&p, &mua_ref, &mut rng, &mut s, &mut work);
            }
            (s.photons, work, s.sets)
        },
        |(photons, work, sets)| {
            all.photons += photons;
            all.scattering_events += work.events;
            all.junction_evals += work.junction_evals;
            for (a, b) in all.sets.iter_mut().zip(&sets) {
                a.merge(b);
            }
        },
    )?;
    all.threads = threads;
    all.seconds = t0.elapsed().as_secs_f64();
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::Layer;

    /// Hostile absorption sets are refused with the set, the layer and the value: negative,
    /// NaN and infinite μa, a wrong length, none at all, and no absorption in a semi-infinite
    /// last layer.
    #[test]
    fn absorption_sets_are_checked() {
        let stack = |d_mm: f64| {
            Stack::in_air(
                Layer {
                    name: "dermis".into(),
                    d_mm,
                    eta: 1.4,
                    mua_per_mm: 0.1,
                    mus_per_mm: 10.0,
                    g: 0.8,
                },
                0.01,
                10,
            )
        };
        let finite = stack(1.0);
        assert!(check_sets(&finite, &[vec![0.0], vec![2.5]]).is_ok());
        for bad in [-0.1, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = check_sets(&finite, &[vec![0.1], vec![bad]]).unwrap_err();
            assert!(
                e.contains("absorption set 1, layer 0") && e.contains("finite and >= 0"),
                "{bad}: {e}"
            );
        }
        assert!(check_sets(&finite, &[vec![0.1, 0.2]])
            .unwrap_err()
            .contains("2 values for 1 layers"));
        assert!(check_sets(&finite, &[]).is_err());
        let e = check_sets(&stack(f64::INFINITY), &[vec![0.1], vec![0.0]]).unwrap_err();
        assert!(e.contains("dermis is semi-infinite"), "{e}");
        assert!(check_sets(&stack(f64::INFINITY), &[vec![0.1]]).is_ok());
    }
}
