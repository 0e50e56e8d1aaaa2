//! `unreal`: an Unreal Editor Python script that creates or updates one `SubsurfaceProfile`
//! asset per entry ([`write_unreal_script`]), and the same fields as JSON beside it
//! ([`write_unreal`]).
//!
//! `baker export profiles.bkt --to unreal -o skin.py` writes `skin.py` and `skin.json` (each
//! atomically; the JSON first). Without `-o` the script goes to standard output alone.
//!
//! The script uses only the Unreal Editor Python API (UE 5.0–5.7,
//! <https://dev.epicgames.com/documentation/en-us/unreal-engine/python-api/>):
//! `unreal.AssetToolsHelpers.get_asset_tools().create_asset(name, package_path,
//! unreal.SubsurfaceProfile, unreal.SubsurfaceProfileFactory())` for a new asset,
//! `unreal.EditorAssetLibrary.does_asset_exist` / `load_asset` for an existing one (so a rerun
//! updates the assets in place), `SubsurfaceProfile.get_editor_property("settings")` (a
//! `SubsurfaceProfileStruct`), `set_editor_property` of its fields (`surface_albedo`,
//! `mean_free_path_color`: `LinearColor`; `mean_free_path_distance`, `world_unit_scale`, `ior`:
//! float; `enable_burley`, `enable_mean_free_path`: bool — Unreal's Python names drop the `b`
//! of `bEnableBurley`), and `EditorAssetLibrary.save_loaded_asset`. The folder is
//! `PACKAGE_PATH` at the top of the script (default `/Game/BakerSkin`), or the environment
//! variable `BAKER_UNREAL_PACKAGE_PATH`. `validation/engine_reference/unreal_python_api.json`
//! lists these names with the documentation pages they come from.

use std::fmt::Write as _;

use serde_json::{json, Value};

use super::format::{identifiers, split_max};
use super::{Provenance, SkinFit, Target};
use crate::export::burley;

/// Unreal Engine 5 clamps `MeanFreePathDistance` below at 0.1 cm and shifts the rest into the
/// colour (`SubsurfaceProfile.cpp`, `UpgradeDiffuseMeanFreePathToMeanFreePath`, "Support
/// mfp < 0.1f").
const UNREAL_MIN_MFP_DISTANCE_CM: f64 = 0.1;
/// Unreal clamps `SurfaceAlbedo` and `MeanFreePathColor` below at this bias
/// (`FSubsurfaceProfileTexture::CreateTexture`, `Bias`).
const UNREAL_COLOR_BIAS: f64 = 0.009;
/// Unreal's default `WorldUnitScale`, at which 1 world unit = 1 cm of skin
/// (`SubsurfaceProfile.h`, constructor: `WorldUnitScale = 0.1f`).
const UNREAL_WORLD_UNIT_SCALE: f64 = 0.1;
/// The asset folder the script writes to unless told otherwise.
pub const UNREAL_DEFAULT_PACKAGE_PATH: &str = "/Game/BakerSkin";

/// The `SubsurfaceProfile` fields of one entry.
#[derive(Debug, Clone)]
struct Fields {
    albedo: [f64; 3],
    mfp_color: [f64; 3],
    mfp_distance_cm: f64,
    mfp_cm: [f64; 3],
    notes: Vec<String>,
}

/// MFP_c (cm) = 0.06·s_perpendicular(A_c)·d_c ([`burley::unreal_mfp_cm`]: Unreal converts the
/// MFP to a DMFP with `GetDiffuseMeanFreePathFromMeanFreePath`·10/`Dmfp2MfpMagicNumber` and
/// renders e^(−r·s_dmfp(A)/DMFP)); `MeanFreePathDistance` = max_c MFP_c,
/// `MeanFreePathColor` = MFP/`MeanFreePathDistance`; `SurfaceAlbedo` = A;
/// `WorldUnitScale` = 0.1, Unreal's default, at which 1 world unit = 1 cm of skin
/// (`BurleyNormalizedSSS.cpp`, `ComputeTransmissionProfileBurley`: DistanceCm·(WorldUnitScale/0.1)·10 = mm).
fn fields(f: &SkinFit) -> Fields {
    let a = f.a_rgb();
    let mfp_cm: [f64; 3] = std::array::from_fn(|c| burley::unreal_mfp_cm(a[c], f.burley[c].d_mm));
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
    Fields {
        albedo: a,
        mfp_color: color,
        mfp_distance_cm: dist,
        mfp_cm,
        notes,
    }
}

/// JSON with one `SubsurfaceProfile` per entry (Burley, mean-free-path mode): the side file
/// of the script, and what its values are (`fields`).
pub fn write_unreal(fits: &[SkinFit], prov: &Provenance) -> String {
    let ids = identifiers(fits);
    let entries: Vec<Value> = fits
        .iter()
        .zip(&ids)
        .map(|(f, id)| {
            let u = fields(f);
            let lin = |v: [f64; 3]| json!({"R": v[0], "G": v[1], "B": v[2], "A": 1.0});
            json!({
                "name": f.name,
                "asset": asset_name(id),
                "SubsurfaceProfile": {
                    "bEnableBurley": true,
                    "bEnableMeanFreePath": true,
                    "SurfaceAlbedo": lin(u.albedo),
                    "MeanFreePathColor": lin(u.mfp_color),
                    "MeanFreePathDistance": u.mfp_distance_cm,
                    "WorldUnitScale": UNREAL_WORLD_UNIT_SCALE,
                    "IOR": f.eta,
                },
                "derived": {
                    "mean_free_path_cm_rgb": u.mfp_cm,
                    "diffuse_mean_free_path_mm_rgb": f.burley.map(|b| burley::dmfp_mm(b.a, b.d_mm)),
                    "burley_d_mm_rgb": f.d_mm_rgb(),
                    "burley_error_rgb": f.burley_error_rgb(),
                },
                "notes": u.notes,
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

/// The asset name of an entry's identifier (Unreal's `SP_` prefix for subsurface profiles).
fn asset_name(id: &str) -> String {
    format!("SP_{id}")
}

/// `s` as a Python string literal (double quotes; backslash, quote and control characters
/// escaped).
fn py_str(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '"' => out.push_str("\\\""),
            c if c.is_control() => {
                let _ = write!(out, "\\U{:08x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A float as Python reads it back exactly (Rust's shortest round-trip form).
fn py_f(x: f64) -> String {
    format!("{x:?}")
}

fn py_rgb(v: [f64; 3]) -> String {
    format!("({}, {}, {})", py_f(v[0]), py_f(v[1]), py_f(v[2]))
}

/// The Unreal Editor Python script ([module docs](self)): the fields of [`write_unreal`] as
/// `SubsurfaceProfileStruct` properties.
pub fn write_unreal_script(fits: &[SkinFit], prov: &Provenance) -> String {
    let ids = identifiers(fits);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# {}\n\
         # Unreal Engine 5 Editor Python script: creates or updates one Subsurface Profile asset\n\
         # (Burley, Enable Mean Free Path) per skin entry in PACKAGE_PATH.\n\
         # Run it in the editor (Output Log, Python: py \"THIS.py\"; or Tools > Execute Python\n\
         # Script), with the Python Editor Script Plugin enabled. The fields and their\n\
         # conversions from the Christensen-Burley fit (A, d) of the table are in the JSON side\n\
         # file written beside this script (-o X.py writes X.json):\n\
         #   mean_free_path (cm) = 0.06 d_mm (1.85 - A + 7|A - 0.8|^3) per channel\n\
         #   (SubsurfaceProfile.cpp CreateTexture, BurleyNormalizedSSS.cpp Burley_ScatteringProfile),\n\
         #   mean_free_path_distance = its maximum (at least 0.1 cm), mean_free_path_color = the\n\
         #   ratio, surface_albedo = A (linear sRGB), world_unit_scale = 0.1 (1 unit = 1 cm).\n\
         # Python API: unreal.AssetToolsHelpers, unreal.SubsurfaceProfileFactory,\n\
         # unreal.SubsurfaceProfile (property settings: SubsurfaceProfileStruct),\n\
         # unreal.EditorAssetLibrary (dev.epicgames.com/documentation/en-us/unreal-engine/python-api/).\n",
        prov.line(Target::Unreal).replace('\n', " ")
    );
    let _ = writeln!(
        s,
        "import os\n\nimport unreal\n\n\
         PACKAGE_PATH = os.environ.get(\"BAKER_UNREAL_PACKAGE_PATH\", {})\n",
        py_str(UNREAL_DEFAULT_PACKAGE_PATH)
    );
    s.push_str("# (asset name, skin entry, SubsurfaceProfileStruct fields)\nPROFILES = [\n");
    for (f, id) in fits.iter().zip(&ids) {
        let u = fields(f);
        let _ = writeln!(
            s,
            "    ({}, {}, {{\n        \"surface_albedo\": {},\n        \
             \"mean_free_path_color\": {},\n        \"mean_free_path_distance\": {},\n        \
             \"world_unit_scale\": {},\n        \"ior\": {},\n        \
             \"enable_burley\": True,\n        \"enable_mean_free_path\": True,\n    }}),",
            py_str(&asset_name(id)),
            py_str(&f.name),
            py_rgb(u.albedo),
            py_rgb(u.mfp_color),
            py_f(u.mfp_distance_cm),
            py_f(UNREAL_WORLD_UNIT_SCALE),
            py_f(f.eta),
        );
    }
    s.push_str("]\n");
    s.push_str(UNREAL_SCRIPT_BODY);
    s
}

const UNREAL_SCRIPT_BODY: &str = r#"
COLOR_FIELDS = ("surface_albedo", "mean_free_path_color")


def profile_asset(tools, name):
    """The SubsurfaceProfile at PACKAGE_PATH/name: loaded if it exists, else created."""
    path = PACKAGE_PATH.rstrip("/") + "/" + name
    if unreal.EditorAssetLibrary.does_asset_exist(path):
        asset = unreal.EditorAssetLibrary.load_asset(path)
        if not isinstance(asset, unreal.SubsurfaceProfile):
            raise RuntimeError(f"{path} exists and is not a SubsurfaceProfile; nothing was changed")
        return asset, "updated"
    asset = tools.create_asset(name, PACKAGE_PATH, unreal.SubsurfaceProfile,
                               unreal.SubsurfaceProfileFactory())
    if asset is None:
        raise RuntimeError(f"could not create {path}")
    return asset, "created"


def main():
    tools = unreal.AssetToolsHelpers.get_asset_tools()
    for name, entry, fields in PROFILES:
        asset, how = profile_asset(tools, name)
        settings = asset.get_editor_property("settings")
        for key, value in fields.items():
            if key in COLOR_FIELDS:
                value = unreal.LinearColor(value[0], value[1], value[2], 1.0)
            settings.set_editor_property(key, value)
        asset.set_editor_property("settings", settings)
        if not unreal.EditorAssetLibrary.save_loaded_asset(asset, only_if_is_dirty=False):
            raise RuntimeError(f"could not save {asset.get_path_name()}")
        unreal.log(f"baker: {how} {asset.get_path_name()} (skin entry {entry})")


main()
"#;
