//! `pbrt`: pbrt-v4 `subsurface` materials.

use std::fmt::Write as _;

use super::format::{num, nums, nums_sep};
use super::{Provenance, SkinFit, Target};

/// pbrt-v4 scene text: one `MakeNamedMaterial` of type `subsurface` per entry.
///
/// pbrt-v4 (`src/pbrt/materials.h`, `SubsurfaceMaterial::GetBSSRDF`) takes `reflectance` and
/// `mfp`, sets σt = 1/(scale·mfp) and finds the single-scattering albedo by inverting its
/// photon-beam-diffusion table (`SubsurfaceFromDiffuse`, `InvertCatmullRom` on ρ_eff). So
/// mfp = ℓ = d·s_perpendicular(A) (mm), `scale` = scene units per mm, reflectance = A/(1 − F0)
/// (pbrt applies the boundary's Fresnel transmission on top), eta = η.
pub fn write_pbrt(fits: &[SkinFit], prov: &Provenance) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# {}\n\
         # pbrt-v4 SubsurfaceMaterial per skin entry (use with the volpath or path integrator):\n\
         #   NamedMaterial \"<entry>\"\n\
         # mfp = volume mean free path l = d (1.85 - A + 7|A - 0.8|^3) in millimetres from the\n\
         # Christensen-Burley fit (A, d) of the table (Pixar Tech Memo #15-04, perpendicular\n\
         # illumination); pbrt uses sigma_t = 1 / (scale * mfp), so \"scale\" = scene units per mm\n\
         # (1 for a scene in mm, 0.001 for metres). reflectance = A / (1 - F0): pbrt inverts its\n\
         # photon beam diffusion table for the single-scattering albedo (materials.h,\n\
         # SubsurfaceFromDiffuse) and applies the surface's Fresnel transmission itself.\n\
         # Colours: linear sRGB.",
        prov.line(Target::Pbrt)
    );
    for f in fits {
        let name = f.name.replace('\\', "\\\\").replace('"', "\\\"");
        let _ = writeln!(
            s,
            "\n# {}: A = ({}), d = ({}) mm, Burley fit error ({})\n\
             MakeNamedMaterial \"{name}\"\n    \
             \"string type\" [ \"subsurface\" ]\n    \
             \"rgb reflectance\" [ {} ]\n    \
             \"rgb mfp\" [ {} ]\n    \
             \"float scale\" [ 1 ]\n    \
             \"float eta\" [ {} ]\n    \
             \"float g\" [ 0 ]",
            f.name.replace('\n', " "),
            nums(&f.a_rgb()),
            nums(&f.d_mm_rgb()),
            nums(&f.burley_error_rgb()),
            nums_sep(&f.albedo_below_interface_rgb(), " "),
            nums_sep(&f.volume_mfp_mm_rgb(), " "),
            num(f.eta),
        );
    }
    s
}
