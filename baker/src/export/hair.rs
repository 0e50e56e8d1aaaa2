//! `baker export TABLE.bcsdf --to chiang|pbrt|mitsuba|blender`: the closest Chiang et al. 2016
//! fiber to a baked BCSDF table ([`super::chiang`]), with its error, for engines that cannot
//! read the table.
//!
//! | target | writes |
//! |---|---|
//! | `chiang` | JSON: fitted parameters per channel, fit error and albedos, each engine's parameters, test evaluations of the model |
//! | `pbrt` | a pbrt-v4 `Material "hair"` statement |
//! | `mitsuba` | a Mitsuba 3 scene file holding one `<bsdf type="hair">` (load it, or `<include>` it and `<ref>` its id) |
//! | `blender` | a Python script that builds a Principled Hair BSDF (Chiang model, absorption coefficient) material |
//!
//! The parameter conversions, each with its source:
//! - Mitsuba 3 (`src/bsdfs/hair.cpp`): the fit *is* Mitsuba's model, so `int_ior` = η with
//!   `ext_ior` = 1 (the plugin divides them; its default exterior is air, 1.000277),
//!   `sigma_a` = σa (per unit radius: `transmitted_length = 2 cos γt / cos θt`),
//!   `longitudinal_roughness` = β_m, `azimuthal_roughness` = β_n, `scale_tilt` = α in degrees.
//! - pbrt-v4 (`src/pbrt/materials.cpp` `HairMaterial::Create`, `src/pbrt/bxdfs.cpp`
//!   `HairBxDF`): `sigma_a` = σa, `eta` = η, `beta_m`, `beta_n`, `alpha` = α in degrees. Its
//!   `HairBxDF::f` is Mitsuba's `eval` with pbrt's `wo` in the role of Mitsuba's `si.wi` (same
//!   v, s polynomials, same tilt of the `wo` side by −2α/+α/+4α, same I₀ approximations).
//! - Blender / Cycles (`intern/cycles/kernel/svm/closure.h`,
//!   `intern/cycles/kernel/closure/bsdf_principled_hair_chiang.h`): Roughness = β_m and Radial
//!   Roughness = β_n (mapped to v and s by the same polynomials), Coat = 0 (the R lobe's
//!   roughness is (1 − Coat)·β_m), IOR = η, Absorption Coefficient = σa (same chord length),
//!   and **Offset = −α in radians**: `hair_alpha_angles` tilts the light side by +2α for R,
//!   so Cycles' R lobe peaks at θi + θo = −2·Offset where Mitsuba's and pbrt's peak at +2α.
//!
//! In every engine the fiber axis of the table (+z, the tip for cuticle scales) is the curve
//! direction, first control point to last.
//!
//! The `chiang` JSON: `parameters` (`eta`, `eta_fixed`, `sigma_a` per channel and per unit
//! radius, `mua_per_mm` where the table gives `diameter_um`, `beta_m`, `beta_n`,
//! `alpha_deg`), `fit` (`rel_l1`, `rel_l2`, per channel, `noise_l1_estimate`, `albedo_table`,
//! `albedo_model`, the sampled `theta_i_deg` and `phi_i_deg`), `targets` (each engine's
//! parameter names and values, with the source file), `conventions`, `table_metadata`, and
//! `tests`: evaluations of the model that an engine must reproduce, `near` (Mitsuba's `eval`
//! at `wi_local`, `wo_local`) and `far` (averaged over h by `panels` × 8 Gauss–Legendre nodes
//! in γ = asin h), each with `value` per channel, sr⁻¹.

use std::io::Write as _;

use anyhow::Context as _;
use formats::bcsdf::Bcsdf;
use serde_json::json;

use super::chiang::{self, Chiang, FitOptions, FitReport, FitTarget, TestEvaluation};
use super::ExportRequest;
use crate::cli::UsageError;
use crate::output::atomic;

/// The `--to` values of fiber tables.
pub const TARGETS: [&str; 4] = ["chiang", "pbrt", "mitsuba", "blender"];

/// A table, its variant and the fit.
#[derive(Debug, Clone)]
pub struct HairFit {
    /// The table's path as given.
    pub table: String,
    pub variant: String,
    pub channels: Vec<String>,
    /// The table's provenance (`metadata` of its directory).
    pub metadata: serde_json::Value,
    pub report: FitReport,
    /// The table's own Monte Carlo noise in the fit's error measure
    /// ([`FitTarget::noise_l1`]), when the metadata gives the photon count.
    pub noise_l1: Option<f64>,
    pub tests: Vec<TestEvaluation>,
}

/// Runs a fiber export.
pub fn run(req: &ExportRequest) -> anyhow::Result<()> {
    let target = req.to.as_str();
    if !TARGETS.contains(&target) {
        return Err(UsageError(format!(
            "unknown fiber export target {:?}; allowed: {}",
            req.to,
            TARGETS.join(", ")
        ))
        .into());
    }
    let table =
        Bcsdf::open(&req.table).with_context(|| format!("reading {}", req.table.display()))?;
    // Every chunk is checked (checksums, finite values) before anything is written.
    table.verify().with_context(|| {
        format!(
            "{}: the table is damaged; nothing was exported",
            req.table.display()
        )
    })?;
    let variants = &table.dir.variants;
    let variant = match &req.entry {
        None => 0,
        Some(name) => variants.iter().position(|v| v == name).ok_or_else(|| {
            UsageError(format!(
                "{}: no variant {name:?}; allowed: {}",
                req.table.display(),
                variants.join(", ")
            ))
        })?,
    };
    let channels = Channels::of(&table.dir.channels);
    if target != "chiang" && channels == Channels::Other {
        return Err(UsageError(format!(
            "{}: channels {} are neither R, G, B nor wavelengths (`550nm`); only --to chiang \
             can export them",
            req.table.display(),
            table.dir.channels.join(", ")
        ))
        .into());
    }
    if target == "blender" && channels != Channels::Rgb {
        return Err(UsageError(format!(
            "{}: Blender's Principled Hair BSDF takes RGB; this table's channels are {} \
             (bake it with `channels: rgb`)",
            req.table.display(),
            table.dir.channels.join(", ")
        ))
        .into());
    }
    let fit = fit_table(&table, variant, &req.table.display().to_string())?;
    let p = &fit.report.params;
    let finite = [p.eta, p.beta_m, p.beta_n, p.alpha_deg, fit.report.rel_l1]
        .iter()
        .chain(&p.sigma_a)
        .all(|x| x.is_finite());
    if !finite {
        return Err(anyhow::anyhow!(
            "{}: the Chiang fit is not finite; nothing was exported",
            req.table.display()
        ));
    }
    let text = match target {
        "chiang" => chiang_json(&fit),
        "pbrt" => pbrt(&fit),
        "mitsuba" => mitsuba(&fit),
        _ => blender(&fit),
    };
    let r = &fit.report;
    eprintln!(
        "{} [{}]: Chiang fit relative L1 {:.3} (L2 {:.3}) over {} θi × {} φi; η {:.4}{}, β_m {:.3}, \
         β_n {:.3}, α {:.2}°, σa {}",
        req.table.display(),
        fit.variant,
        r.rel_l1,
        r.rel_l2,
        r.theta_i_deg.len(),
        r.phi_i_deg.len(),
        r.params.eta,
        if r.eta_fixed { " (table)" } else { "" },
        r.params.beta_m,
        r.params.beta_n,
        r.params.alpha_deg,
        list(&r.params.sigma_a, ", "),
    );
    match &req.output {
        Some(path) => atomic::write(path, text.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?,
        None => {
            let mut out = std::io::stdout().lock();
            out.write_all(text.as_bytes())?;
            out.flush()?;
        }
    }
    Ok(())
}

/// Fits variant `variant` of `table` (η from the table's metadata when it has one).
pub fn fit_table(table: &Bcsdf, variant: usize, name: &str) -> Result<HairFit, chiang::FitError> {
    let eta = table.dir.metadata["eta"]
        .as_f64()
        .filter(|e| e.is_finite() && *e > 1.0);
    let opts = FitOptions {
        eta,
        ..FitOptions::default()
    };
    let target = FitTarget::from_table(table, variant, &opts)?;
    let report = chiang::fit(&target, &opts);
    let noise_l1 = table.dir.metadata["photons_per_direction"]
        .as_f64()
        .filter(|n| *n > 0.0)
        .map(|n| target.noise_l1(n));
    let tests = chiang::test_evaluations(&Chiang::new(report.params.clone()));
    Ok(HairFit {
        table: name.to_string(),
        variant: table.dir.variants[variant].clone(),
        channels: table.dir.channels.clone(),
        metadata: table.dir.metadata.clone(),
        report,
        noise_l1,
        tests,
    })
}

/// What the channels of a table are.
#[derive(Debug, Clone, PartialEq)]
enum Channels {
    /// `R`, `G`, `B` (linear sRGB, D65).
    Rgb,
    /// Wavelengths in nm (`550nm`, …).
    Spectral(Vec<f64>),
    Other,
}

impl Channels {
    fn of(names: &[String]) -> Self {
        if names == ["R", "G", "B"] {
            return Channels::Rgb;
        }
        let nm: Option<Vec<f64>> = names
            .iter()
            .map(|n| n.strip_suffix("nm").and_then(|x| x.trim().parse().ok()))
            .collect();
        match nm {
            Some(l) if !l.is_empty() => Channels::Spectral(l),
            _ => Channels::Other,
        }
    }
}

fn list(v: &[f64], sep: &str) -> String {
    v.iter()
        .map(|x| format!("{x:.6}"))
        .collect::<Vec<_>>()
        .join(sep)
}

/// Fiber radius in mm from the table's `diameter_um`, if any.
fn radius_mm(metadata: &serde_json::Value) -> Option<f64> {
    metadata["diameter_um"]
        .as_f64()
        .filter(|d| d.is_finite() && *d > 0.0)
        .map(|d| 0.5e-3 * d)
}

/// Blender's Offset socket, radians: −α (see the module docs).
fn blender_offset_rad(alpha_deg: f64) -> f64 {
    // Cycles bsdf_principled_hair_chiang.h hair_alpha_angles: R peak at θi + θo = −2·Offset;
    // Mitsuba hair.cpp reframe_with_scales: at θi + θo = +2α.
    -alpha_deg.to_radians()
}

/// Lines of the fit summary shared by the text formats.
fn summary(fit: &HairFit) -> Vec<String> {
    let r = &fit.report;
    let ch = fit.channels.join(" ");
    vec![
        format!("table {} (variant {})", fit.table, fit.variant),
        format!(
            "Chiang et al. 2016 fit, as Mitsuba 3 hair.cpp evaluates it, averaged over the fiber width: \
             relative L1 error of f over the table's bins {:.4} (L2 {:.4}), per channel {ch}: L1 {}",
            r.rel_l1,
            r.rel_l2,
            list(&r.rel_l1_per_channel, " ")
        ),
        match fit.noise_l1 {
            Some(n) => format!(
                "the table's own Monte Carlo noise accounts for about {n:.4} of that (L1 of \
                 photon-count noise, an estimate)"
            ),
            None => "the table's noise level is unknown (no photon count in its metadata)".into(),
        },
        format!(
            "albedo {ch}: table {}, model {} (mean over θi {} deg; φi averaged: {} samples)",
            list(&r.albedo_table, " "),
            list(&r.albedo_model, " "),
            r.theta_i_deg
                .iter()
                .map(|t| format!("{t:.0}"))
                .collect::<Vec<_>>()
                .join(" "),
            r.phi_i_deg.len()
        ),
        format!(
            "eta {:.4}{}, beta_m {:.4}, beta_n {:.4}, alpha {:.3} deg, sigma_a (per fiber radius) {}",
            r.params.eta,
            if r.eta_fixed {
                " (from the table)"
            } else {
                " (fitted)"
            },
            r.params.beta_m,
            r.params.beta_n,
            r.params.alpha_deg,
            list(&r.params.sigma_a, " ")
        ),
        "fiber axis: the table's +z (the tip for cuticle scales) = the curve direction, first \
         control point to last"
            .to_string(),
    ]
}

/// The `chiang` target: everything, as JSON.
pub fn chiang_json(fit: &HairFit) -> String {
    let r = &fit.report;
    let p = &r.params;
    let mua =
        radius_mm(&fit.metadata).map(|rmm| p.sigma_a.iter().map(|s| s / rmm).collect::<Vec<_>>());
    let doc = json!({
        "format": "baker-chiang-hair-fit",
        "version": 1,
        "model": "Chiang et al. 2016 (Computer Graphics Forum 35(2)), far field: averaged over \
                  the fiber width h, evaluated as Mitsuba 3 src/bsdfs/hair.cpp (baker/src/export/chiang.rs)",
        "table": fit.table,
        "variant": fit.variant,
        "channels": fit.channels,
        "table_metadata": fit.metadata,
        "parameters": {
            "eta": p.eta,
            "eta_fixed": r.eta_fixed,
            "sigma_a": p.sigma_a,
            "sigma_a_units": "per unit fiber radius (dimensionless mu_a * r): the chord length in \
                              hair.cpp, pbrt-v4 bxdfs.cpp and Cycles is 2 cos(gamma_t)/cos(theta_t) radii",
            "mua_per_mm": mua,
            "beta_m": p.beta_m,
            "beta_n": p.beta_n,
            "alpha_deg": p.alpha_deg,
        },
        "fit": {
            "objective": "relative L1 error of f = albedo * f_normalised over the table's bins: \
                          sum |model - table| dOmega / sum table dOmega over the sampled theta_i, \
                          all theta_o x dphi bins and channels; the model is integrated over each bin; \
                          the table is averaged over the sampled phi_i",
            "rel_l1": r.rel_l1,
            "rel_l2": r.rel_l2,
            "rel_l1_per_channel": r.rel_l1_per_channel,
            "rel_l2_per_channel": r.rel_l2_per_channel,
            "noise_l1_estimate": fit.noise_l1,
            "albedo_table": r.albedo_table,
            "albedo_model": r.albedo_model,
            "theta_i_deg": r.theta_i_deg,
            "phi_i_deg": r.phi_i_deg,
            "evaluations": r.evaluations,
        },
        "targets": {
            "mitsuba": {
                "source": "mitsuba3 src/bsdfs/hair.cpp",
                "int_ior": p.eta, "ext_ior": 1.0, "sigma_a": p.sigma_a,
                "longitudinal_roughness": p.beta_m, "azimuthal_roughness": p.beta_n,
                "scale_tilt": p.alpha_deg,
            },
            "pbrt": {
                "source": "pbrt-v4 src/pbrt/materials.cpp HairMaterial::Create, src/pbrt/bxdfs.cpp HairBxDF",
                "sigma_a": p.sigma_a, "eta": p.eta, "beta_m": p.beta_m, "beta_n": p.beta_n,
                "alpha": p.alpha_deg,
            },
            "blender": {
                "source": "Blender intern/cycles/kernel/svm/closure.h, \
                           intern/cycles/kernel/closure/bsdf_principled_hair_chiang.h",
                "model": "Chiang", "parametrization": "Absorption coefficient",
                "Absorption Coefficient": p.sigma_a, "Roughness": p.beta_m,
                "Radial Roughness": p.beta_n, "Coat": 0.0, "IOR": p.eta,
                "Offset_rad": blender_offset_rad(p.alpha_deg), "Random Roughness": 0.0,
            },
        },
        "conventions": {
            "table_frame": "fiber axis +z; theta = asin(w.z), phi = atan2(w.y, w.x), dphi = phi_o - phi_i; \
                            w_i points towards the light",
            "mitsuba_local_frame": "hair.cpp: fiber tangent = local y, surface normal = local z; \
                                    sin(theta) = w.y, phi = atan2(w.z, w.x), h = sin(gamma(w_i)) = -x/sqrt(x^2+z^2); \
                                    table (x, y, z) = local (x, z, y)",
            "roles": "the table's w_i is the engine's wi (Mitsuba si.wi, pbrt wo); by the fiber's \
                      reciprocity that is the radiance a renderer needs",
            "alpha_sign": "Mitsuba/pbrt: R lobe peaks at theta_i + theta_o = +2 alpha; Cycles: at -2 Offset",
            "tests": "near: Mitsuba Hair::eval with si.wi = wi_local (si.sh_frame = identity), wo = wo_local; \
                      far: (1/2) integral over h in [-1, 1] of the near value at wi = (-h cos ti, sin ti, sqrt(1-h^2) cos ti), \
                      wo at theta_o and azimuth phi(wi) + dphi",
        },
        "tests": fit.tests,
    });
    let mut s = serde_json::to_string_pretty(&doc).expect("serialisable");
    s.push('\n');
    s
}

/// pbrt-v4 `rgb`/`spectrum` value of σa.
fn pbrt_sigma_a(fit: &HairFit) -> String {
    let s = &fit.report.params.sigma_a;
    match Channels::of(&fit.channels) {
        Channels::Spectral(nm) => format!(
            "\"spectrum sigma_a\" [ {} ]",
            nm.iter()
                .zip(s)
                .map(|(l, v)| format!("{l} {v:.6}"))
                .collect::<Vec<_>>()
                .join(" ")
        ),
        _ => format!("\"rgb sigma_a\" [ {} ]", list(s, " ")),
    }
}

/// The `pbrt` target: a pbrt-v4 `Material "hair"` statement.
pub fn pbrt(fit: &HairFit) -> String {
    let p = &fit.report.params;
    let mut s = String::from("# pbrt-v4 hair material written by `baker export --to pbrt`.\n");
    for line in summary(fit) {
        s += &format!("# {line}\n");
    }
    s += "# Parameters (pbrt-v4 src/pbrt/materials.cpp HairMaterial::Create, src/pbrt/bxdfs.cpp HairBxDF):\n\
          #   sigma_a per unit fiber radius (HairBxDF's chord is 2 cos(gamma_t)/cos(theta_t) radii);\n\
          #   beta_m, beta_n as in Chiang et al. 2016; alpha in degrees, the sign HairBxDF uses.\n\
          # Use it on \"curve\" shapes (type \"cylinder\") whose direction is the fiber's +z.\n";
    s += &format!(
        "Material \"hair\"\n    {}\n    \"float eta\" [ {:.6} ]\n    \"float beta_m\" [ {:.6} ]\n    \
         \"float beta_n\" [ {:.6} ]\n    \"float alpha\" [ {:.6} ]\n",
        pbrt_sigma_a(fit),
        p.eta,
        p.beta_m,
        p.beta_n,
        p.alpha_deg
    );
    s
}

/// Text safe inside an XML comment (no `--`).
fn xml_comment(text: &str) -> String {
    text.replace("--", "- -")
}

/// An XML id from a variant name.
fn xml_id(variant: &str) -> String {
    let body: String = variant
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("hair_{body}")
}

/// The `mitsuba` target: a Mitsuba 3 scene file with one named `hair` BSDF.
pub fn mitsuba(fit: &HairFit) -> String {
    let p = &fit.report.params;
    let mut s = String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    s += "<!-- Mitsuba 3 hair BSDF written by baker export (target mitsuba).\n";
    for line in summary(fit) {
        s += &format!("     {}\n", xml_comment(&line));
    }
    s += "     Parameters (mitsuba3 src/bsdfs/hair.cpp): the fitted model is this plugin's;\n\
          \x20    int_ior/ext_ior = eta (ext_ior defaults to air, 1.000277, so it is set to 1);\n\
          \x20    sigma_a per unit fiber radius; scale_tilt in degrees.\n\
          \x20    Use: <include filename=\"this file\"/> in a scene, then <ref id=\"ID\"/> in a\n\
          \x20    bsplinecurve shape (its local y, the curve direction, is the fiber's +z). -->\n";
    let id = xml_id(&fit.variant);
    s += "<scene version=\"3.0.0\">\n";
    s += &format!("    <bsdf type=\"hair\" id=\"{id}\">\n");
    s += &format!("        <float name=\"int_ior\" value=\"{:.6}\"/>\n", p.eta);
    s += "        <float name=\"ext_ior\" value=\"1.0\"/>\n";
    match Channels::of(&fit.channels) {
        Channels::Spectral(nm) => {
            s += &format!(
                "        <spectrum name=\"sigma_a\" value=\"{}\"/>\n",
                nm.iter()
                    .zip(&p.sigma_a)
                    .map(|(l, v)| format!("{l}:{v:.6}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
        _ => {
            s += &format!(
                "        <rgb name=\"sigma_a\" value=\"{}\"/>\n",
                list(&p.sigma_a, ", ")
            )
        }
    }
    s += &format!(
        "        <float name=\"longitudinal_roughness\" value=\"{:.6}\"/>\n",
        p.beta_m
    );
    s += &format!(
        "        <float name=\"azimuthal_roughness\" value=\"{:.6}\"/>\n",
        p.beta_n
    );
    s += &format!(
        "        <float name=\"scale_tilt\" value=\"{:.6}\"/>\n",
        p.alpha_deg
    );
    s += "    </bsdf>\n</scene>\n";
    s
}

/// The `blender` target: a Python script for Blender (3.x and 4.x) that builds the material.
pub fn blender(fit: &HairFit) -> String {
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
        "import bpy\n\nMATERIAL = {:?}\nSIGMA_A = ({})\nBETA_M = {:.6}\nBETA_N = {:.6}\n\
         IOR = {:.6}\nOFFSET_RAD = {:.8}  # alpha = {:.4} deg\n\n",
        format!("baker {}", fit.variant),
        list(&p.sigma_a, ", "),
        p.beta_m,
        p.beta_n,
        p.eta,
        blender_offset_rad(p.alpha_deg),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::chiang::ChiangParams;

    fn fit() -> HairFit {
        let params = ChiangParams {
            eta: 1.635,
            sigma_a: vec![0.1, 0.5, 2.0],
            beta_m: 0.2,
            beta_n: 0.35,
            alpha_deg: -2.5,
        };
        HairFit {
            table: "t.bcsdf".into(),
            variant: "disperse_red_1@1%".into(),
            channels: vec!["R".into(), "G".into(), "B".into()],
            metadata: json!({"diameter_um": 10.0}),
            report: FitReport {
                params: params.clone(),
                eta_fixed: true,
                rel_l1: 0.2,
                rel_l2: 0.3,
                rel_l1_per_channel: vec![0.2; 3],
                rel_l2_per_channel: vec![0.3; 3],
                albedo_table: vec![0.9, 0.5, 0.4],
                albedo_model: vec![0.88, 0.52, 0.41],
                theta_i_deg: vec![-30.0, 30.0],
                phi_i_deg: vec![0.0],
                evaluations: 1,
            },
            noise_l1: Some(0.05),
            tests: vec![],
        }
    }

    #[test]
    fn writers_carry_the_parameters_in_each_engines_units() {
        let f = fit();
        let x = mitsuba(&f);
        assert!(x.contains("<bsdf type=\"hair\" id=\"hair_disperse_red_1_1_\">"));
        assert!(x.contains("<float name=\"scale_tilt\" value=\"-2.500000\"/>"));
        assert!(x.contains("<rgb name=\"sigma_a\" value=\"0.100000, 0.500000, 2.000000\"/>"));
        // No "--" inside XML comments.
        let comments: Vec<&str> = x.split("<!--").skip(1).collect();
        assert!(comments
            .iter()
            .all(|c| !c.split("-->").next().unwrap().contains("--")));
        let p = pbrt(&f);
        assert!(p.contains("\"rgb sigma_a\" [ 0.100000 0.500000 2.000000 ]"));
        assert!(p.contains("\"float alpha\" [ -2.500000 ]"));
        let b = blender(&f);
        assert!(b.contains(&format!("OFFSET_RAD = {:.8}", 2.5f64.to_radians())));
        let j: serde_json::Value = serde_json::from_str(&chiang_json(&f)).unwrap();
        assert_eq!(j["parameters"]["beta_n"], 0.35);
        let mua = j["parameters"]["mua_per_mm"][2].as_f64().unwrap();
        assert!((mua - 2.0 / 0.005).abs() < 1e-9);
    }

    /// Fits the tables listed in `BAKER_HAIR_TABLES` (`:`-separated) and prints the result:
    /// `BAKER_HAIR_TABLES=a.bcsdf:b.bcsdf cargo test -p baker --lib fit_listed -- --ignored
    /// --nocapture`.
    #[test]
    #[ignore]
    fn fit_listed_tables() {
        let list = std::env::var("BAKER_HAIR_TABLES").unwrap_or_default();
        for path in list.split(':').filter(|p| !p.is_empty()) {
            let t = Bcsdf::open(path).unwrap();
            for v in 0..t.dir.variants.len() {
                let start = std::time::Instant::now();
                let f = fit_table(&t, v, path).unwrap();
                eprintln!("{:.1} s", start.elapsed().as_secs_f64());
                for line in summary(&f) {
                    eprintln!("  {line}");
                }
            }
        }
    }

    #[test]
    fn spectral_channels_become_spectra() {
        let mut f = fit();
        f.channels = vec!["450nm".into(), "550nm".into(), "650nm".into()];
        assert!(mitsuba(&f).contains("value=\"450:0.100000, 550:0.500000, 650:2.000000\""));
        assert!(
            pbrt(&f).contains("\"spectrum sigma_a\" [ 450 0.100000 550 0.500000 650 2.000000 ]")
        );
    }
}
