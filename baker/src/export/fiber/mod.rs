//! `baker export TABLE.bcsdf --to chiang|pbrt|mitsuba|blender|mtlx`: the closest Chiang et al. 2016
//! fiber to a baked BCSDF table ([`super::chiang`]), with its error, for engines that cannot
//! read the table. One file per target: [`chiang_json`], [`pbrt`], [`mitsuba`], [`blender`],
//! [`mtlx`].
//!
//! | target | writes |
//! |---|---|
//! | `chiang` | JSON: fitted parameters per channel, fit error and albedos, each engine's parameters, test evaluations of the model |
//! | `pbrt` | a pbrt-v4 `Material "hair"` statement |
//! | `mitsuba` | a Mitsuba 3 scene file holding one `<bsdf type="hair">` (load it, or `<include>` it and `<ref>` its id) |
//! | `blender` | a Python script that builds a Principled Hair BSDF (Chiang model, absorption coefficient) material |
//! | `mtlx` | a MaterialX 1.39 document: one `chiang_hair_bsdf` (pbrlib), its `surface` and `surfacematerial` (conversions in [`mtlx`]) |
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

use anyhow::Context as _;
use formats::bcsdf::Bcsdf;

use super::{Export, ExportRequest};
use crate::error::UsageError;
use channels::Channels;

pub mod blender;
mod channels;
pub mod chiang_json;
mod fit;
pub mod mitsuba;
pub mod mtlx;
pub mod pbrt;
mod summary;

pub use blender::write_blender;
pub use chiang_json::write_chiang;
pub use fit::{fit_table, FiberFit};
pub use mitsuba::write_mitsuba;
pub use mtlx::write_mtlx;
pub use pbrt::write_pbrt;

/// The `--to` values of fiber tables.
pub use super::FIBER_TARGETS as TARGETS;

/// Exports a fiber table: reads and checks it, fits the variant and writes the target's
/// document (nothing is written to disk here; see [`Export`]).
pub fn export(req: &ExportRequest) -> anyhow::Result<Export> {
    let target = TARGETS.into_iter().find(|t| *t == req.to).ok_or_else(|| {
        let skin_names = super::skin::Target::names();
        let fiber = super::TableKind {
            name: "fiber",
            file: ".bcsdf",
            targets: &TARGETS,
        };
        let skin = super::TableKind {
            name: "skin",
            file: "profiles.bkt",
            targets: &skin_names,
        };
        super::unknown_target(req, &fiber, &skin)
    })?;
    blender::refuse_method(req)?;
    let table =
        Bcsdf::open(&req.table).with_context(|| format!("reading {}", req.table.display()))?;
    // Every chunk is checked (checksums, finite values) before anything is exported.
    table.verify().with_context(|| {
        format!(
            "{}: the table is damaged; nothing was exported",
            req.table.display()
        )
    })?;
    let variant = select_variant(&table, req)?;
    check_channels(&table, req, target)?;
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
        "chiang" => write_chiang(&fit),
        "pbrt" => write_pbrt(&fit),
        "mitsuba" => write_mitsuba(&fit),
        "mtlx" => write_mtlx(&fit),
        _ => write_blender(&fit),
    };
    Ok(Export {
        text,
        target,
        summary: Some(summary::stderr_line(&fit, &req.table.display().to_string())),
        written: None,
        layout: super::Layout::File,
    })
}

/// The variant to export: `--entry` by name, else the first.
fn select_variant(table: &Bcsdf, req: &ExportRequest) -> Result<usize, UsageError> {
    let variants = &table.dir.variants;
    match req.entries.as_slice() {
        [] => Ok(0),
        [name] => variants.iter().position(|v| v == name).ok_or_else(|| {
            let names: Vec<&str> = variants.iter().map(String::as_str).collect();
            super::unknown_entry(req, ("variant", "variants"), name, &names)
        }),
        several => Err(UsageError(format!(
            "{}: a fiber export is one dye variant's fit; --entry was given {} times ({}): \
             export each variant to its own file",
            req.table.display(),
            several.len(),
            several.join(", ")
        ))),
    }
}

/// Every target but `chiang` needs RGB or wavelength channels; Blender and MaterialX need RGB.
fn check_channels(table: &Bcsdf, req: &ExportRequest, target: &str) -> Result<(), UsageError> {
    let channels = Channels::of(&table.dir.channels);
    if target != "chiang" && channels == Channels::Other {
        return Err(UsageError(format!(
            "{}: channels {} are neither R, G, B nor wavelengths (`550nm`); only --to chiang \
             can export them",
            req.table.display(),
            table.dir.channels.join(", ")
        )));
    }
    if matches!(target, "blender" | "mtlx") && channels != Channels::Rgb {
        let who = if target == "blender" {
            "Blender's Principled Hair BSDF"
        } else {
            "MaterialX's chiang_hair_bsdf"
        };
        return Err(UsageError(format!(
            "{}: {who} takes RGB; this table's channels are {} (bake it with `channels: rgb`)",
            req.table.display(),
            table.dir.channels.join(", ")
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
