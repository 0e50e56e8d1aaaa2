//! `baker plan`: the work units of specs, their cost and whether they are cached.

use std::path::PathBuf;

use clap::Args;

use crate::bake::{self, Request};

#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Spec files.
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Output root whose cache is consulted (as `baker bake --out`).
    #[arg(short = 'o', long, default_value = "out")]
    pub out: PathBuf,
    /// Unit cache directory (default: OUT/.cache), as `baker bake --cache`.
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Photon packets per simulation or direction, as `baker bake --photons`.
    #[arg(long)]
    pub photons: Option<u64>,
    /// Plan only this entry (repeatable), as `baker bake --entry`.
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Skin: one simulation per entry, as `baker bake --no-reuse`.
    #[arg(long)]
    pub no_reuse: bool,
    /// Worker threads the bake will run (for the memory bound; default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Print only the totals and the time estimate, not one line per unit.
    #[arg(short, long)]
    pub quiet: bool,
    /// Skip the time estimate (a calibration run of about a second per spec).
    #[arg(long)]
    pub no_estimate: bool,
}

/// `baker plan`: the work units of the specs, their cost and whether they are cached, and
/// what each bake will cost (photons, the memory bound) against the spec's limits.
pub fn run(p: PlanArgs) -> anyhow::Result<()> {
    let req = Request {
        specs: p.specs.clone(),
        out: p.out.clone(),
        entries: p.entries.clone(),
        photons: p.photons,
        threads: p.threads,
        no_reuse: p.no_reuse,
        cache: p.cache.clone(),
        ..Request::default()
    };
    let o = req.overrides();
    let cache = crate::pipeline::Cache::new(req.cache_dir(), crate::pipeline::CacheMode::Use);
    let mut report = bake::plan::Report {
        units: Vec::new(),
        calibration_s: None,
        threads: req.thread_count(),
    };
    let mut costs = Vec::new();
    let loaded = p
        .specs
        .iter()
        .map(|path| bake::load_checked(path, &o))
        .collect::<anyhow::Result<Vec<_>>>()?;
    bake::check_entries(&req, loaded.iter().map(|(s, _)| s))?;
    for (path, (spec, cost)) in p.specs.iter().zip(loaded) {
        let stem = bake::spec_stem(path)?;
        let plan = bake::plan::plan_units(&spec, &stem, &req, &cache, !p.no_estimate)?;
        report.units.extend(plan.units);
        if let Some(c) = plan.calibration_s {
            *report.calibration_s.get_or_insert(0.0) += c;
        }
        costs.push((path.clone(), cost, *spec.limits()));
    }
    if p.json {
        let budgets: Vec<serde_json::Value> = costs
            .iter()
            .map(|(path, c, l)| {
                serde_json::json!({"spec": path, "photons_max": c.photons,
                    "memory_bytes_max": c.memory_bytes, "threads": o.threads, "limits": l})
            })
            .collect();
        outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "units": report.units, "total": report.units.len(), "cached": report.cached(),
                "photons_to_trace": report.photons_to_trace(), "cache": cache.dir,
                "budget": budgets, "estimate_s": report.estimate_s(),
                "calibration_s": report.calibration_s, "threads": report.threads,
            }))?
        )?;
        return Ok(());
    }
    outln!("{}", report.table(!p.quiet))?;
    outln!("cache {}", cache.dir.display())?;
    for (path, c, l) in &costs {
        outln!(
            "{}: at most {} on {} thread(s) (limits: {:.3e} photons, {} GiB)",
            path.display(),
            c.describe(),
            o.threads,
            l.photons,
            l.memory_gib
        )?;
    }
    Ok(())
}
