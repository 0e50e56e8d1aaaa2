//! `unreal`: Unreal Engine 5 `SubsurfaceProfile` fields, as JSON.

use serde_json::{json, Value};

use super::format::split_max;
use super::{Provenance, SkinFit, Target};
use crate::export::burley;

/// Unreal Engine 5 clamps `MeanFreePathDistance` below at 0.1 cm and shifts the rest into the
/// colour (`SubsurfaceProfile.cpp`, `UpgradeDiffuseMeanFreePathToMeanFreePath`, "Support
/// mfp < 0.1f").
const UNREAL_MIN_MFP_DISTANCE_CM: f64 = 0.1;
/// Unreal clamps `SurfaceAlbedo` and `MeanFreePathColor` below at this bias
/// (`FSubsurfaceProfileTexture::CreateTexture`, `Bias`).
const UNREAL_COLOR_BIAS: f64 = 0.009;

/// JSON with one `SubsurfaceProfile` per entry (Burley, mean-free-path mode).
///
/// MFP_c (cm) = 0.06·s_perpendicular(A_c)·d_c ([`burley::unreal_mfp_cm`]: Unreal converts the
/// MFP to a DMFP with `GetDiffuseMeanFreePathFromMeanFreePath`·10/`Dmfp2MfpMagicNumber` and
/// renders e^(−r·s_dmfp(A)/DMFP)); `MeanFreePathDistance` = max_c MFP_c,
/// `MeanFreePathColor` = MFP/`MeanFreePathDistance`; `SurfaceAlbedo` = A;
/// `WorldUnitScale` = 0.1, Unreal's default, at which 1 world unit = 1 cm of skin
/// (`BurleyNormalizedSSS.cpp`, `ComputeTransmissionProfileBurley`: DistanceCm·(WorldUnitScale/0.1)·10 = mm).
pub fn write_unreal(fits: &[SkinFit], prov: &Provenance) -> String {
    let entries: Vec<Value> = fits
        .iter()
        .map(|f| {
            let a = f.a_rgb();
            let mfp_cm: [f64; 3] =
                std::array::from_fn(|c| burley::unreal_mfp_cm(a[c], f.burley[c].d_mm));
            let (mut color, mut dist) = split_max(mfp_cm);
            if dist < UNREAL_MIN_MFP_DISTANCE_CM {
                color = color.map(|x| x * dist / UNREAL_MIN_MFP_DISTANCE_CM);
                dist = UNREAL_MIN_MFP_DISTANCE_CM;
            }
            let mut notes = Vec::new();
            if color.iter().chain(a.iter()).any(|&x| x < UNREAL_COLOR_BIAS) {
                notes.push(format!(
                    "a SurfaceAlbedo or MeanFreePathColor channel is below {UNREAL_COLOR_BIAS}; \
                     Unreal clamps it to that (SubsurfaceProfile.cpp, Bias)"
                ));
            }
            let lin = |v: [f64; 3]| json!({"R": v[0], "G": v[1], "B": v[2], "A": 1.0});
            json!({
                "name": f.name,
                "SubsurfaceProfile": {
                    "bEnableBurley": true,
                    "bEnableMeanFreePath": true,
                    "SurfaceAlbedo": lin(a),
                    "MeanFreePathColor": lin(color),
                    "MeanFreePathDistance": dist,
                    "WorldUnitScale": 0.1,
                    "IOR": f.eta,
                },
                "derived": {
                    "mean_free_path_cm_rgb": mfp_cm,
                    "diffuse_mean_free_path_mm_rgb": f.burley.map(|b| burley::dmfp_mm(b.a, b.d_mm)),
                    "burley_d_mm_rgb": f.d_mm_rgb(),
                    "burley_error_rgb": f.burley_error_rgb(),
                },
                "notes": notes,
            })
        })
        .collect();
    let doc = json!({
        "format": "baker-unreal-subsurface-profiles",
        "version": 1,
        "generated_by": prov.line(Target::Unreal),
        "engine": "Unreal Engine 5 (Subsurface Profile asset, Burley, 'Enable Mean Free Path')",
        "units": {
            "MeanFreePathDistance": "cm (world units at WorldUnitScale 0.1)",
            "MeanFreePathColor": "1 (multiplies MeanFreePathDistance per channel)",
            "SurfaceAlbedo": "linear sRGB",
            "diffuse_mean_free_path_mm_rgb": "mm, what Unreal computes internally",
        },
        "convention": "Unreal's MeanFreePath is the volume mean free path ell of Christensen & \
            Burley 2015 (perpendicular fit s = 1.85 - A + 7|A-0.8|^3) scaled by \
            Dmfp2MfpMagicNumber = 0.6: Unreal renders d = DMFP / (3.5 + 100 (A-0.33)^4) with \
            DMFP_mm = MFP_cm * 10 * (3.5 + 100 (A-0.33)^4) / (1.85 - A + 7|A-0.8|^3) / 0.6 \
            (Engine/Source/Runtime/Engine/Private/SubsurfaceProfile.cpp, CreateTexture; \
            Engine/Source/Runtime/Engine/Private/Rendering/BurleyNormalizedSSS.cpp, \
            Burley_ScatteringProfile), hence MFP_cm = 0.06 d_mm (1.85 - A + 7|A-0.8|^3). \
            MeanFreePathDistance below 0.1 cm is raised to 0.1 and the colour scaled down, as \
            UpgradeDiffuseMeanFreePathToMeanFreePath does.",
        "profiles": entries,
    });
    serde_json::to_string_pretty(&doc).expect("JSON of numbers and strings") + "\n"
}
