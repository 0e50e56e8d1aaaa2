//! The fit of the Chiang model to a [`FitTarget`]: σa per channel by bisection on the
//! table's albedo, the shape (η, β_m, β_n, α) by Nelder–Mead; see the module docs, "The fit".

use super::binning::{bin_panels, binned, ShapeSlice};
use super::model::{Chiang, ChiangParams};
use super::target::{ChiangFitOptions, FitTarget};
use serde::Serialize;

/// Lower bound of β_m and β_n in the fit (Mitsuba, pbrt-v4 and Cycles accept \[0, 1\]; below
/// this the lobes are far narrower than any table bin).
pub const BETA_MIN: f64 = 0.02;

/// Sums over bins of |model − table|·ΔΩ, (model − table)²·ΔΩ, model·ΔΩ.
fn bin_errors(model: &[f64], table: &[f64], d_omega: &[f64], n_phi: usize) -> (f64, f64, f64) {
    let (mut l1, mut l2, mut e) = (0.0, 0.0, 0.0);
    for (b, (&m, &t)) in model.iter().zip(table).enumerate() {
        let dw = d_omega[b / n_phi];
        l1 += (m - t).abs() * dw;
        l2 += (m - t) * (m - t) * dw;
        e += m * dw;
    }
    (l1, l2, e)
}

/// What the fit found and how close it is.
#[derive(Debug, Clone, Serialize)]
pub struct FitReport {
    pub params: ChiangParams,
    /// η came from the table's metadata (not fitted).
    pub eta_fixed: bool,
    /// Σ |S̄ − f|·ΔΩ / Σ f·ΔΩ over the sampled θi, bins and channels.
    pub rel_l1: f64,
    /// √(Σ (S̄ − f)²·ΔΩ / Σ f²·ΔΩ), same bins.
    pub rel_l2: f64,
    pub rel_l1_per_channel: Vec<f64>,
    pub rel_l2_per_channel: Vec<f64>,
    /// Per channel, the mean over the sampled θi of the table's Λ (φi-averaged).
    pub albedo_table: Vec<f64>,
    /// Per channel, the mean over the sampled θi of the model's Σ S̄·ΔΩ.
    pub albedo_model: Vec<f64>,
    pub theta_i_deg: Vec<f64>,
    pub phi_i_deg: Vec<f64>,
    /// Objective evaluations (shape parameter sets tried).
    pub evaluations: usize,
}

/// Shape parameters in the optimiser's unbounded coordinates.
#[derive(Debug, Clone, Copy)]
struct Shape {
    eta: f64,
    beta_m: f64,
    beta_n: f64,
    alpha_deg: f64,
}

const ALPHA_MAX_DEG: f64 = 15.0;

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

fn logit(y: f64) -> f64 {
    (y / (1.0 - y)).ln()
}

impl Shape {
    fn from_x(x: &[f64], eta: Option<f64>) -> Self {
        let beta = |x: f64| BETA_MIN + (1.0 - BETA_MIN) * sigmoid(x);
        Shape {
            beta_m: beta(x[0]),
            beta_n: beta(x[1]),
            alpha_deg: ALPHA_MAX_DEG * x[2].tanh(),
            eta: eta.unwrap_or_else(|| (1.0 + x[3].exp()).min(3.0)),
        }
    }

    fn to_x(self, fit_eta: bool) -> Vec<f64> {
        let inv_beta = |b: f64| logit(((b - BETA_MIN) / (1.0 - BETA_MIN)).clamp(1e-6, 1.0 - 1e-6));
        let mut x = vec![
            inv_beta(self.beta_m),
            inv_beta(self.beta_n),
            (self.alpha_deg / ALPHA_MAX_DEG)
                .clamp(-0.999, 0.999)
                .atanh(),
        ];
        if fit_eta {
            x.push((self.eta - 1.0).max(1e-3).ln());
        }
        x
    }
}

/// Range of ln σa searched per channel.
const LN_SIGMA_RANGE: (f64, f64) = (-9.0, 6.5);

struct Problem<'a> {
    target: &'a FitTarget,
    d_omega: Vec<f64>,
    /// Σ f·ΔΩ over all sampled θi and channels.
    norm_l1: f64,
}

impl<'a> Problem<'a> {
    fn new(target: &'a FitTarget) -> Self {
        let d_omega = target.d_omega();
        let n_phi = target.grid.n_phi;
        let norm_l1 = target
            .values
            .iter()
            .enumerate()
            .map(|(b, &t)| t * d_omega[(b % target.grid.bins()) / n_phi])
            .sum();
        Self {
            target,
            d_omega,
            norm_l1,
        }
    }

    fn slices(&self, shape: Shape) -> Vec<ShapeSlice> {
        let model = Chiang::new(ChiangParams {
            eta: shape.eta,
            sigma_a: vec![],
            beta_m: shape.beta_m,
            beta_n: shape.beta_n,
            alpha_deg: shape.alpha_deg,
        });
        self.target
            .theta_i_deg
            .iter()
            .map(|t| {
                model.shape_slice(
                    &self.target.grid,
                    t.to_radians(),
                    bin_panels(model.s, &self.target.grid),
                )
            })
            .collect()
    }

    /// L1 numerator of channel c for absorption σa.
    fn channel_l1(&self, slices: &[ShapeSlice], c: usize, sigma_a: f64, buf: &mut [f64]) -> f64 {
        let grid = &self.target.grid;
        let mut l1 = 0.0;
        for (i, s) in slices.iter().enumerate() {
            s.channel(grid, sigma_a, buf);
            l1 += bin_errors(buf, self.target.slice(i, c), &self.d_omega, grid.n_phi).0;
        }
        l1
    }

    /// σa of channel c that gives the model the table's albedo (Σ over the sampled θi of
    /// Σ S̄·ΔΩ = Σ of the table's), by bisection on ln σa (the albedo falls as σa grows), and
    /// the channel's L1 numerator there.
    fn best_sigma(&self, slices: &[ShapeSlice], c: usize, buf: &mut [f64]) -> (f64, f64) {
        let nc = self.target.channels.len();
        let want: f64 = (0..slices.len())
            .map(|i| self.target.albedo[i * nc + c])
            .sum();
        let albedo = |x: f64| -> f64 { slices.iter().map(|s| s.albedo(x.exp())).sum() };
        let (mut lo, mut hi) = LN_SIGMA_RANGE;
        if albedo(lo) <= want {
            // Even a clear fiber is darker than the table: no absorption at all.
            return (0.0, self.channel_l1(slices, c, 0.0, buf));
        }
        let x = if albedo(hi) >= want {
            hi
        } else {
            for _ in 0..48 {
                let mid = 0.5 * (lo + hi);
                if albedo(mid) > want {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        };
        (x.exp(), self.channel_l1(slices, c, x.exp(), buf))
    }

    /// Objective of a shape: relative L1 with each channel's best σa.
    fn objective(&self, shape: Shape) -> (f64, Vec<f64>) {
        let slices = self.slices(shape);
        let mut buf = vec![0.0; self.target.grid.bins()];
        let mut total = 0.0;
        let mut sigma = Vec::with_capacity(self.target.channels.len());
        for c in 0..self.target.channels.len() {
            let (s, l1) = self.best_sigma(&slices, c, &mut buf);
            total += l1;
            sigma.push(s);
        }
        (total / self.norm_l1, sigma)
    }
}

/// Fits the model to `target` (see the module docs for the objective).
pub fn fit(target: &FitTarget, opts: &ChiangFitOptions) -> FitReport {
    let problem = Problem::new(target);
    let fit_eta = opts.eta.is_none();
    let mut evaluations = 0usize;
    // Start: the best of a small grid of shapes.
    let mut start = None;
    for &bm in &[0.08, 0.2, 0.45] {
        for &bn in &[0.15, 0.35, 0.7] {
            for &eta in if fit_eta { &[1.4, 1.6][..] } else { &[0.0][..] } {
                let shape = Shape {
                    eta: opts.eta.unwrap_or(eta),
                    beta_m: bm,
                    beta_n: bn,
                    alpha_deg: 0.0,
                };
                let (v, _) = problem.objective(shape);
                evaluations += 1;
                if start.as_ref().is_none_or(|(best, _)| v < *best) {
                    start = Some((v, shape));
                }
            }
        }
    }
    let (_, shape0) = start.expect("the grid is not empty");
    let mut objective = |x: &[f64]| problem.objective(Shape::from_x(x, opts.eta)).0;
    let (mut x, mut fx, n) = crate::fit::nelder_mead(
        &mut objective,
        &shape0.to_x(fit_eta),
        0.6,
        opts.max_evaluations,
        1e-7,
    );
    evaluations += n;
    // Restart from the best point until it stops improving.
    for step in [0.3, 0.15] {
        let (x2, f2, n) =
            crate::fit::nelder_mead(&mut objective, &x, step, opts.max_evaluations, 1e-7);
        evaluations += n;
        let better = f2 < fx * (1.0 - 1e-4);
        if f2 < fx {
            x = x2;
            fx = f2;
        }
        if !better {
            break;
        }
    }
    let shape = Shape::from_x(&x, opts.eta);
    let (_, sigma_a) = problem.objective(shape);
    let params = ChiangParams {
        eta: shape.eta,
        sigma_a,
        beta_m: shape.beta_m,
        beta_n: shape.beta_n,
        alpha_deg: shape.alpha_deg,
    };
    let mut report = evaluate(target, &params);
    report.eta_fixed = !fit_eta;
    report.evaluations = evaluations;
    report
}

/// The errors and albedos of `params` against `target` (a [`FitReport`] with no fitting).
pub fn evaluate(target: &FitTarget, params: &ChiangParams) -> FitReport {
    let model = Chiang::new(params.clone());
    let problem = Problem::new(target);
    let grid = &target.grid;
    let nc = target.channels.len();
    let (mut l1, mut l2, mut t1, mut t2) =
        (vec![0.0; nc], vec![0.0; nc], vec![0.0; nc], vec![0.0; nc]);
    let mut albedo_model = vec![0.0; nc];
    let mut albedo_table = vec![0.0; nc];
    let n_ti = target.theta_i_deg.len() as f64;
    let zeros = vec![0.0; grid.bins()];
    for (i, t) in target.theta_i_deg.iter().enumerate() {
        let m = binned(&model, grid, t.to_radians());
        for c in 0..nc {
            let tab = target.slice(i, c);
            let mc = &m[c * grid.bins()..(c + 1) * grid.bins()];
            let (a, b, e) = bin_errors(mc, tab, &problem.d_omega, grid.n_phi);
            l1[c] += a;
            l2[c] += b;
            albedo_model[c] += e / n_ti;
            albedo_table[c] += target.albedo[i * nc + c] / n_ti;
            // Against zero: Σ f·ΔΩ and Σ f²·ΔΩ, the normalisers.
            let (n1, n2, _) = bin_errors(&zeros, tab, &problem.d_omega, grid.n_phi);
            t1[c] += n1;
            t2[c] += n2;
        }
    }
    let ratio = |a: &[f64], b: &[f64]| a.iter().sum::<f64>() / b.iter().sum::<f64>();
    FitReport {
        params: params.clone(),
        eta_fixed: false,
        rel_l1: ratio(&l1, &t1),
        rel_l2: ratio(&l2, &t2).sqrt(),
        rel_l1_per_channel: l1.iter().zip(&t1).map(|(a, b)| a / b).collect(),
        rel_l2_per_channel: l2.iter().zip(&t2).map(|(a, b)| (a / b).sqrt()).collect(),
        albedo_table,
        albedo_model,
        theta_i_deg: target.theta_i_deg.clone(),
        phi_i_deg: target.phi_i_deg.clone(),
        evaluations: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::chiang::model::tests::params;
    use crate::export::chiang::FitGrid;
    use formats::bcsdf::{solid_angle, Bcsdf, Directory, Precision, Writer, FLIP_THETA, KIND};

    /// A `.bcsdf` whose values are the binned model itself (round fiber: one stored ωi per θi
    /// row, mirrored rows flagged).
    fn table_of(model: &Chiang, res_deg: f64) -> Bcsdf {
        let n_theta = (180.0 / res_deg) as usize;
        let grid = FitGrid {
            res_deg,
            n_theta,
            n_phi: 2 * n_theta,
        };
        let nc = model.channels();
        let mut wi_map = vec![0u32; grid.bins()];
        let mut wi_deg = Vec::new();
        let mut slices = Vec::new();
        let mut albedo = Vec::new();
        for r in 0..n_theta {
            let ti = grid.theta_centre(r);
            let b = binned(model, &grid, ti);
            let mut values = Vec::with_capacity(b.len());
            for c in 0..nc {
                let part = &b[c * grid.bins()..(c + 1) * grid.bins()];
                let a: f64 = part
                    .iter()
                    .enumerate()
                    .map(|(i, x)| x * solid_angle(res_deg, i / grid.n_phi))
                    .sum();
                albedo.push(a as f32);
                values.extend(part.iter().map(|x| x / a));
            }
            for k in 0..grid.n_phi {
                wi_map[r * grid.n_phi + k] = r as u32;
            }
            wi_deg.push([ti.to_degrees(), -180.0 + 0.5 * res_deg]);
            slices.push(values);
        }
        // Exercise the mirror flag: the top row reuses the bottom row with θo flipped (exact
        // for α = 0).
        if model.params.alpha_deg == 0.0 {
            wi_map[(n_theta - 1) * grid.n_phi..].fill(FLIP_THETA);
        }
        let dir = Directory {
            kind: KIND.into(),
            res_deg,
            n_theta,
            n_phi: grid.n_phi,
            wi_deg,
            wi_map,
            variants: vec!["model".into()],
            channels: (0..nc).map(|c| format!("c{c}")).collect(),
            dtype: Precision::F32,
            keep_bits: 23,
            scale: vec![],
            albedo,
            albedo_se: vec![0.0; n_theta * nc],
            area_um: vec![10.0; grid.n_phi],
            chunks: vec![],
            metadata: serde_json::json!({"eta": model.params.eta}),
        };
        let mut w = Writer::new(dir, 1);
        for s in &slices {
            w.push(s).unwrap();
        }
        Bcsdf::from_bytes(w.finish().unwrap()).unwrap()
    }

    #[test]
    fn fit_recovers_the_parameters_of_a_table_made_by_the_model() {
        let truth = ChiangParams {
            eta: 1.55,
            sigma_a: vec![0.15, 0.8, 2.5],
            beta_m: 0.3,
            beta_n: 0.4,
            alpha_deg: -3.0,
        };
        let table = table_of(&Chiang::new(truth.clone()), 15.0);
        let opts = ChiangFitOptions {
            theta_i_rows: 6,
            phi_i_samples: 2,
            eta: Some(1.55),
            max_evaluations: 250,
            ..ChiangFitOptions::default()
        };
        let target = FitTarget::from_table(&table, 0, &opts).unwrap();
        let exact = evaluate(&target, &truth);
        assert!(
            exact.rel_l1 < 1e-5,
            "the table is the model: {}",
            exact.rel_l1
        );
        let r = fit(&target, &opts);
        let p = &r.params;
        assert!(r.rel_l1 < 0.01, "rel L1 {}", r.rel_l1);
        assert!((p.beta_m - 0.3).abs() < 0.02, "{p:?}");
        assert!((p.beta_n - 0.4).abs() < 0.02, "{p:?}");
        assert!((p.alpha_deg + 3.0).abs() < 0.5, "{p:?}");
        for (a, b) in p.sigma_a.iter().zip(&truth.sigma_a) {
            assert!((a / b - 1.0).abs() < 0.05, "{p:?}");
        }
        for (a, b) in r.albedo_model.iter().zip(&r.albedo_table) {
            assert!((a - b).abs() < 0.01, "{r:?}");
        }
    }

    #[test]
    fn mirrored_rows_read_back_through_the_flags() {
        let m = Chiang::new(params(vec![0.5], 0.0));
        let table = table_of(&m, 30.0);
        let opts = ChiangFitOptions {
            theta_i_rows: 6,
            max_theta_i_deg: 90.0,
            phi_i_samples: 1,
            ..ChiangFitOptions::default()
        };
        let target = FitTarget::from_table(&table, 0, &opts).unwrap();
        assert!(evaluate(&target, &m.params).rel_l1 < 1e-5);
        assert!(FitTarget::from_table(&table, 1, &opts).is_err());
    }
}
