//! `unity`: Unity HDRP Diffusion Profile assets, one `.asset` (+ `.meta`) per entry, and the
//! same fields as JSON (`profiles.json`, the folder's index).
//!
//! `baker export profiles.bkt --to unity -o DIR` writes the folder DIR (atomically: a staging
//! folder renamed into place; [`crate::export::layout`]): for each entry `<id>.asset` and
//! `<id>.asset.meta`, and `profiles.json` ([`write_unity`]), which lists the files. DIR may be
//! replaced only if it is empty or a previous `--to unity` export (its `profiles.json` and the
//! files it lists, plus the `.meta` files Unity adds); anything else in it stops the export.
//! Copy or export DIR into the project's `Assets/`; Unity imports the profiles as
//! `DiffusionProfileSettings`.
//!
//! Target: HDRP 14–17 (Unity 2022.2 – Unity 6), whose `DiffusionProfileSettings` holds one
//! profile and is at migration version 2 (`SplitScatteringDistance`: an LDR scattering colour
//! and a multiplier). Sources (Unity-Technologies/Graphics, `Packages/com.unity.render-pipelines.high-definition/`):
//! - `Runtime/Material/DiffusionProfile/DiffusionProfileSettings.cs` (@ 0777f7c6): the
//!   serialised `DiffusionProfile` fields in declaration order (`scatteringDistance`,
//!   `scatteringDistanceMultiplier`, `transmissionTint`, `texturingMode`,
//!   `smoothnessMultipliers`, `lobeMix`, `diffuseShadingPower`, `transmissionMode`,
//!   `thicknessRemap`, `worldScale`, `ior`, `hash`), their defaults (`ResetToDefault`) and
//!   ranges (`Validate`: ior in \[1, 2\], worldScale ≥ 0.001; `[Range(1, 2)]`
//!   smoothnessMultipliers, `[Range(0, 1)]` lobeMix, `[Range(1, 3)]` diffuseShadingPower).
//! - `Runtime/Material/DiffusionProfile/DiffusionProfileSettings.Migration.cs` (@ 75a39ecd):
//!   `enum Version { Initial, DiffusionProfileRework, SplitScatteringDistance }`, so
//!   `m_Version: 2` needs no migration.
//! - the script GUID `b2686e09ec7aef44bad2843e4416f057` of `DiffusionProfileSettings.cs.meta`
//!   (Unity-Technologies/FPSSample @ 45b395b2, the HDRP package it ships).
//! - `hash: 0`: the editor's `DiffusionProfileHashTable.UpdateDiffusionProfileHashNow` gives a
//!   profile whose hash is 0 ("it means that the profile was just created") a unique hash from
//!   its asset GUID when it loads it, as it does for any profile it has not seen; a hash
//!   written here would be replaced the same way.
//!
//! Each `.meta` is a `NativeFormatImporter` with `mainObjectFileID: 11400000` (the
//! MonoBehaviour's file ID) and a GUID derived from the spec's name and the entry's name
//! (SHA-256), so a re-export keeps the GUIDs and the materials that reference the profiles.

use std::fmt::Write as _;

use serde_json::{json, Value};
use sha2::{Digest, Sha256};

use super::format::{identifiers, split_max};
use super::{Provenance, SkinFit, Target};
use crate::export::burley;

/// The GUID of HDRP's `DiffusionProfileSettings.cs` (its `.meta`): the `m_Script` of every
/// diffusion profile asset.
pub const HDRP_DIFFUSION_PROFILE_SCRIPT_GUID: &str = "b2686e09ec7aef44bad2843e4416f057";
/// `DiffusionProfileSettings.Version.SplitScatteringDistance`.
pub const HDRP_DIFFUSION_PROFILE_VERSION: u32 = 2;
/// The name of the folder's index.
pub const UNITY_INDEX: &str = "profiles.json";
/// Its `"format"`.
pub const UNITY_FORMAT: &str = "baker-unity-hdrp-diffusion-profiles";

/// HDRP's defaults for what the table does not describe (`ResetToDefault`).
const THICKNESS_REMAP_MM: [f64; 2] = [0.0, 5.0];
/// `TransmissionMode.ThinObject`.
const TRANSMISSION_MODE_THIN: u32 = 1;
/// `TexturingMode.PreAndPostScatter`.
const TEXTURING_MODE_PRE_AND_POST: u32 = 0;

/// The profile of one entry: `scatteringDistance` (LDR colour) and its multiplier (mm).
///
/// HDRP's profile is R = S·(e^(−rS) + e^(−rS/3))/(8πr) with S = 1/(scatteringDistance ×
/// scatteringDistanceMultiplier) in millimetres (`DiffusionProfileSettings.cs`, `UpdateKernel`:
/// "shapeParam … S = 1 / D", "filterRadius … In millimeters"), so the product is d;
/// `scatteringDistance` is an LDR colour, so it is d/max d and the multiplier max d
/// (`HDUtils.ConvertHDRColorToLDR`, used by the `scatteringDistance` setter). The albedo is
/// the material's diffuse colour (A), not a profile field.
fn profile(f: &SkinFit) -> ([f64; 3], f64) {
    split_max(f.d_mm_rgb().map(burley::unity_scattering_distance_mm))
}

/// The asset files of each entry: `(<id>.asset, <id>.asset.meta)` names.
fn file_names(ids: &[String]) -> Vec<(String, String)> {
    ids.iter()
        .map(|id| (format!("{id}.asset"), format!("{id}.asset.meta")))
        .collect()
}

/// JSON with one HDRP diffusion profile per entry: the folder's index (`files`) and the values
/// of the `.asset` files with their derivation (`profile`).
pub fn write_unity(fits: &[SkinFit], prov: &Provenance) -> String {
    let ids = identifiers(fits);
    let names = file_names(&ids);
    let entries: Vec<Value> = fits
        .iter()
        .zip(&names)
        .map(|(f, (asset, _))| {
            let (color, mult) = profile(f);
            let rgba = |v: [f64; 3]| json!({"r": v[0], "g": v[1], "b": v[2], "a": 1.0});
            json!({
                "name": f.name,
                "asset": asset,
                "guid": meta_guid(prov, &f.name),
                "DiffusionProfile": {
                    "scatteringDistance": rgba(color),
                    "scatteringDistanceMultiplier": mult,
                    "transmissionTint": rgba([1.0; 3]),
                    "texturingMode": "PreAndPostScatter",
                    "transmissionMode": "ThinObject",
                    "thicknessRemap": THICKNESS_REMAP_MM,
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
    let mut files = vec![UNITY_INDEX.to_string()];
    for (a, m) in &names {
        files.push(a.clone());
        files.push(m.clone());
    }
    let doc = json!({
        "format": UNITY_FORMAT,
        "version": 2,
        "generated_by": prov.line(Target::Unity),
        "engine": "Unity HDRP 14-17 (Diffusion Profile asset, DiffusionProfileSettings m_Version 2)",
        "files": files,
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

/// Every file of the folder: the index ([`write_unity`]) and per entry its `.asset` and `.meta`.
pub fn unity_files(fits: &[SkinFit], prov: &Provenance) -> Vec<(String, String)> {
    let ids = identifiers(fits);
    let mut out = vec![(UNITY_INDEX.to_string(), write_unity(fits, prov))];
    for (f, (asset, meta)) in fits.iter().zip(file_names(&ids)) {
        out.push((asset, write_unity_asset(f)));
        out.push((meta, write_unity_meta(&meta_guid(prov, &f.name))));
    }
    out
}

/// A float as Unity serialises one (single precision, shortest form).
fn uf(x: f64) -> String {
    format!("{}", x as f32)
}

/// One entry's `DiffusionProfileSettings` asset in Unity's YAML serialisation.
pub fn write_unity_asset(f: &SkinFit) -> String {
    let (c, mult) = profile(f);
    let mut s = String::from("%YAML 1.1\n%TAG !u! tag:unity3d.com,2011:\n--- !u!114 &11400000\n");
    let _ = write!(
        s,
        "MonoBehaviour:\n  m_ObjectHideFlags: 0\n  m_CorrespondingSourceObject: {{fileID: 0}}\n  \
         m_PrefabInstance: {{fileID: 0}}\n  m_PrefabAsset: {{fileID: 0}}\n  m_GameObject: {{fileID: 0}}\n  \
         m_Enabled: 1\n  m_EditorHideFlags: 0\n  \
         m_Script: {{fileID: 11500000, guid: {HDRP_DIFFUSION_PROFILE_SCRIPT_GUID}, type: 3}}\n  \
         m_Name: {}\n  m_EditorClassIdentifier: \n",
        yaml_plain(&f.name)
    );
    let _ = write!(
        s,
        "  profile:\n    scatteringDistance: {{r: {}, g: {}, b: {}, a: 1}}\n    \
         scatteringDistanceMultiplier: {}\n    transmissionTint: {{r: 1, g: 1, b: 1, a: 1}}\n    \
         texturingMode: {TEXTURING_MODE_PRE_AND_POST}\n    smoothnessMultipliers: {{x: 1, y: 1}}\n    \
         lobeMix: 0.5\n    diffuseShadingPower: 1\n    transmissionMode: {TRANSMISSION_MODE_THIN}\n    \
         thicknessRemap: {{x: {}, y: {}}}\n    worldScale: 1\n    ior: {}\n    hash: 0\n  \
         m_Version: {HDRP_DIFFUSION_PROFILE_VERSION}\n",
        uf(c[0]),
        uf(c[1]),
        uf(c[2]),
        uf(mult),
        uf(THICKNESS_REMAP_MM[0]),
        uf(THICKNESS_REMAP_MM[1]),
        uf(f.eta.clamp(1.0, 2.0)),
    );
    s
}

/// The `.meta` of an asset with GUID `guid`.
pub fn write_unity_meta(guid: &str) -> String {
    format!(
        "fileFormatVersion: 2\nguid: {guid}\nNativeFormatImporter:\n  externalObjects: {{}}\n  \
         mainObjectFileID: 11400000\n  userData: \n  assetBundleName: \n  assetBundleVariant: \n"
    )
}

/// The asset GUID of an entry: 32 hex digits of SHA-256 over the spec's file name (not its
/// folder, which differs between machines) and the entry's name.
fn meta_guid(prov: &Provenance, entry: &str) -> String {
    let spec = std::path::Path::new(&prov.spec_file)
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut h = Sha256::new();
    h.update(b"baker unity diffusion profile\0");
    h.update(spec.as_bytes());
    h.update(b"\0");
    h.update(entry.as_bytes());
    h.finalize()[..16]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// `s` as a YAML scalar: plain when it starts with a letter or `_`, holds only letters,
/// digits, `_`, `-`, `.` and `@`, and is no YAML 1.1 boolean or null; else double-quoted.
fn yaml_plain(s: &str) -> String {
    const WORDS: [&str; 11] = [
        "y", "n", "yes", "no", "on", "off", "true", "false", "null", "~", "nan",
    ];
    let plain = s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '@'))
        && !WORDS.contains(&s.to_ascii_lowercase().as_str());
    if plain {
        s.to_string()
    } else {
        serde_json::to_string(s).expect("a string")
    }
}
