//! Closed-form far-field scattering of a smooth dielectric cylinder, the independent
//! reference of the fiber tests (also `validation/check_fiber_cylinder.py`, in numpy; nothing
//! of the tracer is reused).
//!
//! S. R. Marschner, H. W. Jensen, M. Cammarano, S. Worley, P. Hanrahan, "Light scattering
//! from human hair fibers", ACM TOG 22(3), 2003: Bravais index η′ = √(η² − sin²θi)/cos θi,
//! exit azimuth φp(h) = 2p·γt − 2γi + pπ with γi = asin h, γt = asin(h/η′).
//! E. d'Eon, G. Francois, M. Hill, J. Letteri, J.-M. Aubry, "An energy-conserving hair
//! reflectance model", EGSR 2011: attenuation A0 = F, Ap = (1 − F)²F^(p−1)T^p with the
//! unpolarised Fresnel F at the true 3D angle, cos = cos θi cos γi, and the 3D chord
//! transmittance T = exp(−μa·2R·cos γt / cos θt), sin θt = sin θi/η.
//!
//! Conventions of the tracer: ωi points towards the light; Δφ = φo − φi in [−π, π), bins of
//! equal width from −π; a smooth cylinder sends everything to θo = −θi.

use std::f64::consts::PI;

/// Unpolarised Fresnel reflectance from air into index `eta` at incidence cosine `cos_i`.
pub fn fresnel(cos_i: f64, eta: f64) -> f64 {
    let c = cos_i.clamp(0.0, 1.0);
    let ct = (1.0 - (1.0 - c * c) / (eta * eta)).sqrt();
    let rs = (c - eta * ct) / (c + eta * ct);
    let rp = (eta * c - ct) / (eta * c + ct);
    0.5 * (rs * rs + rp * rp)
}

/// Adds `w` spread uniformly over [φ − box/2, φ + box/2] (wrapped) to `hist` (bins of
/// 2π/len from −π); `box_rad` = 0 deposits at φ.
fn deposit(hist: &mut [f64], phi: f64, w: f64, box_rad: f64) {
    let n = hist.len() as i64;
    let bw = 2.0 * PI / n as f64;
    if box_rad <= 0.0 {
        let b = ((phi + PI) / bw).floor() as i64;
        hist[b.rem_euclid(n) as usize] += w;
        return;
    }
    let (mut x, end) = (
        (phi - 0.5 * box_rad + PI) / bw,
        (phi + 0.5 * box_rad + PI) / bw,
    );
    let width = end - x;
    while x < end {
        let b = x.floor();
        let next = (b + 1.0).min(end);
        hist[(b as i64).rem_euclid(n) as usize] += w * (next - x) / width;
        x = next;
    }
}

/// Fraction of the intercepted power per Δφ bin (`n_phi` bins) for a beam at θi (rad) with
/// offsets uniform across the fiber (`nq` midpoints), each exit spread over a box of
/// `box_rad` in Δφ. Internal paths are followed until < 10⁻¹⁶ of the photon remains inside.
pub fn dphi_fractions(
    theta_i: f64,
    eta: f64,
    mua_per_um: f64,
    diameter_um: f64,
    n_phi: usize,
    box_rad: f64,
    nq: usize,
) -> Vec<f64> {
    let mut hist = vec![0.0; n_phi];
    let (st, ct) = theta_i.sin_cos();
    let eta_p = (eta * eta - st * st).sqrt() / ct;
    let cos_tt = (1.0 - (st / eta) * (st / eta)).sqrt();
    let wq = 1.0 / nq as f64;
    for k in 0..nq {
        let h = -1.0 + (k as f64 + 0.5) * 2.0 * wq;
        let gi = h.asin();
        let gt = (h / eta_p).asin();
        let f = fresnel(ct * gi.cos(), eta);
        let t = (-mua_per_um * diameter_um * gt.cos() / cos_tt).exp();
        deposit(&mut hist, -2.0 * gi, f * wq, box_rad);
        let mut inside = 1.0 - f;
        let mut p = 1.0;
        while inside > 1e-16 {
            inside *= t;
            deposit(
                &mut hist,
                2.0 * p * gt - 2.0 * gi + p * PI,
                inside * (1.0 - f) * wq,
                box_rad,
            );
            inside *= f;
            p += 1.0;
        }
    }
    hist
}

/// [`dphi_fractions`] for a beam averaged over an incoming bin, as the BCSDF bake traces it:
/// θ uniform in sin θ over [θc − Δθ/2, θc + Δθ/2] weighted by the intercepted power, which
/// for a cylinder is ∝ cos θ, and φi uniform over the bin (Δφ measured from the centre: a box
/// of the bin's width).
pub fn bin_averaged_dphi_fractions(
    theta_c: f64,
    bin_rad: f64,
    eta: f64,
    mua_per_um: f64,
    diameter_um: f64,
    n_phi: usize,
    nq: usize,
) -> Vec<f64> {
    let nt = 16;
    let (s0, s1) = (
        (theta_c - 0.5 * bin_rad).sin(),
        (theta_c + 0.5 * bin_rad).sin(),
    );
    let mut out = vec![0.0; n_phi];
    let mut wsum = 0.0;
    for k in 0..nt {
        let s = s0 + (s1 - s0) * (k as f64 + 0.5) / nt as f64;
        let w = (1.0 - s * s).sqrt();
        let h = dphi_fractions(s.asin(), eta, mua_per_um, diameter_um, n_phi, bin_rad, nq);
        for (o, x) in out.iter_mut().zip(h) {
            *o += w * x;
        }
        wsum += w;
    }
    out.iter_mut().for_each(|x| *x /= wsum);
    out
}
