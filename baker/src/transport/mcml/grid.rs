//! MCML's 2D tallies: absorption A(r, z) and the reflectance and transmittance Rd(r, α),
//! Tt(r, α), scored alongside the engine's own tallies.

use std::f64::consts::PI;
use std::time::Instant;

use super::mci::McmlRun;
use crate::math::rng::batch_rng;
use crate::transport::engine::{
    run_batches, trace, DirectScorer, Exit, McOptions, Prepared, Scorer, Work,
};
use crate::transport::stack::MAX_LAYERS;
use crate::transport::tally::{McResult, RadialTally};

/// MCML's raw 2D tallies (photon weight), clamped into the last bins as MCML does.
#[derive(Debug, Clone, PartialEq)]
pub struct McmlGrid {
    pub a_rz: Vec<f64>,
    pub rd_ra: Vec<f64>,
    pub tt_ra: Vec<f64>,
}

struct GridScorer<'a> {
    direct: DirectScorer<'a>,
    grid: McmlGrid,
    nz: usize,
    nr: usize,
    na: usize,
    dz_mm: f64,
    dr_mm: f64,
    da: f64,
}

impl GridScorer<'_> {
    fn ir(&self, pos: &[f64; 3]) -> usize {
        (((pos[0] * pos[0] + pos[1] * pos[1]).sqrt() / self.dr_mm) as usize).min(self.nr - 1)
    }
    fn ia(&self, cos_out: f64) -> usize {
        ((cos_out.abs().min(1.0).acos() / self.da) as usize).min(self.na - 1)
    }
}

impl Scorer for GridScorer<'_> {
    fn absorb(&mut self, layer: usize, dw: f64, pos: &[f64; 3]) {
        self.direct.absorb(layer, dw, pos);
        let iz = ((pos[2] / self.dz_mm) as usize).min(self.nz - 1);
        let ir = self.ir(pos);
        self.grid.a_rz[ir * self.nz + iz] += dw;
    }
    fn escape(&mut self, e: &Exit) {
        self.direct.escape(e);
        let k = self.ir(&e.pos) * self.na + self.ia(e.cos_out);
        if e.top {
            self.grid.rd_ra[k] += e.weight;
        } else {
            self.grid.tt_ra[k] += e.weight;
        }
    }
    fn lost(&mut self, weight: f64) {
        self.direct.lost(weight);
    }
    fn roulette(&mut self, dw: f64) {
        self.direct.roulette(dw);
    }
    fn photon_done(&mut self) {
        self.direct.photon_done();
    }
}

/// Runs `run` with MCML's grids as well as the engine's own tallies.
pub fn simulate_grid(run: &McmlRun, o: &McOptions) -> anyhow::Result<(McResult, McmlGrid)> {
    let p = Prepared::new(&run.stack)?;
    let (nz, nr, na) = (run.nz, run.nr, run.na);
    let empty = || McmlGrid {
        a_rz: vec![0.0; nr * nz],
        rd_ra: vec![0.0; nr * na],
        tt_ra: vec![0.0; nr * na],
    };
    let no_ref = [0.0; MAX_LAYERS];
    let t0 = Instant::now();
    let mut total = RadialTally::new(p.nl, p.nr);
    let mut grid = empty();
    // Grids can be large (nr·nz values per batch): batches 10× larger than usual amortise
    // their allocation, and only a couple per thread are in flight. Still deterministic for a
    // given seed, whatever the thread count.
    let o = &McOptions {
        batch_size: o.batch_size.max(1) * 10,
        ..o.clone()
    };
    let threads = run_batches(
        2,
        o,
        |b, n| {
            let mut rng = batch_rng(o.seed, b);
            let mut t = RadialTally::new(p.nl, p.nr);
            let mut work = Work::default();
            let g = {
                let mut s = GridScorer {
                    direct: DirectScorer {
                        t: &mut t,
                        absorbed: [0.0; MAX_LAYERS],
                        roulette: 0.0,
                        dr_mm: p.dr_mm,
                    },
                    grid: empty(),
                    nz,
                    nr,
                    na,
                    dz_mm: run.dz_cm * 10.0,
                    dr_mm: run.dr_cm * 10.0,
                    da: 0.5 * PI / na as f64,
                };
                for _ in 0..n {
                    trace::<false, _>(&p, &no_ref, &mut rng, &mut s, &mut work);
                }
                s.grid
            };
            t.scattering_events = work.events;
            (t, g)
        },
        |(t, g)| {
            total.merge(&t);
            for (a, b) in grid.a_rz.iter_mut().zip(&g.a_rz) {
                *a += b;
            }
            for (a, b) in grid.rd_ra.iter_mut().zip(&g.rd_ra) {
                *a += b;
            }
            for (a, b) in grid.tt_ra.iter_mut().zip(&g.tt_ra) {
                *a += b;
            }
        },
    )?;
    let r = McResult::from_tally(&total, p.rsp, p.dr_mm, threads, t0.elapsed().as_secs_f64());
    Ok((r, grid))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::{Layer, RadialGrid, Stack};

    /// MCML's Rd_ra summed over angles holds, annulus by annulus, what the engine's own Rd(r)
    /// tally holds (an index-matched slab: every top exit has scattered), the last annulus
    /// excepted (MCML's overflow); its A_rz summed holds the absorbed total.
    #[test]
    fn mcml_grids_agree_with_the_engine_tallies() {
        let stack = Stack::in_air(
            Layer {
                name: "slab".into(),
                d_mm: 1.0,
                eta: 1.0,
                mua_per_mm: 0.5,
                mus_per_mm: 10.0,
                g: 0.7,
            },
            0.05,
            40,
        );
        let run = McmlRun::from_stack(&stack, 20_000);
        let (r, g) = simulate_grid(&run, &McOptions::new(20_000, 3)).unwrap();
        assert_eq!(r.rd_unscattered, 0.0);
        let n = r.photons as f64;
        for i in 0..run.nr - 1 {
            let grid: f64 = g.rd_ra[i * run.na..(i + 1) * run.na].iter().sum::<f64>() / n;
            let area = std::f64::consts::PI * stack.grid.dr_mm.powi(2) * (2 * i + 1) as f64;
            let engine = r.rd_r_per_mm2[i] * area;
            assert!(
                (grid - engine).abs() <= 1e-12 * engine.max(1e-300),
                "annulus {i}: {grid} vs {engine}"
            );
        }
        let absorbed: f64 = g.a_rz.iter().sum::<f64>() / n;
        assert!(
            (absorbed - r.absorbed[0]).abs() < 1e-12,
            "{absorbed} vs {}",
            r.absorbed[0]
        );
    }

    /// A(z) of a purely absorbing, index-matched slab against Beer–Lambert: a packet goes
    /// straight down and leaves all its weight where it first interacts, so depth bin
    /// [z₀, z₁) holds e^(−μa z₀) − e^(−μa z₁) of the photons (within 4.5 binomial SE).
    #[test]
    fn absorption_depths_follow_beer_lambert() {
        let stack = Stack {
            n_above: 1.0,
            n_below: 1.0,
            layers: vec![Layer {
                name: "absorber".into(),
                d_mm: 1.0,
                eta: 1.0,
                mua_per_mm: 1.5,
                mus_per_mm: 0.0,
                g: 0.0,
            }],
            junction: None,
            grid: RadialGrid { dr_mm: 0.05, nr: 4 },
        };
        let run = McmlRun::from_stack(&stack, 40_000);
        assert_eq!(run.nz, 20);
        let (r, g) = simulate_grid(&run, &McOptions::new(40_000, 5)).unwrap();
        let n = r.photons as f64;
        let dz_mm = run.dz_cm * 10.0;
        for iz in 0..run.nz {
            let a: f64 = (0..run.nr).map(|ir| g.a_rz[ir * run.nz + iz]).sum::<f64>() / n;
            let (z0, z1) = (iz as f64 * dz_mm, (iz + 1) as f64 * dz_mm);
            let p = (-1.5 * z0).exp() - (-1.5 * z1).exp();
            let se = (p * (1.0 - p) / n).sqrt();
            assert!(
                (a - p).abs() < 4.5 * se,
                "depth bin {iz}: {a} vs {p} ± {se}"
            );
        }
    }
}
