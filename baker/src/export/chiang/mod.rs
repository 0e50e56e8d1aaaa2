//! The Chiang et al. 2016 hair model[^chiang16] as Mitsuba 3's `hair` plugin evaluates it,
//! and its fit to a baked fiber BCSDF table (`.bcsdf`, thesis §5.5).
//!
//! # The model
//! The fiber is a rough dielectric cylinder of index η with an absorbing interior. Light that
//! enters at offset h ∈ \[−1, 1\] (h = sin γi across the width) leaves after p internal paths
//! (R, TT, TRT, and a residual for p ≥ 3):
//!
//! S(ωi, ωo; h) = Σ_{p<3} Mp(θi′ₚ, θo)·Ap(θi, h)·Np(Δφ; h) + M₃(θi, θo)·A₃(θi, h)/(2π)
//!
//! - Mp: d'Eon et al.'s[^deon11] longitudinal lobe with the log-Bessel form for small
//!   variance; variances v₀ = (0.726 βm + 0.812 βm² + 3.7 βm²⁰)², v₁ = v₀/4, v₂ = v₃ = 4 v₀
//!   (Chiang Eq. 7).
//! - θi′ₚ: the cuticle tilt α shifts the longitudinal angle by −2α (R), +α (TT), +4α (TRT).
//! - Ap: Fresnel reflectance f at cos θi·cos γi and the transmittance T = exp(−σa·2 cos γt /
//!   cos θt) of one chord (Chiang Eq. 3–6); σa is per unit fiber *radius* (the chord length
//!   2 cos γt is that of a unit-radius circle).
//! - Np: a logistic of scale s = √(π/8)·(0.265 βn + 1.194 βn² + 5.372 βn²²) around
//!   Φ(p, h) = 2p γt − 2γi + pπ, trimmed to \[−π, π\] (Chiang Eq. 8–10).
//!
//! Every formula follows mitsuba3 `src/bsdfs/hair.cpp` (v3.9, `Hair::eval`, `attenuation`,
//! `reframe_with_scales`, `azimuthal_scattering`, `update`) and `include/mitsuba/core/warp.h`
//! (`square_to_rough_fiber_pdf`, its 10-term I₀ series and asymptotic log I₀ above 12, the
//! constant 0.6931), so [`Chiang::eval_local`] returns what Mitsuba's `eval` returns, including
//! its lack of a cosine factor (∫ S dωo = Σ Ap; Mitsuba's `test_hair.py` white furnace).
//! `validation/check_export_hair.py` compares the two at the directions listed by
//! [`test_evaluations`].
//!
//! # Frames
//! Mitsuba's local frame (`hair.cpp`): the fiber tangent is local **y**, the surface normal
//! local **z**; sin θ = ω·y, φ = atan2(ω·z, ω·x) and h = sin γ(wi) with γ the angle between
//! wi's projection on the x–z plane and z, negative for x > 0, so h = −x/√(x² + z²). On a
//! `bsplinecurve` (Mitsuba 3.9) the shading frame's s = ∂p/∂u goes around the fiber and
//! t = ∂p/∂v along it, so local y is the curve direction (first to last control point) and h
//! follows the hit point. The table frame (fiber axis +z, θ = asin(ω·z), φ = atan2(ω·y, ω·x))
//! maps to it by (x, y, z)table = (x, z, y)Mitsuba: same θ, same φ, same Δφ. The model's α
//! sign is Mitsuba's and pbrt-v4's: the R lobe peaks at θi + θo = 2α about that axis.
//!
//! # Far field and the table
//! A table stores f = Λ·f̂: the fraction of the power the fiber intercepts from ωi that
//! leaves per steradian around ωo, averaged over the fiber width. Chiang's model integrates
//! over the width the same way (uniform in h, the projected width): the far-field
//! S̄(ωi, ωo) = ½∫ S(ωi, ωo; h) dh has ∫ S̄ dωo = the albedo, like ∫ f dωo = Λ, so the fit
//! compares S̄ with f directly, bin by bin (no cosine). The table's ωi (towards the light)
//! plays the role of the engine's `wi` (Mitsuba's `si.wi`, pbrt's `wo`: the direction the
//! path arrived from); by the reciprocity of the fiber (cos θi·f(ωi, ωo) = cos θo·f(ωo, ωi))
//! that is exactly the radiance a renderer needs, L(ωo) = ∫ S̄(ωo, ωi) L(ωi) dωi.
//!
//! Chiang's model is rotation invariant: it depends on Δφ only, and S̄ is even in Δφ. A table of
//! a non-round section depends on φi too; the fit is to its average over φi (a fiber seen at
//! every orientation), and so is the error reported.
//!
//! # The fit
//! Parameters: σa per channel, βm, βn, α, and η unless the table's metadata gives it (the
//! spec's mean index, used as is). For every θi of a subsample of the table's rows (default
//! 8, symmetric about 0, |θi| ≤ 80°) and every bin (θo row, Δφ column) the model is integrated
//! exactly over the bin — Δφ through the logistic's CDF, θo by Gauss–Legendre within the row,
//! h by composite Gauss–Legendre in γ — and compared with the table's value averaged over a
//! few φi. The objective is the **relative L1 error of f over the bins**,
//! Σ |S̄ − f|·ΔΩ / Σ f·ΔΩ summed over θi and channels: the fraction of scattered energy the
//! fit puts in the wrong bins (0 = exact; 2 = disjoint). The relative L2 error
//! √(Σ (S̄ − f)²·ΔΩ / Σ f²·ΔΩ) and the albedo of both are reported as well.
//!
//! Each channel's σa is not free: for given shape parameters (η, βm, βn, α) it is the one
//! that gives the model the table's albedo (summed over the sampled θi), found by bisection.
//! The fit so keeps every channel's energy — the fiber's colour — and spends its freedom on
//! the angular distribution; a free L1 fit trades energy for shape where the shapes differ
//! (on the trilobal polyester it would drop 40 % of the red). Where even σa → 0 gives less
//! than the table (a table albedo above the smooth cylinder's), σa is 0. The
//! shape parameters come from Nelder–Mead (Lagarias et al. 1998 coefficients) started from
//! the best of a small grid.
//!
//! [^chiang16]: M. J.-Y. Chiang, B. Bitterli, C. Tappan, B. Burley, "A Practical and
//!   Controllable Hair and Fur Model for Production Path Tracing", Computer Graphics Forum
//!   35(2), 2016.
//! [^deon11]: E. d'Eon, G. Francois, M. Hill, J. Letteri, J.-M. Aubry, "An Energy-Conserving
//!   Hair Reflectance Model", Computer Graphics Forum 30(4), 2011.
//!
//! # Files
//! `lobes` (Mp and Np), `frame` (Mitsuba's local frame), `model` ([`Chiang`]: near and far
//! field), `binning` ([`FitGrid`], the model averaged over a table's bins), `target` (what the
//! fit samples from a table), `fit` (the optimisation), `engine_checks` (values an engine must
//! reproduce).

// Index loops mirror the formulas (lobes, nodes, bins); iterator chains would hide them.
#![allow(clippy::needless_range_loop)]

mod binning;
mod engine_checks;
mod fit;
mod frame;
mod lobes;
mod model;
mod target;

pub use binning::{binned, FitGrid};
pub use engine_checks::{test_evaluations, TestEvaluation};
pub use fit::{evaluate, fit, FitReport, BETA_MIN};
pub use frame::{local_direction, local_wi, table_to_local};
pub use lobes::{logistic_scale, longitudinal_variances, P_MAX};
pub use model::{width_nodes, Chiang, ChiangParams};
pub use target::{ChiangFitOptions, FitError, FitTarget};

/// √x, 0 for x < 0 (rounding below zero).
fn safe_sqrt(x: f64) -> f64 {
    x.max(0.0).sqrt()
}

/// asin of x clamped to \[−1, 1\].
fn safe_asin(x: f64) -> f64 {
    x.clamp(-1.0, 1.0).asin()
}
