//! One incoming direction of a spec entry, traced the way the entry's bake traces a stored
//! direction: its `bake:` settings (bin size, `split`, `exit_draws`, `target_rel_se`,
//! `max_photons_per_direction`, batch size) on its first cross-section, scored for one
//! absorption coefficient. `baker fiber trace SPEC --entry E` prints it, so what a user probes
//! is what the table will hold, with the estimator's own standard errors (batch means).
//!
//! Two differences from a bake, both deliberate: the beam comes from exactly (θi, φi), not
//! averaged over the bin that contains it, and there is one channel (the fraction of the
//! intercepted power at one wavelength) instead of the entry's dye sweep. Under
//! `share_theta` = k the direction is traced with the directions a bake would share its
//! photons with: (θi + j·res, φi) for the k − 1 θ rows on either side (every window holding
//! it, [`crate::fiber::tracer::shared::Windows`]), its result the one returned.

use super::setup::typical_path_um;
use crate::cancel::{Cancel, Cancelled};
use crate::fiber::slices::{trace_group, BakeSettings, SliceResult};
use crate::fiber::sweep::{ChannelKind, Channels, Variant};
use crate::fiber::tracer::shared::Windows;
use crate::fiber::{Fiber, Incident};
use formats::AngularGrid;

/// A direction traced with a bake's settings.
#[derive(Debug, Clone)]
pub struct DirectionTrace {
    pub grid: AngularGrid,
    /// One channel: `fraction` is `[θo][Δφ]`, `density_se` its standard error per bin,
    /// `dphi_se` that of its sum over θo.
    pub result: SliceResult,
    /// A(ωi): exact projected width per unit length from the outline, µm.
    pub projected_width_um: f64,
    /// Whether the slice reached `settings.target` (None without a target).
    pub reached_target: Option<bool>,
}

/// Traces `fiber` lit from `inc` with the estimators, bins and photon budget of `st`, scoring
/// absorption `mua_per_um` (at `lambda_nm`, a label only). Deterministic for a given `seed`
/// whatever the thread count.
pub fn trace_direction(
    fiber: &Fiber,
    st: &BakeSettings,
    inc: Incident,
    (lambda_nm, mua_per_um): (f64, f64),
    seed: u64,
    cancel: &Cancel,
) -> anyhow::Result<Result<DirectionTrace, Cancelled>> {
    let grid = AngularGrid::new(st.res_deg).map_err(anyhow::Error::msg)?;
    let variant = Variant {
        name: format!("μa {mua_per_um} /µm at {lambda_nm} nm"),
        mua_per_um: vec![mua_per_um],
    };
    let channels = Channels::new(
        &[variant],
        &[lambda_nm],
        ChannelKind::Spectral,
        typical_path_um(fiber),
    );
    // The θ rows of every window holding the direction ([`crate::fiber::tracer::shared::Windows`]):
    // the k − 1 rows on each side, so it lies at every place of a window as in a bake's
    // column.
    let k = match crate::fiber::tracer::shared::shares(&fiber.surface, fiber.cuticle.as_ref()) {
        true => st.share_theta.max(1) as usize,
        false => 1,
    };
    let res = st.res_deg.to_radians();
    let it = (((inc.theta_rad + 0.5 * std::f64::consts::PI) / res).floor() as usize)
        .min(grid.n_theta - 1);
    let windows = Windows::new(grid.n_theta, k);
    let it0 = windows.members(it).start;
    let incs: Vec<Incident> = (it0..windows.members(it + windows.k - 1).end)
        .map(|t| Incident {
            theta_rad: inc.theta_rad + (t as f64 - it as f64) * res,
            ..inc
        })
        .collect();
    let seeds = vec![seed; incs.len()];
    let traced = trace_group(fiber, &incs, &grid, &channels, st, &seeds, cancel);
    Ok(traced.map(|mut all| {
        let result = all.swap_remove(it - it0);
        DirectionTrace {
            grid,
            reached_target: st.target.map(|t| t.met_by(&result.noise)),
            projected_width_um: fiber.projected_width_um(inc.phi_rad),
            result,
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fiber::section::Section;
    use crate::fiber::surface::Surface;

    /// Probes with different seeds differ by what their per-bin standard errors claim:
    /// Σ (a − b)²/(σa² + σb²) over the well-populated bins (σ below 10 % of the value) is
    /// χ² with one degree of freedom per bin, pooled here over four pairs of seeds. Its mean
    /// per bin is 1 (a little above with estimated σ: 1.02 for 64 batches, more in sparse
    /// bins); measured 1.07 over 820 bins and 1.00 over 144 Δφ columns. σ off by 25 % either way gives
    /// 1.78 or 0.64 and fails.
    #[test]
    fn seeds_differ_by_the_claimed_standard_errors() {
        let fiber = Fiber {
            section: Section::circle(10.0),
            surface: Surface {
                eta: 1.55,
                alpha: 10f64.to_radians().tan(),
            },
            cuticle: None,
        };
        let st = BakeSettings {
            res_deg: 10.0,
            photons: 64 * 1024,
            batch: 1024,
            split: 4,
            exit_draws: 8,
            ..BakeSettings::default()
        };
        let inc = Incident::from_deg(-30.0, 20.0);
        let cancel = Cancel::default();
        let run = |seed| {
            trace_direction(&fiber, &st, inc, (550.0, 0.02), seed, &cancel)
                .unwrap()
                .unwrap()
        };
        let (mut bins, mut cols) = ((0.0, 0usize), (0.0, 0usize));
        let add = |acc: &mut (f64, usize), (a, sa): (f64, f64), (b, sb): (f64, f64)| {
            let m = 0.5 * (a + b);
            if m > 0.0 && sa > 0.0 && sb > 0.0 && sa < 0.1 * m {
                acc.0 += (a - b).powi(2) / (sa * sa + sb * sb);
                acc.1 += 1;
            }
        };
        for seed in [1, 3, 5, 7] {
            let (a, b) = (run(seed).result, run(seed + 1).result);
            let g = AngularGrid::new(st.res_deg).unwrap();
            for bin in 0..g.bins() {
                add(
                    &mut bins,
                    (a.fraction[bin], a.density_se[bin]),
                    (b.fraction[bin], b.density_se[bin]),
                );
            }
            let col = |r: &SliceResult, j: usize| -> f64 {
                (0..g.n_theta).map(|i| r.fraction[i * g.n_phi + j]).sum()
            };
            for j in 0..g.n_phi {
                add(
                    &mut cols,
                    (col(&a, j), a.dphi_se[j]),
                    (col(&b, j), b.dphi_se[j]),
                );
            }
        }
        let (rb, rc) = (bins.0 / bins.1 as f64, cols.0 / cols.1 as f64);
        assert!(
            bins.1 > 600 && cols.1 > 100,
            "bins {bins:?}, columns {cols:?}"
        );
        assert!(
            (0.85..1.25).contains(&rb),
            "χ²/bin {rb:.3} over {} bins",
            bins.1
        );
        assert!(
            (0.7..1.45).contains(&rc),
            "χ²/column {rc:.3} over {}",
            cols.1
        );
    }
}
