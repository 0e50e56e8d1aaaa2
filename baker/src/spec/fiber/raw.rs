//! The fiber spec as written: serde structs that keep the location of every value and reject
//! unknown fields. Ranges and meaning are checked by the resolver ([`super`]).

use schemars::JsonSchema;
use serde::Deserialize;

use crate::spec::yaml::Spanned;

/// A fiber spec (thesis ch. 5): dyes and fibers, for fiber BCSDF tables.
#[derive(Debug, Deserialize, Default, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawFiberSpec {
    /// Spec format version; 1 today.
    pub version: Option<Spanned<u32>>,
    /// Dyes besides the shipped presets, each under a new name.
    #[serde(default)]
    pub dyes: Vec<Spanned<RawDye>>,
    /// The fibers to bake.
    #[serde(default)]
    pub fibers: Vec<Spanned<RawFiber>>,
    /// How `baker bake` tabulates the BCSDFs (all optional).
    pub bake: Option<Spanned<RawBake>>,
    /// Resource budgets: what the spec may ask for before the baker allocates it (raise one
    /// deliberately for a larger bake; README "Hostile input").
    pub limits: Option<Spanned<crate::spec::limits::RawLimits>>,
}

/// `bake:` — how `baker bake` tabulates the BCSDFs (all optional).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawBake {
    /// Angular bin width, degrees: a divisor of 180 (1, 2, 3, 5, 6, 10 …).
    pub resolution_deg: Option<Spanned<f64>>,
    /// Photons traced per stored incoming bin (a whole number).
    pub photons_per_direction: Option<Spanned<f64>>,
    /// Random seed (a whole number).
    pub seed: Option<Spanned<f64>>,
    /// Draws per boundary event of the main path met from outside (a whole number; 1 = plain
    /// tracing).
    pub split: Option<Spanned<f64>>,
    /// Draws per boundary event met from inside the fiber, so every exit lobe is sampled this
    /// many times per photon (a whole number; 1 = plain tracing). Never fewer than `split`:
    /// a smaller value draws `split` times (and the manifest records `split`).
    pub exit_draws: Option<Spanned<f64>>,
    /// Expected-value exit scoring: `none`; `inside`, where a photon's main path leaves
    /// through a rough boundary from inside (TT, TRT, …) its exit lobe is scored over the
    /// outgoing bins in expectation instead of one draw (the branches a split event starts
    /// score theirs by their draw); `all`, and the first reflection R too.
    pub expected_exits: Option<Spanned<String>>,
    /// Where the photons take their uniform numbers: `random`, or `sobol` (each batch of
    /// photons one randomised Sobol' point set over the launch and the first boundary
    /// events).
    pub sampling: Option<Spanned<String>>,
    /// Incoming directions that share their photons: up to this many stored directions of one
    /// azimuth and neighbouring elevations trace one set of photons together, each weighted
    /// for its own direction (a whole number in [1, 8]; 1 = each traced alone). Used on
    /// straight fibers with a rough surface; others trace each direction alone.
    pub share_theta: Option<Spanned<f64>>,
    /// Adaptive allocation: each incoming direction traces past `photons_per_direction` until
    /// the median relative standard error of its table (over bins with f̂ ≥ 1 % of the
    /// slice's maximum) is at most this: a number in (0, 0.5], or `thesis` for the noise plain
    /// sampling with the thesis's 16 M photons gives that slice.
    pub target_rel_se: Option<Spanned<crate::spec::skin::raw::Token>>,
    /// The most photons one incoming direction may use under `target_rel_se` (a whole number).
    pub max_photons_per_direction: Option<Spanned<f64>>,
    /// Precision of the stored tables.
    pub precision: Option<Spanned<String>>,
    /// Mantissa bits kept (bit rounding; a whole number up to the precision's: 10 for f16, 23
    /// for f32; all by default).
    pub keep_bits: Option<Spanned<f64>>,
    /// Noise-aware rounding: each stored value keeps mantissa bits only down to this fraction
    /// of its bin's standard error (0 = off; 0.25 by default; `keep_bits` stays the upper
    /// bound).
    pub quantise_to_se: Option<Spanned<f64>>,
    /// zstd level of the `.bcsdf` frames: a whole number in [1, 22] (higher: smaller files,
    /// slower to bake; every level decodes as fast), or `auto` (the default): per stored
    /// direction, 19, 15, 9, 5 or 1 as its slice took at least 13, 5, 0.8, 0.25 or fewer
    /// photons per stored byte, which keeps compression near 3 % of the tracing's CPU time.
    pub zstd_level: Option<Spanned<crate::spec::skin::raw::Token>>,
    /// Channels of the tables: linear sRGB (D65), or one per wavelength.
    pub channels: Option<Spanned<String>>,
    /// The spectrum traced, nm.
    pub lambda_nm: Option<Spanned<RawLambda>>,
}

/// `lambda_nm: {start, end, step}`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawLambda {
    /// First wavelength, nm.
    pub start: Spanned<f64>,
    /// Last wavelength, nm (not below `start`).
    pub end: Spanned<f64>,
    /// Step, nm.
    pub step: Spanned<f64>,
}

/// `sweep:` — every dye × every depth of shade, from the same trace.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSweep {
    /// Dyes to bake, each once (presets or the spec's `dyes`).
    pub dyes: Spanned<Vec<Spanned<String>>>,
    /// Depths of shade ζ, percent of the fiber's weight, each once.
    pub depth_of_shade_percent: Spanned<Vec<Spanned<f64>>>,
    /// Also bake the undyed fiber (first).
    pub undyed: Option<Spanned<bool>>,
}

/// `{name, class, bands: [{peak_nm, fwhm_nm, peak_eps_l_per_mg_cm}]}` or `{name, class, csv}`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawDye {
    /// Name fibers use it by (not a preset's name).
    pub name: Spanned<String>,
    /// Dye class, whose peak extinction range the dye must have (§5.3.1).
    pub class: Spanned<String>,
    /// Gaussian absorption bands (at least one); or give `csv`.
    pub bands: Option<Spanned<Vec<Spanned<RawBand>>>>,
    /// A CSV of lambda_nm,eps_l_per_mg_cm rows (relative to the spec's folder); or give
    /// `bands`.
    pub csv: Option<Spanned<String>>,
    /// Where the spectrum comes from (recorded in the tables' provenance).
    pub source: Option<Spanned<String>>,
}

/// A Gaussian absorption band: ε(λ) = peak·exp(−4 ln 2 (λ − λp)²/FWHM²).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawBand {
    /// Wavelength of the peak λp, nm.
    pub peak_nm: Spanned<f64>,
    /// Full width at half maximum, nm.
    pub fwhm_nm: Spanned<f64>,
    /// Extinction at the peak, l mg⁻¹ cm⁻¹.
    pub peak_eps_l_per_mg_cm: Spanned<f64>,
}

/// One fiber to bake.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawFiber {
    /// Entry name (names the output files).
    pub name: Spanned<String>,
    /// Fiber type of Table 9 (diameter, density, refractive index, roughness).
    #[serde(rename = "type")]
    pub kind: Spanned<String>,
    /// Cross-section: the type's generated shape by default.
    pub section: Option<Spanned<RawSection>>,
    /// Diameter, µm (drawn in the type's Table 9 range by default; a polygon or mask keeps its
    /// measured size unless given).
    pub diameter_um: Option<Spanned<f64>>,
    /// Seed of the generated section and drawn diameter (a whole number; 1 by default).
    pub seed: Option<Spanned<f64>>,
    /// Which fiber of the seeded population (a whole number; 0 by default).
    pub variant: Option<Spanned<f64>>,
    /// Refractive index η (the type's by default).
    pub eta: Option<Spanned<f64>>,
    /// Beckmann slope angle β of the surface facets, degrees (the type's by default); or give
    /// `roughness`.
    pub beta_deg: Option<Spanned<f64>>,
    /// Surface roughness, for β = arctan(Ra/l) (§5.3.1); or give `beta_deg`.
    pub roughness: Option<Spanned<RawRoughness>>,
    /// Dye (a preset or one of the spec's `dyes`), with `depth_of_shade_percent`.
    pub dye: Option<Spanned<String>>,
    /// Depth of shade ζ of `dye`, percent of the fiber's weight (§5.3.1).
    pub depth_of_shade_percent: Option<Spanned<f64>>,
    /// Cuticle scales (wool has them by default).
    pub cuticle: Option<Spanned<RawCuticle>>,
    /// Seeded cross-sections baked into the table (a whole number; several need a generated
    /// `shape`).
    pub sections: Option<Spanned<f64>>,
    /// Every dye × every depth of shade, baked from the same trace; instead of `dye`.
    pub sweep: Option<Spanned<RawSweep>>,
    /// `auto`: detect the section's symmetries; `none`: trace every incoming direction.
    pub symmetry: Option<Spanned<String>>,
    /// This fiber's own estimators, each over the spec's `bake:` one (the best estimator
    /// differs between fiber types; the tables' layout and photons stay the spec's).
    pub estimators: Option<Spanned<RawEstimators>>,
}

/// `estimators:` of one fiber: the estimator fields of `bake:` (all optional; an absent one
/// is the spec's).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawEstimators {
    /// Draws per boundary event of the main path met from outside (a whole number; 1 = plain
    /// tracing).
    pub split: Option<Spanned<f64>>,
    /// Draws per boundary event met from inside the fiber (a whole number; 1 = plain
    /// tracing; never fewer than `split`: a smaller value draws `split` times, and is recorded so).
    pub exit_draws: Option<Spanned<f64>>,
    /// Expected-value exit scoring: `none`, `inside` or `all` (as `bake.expected_exits`).
    pub expected_exits: Option<Spanned<String>>,
    /// Where the photons take their uniform numbers: `random` or `sobol` (as `bake.sampling`).
    pub sampling: Option<Spanned<String>>,
    /// Incoming directions that share their photons (as `bake.share_theta`).
    pub share_theta: Option<Spanned<f64>>,
}

/// Exactly one of `shape` (a generator, or `ellipse` with `ratio`), `polygon` (CSV) or `mask`
/// (image, with `um_per_px`).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSection {
    /// A generated section, or `ellipse` (with `ratio`).
    pub shape: Option<Spanned<String>>,
    /// Minor/major axis ratio of `shape: ellipse`.
    pub ratio: Option<Spanned<f64>>,
    /// A CSV outline of x_um,y_um rows (a blank line or `hole` starts a hole), relative to the
    /// spec's folder.
    pub polygon: Option<Spanned<String>>,
    /// A binary image (PNG) of the section, relative to the spec's folder; with `um_per_px`.
    pub mask: Option<Spanned<String>>,
    /// Scale of `mask`, µm per pixel.
    pub um_per_px: Option<Spanned<f64>>,
    /// Smoothing passes over the outline of `mask` (a whole number).
    pub smoothing_passes: Option<Spanned<f64>>,
}

/// Surface roughness (§5.3.1).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawRoughness {
    /// Arithmetic mean roughness Ra, nm.
    pub ra_nm: Spanned<f64>,
    /// Correlation length l, nm (Ra/l at most tan 45° = 1).
    pub l_nm: Spanned<f64>,
}

/// Cuticle scales on the surface (wool's size and tilt by default).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawCuticle {
    /// Whether the fiber has the scales (true by default).
    pub enabled: Option<Spanned<bool>>,
    /// Length of a scale along the fiber, µm.
    pub length_um: Option<Spanned<f64>>,
    /// Tilt of a scale, degrees.
    pub tilt_deg: Option<Spanned<f64>>,
}
