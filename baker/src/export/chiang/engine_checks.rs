//! Evaluations of a fitted model that an engine must reproduce (the `tests` of the `chiang`
//! export; `validation/check_export_hair.py` runs them through Mitsuba 3).

use std::f64::consts::{PI, TAU};

use serde::Serialize;

use super::frame::{local_direction, local_wi};
use super::lobes::{perfect_dphi, P_MAX};
use super::model::{width_panels, Chiang};
use super::safe_asin;

/// One evaluation of the fitted model, for checking an engine against it.
#[derive(Debug, Clone, Serialize)]
pub struct TestEvaluation {
    /// `near`: Mitsuba's `eval` at `wi_local`, `wo_local` (offset h); `far`: the h average.
    pub kind: &'static str,
    pub theta_i_deg: f64,
    pub theta_o_deg: f64,
    pub dphi_deg: f64,
    /// Offset across the fiber (near only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub h: Option<f64>,
    /// Mitsuba local frame (tangent y, normal z), near only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wi_local: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wo_local: Option<[f64; 3]>,
    /// Far only: the h average is over `panels` × 8 Gauss–Legendre nodes in γ = asin h on
    /// \[−π/2, π/2\], weights ½ cos γ (converged to < 0.1 % for the model's β_n).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub panels: Option<usize>,
    /// S or S̄ per channel, sr⁻¹.
    pub value: Vec<f64>,
}

/// Directions where an engine's evaluation must match the model: near-field values at the
/// centres of the R, TT and TRT lobes and beside them, for a few θi and h, and far-field
/// values (h averages) at a few (θi, θo, Δφ).
pub fn test_evaluations(model: &Chiang) -> Vec<TestEvaluation> {
    let mut out = Vec::new();
    let alpha = model.params.alpha_deg;
    // Lobe centres in θo: R at −θi + 2α, TT at −θi − α, TRT at −θi − 4α (hair.cpp reframe).
    let shift = [2.0 * alpha, -alpha, -4.0 * alpha];
    for &(ti, h) in &[(-50.0, -0.6), (-15.0, 0.25), (20.0, 0.8), (45.0, -0.1)] {
        let theta_i = f64::to_radians(ti);
        let inc = model.incidence(theta_i.sin(), theta_i.cos(), safe_asin(h));
        for p in 0..P_MAX {
            for &(dt, dp) in &[(0.0, 0.0), (4.0, 0.15)] {
                let to = -ti + shift[p] + dt;
                let dphi = perfect_dphi(p, inc.gamma_i, inc.gamma_t) + dp;
                let dphi = dphi - TAU * ((dphi + PI) / TAU).floor();
                let wi = local_wi(theta_i, h);
                let phi_i = wi[2].atan2(wi[0]);
                let wo = local_direction(to.to_radians(), phi_i + dphi);
                out.push(TestEvaluation {
                    kind: "near",
                    theta_i_deg: ti,
                    theta_o_deg: to,
                    dphi_deg: dphi.to_degrees(),
                    h: Some(h),
                    wi_local: Some(wi),
                    wo_local: Some(wo),
                    panels: None,
                    value: model.eval_local(wi, wo),
                });
            }
        }
    }
    for &(ti, to, dphi) in &[
        (-40.0, 40.0, 0.0),
        (-40.0, 35.0, 60.0),
        (-20.0, 22.0, 180.0),
        (10.0, -12.0, 150.0),
        (30.0, -30.0, 120.0),
        (60.0, -55.0, 30.0),
    ] {
        let panels = 4 * width_panels(model.s);
        out.push(TestEvaluation {
            kind: "far",
            theta_i_deg: ti,
            theta_o_deg: to + 2.0 * alpha,
            dphi_deg: dphi,
            h: None,
            wi_local: None,
            wo_local: None,
            panels: Some(panels),
            value: model.eval_far(
                f64::to_radians(ti),
                f64::to_radians(to + 2.0 * alpha),
                f64::to_radians(dphi),
                Some(panels),
            ),
        });
    }
    out
}
