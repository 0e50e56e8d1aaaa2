//! `mtlx`: OpenPBR Surface in MaterialX.

use std::fmt::Write as _;

use super::format::{identifiers, num, nums, split_max};
use super::{Provenance, SkinFit, Target};
use crate::export::xml::{xml_comment, xml_escape};

/// MaterialX 1.39 document, one `open_pbr_surface` and `surfacematerial` per entry.
///
/// OpenPBR specification (v1.x, "Subsurface"): `subsurface_radius × subsurface_radius_scale`
/// is the mean free path r per channel, μt = 1/r; `subsurface_color` C is the multiple-scattering
/// albedo below the interface, E_multi-scatter = (1 − E_spec)·C. So radius = max_c ℓ_c (mm,
/// `unit="millimeter"`, which MaterialX's unit system converts to the renderer's distance
/// unit), scale = ℓ/max ℓ (in \[0, 1\]), ℓ = d·s_perpendicular(A)
/// ([`burley::volume_mfp_mm`](crate::export::burley::volume_mfp_mm)); C = A/(1 − F0);
/// `specular_ior` = the skin surface's η, `base_color` = C (what a renderer without subsurface
/// falls back to).
pub fn write_mtlx(fits: &[SkinFit], prov: &Provenance) -> String {
    let ids = identifiers(fits);
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n");
    let _ = writeln!(
        s,
        "<!--\n  {}\n  OpenPBR Surface (MaterialX 1.39 open_pbr_surface), one material per skin entry.\n  \
         subsurface_radius * subsurface_radius_scale = volume mean free path l = 1/mu_t (OpenPBR spec, \
         \"Subsurface\"),\n  l = d (1.85 - A + 7|A - 0.8|^3) from the Christensen-Burley fit (A, d) of the \
         table (Pixar Tech Memo #15-04,\n  perpendicular illumination). subsurface_radius is in millimetres \
         (unit=\"millimeter\"). subsurface_color = A / (1 - F0):\n  OpenPBR's multiple-scattering albedo \
         below the dielectric interface, E_ms = (1 - E_spec) C. Colours: linear sRGB (lin_rec709).\n-->",
        xml_comment(&prov.line(Target::Mtlx))
    );
    s.push_str("<materialx version=\"1.39\" colorspace=\"lin_rec709\">\n");
    for (f, id) in fits.iter().zip(&ids) {
        let c = f.albedo_below_interface_rgb();
        let (scale, radius) = split_max(f.volume_mfp_mm_rgb());
        let doc = format!(
            "skin entry {}: A = ({}), d = ({}) mm, F0 = {}, Burley fit error = ({})",
            f.name,
            nums(&f.a_rgb()),
            nums(&f.d_mm_rgb()),
            num(f.f0),
            nums(&f.burley_error_rgb())
        );
        let _ = writeln!(
            s,
            "  <open_pbr_surface name=\"SR_{id}\" type=\"surfaceshader\" doc=\"{}\">",
            xml_escape(&doc)
        );
        let input = |s: &mut String, name: &str, ty: &str, value: String, extra: &str| {
            let _ = writeln!(
                s,
                "    <input name=\"{name}\" type=\"{ty}\" value=\"{value}\"{extra} />"
            );
        };
        input(&mut s, "base_color", "color3", nums(&c), "");
        input(&mut s, "specular_ior", "float", num(f.eta), "");
        input(&mut s, "subsurface_weight", "float", "1".into(), "");
        input(&mut s, "subsurface_color", "color3", nums(&c), "");
        input(
            &mut s,
            "subsurface_radius",
            "float",
            num(radius),
            " unittype=\"distance\" unit=\"millimeter\"",
        );
        input(
            &mut s,
            "subsurface_radius_scale",
            "color3",
            nums(&scale),
            "",
        );
        s.push_str("  </open_pbr_surface>\n");
        let _ = writeln!(
            s,
            "  <surfacematerial name=\"{id}\" type=\"material\" doc=\"{}\">\n    \
             <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR_{id}\" />\n  \
             </surfacematerial>",
            xml_escape(&format!("skin entry {}", f.name))
        );
    }
    s.push_str("</materialx>\n");
    s
}
