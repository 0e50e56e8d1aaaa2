//! Absorption reuse ("white" Monte Carlo): trace the scattering once, keep each escaping
//! packet's per-layer path lengths, and apply any per-layer absorption afterwards, exactly:
//! a packet of weight w that travelled Li in layer i leaves with w·exp(−Σ μa,i·Li)
//! (microscopic Beer–Lambert; Sassaroli & Fantini 2004, Alerstam et al. 2008).
//!
//! Every stack sharing thicknesses, indices and scattering (e.g. the six skin types at one age
//! and wavelength) then costs one simulation.

use std::time::Instant;

use super::engine::{run_batches, trace, McOptions, Prepared, Scorer};
use super::rng::batch_rng;
use super::stack::{Stack, StackError, MAX_LAYERS};
use super::tally::{McResult, Tally};

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
    fn escape(
        &mut self,
        top: bool,
        scattered: bool,
        weight: f64,
        pos: &[f64; 3],
        _cos_out: f64,
        path: &[f64],
    ) {
        let (x, y) = (pos[0], pos[1]);
        self.run.exit.push(match (top, scattered) {
            (true, true) => 0,
            (true, false) => 1,
            (false, _) => 2,
        });
        self.run.r_mm.push((x * x + y * y).sqrt());
        self.run.weight.push(weight);
        self.run.path_mm.extend_from_slice(path);
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
    let p = Prepared::new(stack)?;
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
        o.photons,
        o.batch_size.max(1),
        o.threads,
        o.progress,
        |b, n| {
            let mut rng = batch_rng(o.seed, b);
            let mut s = WhiteScorer::default();
            let mut events = 0;
            for _ in 0..n {
                trace::<true, _>(&p, &mua_ref, &mut rng, &mut s, &mut events);
            }
            s.run.scattering_events = events;
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
        let mut t = Tally::new(0, self.nr);
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
