//! Scaling factors s(A) = ℓ/d (cb15) and the conventions of each renderer: which mean free
//! path or radius it takes for Burley's d.

use std::f64::consts::PI;

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

#[cfg(test)]
mod tests {
    use super::*;

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

    /// Issue 22: s(A) at several albedos against Christensen & Burley 2015's formulas
    /// evaluated by hand (perpendicular: 1.85 − A + 7|A − 0.8|³; diffuse surface transmission,
    /// their Eq. 6: 1.9 − A + 3.5(A − 0.8)²; diffuse mean free path: 3.5 + 100(A − 0.33)⁴),
    /// away from A = 0.8 and 0.33 where their A-dependent terms vanish.
    #[test]
    fn scaling_factors_at_several_albedos() {
        // (A, s_perpendicular, s_diffuse_transmission, s_dmfp)
        let table = [
            (0.0, 5.434, 4.14, 4.685_921),
            (0.2, 3.162, 2.96, 3.528_561),
            (0.5, 1.539, 1.715, 3.583_521),
            (0.9, 0.957, 1.035, 14.056_001),
            (1.0, 0.906, 1.04, 23.651_121),
        ];
        for (a, sp, sd, sm) in table {
            assert!(
                (s_perpendicular(a) - sp).abs() < 1e-12,
                "s_perp({a}) = {}",
                s_perpendicular(a)
            );
            assert!(
                (s_diffuse_transmission(a) - sd).abs() < 1e-12,
                "s_diffuse({a}) = {}",
                s_diffuse_transmission(a)
            );
            assert!(
                (s_dmfp(a) - sm).abs() < 1e-12,
                "s_dmfp({a}) = {}",
                s_dmfp(a)
            );
        }
    }
}
