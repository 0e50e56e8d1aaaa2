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
#[cfg(test)]
mod conventions;
mod export;
mod fiber;
mod init;
mod mc;
mod merge;
mod observer;
mod optics;
mod plan;
mod progress;
mod schema;
mod shell;
mod slurm;
mod validate;

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
    /// Check specs without baking: prints the entries they define, or every error with
    /// file:line.
    Validate(validate::ValidateArgs),
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
    /// Write a commented starter spec (skin or fiber) to begin from.
    Init(init::InitArgs),
    /// Shell completions for bash, zsh, fish, elvish or PowerShell.
    Completions(shell::CompletionsArgs),
    /// Manual pages (roff): baker.1 on standard output, or every command's page into a folder.
    Man(shell::ManArgs),
    /// Print the JSON Schema (draft 2020-12) of a spec kind, for editors and checkers.
    Schema(schema::SchemaArgs),
}

/// A command's text result to standard output, or atomically to `out` (announced unless
/// quiet).
fn emit_table(
    text: &str,
    out: Option<&std::path::Path>,
    progress: &observer::ProgressArgs,
) -> anyhow::Result<()> {
    match out {
        Some(path) => {
            crate::output::atomic::write(path, text.as_bytes())
                .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))?;
            progress.note(format!("wrote {}", path.display()));
            Ok(())
        }
        None => Ok(out!("{text}")?),
    }
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Validate(a) => validate::run(a),
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
        Command::Init(a) => init::run(a),
        Command::Completions(a) => shell::completions(a),
        Command::Man(a) => shell::man(a),
        Command::Schema(a) => schema::run(a),
    }
}
