//! `baker merge`: shard directories into the tables one bake would write.

use std::path::PathBuf;

use clap::Args;

use super::observer::ProgressArgs;

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Shard directories written by `baker bake … --shard I/N --out DIR`.
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Output root (as `baker bake --out`).
    #[arg(short = 'o', long = "out", default_value = "out")]
    pub out: PathBuf,
    #[command(flatten)]
    pub progress: ProgressArgs,
    /// Worker threads (default: all cores). The tables do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
}

pub fn run(m: MergeArgs) -> anyhow::Result<()> {
    crate::bake::merge::merge(&m.shards, &m.out, m.threads, m.progress.events())
}
