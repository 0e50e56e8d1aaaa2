//! `baker cache`: the work-unit cache.

use std::path::PathBuf;

use clap::Subcommand;

#[derive(Debug, Subcommand)]
pub enum CacheCommand {
    /// Delete cached units that no recorded bake uses (the roots are the keys of the last
    /// bake of each spec and shard).
    Gc {
        /// Output root whose recorded bakes keep their units (as `baker bake --out`).
        #[arg(short = 'o', long, default_value = "out")]
        out: PathBuf,
        /// Unit cache directory (default: OUT/.cache).
        #[arg(long, value_name = "DIR")]
        cache: Option<PathBuf>,
        /// Only list what would be deleted.
        #[arg(long)]
        dry_run: bool,
        /// Print nothing (errors still go to stderr).
        #[arg(short, long)]
        quiet: bool,
    },
}

pub fn run(c: CacheCommand) -> anyhow::Result<()> {
    match c {
        CacheCommand::Gc {
            out,
            cache,
            dry_run,
            quiet,
        } => {
            let dir = cache.unwrap_or_else(|| out.join(".cache"));
            let c = crate::bake::gc::collect(&dir, &out, dry_run)?;
            if quiet {
                return Ok(());
            }
            outln!(
                "{} {} unused units ({:.1} MB) from {}; {} in use",
                if dry_run { "would delete" } else { "deleted" },
                c.units,
                c.bytes as f64 / 1e6,
                dir.display(),
                c.live
            )?;
            Ok(())
        }
    }
}
