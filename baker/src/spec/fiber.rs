//! Fiber specs (`specs/fibers.yaml`): dyes and fiber entries, validated with file:line:column
//! like skin specs. Section files (CSV outlines, mask images) and dye spectra are read here,
//! relative to the spec's folder, so a bad file is reported against the line that names it.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::error::{SpecError, SpecErrors};
use super::raw::Spanned;
use super::resolve::{loc, parse_yaml, Ctx};
use crate::fiber::dye::{self, Band, Dye, DyeClass, Spectrum};
use crate::fiber::material::{
    fiber_type, FiberType, TABLE_9, WOOL_SCALE_LENGTH_UM, WOOL_SCALE_TILT_DEG,
};
use crate::fiber::section::generate::{generate, Shape};
use crate::fiber::section::mask::{from_mask, MaskOptions};
use crate::fiber::{Cuticle, Fiber, Section, Surface};

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct RawFiberSpec {
    pub version: Option<Spanned<u32>>,
    #[serde(default)]
    pub dyes: Vec<Spanned<RawDye>>,
    #[serde(default)]
    pub fibers: Vec<Spanned<RawFiber>>,
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
}

impl FiberEntry {
    pub fn fiber(&self) -> Fiber {
        Fiber {
            section: self.section.clone(),
            surface: Surface {
                eta: self.eta,
                alpha: self.beta_deg.to_radians().tan(),
            },
            cuticle: self.cuticle,
        }
    }

    /// μa(λ) of the dyed fiber, per µm (0 undyed).
    pub fn mua_per_um(&self, lambda_nm: f64) -> f64 {
        self.dye.as_ref().map_or(0.0, |(d, dos)| {
            d.mua_per_mm(lambda_nm, self.fiber_type.density_g_per_cm3, *dos) * 1e-3
        })
    }
}

/// True when the YAML text is a fiber spec (it has a top-level `fibers:` key).
pub fn is_fiber_spec(text: &str) -> bool {
    text.lines().any(|l| l.starts_with("fibers:"))
}

pub fn load(path: &Path) -> Result<FiberSpec, SpecErrors> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| {
        SpecErrors(vec![SpecError::Io {
            file: file.clone(),
            message: e.to_string(),
        }])
    })?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    load_str(&file, &text, &dir)
}

/// Validates fiber-spec text; files it names are looked up relative to `dir`.
pub fn load_str(file: &str, text: &str, dir: &Path) -> Result<FiberSpec, SpecErrors> {
    let raw: RawFiberSpec = parse_yaml(file, text)?;
    let mut cx = Ctx {
        file: file.to_string(),
        errors: Vec::new(),
    };
    let spec = cx.fiber_spec(raw, dir);
    if cx.errors.is_empty() {
        Ok(spec)
    } else {
        Err(SpecErrors(cx.errors))
    }
}

impl Ctx {
    fn fiber_spec(&mut self, raw: RawFiberSpec, dir: &Path) -> FiberSpec {
        if let Some(v) = &raw.version {
            if v.value != 1 {
                self.out_of_range(loc(v), "version", v.value.to_string(), "1".into());
            }
        }
        let mut dyes = dye::presets();
        for d in &raw.dyes {
            if let Some(dy) = self.dye(&d.value, dir) {
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
        }
        let mut fibers: Vec<FiberEntry> = Vec::new();
        for f in &raw.fibers {
            if let Some(e) = self.fiber(f, &dyes, dir) {
                if let Some(first) = fibers.iter().find(|x| x.name == e.name) {
                    self.invalid(
                        loc(&f.value.name),
                        "fibers.name",
                        format!("{:?} already defined on line {}", e.name, first.line),
                    );
                } else {
                    fibers.push(e);
                }
            }
        }
        if raw.fibers.is_empty() {
            self.invalid((1, 1), "fibers", "the spec lists no fibers");
        }
        FiberSpec {
            file: self.file.clone(),
            dyes,
            fibers,
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
            (None, Some(c)) => match dye::spectrum_from_csv(&dir.join(&c.value)) {
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

    fn count(&mut self, field: &str, v: &Option<Spanned<f64>>, hi: f64, default: u64) -> u64 {
        match v {
            Some(s) if s.value.fract() != 0.0 => {
                self.out_of_range(
                    loc(s),
                    field,
                    s.value.to_string(),
                    format!("a whole number in [0, {hi}]"),
                );
                default
            }
            _ => self.opt_range(field, v, 0.0, hi, false, default as f64) as u64,
        }
    }

    fn fiber(&mut self, f: &Spanned<RawFiber>, dyes: &[Dye], dir: &Path) -> Option<FiberEntry> {
        let r = &f.value;
        let types: Vec<(&str, &'static FiberType)> = TABLE_9.iter().map(|t| (t.name, t)).collect();
        let ft: &'static FiberType = self.choice("fibers.type", &r.kind, &types)?;
        let seed = self.count("fibers.seed", &r.seed, 2f64.powi(53), 1);
        let variant = self.count("fibers.variant", &r.variant, 1e6, 0);
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
            (Some(b), None) => self.in_range("fibers.beta_deg", b, 0.0, 45.0, false)?,
            (None, Some(rr)) => {
                let ra = self.in_range(
                    "fibers.roughness.ra_nm",
                    &rr.value.ra_nm,
                    0.0,
                    1000.0,
                    false,
                )?;
                let l = self.in_range("fibers.roughness.l_nm", &rr.value.l_nm, 0.0, 1e4, true)?;
                (ra / l).atan().to_degrees() // §5.3.1: β = arctan(Ra/l)
            }
            (None, None) => ft.beta_deg(),
        };
        let (source, raw_section) = self.section(r, ft, seed, variant, dir)?;
        let section = match raw_section.scaled_to_diameter(diameter_um) {
            Ok(s) => s,
            Err(e) => {
                self.invalid(loc(&r.name), "fibers.section", e.to_string());
                return None;
            }
        };
        // Mask and polygon sections keep their measured size unless a diameter is given.
        let section = match (&source, &r.diameter_um) {
            (SectionSource::Polygon { .. } | SectionSource::Mask { .. }, None) => raw_section,
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
        Some(FiberEntry {
            name: r.name.value.clone(),
            line: loc(f).0,
            fiber_type: ft,
            source,
            diameter_um,
            eta,
            beta_deg,
            section,
            cuticle,
            dye,
        })
    }

    fn section(
        &mut self,
        r: &RawFiber,
        ft: &FiberType,
        seed: u64,
        variant: u64,
        dir: &Path,
    ) -> Option<(SectionSource, Section)> {
        let Some(s) = &r.section else {
            let shape = ft.default_shape;
            return self.generated(&r.name, shape, seed, variant);
        };
        let v = &s.value;
        let given = [v.shape.is_some(), v.polygon.is_some(), v.mask.is_some()];
        if given.iter().filter(|&&g| g).count() != 1 {
            self.invalid(loc(s), "fibers.section", "give exactly one of `shape`, `polygon` (CSV of x_um,y_um) or `mask` (image with `um_per_px`)");
            return None;
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
            let mut opts: Vec<(&str, Shape)> = Shape::ALL.to_vec();
            opts.push(("ellipse", Shape::Circle));
            let sh = self.choice("fibers.section.shape", shape, &opts)?;
            return self.generated(&r.name, sh, seed, variant);
        }
        if let Some(p) = &v.polygon {
            let file = dir.join(&p.value);
            return match Section::from_csv(&file) {
                Ok(sec) => Some((SectionSource::Polygon { file }, sec)),
                Err(e) => {
                    self.invalid(loc(p), "fibers.section.polygon", e.to_string());
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
        if let Some(sp) = &v.smoothing_passes {
            o.smoothing_passes =
                self.in_range("fibers.section.smoothing_passes", sp, 0.0, 100.0, false)? as usize;
        }
        let file = dir.join(&m.value);
        match from_mask(&file, &o) {
            Ok((sec, _)) => Some((SectionSource::Mask { file, um_per_px }, sec)),
            Err(e) => {
                self.invalid(loc(m), "fibers.section.mask", e.to_string());
                None
            }
        }
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

/// Looks up the fiber type by name for the command line (`--type`).
pub fn type_by_name(name: &str) -> Option<&'static FiberType> {
    fiber_type(name)
}
