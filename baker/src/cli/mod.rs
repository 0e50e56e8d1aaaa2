//! The commands behind the `baker` binary. `main.rs` only parses; everything runs from here.

/// `println!` that returns an error instead of panicking when stdout is closed (`| head`).
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($t)*)
    }};
}

/// `print!` counterpart of [`outln!`].
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($t)*)
    }};
}

mod bake;
mod bench;
mod cache;
mod export;
mod fiber;
mod mc;
mod merge;
mod observer;
mod optics;
mod plan;
mod progress;
mod schema;
mod slurm;
mod validate;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(
    name = "baker",
    version,
    about = "Offline asset baker for physically based skin and cloth"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check a spec without baking: prints the entries it defines, or every error with file:line.
    Validate {
        /// Spec file (YAML).
        spec: PathBuf,
    },
    /// Per-layer optical properties of skin entries (thesis ch. 3): d, η, μa(λ), μs′(λ),
    /// junction and surface parameters.
    Optics(optics::OpticsArgs),
    /// Layered Monte Carlo photon transport (MCML class): Rd, Tt, absorption, Rd(r) with
    /// standard errors, for a stack file, an MCML .mci file, or a skin spec entry.
    Mc(mc::McArgs),
    /// Transport throughput (photons/s, scattering events/s) on the thesis's reference skin
    /// stack, for each thread count.
    Bench(bench::BenchArgs),
    /// Single-fiber light transport (thesis ch. 5): trace a beam through one fiber.
    #[command(subcommand)]
    Fiber(fiber::FiberCommand),
    /// Bake whole specs into `--out` (default `out/`): every product of every entry.
    Bake(bake::BakeArgs),
    /// Convert a baked table to the parameters a renderer takes: Burley/OpenPBR/MaterialX,
    /// Blender, Unreal, Unity, pbrt-v4, Mitsuba 3 (skin); Chiang hair (fibers).
    Export(export::ExportArgs),
    /// Combine shard directories (`baker bake --shard I/N`) into the tables one bake would
    /// write, byte for byte.
    Merge(merge::MergeArgs),
    /// List the work units of specs, their cost and whether they are cached.
    Plan(plan::PlanArgs),
    /// Bake on a Slurm cluster: an array job of shards and a dependent merge job.
    Slurm(slurm::SlurmArgs),
    /// Manage the work-unit cache.
    #[command(subcommand)]
    Cache(cache::CacheCommand),
    /// Print the JSON Schema (draft 2020-12) of a spec kind, for editors and checkers.
    Schema(schema::SchemaArgs),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Validate { spec } => validate::run(&spec),
        Command::Optics(a) => optics::run(a),
        Command::Bake(a) => bake::run(a),
        Command::Mc(a) => mc::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Fiber(c) => fiber::run(c),
        Command::Export(a) => export::run(a),
        Command::Merge(m) => merge::run(m),
        Command::Plan(p) => plan::run(p),
        Command::Cache(c) => cache::run(c),
        Command::Slurm(a) => slurm::run(a),
        Command::Schema(a) => schema::run(a),
    }
}
