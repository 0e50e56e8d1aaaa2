//! `unity`: Unity HDRP diffusion profiles, as JSON.

use serde_json::{json, Value};

use super::format::split_max;
use super::{Provenance, SkinFit, Target};
use crate::export::burley;

/// JSON with one HDRP diffusion profile per entry.
///
/// HDRP's profile is R = S·(e^(−rS) + e^(−rS/3))/(8πr) with S = 1/(scatteringDistance ×
/// scatteringDistanceMultiplier) in millimetres (`DiffusionProfileSettings.cs`, `UpdateKernel`:
/// "shapeParam … S = 1 / D", "filterRadius … In millimeters"), so the product is d;
/// `scatteringDistance` is an LDR colour, so it is d/max d and the multiplier max d. The
/// albedo is the material's diffuse colour (A), not a profile field.
pub fn write_unity(fits: &[SkinFit], prov: &Provenance) -> String {
    let entries: Vec<Value> = fits
        .iter()
        .map(|f| {
            let (color, mult) = split_max(f.d_mm_rgb().map(burley::unity_scattering_distance_mm));
            let rgba = |v: [f64; 3]| json!({"r": v[0], "g": v[1], "b": v[2], "a": 1.0});
            json!({
                "name": f.name,
                "DiffusionProfile": {
                    "scatteringDistance": rgba(color),
                    "scatteringDistanceMultiplier": mult,
                    "transmissionTint": rgba([1.0; 3]),
                    "texturingMode": "PreAndPostScatter",
                    "transmissionMode": "ThinObject",
                    "thicknessRemap": [0.0, 5.0],
                    "worldScale": 1.0,
                    "ior": f.eta,
                },
                "materialDiffuseColor": f.a_rgb(),
                "derived": {
                    "burley_d_mm_rgb": f.d_mm_rgb(),
                    "filter_radius_mm": burley::sample_burley_radius(0.997, mult),
                    "burley_error_rgb": f.burley_error_rgb(),
                },
            })
        })
        .collect();
    let doc = json!({
        "format": "baker-unity-hdrp-diffusion-profiles",
        "version": 1,
        "generated_by": prov.line(Target::Unity),
        "engine": "Unity HDRP (Diffusion Profile asset)",
        "units": {
            "scatteringDistance": "1 (LDR colour, times scatteringDistanceMultiplier)",
            "scatteringDistanceMultiplier": "mm",
            "worldScale": "metres per world unit",
            "thicknessRemap": "mm (HDRP default; the table holds no thickness)",
            "materialDiffuseColor": "linear sRGB, the Lit material's base colour",
            "filter_radius_mm": "radius holding 99.7 % of the widest channel's energy, as HDRP computes it",
        },
        "convention": "scatteringDistance * scatteringDistanceMultiplier = Burley's d in mm: \
            HDRP evaluates R(r) = S (exp(-S r) + exp(-S r/3)) / (8 pi r), S = 1/D \
            (com.unity.render-pipelines.high-definition/Runtime/Material/DiffusionProfile/\
            DiffusionProfileSettings.cs, UpdateKernel, DisneyProfile). transmissionTint, \
            texturingMode, transmissionMode and thicknessRemap are HDRP's defaults: the table \
            describes reflectance only.",
        "profiles": entries,
    });
    serde_json::to_string_pretty(&doc).expect("JSON of numbers and strings") + "\n"
}
