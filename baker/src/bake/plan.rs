//! `baker plan`: a spec's work units as `baker bake` with the same flags would run them.

use crate::pipeline::Cache;
use crate::profile::{self, SimOptions};
use crate::spec::Spec;
use crate::transport::RadialBins;

/// The work units of one spec (as `baker bake` with the same request would run them), with
/// whether each is in `cache`.
pub fn plan_units(
    spec: &Spec,
    stem: &str,
    req: &crate::bake::request::Request,
    cache: &Cache,
) -> anyhow::Result<Vec<crate::pipeline::UnitInfo>> {
    let pick = |name: &str| req.selects(name);
    let (photons, no_reuse) = (req.photons, req.no_reuse);
    let mut out = Vec::new();
    let spec = match spec {
        Spec::Fiber(spec) => {
            let mut st = spec.bake.clone();
            if let Some(p) = photons {
                st.photons = p;
            }
            let mut index = 0;
            for e in spec.fibers.iter().filter(|e| pick(&e.name)) {
                out.extend(super::fiber::plan_entry(stem, e, &st, cache, &mut index)?);
            }
            return Ok(out);
        }
        Spec::Skin(s) => s,
    };
    let optics = super::skin::optics_of(spec, |e| pick(&e.name));
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
    let units = profile::skin_units(&optics, lam, &bins, &plan, &sim);
    let prefix = format!("{stem}/skin");
    let nl = lam.len();
    for g in 0..plan.groups.len() {
        for (i, l) in lam.iter().enumerate() {
            if let Some(k) = units.pilot.get(g).and_then(|p| p.get(i)) {
                out.push(crate::pipeline::UnitInfo {
                    id: profile::simulate::unit_id(&prefix, "pilot/", g, *l),
                    key: k.hex(),
                    index: None,
                    photons: units.pilot_photons,
                    cached: cache.path(k).exists(),
                });
            }
        }
        for (i, l) in lam.iter().enumerate() {
            let k = &units.run[g][i];
            out.push(crate::pipeline::UnitInfo {
                id: profile::simulate::unit_id(&prefix, "", g, *l),
                key: k.hex(),
                index: Some(g * nl + i),
                photons: sim.photons,
                cached: cache.path(k).exists(),
            });
        }
    }
    Ok(out)
}
