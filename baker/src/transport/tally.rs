//! What a transport run scores, with standard errors from per-photon Σx and Σx².

use serde::Serialize;

use crate::stats::Sums;

/// Raw sums of a direct (absorbing) run on a uniform radial grid: Rd, Rd(r) per annulus, the
/// unscattered Rd, Tt and the absorption per layer, for one batch (or a whole run once
/// batches are merged in order).
#[derive(Debug, Clone, PartialEq)]
pub struct RadialTally {
    pub photons: u64,
    pub rd: Sums,
    pub rd_unscattered: Sums,
    pub tt: Sums,
    pub absorbed: Vec<Sums>,
    /// Absorbed in all layers together, per photon (its Σx² gives the total's own SE).
    pub absorbed_total: Sums,
    pub rd_r: Vec<Sums>,
    /// Weight of photons stopped after too many boundary hits without interacting.
    pub lost: Sums,
    /// Net weight Russian roulette added, per photon (zero in expectation).
    pub roulette: Sums,
    pub scattering_events: u64,
}

impl RadialTally {
    pub fn new(layers: usize, nr: usize) -> Self {
        Self {
            photons: 0,
            rd: Sums::default(),
            rd_unscattered: Sums::default(),
            tt: Sums::default(),
            absorbed: vec![Sums::default(); layers],
            absorbed_total: Sums::default(),
            rd_r: vec![Sums::default(); nr],
            lost: Sums::default(),
            roulette: Sums::default(),
            scattering_events: 0,
        }
    }

    pub fn merge(&mut self, o: &RadialTally) {
        self.photons += o.photons;
        self.rd.merge(&o.rd);
        self.rd_unscattered.merge(&o.rd_unscattered);
        self.tt.merge(&o.tt);
        for (a, b) in self.absorbed.iter_mut().zip(&o.absorbed) {
            a.merge(b);
        }
        self.absorbed_total.merge(&o.absorbed_total);
        for (a, b) in self.rd_r.iter_mut().zip(&o.rd_r) {
            a.merge(b);
        }
        self.lost.merge(&o.lost);
        self.roulette.merge(&o.roulette);
        self.scattering_events += o.scattering_events;
    }
}

/// The result of a run, as `baker mc --json` prints it. Reflectances and transmittances are
/// fractions of the incident power; `rd_r_per_mm2` is Rd(r) per unit area at the bin centres.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct McResult {
    pub rsp: f64,
    pub rsp_se: f64,
    pub rd: f64,
    pub rd_se: f64,
    pub rd_unscattered: f64,
    pub rd_unscattered_se: f64,
    pub tt: f64,
    pub tt_se: f64,
    pub absorbed: Vec<f64>,
    pub absorbed_se: Vec<f64>,
    /// Absorbed in all layers (MCML's A), with its standard error from per-photon sums (not
    /// the per-layer SEs in quadrature: one photon's absorptions in different layers are
    /// correlated). Absent where absorption is not resolved (white runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub absorbed_total: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub absorbed_total_se: Option<f64>,
    pub r_mm: Vec<f64>,
    pub rd_r_per_mm2: Vec<f64>,
    pub rd_r_per_mm2_se: Vec<f64>,
    /// ∫ Rd(r) 2πr dr over the grid: equals `rd` up to light beyond the last bin.
    pub rd_r_integrated: f64,
    /// Weight of photons stopped for bouncing without interacting (reported, ideally 0).
    pub lost: f64,
    /// Net weight Russian roulette added per incident photon (zero in expectation), with its
    /// standard error: Rsp + Rd + Tt + ΣA + lost = 1 + `roulette` exactly, photon by photon.
    pub roulette: f64,
    pub roulette_se: f64,
    pub photons: u64,
    pub threads: usize,
    pub seconds: f64,
    pub photons_per_s: f64,
    pub scattering_events: u64,
    pub scattering_events_per_s: f64,
}

impl McResult {
    pub fn from_tally(t: &RadialTally, rsp: f64, dr_mm: f64, threads: usize, seconds: f64) -> Self {
        let n = t.photons;
        let area = |i: usize| std::f64::consts::PI * dr_mm * dr_mm * (2 * i + 1) as f64;
        let rd_r: Vec<f64> = t
            .rd_r
            .iter()
            .enumerate()
            .map(|(i, s)| s.mean(n) / area(i))
            .collect();
        let rd_r_integrated = t.rd_r.iter().map(|s| s.mean(n)).sum();
        Self {
            rsp,
            rsp_se: 0.0,
            rd: t.rd.mean(n),
            rd_se: t.rd.se(n),
            rd_unscattered: t.rd_unscattered.mean(n),
            rd_unscattered_se: t.rd_unscattered.se(n),
            tt: t.tt.mean(n),
            tt_se: t.tt.se(n),
            absorbed: t.absorbed.iter().map(|s| s.mean(n)).collect(),
            absorbed_se: t.absorbed.iter().map(|s| s.se(n)).collect(),
            absorbed_total: (!t.absorbed.is_empty()).then(|| t.absorbed_total.mean(n)),
            absorbed_total_se: (!t.absorbed.is_empty()).then(|| t.absorbed_total.se(n)),
            r_mm: (0..t.rd_r.len())
                .map(|i| (i as f64 + 0.5) * dr_mm)
                .collect(),
            rd_r_per_mm2: rd_r,
            rd_r_per_mm2_se: t
                .rd_r
                .iter()
                .enumerate()
                .map(|(i, s)| s.se(n) / area(i))
                .collect(),
            rd_r_integrated,
            lost: t.lost.mean(n),
            roulette: t.roulette.mean(n),
            roulette_se: t.roulette.se(n),
            photons: n,
            threads,
            seconds,
            photons_per_s: n as f64 / seconds.max(1e-12),
            scattering_events: t.scattering_events,
            scattering_events_per_s: t.scattering_events as f64 / seconds.max(1e-12),
        }
    }

    /// Rsp + Rd + Tt + ΣA + lost: 1 up to statistical error.
    pub fn energy(&self) -> f64 {
        self.rsp
            + self.rd
            + self.rd_unscattered
            + self.tt
            + self.absorbed.iter().sum::<f64>()
            + self.lost
    }
}
