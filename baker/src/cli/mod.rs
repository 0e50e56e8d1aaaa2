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
mod bake_fiber;
mod bench;
mod export;
mod fiber;
mod mc;
mod optics;
pub mod pipeline;
mod progress;
mod slurm;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

/// A user error (bad spec, bad flag combination): exit code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

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
    Merge(pipeline::MergeArgs),
    /// List the work units of specs, their cost and whether they are cached.
    Plan(pipeline::PlanArgs),
    /// Bake on a Slurm cluster: an array job of shards and a dependent merge job.
    Slurm(slurm::SlurmArgs),
    /// Manage the work-unit cache.
    #[command(subcommand)]
    Cache(pipeline::CacheCommand),
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Validate { spec } => validate(&spec),
        Command::Optics(a) => optics::run(a),
        Command::Bake(a) => bake::run(a),
        Command::Mc(a) => mc::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Fiber(c) => fiber::run(c),
        Command::Export(a) => export::run(a),
        Command::Merge(m) => pipeline::merge(m),
        Command::Plan(p) => pipeline::plan(p),
        Command::Cache(c) => pipeline::cache(c),
        Command::Slurm(a) => slurm::run(a),
    }
}

/// `baker validate`: the checks `baker bake` makes before it writes anything — the same code
/// path — and what the spec defines.
fn validate(spec: &std::path::Path) -> anyhow::Result<()> {
    let (s, cost) = bake::load_checked(spec, &crate::spec::budget::Overrides::none())?;
    bake::spec_stem(spec)?;
    match &s {
        crate::spec::Spec::Fiber(s) => {
            outln!(
                "{}: ok, {} fibers, {} dyes (presets included); {}",
                spec.display(),
                s.fibers.len(),
                s.dyes.len(),
                cost.describe()
            )?;
            for f in &s.fibers {
                outln!(
                    "  {} (line {}): {}, {:.2} µm, area {:.1} µm², {} hole(s), η {:.4}, β {:.2}°{}{}",
                    f.name,
                    f.line,
                    f.fiber_type.name,
                    f.diameter_um,
                    f.section.area_um2(),
                    f.section.hole_count(),
                    f.eta,
                    f.beta_deg,
                    f.cuticle.map_or(String::new(), |c| format!(
                        ", cuticle {} µm × {}°",
                        c.length_um, c.tilt_deg
                    )),
                    f.dye.as_ref().map_or(String::new(), |(d, z)| format!(
                        ", {} at {}% (μa(550 nm) = {:.3} /mm)",
                        d.name,
                        z * 100.0,
                        f.mua_per_um(550.0) * 1e3
                    )),
                )?;
            }
        }
        crate::spec::Spec::Skin(s) => {
            outln!(
                "{}: ok, {} entries, {} wavelengths ({}–{} nm); {}",
                spec.display(),
                s.entries.len(),
                s.wavelengths.len(),
                s.wavelengths.lambda_nm()[0],
                s.wavelengths.lambda_nm()[s.wavelengths.len() - 1],
                cost.describe()
            )?;
            for e in &s.entries {
                outln!("  {} (line {})", e.name, e.line)?;
            }
        }
    }
    Ok(())
}

/// Loads a spec; its errors become a [`UsageError`] listing every problem.
pub(crate) fn load_spec(path: &std::path::Path) -> anyhow::Result<crate::spec::SkinSpec> {
    crate::spec::load(path).map_err(|e| UsageError(e.to_string().trim_end().to_string()).into())
}
