//! `baker bake`: the flags of a bake, as a [`Request`] for the bake library.

use std::path::PathBuf;

use clap::Args;

use super::observer::ProgressArgs;
use crate::bake::Request;
use crate::pipeline::Shard;

#[derive(Debug, Args)]
pub struct BakeArgs {
    /// Spec files (YAML).
    #[arg(required = true)]
    pub specs: Vec<PathBuf>,
    /// Output root; each spec bakes into OUT/<spec name>/.
    #[arg(short = 'o', long, default_value = "out")]
    pub out: PathBuf,
    /// Bake only this entry (repeatable), e.g. for a preview.
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Photon packets per wavelength and simulation, overriding the spec's `profiles.photons`
    /// (fewer for a quick preview).
    #[arg(long)]
    pub photons: Option<u64>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub progress: ProgressArgs,
    /// Skin: skip the Monte Carlo profiles, layer optics only.
    #[arg(long)]
    pub optics_only: bool,
    /// Skin: one simulation per entry instead of one per group of entries sharing scattering (to
    /// measure what absorption reuse saves; results differ only by Monte Carlo noise).
    #[arg(long)]
    pub no_reuse: bool,
    /// Skin: also write PNG plots of every entry's coefficients.
    #[arg(long)]
    pub plots: bool,
    /// Bake only the work units of shard I of N (1 ≤ I ≤ N) into OUT (their cache and
    /// `shard.json`); `baker merge` assembles the tables from all shards.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
    /// Recompute every work unit even if it is cached (and overwrite the cache).
    #[arg(long)]
    pub force: bool,
    /// Write a subset bake (some --entry, fewer --photons, --optics-only) to OUT/<spec>/
    /// itself, replacing the finished bake there. Without it a subset goes to
    /// OUT/<spec>/subset/, and a finished bake of the same spec with more entries or photons
    /// is never replaced.
    #[arg(long)]
    pub replace: bool,
    /// Unit cache directory (default: OUT/.cache).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
}

impl BakeArgs {
    /// The bake these flags ask for.
    pub fn request(&self) -> Request {
        Request {
            specs: self.specs.clone(),
            out: self.out.clone(),
            entries: self.entries.clone(),
            photons: self.photons,
            threads: self.threads,
            optics_only: self.optics_only,
            no_reuse: self.no_reuse,
            plots: self.plots,
            shard: self.shard,
            force: self.force,
            replace: self.replace,
            cache: self.cache.clone(),
            require_cached: false,
        }
    }
}

pub fn run(a: BakeArgs) -> anyhow::Result<()> {
    crate::bake::run(&a.request(), a.progress.events())
}
