//! `blender`: a Python script that builds a Principled Hair BSDF (Chiang model) material.

use super::fit::FiberFit;
use super::summary::{exact, exact_list, summary};
use crate::error::UsageError;
use crate::export::ExportRequest;

/// `--method` (the Subsurface Method of a skin `--to blender` export) on a fiber table: a
/// usage error; the Principled Hair BSDF has no such choice.
pub(super) fn refuse_method(req: &ExportRequest) -> Result<(), UsageError> {
    match &req.method {
        None => Ok(()),
        Some(m) => Err(UsageError(format!(
            "--method {m:?}: {} is a fiber table; --method chooses the Subsurface Method of a \
             skin table's --to blender export (fiber exports have no method)",
            req.table.display()
        ))),
    }
}

/// Blender's Offset socket, radians: −α (see the [`fiber`](super) module docs).
pub(super) fn blender_offset_rad(alpha_deg: f64) -> f64 {
    // Cycles bsdf_principled_hair_chiang.h hair_alpha_angles: R peak at θi + θo = −2·Offset;
    // Mitsuba hair.cpp reframe_with_scales: at θi + θo = +2α.
    -alpha_deg.to_radians()
}

/// The `blender` target: a Python script for Blender (3.x and 4.x) that builds the material.
pub fn write_blender(fit: &FiberFit) -> String {
    let p = &fit.report.params;
    let mut s = String::from(
        "# Blender Principled Hair BSDF (Chiang model) written by `baker export --to blender`.\n",
    );
    for line in summary(fit) {
        s += &format!("# {line}\n");
    }
    s += "# Run: blender FILE.blend --python THIS.py (or Blender's Text Editor, Run Script). It\n\
          # creates or updates the material MATERIAL and assigns it to the selected objects\n\
          # (hair curves: Cycles, 3D curves; their direction is the fiber's +z).\n\
          # Conversions (intern/cycles/kernel/svm/closure.h,\n\
          # intern/cycles/kernel/closure/bsdf_principled_hair_chiang.h):\n\
          #   Roughness = beta_m, Radial Roughness = beta_n (Cycles maps them to v and s with the\n\
          #   polynomials of Mitsuba's hair.cpp); Coat = 0 (R roughness = (1 - Coat) * beta_m);\n\
          #   IOR = eta; Absorption Coefficient = sigma_a per unit radius (same chord length);\n\
          #   Offset = -alpha in radians (hair_alpha_angles tilts the other way round).\n";
    s += &format!(
        "import bpy\n\nMATERIAL = {:?}\nSIGMA_A = ({})\nBETA_M = {}\nBETA_N = {}\n\
         IOR = {}\nOFFSET_RAD = {}  # alpha = {:.4} deg\n\n",
        format!("baker {}", fit.variant),
        exact_list(&p.sigma_a, ", "),
        exact(p.beta_m),
        exact(p.beta_n),
        exact(p.eta),
        exact(blender_offset_rad(p.alpha_deg)),
        p.alpha_deg,
    );
    s += r#"mat = bpy.data.materials.get(MATERIAL) or bpy.data.materials.new(MATERIAL)
mat.use_nodes = True
nodes, links = mat.node_tree.nodes, mat.node_tree.links
nodes.clear()
output = nodes.new("ShaderNodeOutputMaterial")
hair = nodes.new("ShaderNodeBsdfHairPrincipled")
hair.location = (-320, 0)


def enum_value(prop, want):
    """The identifier of enum `prop` whose identifier or name matches `want`."""
    for item in hair.bl_rna.properties[prop].enum_items:
        if item.identifier.upper() == want.upper() or want.lower() in item.name.lower():
            return item.identifier
    raise RuntimeError(f"Principled Hair BSDF: no {prop} {want!r}")


def set_input(name, value):
    if name not in hair.inputs:
        return
    socket = hair.inputs[name]
    try:
        n = len(socket.default_value)
    except TypeError:
        socket.default_value = value
        return
    socket.default_value = (tuple(value) + (1.0,) * n)[:n]


if "model" in hair.bl_rna.properties:  # Blender >= 4.0: Chiang or Huang
    hair.model = enum_value("model", "CHIANG")
hair.parametrization = enum_value("parametrization", "ABSORPTION")
set_input("Absorption Coefficient", SIGMA_A)
set_input("Roughness", BETA_M)
set_input("Radial Roughness", BETA_N)
set_input("Coat", 0.0)
set_input("IOR", IOR)
set_input("Offset", OFFSET_RAD)
set_input("Random Roughness", 0.0)
links.new(hair.outputs["BSDF"], output.inputs["Surface"])

for ob in getattr(bpy.context, "selected_objects", None) or []:
    if hasattr(ob.data, "materials"):
        if ob.data.materials:
            ob.data.materials[0] = mat
        else:
            ob.data.materials.append(mat)
"#;
    s
}
