//! `profiles:`, how a skin spec's diffusion profiles are baked: photons, seed, Gaussians,
//! photon boost and the radial grid (its bins counted against `limits.radial_bins` before any
//! is allocated).

use super::cx::SkinCx;
use super::raw::{RawRadial, RawSpec};
use crate::spec::check::{count_text, loc, num, Bounds};
use crate::spec::limits::Limits;
use crate::spec::yaml::Spanned;

/// How the diffusion profiles of a spec are baked (`profiles:` block).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ProfileSettings {
    /// Photon packets per wavelength of each shared simulation.
    pub photons: u64,
    pub seed: u64,
    /// Gaussians in the sum-of-Gaussians fit (6 for real-time renderers).
    pub gaussians: usize,
    /// Cheap wavelengths get up to this many times `photons` ([`crate::profile::SimOptions`]).
    pub max_photon_boost: u64,
    /// Relative standard error the RGB profile bins (r ≤ min(2 mm, r99)) may relax to, never
    /// above what `photons` at every wavelength would give; packets per wavelength are then
    /// allocated from pilot runs (`profile::allocate`). 0: `photons` everywhere.
    pub noise_target: f64,
    /// Radial grid: bins of `dr_min_mm`, then each `growth` times wider, up to `r_max_mm`.
    pub dr_min_mm: f64,
    pub growth: f64,
    pub r_max_mm: f64,
}

impl Default for ProfileSettings {
    /// Photon count: ≤ 1 % relative standard error of every RGB profile bin out to 2 mm (and
    /// within the channel's 99 % radius) on the default database (measured; README
    /// "Diffusion profiles"). Grid: 10 µm core, 5 % growth, 40 mm —
    /// past the red 99 % radius of the most translucent entry.
    fn default() -> Self {
        Self {
            photons: DEFAULT_PROFILE_PHOTONS,
            seed: 1,
            gaussians: 6,
            max_photon_boost: 1,
            noise_target: DEFAULT_NOISE_TARGET,
            dr_min_mm: 0.01,
            growth: 1.05,
            r_max_mm: 40.0,
        }
    }
}

/// Default photons per wavelength and shared simulation.
pub const DEFAULT_PROFILE_PHOTONS: u64 = 4_000_000;

/// Default noise target: 1 % relative standard error (README "Diffusion profiles").
pub const DEFAULT_NOISE_TARGET: f64 = 0.01;

/// Radius out to which a noise target holds, mm (profile/DECISIONS.md row 7).
pub const NOISE_R_MAX_MM: f64 = 2.0;

/// Under a noise target a wavelength gets at least 1/`MIN_SHARE` of `photons` (so every
/// spectral profile keeps some precision) and at most `MAX_SHARE` times them.
pub const MIN_SHARE: u64 = 10;
pub const MAX_SHARE: u64 = 4;

/// Packets of a noise target's pilot run per wavelength: 2.5 % of `photons`, at most this.
pub const NOISE_PILOT_MAX: u64 = 100_000;

/// Packets of a photon boost's pilot run per wavelength: 1 % of `photons`, at most this.
pub const BOOST_PILOT_MAX: u64 = 20_000;

/// `profiles.photons`: packets per wavelength and shared simulation.
pub(in crate::spec) const PHOTONS: Bounds = Bounds::whole(1.0, 1e12);
/// `profiles.seed`: any whole number an f64 holds exactly (up to 2^53).
pub(in crate::spec) const SEED: Bounds = Bounds::whole(0.0, 9.007_199_254_740_992e15);
/// `profiles.gaussians`: terms of the sum-of-Gaussians fit.
pub(in crate::spec) const GAUSSIANS: Bounds = Bounds::whole(1.0, 16.0);
/// `profiles.max_photon_boost`: at most this many times `photons` for cheap wavelengths.
pub(in crate::spec) const MAX_PHOTON_BOOST: Bounds = Bounds::whole(1.0, 64.0);
/// `profiles.noise_target`: relative standard error (0 = `photons` everywhere).
pub(in crate::spec) const NOISE_TARGET: Bounds = Bounds::closed(0.0, 0.5);
/// `profiles.radial.dr_min_mm`: width of the fine bins, mm.
pub(in crate::spec) const DR_MIN_MM: Bounds = Bounds::above(0.0, 1.0);
/// `profiles.radial.growth`: each coarse bin this many times wider than the one before.
pub(in crate::spec) const GROWTH: Bounds = Bounds::closed(1.001, 2.0);
/// `profiles.radial.r_max_mm`: outer radius of the grid, mm.
pub(in crate::spec) const R_MAX_MM: Bounds = Bounds::above(0.0, 1000.0);

impl SkinCx {
    pub(super) fn profiles(&mut self, raw: &RawSpec, limits: &Limits) -> ProfileSettings {
        let mut s = ProfileSettings::default();
        let Some(p) = &raw.profiles else {
            return s;
        };
        let p = &p.value;
        if let Some(n) = self.whole("profiles.photons", &p.photons, PHOTONS.lo, PHOTONS.hi) {
            s.photons = n;
        }
        if let Some(n) = self.whole("profiles.seed", &p.seed, SEED.lo, SEED.hi) {
            s.seed = n;
        }
        if let Some(n) = self.whole(
            "profiles.gaussians",
            &p.gaussians,
            GAUSSIANS.lo,
            GAUSSIANS.hi,
        ) {
            s.gaussians = n as usize;
        }
        if let Some(n) = self.whole(
            "profiles.max_photon_boost",
            &p.max_photon_boost,
            MAX_PHOTON_BOOST.lo,
            MAX_PHOTON_BOOST.hi,
        ) {
            s.max_photon_boost = n;
        }
        s.noise_target = self.opt_bounds(
            "profiles.noise_target",
            &p.noise_target,
            NOISE_TARGET,
            s.noise_target,
        );
        if s.noise_target > 0.0 && s.max_photon_boost > 1 {
            if let Some(b) = &p.max_photon_boost {
                self.invalid(
                    loc(b),
                    "profiles.max_photon_boost",
                    "a boost applies without a noise target only; set `noise_target: 0` to use it",
                );
            }
        }
        if let Some(r) = &p.radial {
            self.radial(r, limits, &mut s);
        }
        s
    }

    /// `profiles.radial` into `s`; the defaults where it gives too many bins.
    fn radial(&mut self, r: &Spanned<RawRadial>, limits: &Limits, s: &mut ProfileSettings) {
        let radial_at = loc(r);
        let r = &r.value;
        s.dr_min_mm = self.opt_bounds(
            "profiles.radial.dr_min_mm",
            &r.dr_min_mm,
            DR_MIN_MM,
            s.dr_min_mm,
        );
        s.growth = self.opt_bounds("profiles.radial.growth", &r.growth, GROWTH, s.growth);
        s.r_max_mm = self.opt_bounds(
            "profiles.radial.r_max_mm",
            &r.r_max_mm,
            R_MAX_MM,
            s.r_max_mm,
        );
        if s.r_max_mm <= s.dr_min_mm {
            let at = r.r_max_mm.as_ref().map(loc).unwrap_or(radial_at);
            self.invalid(
                at,
                "profiles.radial.r_max_mm",
                format!("must exceed dr_min_mm = {}", s.dr_min_mm),
            );
            s.r_max_mm = 40.0;
        }
        // The bins the grid will have, counted (and capped) before any is allocated.
        let cap = limits.radial_bins;
        let n = crate::transport::RadialBins::fine_then_log_count(
            s.dr_min_mm,
            s.growth,
            s.r_max_mm,
            cap,
        );
        if n > cap {
            let at = r
                .dr_min_mm
                .as_ref()
                .or(r.growth.as_ref())
                .or(r.r_max_mm.as_ref())
                .map_or(radial_at, loc);
            self.over_limit(
                at,
                "profiles.radial",
                format!(
                    "dr_min_mm = {}, growth = {}, r_max_mm = {} give more than {} radial bins",
                    num(s.dr_min_mm),
                    num(s.growth),
                    num(s.r_max_mm),
                    count_text(cap)
                ),
                "radial_bins",
                count_text(cap),
            );
            let d = ProfileSettings::default();
            (s.dr_min_mm, s.growth, s.r_max_mm) = (d.dr_min_mm, d.growth, d.r_max_mm);
        }
    }
}
