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
//! `skin/`):
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

//!
//! # Files
//! `profile` (R, F and sampling), `fit` (the fit), `conventions` (s(A) and each renderer's
//! parameters), `medium` (the single-scattering albedo of the Mitsuba medium).

mod conventions;
mod fit;
mod medium;
mod profile;

pub use conventions::{
    cycles_burley_radius, diffuse_transmission_mfp_mm, dmfp_mm, s_diffuse_transmission, s_dmfp,
    s_perpendicular, unity_scattering_distance_mm, unreal_d_mm, unreal_mfp_cm, volume_mfp_mm,
    UNREAL_CM_TO_MM, UNREAL_DMFP2MFP,
};
pub use fit::{bins_inside, fit_channel, fit_error, fit_rgb, BurleyError, BurleyFit};
pub use medium::{chandrasekhar_h1, normal_incidence_albedo, single_scattering_albedo};
pub use profile::{burley_cdf, burley_energy, burley_radius_pdf, burley_rd, sample_burley_radius};
