//! `blender`: a Python script setting up Blender's Principled BSDF.

use std::fmt::Write as _;

use super::format::{num, nums};
use super::{Provenance, SkinFit, Target};
use crate::export::burley;

/// Python script for Blender 4.x: one material per entry (created or updated), Principled BSDF
/// with Subsurface Method "Christensen-Burley".
///
/// Cycles (3.0 – 4.x, `intern/cycles/kernel/closure/bssrdf.h`) renders Burley with
/// d = (Subsurface Radius × Subsurface Scale)/(4π) (`bssrdf_setup_radius`, then
/// `bssrdf_burley_eval`), and weights it by Base Color under the specular layer
/// (`svm_closure.h`: bssrdf albedo = base_color, after the dielectric layer's albedo scaling).
/// So Subsurface Radius = 4π·d in mm, Subsurface Scale = scene units per mm, Base Color =
/// A/(1 − F0), IOR = η.
pub fn write_blender(fits: &[SkinFit], prov: &Provenance) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# {}\n\
         # Blender 4.x: creates or updates one material per skin entry, Principled BSDF with\n\
         # Subsurface Method \"Christensen-Burley\". Run in Blender's Text Editor or with\n\
         # `blender --python THIS_FILE`.\n\
         #\n\
         # Cycles renders R(r) = A (e^(-r/d) + e^(-r/3d)) / (8 pi d r) with\n\
         # d = Subsurface Radius * Subsurface Scale / (4 pi) (intern/cycles/kernel/closure/bssrdf.h,\n\
         # bssrdf_setup_radius), so Subsurface Radius = 4 pi d in millimetres and Subsurface Scale\n\
         # converts millimetres to scene units. Base Color = A / (1 - F0): Cycles scales it by the\n\
         # energy the specular layer (IOR = skin eta) lets through. (A, d): Christensen-Burley fit\n\
         # of the baked table (Pixar Tech Memo #15-04). Colours: linear sRGB (Blender's default\n\
         # scene-linear space).",
        prov.line(Target::Blender)
    );
    s.push_str("import bpy\n\n");
    s.push_str("# (name, base colour, Subsurface Radius in mm = 4 pi d, IOR, fitted A, d in mm)\n");
    s.push_str("SKINS = [\n");
    for f in fits {
        let radius = f.d_mm_rgb().map(burley::cycles_burley_radius);
        let _ = writeln!(
            s,
            "    ({}, ({}), ({}), {}, ({}), ({})),",
            serde_json::to_string(&f.name).expect("string"),
            nums(&f.albedo_below_interface_rgb()),
            nums(&radius),
            num(f.eta),
            nums(&f.a_rgb()),
            nums(&f.d_mm_rgb()),
        );
    }
    s.push_str("]\n\n");
    s.push_str(
        r#"
def scene_units_per_mm(scene):
    # One Blender unit is unit_settings.scale_length metres.
    return 0.001 / scene.unit_settings.scale_length


def apply(name, base_color, radius_mm, ior, mm):
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    if bsdf is None:
        bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    out = next((n for n in nodes if n.type == "OUTPUT_MATERIAL"), None)
    if out is None:
        out = nodes.new("ShaderNodeOutputMaterial")
    if not out.inputs["Surface"].is_linked:
        links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    bsdf.subsurface_method = "BURLEY"
    bsdf.inputs["Base Color"].default_value = (*base_color, 1.0)
    bsdf.inputs["Subsurface Weight"].default_value = 1.0
    bsdf.inputs["Subsurface Radius"].default_value = radius_mm
    bsdf.inputs["Subsurface Scale"].default_value = mm
    bsdf.inputs["IOR"].default_value = ior
    return mat


def main():
    mm = scene_units_per_mm(bpy.context.scene)
    for name, base_color, radius_mm, ior, _a, _d in SKINS:
        apply(name, base_color, radius_mm, ior, mm)
    print(f"baker skin export: {len(SKINS)} materials, Subsurface Scale {mm:g} scene units/mm")


if __name__ == "__main__":
    main()
"#,
    );
    s
}
