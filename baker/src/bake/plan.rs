//! `baker plan`: a spec's work units as `baker bake` with the same flags would run them, and
//! what they will take.

use super::estimate::{self, SkinCalibration, SkinInputs};
use crate::pipeline::{Cache, CacheMode, Events, Runner, UnitInfo};
use crate::profile::{self, SimOptions};
use crate::spec::Spec;
use crate::transport::{McOptions, RadialBins};

/// One spec's plan: its units and, with an estimate, the calibration's own seconds.
#[derive(Debug, Clone)]
pub struct SpecPlan {
    pub units: Vec<UnitInfo>,
    pub calibration_s: Option<f64>,
}

/// The work units of one spec (as `baker bake` with the same request would run them), with
/// whether each is in `cache`; with `estimate`, a short calibration run of the spec's own
/// units gives each its estimated seconds on the request's threads.
pub fn plan_units(
    spec: &Spec,
    stem: &str,
    req: &crate::bake::request::Request,
    cache: &Cache,
    estimate: bool,
) -> anyhow::Result<SpecPlan> {
    match spec {
        Spec::Fiber(spec) => {
            let mut st = spec.bake.clone();
            if let Some(p) = req.photons {
                st.photons = p;
            }
            let (mut index, mut out, mut cal) = (0, Vec::new(), None);
            for e in spec.fibers.iter().filter(|e| req.selects(&e.name)) {
                let st = e.settings(&st);
                let cost = if estimate {
                    let (c, s) = super::fiber::calibrate_entry(e, &st)?;
                    *cal.get_or_insert(0.0) += s;
                    Some((c, req.thread_count()))
                } else {
                    None
                };
                out.extend(super::fiber::plan_entry(
                    stem, e, &st, cache, &mut index, cost,
                )?);
            }
            Ok(SpecPlan {
                units: out,
                calibration_s: cal,
            })
        }
        Spec::Skin(s) => skin_units(s, stem, req, cache, estimate),
    }
}

/// [`plan_units`] of a skin spec: per group its pilots and runs, then one fit per entry.
fn skin_units(
    spec: &crate::spec::SkinSpec,
    stem: &str,
    req: &crate::bake::request::Request,
    cache: &Cache,
    estimate: bool,
) -> anyhow::Result<SpecPlan> {
    let (photons, no_reuse) = (req.photons, req.no_reuse);
    let mut out = Vec::new();
    let optics = super::skin::optics_of(spec, |e| req.selects(&e.name));
    if req.optics_only {
        return Ok(SpecPlan {
            units: out,
            calibration_s: None,
        });
    }
    let lam = spec.wavelengths.lambda_nm();
    let s = &spec.profiles;
    let bins = RadialBins::fine_then_log(s.dr_min_mm, s.growth, s.r_max_mm);
    let plan = profile::plan(&optics, lam.len(), !no_reuse);
    let sim = SimOptions {
        photons: photons.unwrap_or(s.photons),
        seed: s.seed,
        threads: None,
        max_boost: s.max_photon_boost,
        noise: profile::NoiseTarget::new(s.noise_target, photons.unwrap_or(s.photons)),
        progress: None,
    };
    let cal = if estimate {
        Some(estimate::calibrate_skin(&SkinInputs {
            entries: &optics,
            lambda_nm: lam,
            bins: &bins,
            plan: &plan,
            sim: &sim,
            gaussians: s.gaussians,
        })?)
    } else {
        None
    };
    let threads = req.thread_count();
    let batch = McOptions::new(1, 0).batch_size;
    let units = profile::skin_units(&optics, lam, &bins, &plan, &sim);
    let prefix = format!("{stem}/skin");
    let nl = lam.len();
    let seconds = |n: u64, g: usize, i: usize, cached: bool| {
        cal.as_ref().map(|c: &SkinCalibration| {
            if cached {
                0.0
            } else {
                estimate::transport_seconds(n, c.cost[g][i], threads, batch)
            }
        })
    };
    for g in 0..plan.groups.len() {
        let boosted = cal
            .as_ref()
            .map(|c| estimate::boosted(sim.photons, &c.cost[g], &sim));
        for (i, l) in lam.iter().enumerate() {
            if let Some(k) = units.pilot.get(g).and_then(|p| p.get(i)) {
                let cached = cache.path(k).exists();
                out.push(UnitInfo {
                    id: profile::simulate::unit_id(&prefix, "pilot/", g, *l),
                    key: k.hex(),
                    index: None,
                    photons: units.pilot_photons,
                    cached,
                    kind: "pilot",
                    estimate_s: seconds(units.pilot_photons, g, i, cached),
                });
            }
        }
        for (i, l) in lam.iter().enumerate() {
            let k = &units.run[g][i];
            let cached = cache.path(k).exists();
            let n = boosted.as_ref().map_or(sim.photons, |b| b[i]);
            out.push(UnitInfo {
                id: profile::simulate::unit_id(&prefix, "", g, *l),
                key: k.hex(),
                index: Some(g * nl + i),
                photons: sim.photons,
                cached,
                kind: "transport",
                estimate_s: seconds(n, g, i, cached),
            });
        }
    }
    let runs_cached = out.iter().all(|u| u.kind == "pilot" || u.cached);
    let sim_in = profile::SkinSimulation {
        entries: &optics,
        lambda_nm: lam,
        bins: &bins,
        plan: &plan,
        o: &sim,
    };
    let fits = fit_units(stem, spec, &optics, cache, runs_cached.then_some(&sim_in))?;
    let n_fit = fits.iter().filter(|u| !u.cached).count();
    for mut u in fits {
        // The fits run in parallel over the entries, one per thread.
        u.estimate_s = cal.as_ref().map(|c| {
            if u.cached {
                0.0
            } else {
                c.fit_seconds * (n_fit as f64 / threads as f64).max(1.0) / n_fit as f64
            }
        });
        out.push(u);
    }
    Ok(SpecPlan {
        units: out,
        calibration_s: cal.map(|c| c.seconds),
    })
}

/// One Gaussian-fit unit per entry (the bake fits every entry's RGB profile after the
/// simulations). Its key is that of the entry's spectral profile: known only when every
/// simulation is cached (`sim` given), else empty and the fit counted as to do.
fn fit_units(
    stem: &str,
    spec: &crate::spec::SkinSpec,
    optics: &[formats::OpticsEntry],
    cache: &Cache,
    sim: Option<&profile::SkinSimulation<'_>>,
) -> anyhow::Result<Vec<UnitInfo>> {
    let profiles = match sim {
        Some(sim) => {
            let mut runner = Runner::new(
                Cache::new(cache.dir.clone(), CacheMode::Use),
                Events::silent(),
                None,
            );
            runner.require_cached = true;
            // Read-only: every unit is in the cache, nothing is computed or stored.
            profile::simulate_units(sim, &runner, "", |_, _, _| {})
                .ok()
                .flatten()
        }
        None => None,
    };
    Ok(optics
        .iter()
        .enumerate()
        .map(|(j, e)| {
            let key = profiles
                .as_ref()
                .map(|p| super::skin::fit_key(&p[j], spec.profiles.gaussians));
            UnitInfo {
                id: super::skin::fit_id(stem, &e.name),
                key: key.map(|k| k.hex()).unwrap_or_default(),
                index: None,
                photons: 0,
                cached: key.is_some_and(|k| cache.path(&k).exists()),
                kind: "fit",
                estimate_s: None,
            }
        })
        .collect())
}

/// What `baker plan` prints for all its specs.
#[derive(Debug, Clone)]
pub struct Report {
    pub units: Vec<UnitInfo>,
    /// Seconds the calibration runs took (`None`: no estimate).
    pub calibration_s: Option<f64>,
    pub threads: usize,
}

impl Report {
    pub fn cached(&self) -> usize {
        self.units.iter().filter(|u| u.cached).count()
    }

    /// Photons still to trace (before the boost of cheap skin wavelengths).
    pub fn photons_to_trace(&self) -> u64 {
        self.units
            .iter()
            .filter(|u| !u.cached)
            .map(|u| u.photons)
            .sum()
    }

    /// Estimated seconds of the whole bake (`None` without an estimate).
    pub fn estimate_s(&self) -> Option<f64> {
        self.calibration_s?;
        Some(self.units.iter().filter_map(|u| u.estimate_s).sum())
    }

    fn count(&self, kind: &str) -> usize {
        self.units.iter().filter(|u| u.kind == kind).count()
    }

    /// The plan as text: one line per unit (with `rows`), then the totals and the estimate.
    pub fn table(&self, rows: bool) -> String {
        use crate::progress::{duration, grouped, si};
        use std::fmt::Write as _;
        let mut s = String::new();
        let est = self.calibration_s.is_some();
        let units: &[UnitInfo] = if rows { &self.units } else { &[] };
        if rows {
            let _ = writeln!(
                s,
                "{:<56} {:<9} {:>7} {:>14} {:<6}{}",
                "unit",
                "kind",
                "shard#",
                "photons",
                "cached",
                if est { "  estimate" } else { "" }
            );
        }
        for u in units {
            let e = u.estimate_s.map_or(String::new(), |e| {
                format!("  {:>8}", if u.cached { "-".into() } else { duration(e) })
            });
            let _ = writeln!(
                s,
                "{:<56} {:<9} {:>7} {:>14} {:<6}{e}",
                u.id,
                u.kind,
                u.index.map_or("-".into(), |i| i.to_string()),
                if u.kind == "fit" {
                    "-".into()
                } else {
                    si(u.photons as f64, "")
                },
                if u.cached { "yes" } else { "no" }
            );
        }
        let kinds: Vec<String> = [
            ("transport", "transport"),
            ("pilot", "pilot"),
            ("fit", "fit"),
            ("fiber", "fiber"),
        ]
        .iter()
        .filter(|(k, _)| self.count(k) > 0)
        .map(|(k, name)| format!("{} {name}", self.count(k)))
        .collect();
        let p = self.photons_to_trace();
        let _ = write!(
            s,
            "{} units ({}), {} cached; {} to trace ({})",
            self.units.len(),
            kinds.join(", "),
            self.cached(),
            si(p as f64, "photons"),
            grouped(p)
        );
        if let (Some(e), Some(c)) = (self.estimate_s(), self.calibration_s) {
            let fits: f64 = self
                .units
                .iter()
                .filter(|u| u.kind == "fit")
                .filter_map(|u| u.estimate_s)
                .sum();
            let _ = write!(
                s,
                "\nestimated {} on {} thread(s) (from a {} calibration run{})",
                duration(e),
                self.threads,
                duration(c),
                if self.count("fit") > 0 {
                    format!("; Gaussian fits {}", duration(fits))
                } else {
                    String::new()
                }
            );
        }
        s
    }
}
