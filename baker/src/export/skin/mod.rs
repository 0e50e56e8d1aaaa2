//! Skin profile tables (`profiles.bkt`) → the subsurface parameters of renderers
//! (`baker export profiles.bkt --to TARGET [--entry NAME] [-o FILE]`).
//!
//! Every target starts from the same per-channel Christensen–Burley fit
//! ([`burley`](super::burley)): surface albedo A and shape d (mm) of
//! R(r) = A·(e^(−r/d) + e^(−r/3d))/(8π·d·r). Each renderer then
//! takes A and d in its own convention; the formula and its source are next to each writer and
//! in the header of every file written:
//!
//! | target | file | what it holds |
//! |---|---|---|
//! | `burley` | JSON | A, d, the three mean free paths of the paper, the fit error next to the six-Gaussian error |
//! | `mtlx` | MaterialX 1.39 | one `open_pbr_surface` + `surfacematerial` per entry: `subsurface_color`, `subsurface_radius` (mm), `subsurface_radius_scale` |
//! | `blender` | Python | Principled BSDF (Blender 3.0 – 5.x), Subsurface Method `--method` (default Random Walk (Skin)): Base Color, Subsurface Weight/Radius/Scale, IOR, Subsurface IOR |
//! | `unreal` | Unreal Editor Python (+ JSON beside it) | a script that creates or updates `SubsurfaceProfile` assets: surface_albedo, mean_free_path_color, mean_free_path_distance (cm), world_unit_scale; `-o X.py` also writes `X.json` |
//! | `unity` | a folder (`-o DIR`) | one HDRP Diffusion Profile `.asset` (+ `.meta`) per entry: scatteringDistance, scatteringDistanceMultiplier (mm), worldScale, ior, …; `profiles.json` lists them, with the fields as JSON |
//! | `pbrt` | pbrt-v4 scene text | one `MakeNamedMaterial` of type `subsurface` per entry: reflectance, mfp, scale, eta |
//! | `mitsuba` | Mitsuba 3 XML | per entry a `null` boundary BSDF and a `homogeneous` interior medium |
//!
//! Two albedos appear. A is the table's diffuse reflectance for light arriving from air: the
//! normal-incidence Fresnel reflection F0 of the skin surface is already lost. Layered models
//! (OpenPBR, Blender's Principled BSDF, pbrt-v4's `subsurface`) put a dielectric interface on
//! top of their subsurface colour C and scale it by the energy the interface lets through, so
//! they get C = A/(1 − F0) (OpenPBR specification, "Subsurface": E_multi-scatter =
//! (1 − E_spec)·C). Screen-space models (Unreal, Unity) take A itself.
//!
//! All entries go into one file for every target but `unity` (one asset per entry);
//! `--entry` keeps one. Every skin export prints the Burley fit's error on stderr
//! ([`fit_summary`]).

//!
//! Files: [`fit`] (an entry's Burley fit, [`SkinFit`]), [`provenance`] (the header line),
//! `format` (numbers and identifiers as the documents print them), and one file per engine:
//! [`burley_json`], [`mtlx`], [`blender`], [`unreal`], [`unity`], [`pbrt`], [`mitsuba`].

use anyhow::Context as _;
use formats::{ProfileTable, TableIndex};

use super::{Export, ExportRequest};

pub mod blender;
pub mod burley_json;
pub mod fit;
mod format;
pub mod mitsuba;
pub mod mtlx;
pub mod pbrt;
pub mod provenance;
pub mod unity;
pub mod unreal;

pub use blender::{method_of, write_blender, write_blender_with};
pub use burley_json::write_burley;
pub use fit::{fit_entry, SkinFit};
pub use mitsuba::write_mitsuba;
pub use mtlx::write_mtlx;
pub use pbrt::write_pbrt;
pub use provenance::Provenance;
pub use unity::{unity_files, write_unity, UNITY_FORMAT, UNITY_INDEX};
pub use unreal::{write_unreal, write_unreal_script};

/// An export target of a skin table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    Burley,
    Mtlx,
    Blender,
    Unreal,
    Unity,
    Pbrt,
    Mitsuba,
}

impl Target {
    pub const ALL: [Target; 7] = [
        Target::Burley,
        Target::Mtlx,
        Target::Blender,
        Target::Unreal,
        Target::Unity,
        Target::Pbrt,
        Target::Mitsuba,
    ];

    /// The name given to `--to`.
    pub fn name(self) -> &'static str {
        match self {
            Target::Burley => "burley",
            Target::Mtlx => "mtlx",
            Target::Blender => "blender",
            Target::Unreal => "unreal",
            Target::Unity => "unity",
            Target::Pbrt => "pbrt",
            Target::Mitsuba => "mitsuba",
        }
    }

    /// Every `--to` name, in [`Target::ALL`] order.
    pub fn names() -> [&'static str; 7] {
        Target::ALL.map(Target::name)
    }

    pub fn parse(s: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == s)
    }
}

/// IOR assumed when a table carries no `surface/eta` (a typical skin value, as the defaults
/// of Unity HDRP's diffusion profile and the OpenPBR skin examples).
pub const DEFAULT_ETA: f64 = 1.4;

/// Exports a skin table: reads and checks it, fits the selected entries and writes the
/// target's document (nothing is written to disk here; see [`Export`]).
pub fn export(req: &ExportRequest) -> anyhow::Result<Export> {
    let target = Target::parse(&req.to).ok_or_else(|| {
        let names = Target::names();
        let skin = super::TableKind {
            name: "skin",
            file: "profiles.bkt",
            targets: &names,
        };
        let fiber = super::TableKind {
            name: "fiber",
            file: ".bcsdf",
            targets: &super::FIBER_TARGETS,
        };
        super::unknown_target(req, &skin, &fiber)
    })?;
    let method = method_of(req, target)?;
    let (table, index) = read_table(req)?;
    let names = select_entries(&table, req)?;
    let fits = names
        .iter()
        .map(|n| fit_entry(&table, &index, n))
        .collect::<anyhow::Result<Vec<_>>>()?;
    // A fit that is not finite would write `null` or NaN parameters into a renderer's file.
    if let Some(f) = fits.iter().find(|f| {
        !(f.eta.is_finite() && f.f0.is_finite())
            || f.burley
                .iter()
                .any(|b| !(b.a.is_finite() && b.d_mm.is_finite() && b.d_mm > 0.0))
    }) {
        return Err(anyhow::anyhow!(
            "{}: entry {}: the Burley fit is not finite (A, d = {:?}); nothing was exported",
            req.table.display(),
            f.name,
            f.burley.iter().map(|b| (b.a, b.d_mm)).collect::<Vec<_>>()
        ));
    }
    let prov = Provenance::from_table(&table, &req.table.display().to_string());
    Ok(Export {
        text: match target {
            Target::Blender => write_blender_with(&fits, &prov, method),
            Target::Unreal => write_unreal_script(&fits, &prov),
            _ => write(target, &fits, &prov),
        },
        target: target.name(),
        summary: Some(fit_summary(&fits, &req.table.display().to_string())),
        written: Some(format!(
            "{} entr{}",
            fits.len(),
            if fits.len() == 1 { "y" } else { "ies" }
        )),
        layout: layout(target, &fits, &prov),
    })
}

/// Where a skin target's documents go: Unreal's script with its JSON beside it, Unity's
/// folder of assets ([`unity`]), one file for the rest.
fn layout(target: Target, fits: &[SkinFit], prov: &Provenance) -> super::Layout {
    match target {
        Target::Unreal => super::Layout::WithSide {
            ext: "json",
            text: write_unreal(fits, prov),
            what: "the profiles' fields as JSON",
        },
        Target::Unity => super::Layout::Folder {
            files: unity_files(fits, prov),
            index: UNITY_INDEX.to_string(),
            format: UNITY_FORMAT,
        },
        _ => super::Layout::File,
    }
}

/// The line printed on stderr for every skin export: per channel, the Burley fit's error
/// (energy-weighted relative L1 inside r99, as `burley_error_rgb`) of the worst entry, and
/// the median over the entries.
pub fn fit_summary(fits: &[SkinFit], table: &str) -> String {
    let channels = ["R", "G", "B"].iter().enumerate().map(|(c, ch)| {
        let mut e: Vec<(f64, &str)> = fits
            .iter()
            .map(|f| (f.burley_error_rgb()[c], f.name.as_str()))
            .collect();
        e.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (worst, name) = e.last().copied().unwrap_or((f64::NAN, "-"));
        let median = e.get(e.len() / 2).map_or(f64::NAN, |m| m.0);
        format!("{ch} {worst:.4} ({name}), median {median:.4}")
    });
    format!(
        "{table}: Burley fit of {} entr{}, relative L1 error inside r99 (energy-weighted); \
         worst entry per channel: {}",
        fits.len(),
        if fits.len() == 1 { "y" } else { "ies" },
        channels.collect::<Vec<_>>().join("; ")
    )
}

/// The table of `req` decoded twice (as a profile table and as an index of its arrays), every
/// chunk checked (checksums, finite values) before anything is exported.
fn read_table(req: &ExportRequest) -> anyhow::Result<(ProfileTable, TableIndex)> {
    let bytes = formats::table::read_file(&req.table)?;
    let index = TableIndex::from_bytes(bytes.clone())
        .with_context(|| format!("reading {}", req.table.display()))?;
    let table = ProfileTable::from_bytes(bytes)
        .with_context(|| format!("{}: not a skin profile table", req.table.display()))?;
    table.verify().with_context(|| {
        format!(
            "{}: the table is damaged; nothing was exported",
            req.table.display()
        )
    })?;
    Ok((table, index))
}

/// The entries to export: each `--entry` (in the order given; each must be in the table), or
/// every entry.
fn select_entries(table: &ProfileTable, req: &ExportRequest) -> anyhow::Result<Vec<String>> {
    if req.entries.is_empty() {
        return Ok(table.entries().iter().map(|x| x.name.clone()).collect());
    }
    if let Some(e) = req.entries.iter().find(|e| table.position(e).is_none()) {
        let all: Vec<&str> = table.entries().iter().map(|x| x.name.as_str()).collect();
        return Err(super::unknown_entry(req, ("entry", "entries"), e, &all).into());
    }
    Ok(req.entries.clone())
}

/// The document of `target` for `fits`.
pub fn write(target: Target, fits: &[SkinFit], prov: &Provenance) -> String {
    match target {
        Target::Burley => write_burley(fits, prov),
        Target::Mtlx => write_mtlx(fits, prov),
        Target::Blender => write_blender(fits, prov),
        Target::Unreal => write_unreal(fits, prov),
        Target::Unity => write_unity(fits, prov),
        Target::Pbrt => write_pbrt(fits, prov),
        Target::Mitsuba => write_mitsuba(fits, prov),
    }
}

#[cfg(test)]
pub(crate) mod tests;
