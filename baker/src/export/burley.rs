//! Christensen–Burley normalized diffusion[^cb15], fitted per channel to a baked profile, and
//! the conversions from its (A, d) to the parameters renderers take.
//!
//! The profile of a channel with surface albedo A and shape parameter d (mm) is
//!
//! ```text
//! R(r) = A·(e^(−r/d) + e^(−r/(3d))) / (8π·d·r)                      mm⁻²   [cb15, Eq. 3]
//! F(r) = ∫₀ʳ R/A·2πr′ dr′ = 1 − ¼·e^(−r/d) − ¾·e^(−r/(3d))                 [cb15, Eq. 11]
//! ```
//!
//! R integrates to A over the plane, so A is the channel's total diffuse reflectance. Our
//! tables hold annulus averages (`formats/FORMAT.md`, "Skin profiles"), so the model is
//! compared through its exact annulus energy A·(F(b) − F(a)), never sampled at bin centres.
//!
//! # The fit
//!
//! Per channel, A and d minimise the same energy-weighted relative L1 error as the
//! sum-of-Gaussians fit of the bake (FORMAT.md, "The sum-of-Gaussians fit"):
//!
//! ```text
//! error = Σ_k |A·E_k(d) − T_k| / Σ_k T_k,   E_k(d) = F(b_k) − F(a_k),   T_k = table_k·π(b_k² − a_k²),
//! ```
//!
//! over the bins with `r_edges_mm[k] < r99_mm` (bin 0 always). For a given d the optimal A is
//! exact: Σ_k E_k·|A − T_k/E_k| is minimised by the weighted median of T_k/E_k with weights
//! E_k. The error is then minimised over ln d: a scan over a log grid spanning the radial grid
//! brackets the minimum, and golden-section search refines it.
//!
//! # Mean free paths
//!
//! The paper fits d = ℓ/s(A) against brute-force Monte Carlo (isotropic scattering, mean free
//! path ℓ) for three configurations; each renderer picked one (see the export functions and
//! `skin.rs`):
//!
//! | fit | s(A) | ℓ is | used by |
//! |---|---|---|---|
//! | perpendicular (searchlight) illumination | 1.85 − A + 7·\|A − 0.8\|³ | volume mean free path 1/σt | Unreal (MFP ↔ DMFP), pbrt-v4, OpenPBR, Mitsuba (this export) |
//! | diffuse surface transmission, Eq. 6 | 1.9 − A + 3.5·(A − 0.8)² | volume mean free path 1/σt | Cycles ≤ 2.9x, Chiang et al. 2016 random walk |
//! | diffuse mean free path | 3.5 + 100·(A − 0.33)⁴ | dmfp, a surface distance | Unreal's Burley kernel |
//!
//! Blender Cycles 3.0 – 4.x (method "Christensen-Burley") and Unity HDRP take d itself, Cycles
//! as 4π·d ([`cycles_burley_radius`], [`unity_scattering_distance_mm`]). Mitsuba 3 has no
//! BSSRDF: its export is the medium itself, whose single-scattering albedo comes from
//! Chandrasekhar's H-function ([`single_scattering_albedo`]).
//!
//! [^cb15]: P. H. Christensen, B. Burley, "Approximate Reflectance Profiles for Efficient
//!     Subsurface Scattering", Pixar Technical Memo #15-04, 2015.
//!     <https://graphics.pixar.com/library/ApproxBSSRDF/>. Equation numbers: Eq. 3 (profile)
//!     and Eq. 6 (diffuse surface transmission) as cited in Blender Cycles
//!     `intern/cycles/kernel/closure/bssrdf.h`; Eq. 11 (CDF) as cited on the first author's
//!     page <https://www.seanet.com/~myandper/abstract/memo1504.htm>.

use std::f64::consts::PI;

/// Why a channel cannot be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BurleyError {
    /// The radial grid is not 0 = e₀ < e₁ < … or does not match the table.
    #[error("radial grid: {0}")]
    Grid(String),
    /// No positive energy inside the fitted radius: nothing to fit.
    #[error("no positive energy in the {bins} bins inside r99 = {r99_mm} mm")]
    NoEnergy { bins: usize, r99_mm: f64 },
}

/// The fit of one channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BurleyFit {
    /// Surface albedo A (the profile's integral over the plane).
    pub a: f64,
    /// Shape parameter d, mm.
    pub d_mm: f64,
    /// Energy-weighted relative L1 error (FORMAT.md's fit error), over the bins inside r99.
    pub error: f64,
}

/// R(r)/A, the normalized profile at `r_mm`, mm⁻² (cb15, Eq. 3; integrates to 1).
pub fn burley_rd(r_mm: f64, d_mm: f64) -> f64 {
    let x = r_mm / d_mm;
    ((-x).exp() + (-x / 3.0).exp()) / (8.0 * PI * d_mm * r_mm)
}

/// F(r): the fraction of the profile's energy inside radius `r_mm` (cb15, Eq. 11).
pub fn burley_cdf(r_mm: f64, d_mm: f64) -> f64 {
    let x = r_mm / d_mm;
    1.0 - 0.25 * (-x).exp() - 0.75 * (-x / 3.0).exp()
}

/// dF/dr, the density of the exit radius, mm⁻¹ (Eq. 3 times 2πr, as Cycles'
/// `bssrdf_burley_eval`).
pub fn burley_radius_pdf(r_mm: f64, d_mm: f64) -> f64 {
    let x = r_mm / d_mm;
    ((-x).exp() + (-x / 3.0).exp()) / (4.0 * d_mm)
}

/// Samples an exit radius from [`burley_radius_pdf`]: the closed-form inverse of F (E. Golubev,
/// "Sampling Burley's Normalized Diffusion Profiles", 2019,
/// <https://zero-radiance.github.io/post/sampling-diffusion/>; also Unity HDRP
/// `DiffusionProfileSettings.cs`, `SampleBurleyDiffusionProfile`). `u` in \[0, 1).
pub fn sample_burley_radius(u: f64, d_mm: f64) -> f64 {
    let v = 1.0 - u; // the complementary CDF, in (0, 1]
    let g = 1.0 + 4.0 * v * (2.0 * v + (1.0 + 4.0 * v * v).sqrt());
    let n = g.powf(-1.0 / 3.0);
    let c = 1.0 + g * n * n + n; // 1 + g^(1/3) + g^(−1/3)
    3.0 * (c / (4.0 * v)).ln() * d_mm
}

/// Energy of the normalized profile in the annulus \[a, b\]: F(b) − F(a), written as a sum of
/// positive differences so thin annuli far out keep their digits.
#[inline]
pub fn burley_energy(d_mm: f64, a_mm: f64, b_mm: f64) -> f64 {
    let d3 = 3.0 * d_mm;
    0.25 * ((-a_mm / d_mm).exp() - (-b_mm / d_mm).exp())
        + 0.75 * ((-a_mm / d3).exp() - (-b_mm / d3).exp())
}

/// The bins that count for a channel with 99 % radius `r99_mm`: k with `edges[k] < r99`, and
/// bin 0 always (FORMAT.md; the same rule as `fit::gaussians::fit_error`). NaN or ∞ = all.
pub fn bins_inside(edges_mm: &[f64], r99_mm: f64) -> usize {
    let nr = edges_mm.len().saturating_sub(1);
    if r99_mm.is_nan() {
        return nr;
    }
    let n = edges_mm[..nr].iter().take_while(|&&a| a < r99_mm).count();
    n.max(nr.min(1))
}

/// FORMAT.md's energy-weighted relative L1 error of the profile (A, d) against one channel of
/// a table (`table_per_mm2`, annulus averages), over the bins inside `r99_mm`.
pub fn fit_error(edges_mm: &[f64], table_per_mm2: &[f64], r99_mm: f64, a: f64, d_mm: f64) -> f64 {
    let n = bins_inside(edges_mm, r99_mm).min(table_per_mm2.len());
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..n {
        let (lo, hi) = (edges_mm[k], edges_mm[k + 1]);
        let t = table_per_mm2[k] * PI * (hi * hi - lo * lo);
        num += (a * burley_energy(d_mm, lo, hi) - t).abs();
        den += t;
    }
    num / den
}

/// The channel data a fit works on: annulus energies T_k of the counted bins.
struct Channel<'a> {
    edges_mm: &'a [f64],
    energy: Vec<f64>,
    total: f64,
}

impl Channel<'_> {
    /// For shape `d_mm`: the L1-optimal A (weighted median of T_k/E_k, weights E_k) and the
    /// error it leaves. `scratch` avoids an allocation per evaluation.
    fn best_a(&self, d_mm: f64, scratch: &mut Vec<(f64, f64)>) -> (f64, f64) {
        scratch.clear();
        let mut weight = 0.0;
        for (k, &t) in self.energy.iter().enumerate() {
            let e = burley_energy(d_mm, self.edges_mm[k], self.edges_mm[k + 1]);
            if e > 0.0 {
                scratch.push((t / e, e));
                weight += e;
            }
        }
        let a = if weight > 0.0 {
            scratch.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut cum = 0.0;
            let mut med = scratch.last().map_or(0.0, |p| p.0);
            for &(ratio, e) in scratch.iter() {
                cum += e;
                if cum >= 0.5 * weight {
                    med = ratio;
                    break;
                }
            }
            // A negative albedo is never optimal for a physical profile; keep A ≥ 0.
            med.max(0.0)
        } else {
            0.0
        };
        let mut num = 0.0;
        for (k, &t) in self.energy.iter().enumerate() {
            let e = burley_energy(d_mm, self.edges_mm[k], self.edges_mm[k + 1]);
            num += (a * e - t).abs();
        }
        (a, num / self.total)
    }
}

/// Log-spaced shapes scanned before the golden-section refinement.
const SCAN_POINTS: usize = 241;
/// Golden-section stopping width in ln d (relative precision of d).
const LN_D_TOLERANCE: f64 = 1e-10;

/// Fits A and d to one channel: `table_per_mm2[k]` is the annulus average of bin
/// \[`edges_mm[k]`, `edges_mm[k+1]`), `r99_mm` the channel's 99 % radius (NaN: use every bin).
pub fn fit_channel(
    edges_mm: &[f64],
    table_per_mm2: &[f64],
    r99_mm: f64,
) -> Result<BurleyFit, BurleyError> {
    if edges_mm.len() != table_per_mm2.len() + 1 || table_per_mm2.is_empty() {
        return Err(BurleyError::Grid(format!(
            "{} edges for {} bins",
            edges_mm.len(),
            table_per_mm2.len()
        )));
    }
    if edges_mm[0] != 0.0
        || !edges_mm.iter().all(|e| e.is_finite())
        || edges_mm.windows(2).any(|w| w[0] >= w[1])
    {
        return Err(BurleyError::Grid(
            "edges must start at 0 and increase strictly".into(),
        ));
    }
    let n = bins_inside(edges_mm, r99_mm);
    let energy: Vec<f64> = (0..n)
        .map(|k| {
            let (a, b) = (edges_mm[k], edges_mm[k + 1]);
            table_per_mm2[k] * PI * (b * b - a * a)
        })
        .collect();
    let total: f64 = energy.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err(BurleyError::NoEnergy { bins: n, r99_mm });
    }
    let ch = Channel {
        edges_mm,
        energy,
        total,
    };
    let mut scratch = Vec::with_capacity(n);
    let mut eval = |ln_d: f64| ch.best_a(ln_d.exp(), &mut scratch).1;

    // d ≈ r99/13 for a pure Burley profile (F(13d) ≈ 0.99); scan far beyond both ends of the
    // counted grid so neither a one-bin spike nor a flat tail sits on the boundary.
    let lo = (edges_mm[1] * 1e-2).ln();
    let hi = (edges_mm[n] * 10.0).ln();
    let step = (hi - lo) / (SCAN_POINTS - 1) as f64;
    let (mut best_i, mut best_f) = (0, f64::INFINITY);
    for i in 0..SCAN_POINTS {
        let f = eval(lo + step * i as f64);
        if f < best_f {
            (best_i, best_f) = (i, f);
        }
    }
    // Golden section on the bracket around the best scan point.
    let mut a = lo + step * best_i.saturating_sub(1) as f64;
    let mut b = lo + step * (best_i + 1).min(SCAN_POINTS - 1) as f64;
    let inv_phi = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - inv_phi * (b - a);
    let mut x2 = a + inv_phi * (b - a);
    let (mut f1, mut f2) = (eval(x1), eval(x2));
    while b - a > LN_D_TOLERANCE {
        if f1 <= f2 {
            (b, x2, f2) = (x2, x1, f1);
            x1 = b - inv_phi * (b - a);
            f1 = eval(x1);
        } else {
            (a, x1, f1) = (x1, x2, f2);
            x2 = a + inv_phi * (b - a);
            f2 = eval(x2);
        }
    }
    let mut ln_d = 0.5 * (a + b);
    // The scan point itself may beat the refined one (kinks of an L1 objective).
    if eval(ln_d) > best_f {
        ln_d = lo + step * best_i as f64;
    }
    let d_mm = ln_d.exp();
    let (a, error) = ch.best_a(d_mm, &mut scratch);
    Ok(BurleyFit { a, d_mm, error })
}

/// Fits each channel of an RGB table (`table_rgb_per_mm2[k][c]`) with its own 99 % radius.
pub fn fit_rgb(
    edges_mm: &[f64],
    table_rgb_per_mm2: &[[f64; 3]],
    r99_mm: [f64; 3],
) -> Result<[BurleyFit; 3], BurleyError> {
    let ch = |c: usize| -> Result<BurleyFit, BurleyError> {
        let t: Vec<f64> = table_rgb_per_mm2.iter().map(|v| v[c]).collect();
        fit_channel(edges_mm, &t, r99_mm[c])
    };
    Ok([ch(0)?, ch(1)?, ch(2)?])
}

// ---------------------------------------------------------------------------------------------
// Scaling factors s(A) = ℓ/d (cb15) and the conventions of each renderer.

/// s(A) for perpendicular (searchlight) illumination, ℓ the volume mean free path 1/σt (cb15,
/// "perpendicular illumination"; Unreal `BurleyNormalizedSSS.cpp`,
/// `GetPerpendicularScalingFactor`, "Method 1", average error 5.5 %).
pub fn s_perpendicular(a: f64) -> f64 {
    1.85 - a + 7.0 * (a - 0.8).abs().powi(3)
}

/// s(A) for diffuse surface transmission, ℓ the volume mean free path (cb15, Eq. 6; Cycles
/// `bssrdf_burley_fitting`; Unreal `GetDiffuseSurfaceScalingFactor`, "Method 2", 3.9 %).
pub fn s_diffuse_transmission(a: f64) -> f64 {
    1.9 - a + 3.5 * (a - 0.8) * (a - 0.8)
}

/// s(A) for the diffuse mean free path ℓd, a distance measured on the surface (cb15,
/// "alternative measure of scattering distance"; Unreal `GetSearchLightDiffuseScalingFactor`,
/// "Method 3", 7.7 %).
pub fn s_dmfp(a: f64) -> f64 {
    3.5 + 100.0 * (a - 0.33).powi(4)
}

/// Volume mean free path ℓ = 1/σt (mm) of a medium whose searchlight profile is Burley (A, d):
/// ℓ = d·s_perpendicular(A). What pbrt-v4 (`"mfp"`), OpenPBR (`subsurface_radius ×
/// subsurface_radius_scale`, "the mean free path … μt = 1/r") and a Mitsuba medium
/// (σt = 1/ℓ) take.
pub fn volume_mfp_mm(a: f64, d_mm: f64) -> f64 {
    d_mm * s_perpendicular(a)
}

/// Diffuse mean free path ℓd = d·s_dmfp(A), mm.
pub fn dmfp_mm(a: f64, d_mm: f64) -> f64 {
    d_mm * s_dmfp(a)
}

/// Mean free path of Chiang et al.'s random walk (ℓ = d·s_diffuse_transmission(A); "Practical
/// and Controllable Subsurface Scattering for Production Path Tracing", SIGGRAPH 2016 talk, as
/// in Cycles 2.9x `subsurface_random_walk_remap`), mm.
pub fn diffuse_transmission_mfp_mm(a: f64, d_mm: f64) -> f64 {
    d_mm * s_diffuse_transmission(a)
}

/// Unreal Engine 5 `MeanFreePathDistance`·`MeanFreePathColor` (cm) giving Burley shape d.
///
/// `SubsurfaceProfile.cpp` (`FSubsurfaceProfileTexture::CreateTexture`) turns the mean free
/// path into the diffuse mean free path it renders with,
/// DMFP_mm = MFP_cm·10·s_dmfp(A)/s_perpendicular(A) / 0.6 (`Dmfp2MfpMagicNumber` = 0.6), and
/// `BurleyNormalizedSSS.cpp` (`Burley_ScatteringProfile`) evaluates e^(−r·S/L) with
/// L = DMFP_mm, S = s_dmfp(A), i.e. d = DMFP/s_dmfp. Together: MFP_cm = 0.06·s_perp(A)·d_mm.
pub fn unreal_mfp_cm(a: f64, d_mm: f64) -> f64 {
    d_mm * s_perpendicular(a) * UNREAL_DMFP2MFP / UNREAL_CM_TO_MM
}

/// Unreal's `Dmfp2MfpMagicNumber` (`SubsurfaceProfile.cpp`, "Match the magic number in
/// BurleyNormalizedSSSCommon.ush").
pub const UNREAL_DMFP2MFP: f64 = 0.6;
/// Unreal's `CmToMm`.
pub const UNREAL_CM_TO_MM: f64 = 10.0;

/// The inverse of [`unreal_mfp_cm`], step by step as Unreal computes it: the Burley shape d
/// (mm) Unreal renders for surface albedo `a` and mean free path `mfp_cm`.
pub fn unreal_d_mm(a: f64, mfp_cm: f64) -> f64 {
    let dmfp_mm = mfp_cm * s_dmfp(a) / s_perpendicular(a) * UNREAL_CM_TO_MM / UNREAL_DMFP2MFP;
    dmfp_mm / s_dmfp(a)
}

/// Blender Cycles (3.0 – 4.x) `Subsurface Radius × Subsurface Scale` with Subsurface Method
/// "Christensen-Burley" that renders Burley shape d: Cycles scales the radius by 1/(4π)
/// (`bssrdf_setup_radius`, "Scale mean free path length so it gives similar looking result to
/// older Cubic, Gaussian and Burley models") and evaluates `bssrdf_burley_eval(d = radius)`,
/// so radius = 4π·d. (The albedo-dependent `bssrdf_burley_setup` of Cycles ≤ 2.9x is no longer
/// called.)
pub fn cycles_burley_radius(d: f64) -> f64 {
    4.0 * PI * d
}

/// Unity HDRP `scatteringDistance × scatteringDistanceMultiplier` (mm): HDRP's shape parameter
/// is S = 1/scatteringDistance in R = S·(e^(−rS) + e^(−rS/3))/(8πr)
/// (`DiffusionProfileSettings.cs`, `UpdateKernel`, `DisneyProfile`), i.e. exactly d.
pub fn unity_scattering_distance_mm(d_mm: f64) -> f64 {
    d_mm
}

/// Chandrasekhar's H-function of isotropic scattering at μ = 1 for single-scattering albedo
/// α < 1, from its explicit integral form (S. Chandrasekhar, "Radiative Transfer", 1950/1960;
/// the H-function of isotropic scattering):
/// ln H(μ) = −(μ/π)·∫₀^(π/2) ln(1 − α·θ·cot θ) / (cos²θ + μ²·sin²θ) dθ, at μ = 1 (64-point
/// Gauss–Legendre; the integrand is smooth for α < 1).
pub fn chandrasekhar_h1(alpha: f64) -> f64 {
    let (x, w) = gauss_legendre_64();
    let half = 0.25 * PI; // [0, π/2] = half·(x + 1)
    let integral: f64 = x
        .iter()
        .zip(w.iter())
        .map(|(&xi, &wi)| {
            let t = half * (xi + 1.0);
            wi * half * (1.0 - alpha * t / t.tan()).ln()
        })
        .sum();
    (-integral / PI).exp()
}

/// Albedo for normal incidence of an index-matched half-space of isotropic scatterers with
/// single-scattering albedo α: R = 1 − H(1)·√(1 − α) (Chandrasekhar, "Radiative Transfer":
/// the plane albedo of a semi-infinite atmosphere, 1 − H(μ₀)·√(1 − ϖ₀), at μ₀ = 1). This is the
/// quantity our tables hold (a pencil beam at normal incidence), where van de Hulst's relation
/// quoted by OpenPBR is the albedo under uniform illumination (larger: 0.356 against 0.299 at
/// α = 0.814).
pub fn normal_incidence_albedo(alpha: f64) -> f64 {
    if alpha >= 1.0 {
        return 1.0;
    }
    1.0 - chandrasekhar_h1(alpha) * (1.0 - alpha).max(0.0).sqrt()
}

/// The single-scattering albedo α whose [`normal_incidence_albedo`] is `a` (bisection; `a` is
/// clamped to \[0, 1\]).
pub fn single_scattering_albedo(a: f64) -> f64 {
    let a = a.clamp(0.0, 1.0);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if normal_incidence_albedo(mid) < a {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Nodes and weights of 64-point Gauss–Legendre quadrature on \[−1, 1\] (Newton's method on
/// the Legendre recurrence), computed once.
fn gauss_legendre_64() -> &'static ([f64; 64], [f64; 64]) {
    static NODES: std::sync::OnceLock<([f64; 64], [f64; 64])> = std::sync::OnceLock::new();
    NODES.get_or_init(|| {
        const N: usize = 64;
        let (mut x, mut w) = ([0.0; N], [0.0; N]);
        for i in 0..N {
            let mut z = (PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, z);
                for k in 2..=N {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k);
                }
                dp = N as f64 * (z * p1 - p0) / (z * z - 1.0);
                let dz = p1 / dp;
                z -= dz;
                if dz.abs() < 1e-16 {
                    break;
                }
            }
            x[i] = z;
            w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        }
        (x, w)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::rgb::radius_of_energy;
    use crate::transport::RadialBins;

    /// Annulus averages of Burley (A, d) on `edges`, as the bake writes them.
    fn burley_table(edges: &[f64], a: f64, d: f64) -> Vec<f64> {
        edges
            .windows(2)
            .map(|e| a * burley_energy(d, e[0], e[1]) / (PI * (e[1] * e[1] - e[0] * e[0])))
            .collect()
    }

    /// The bake's radial grid: 10 µm bins, growing 5 % per bin from 0.2 mm, out to 40 mm
    /// (FORMAT.md; spec `profiles.radial`).
    fn bake_grid() -> Vec<f64> {
        RadialBins::fine_then_log(0.01, 1.05, 40.0)
            .edges_mm()
            .to_vec()
    }

    fn r99(edges: &[f64], table: &[f64], albedo: f64) -> f64 {
        radius_of_energy(edges, table.iter().copied(), 0.99 * albedo)
    }

    fn assert_recovers(edges: &[f64], a: f64, d: f64, r99_mm: f64, tol: f64) {
        let t = burley_table(edges, a, d);
        let fit = fit_channel(edges, &t, r99_mm).unwrap();
        assert!(
            (fit.a / a - 1.0).abs() < tol && (fit.d_mm / d - 1.0).abs() < tol,
            "A {a} d {d}: fitted A {} d {} (error {})",
            fit.a,
            fit.d_mm,
            fit.error
        );
        assert!(fit.error < 1e-6, "error {}", fit.error);
    }

    #[test]
    fn closed_forms_agree() {
        let d = 0.37;
        // F is the integral of the pdf, the pdf is 2πr·R, and F(∞) = 1.
        let (mut r, h) = (0.0, 1e-4);
        let mut f = 0.0;
        while r < 30.0 * d {
            f += 0.5 * h * (burley_radius_pdf(r, d) + burley_radius_pdf(r + h, d));
            r += h;
            let rm = r - 0.5 * h;
            let diff = burley_radius_pdf(rm, d) - 2.0 * PI * rm * burley_rd(rm, d);
            assert!(diff.abs() < 1e-9, "pdf vs profile at {rm}: {diff}");
        }
        assert!(
            (f - burley_cdf(r, d)).abs() < 1e-7,
            "{f} vs {}",
            burley_cdf(r, d)
        );
        assert!((burley_cdf(1e6, d) - 1.0).abs() < 1e-15);
        assert_eq!(burley_cdf(0.0, d), 0.0);
        let (a, b) = (1.3, 1.4);
        assert!((burley_energy(d, a, b) - (burley_cdf(b, d) - burley_cdf(a, d))).abs() < 1e-15);
    }

    #[test]
    fn sampling_inverts_the_cdf() {
        for &d in &[0.05, 1.0, 7.5] {
            for i in 0..1000 {
                let u = (i as f64 + 0.5) / 1000.0;
                let r = sample_burley_radius(u, d);
                assert!(
                    (burley_cdf(r, d) - u).abs() < 1e-12,
                    "d {d} u {u}: F(r) = {}",
                    burley_cdf(r, d)
                );
            }
        }
        assert_eq!(sample_burley_radius(0.0, 1.0), 0.0);
    }

    #[test]
    fn recovers_known_a_and_d_on_the_bake_grid() {
        let edges = bake_grid();
        assert!((edges[1] - 0.01).abs() < 1e-15 && edges.last().copied().unwrap() >= 40.0);
        // Skin-like channels (red: wide, blue: narrow) and extremes of A and d.
        for &(a, d) in &[
            (0.55, 0.9),
            (0.35, 0.25),
            (0.25, 0.06),
            (0.02, 0.015),
            (0.95, 2.5),
            (0.6, 0.012),
        ] {
            let t = burley_table(&edges, a, d);
            assert_recovers(&edges, a, d, r99(&edges, &t, a), 1e-3);
        }
    }

    #[test]
    fn recovers_known_a_and_d_per_channel() {
        let edges = bake_grid();
        let (a, d) = ([0.6, 0.35, 0.25], [1.1, 0.3, 0.12]);
        let table: Vec<[f64; 3]> = {
            let ch: Vec<Vec<f64>> = (0..3).map(|c| burley_table(&edges, a[c], d[c])).collect();
            (0..edges.len() - 1)
                .map(|k| [ch[0][k], ch[1][k], ch[2][k]])
                .collect()
        };
        let r99_mm = std::array::from_fn(|c| {
            radius_of_energy(&edges, table.iter().map(|v| v[c]), 0.99 * a[c])
        });
        let fit = fit_rgb(&edges, &table, r99_mm).unwrap();
        for c in 0..3 {
            assert!((fit[c].a / a[c] - 1.0).abs() < 1e-3, "{c}: {:?}", fit[c]);
            assert!((fit[c].d_mm / d[c] - 1.0).abs() < 1e-3, "{c}: {:?}", fit[c]);
        }
    }

    #[test]
    fn recovers_on_truncated_and_coarse_grids() {
        // The grid ends at 2 mm while d = 0.5 mm holds a third of the energy beyond it:
        // r99 is never reached (NaN), every bin counts, and the fit still finds (A, d).
        let short = RadialBins::fine_then_log(0.01, 1.05, 2.0)
            .edges_mm()
            .to_vec();
        let t = burley_table(&short, 0.5, 0.5);
        assert!(r99(&short, &t, 0.5).is_nan());
        assert_recovers(&short, 0.5, 0.5, f64::NAN, 1e-3);
        // A coarse uniform grid (MCML's 0.1 mm × 100): bins as wide as d.
        let coarse = RadialBins::uniform(0.1, 100).edges_mm().to_vec();
        let t = burley_table(&coarse, 0.4, 0.08);
        assert_recovers(&coarse, 0.4, 0.08, r99(&coarse, &t, 0.4), 1e-3);
    }

    #[test]
    fn recovers_within_one_percent_under_monte_carlo_like_noise() {
        // ±5 % uniform multiplicative noise per bin (a fixed SplitMix64 stream): the L1 fit
        // stays within 1 % of the truth.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut uniform = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let edges = bake_grid();
        for &(a, d) in &[(0.55, 0.9), (0.3, 0.2), (0.2, 0.07)] {
            let clean = burley_table(&edges, a, d);
            let noisy: Vec<f64> = clean
                .iter()
                .map(|v| v * (1.0 + 0.1 * (uniform() - 0.5)))
                .collect();
            let fit = fit_channel(&edges, &noisy, r99(&edges, &clean, a)).unwrap();
            assert!(
                (fit.a / a - 1.0).abs() < 0.01 && (fit.d_mm / d - 1.0).abs() < 0.01,
                "A {a} d {d}: {fit:?}"
            );
            assert!(fit.error < 0.05, "{fit:?}");
        }
    }

    #[test]
    fn error_is_the_documented_formula() {
        let edges = bake_grid();
        let t = burley_table(&edges, 0.5, 0.4);
        let r99_mm = r99(&edges, &t, 0.5);
        // Off by 10 % in A everywhere: the error is 10 % of the energy inside r99.
        let e = fit_error(&edges, &t, r99_mm, 0.55, 0.4);
        assert!((e - 0.1).abs() < 1e-12, "{e}");
        let fit = fit_channel(&edges, &t, r99_mm).unwrap();
        assert!((fit.error - fit_error(&edges, &t, r99_mm, fit.a, fit.d_mm)).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_input() {
        let edges = bake_grid();
        let zero = vec![0.0; edges.len() - 1];
        assert!(matches!(
            fit_channel(&edges, &zero, 1.0),
            Err(BurleyError::NoEnergy { .. })
        ));
        assert!(matches!(
            fit_channel(&[0.0, 2.0, 1.0], &[1.0, 1.0], 1.0),
            Err(BurleyError::Grid(_))
        ));
        assert!(matches!(
            fit_channel(&[0.0, 1.0], &[1.0, 1.0], 1.0),
            Err(BurleyError::Grid(_))
        ));
    }

    #[test]
    fn unreal_round_trip() {
        for &a in &[0.05, 0.33, 0.5, 0.8, 0.95] {
            for &d in &[0.01, 0.3, 2.0] {
                let back = unreal_d_mm(a, unreal_mfp_cm(a, d));
                assert!((back / d - 1.0).abs() < 1e-12, "A {a} d {d}: {back}");
            }
        }
        // Unreal's own default skin, upgraded from DMFP to MFP as `UpgradeDiffuseMeanFreePath
        // ToMeanFreePath` does (red channel: A 0.91058, DMFP 2.6748 cm): d = DMFP/s_dmfp.
        let (a, dmfp_cm) = (0.91058, 2.6748);
        let mfp_cm = dmfp_cm * s_perpendicular(a) / s_dmfp(a) * UNREAL_DMFP2MFP;
        let d = unreal_d_mm(a, mfp_cm);
        assert!((d - dmfp_cm * 10.0 / s_dmfp(a)).abs() < 1e-12);
    }

    #[test]
    fn h_function_matches_its_integral_equation() {
        // Independent route: iterate H(μ) = 1 / (1 − (α/2)·μ·∫₀¹ H(μ′)/(μ + μ′) dμ′) on a
        // 200-point midpoint grid, then evaluate at μ = 1.
        let n = 400;
        let mu: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) / n as f64).collect();
        for &alpha in &[0.3, 0.814, 0.95] {
            let mut h = vec![1.0; n];
            for _ in 0..500 {
                h = mu
                    .iter()
                    .map(|&m| {
                        let s: f64 = mu.iter().zip(&h).map(|(&m2, &h2)| h2 / (m + m2)).sum();
                        1.0 / (1.0 - 0.5 * alpha * m * s / n as f64)
                    })
                    .collect();
            }
            let s: f64 = mu.iter().zip(&h).map(|(&m2, &h2)| h2 / (1.0 + m2)).sum();
            let h1 = 1.0 / (1.0 - 0.5 * alpha * s / n as f64);
            let ours = chandrasekhar_h1(alpha);
            assert!((ours / h1 - 1.0).abs() < 1e-4, "α {alpha}: {ours} vs {h1}");
        }
        // Conservative limit H(1) = 2.9078 (Chandrasekhar's table for ϖ₀ = 1).
        assert!((chandrasekhar_h1(1.0 - 1e-12) - 2.9078).abs() < 2e-3);
    }

    #[test]
    fn normal_incidence_albedo_inverts() {
        for i in 1..100 {
            let a = i as f64 / 100.0;
            let alpha = single_scattering_albedo(a);
            assert!(
                (normal_incidence_albedo(alpha) - a).abs() < 1e-12,
                "A {a}: α {alpha}"
            );
        }
        assert_eq!(normal_incidence_albedo(0.0), 0.0);
        assert!(single_scattering_albedo(1.0) > 1.0 - 1e-12);
        // A Monte Carlo half-space (isotropic, index-matched, normal incidence) gives
        // 0.2986 ± 0.001 at α = 0.814 (validation/check_export_skin.py renders the same in
        // Mitsuba 3).
        assert!((normal_incidence_albedo(0.814) - 0.2990).abs() < 5e-4);
    }

    #[test]
    fn scaling_factors_match_the_papers_values() {
        // s(A) at A = 0.8, the centre of both polynomial fits.
        assert!((s_perpendicular(0.8) - 1.05).abs() < 1e-12);
        assert!((s_diffuse_transmission(0.8) - 1.1).abs() < 1e-12);
        assert!((s_dmfp(0.33) - 3.5).abs() < 1e-12);
        assert!((cycles_burley_radius(1.0) / (4.0 * PI) - 1.0).abs() < 1e-15);
        assert_eq!(volume_mfp_mm(0.8, 2.0), 2.1);
        assert!((dmfp_mm(0.33, 2.0) - 7.0).abs() < 1e-12);
        assert!((diffuse_transmission_mfp_mm(0.8, 1.0) - 1.1).abs() < 1e-12);
        assert_eq!(unity_scattering_distance_mm(0.7), 0.7);
    }
}
