//! `blender`: a Python script setting up Blender's Principled BSDF, with the Subsurface Method
//! chosen by `--method` (`burley`, `random-walk`, `random-walk-skin`, the default).
//!
//! How Cycles reads the Principled BSDF's subsurface inputs (Blender 4.0 – 5.0,
//! `intern/cycles/kernel/closure/bssrdf.h` and
//! `intern/cycles/kernel/integrator/subsurface_random_walk.h`):
//!
//! - The closure albedo is Base Color, under the dielectric specular layer (its weight is
//!   scaled by the energy the layer lets through). Every method gets C = A/(1 − F0)
//!   ([`SkinFit::albedo_below_interface_rgb`]), A the table's diffuse reflectance.
//! - `bssrdf_setup_radius`: for `BURLEY` and `RANDOM_WALK` the radius R = Subsurface Radius ×
//!   Subsurface Scale is multiplied by 1/(4π) ("Scale mean free path length so it gives
//!   similar looking result to older Cubic, Gaussian and Burley models"). For
//!   `RANDOM_WALK_SKIN` it is multiplied by √(3(1 − α′)), α′ the albedo whose dipole
//!   reflectance ½α′(1 + e^(−(4/3)·A_J·s))·e^(−s), s = √(3(1 − α′)), is C
//!   (`bssrdf_dipole_compute_Rd`, `bssrdf_dipole_compute_alpha_prime`: 12 bisection steps on
//!   \[0, 1\]), with A_J = (1 + F_dr)/(1 − F_dr) and Jensen's F_dr(η) =
//!   −1.440/η² + 0.710/η + 0.668 + 0.0636·η, η = Subsurface IOR clamped to \[1.01, 3.8\]
//!   (`bssrdf_setup`).
//! - Burley (`bssrdf_burley_eval`): the profile (e^(−r/d) + e^(−r/3d))/(8π·d·r) with d the
//!   scaled radius, so Subsurface Radius = 4π·d ([`burley::cycles_burley_radius`]).
//! - Random walk (`subsurface_random_walk_remap`): σt = 1/(scaled radius·(1 − g)), g =
//!   Subsurface Anisotropy (written 0), and a single-scattering albedo inverted from C so that
//!   the walk's total reflectance is C. The walk enters the surface in a cosine-distributed
//!   direction (`sample_cos_hemisphere`; the skin method refracts through a rough interface of
//!   IOR Subsurface IOR), i.e. diffuse surface transmission, whose Burley shape is
//!   d = ℓ/s(C) with s(C) = 1.9 − C + 3.5(C − 0.8)² (Christensen & Burley 2015, Eq. 6; the same
//!   `bssrdf_burley_fitting` Cycles ships). So the walk that reproduces the baked shape d has
//!   mean free path ℓ = d·s(C) ([`burley::diffuse_transmission_mfp_mm`] with C), and
//!   Subsurface Radius = 4π·ℓ (`random-walk`) or ℓ/√(3(1 − α′)) (`random-walk-skin`: the
//!   diffusion length 1/σtr of the dipole albedo α′).
//!
//! Radii are in millimetres and Subsurface Scale converts them to scene units
//! (`0.001 / unit_settings.scale_length`). Blender 3.x names the same closures `BURLEY`,
//! `RANDOM_WALK_FIXED_RADIUS` and `RANDOM_WALK` (Cycles 3.x `bssrdf_setup_radius`, which
//! scales `RANDOM_WALK_FIXED_RADIUS` by 1/(4π) and `RANDOM_WALK` by √(3(1 − α′)) with the
//! Principled IOR) and has no Subsurface Scale; the script handles both.

use std::f64::consts::PI;
use std::fmt::Write as _;

use super::format::{num, nums};
use super::{Provenance, SkinFit, Target};
use crate::error::UsageError;
use crate::export::{burley, ExportRequest};

/// The Principled BSDF's Subsurface Method, as `--method` names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    Burley,
    RandomWalk,
    /// Blender's default suggestion for skin ("designed for skin shading", Blender manual,
    /// Principled BSDF, Subsurface Method), and ours.
    #[default]
    RandomWalkSkin,
}

impl Method {
    pub const ALL: [Method; 3] = [Method::Burley, Method::RandomWalk, Method::RandomWalkSkin];

    /// The name given to `--method`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Burley => "burley",
            Method::RandomWalk => "random-walk",
            Method::RandomWalkSkin => "random-walk-skin",
        }
    }

    /// The `subsurface_method` enum identifier of Blender ≥ 4.0.
    pub fn blender_enum(self) -> &'static str {
        match self {
            Method::Burley => "BURLEY",
            Method::RandomWalk => "RANDOM_WALK",
            Method::RandomWalkSkin => "RANDOM_WALK_SKIN",
        }
    }

    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// The method of `req` for a skin export to `target`: `--method` is an option of
/// `--to blender` only; absent, [`Method::default`].
pub fn method_of(req: &ExportRequest, target: Target) -> Result<Method, UsageError> {
    let Some(m) = req.method.as_deref() else {
        return Ok(Method::default());
    };
    let names = Method::ALL.map(Method::name);
    let Some(method) = Method::parse(m) else {
        return Err(UsageError(format!(
            "--method {m:?} is not a Blender subsurface method; {}",
            crate::suggest::advice(m, &names, "methods", "")
        )));
    };
    if target != Target::Blender {
        return Err(UsageError(format!(
            "--method chooses the Principled BSDF's Subsurface Method of --to blender; \
             --to {} has no method (drop --method {})",
            target.name(),
            method.name()
        )));
    }
    Ok(method)
}

/// What one entry sets on the Principled BSDF: Base Color (linear sRGB), Subsurface Radius
/// (mm; Subsurface Scale turns it into scene units) and IOR (also Subsurface IOR).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlenderSkin {
    pub base_color: [f64; 3],
    pub radius_mm: [f64; 3],
    pub ior: f64,
}

/// The Principled BSDF inputs of `f` rendered with `method` (formulas and sources: module
/// docs).
pub fn blender_parameters(f: &SkinFit, method: Method) -> BlenderSkin {
    let c = f.albedo_below_interface_rgb();
    let d = f.d_mm_rgb();
    let radius_mm = std::array::from_fn(|k| {
        let mfp_mm = burley::diffuse_transmission_mfp_mm(c[k], d[k]);
        match method {
            Method::Burley => burley::cycles_burley_radius(d[k]),
            Method::RandomWalk => 4.0 * PI * mfp_mm,
            Method::RandomWalkSkin => {
                let alpha_prime = cycles_dipole_alpha_prime(c[k], f.eta);
                mfp_mm / (3.0 * (1.0 - alpha_prime)).sqrt()
            }
        }
    });
    BlenderSkin {
        base_color: c,
        radius_mm,
        ior: f.eta,
    }
}

/// The dipole albedo α′ Cycles' `RANDOM_WALK_SKIN` derives from albedo `rd` and IOR `eta`,
/// step by step as `bssrdf.h` computes it (`bssrdf_setup` clamps η to \[1.01, 3.8\];
/// `bssrdf_dipole_compute_alpha_prime`: 0 below 1e-4, 0.999999 from 0.995, else the midpoint
/// after 12 bisection steps of `bssrdf_dipole_compute_Rd` on \[0, 1\]).
pub fn cycles_dipole_alpha_prime(rd: f64, eta: f64) -> f64 {
    let eta = eta.clamp(1.01, 3.8);
    let inv = 1.0 / eta;
    // Jensen et al. 2001's fit of the diffuse Fresnel reflectance, as in bssrdf.h.
    let f_dr = inv * (-1.440 * inv + 0.710) + 0.668 + 0.0636 * eta;
    let four_third_a = (4.0 / 3.0) * (1.0 + f_dr) / (1.0 - f_dr);
    if rd < 1e-4 {
        return 0.0;
    }
    if rd >= 0.995 {
        return 0.999999;
    }
    let dipole_rd = |ap: f64| {
        let s = (3.0 * (1.0 - ap)).sqrt();
        0.5 * ap * (1.0 + (-four_third_a * s).exp()) * (-s).exp()
    };
    let (mut x0, mut x1, mut mid) = (0.0f64, 1.0f64, 0.5f64);
    for _ in 0..12 {
        mid = 0.5 * (x0 + x1);
        if dipole_rd(mid) < rd {
            x0 = mid;
        } else {
            x1 = mid;
        }
    }
    mid
}

/// The script with the default method ([`write_blender_with`]).
pub fn write_blender(fits: &[SkinFit], prov: &Provenance) -> String {
    write_blender_with(fits, prov, Method::default())
}

/// Python script for Blender 3.0 – 5.x: one material per entry (created or updated), a
/// Principled BSDF with Subsurface Method `method` and the inputs of [`blender_parameters`].
pub fn write_blender_with(fits: &[SkinFit], prov: &Provenance, method: Method) -> String {
    let mut s = String::new();
    let radius_rule = match method {
        Method::Burley => "Subsurface Radius = 4 pi d: Cycles renders\n\
             # R(r) = (e^(-r/d) + e^(-r/3d)) / (8 pi d r) with d = radius / (4 pi)\n\
             # (bssrdf.h: bssrdf_setup_radius, bssrdf_burley_eval)."
            .to_string(),
        Method::RandomWalk => "Subsurface Radius = 4 pi l: the walk's sigma_t = 4 pi / radius\n\
             # (bssrdf.h bssrdf_setup_radius; subsurface_random_walk.h\n\
             # subsurface_random_walk_remap), and l = d * s(C), s(C) = 1.9 - C + 3.5 (C - 0.8)^2\n\
             # (Christensen & Burley 2015, Eq. 6, diffuse surface transmission) is the mean free\n\
             # path whose walk has the baked Burley shape d."
            .to_string(),
        Method::RandomWalkSkin => "Subsurface Radius = l / sqrt(3 (1 - a')): Cycles' skin walk\n\
             # has sigma_t = 1 / (radius * sqrt(3 (1 - a'))), a' the dipole albedo of C at the\n\
             # Subsurface IOR (bssrdf.h bssrdf_setup_radius, bssrdf_dipole_compute_alpha_prime),\n\
             # and l = d * s(C), s(C) = 1.9 - C + 3.5 (C - 0.8)^2 (Christensen & Burley 2015,\n\
             # Eq. 6, diffuse surface transmission) is the mean free path whose walk has the\n\
             # baked Burley shape d."
            .to_string(),
    };
    let _ = writeln!(
        s,
        "# {}\n\
         # Blender 3.0 - 5.x: creates or updates one material per skin entry, Principled BSDF\n\
         # with Subsurface Method {:?} (`baker export --method {}`). Run in Blender's Text\n\
         # Editor or with `blender --python THIS_FILE`.\n\
         #\n\
         # {radius_rule}\n\
         # Subsurface Scale converts millimetres to scene units. Base Color = C = A / (1 - F0):\n\
         # Cycles scales it by the energy the specular layer (IOR = skin eta) lets through.\n\
         # (A, d): Christensen-Burley fit of the baked table (Pixar Tech Memo #15-04).\n\
         # Colours: linear sRGB (Blender's default scene-linear space).",
        prov.line(Target::Blender),
        method.blender_enum(),
        method.name(),
    );
    s.push_str("import bpy\n\n");
    let _ = writeln!(s, "METHOD = {:?}\n", method.blender_enum());
    s.push_str("# (name, Base Color, Subsurface Radius in mm, IOR, fitted A, d in mm)\n");
    s.push_str("SKINS = [\n");
    for f in fits {
        let p = blender_parameters(f, method);
        let _ = writeln!(
            s,
            "    ({}, ({}), ({}), {}, ({}), ({})),",
            serde_json::to_string(&f.name).expect("string"),
            nums(&p.base_color),
            nums(&p.radius_mm),
            num(p.ior),
            nums(&f.a_rgb()),
            nums(&f.d_mm_rgb()),
        );
    }
    s.push_str("]\n");
    s.push_str(SCRIPT_BODY);
    s
}

/// The part of the script that does not depend on the table.
const SCRIPT_BODY: &str = r#"
# Blender 3.x names the same Cycles closures differently (3.x bssrdf.h bssrdf_setup_radius).
METHOD_3X = {"BURLEY": "BURLEY", "RANDOM_WALK": "RANDOM_WALK_FIXED_RADIUS",
             "RANDOM_WALK_SKIN": "RANDOM_WALK"}


def scene_units_per_mm(scene):
    # One Blender unit is unit_settings.scale_length metres.
    return 0.001 / scene.unit_settings.scale_length


def set_input(bsdf, name, value):
    # By name among all sockets: `name in bsdf.inputs` skips the ones the current Subsurface
    # Method hides (Blender 4+), and older Blenders lack some.
    socket = next((s for s in bsdf.inputs if s.name == name), None)
    if socket is not None:
        socket.default_value = value


def apply(name, base_color, radius_mm, ior, mm):
    if bpy.app.version < (3, 0, 0):
        raise RuntimeError("this script needs Blender 3.0 or later: older Cycles scales the "
                           "subsurface radius by the albedo (bssrdf_burley_setup)")
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0) or mat.node_tree is None:
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
    bsdf.inputs["Base Color"].default_value = (*base_color, 1.0)
    bsdf.inputs["IOR"].default_value = ior
    set_input(bsdf, "Subsurface Anisotropy", 0.0)
    if bpy.app.version >= (4, 0, 0):
        bsdf.subsurface_method = METHOD
        bsdf.inputs["Subsurface Weight"].default_value = 1.0
        bsdf.inputs["Subsurface Radius"].default_value = radius_mm
        bsdf.inputs["Subsurface Scale"].default_value = mm
        set_input(bsdf, "Subsurface IOR", ior)
    else:
        # Principled v1: Subsurface (weight), Subsurface Color, a radius in scene units.
        bsdf.subsurface_method = METHOD_3X[METHOD]
        bsdf.inputs["Subsurface"].default_value = 1.0
        bsdf.inputs["Subsurface Color"].default_value = (*base_color, 1.0)
        bsdf.inputs["Subsurface Radius"].default_value = tuple(r * mm for r in radius_mm)
    return mat


def main():
    mm = scene_units_per_mm(bpy.context.scene)
    for name, base_color, radius_mm, ior, _a, _d in SKINS:
        apply(name, base_color, radius_mm, ior, mm)
    print(f"baker skin export: {len(SKINS)} materials, Subsurface Method {METHOD}, "
          f"Subsurface Scale {mm:g} scene units/mm")


if __name__ == "__main__":
    main()
"#;
