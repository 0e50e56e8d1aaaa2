//! Fiber specs (`specs/fibers.yaml`): dyes and fiber entries, validated with file:line:column
//! like skin specs. Section files (CSV outlines, mask images) and dye spectra are read here,
//! relative to the spec's folder, so a bad file is reported against the line that names it.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::error::{SpecError, SpecErrors};
use super::limits::{count_text, Limits};
use super::names;
use super::raw::Spanned;
use super::resolve::{loc, parse_plain, parse_yaml, Ctx};
use crate::fiber::bake::BakeSettings;
use crate::fiber::dye::{self, Band, Dye, DyeClass, Spectrum};
use crate::fiber::material::{FiberType, TABLE_9, WOOL_SCALE_LENGTH_UM, WOOL_SCALE_TILT_DEG};
use crate::fiber::section::generate::{generate, Shape};
use crate::fiber::section::mask::{from_mask, MaskOptions};
use crate::fiber::sweep::ChannelKind;
use crate::fiber::symmetry::{self, Symmetry};
use crate::fiber::{Cuticle, Fiber, Section, Surface};
use formats::Precision;

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RawFiberSpec {
    pub version: Option<Spanned<u32>>,
    #[serde(default)]
    pub dyes: Vec<Spanned<RawDye>>,
    #[serde(default)]
    pub fibers: Vec<Spanned<RawFiber>>,
    pub bake: Option<Spanned<RawBake>>,
    /// Resource budgets ([`super::limits`]).
    pub limits: Option<Spanned<super::limits::RawLimits>>,
}

/// `bake:` — how `baker bake` tabulates the BCSDFs (all optional).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawBake {
    pub resolution_deg: Option<Spanned<f64>>,
    pub photons_per_direction: Option<Spanned<f64>>,
    pub seed: Option<Spanned<f64>>,
    pub split: Option<Spanned<f64>>,
    pub precision: Option<Spanned<String>>,
    pub keep_bits: Option<Spanned<f64>>,
    pub channels: Option<Spanned<String>>,
    pub lambda_nm: Option<Spanned<RawLambda>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLambda {
    pub start: Spanned<f64>,
    pub end: Spanned<f64>,
    pub step: Spanned<f64>,
}

/// `sweep:` — every dye × every depth of shade, from the same trace.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSweep {
    pub dyes: Spanned<Vec<Spanned<String>>>,
    pub depth_of_shade_percent: Spanned<Vec<Spanned<f64>>>,
    pub undyed: Option<Spanned<bool>>,
}

/// `{name, class, bands: [{peak_nm, fwhm_nm, peak_eps_l_per_mg_cm}]}` or `{name, class, csv}`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDye {
    pub name: Spanned<String>,
    pub class: Spanned<String>,
    pub bands: Option<Spanned<Vec<Spanned<RawBand>>>>,
    pub csv: Option<Spanned<String>>,
    pub source: Option<Spanned<String>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawBand {
    pub peak_nm: Spanned<f64>,
    pub fwhm_nm: Spanned<f64>,
    pub peak_eps_l_per_mg_cm: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawFiber {
    pub name: Spanned<String>,
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    pub section: Option<Spanned<RawSection>>,
    pub diameter_um: Option<Spanned<f64>>,
    pub seed: Option<Spanned<f64>>,
    pub variant: Option<Spanned<f64>>,
    pub eta: Option<Spanned<f64>>,
    pub beta_deg: Option<Spanned<f64>>,
    pub roughness: Option<Spanned<RawRoughness>>,
    pub dye: Option<Spanned<String>>,
    pub depth_of_shade_percent: Option<Spanned<f64>>,
    pub cuticle: Option<Spanned<RawCuticle>>,
    pub sections: Option<Spanned<f64>>,
    pub sweep: Option<Spanned<RawSweep>>,
    pub symmetry: Option<Spanned<String>>,
}

/// Exactly one of `shape` (a generator, or `ellipse` with `ratio`), `polygon` (CSV) or `mask`
/// (image, with `um_per_px`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSection {
    pub shape: Option<Spanned<String>>,
    pub ratio: Option<Spanned<f64>>,
    pub polygon: Option<Spanned<String>>,
    pub mask: Option<Spanned<String>>,
    pub um_per_px: Option<Spanned<f64>>,
    pub smoothing_passes: Option<Spanned<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRoughness {
    pub ra_nm: Spanned<f64>,
    pub l_nm: Spanned<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawCuticle {
    pub enabled: Option<Spanned<bool>>,
    pub length_um: Option<Spanned<f64>>,
    pub tilt_deg: Option<Spanned<f64>>,
}

/// A validated fiber spec.
#[derive(Debug, Clone)]
pub struct FiberSpec {
    pub file: String,
    /// Presets plus the spec's own dyes.
    pub dyes: Vec<Dye>,
    pub fibers: Vec<FiberEntry>,
    pub bake: BakeSettings,
    pub limits: Limits,
    /// Where `bake.photons_per_direction` is set (line 1 when it is not).
    pub photons_at: (u64, u64),
    /// SHA-256 of the spec text as read (provenance in every table).
    pub sha256: String,
}

/// Largest Beckmann slope angle β, degrees, whether given as `beta_deg` or from `roughness`.
pub const MAX_BETA_DEG: f64 = 45.0;

/// A measured (polygon or mask) section must be within this factor of its type's Table 9
/// diameter range: real fibers vary (Table 9 gives one value for polyester), unit mistakes are
/// factors of 1000 (mm for µm) or ~25 (a wrong `um_per_px`).
pub const MEASURED_SIZE_FACTOR: f64 = 2.0;

/// A range bound as people write it: `1`, `64`, `1e12`, `9.007199254740992e15`.
fn bound(x: f64) -> String {
    if x.abs() >= 1e6 {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A width for messages: `0.011`, `1003.7`, `1.2e-5`.
fn fmt_um(w: f64) -> String {
    if w.is_finite() && (0.01..1e5).contains(&w) {
        format!("{}", (w * 1000.0).round() / 1000.0)
    } else {
        format!("{w:.3e}")
    }
}

/// Where a section came from.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SectionSource {
    Generator {
        shape: Shape,
        seed: u64,
        variant: u64,
    },
    Ellipse {
        ratio: f64,
    },
    Polygon {
        file: PathBuf,
    },
    Mask {
        file: PathBuf,
        um_per_px: f64,
    },
}

/// One fiber of a spec, resolved.
#[derive(Debug, Clone)]
pub struct FiberEntry {
    pub name: String,
    pub line: u64,
    pub fiber_type: &'static FiberType,
    pub source: SectionSource,
    pub diameter_um: f64,
    pub eta: f64,
    pub beta_deg: f64,
    pub section: Section,
    pub cuticle: Option<Cuticle>,
    /// The dye and its depth of shade ζ (fraction).
    pub dye: Option<(Dye, f64)>,
    /// Seeded cross-sections baked for this entry (variants `variant`, `variant + 1`, …).
    pub sections: u64,
    /// The dyeings baked from one trace: `None` is the undyed fiber.
    pub variants: Vec<Option<(Dye, f64)>>,
    /// `auto`: detect the symmetries; `none`: trace every incoming direction.
    pub symmetry: SymmetryMode,
    /// Every cross-section baked (`sections` of them, the first is [`FiberEntry::section`]),
    /// built by the resolver so a bake cannot fail on one.
    pub population: Vec<Section>,
    /// The symmetries the bake uses (those every section shares, on the bake's grid; none
    /// with `symmetry: none`).
    pub symmetries: Symmetry,
    /// Incoming directions the tables store after symmetry reduction.
    pub stored_directions: usize,
}

impl FiberEntry {
    pub fn fiber(&self) -> Fiber {
        self.fiber_with(self.section.clone())
    }

    /// Cross-section `s` of the entry's population (0 is [`FiberEntry::section`]): the
    /// generator's next variants, scaled to the same mean width.
    pub fn section_variant(&self, s: u64) -> Result<Section, String> {
        if s == 0 {
            return Ok(self.section.clone());
        }
        match &self.source {
            SectionSource::Generator {
                shape,
                seed,
                variant,
            } => generate(*shape, 1.0, *seed, variant + s)
                .and_then(|x| x.scaled_to_diameter(self.diameter_um))
                .map_err(|e| e.to_string()),
            _ => Err("only generated sections have variants".into()),
        }
    }

    /// The fiber with another cross-section of the population.
    pub fn fiber_with(&self, section: Section) -> Fiber {
        Fiber {
            section,
            surface: Surface {
                eta: self.eta,
                alpha: self.beta_deg.to_radians().tan(),
            },
            cuticle: self.cuticle,
        }
    }

    /// μa(λ) of the dyed fiber, per µm (0 undyed).
    pub fn mua_per_um(&self, lambda_nm: f64) -> f64 {
        self.variant_mua_per_um(self.dye.as_ref(), lambda_nm)
    }

    /// μa(λ) of the fiber dyed with `dye` at its depth of shade, per µm (Eq. of §5.3.1:
    /// μa = ρ·ζ·ε).
    pub fn variant_mua_per_um(&self, dye: Option<&(Dye, f64)>, lambda_nm: f64) -> f64 {
        dye.map_or(0.0, |(d, dos)| {
            d.mua_per_mm(lambda_nm, self.fiber_type.density_g_per_cm3, *dos) * 1e-3
        })
    }

    /// Name of a dyeing: `undyed` or `<dye>@<DoS>%`.
    pub fn variant_name(v: Option<&(Dye, f64)>) -> String {
        v.map_or("undyed".into(), |(d, z)| {
            format!("{}@{}%", d.name, z * 100.0)
        })
    }
}

/// How the bake finds the fiber's symmetries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SymmetryMode {
    Auto,
    None,
}

/// Reads and validates the fiber spec at `path` (a skin spec is an error that says so).
pub fn load(path: &Path) -> Result<FiberSpec, SpecErrors> {
    match super::load_as(path, super::SpecKind::Fiber)? {
        super::Spec::Fiber(s) => Ok(s),
        super::Spec::Skin(_) => unreachable!("load_as checked the kind"),
    }
}

/// Validates fiber-spec text; files it names are looked up relative to `dir`.
pub fn load_str(file: &str, text: &str, dir: &Path) -> Result<FiberSpec, SpecErrors> {
    let raw: RawFiberSpec = parse_yaml(file, text, &|t| check_str(file, t, dir))?;
    resolve_raw(file, raw, dir).map(|s| FiberSpec {
        sha256: super::sha256_hex(text.as_bytes()),
        ..s
    })
}

fn resolve_raw(file: &str, raw: RawFiberSpec, dir: &Path) -> Result<FiberSpec, SpecErrors> {
    let mut cx = Ctx {
        file: file.to_string(),
        ..Ctx::default()
    };
    let spec = cx.fiber_spec(raw, dir);
    if cx.errors.is_empty() {
        Ok(spec)
    } else {
        Err(SpecErrors(cx.errors))
    }
}

/// Every error of fiber-spec text, parse errors undiagnosed (to probe what a field allows).
fn check_str(file: &str, text: &str, dir: &Path) -> Vec<SpecError> {
    match parse_plain::<RawFiberSpec>(file, text) {
        Ok(raw) => resolve_raw(file, raw, dir)
            .err()
            .map_or_else(Vec::new, |e| e.0),
        Err(e) => vec![e],
    }
}

impl Ctx {
    fn fiber_spec(&mut self, raw: RawFiberSpec, dir: &Path) -> FiberSpec {
        if let Some(v) = &raw.version {
            if v.value != 1 {
                self.out_of_range(loc(v), "version", v.value.to_string(), "1".into());
            }
        }
        let limits = self.limits(raw.limits.as_ref());
        let mut dyes = dye::presets();
        // Dyes of the spec that failed their checks: already reported, so a fiber naming one
        // is not told the name is unknown.
        let mut broken: Vec<String> = Vec::new();
        for d in &raw.dyes {
            let Some(dy) = self.dye(&d.value, dir) else {
                broken.push(d.value.name.value.clone());
                continue;
            };
            if dyes.iter().any(|x| x.name == dy.name) {
                self.invalid(
                    loc(&d.value.name),
                    "dyes.name",
                    format!("{:?} is already defined (presets included)", dy.name),
                );
            } else {
                dyes.push(dy);
            }
        }
        // Each cross-section of each fiber is built, measured and checked for symmetry here:
        // they count as entries (counted before any is built).
        let sections: f64 = raw
            .fibers
            .iter()
            .map(|f| {
                f.value
                    .sections
                    .as_ref()
                    .map_or(1.0, |s| s.value.clamp(1.0, 64.0))
            })
            .sum();
        let within = sections <= limits.entries as f64;
        if !within {
            self.over_limit(
                (1, 1),
                "fibers",
                format!(
                    "the spec lists {} fibers with {} cross-sections",
                    count_text(raw.fibers.len() as u64),
                    count_text(sections as u64)
                ),
                "entries",
                count_text(limits.entries),
            );
        }
        let bake = raw
            .bake
            .as_ref()
            .map_or_else(BakeSettings::default, |b| self.bake(&b.value, &limits));
        let mut fibers: Vec<FiberEntry> = Vec::new();
        for f in raw.fibers.iter().filter(|_| within) {
            if let Some(e) = self.fiber(f, &dyes, &broken, dir, &bake, &limits) {
                if let Some(first) = fibers.iter().find(|x| x.name.eq_ignore_ascii_case(&e.name)) {
                    self.invalid(
                        loc(&f.value.name),
                        "fibers.name",
                        super::resolve::duplicate_message(&e.name, &first.name, first.line),
                    );
                } else {
                    fibers.push(e);
                }
            }
        }
        if raw.fibers.is_empty() {
            self.invalid((1, 1), "fibers", "the spec lists no fibers");
        }
        let photons_at = raw
            .bake
            .as_ref()
            .and_then(|b| b.value.photons_per_direction.as_ref().map(loc))
            .unwrap_or((1, 1));
        FiberSpec {
            file: self.file.clone(),
            dyes,
            fibers,
            bake,
            limits,
            photons_at,
            sha256: String::new(),
        }
    }

    /// The symmetries and stored directions of an entry's population on the bake's grid, and
    /// the size of its tables against `limits.table_gib`.
    fn population_costs(
        &mut self,
        at: (u64, u64),
        e: &mut FiberEntry,
        st: &BakeSettings,
        limits: &Limits,
    ) -> Option<()> {
        let fibers: Vec<Fiber> = e
            .population
            .iter()
            .map(|s| e.fiber_with(s.clone()))
            .collect();
        e.symmetries = if e.symmetry == SymmetryMode::None {
            Symmetry::NONE
        } else {
            let mut sym = symmetry::detect(&fibers[0], st.res_deg);
            for f in &fibers[1..] {
                sym = sym.common(&symmetry::detect(f, st.res_deg));
            }
            sym
        };
        let grid = crate::fiber::AngularGrid::new(st.res_deg).ok()?;
        e.stored_directions = e
            .symmetries
            .stored_count(grid.n_theta, grid.n_phi, st.res_deg);
        let tables = fibers.len() + usize::from(fibers.len() > 1);
        let bytes = e.stored_directions as f64
            * tables as f64
            * e.variants.len() as f64
            * st.channels_per_variant() as f64
            * grid.bins() as f64
            * 4.0;
        let gib = bytes / (1u64 << 30) as f64;
        if gib > limits.table_gib {
            self.over_limit(
                at,
                "fibers",
                format!(
                    "{}: {} stored directions × {tables} table(s) × {} variant(s) × {} channel(s) × {} bins \
                     is {gib:.2} GiB of f32 tables",
                    e.name,
                    count_text(e.stored_directions as u64),
                    e.variants.len(),
                    st.channels_per_variant(),
                    count_text(grid.bins() as u64),
                ),
                "table_gib",
                format!("{} GiB", limits.table_gib),
            );
            return None;
        }
        Some(())
    }

    fn bake(&mut self, b: &RawBake, limits: &Limits) -> BakeSettings {
        let d = BakeSettings::default();
        let res_deg = match &b.resolution_deg {
            Some(r) => match self.in_range("bake.resolution_deg", r, 0.25, 30.0, false) {
                Some(x) if crate::fiber::AngularGrid::new(x).is_ok() => x,
                Some(x) => {
                    self.out_of_range(
                        loc(r),
                        "bake.resolution_deg",
                        x.to_string(),
                        "a divisor of 180 in [0.25, 30], e.g. 1, 2, 3, 5, 6, 10".into(),
                    );
                    d.res_deg
                }
                None => d.res_deg,
            },
            None => d.res_deg,
        };
        let photons = self.count(
            "bake.photons_per_direction",
            &b.photons_per_direction,
            1.0,
            1e12,
            d.photons,
        );
        let seed = self.count("bake.seed", &b.seed, 0.0, 2f64.powi(53), d.seed);
        let split = self.count("bake.split", &b.split, 1.0, 64.0, d.split as u64) as u32;
        let precision = match &b.precision {
            Some(p) => self
                .choice(
                    "bake.precision",
                    p,
                    &[("f16", Precision::F16), ("f32", Precision::F32)],
                )
                .unwrap_or(d.precision),
            None => d.precision,
        };
        let bits = precision.mantissa_bits();
        let keep_bits = match &b.keep_bits {
            Some(k) if k.value.fract() != 0.0 || !(0.0..=bits as f64).contains(&k.value) => {
                let name = match precision {
                    Precision::F16 => "f16",
                    Precision::F32 => "f32",
                };
                self.out_of_range(
                    loc(k),
                    "bake.keep_bits",
                    k.value.to_string(),
                    format!("a whole number in [0, {bits}] ({name} has {bits} mantissa bits)"),
                );
                bits
            }
            Some(k) => k.value as u32,
            None => bits,
        };
        let channels = match &b.channels {
            Some(c) => self
                .choice(
                    "bake.channels",
                    c,
                    &[
                        ("rgb", ChannelKind::Rgb),
                        ("spectral", ChannelKind::Spectral),
                    ],
                )
                .unwrap_or(d.channels),
            None => d.channels,
        };
        let lambda_nm = match &b.lambda_nm {
            Some(l) => {
                let r = &l.value;
                let a = self.in_range("bake.lambda_nm.start", &r.start, 360.0, 830.0, false);
                let e = self.in_range("bake.lambda_nm.end", &r.end, 360.0, 830.0, false);
                let st = self.in_range("bake.lambda_nm.step", &r.step, 0.0, 100.0, true);
                match (a, e, st) {
                    (Some(a), Some(e), Some(st)) if e >= a => {
                        // Counted in f64 before any wavelength is built.
                        let n = ((e - a) / st + 1e-9).floor() + 1.0;
                        if n > limits.wavelengths as f64 {
                            self.over_limit(
                                loc(&r.step),
                                "bake.lambda_nm.step",
                                format!(
                                    "{}–{} nm in steps of {} nm gives {} wavelengths",
                                    super::error::num(a),
                                    super::error::num(e),
                                    super::error::num(st),
                                    if n < 1e15 {
                                        count_text(n as u64)
                                    } else {
                                        format!("{n:.3e}")
                                    }
                                ),
                                "wavelengths",
                                count_text(limits.wavelengths),
                            );
                            d.lambda_nm.clone()
                        } else {
                            (0..n as usize).map(|i| a + st * i as f64).collect()
                        }
                    }
                    (Some(a), Some(e), Some(_)) => {
                        self.out_of_range(
                            loc(&r.end),
                            "bake.lambda_nm.end",
                            e.to_string(),
                            format!("[{a}, 830] (not below start = {a})"),
                        );
                        d.lambda_nm.clone()
                    }
                    _ => d.lambda_nm.clone(),
                }
            }
            None => d.lambda_nm.clone(),
        };
        BakeSettings {
            res_deg,
            photons: photons.max(1),
            seed,
            split,
            precision,
            keep_bits,
            channels,
            lambda_nm,
            ..d
        }
    }

    fn dye(&mut self, d: &RawDye, dir: &Path) -> Option<Dye> {
        let class = self.choice("dyes.class", &d.class, &DyeClass::ALL)?;
        let spectrum = match (&d.bands, &d.csv) {
            (Some(b), None) => {
                let mut bands = Vec::new();
                for rb in &b.value {
                    let r = &rb.value;
                    let peak = self.in_range("dyes.bands.peak_nm", &r.peak_nm, 300.0, 800.0, false);
                    let fwhm = self.in_range("dyes.bands.fwhm_nm", &r.fwhm_nm, 1.0, 500.0, false);
                    let eps = self.in_range(
                        "dyes.bands.peak_eps_l_per_mg_cm",
                        &r.peak_eps_l_per_mg_cm,
                        0.0,
                        1.0,
                        true,
                    );
                    bands.push(Band {
                        peak_nm: peak?,
                        fwhm_nm: fwhm?,
                        peak_eps_l_per_mg_cm: eps?,
                    });
                }
                if bands.is_empty() {
                    self.invalid(loc(b), "dyes.bands", "give at least one band");
                    return None;
                }
                Spectrum::Bands(bands)
            }
            (None, Some(c)) => match dye::spectrum_from_csv(&self.data_file(
                c,
                "dyes.csv",
                dir,
                "a CSV of lambda_nm,eps_l_per_mg_cm rows",
            )?) {
                Ok(s) => s,
                Err(m) => {
                    self.invalid(loc(c), "dyes.csv", format!("{}: {m}", c.value));
                    return None;
                }
            },
            _ => {
                self.invalid(
                    loc(&d.name),
                    "dyes",
                    "give exactly one of `bands` (Gaussian band model) or `csv` (lambda_nm,eps_l_per_mg_cm)",
                );
                return None;
            }
        };
        let dye = Dye {
            name: d.name.value.clone(),
            class,
            spectrum,
            source: d
                .source
                .as_ref()
                .map_or_else(|| self.file.clone(), |s| s.value.clone()),
        };
        let (lo, hi) = class.peak_range();
        let peak = dye.peak_eps();
        if !(lo..=hi).contains(&peak) {
            self.out_of_range(
                loc(&d.class),
                &format!("dyes.{}: peak extinction", dye.name),
                format!("{peak:.4} l/(mg·cm)"),
                format!("[{lo}, {hi}] for {} dyes (thesis §5.3.1)", class.name()),
            );
            return None;
        }
        Some(dye)
    }

    /// A whole number in [lo, hi] (the range printed is the one checked).
    fn count(
        &mut self,
        field: &str,
        v: &Option<Spanned<f64>>,
        lo: f64,
        hi: f64,
        default: u64,
    ) -> u64 {
        match v {
            Some(s) if !(s.value.fract() == 0.0 && s.value >= lo && s.value <= hi) => {
                self.out_of_range(
                    loc(s),
                    field,
                    s.value.to_string(),
                    format!("[{}, {}], a whole number", bound(lo), bound(hi)),
                );
                default
            }
            _ => self.opt_range(field, v, lo, hi, false, default as f64) as u64,
        }
    }

    fn fiber(
        &mut self,
        f: &Spanned<RawFiber>,
        dyes: &[Dye],
        broken: &[String],
        dir: &Path,
        st: &BakeSettings,
        limits: &Limits,
    ) -> Option<FiberEntry> {
        let r = &f.value;
        if let Err(m) = names::check(&r.name.value) {
            self.invalid(
                loc(&r.name),
                "fibers.name",
                names::message(&r.name.value, &m),
            );
            return None;
        }
        let types: Vec<(&str, &'static FiberType)> = TABLE_9.iter().map(|t| (t.name, t)).collect();
        let ft: &'static FiberType = self.choice("fibers.type", &r.kind, &types)?;
        let seed = self.count("fibers.seed", &r.seed, 0.0, 2f64.powi(53), 1);
        let variant = self.count("fibers.variant", &r.variant, 0.0, 1e6, 0);
        // Diameter: given, or drawn in Table 9's range from the seed and variant.
        let (dlo, dhi) = ft.diameter_um;
        let diameter_um = match &r.diameter_um {
            Some(d) => self.in_range("fibers.diameter_um", d, 1.0, 200.0, false)?,
            None => {
                use rand_core::Rng;
                let mut rng = crate::transport::rng::batch_rng(seed ^ 0xd1a_3e7e5, variant);
                dlo + (dhi - dlo) * crate::transport::rng::uniform(rng.next_u64())
            }
        };
        let eta = self.opt_range("fibers.eta", &r.eta, 1.0, 3.0, true, ft.eta());
        let beta_deg = match (&r.beta_deg, &r.roughness) {
            (Some(_), Some(rr)) => {
                self.invalid(
                    loc(rr),
                    "fibers.roughness",
                    "give `beta_deg` or `roughness`, not both",
                );
                return None;
            }
            (Some(b), None) => self.in_range("fibers.beta_deg", b, 0.0, MAX_BETA_DEG, false)?,
            (None, Some(rr)) => {
                let ra = self.in_range(
                    "fibers.roughness.ra_nm",
                    &rr.value.ra_nm,
                    0.0,
                    1000.0,
                    false,
                )?;
                let l = self.in_range("fibers.roughness.l_nm", &rr.value.l_nm, 0.0, 1e4, true)?;
                let beta = (ra / l).atan().to_degrees(); // §5.3.1: β = arctan(Ra/l)
                                                         // The same range as `beta_deg`: the facet model is not meant for steeper slopes.
                if beta > MAX_BETA_DEG {
                    self.out_of_range(
                        loc(rr),
                        "fibers.roughness",
                        format!("ra_nm = {ra}, l_nm = {l} (β = arctan(Ra/l) = {beta:.2}°)"),
                        format!("Ra/l ≤ tan {MAX_BETA_DEG}° = 1, as `beta_deg` is in [0, {MAX_BETA_DEG}]"),
                    );
                    return None;
                }
                beta
            }
            (None, None) => ft.beta_deg(),
        };
        let (source, raw_section) = self.section(r, ft, seed, variant, dir, limits)?;
        let section = match raw_section.scaled_to_diameter(diameter_um) {
            Ok(s) => s,
            Err(e) => {
                self.invalid(loc(&r.name), "fibers.section", e.to_string());
                return None;
            }
        };
        // Mask and polygon sections keep their measured size unless a diameter is given; that
        // size must be a plausible fiber of the type (a polygon in mm or a mask at a wrong
        // scale is off by a factor of ~1000 or ~25).
        let section = match (&source, &r.diameter_um) {
            (SectionSource::Polygon { .. } | SectionSource::Mask { .. }, None) => {
                let w = raw_section.mean_width_um();
                let (lo, hi) = (dlo / MEASURED_SIZE_FACTOR, dhi * MEASURED_SIZE_FACTOR);
                if !(lo..=hi).contains(&w) {
                    let what = match &source {
                        SectionSource::Mask { .. } => "the mask at its `um_per_px`",
                        _ => "the polygon (coordinates in µm)",
                    };
                    self.out_of_range(
                        loc(r.section.as_ref().map_or(&r.name, |s| {
                            let v = &s.value;
                            v.polygon.as_ref().or(v.mask.as_ref()).unwrap_or(&r.name)
                        })),
                        "fibers.section",
                        format!("{what} measures {} µm across", fmt_um(w)),
                        format!(
                            "{lo}–{hi} µm for {} (Table 9: {dlo}–{dhi} µm, within a factor of \
                             {MEASURED_SIZE_FACTOR}); check the units, or set `diameter_um` to \
                             scale the section",
                            ft.name
                        ),
                    );
                    return None;
                }
                raw_section
            }
            _ => section,
        };
        let diameter_um = section.mean_width_um();
        let cuticle = match &r.cuticle {
            Some(c) => {
                let on = c.value.enabled.as_ref().is_none_or(|e| e.value);
                let len = self.opt_range(
                    "fibers.cuticle.length_um",
                    &c.value.length_um,
                    0.5,
                    200.0,
                    false,
                    WOOL_SCALE_LENGTH_UM,
                );
                let tilt = self.opt_range(
                    "fibers.cuticle.tilt_deg",
                    &c.value.tilt_deg,
                    0.0,
                    20.0,
                    false,
                    WOOL_SCALE_TILT_DEG,
                );
                on.then_some(Cuticle {
                    length_um: len,
                    tilt_deg: tilt,
                })
            }
            None => ft.cuticle.then_some(Cuticle {
                length_um: WOOL_SCALE_LENGTH_UM,
                tilt_deg: WOOL_SCALE_TILT_DEG,
            }),
        };
        let dye = match (&r.dye, &r.depth_of_shade_percent) {
            (Some(name), dos) => {
                let Some(d) = dyes.iter().find(|d| d.name == name.value) else {
                    if broken.contains(&name.value) {
                        return None;
                    }
                    let names: Vec<&str> = dyes.iter().map(|d| d.name.as_str()).collect();
                    self.out_of_range(
                        loc(name),
                        "fibers.dye",
                        format!("{:?}", name.value),
                        format!("one of {}", names.join(", ")),
                    );
                    return None;
                };
                let Some(dos) = dos else {
                    self.invalid(
                        loc(name),
                        "fibers.depth_of_shade_percent",
                        "a dyed fiber needs its depth of shade, 0.1–4 % (§5.3.1)",
                    );
                    return None;
                };
                let z = self.in_range(
                    "fibers.depth_of_shade_percent",
                    dos,
                    100.0 * dye::DOS_RANGE.0,
                    100.0 * dye::DOS_RANGE.1,
                    false,
                )?;
                Some((d.clone(), z / 100.0))
            }
            (None, Some(dos)) => {
                self.invalid(loc(dos), "fibers.depth_of_shade_percent", "set `dye` too");
                return None;
            }
            (None, None) => None,
        };
        let sections = self.count("fibers.sections", &r.sections, 1.0, 64.0, 1);
        if sections > 1 && !matches!(source, SectionSource::Generator { .. }) {
            self.invalid(
                loc(r.sections.as_ref().unwrap()),
                "fibers.sections",
                "several sections need a generated `shape` (a polygon or mask is one section)",
            );
            return None;
        }
        let mut variants = Vec::new();
        if let Some(sweep) = &r.sweep {
            let sw = &sweep.value;
            let undyed = sw.undyed.as_ref().is_some_and(|u| u.value);
            // Counted before any is built: every dye × every depth of shade (+ undyed).
            let n = (sw.dyes.value.len() as u64)
                .saturating_mul(sw.depth_of_shade_percent.value.len() as u64)
                .saturating_add(u64::from(undyed));
            if n > limits.variants {
                self.over_limit(
                    loc(sweep),
                    "fibers.sweep",
                    format!(
                        "{} dyes × {} depths of shade{} are {} variants",
                        count_text(sw.dyes.value.len() as u64),
                        count_text(sw.depth_of_shade_percent.value.len() as u64),
                        if undyed { " + undyed" } else { "" },
                        count_text(n)
                    ),
                    "variants",
                    count_text(limits.variants),
                );
                return None;
            }
            if undyed {
                variants.push(None);
            }
            let mut first_dos: std::collections::HashMap<u64, u64> = Default::default();
            for dos in &sw.depth_of_shade_percent.value {
                if let Some(l) = first_dos.insert(dos.value.to_bits(), loc(dos).0) {
                    self.invalid(
                        loc(dos),
                        "fibers.sweep.depth_of_shade_percent",
                        format!(
                            "{} is listed twice (first on line {l}); allowed: each depth of shade once",
                            dos.value
                        ),
                    );
                    return None;
                }
            }
            let mut first_dye: std::collections::HashMap<&str, u64> = Default::default();
            for name in &sw.dyes.value {
                if let Some(first_line) = first_dye.insert(name.value.as_str(), loc(name).0) {
                    self.invalid(
                        loc(name),
                        "fibers.sweep.dyes",
                        format!(
                            "{:?} is listed twice (first on line {first_line}); allowed: each dye once",
                            name.value,
                        ),
                    );
                    return None;
                }
                let Some(d) = dyes.iter().find(|d| d.name == name.value) else {
                    if broken.contains(&name.value) {
                        return None;
                    }
                    let names: Vec<&str> = dyes.iter().map(|d| d.name.as_str()).collect();
                    self.out_of_range(
                        loc(name),
                        "fibers.sweep.dyes",
                        format!("{:?}", name.value),
                        format!("one of {}", names.join(", ")),
                    );
                    return None;
                };
                for dos in &sw.depth_of_shade_percent.value {
                    let z = self.in_range(
                        "fibers.sweep.depth_of_shade_percent",
                        dos,
                        100.0 * dye::DOS_RANGE.0,
                        100.0 * dye::DOS_RANGE.1,
                        false,
                    )?;
                    variants.push(Some((d.clone(), z / 100.0)));
                }
            }
            if variants.is_empty() {
                self.invalid(
                    loc(&r.name),
                    "fibers.sweep",
                    "the sweep lists no dye or depth of shade",
                );
                return None;
            }
            if let (Some(_), Some(d)) = (&dye, &r.dye) {
                self.invalid(
                    loc(sweep),
                    "fibers.sweep",
                    format!("give `dye` (line {}) or `sweep`, not both", loc(d).0),
                );
                return None;
            }
        } else {
            variants.push(dye.clone());
        }
        // With a sweep, the entry's representative dyeing (what `fiber trace` and `validate`
        // use) is its first dyed variant.
        let dye = dye.or_else(|| variants.iter().flatten().next().cloned());
        let symmetry = match &r.symmetry {
            Some(sy) => self.choice(
                "fibers.symmetry",
                sy,
                &[("auto", SymmetryMode::Auto), ("none", SymmetryMode::None)],
            )?,
            None => SymmetryMode::Auto,
        };
        let mut e = FiberEntry {
            sections,
            variants,
            symmetry,
            name: r.name.value.clone(),
            line: loc(f).0,
            fiber_type: ft,
            source,
            diameter_um,
            eta,
            beta_deg,
            section: section.clone(),
            cuticle,
            dye,
            population: vec![section],
            symmetries: Symmetry::NONE,
            stored_directions: 0,
        };
        // The population the bake traces, built here so that a bake cannot fail on it.
        for k in 1..sections {
            match e.section_variant(k) {
                Ok(sec) => e.population.push(sec),
                Err(m) => {
                    let at = r.sections.as_ref().map_or(loc(&r.name), loc);
                    self.invalid(at, "fibers.sections", format!("section {k}: {m}"));
                    return None;
                }
            }
        }
        self.population_costs(loc(f), &mut e, st, limits)?;
        Some(e)
    }

    fn section(
        &mut self,
        r: &RawFiber,
        ft: &FiberType,
        seed: u64,
        variant: u64,
        dir: &Path,
        limits: &Limits,
    ) -> Option<(SectionSource, Section)> {
        let Some(s) = &r.section else {
            let shape = ft.default_shape;
            return self.generated(&r.name, shape, seed, variant);
        };
        let v = &s.value;
        let given: Vec<(&str, (u64, u64))> = [
            ("shape", v.shape.as_ref().map(loc)),
            ("polygon", v.polygon.as_ref().map(loc)),
            ("mask", v.mask.as_ref().map(loc)),
        ]
        .into_iter()
        .filter_map(|(k, at)| Some((k, at?)))
        .collect();
        const ONE_OF: &str = "give exactly one of `shape`, `polygon` (CSV of x_um,y_um) or `mask` \
                              (image with `um_per_px`)";
        match given.as_slice() {
            [_] => {}
            [] => {
                self.invalid(loc(s), "fibers.section", ONE_OF);
                return None;
            }
            [(first, at1), rest @ ..] => {
                for (k, at) in rest {
                    self.invalid(
                        *at,
                        &format!("fibers.section.{k}"),
                        format!("{ONE_OF}; `{first}` is on line {}", at1.0),
                    );
                }
                return None;
            }
        }
        if v.mask.is_none() && (v.um_per_px.is_some() || v.smoothing_passes.is_some()) {
            self.invalid(
                loc(s),
                "fibers.section",
                "`um_per_px` and `smoothing_passes` belong to `mask`",
            );
            return None;
        }
        if let Some(shape) = &v.shape {
            if shape.value == "ellipse" {
                let Some(ratio) = &v.ratio else {
                    self.invalid(
                        loc(shape),
                        "fibers.section.ratio",
                        "an ellipse needs `ratio` (minor/major axis), (0, 1]",
                    );
                    return None;
                };
                let ratio = self.in_range("fibers.section.ratio", ratio, 0.05, 1.0, false)?;
                return Some((
                    SectionSource::Ellipse { ratio },
                    Section::Conic {
                        rx_um: 1.0,
                        ry_um: ratio,
                    },
                ));
            }
            if let Some(ra) = &v.ratio {
                self.invalid(
                    loc(ra),
                    "fibers.section.ratio",
                    "`ratio` belongs to `shape: ellipse`",
                );
                return None;
            }
            // `ellipse` was handled above; it is listed so the error names every shape.
            let mut opts: Vec<(&str, Shape)> = Shape::ALL.to_vec();
            opts.push(("ellipse", Shape::Circle));
            let sh = self.choice("fibers.section.shape", shape, &opts)?;
            return self.generated(&r.name, sh, seed, variant);
        }
        if let Some(p) = &v.polygon {
            let file = self.data_file(
                p,
                "fibers.section.polygon",
                dir,
                "a CSV of x_um,y_um rows (a blank line or `hole` starts a hole)",
            )?;
            let key = format!("polygon\0{}\0{}", file.display(), limits.polygon_vertices);
            let read = self
                .read_sections
                .entry(key)
                .or_insert_with(|| {
                    Section::from_csv(&file, limits.polygon_vertices).map_err(|e| e.to_string())
                })
                .clone();
            return match read {
                Ok(sec) => Some((SectionSource::Polygon { file }, sec)),
                Err(e) => {
                    self.invalid(loc(p), "fibers.section.polygon", e);
                    None
                }
            };
        }
        let m = v.mask.as_ref()?;
        let Some(um) = &v.um_per_px else {
            self.invalid(
                loc(m),
                "fibers.section.um_per_px",
                "a mask needs its scale, µm per pixel",
            );
            return None;
        };
        let um_per_px = self.in_range("fibers.section.um_per_px", um, 0.0, 100.0, true)?;
        let mut o = MaskOptions::new(um_per_px);
        o.max_pixels = limits.mask_pixels;
        o.max_vertices = limits.polygon_vertices;
        if let Some(sp) = &v.smoothing_passes {
            o.smoothing_passes =
                self.in_range("fibers.section.smoothing_passes", sp, 0.0, 100.0, false)? as usize;
        }
        let file = self.data_file(
            m,
            "fibers.section.mask",
            dir,
            "a binary image (PNG) of the cross-section",
        )?;
        let key = format!(
            "mask\0{}\0{}\0{}\0{}\0{}",
            file.display(),
            um_per_px.to_bits(),
            o.smoothing_passes,
            o.max_pixels,
            o.max_vertices
        );
        let read = self
            .read_sections
            .entry(key)
            .or_insert_with(|| {
                from_mask(&file, &o)
                    .map(|(s, _)| s)
                    .map_err(|e| e.to_string())
            })
            .clone();
        match read {
            Ok(sec) => Some((SectionSource::Mask { file, um_per_px }, sec)),
            Err(e) => {
                self.invalid(loc(m), "fibers.section.mask", e);
                None
            }
        }
    }

    /// The file a spec names, relative to the spec's folder; a missing one is reported with
    /// what it should contain.
    fn data_file(
        &mut self,
        name: &Spanned<String>,
        field: &str,
        dir: &Path,
        what: &str,
    ) -> Option<PathBuf> {
        let file = dir.join(&name.value);
        match std::fs::metadata(&file) {
            Ok(m) if !m.is_dir() => return Some(file),
            Ok(_) => {
                self.invalid(
                    loc(name),
                    field,
                    format!("{}: is a directory; expected {what}", file.display()),
                );
                return None;
            }
            Err(_) => {}
        }
        self.invalid(
            loc(name),
            field,
            format!(
                "{}: no such file (paths are relative to the spec's folder); expected {what}",
                file.display()
            ),
        );
        None
    }

    fn generated(
        &mut self,
        name: &Spanned<String>,
        shape: Shape,
        seed: u64,
        variant: u64,
    ) -> Option<(SectionSource, Section)> {
        match generate(shape, 1.0, seed, variant) {
            Ok(s) => Some((
                SectionSource::Generator {
                    shape,
                    seed,
                    variant,
                },
                s,
            )),
            Err(e) => {
                self.invalid(loc(name), "fibers.section", e.to_string());
                None
            }
        }
    }
}
