//! Skin profile tables (`profiles.bkt`) → the subsurface parameters of renderers
//! (`baker export profiles.bkt --to TARGET [--entry NAME] [-o FILE]`).
//!
//! Every target starts from the same per-channel Christensen–Burley fit ([`burley`]): surface
//! albedo A and shape d (mm) of R(r) = A·(e^(−r/d) + e^(−r/3d))/(8π·d·r). Each renderer then
//! takes A and d in its own convention; the formula and its source are next to each writer and
//! in the header of every file written:
//!
//! | target | file | what it holds |
//! |---|---|---|
//! | `burley` | JSON | A, d, the three mean free paths of the paper, the fit error next to the six-Gaussian error |
//! | `mtlx` | MaterialX 1.39 | one `open_pbr_surface` + `surfacematerial` per entry: `subsurface_color`, `subsurface_radius` (mm), `subsurface_radius_scale` |
//! | `blender` | Python | Principled BSDF (Blender 4.x), Christensen–Burley method: Base Color, Subsurface Weight/Radius/Scale, IOR |
//! | `unreal` | JSON | `SubsurfaceProfile` fields: SurfaceAlbedo, MeanFreePathColor, MeanFreePathDistance (cm), WorldUnitScale |
//! | `unity` | JSON | HDRP diffusion profile: scatteringDistance, scatteringDistanceMultiplier (mm), worldScale, ior, … |
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
//! All entries go into one file for every target; `--entry` keeps one.

use std::fmt::Write as _;
use std::io::Write as _;

use anyhow::Context as _;
use formats::{ProfileTable, TableIndex};
use serde_json::{json, Value};

use super::burley::{self, BurleyFit};
use super::ExportRequest;
use crate::cli::UsageError;

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

    pub fn parse(s: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == s)
    }
}

/// IOR assumed when a table carries no `surface/eta` (a typical skin value, as the defaults
/// of Unity HDRP's diffusion profile and the OpenPBR skin examples).
pub const DEFAULT_ETA: f64 = 1.4;

/// One table entry with its Burley fit.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinFit {
    pub name: String,
    /// The table's total diffuse reflectance per channel (linear sRGB).
    pub albedo_rgb: [f64; 3],
    /// 99 % radius per channel, mm (NaN: the grid ends first; then every bin is fitted).
    pub r99_mm: [f64; 3],
    pub burley: [BurleyFit; 3],
    /// The six-Gaussian fit error stored in the table (NaN if it holds none).
    pub gaussian_error_rgb: [f64; 3],
    /// Refractive index of the skin surface (`surface/eta`).
    pub eta: f64,
    /// Normal-incidence Fresnel reflectance of the surface (`surface/f0`, else from `eta`).
    pub f0: f64,
}

impl SkinFit {
    /// Fitted surface albedo A per channel.
    pub fn a_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| f.a)
    }

    /// Fitted shape d per channel, mm.
    pub fn d_mm_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| f.d_mm)
    }

    pub fn burley_error_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| f.error)
    }

    /// C = A/(1 − F0), clamped to \[0, 1\]: the albedo of the light that crossed the surface,
    /// what layered models call their subsurface colour (OpenPBR, "Subsurface").
    pub fn albedo_below_interface_rgb(&self) -> [f64; 3] {
        self.a_rgb().map(|a| (a / (1.0 - self.f0)).clamp(0.0, 1.0))
    }

    /// Volume mean free path ℓ = d·s_perpendicular(A) per channel, mm ([`burley::volume_mfp_mm`]).
    pub fn volume_mfp_mm_rgb(&self) -> [f64; 3] {
        self.burley.map(|f| burley::volume_mfp_mm(f.a, f.d_mm))
    }
}

/// Fits entry `name` of a table (`index` is the same file, for the arrays `ProfileTable` does
/// not decode: `r99_mm`, `surface/eta`, `surface/f0`).
pub fn fit_entry(table: &ProfileTable, index: &TableIndex, name: &str) -> anyhow::Result<SkinFit> {
    let data = table
        .data(name)
        .with_context(|| format!("entry {name:?}"))?;
    let f64s = |q: &str| -> anyhow::Result<Option<Vec<f64>>> {
        let full = format!("{name}/{q}");
        Ok(index
            .array(&full)
            .with_context(|| full.clone())?
            .and_then(|a| a.as_f64().map(<[f64]>::to_vec)))
    };
    // The table's own r99 (FORMAT.md); recomputed the same way if an older table lacks it.
    let r99_mm: [f64; 3] = match f64s("r99_mm")? {
        Some(v) if v.len() == 3 => [v[0], v[1], v[2]],
        _ => std::array::from_fn(|c| {
            crate::profile::rgb::radius_of_energy(
                &data.r_edges_mm,
                data.rd_rgb_per_mm2.iter().map(|v| v[c]),
                0.99 * data.albedo_rgb[c],
            )
        }),
    };
    let scalar =
        |q: &str| -> anyhow::Result<Option<f64>> { Ok(f64s(q)?.and_then(|v| v.first().copied())) };
    let eta = scalar("surface/eta")?
        .filter(|e| e.is_finite() && *e >= 1.0)
        .unwrap_or(DEFAULT_ETA);
    // Fresnel at normal incidence, ((η − 1)/(η + 1))², when the table does not store it.
    let f0 = scalar("surface/f0")?
        .filter(|f| (0.0..1.0).contains(f))
        .unwrap_or(((eta - 1.0) / (eta + 1.0)).powi(2));
    let fit = burley::fit_rgb(&data.r_edges_mm, &data.rd_rgb_per_mm2, r99_mm)
        .with_context(|| format!("Burley fit of entry {name:?}"))?;
    Ok(SkinFit {
        name: name.to_string(),
        albedo_rgb: data.albedo_rgb,
        r99_mm,
        burley: fit,
        gaussian_error_rgb: data.gaussians.error_rgb,
        eta,
        f0,
    })
}

/// Where a document came from, for its header.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Provenance {
    /// The table as given on the command line.
    pub table: String,
    pub baker_version: String,
    pub spec_file: String,
}

impl Provenance {
    fn from_table(table: &ProfileTable, path: &str) -> Provenance {
        let s = |k: &str| {
            table
                .metadata()
                .get(k)
                .map(|v| v.as_str().map_or_else(|| v.to_string(), str::to_string))
                .unwrap_or_default()
        };
        Provenance {
            table: path.to_string(),
            baker_version: s("baker_version"),
            spec_file: s("spec_file"),
        }
    }

    /// One line for a header (no `--`, so it can sit in an XML comment).
    fn line(&self, target: Target) -> String {
        let or_unknown = |s: &str| {
            if s.is_empty() {
                "(unknown)".to_string()
            } else {
                s.to_string()
            }
        };
        format!(
            "Generated by baker {} (baker export, target {}) from {} (spec {}, baked by baker {}).",
            env!("CARGO_PKG_VERSION"),
            target.name(),
            or_unknown(&self.table),
            or_unknown(&self.spec_file),
            or_unknown(&self.baker_version),
        )
    }
}

/// Runs `baker export` for a skin table.
pub fn run(req: &ExportRequest) -> anyhow::Result<()> {
    let target = Target::parse(&req.to).ok_or_else(|| {
        let names: Vec<&str> = Target::ALL.iter().map(|t| t.name()).collect();
        UsageError(format!(
            "--to {:?} is not a skin export target; allowed: {}",
            req.to,
            names.join(", ")
        ))
    })?;
    let bytes = formats::table::read_file(&req.table)?;
    let index = TableIndex::from_bytes(bytes.clone())
        .with_context(|| format!("reading {}", req.table.display()))?;
    let table = ProfileTable::from_bytes(bytes)
        .with_context(|| format!("{}: not a skin profile table", req.table.display()))?;
    // Every chunk is checked (checksums, finite values) before anything is written.
    table.verify().with_context(|| {
        format!(
            "{}: the table is damaged; nothing was exported",
            req.table.display()
        )
    })?;
    let names: Vec<String> = match &req.entry {
        Some(e) if table.position(e).is_some() => vec![e.clone()],
        Some(e) => {
            let all: Vec<&str> = table.entries().iter().map(|x| x.name.as_str()).collect();
            return Err(UsageError(format!(
                "--entry {e:?} is not in {}; allowed: {}",
                req.table.display(),
                all.join(", ")
            ))
            .into());
        }
        None => table.entries().iter().map(|x| x.name.clone()).collect(),
    };
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
    let text = write(target, &fits, &prov);
    match &req.output {
        Some(path) => {
            crate::output::atomic::write(path, text.as_bytes())
                .with_context(|| format!("writing {}", path.display()))?;
            eprintln!(
                "baker export: {} entr{} → {} ({})",
                fits.len(),
                if fits.len() == 1 { "y" } else { "ies" },
                path.display(),
                target.name()
            );
        }
        None => std::io::stdout().lock().write_all(text.as_bytes())?,
    }
    Ok(())
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

// ---------------------------------------------------------------------------------------------
// Helpers

/// `x` rounded to 7 significant digits, printed without exponent (f64 `Display`).
fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let scale = 10f64.powi(6 - x.abs().log10().floor() as i32);
    let r = (x * scale).round() / scale;
    format!("{r}")
}

fn nums(v: &[f64]) -> String {
    nums_sep(v, ", ")
}

fn nums_sep(v: &[f64], sep: &str) -> String {
    v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(sep)
}

/// `v / max(v)` and `max(v)` (a colour in \[0, 1\] and its multiplier).
fn split_max(v: [f64; 3]) -> ([f64; 3], f64) {
    let m = v.iter().copied().fold(0.0, f64::max);
    if m > 0.0 {
        (v.map(|x| x / m), m)
    } else {
        ([0.0; 3], 0.0)
    }
}

/// An identifier for MaterialX and Mitsuba: letters, digits and `_`, not starting with a
/// digit; `.` and other characters become `_`, and a clash gets a numeric suffix.
fn identifiers(fits: &[SkinFit]) -> Vec<String> {
    let mut seen = std::collections::BTreeSet::new();
    fits.iter()
        .map(|f| {
            let mut s: String = f
                .name
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect();
            if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
                s.insert(0, '_');
            }
            let mut out = s.clone();
            let mut i = 2;
            while !seen.insert(out.clone()) {
                out = format!("{s}_{i}");
                i += 1;
            }
            out
        })
        .collect()
}

/// Escapes text for an XML attribute value or element content.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Text safe inside an XML comment (no `--`).
fn xml_comment(s: &str) -> String {
    s.replace("--", "- -")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn max_finite(v: impl Iterator<Item = f64>) -> f64 {
    v.filter(|x| x.is_finite()).fold(f64::NAN, f64::max)
}

/// Median and maximum per channel of a per-entry quantity.
fn stats(fits: &[SkinFit], f: impl Fn(&SkinFit) -> [f64; 3]) -> Value {
    let ch = |c: usize| fits.iter().map(|x| f(x)[c]).collect::<Vec<_>>();
    json!({
        "median": (0..3).map(|c| median(ch(c))).collect::<Vec<_>>(),
        "max": (0..3).map(|c| max_finite(ch(c).into_iter())).collect::<Vec<_>>(),
    })
}

// ---------------------------------------------------------------------------------------------
// burley: the fit itself

/// JSON: per entry A, d, the mean free paths of the three conventions and the Burley fit error
/// next to the six-Gaussian error (both FORMAT.md's energy-weighted relative L1 error).
pub fn write_burley(fits: &[SkinFit], prov: &Provenance) -> String {
    let entries: Vec<Value> = fits
        .iter()
        .map(|f| {
            let per = |g: fn(f64, f64) -> f64| -> Vec<f64> {
                f.burley.iter().map(|b| g(b.a, b.d_mm)).collect()
            };
            json!({
                "name": f.name,
                "A_rgb": f.a_rgb(),
                "d_mm_rgb": f.d_mm_rgb(),
                "albedo_rgb": f.albedo_rgb,
                "r99_mm": f.r99_mm,
                "burley_error_rgb": f.burley_error_rgb(),
                "gaussian_error_rgb": f.gaussian_error_rgb,
                "mfp_mm_rgb": {
                    "volume_perpendicular": per(burley::volume_mfp_mm),
                    "volume_diffuse_transmission": per(burley::diffuse_transmission_mfp_mm),
                    "dmfp": per(burley::dmfp_mm),
                },
                "eta": f.eta,
                "f0": f.f0,
            })
        })
        .collect();
    let doc = json!({
        "format": "baker-burley-fit",
        "version": 1,
        "generated_by": prov.line(Target::Burley),
        "table": prov.table,
        "baker_version": prov.baker_version,
        "spec_file": prov.spec_file,
        "model": "R_c(r) = A_c (exp(-r/d_c) + exp(-r/(3 d_c))) / (8 pi d_c r), mm^-2; \
                  Christensen & Burley 2015, Pixar Tech Memo #15-04, Eq. 3",
        "annulus_energy": "A (F(b) - F(a)), F(r) = 1 - exp(-r/d)/4 - 3 exp(-r/(3d))/4 (Eq. 11)",
        "error": "energy-weighted relative L1 over annuli with r_edges_mm[k] < r99_mm[c] \
                  (formats/FORMAT.md, 'The sum-of-Gaussians fit'): the same error as \
                  gaussian_error_rgb; A is L1-optimal for each d (weighted median), d by \
                  log-grid scan and golden-section search",
        "units": {"A_rgb": "1", "d_mm_rgb": "mm", "r99_mm": "mm", "mfp_mm_rgb": "mm"},
        "conventions": {
            "volume_perpendicular": "l = d (1.85 - A + 7 |A - 0.8|^3): volume mean free path \
                1/sigma_t, perpendicular illumination (Christensen & Burley 2015); Unreal \
                GetPerpendicularScalingFactor; used for OpenPBR, pbrt-v4 and Mitsuba here",
            "volume_diffuse_transmission": "l = d (1.9 - A + 3.5 (A - 0.8)^2): volume mean \
                free path, diffuse surface transmission (Eq. 6); Cycles bssrdf_burley_fitting, \
                Chiang et al. 2016 random walk",
            "dmfp": "l_d = d (3.5 + 100 (A - 0.33)^4): diffuse mean free path; Unreal \
                GetSearchLightDiffuseScalingFactor (the Burley kernel of SubsurfaceProfile)",
        },
        "summary": {
            "entries": fits.len(),
            "burley_error_rgb": stats(fits, SkinFit::burley_error_rgb),
            "gaussian_error_rgb": stats(fits, |f| f.gaussian_error_rgb),
        },
        "entries": entries,
    });
    serde_json::to_string_pretty(&doc).expect("JSON of numbers and strings") + "\n"
}

// ---------------------------------------------------------------------------------------------
// mtlx: OpenPBR Surface in MaterialX

/// MaterialX 1.39 document, one `open_pbr_surface` and `surfacematerial` per entry.
///
/// OpenPBR specification (v1.x, "Subsurface"): `subsurface_radius × subsurface_radius_scale`
/// is the mean free path r per channel, μt = 1/r; `subsurface_color` C is the multiple-scattering
/// albedo below the interface, E_multi-scatter = (1 − E_spec)·C. So radius = max_c ℓ_c (mm,
/// `unit="millimeter"`, which MaterialX's unit system converts to the renderer's distance
/// unit), scale = ℓ/max ℓ
/// (in \[0, 1\]), ℓ = d·s_perpendicular(A) ([`burley::volume_mfp_mm`]); C = A/(1 − F0);
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

// ---------------------------------------------------------------------------------------------
// blender: Principled BSDF

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

// ---------------------------------------------------------------------------------------------
// unreal: SubsurfaceProfile

/// Unreal Engine 5 clamps `MeanFreePathDistance` below at 0.1 cm and shifts the rest into the
/// colour (`SubsurfaceProfile.cpp`, `UpgradeDiffuseMeanFreePathToMeanFreePath`, "Support
/// mfp < 0.1f").
const UNREAL_MIN_MFP_DISTANCE_CM: f64 = 0.1;
/// Unreal clamps `SurfaceAlbedo` and `MeanFreePathColor` below at this bias
/// (`FSubsurfaceProfileTexture::CreateTexture`, `Bias`).
const UNREAL_COLOR_BIAS: f64 = 0.009;

/// JSON with one `SubsurfaceProfile` per entry (Burley, mean-free-path mode).
///
/// MFP_c (cm) = 0.06·s_perpendicular(A_c)·d_c ([`burley::unreal_mfp_cm`]: Unreal converts the
/// MFP to a DMFP with `GetDiffuseMeanFreePathFromMeanFreePath`·10/`Dmfp2MfpMagicNumber` and
/// renders e^(−r·s_dmfp(A)/DMFP)); `MeanFreePathDistance` = max_c MFP_c,
/// `MeanFreePathColor` = MFP/`MeanFreePathDistance`; `SurfaceAlbedo` = A;
/// `WorldUnitScale` = 0.1, Unreal's default, at which 1 world unit = 1 cm of skin
/// (`BurleyNormalizedSSS.cpp`, `ComputeTransmissionProfileBurley`: DistanceCm·(WorldUnitScale/0.1)·10 = mm).
pub fn write_unreal(fits: &[SkinFit], prov: &Provenance) -> String {
    let entries: Vec<Value> = fits
        .iter()
        .map(|f| {
            let a = f.a_rgb();
            let mfp_cm: [f64; 3] =
                std::array::from_fn(|c| burley::unreal_mfp_cm(a[c], f.burley[c].d_mm));
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
            let lin = |v: [f64; 3]| json!({"R": v[0], "G": v[1], "B": v[2], "A": 1.0});
            json!({
                "name": f.name,
                "SubsurfaceProfile": {
                    "bEnableBurley": true,
                    "bEnableMeanFreePath": true,
                    "SurfaceAlbedo": lin(a),
                    "MeanFreePathColor": lin(color),
                    "MeanFreePathDistance": dist,
                    "WorldUnitScale": 0.1,
                    "IOR": f.eta,
                },
                "derived": {
                    "mean_free_path_cm_rgb": mfp_cm,
                    "diffuse_mean_free_path_mm_rgb": f.burley.map(|b| burley::dmfp_mm(b.a, b.d_mm)),
                    "burley_d_mm_rgb": f.d_mm_rgb(),
                    "burley_error_rgb": f.burley_error_rgb(),
                },
                "notes": notes,
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

// ---------------------------------------------------------------------------------------------
// unity: HDRP diffusion profile

/// JSON with one HDRP diffusion profile per entry.
///
/// HDRP's profile is R = S·(e^(−rS) + e^(−rS/3))/(8πr) with S = 1/(scatteringDistance ×
/// scatteringDistanceMultiplier) in millimetres (`DiffusionProfileSettings.cs`, `UpdateKernel`:
/// "shapeParam … S = 1 / D", "filterRadius … In millimeters"), so the product is d;
/// `scatteringDistance` is an LDR colour, so it is d/max d and the multiplier max d. The
/// albedo is the material's diffuse colour (A), not a profile field.
pub fn write_unity(fits: &[SkinFit], prov: &Provenance) -> String {
    let entries: Vec<Value> = fits
        .iter()
        .map(|f| {
            let (color, mult) = split_max(f.d_mm_rgb().map(burley::unity_scattering_distance_mm));
            let rgba = |v: [f64; 3]| json!({"r": v[0], "g": v[1], "b": v[2], "a": 1.0});
            json!({
                "name": f.name,
                "DiffusionProfile": {
                    "scatteringDistance": rgba(color),
                    "scatteringDistanceMultiplier": mult,
                    "transmissionTint": rgba([1.0; 3]),
                    "texturingMode": "PreAndPostScatter",
                    "transmissionMode": "ThinObject",
                    "thicknessRemap": [0.0, 5.0],
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
    let doc = json!({
        "format": "baker-unity-hdrp-diffusion-profiles",
        "version": 1,
        "generated_by": prov.line(Target::Unity),
        "engine": "Unity HDRP (Diffusion Profile asset)",
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

// ---------------------------------------------------------------------------------------------
// pbrt: pbrt-v4 subsurface material

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

// ---------------------------------------------------------------------------------------------
// mitsuba: Mitsuba 3 medium

/// Mitsuba 3 XML: per entry a `null` BSDF (`<id>_boundary`) and a `homogeneous` medium (`<id>`)
/// to put inside a closed shape, rendered with the `volpathmis` integrator.
///
/// Mitsuba 3 has no BSSRDF plugin; the closest is volumetric path tracing of the medium the
/// fit describes. Christensen–Burley's perpendicular fit relates d to a medium of isotropic
/// scatterers seen by a normally incident beam: σt = 1/ℓ, ℓ = d·s_perpendicular(A), and the
/// single-scattering albedo is the one whose normal-incidence albedo is A
/// ([`burley::single_scattering_albedo`], Chandrasekhar's H-function), for an index-matched
/// boundary: hence the `null` BSDF. `sigma_t` is an RGB colour in \[0, 1\] (Mitsuba reads it
/// as a reflectance), so it holds σt/max σt and `scale` = max σt in mm⁻¹.
///
/// Measured with Mitsuba 3.9.1 (`scalar_rgb`, uniform white light, a cube face seen head-on,
/// 64k paths per channel), for α = 0.86 and σt in the ratios 0.235 : 0.39 : 1, where the
/// exact normal-incidence albedo is 0.3526: `volpath` renders 0.323, 0.347, 0.343 (it is not
/// made for chromatic media), `volpathmis` 0.351, 0.350, 0.350. Mitsuba's scalar variants are
/// single precision and offset spawned rays by about 1e-4 × the coordinates' magnitude: an
/// index-matched cube 2000 mean free paths across rendered 8 % dark. Keep the object centred
/// near the origin and no larger than a few hundred of its smallest mean free path.
pub fn write_mitsuba(fits: &[SkinFit], prov: &Provenance) -> String {
    let ids = identifiers(fits);
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let _ = writeln!(
        s,
        "<!--\n  {}\n  Mitsuba 3: per skin entry a null boundary BSDF (id \"<entry>_boundary\") and a \
         homogeneous interior\n  medium (id \"<entry>\"), for a closed shape rendered with volpathmis (volpath gave channel-dependent\n  \
         albedos for chromatic media in our tests; single-precision ray offsets bias objects much\n  \
         larger than a few hundred of the smallest mean free path):\n    \
         <shape ...> <ref id=\"ENTRY_boundary\"/> <ref name=\"interior\" id=\"ENTRY\"/> </shape>\n  \
         Mitsuba 3 has no BSSRDF plugin; this is the medium whose searchlight profile is the fitted \
         Burley (A, d)\n  (Christensen & Burley 2015, Pixar Tech Memo #15-04): sigma_t = 1/l, \
         l = d (1.85 - A + 7|A - 0.8|^3),\n  albedo = the single-scattering albedo whose \
         normal-incidence albedo 1 - H(1) sqrt(1 - albedo) is A\n  (Chandrasekhar's H-function; \
         index-matched boundary, hence the null BSDF; isotropic phase). sigma_t holds sigma_t / max(sigma_t) and \"scale\" = max(sigma_t)\n  in 1/mm: \
         multiply scale by 1000 for a scene in metres. Colours: linear sRGB (use an *_rgb variant).\n-->",
        xml_comment(&prov.line(Target::Mitsuba))
    );
    s.push_str("<scene version=\"3.0.0\">\n");
    for (f, id) in fits.iter().zip(&ids) {
        let alpha = f.a_rgb().map(burley::single_scattering_albedo);
        let (sigma, scale) = split_max(f.volume_mfp_mm_rgb().map(|l| 1.0 / l));
        let _ = writeln!(
            s,
            "    <!-- {}: A = ({}), d = ({}) mm, Burley fit error ({}) -->\n    \
             <bsdf type=\"null\" id=\"{id}_boundary\"/>\n    \
             <medium type=\"homogeneous\" id=\"{id}\">\n        \
             <rgb name=\"albedo\" value=\"{}\"/>\n        \
             <rgb name=\"sigma_t\" value=\"{}\"/>\n        \
             <float name=\"scale\" value=\"{}\"/>\n        \
             <phase type=\"isotropic\"/>\n    \
             </medium>",
            xml_comment(&xml_escape(&f.name)),
            nums(&f.a_rgb()),
            nums(&f.d_mm_rgb()),
            nums(&f.burley_error_rgb()),
            nums(&alpha),
            nums(&sigma),
            num(scale),
        );
    }
    s.push_str("</scene>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::burley::{burley_energy, volume_mfp_mm};
    use crate::transport::RadialBins;
    use formats::{Array, TableFile};
    use std::f64::consts::PI;

    const A: [f64; 3] = [0.55, 0.3, 0.2];
    const D: [f64; 3] = [0.9, 0.25, 0.08];

    /// A two-entry skin table whose profiles are exactly Burley (A, d) (entry 2: d × 1.5).
    fn synthetic_table(dir: &std::path::Path) -> std::path::PathBuf {
        let edges = RadialBins::fine_then_log(0.01, 1.05, 40.0)
            .edges_mm()
            .to_vec();
        let nr = edges.len() - 1;
        let centres: Vec<f64> = edges.windows(2).map(|e| 0.5 * (e[0] + e[1])).collect();
        let names = ["typeI_age30_xi0.5", "typeVI_age80_xi1"];
        let meta = json!({
            "entries": serde_json::to_string(&names).unwrap(),
            "baker_version": "test",
            "spec_file": "synthetic.yaml",
        });
        let mut t = TableFile::new(formats::profile::KIND, meta);
        for (i, name) in names.iter().enumerate() {
            let d: Vec<f64> = D.iter().map(|d| d * (1.0 + 0.5 * i as f64)).collect();
            let mut rd = Vec::with_capacity(nr * 3);
            for k in 0..nr {
                let area = PI * (edges[k + 1] * edges[k + 1] - edges[k] * edges[k]);
                for c in 0..3 {
                    rd.push(A[c] * burley_energy(d[c], edges[k], edges[k + 1]) / area);
                }
            }
            let arr = |q: &str, shape: Vec<u64>, v: Vec<f64>| {
                Array::new_f64(format!("{name}/{q}"), shape, v).unwrap()
            };
            t.push(arr("r_mm", vec![nr as u64], centres.clone()))
                .unwrap();
            t.push(arr("r_edges_mm", vec![nr as u64 + 1], edges.clone()))
                .unwrap();
            t.push(arr("rd_rgb_per_mm2", vec![nr as u64, 3], rd))
                .unwrap();
            t.push(arr("albedo_rgb", vec![3], A.to_vec())).unwrap();
            t.push(arr("surface/eta", vec![], vec![1.5])).unwrap();
            t.push(arr("surface/f0", vec![], vec![0.04])).unwrap();
            if i == 0 {
                t.push(arr("gaussians/variance_mm2", vec![1], vec![1.0]))
                    .unwrap();
                t.push(arr("gaussians/weight_rgb", vec![1, 3], A.to_vec()))
                    .unwrap();
                t.push(arr("gaussians/error_rgb", vec![3], vec![0.05, 0.04, 0.03]))
                    .unwrap();
            }
        }
        let path = dir.join("profiles.bkt");
        t.write(&path, 3).unwrap();
        path
    }

    fn request(
        table: &std::path::Path,
        to: &str,
        entry: Option<&str>,
        out: &std::path::Path,
    ) -> ExportRequest {
        ExportRequest {
            table: table.to_path_buf(),
            to: to.into(),
            entry: entry.map(str::to_string),
            output: Some(out.to_path_buf()),
        }
    }

    #[test]
    fn burley_export_recovers_the_generating_profile() {
        let dir = tempfile::tempdir().unwrap();
        let table = synthetic_table(dir.path());
        let out = dir.path().join("burley.json");
        run(&request(&table, "burley", None, &out)).unwrap();
        let doc: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
        let entries = doc["entries"].as_array().unwrap();
        assert_eq!(entries.len(), 2);
        for (i, e) in entries.iter().enumerate() {
            for c in 0..3 {
                let a = e["A_rgb"][c].as_f64().unwrap();
                let d = e["d_mm_rgb"][c].as_f64().unwrap();
                let d_true = D[c] * (1.0 + 0.5 * i as f64);
                assert!((a / A[c] - 1.0).abs() < 0.01, "entry {i} ch {c}: A {a}");
                assert!((d / d_true - 1.0).abs() < 0.01, "entry {i} ch {c}: d {d}");
                let mfp = e["mfp_mm_rgb"]["volume_perpendicular"][c].as_f64().unwrap();
                assert!((mfp - volume_mfp_mm(a, d)).abs() < 1e-12);
                assert!(e["burley_error_rgb"][c].as_f64().unwrap() < 1e-6);
            }
        }
        // Gaussian errors are copied from the table; absent ones are null (NaN).
        assert_eq!(entries[0]["gaussian_error_rgb"][2].as_f64(), Some(0.03));
        assert!(entries[1]["gaussian_error_rgb"][0].is_null());
        assert_eq!(doc["summary"]["entries"].as_u64(), Some(2));
    }

    #[test]
    fn every_target_writes_every_entry() {
        let dir = tempfile::tempdir().unwrap();
        let table = synthetic_table(dir.path());
        for t in Target::ALL {
            let out = dir.path().join(format!("out.{}", t.name()));
            run(&request(&table, t.name(), None, &out)).unwrap();
            let text = std::fs::read_to_string(&out).unwrap();
            for name in ["typeI_age30_xi0", "typeVI_age80_xi1"] {
                assert!(text.contains(name), "{}: no {name}", t.name());
            }
            if matches!(t, Target::Burley | Target::Unreal | Target::Unity) {
                serde_json::from_str::<Value>(&text).unwrap();
            }
        }
        // --entry keeps one.
        let out = dir.path().join("one.mtlx");
        run(&request(&table, "mtlx", Some("typeVI_age80_xi1"), &out)).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert_eq!(text.matches("<open_pbr_surface").count(), 1);
        assert!(text.contains("SR_typeVI_age80_xi1"));
    }

    #[test]
    fn unknown_target_and_entry_are_usage_errors_listing_the_choices() {
        let dir = tempfile::tempdir().unwrap();
        let table = synthetic_table(dir.path());
        let out = dir.path().join("x");
        let e = run(&request(&table, "povray", None, &out)).unwrap_err();
        let u = e.downcast_ref::<UsageError>().expect("usage error");
        assert!(
            u.0.contains("burley, mtlx, blender, unreal, unity, pbrt, mitsuba"),
            "{}",
            u.0
        );
        let e = run(&request(&table, "unreal", Some("typeIV"), &out)).unwrap_err();
        let u = e.downcast_ref::<UsageError>().expect("usage error");
        assert!(
            u.0.contains("typeI_age30_xi0.5, typeVI_age80_xi1"),
            "{}",
            u.0
        );
        assert!(!out.exists());
    }

    fn fit_of(a: [f64; 3], d: [f64; 3]) -> SkinFit {
        SkinFit {
            name: "skin.1".into(),
            albedo_rgb: a,
            r99_mm: [1.0; 3],
            burley: std::array::from_fn(|c| BurleyFit {
                a: a[c],
                d_mm: d[c],
                error: 0.01,
            }),
            gaussian_error_rgb: [0.02; 3],
            eta: 1.5,
            f0: 0.04,
        }
    }

    #[test]
    fn engine_values_follow_the_stated_conventions() {
        let f = fit_of(A, D);
        let prov = Provenance::default();
        // Unreal: MFP (cm) = 0.06 s_perp(A) d, and back through Unreal's own chain to d.
        let u: Value =
            serde_json::from_str(&write_unreal(std::slice::from_ref(&f), &prov)).unwrap();
        let p = &u["profiles"][0]["SubsurfaceProfile"];
        let dist = p["MeanFreePathDistance"].as_f64().unwrap();
        for (c, key) in ["R", "G", "B"].iter().enumerate() {
            let mfp = p["MeanFreePathColor"][key].as_f64().unwrap() * dist;
            let d = burley::unreal_d_mm(A[c], mfp);
            assert!((d / D[c] - 1.0).abs() < 1e-12, "{key}: {d}");
            assert_eq!(p["SurfaceAlbedo"][key].as_f64(), Some(A[c]));
        }
        // Unity: colour × multiplier = d.
        let h: Value = serde_json::from_str(&write_unity(std::slice::from_ref(&f), &prov)).unwrap();
        let p = &h["profiles"][0]["DiffusionProfile"];
        let m = p["scatteringDistanceMultiplier"].as_f64().unwrap();
        for (c, key) in ["r", "g", "b"].iter().enumerate() {
            let d = p["scatteringDistance"][key].as_f64().unwrap() * m;
            assert!((d / D[c] - 1.0).abs() < 1e-12);
        }
        // MaterialX: radius × scale = ℓ, colour = A/(1 − F0).
        let x = write_mtlx(std::slice::from_ref(&f), &prov);
        let value = |name: &str| -> Vec<f64> {
            let at = x.find(&format!("name=\"{name}\"")).unwrap();
            let v = &x[at..];
            let v = &v[v.find("value=\"").unwrap() + 7..];
            v[..v.find('"').unwrap()]
                .split(',')
                .map(|t| t.trim().parse().unwrap())
                .collect()
        };
        let (radius, scale, colour) = (
            value("subsurface_radius")[0],
            value("subsurface_radius_scale"),
            value("subsurface_color"),
        );
        for c in 0..3 {
            let l = volume_mfp_mm(A[c], D[c]);
            assert!((radius * scale[c] / l - 1.0).abs() < 1e-5);
            assert!((colour[c] - A[c] / 0.96).abs() < 1e-6);
        }
        assert!(x.contains("name=\"SR_skin_1\""), "identifier: {x}");
        // Blender: radius = 4π d.
        let b = write_blender(std::slice::from_ref(&f), &prov);
        assert!(b.contains(&nums(&D.map(|d| 4.0 * PI * d))), "{b}");
        // Mitsuba: scale × sigma_t = 1/ℓ.
        let m = write_mitsuba(&[f], &prov);
        assert!(
            m.contains("id=\"skin_1_boundary\"")
                && m.contains("<medium type=\"homogeneous\" id=\"skin_1\">")
        );
    }

    #[test]
    fn unreal_small_mean_free_paths_move_into_the_colour() {
        let f = fit_of([0.5, 0.3, 0.2], [0.3, 0.1, 0.05]);
        let u: Value = serde_json::from_str(&write_unreal(&[f], &Provenance::default())).unwrap();
        let p = &u["profiles"][0]["SubsurfaceProfile"];
        assert_eq!(p["MeanFreePathDistance"].as_f64(), Some(0.1));
        let r = p["MeanFreePathColor"]["R"].as_f64().unwrap();
        let want = burley::unreal_mfp_cm(0.5, 0.3) / 0.1;
        assert!(r < 1.0 && (r - want).abs() < 1e-12, "{r} vs {want}");
    }

    #[test]
    fn identifiers_are_valid_and_unique() {
        let mut a = fit_of(A, D);
        a.name = "x0.5".into();
        let mut b = a.clone();
        b.name = "x0_5".into();
        let mut c = a.clone();
        c.name = "9lives".into();
        assert_eq!(identifiers(&[a, b, c]), ["x0_5", "x0_5_2", "_9lives"]);
        assert_eq!(num(0.012345678), "0.01234568");
        assert_eq!(num(1234.56789), "1234.568");
        assert_eq!(xml_comment("a--b"), "a- -b");
    }
}
