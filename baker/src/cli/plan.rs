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
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    #[arg(long)]
    pub photons: Option<u64>,
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    #[arg(long)]
    pub no_reuse: bool,
    /// Worker threads the bake will run (for the memory bound; default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
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
    let mut units = Vec::new();
    let mut costs = Vec::new();
    let loaded = p
        .specs
        .iter()
        .map(|path| bake::load_checked(path, &o))
        .collect::<anyhow::Result<Vec<_>>>()?;
    bake::check_entries(&req, loaded.iter().map(|(s, _)| s))?;
    for (path, (spec, cost)) in p.specs.iter().zip(loaded) {
        let stem = bake::spec_stem(path)?;
        units.extend(bake::plan::plan_units(&spec, &stem, &req, &cache)?);
        costs.push((path.clone(), cost, *spec.limits()));
    }
    let cached = units.iter().filter(|u| u.cached).count();
    let photons: u64 = units.iter().filter(|u| !u.cached).map(|u| u.photons).sum();
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
                "units": units, "total": units.len(), "cached": cached,
                "photons_to_trace": photons, "cache": cache.dir, "budget": budgets,
            }))?
        )?;
        return Ok(());
    }
    outln!(
        "{:<56} {:>7} {:>14} {}",
        "unit",
        "shard#",
        "photons",
        "cached"
    )?;
    for u in &units {
        outln!(
            "{:<56} {:>7} {:>14} {}",
            u.id,
            u.index.map_or("-".into(), |i| i.to_string()),
            u.photons,
            if u.cached { "yes" } else { "no" }
        )?;
    }
    outln!(
        "{} units, {cached} cached; {photons} photons to trace (cache {})",
        units.len(),
        cache.dir.display()
    )?;
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
