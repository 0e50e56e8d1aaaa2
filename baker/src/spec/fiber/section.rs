//! A fiber's cross-section: exactly one of a generated `shape` (or `ellipse` with `ratio`), a
//! `polygon` (CSV outline) or a `mask` (image with `um_per_px`), at the fiber's diameter
//! (given, or drawn in Table 9's range); a measured section keeps its own size, which must be
//! plausible for the type.

use std::path::PathBuf;

use super::entry::SectionSource;
use super::raw::{RawFiber, RawSection};
use super::{FiberCx, Scope};
use crate::fiber::material::FiberType;
use crate::fiber::section::generate::{generate, Shape};
use crate::fiber::section::mask::{from_mask, MaskOptions};
use crate::fiber::Section;
use crate::spec::check::{loc, Bounds};
use crate::spec::yaml::Spanned;

/// A measured (polygon or mask) section must be within this factor of its type's Table 9
/// diameter range: real fibers vary (Table 9 gives one value for polyester), unit mistakes are
/// factors of 1000 (mm for µm) or ~25 (a wrong `um_per_px`).
pub const MEASURED_SIZE_FACTOR: f64 = 2.0;

/// `fibers.diameter_um`, µm.
pub(in crate::spec) const DIAMETER_UM: Bounds = Bounds::closed(1.0, 200.0);
/// `section.ratio` of an ellipse, minor/major axis.
pub(in crate::spec) const RATIO: Bounds = Bounds::closed(0.05, 1.0);
/// `section.um_per_px` of a mask, µm per pixel.
pub(in crate::spec) const UM_PER_PX: Bounds = Bounds::above(0.0, 100.0);
/// `section.smoothing_passes` of a mask outline.
pub(in crate::spec) const SMOOTHING_PASSES: Bounds = Bounds::closed(0.0, 100.0);
/// `section.shape` of an ellipse (with `ratio`); the other shapes are generators
/// ([`Shape::ALL`]).
pub(in crate::spec) const ELLIPSE: &str = "ellipse";

/// What a generated section (and a drawn diameter) is drawn from: `fibers.seed` and
/// `fibers.variant`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Seeds {
    pub(super) seed: u64,
    pub(super) variant: u64,
}

/// A width for messages: `0.011`, `1003.7`, `1.2e-5`.
fn fmt_um(w: f64) -> String {
    if w.is_finite() && (0.01..1e5).contains(&w) {
        format!("{}", (w * 1000.0).round() / 1000.0)
    } else {
        format!("{w:.3e}")
    }
}

const ONE_OF: &str = "give exactly one of `shape`, `polygon` (CSV of x_um,y_um) or `mask` \
                      (image with `um_per_px`)";

impl FiberCx {
    /// Diameter: given, or drawn in Table 9's range from the seed and variant.
    pub(super) fn diameter_um(&mut self, r: &RawFiber, ft: &FiberType, s: Seeds) -> Option<f64> {
        let (dlo, dhi) = ft.diameter_um;
        Some(match &r.diameter_um {
            Some(d) => self.in_bounds("fibers.diameter_um", d, DIAMETER_UM)?,
            None => {
                use rand_core::Rng;
                let mut rng = crate::math::rng::batch_rng(s.seed ^ 0xd1a_3e7e5, s.variant);
                dlo + (dhi - dlo) * crate::math::rng::uniform(rng.next_u64())
            }
        })
    }

    /// The section scaled to `diameter_um`, or a measured section at its own size.
    pub(super) fn sized_section(
        &mut self,
        r: &RawFiber,
        ft: &FiberType,
        seeds: Seeds,
        diameter_um: f64,
        sc: &Scope,
    ) -> Option<(SectionSource, Section)> {
        let (source, raw_section) = self.section(r, ft, seeds, sc)?;
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
        match (&source, &r.diameter_um) {
            (SectionSource::Polygon { .. } | SectionSource::Mask { .. }, None) => {
                self.measured_size(r, ft, &source, &raw_section)?;
                Some((source, raw_section))
            }
            _ => Some((source, section)),
        }
    }

    /// A measured section's width within [`MEASURED_SIZE_FACTOR`] of the type's range.
    fn measured_size(
        &mut self,
        r: &RawFiber,
        ft: &FiberType,
        source: &SectionSource,
        raw_section: &Section,
    ) -> Option<()> {
        let (dlo, dhi) = ft.diameter_um;
        let w = raw_section.mean_width_um();
        let (lo, hi) = (dlo / MEASURED_SIZE_FACTOR, dhi * MEASURED_SIZE_FACTOR);
        if (lo..=hi).contains(&w) {
            return Some(());
        }
        let what = match source {
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
        None
    }

    /// The section `section:` describes, at unit size for a generated one (the type's default
    /// shape without `section:`).
    fn section(
        &mut self,
        r: &RawFiber,
        ft: &FiberType,
        seeds: Seeds,
        sc: &Scope,
    ) -> Option<(SectionSource, Section)> {
        let Some(s) = &r.section else {
            let shape = ft.default_shape;
            return self.generated(&r.name, shape, seeds);
        };
        let v = &s.value;
        self.one_source(s)?;
        if v.mask.is_none() && (v.um_per_px.is_some() || v.smoothing_passes.is_some()) {
            self.invalid(
                loc(s),
                "fibers.section",
                "`um_per_px` and `smoothing_passes` belong to `mask`",
            );
            return None;
        }
        if let Some(shape) = &v.shape {
            return self.shaped(&r.name, shape, v, seeds);
        }
        if let Some(p) = &v.polygon {
            return self.polygon(p, sc);
        }
        let m = v.mask.as_ref()?;
        self.mask(m, v, sc)
    }

    /// Exactly one of `shape`, `polygon` and `mask`.
    fn one_source(&mut self, s: &Spanned<RawSection>) -> Option<()> {
        let v = &s.value;
        let given: Vec<(&str, (u64, u64))> = [
            ("shape", v.shape.as_ref().map(loc)),
            ("polygon", v.polygon.as_ref().map(loc)),
            ("mask", v.mask.as_ref().map(loc)),
        ]
        .into_iter()
        .filter_map(|(k, at)| Some((k, at?)))
        .collect();
        match given.as_slice() {
            [_] => Some(()),
            [] => {
                self.invalid(loc(s), "fibers.section", ONE_OF);
                None
            }
            [(first, at1), rest @ ..] => {
                for (k, at) in rest {
                    self.invalid(
                        *at,
                        &format!("fibers.section.{k}"),
                        format!("{ONE_OF}; `{first}` is on line {}", at1.0),
                    );
                }
                None
            }
        }
    }

    /// `shape:`: an ellipse of `ratio`, or a generator.
    fn shaped(
        &mut self,
        name: &Spanned<String>,
        shape: &Spanned<String>,
        v: &RawSection,
        seeds: Seeds,
    ) -> Option<(SectionSource, Section)> {
        if shape.value == ELLIPSE {
            let Some(ratio) = &v.ratio else {
                self.invalid(
                    loc(shape),
                    "fibers.section.ratio",
                    "an ellipse needs `ratio` (minor/major axis), (0, 1]",
                );
                return None;
            };
            let ratio = self.in_bounds("fibers.section.ratio", ratio, RATIO)?;
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
        opts.push((ELLIPSE, Shape::Circle));
        let sh = self.choice("fibers.section.shape", shape, &opts)?;
        self.generated(name, sh, seeds)
    }

    /// `polygon:`, a CSV outline (read once per file and vertex limit).
    fn polygon(&mut self, p: &Spanned<String>, sc: &Scope) -> Option<(SectionSource, Section)> {
        let limits = sc.limits;
        let file = self.data_file(
            p,
            "fibers.section.polygon",
            sc.dir,
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
        match read {
            Ok(sec) => Some((SectionSource::Polygon { file }, sec)),
            Err(e) => {
                self.invalid(loc(p), "fibers.section.polygon", e);
                None
            }
        }
    }

    /// `mask:`, an image at `um_per_px` (read once per file and reading options).
    fn mask(
        &mut self,
        m: &Spanned<String>,
        v: &RawSection,
        sc: &Scope,
    ) -> Option<(SectionSource, Section)> {
        let limits = sc.limits;
        let Some(um) = &v.um_per_px else {
            self.invalid(
                loc(m),
                "fibers.section.um_per_px",
                "a mask needs its scale, µm per pixel",
            );
            return None;
        };
        let um_per_px = self.in_bounds("fibers.section.um_per_px", um, UM_PER_PX)?;
        let mut o = MaskOptions::new(um_per_px);
        o.max_pixels = limits.mask_pixels;
        o.max_vertices = limits.polygon_vertices;
        if let Some(sp) = &v.smoothing_passes {
            o.smoothing_passes =
                self.in_bounds("fibers.section.smoothing_passes", sp, SMOOTHING_PASSES)? as usize;
        }
        let file: PathBuf = self.data_file(
            m,
            "fibers.section.mask",
            sc.dir,
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

    /// Variant `variant` of the generator `shape` at unit size.
    fn generated(
        &mut self,
        name: &Spanned<String>,
        shape: Shape,
        seeds: Seeds,
    ) -> Option<(SectionSource, Section)> {
        let Seeds { seed, variant } = seeds;
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
