//! `baker fiber trace`: one incoming direction through one fiber (§5.3.2), from a spec entry or
//! from a fiber described on the command line.

use std::path::PathBuf;

use clap::{Args, Subcommand};
use serde_json::json;

use crate::error::UsageError;
use crate::fiber::section::generate::{generate, Shape};
use crate::fiber::section::mask::{from_mask, MaskOptions};
use crate::fiber::slices::{BakeSettings, ExpectedExits, Sampling};
use crate::fiber::tracer::shared::MAX_SHARED;
use crate::fiber::{trace, AngularGrid, Cuticle, Fiber, Incident, Section, Surface, TraceOptions};
use crate::spec::fiber::{FiberEntry, TableStorage, MAX_EXIT_DRAWS, MAX_SPLIT};

#[derive(Debug, Subcommand)]
pub enum FiberCommand {
    /// Trace a beam from one direction ωi through one fiber: albedo, projected area,
    /// photons/s, and the outgoing distribution over (θo, Δφ).
    Trace(TraceArgs),
    /// Tracer throughput (photons/s) for each fiber of a spec (default `specs/fibers.yaml`)
    /// and a smooth circular fiber, at each thread count.
    Bench(FiberBenchArgs),
}

#[derive(Debug, Args)]
pub struct FiberBenchArgs {
    /// Fiber specs whose entries are measured.
    #[arg(default_value = "specs/fibers.yaml")]
    pub specs: Vec<PathBuf>,
    /// Measure only this entry (repeatable; default: every entry).
    #[arg(long = "entry", value_name = "NAME")]
    pub entries: Vec<String>,
    /// Photons per measurement.
    #[arg(long, default_value_t = 4_000_000)]
    pub photons: u64,
    /// Thread counts to measure, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Repetitions per measurement (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Incident θi, degrees.
    #[arg(long, allow_hyphen_values = true, default_value_t = -45.0)]
    pub theta_i: f64,
    /// Instead of throughput: per entry, the time one cross-section takes to bake at the
    /// thesis's fidelity (2° bins, each direction traced to the noise of 16 M plain photons)
    /// with the spec's estimators, from a sample of its directions scaled up, next to the
    /// thesis's Table 10.
    #[arg(long)]
    pub thesis: bool,
    /// With --thesis: stored directions measured per entry (evenly spread).
    #[arg(long, default_value_t = 6, requires = "thesis")]
    pub directions: usize,
    /// With --thesis: instead of --directions, every stored θ row of this many evenly spread
    /// φ columns (the same directions whatever `share_theta`).
    #[arg(long, requires = "thesis")]
    pub columns: Option<usize>,
    /// With --thesis: trace each entry's first variant as the spec dyes it (the table a bake
    /// of the entry stores, reaching the target on that variant) instead of the undyed fiber
    /// (the thesis's noise is defined on it, and Table 10 times a monochromatic table).
    #[arg(long, requires = "thesis")]
    pub dyed: bool,
    /// With --thesis: override the spec's `bake.split` (draws per event met from outside).
    #[arg(long, requires = "thesis", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SPLIT)))]
    pub split: Option<u32>,
    /// With --thesis: override the spec's `bake.exit_draws` (draws per event met from inside).
    #[arg(long, requires = "thesis", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_EXIT_DRAWS)))]
    pub exit_draws: Option<u32>,
    /// With --thesis: override the spec's `bake.expected_exits` (none, inside or all).
    #[arg(long, requires = "thesis", value_parser = expected_exits_arg)]
    pub expected_exits: Option<ExpectedExits>,
    /// With --thesis: override the spec's `bake.sampling` (random or sobol).
    #[arg(long, requires = "thesis", value_parser = sampling_arg)]
    pub sampling: Option<Sampling>,
    /// With --thesis: override the spec's `bake.share_theta` (incoming directions sharing
    /// their photons, 1–8).
    #[arg(long, requires = "thesis", value_parser = clap::value_parser!(u32).range(1..=MAX_SHARED as i64))]
    pub share_theta: Option<u32>,
    /// Write the table to FILE, atomically, instead of standard output.
    #[arg(short = 'o', long = "out", value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub progress: super::observer::ProgressArgs,
}

#[derive(Debug, Args)]
pub struct TraceArgs {
    /// Fiber specs (YAML with `fibers:`); use with --entry. Omit to describe the fiber with
    /// --section and the flags below.
    pub specs: Vec<PathBuf>,
    /// Fiber entry of the spec (repeatable: each is traced in turn).
    #[arg(long = "entry", value_name = "NAME", requires = "specs")]
    pub entries: Vec<String>,
    /// θi, degrees in [−90, 90]: ωi (towards the light) makes this angle with the plane
    /// normal to the fiber axis (+z).
    #[arg(long, allow_hyphen_values = true)]
    pub theta_i: f64,
    /// φi, degrees: azimuth of ωi about the fiber axis, from +x towards +y.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.0)]
    pub phi_i: f64,
    /// Photons launched across the beam [default: 1000000; with a spec entry, its
    /// `bake.photons_per_direction`, the first pass when it has a `target_rel_se`].
    #[arg(long)]
    pub photons: Option<u64>,
    /// Seed: the same inputs and seed give bit-identical output for any thread count
    /// [default: 1; with a spec entry, its `bake.seed`].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Bin size of θo and Δφ, degrees (must divide 180) [default: 2; with a spec entry, its
    /// `bake.resolution_deg`].
    #[arg(long)]
    pub resolution_deg: Option<f64>,
    /// With a spec entry: override its `bake.split` (draws per event met from outside).
    #[arg(long, requires = "specs", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SPLIT)))]
    pub split: Option<u32>,
    /// With a spec entry: override its `bake.exit_draws` (draws per event met from inside).
    #[arg(long, requires = "specs", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_EXIT_DRAWS)))]
    pub exit_draws: Option<u32>,
    /// With a spec entry: override its `bake.expected_exits` (none, inside or all).
    #[arg(long, requires = "specs", value_parser = expected_exits_arg)]
    pub expected_exits: Option<ExpectedExits>,
    /// With a spec entry: override its `bake.sampling` (random or sobol).
    #[arg(long, requires = "specs", value_parser = sampling_arg)]
    pub sampling: Option<Sampling>,
    /// With a spec entry: override its `bake.share_theta` (directions sharing their photons,
    /// 1–8; the direction is traced with the k − 1 θ rows on either side, as its windows
    /// in a bake hold it).
    #[arg(long, requires = "specs", value_parser = clap::value_parser!(u32).range(1..=MAX_SHARED as i64))]
    pub share_theta: Option<u32>,
    /// Write the outgoing slice as a false-colour log PNG (like Table 8) to FILE.png; with
    /// several --entry, FILE is a folder and each entry gets `<entry>.png` in it.
    #[arg(short = 'o', long = "out", alias = "png", value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub progress: super::observer::ProgressArgs,
    /// Print one JSON object per traced fiber (one per line) instead of a summary.
    #[arg(long)]
    pub json: bool,
    /// Wavelength at which a spec entry's dye gives μa, nm.
    #[arg(long, default_value_t = 550.0, requires = "specs")]
    pub lambda_nm: f64,
    /// Cross-section: circle | ellipse:RATIO | polygon:FILE.csv | mask:FILE.png:UM_PER_PX |
    /// a generator (trilobal, silk, cotton_raw, cotton_mercerised, wool).
    #[arg(long, conflicts_with = "specs")]
    pub section: Option<String>,
    /// Variant of a generated section (seeded variability).
    #[arg(long, default_value_t = 0)]
    pub variant: u64,
    /// Diameter (mean projected width), µm. Mask and polygon sections keep their own size
    /// unless given.
    #[arg(long)]
    pub diameter_um: Option<f64>,
    /// Refractive index of the fiber.
    #[arg(long, default_value_t = 1.55)]
    pub eta: f64,
    /// Beckmann roughness β = arctan(Ra/l), degrees (0: smooth).
    #[arg(long, default_value_t = 0.0)]
    pub beta_deg: f64,
    /// Absorption coefficient inside the fiber, per µm (overrides a spec entry's dye).
    #[arg(long)]
    pub mua_per_um: Option<f64>,
    /// Cuticle scale interval along the axis, µm (adds wool-like scales).
    #[arg(long, conflicts_with = "specs")]
    pub cuticle_length_um: Option<f64>,
    /// Cuticle tilt, degrees (with --cuticle-length-um).
    #[arg(long, default_value_t = 3.0, requires = "cuticle_length_um")]
    pub cuticle_tilt_deg: f64,
}

pub fn run(c: FiberCommand) -> anyhow::Result<()> {
    match c {
        FiberCommand::Trace(a) => run_trace(a),
        FiberCommand::Bench(a) => run_bench(a),
    }
}

/// `--split` and `--exit-draws` over the spec's `st`, as a spec's block takes them
/// (`spec::fiber::settings`): events met from inside are drawn at least `split` times, so an
/// exit draw count below the split becomes the split (what is traced, and reported).
fn draws(split: Option<u32>, exit_draws: Option<u32>, st: &BakeSettings) -> (u32, u32) {
    let s = split.unwrap_or(st.split);
    (s, exit_draws.unwrap_or(st.exit_draws).max(s))
}

/// A short label of an estimator: `split:exit_draws`, then `+ev` (inside exits scored in
/// expectation) or `+ev+R` (and the first reflection), then `+sobol`, then `+θk` (k
/// directions sharing their photons).
fn estimator_label(
    split: u32,
    exit: u32,
    ev: ExpectedExits,
    sampling: Sampling,
    share: u32,
) -> String {
    let ev = match ev {
        ExpectedExits::None => "",
        ExpectedExits::Inside => "+ev",
        ExpectedExits::All => "+ev+R",
    };
    let qmc = if sampling == Sampling::Sobol {
        "+sobol"
    } else {
        ""
    };
    let share = if share > 1 {
        format!("+θ{share}")
    } else {
        String::new()
    };
    format!("{split}:{exit}{ev}{qmc}{share}")
}

/// `--expected-exits`: a word of the spec's `bake.expected_exits`.
fn expected_exits_arg(s: &str) -> Result<ExpectedExits, String> {
    crate::spec::fiber::choice_of(&crate::spec::fiber::EXPECTED_EXITS, s)
}

/// `--sampling`: a word of the spec's `bake.sampling`.
fn sampling_arg(s: &str) -> Result<Sampling, String> {
    crate::spec::fiber::choice_of(&crate::spec::fiber::SAMPLINGS, s)
}

/// The fibers `fiber bench` measures: a smooth circle, then the selected spec entries.
fn bench_cases(a: &FiberBenchArgs) -> anyhow::Result<Vec<(String, Fiber, f64)>> {
    let smooth = Fiber {
        section: Section::circle(10.0),
        surface: Surface {
            eta: 1.55,
            alpha: 0.0,
        },
        cuticle: None,
    };
    let mut cases = vec![("smooth circle (10 µm, η 1.55)".to_string(), smooth, 0.0)];
    for (e, _, _) in spec_entries(&a.specs, &a.entries)? {
        cases.push((e.name.clone(), e.fiber(), e.mua_per_um(550.0)));
    }
    Ok(cases)
}

/// The entries of `specs` named in `names` (every entry when empty), each with its spec's
/// `bake:` settings and its own `estimators:`; a name no spec has is a usage error that lists the entries.
fn spec_entries(
    specs: &[PathBuf],
    names: &[String],
) -> anyhow::Result<Vec<(FiberEntry, BakeSettings, TableStorage)>> {
    let mut found = Vec::new();
    let mut chosen = Vec::new();
    for spec in specs {
        let s = crate::spec::load_fiber(spec)
            .map_err(|e| usage(e.to_string().trim_end().to_string()))?;
        for e in s.fibers {
            found.push(e.name.clone());
            if names.is_empty() || names.contains(&e.name) {
                let bake = e.settings(&s.bake);
                chosen.push((e, bake, s.storage));
            }
        }
    }
    if let Some(missing) = names.iter().find(|n| !found.contains(n)) {
        let names: Vec<&str> = found.iter().map(String::as_str).collect();
        return Err(usage(crate::spec::names::unknown_entry(
            &shown_list(specs),
            missing,
            &names,
        )));
    }
    Ok(chosen)
}

/// `fiber bench --thesis`: every selected entry at the thesis's noise, next to Table 10.
fn run_thesis_bench(a: FiberBenchArgs) -> anyhow::Result<()> {
    use crate::bake::fiber::thesis;
    use std::fmt::Write as _;
    let entries = spec_entries(&a.specs, &a.entries)?;
    let events = a.progress.events();
    let bar = a
        .progress
        .bar()
        .then(|| super::progress::bar(entries.len() as u64, "entries"));
    let mut s = String::new();
    writeln!(
        s,
        "one cross-section at the thesis's noise (2° bins; per direction the noise 16 M plain photons give), {} threads; {} per entry measured (with `share_theta`, each with its whole φ column), scaled up",
        rayon::current_num_threads(),
        match a.columns {
            Some(c) => format!("every stored θ row of {c} φ column(s)"),
            None => format!("{} stored directions", a.directions),
        }
    )?;
    writeln!(
        s,
        "{:<20} {:>6} {:>14} {:>10} {:>11} {:>8} {:>9} {:>11} {:>9} {:>7} {:>11} {:>9} {:>7}",
        "entry",
        "stored",
        "estimator",
        "photons",
        "s/direction",
        "noise",
        "thesis",
        "estimated",
        "Table 10",
        "ratio",
        ".bcsdf",
        "Table 10",
        "smaller"
    )?;
    for (i, (e, st, storage)) in entries.iter().enumerate() {
        let (split, exit_draws) = draws(a.split, a.exit_draws, st);
        let st = BakeSettings {
            split,
            exit_draws,
            expected_exits: a.expected_exits.unwrap_or(st.expected_exits),
            sampling: a.sampling.unwrap_or(st.sampling),
            share_theta: a.share_theta.unwrap_or(st.share_theta),
            ..st.clone()
        };
        let c = thesis::measure(
            e,
            &st,
            storage,
            a.dyed,
            a.directions,
            a.columns,
            &crate::cancel::Cancel::NEVER,
        )?;
        let t10 = c.table_10_minutes;
        writeln!(
            s,
            "{:<20} {:>6} {:>14} {:>10.3e} {:>11.2} {:>7.2}% {:>8.2}% {:>9.1} min {:>5} min {:>7} {:>8.2} MB {:>6} MB {:>7}",
            if a.dyed {
                format!("{} {}", c.entry, c.variant)
            } else {
                c.entry.clone()
            },
            c.stored_directions,
            estimator_label(
                c.split,
                c.exit_draws,
                c.expected_exits,
                c.sampling,
                c.share_theta
            ),
            c.photons_per_direction,
            c.seconds_per_direction,
            100.0 * c.median_rel_se,
            100.0 * c.thesis_rel_se,
            c.estimated_seconds / 60.0,
            t10.map_or("–".into(), |m| format!("{m}")),
            t10.map_or("–".into(), |m| format!(
                "{:.2}×",
                m * 60.0 / c.estimated_seconds
            )),
            c.estimated_bcsdf_bytes / 1e6,
            c.table_10_mb.map_or("–".into(), |m| format!("{m}")),
            c.table_10_mb.map_or("–".into(), |m| format!(
                "{:.1}×",
                m * 1e6 / c.estimated_bcsdf_bytes
            )),
        )?;
        events.emit(json!({"event": "measured", "index": i, "total": entries.len(), "thesis": c}));
        if let Some(b) = &bar {
            b.set_position(i as u64 + 1);
        }
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    writeln!(
        s,
        "ratio: Table 10's time over the estimate (above 1: faster than the thesis). Noise: mean of each slice's median relative standard error (f̂ ≥ 1 % of its maximum); thesis: the same for 16 M plain photons. .bcsdf: one cross-section's file as the spec stores it (precision, channels, quantise_to_se, zstd_level), the measured slices' mean size scaled up; smaller: Table 10's storage (32-bit, one channel) over it."
    )?;
    super::emit_table(&s, a.out.as_deref(), &a.progress)
}

fn run_bench(a: FiberBenchArgs) -> anyhow::Result<()> {
    use std::fmt::Write as _;
    if a.thesis {
        return run_thesis_bench(a);
    }
    let cases = bench_cases(&a)?;
    let total = cases.len() * a.threads.len();
    let bar = a
        .progress
        .bar()
        .then(|| super::progress::bar(total as u64, "measurements"));
    let events = a.progress.events();
    let mut s = String::new();
    writeln!(
        s,
        "fiber tracer throughput, θi = {}°, {} photons, best of {}",
        a.theta_i, a.photons, a.repeat
    )?;
    write!(s, "{:<32} {:>10} {:>8}", "fiber", "edges", "holes")?;
    for t in &a.threads {
        write!(s, " {:>14}", format!("{t} thr M/s"))?;
    }
    writeln!(s)?;
    let mut done = 0;
    for (name, f, mua) in &cases {
        let edges = match &f.section {
            Section::Polygon(p) => p.edge_count().to_string(),
            Section::Conic { .. } => "conic".into(),
        };
        write!(s, "{name:<32} {edges:>10} {:>8}", f.section.hole_count())?;
        for &t in &a.threads {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build()?;
            let o = TraceOptions {
                photons: a.photons,
                seed: 1,
                grid: AngularGrid::new(2.0).map_err(usage)?,
                mua_per_um: vec![*mua],
                progress: None,
            };
            let best = (0..a.repeat.max(1))
                .map(|_| {
                    pool.install(|| trace(f, Incident::from_deg(a.theta_i, 30.0), &o))
                        .photons_per_s()
                })
                .fold(0.0, f64::max);
            write!(s, " {:>14.3}", best / 1e6)?;
            done += 1;
            events.emit(json!({"event": "measured", "fiber": name, "threads": t,
                "index": done - 1, "total": total, "photons_per_s": best}));
            if let Some(b) = &bar {
                b.set_position(done as u64);
            }
        }
        writeln!(s)?;
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    super::emit_table(&s, a.out.as_deref(), &a.progress)
}

fn usage(m: impl Into<String>) -> anyhow::Error {
    UsageError(m.into()).into()
}

/// The fiber and its μa from the command line.
fn fiber_from_flags(a: &TraceArgs) -> anyhow::Result<(Fiber, f64, String)> {
    let s = a
        .section
        .as_deref()
        .ok_or_else(|| usage("give a SPEC with --entry, or describe the fiber with --section"))?;
    let (kind, rest) = s.split_once(':').unwrap_or((s, ""));
    let diameter = a.diameter_um;
    let section = match kind {
        "circle" => Section::circle(diameter.unwrap_or(10.0)),
        "ellipse" => {
            let ratio: f64 = rest
                .parse()
                .ok()
                .filter(|r: &f64| *r > 0.0 && *r <= 1.0)
                .ok_or_else(|| {
                    usage(format!(
                        "--section ellipse:RATIO needs a ratio in (0, 1], got {rest:?}"
                    ))
                })?;
            Section::Conic {
                rx_um: 1.0,
                ry_um: ratio,
            }
            .scaled_to_diameter(diameter.unwrap_or(10.0))?
        }
        "polygon" => {
            let sec = Section::from_csv(
                std::path::Path::new(rest),
                crate::spec::Limits::default().polygon_vertices,
            )
            .map_err(|e| usage(e.to_string()))?;
            match diameter {
                Some(d) => sec.scaled_to_diameter(d)?,
                None => sec,
            }
        }
        "mask" => {
            let (file, um) = rest
                .rsplit_once(':')
                .ok_or_else(|| usage("--section mask:FILE.png:UM_PER_PX"))?;
            let um: f64 = um.parse().map_err(|_| {
                usage(format!(
                    "--section mask: µm per pixel must be a number, got {um:?}"
                ))
            })?;
            let (sec, rep) = from_mask(std::path::Path::new(file), &MaskOptions::new(um))
                .map_err(|e| usage(e.to_string()))?;
            if rep.ignored_components > 0 && !a.json {
                eprintln!(
                    "note: {} smaller foreground region(s) ignored",
                    rep.ignored_components
                );
            }
            match diameter {
                Some(d) => sec.scaled_to_diameter(d)?,
                None => sec,
            }
        }
        other => {
            let shape = Shape::ALL
                .iter()
                .find(|s| s.0 == other)
                .map(|s| s.1)
                .ok_or_else(|| {
                    let names: Vec<&str> = Shape::ALL.iter().map(|s| s.0).collect();
                    usage(format!(
                        "--section {other:?}: expected circle, ellipse:RATIO, polygon:FILE.csv, mask:FILE.png:UM_PER_PX or one of {}{}",
                        names.join(", "),
                        crate::suggest::suffix(other, &names)
                    ))
                })?;
            generate(
                shape,
                diameter.unwrap_or(10.0),
                a.seed.unwrap_or(1),
                a.variant,
            )?
        }
    };
    if !(a.eta >= 1.0 && a.eta <= 3.0) {
        return Err(usage(format!("--eta {} out of range [1, 3]", a.eta)));
    }
    if !(0.0..=45.0).contains(&a.beta_deg) {
        return Err(usage(format!(
            "--beta-deg {} out of range [0, 45]",
            a.beta_deg
        )));
    }
    let cuticle = match a.cuticle_length_um {
        Some(l) if l > 0.0 && (0.0..=20.0).contains(&a.cuticle_tilt_deg) => Some(Cuticle {
            length_um: l,
            tilt_deg: a.cuticle_tilt_deg,
        }),
        Some(_) => {
            return Err(usage(
                "--cuticle-length-um must be > 0 and --cuticle-tilt-deg in [0, 20]",
            ))
        }
        None => None,
    };
    let fiber = Fiber {
        section,
        surface: Surface {
            eta: a.eta,
            alpha: a.beta_deg.to_radians().tan(),
        },
        cuticle,
    };
    Ok((fiber, a.mua_per_um.unwrap_or(0.0), s.to_string()))
}

/// One fiber `fiber trace` traces: with `bake`, a spec entry traced with its bake's settings
/// ([`crate::bake::fiber::trace_direction`]); without, a fiber from the flags, traced plainly.
struct TraceTarget {
    fiber: Fiber,
    mua_per_um: f64,
    label: String,
    bake: Option<BakeSettings>,
}

/// The fibers to trace: the spec entries in the order of `--entry`, or the flags.
fn targets_of(a: &TraceArgs) -> anyhow::Result<Vec<TraceTarget>> {
    if a.specs.is_empty() {
        let (fiber, mua_per_um, label) = fiber_from_flags(a)?;
        return Ok(vec![TraceTarget {
            fiber,
            mua_per_um,
            label,
            bake: None,
        }]);
    }
    if a.entries.is_empty() {
        return Err(usage("--entry NAME is required with a spec"));
    }
    let found = spec_entries(&a.specs, &a.entries)?;
    let mut out = Vec::new();
    for name in &a.entries {
        let (e, bake, _) = found
            .iter()
            .find(|(e, _, _)| &e.name == name)
            .expect("found");
        let (split, exit_draws) = draws(a.split, a.exit_draws, bake);
        let mut st = BakeSettings {
            photons: a.photons.unwrap_or(bake.photons),
            res_deg: a.resolution_deg.unwrap_or(bake.res_deg),
            seed: a.seed.unwrap_or(bake.seed),
            split,
            exit_draws,
            expected_exits: a.expected_exits.unwrap_or(bake.expected_exits),
            sampling: a.sampling.unwrap_or(bake.sampling),
            share_theta: a.share_theta.unwrap_or(bake.share_theta),
            ..bake.clone()
        };
        st.max_photons = st.max_photons.max(st.photons);
        out.push(TraceTarget {
            fiber: e.fiber(),
            mua_per_um: a.mua_per_um.unwrap_or_else(|| e.mua_per_um(a.lambda_nm)),
            label: e.name.clone(),
            bake: Some(st),
        });
    }
    Ok(out)
}

/// Spec paths as a comma-separated list for messages.
fn shown_list(paths: &[PathBuf]) -> String {
    (paths.iter())
        .map(|p| crate::files::Shown(p).to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

fn run_trace(a: TraceArgs) -> anyhow::Result<()> {
    let targets = targets_of(&a)?;
    if !(-90.0..=90.0).contains(&a.theta_i) {
        return Err(usage(format!(
            "--theta-i {} out of range [-90, 90]",
            a.theta_i
        )));
    }
    if a.photons == Some(0) {
        return Err(usage("--photons must be at least 1"));
    }
    for t in &targets {
        if !(t.mua_per_um >= 0.0 && t.mua_per_um.is_finite()) {
            return Err(usage(format!("--mua-per-um {} must be ≥ 0", t.mua_per_um)));
        }
    }
    let res_deg = |t: &TraceTarget| t.bake.as_ref().map_or(2.0, |b| b.res_deg);
    for t in &targets {
        AngularGrid::new(a.resolution_deg.unwrap_or(res_deg(t))).map_err(usage)?;
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = a.threads {
        builder = builder.num_threads(t);
    }
    let pool = builder.build()?;
    let events = a.progress.events();
    let total = targets.len();
    for (index, t) in targets.iter().enumerate() {
        let png = match &a.out {
            Some(dir) if total > 1 => Some(dir.join(format!("{}.png", t.label))),
            o => o.clone(),
        };
        let photons = (t.bake.as_ref()).map_or(a.photons.unwrap_or(1_000_000), |b| b.photons);
        events.emit(
            json!({"event": "trace_started", "fiber": t.label, "index": index,
            "total": total, "photons": photons}),
        );
        let grid = AngularGrid::new(a.resolution_deg.unwrap_or(res_deg(t))).map_err(usage)?;
        let report = pool.install(|| match &t.bake {
            Some(st) => trace_with_bake(&a, t, st),
            None => Ok(trace_plain(&a, t, grid, photons)),
        })?;
        report.write(&a, t, png.as_deref())?;
        events.emit(
            json!({"event": "trace_finished", "fiber": t.label, "index": index,
            "total": total}),
        );
    }
    Ok(())
}

/// What `fiber trace` prints about one fiber, from either tracer.
struct TraceReport {
    grid: AngularGrid,
    albedo: (f64, f64),
    /// Fractions of the intercepted power per bin, `[θo][Δφ]`, and their standard errors.
    hist2d: (Vec<f64>, Vec<f64>),
    /// The same summed over θo, per Δφ.
    dphi: (Vec<f64>, Vec<f64>),
    projected_width_um: f64,
    launched: u64,
    intercepted: u64,
    seconds: f64,
    /// The plain tracer's extras: intercepted width (µm, SE), photons lost, surface
    /// fallbacks, mean path inside (µm).
    plain: Option<((f64, f64), u64, u64, f64)>,
    /// The bake's estimator: its settings, the slice's noise and whether it met the target.
    bake: Option<(BakeSettings, crate::fiber::slices::Noise, Option<bool>)>,
}

/// A fiber from the flags: the plain tracer, photon by photon, with per-photon errors.
fn trace_plain(a: &TraceArgs, t: &TraceTarget, grid: AngularGrid, photons: u64) -> TraceReport {
    let inc = Incident::from_deg(a.theta_i, a.phi_i);
    let bar = (!a.json && a.progress.bar()).then(|| crate::cli::progress::bar(photons, "photons"));
    let o = TraceOptions {
        photons,
        seed: a.seed.unwrap_or(1),
        grid,
        mua_per_um: vec![t.mua_per_um],
        progress: crate::cli::progress::reporter(&bar),
    };
    let r = trace(&t.fiber, inc, &o);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let tl = &r.tally;
    TraceReport {
        grid,
        albedo: tl.albedo(0),
        hist2d: tl.hist2d(0),
        dphi: tl.dphi_hist(0),
        projected_width_um: r.projected_width_um,
        launched: tl.launched,
        intercepted: tl.intercepted,
        seconds: r.seconds,
        plain: Some((
            r.intercepted_width_um(),
            tl.lost,
            tl.fallbacks,
            tl.mean_path_um(),
        )),
        bake: None,
    }
}

/// A spec entry: its bake's estimators, bins and target, with batch-means errors.
fn trace_with_bake(
    a: &TraceArgs,
    t: &TraceTarget,
    st: &BakeSettings,
) -> anyhow::Result<TraceReport> {
    let inc = Incident::from_deg(a.theta_i, a.phi_i);
    let spinner = (!a.json && a.progress.bar()).then(|| {
        let s = indicatif::ProgressBar::new_spinner();
        s.set_message(format!("tracing {} with its bake's settings", t.label));
        s.enable_steady_tick(std::time::Duration::from_millis(200));
        s
    });
    let cancel = crate::cancel::Cancel::default();
    let d = crate::bake::fiber::trace_direction(
        &t.fiber,
        st,
        inc,
        (a.lambda_nm, t.mua_per_um),
        st.seed,
        &cancel,
    )?
    .map_err(anyhow::Error::from)?;
    if let Some(s) = spinner {
        s.finish_and_clear();
    }
    let (g, r) = (d.grid, d.result);
    let dphi = (0..g.n_phi)
        .map(|j| (0..g.n_theta).map(|i| r.fraction[i * g.n_phi + j]).sum())
        .collect();
    Ok(TraceReport {
        grid: g,
        albedo: (r.albedo[0], r.albedo_se[0]),
        hist2d: (r.fraction.clone(), r.density_se.clone()),
        dphi: (dphi, r.dphi_se.clone()),
        projected_width_um: d.projected_width_um,
        launched: r.launched,
        intercepted: r.intercepted,
        seconds: r.seconds,
        plain: None,
        bake: Some((st.clone(), r.noise, d.reached_target)),
    })
}

impl TraceReport {
    /// Prints the summary or the JSON line, and writes the PNG.
    fn write(
        &self,
        a: &TraceArgs,
        t: &TraceTarget,
        png: Option<&std::path::Path>,
    ) -> anyhow::Result<()> {
        let (grid, label, mua) = (self.grid, &t.label, t.mua_per_um);
        let h2 = &self.hist2d.0;
        let (albedo, albedo_se) = self.albedo;
        let photons_per_s = self.launched as f64 / self.seconds.max(1e-9);
        if let Some(png) = png {
            // Radiance-like density: fraction per solid angle and cos θo.
            let (nt, np) = (grid.n_theta, grid.n_phi);
            let density: Vec<f64> = (0..nt * np)
                .map(|b| {
                    let it = b / np;
                    let t_mid = grid.theta_centre_deg(it).to_radians();
                    h2[b] / (grid.solid_angle(it) * t_mid.cos().max(1e-6))
                })
                .collect();
            let title = format!(
                "{label}: traced at θi = {}°, φi = {}°, {} photons",
                a.theta_i, a.phi_i, self.launched
            );
            let bar = "fraction per sr ÷ cos θo (sr⁻¹)";
            crate::output::slice::write_slice_png(png, (nt, np), &density, &title, bar)?;
        }
        if a.json {
            return self.write_json(a, t);
        }
        outln!(
            "fiber {label}: θi = {}°, φi = {}°, μa = {mua} /µm",
            a.theta_i,
            a.phi_i
        )?;
        outln!("  albedo            {albedo:.6} ± {albedo_se:.6}")?;
        match self.plain {
            Some(((iw, iw_se), lost, _, path)) => {
                outln!(
                    "  projected width   {:.4} µm (exact); intercepted {iw:.4} ± {iw_se:.4} µm",
                    self.projected_width_um
                )?;
                outln!(
                    "  photons           {} launched, {} intercepted, {lost} lost",
                    self.launched,
                    self.intercepted
                )?;
                outln!("  mean path inside  {path:.3} µm")?;
            }
            None => {
                outln!(
                    "  projected width   {:.4} µm (exact)",
                    self.projected_width_um
                )?;
                outln!(
                    "  photons           {} launched, {} intercepted",
                    self.launched,
                    self.intercepted
                )?;
            }
        }
        if let Some((st, noise, reached)) = &self.bake {
            let target = match (st.target, reached) {
                (Some(t), Some(true)) => format!(", target {} reached", target_words(t)),
                (Some(t), _) => format!(
                    ", target {} not reached at the cap of {} photons",
                    target_words(t),
                    st.max_photons
                ),
                (None, _) => String::new(),
            };
            outln!(
                "  estimator         the bake's: {}° bins, split {}, exit_draws {}, expected_exits {:?}, sampling {:?}, share_theta {}{target}",
                st.res_deg,
                st.split,
                st.exit_draws,
                st.expected_exits,
                st.sampling,
                st.share_theta
            )?;
            outln!(
                "  noise             median relative error {:.2} % over {} bins (thesis: {:.2} %)",
                100.0 * noise.median_rel_se,
                noise.bins,
                100.0 * noise.thesis_rel_se
            )?;
        }
        outln!(
            "  throughput        {:.3} M photons/s ({:.2} s)",
            photons_per_s / 1e6,
            self.seconds
        )?;
        if let Some(png) = png.filter(|_| !a.progress.quiet) {
            outln!("  wrote {}", png.display())?;
        }
        Ok(())
    }

    /// Prints the trace as one JSON line (`--json`).
    fn write_json(&self, a: &TraceArgs, t: &TraceTarget) -> anyhow::Result<()> {
        let (grid, label, mua) = (self.grid, &t.label, t.mua_per_um);
        let fiber = &t.fiber;
        let (h2, h2_se) = &self.hist2d;
        let (albedo, albedo_se) = self.albedo;
        let photons_per_s = self.launched as f64 / self.seconds.max(1e-9);
        let rows: Vec<&[f64]> = h2.chunks(grid.n_phi).collect();
        let rows_se: Vec<&[f64]> = h2_se.chunks(grid.n_phi).collect();
        let mut v = json!({
            "fiber": label,
            "theta_i_deg": a.theta_i,
            "phi_i_deg": a.phi_i,
            "mua_per_um": mua,
            "albedo": albedo,
            "albedo_se": albedo_se,
            "projected_width_um": self.projected_width_um,
            "photons": self.intercepted,
            "photons_launched": self.launched,
            "seconds": self.seconds,
            "photons_per_s": photons_per_s,
            "estimator": if self.bake.is_some() { "bake" } else { "plain" },
            "section": {
                "area_um2": fiber.section.area_um2(),
                "mean_width_um": fiber.section.mean_width_um(),
                "holes": fiber.section.hole_count(),
                "eta": fiber.surface.eta,
                "beta_deg": fiber.surface.alpha.atan().to_degrees(),
                "cuticle": fiber.cuticle,
            },
            "theta_o_edges_deg": grid.theta_edges_deg(),
            "dphi_edges_deg": grid.dphi_edges_deg(),
            "dphi_hist": self.dphi.0,
            "dphi_hist_se": self.dphi.1,
            "hist2d": rows,
            "hist2d_se": rows_se,
        });
        if let Some(((iw, iw_se), lost, fallbacks, path)) = self.plain {
            v["intercepted_width_um"] = json!(iw);
            v["intercepted_width_se_um"] = json!(iw_se);
            v["photons_lost"] = json!(lost);
            v["surface_fallbacks"] = json!(fallbacks);
            v["mean_path_um"] = json!(path);
        }
        if let Some((st, noise, reached)) = &self.bake {
            v["bake"] = json!({
                "resolution_deg": st.res_deg,
                "photons_per_direction": st.photons_per_direction(),
                "split": st.split,
                "exit_draws": st.exit_draws,
                "expected_exits": st.expected_exits,
                "sampling": st.sampling,
                "share_theta": st.share_theta,
                "target_rel_se": st.target,
                "max_photons_per_direction": st.max_photons,
                "batch": st.batch,
                "seed": st.seed,
            });
            v["noise"] = json!(noise);
            v["reached_target"] = json!(reached);
        }
        outln!("{v}")?;
        Ok(())
    }
}

/// A noise target in words.
fn target_words(t: crate::fiber::slices::NoiseTarget) -> String {
    match t {
        crate::fiber::slices::NoiseTarget::Thesis => "thesis".into(),
        crate::fiber::slices::NoiseTarget::RelSe(x) => format!("{:.2} %", 100.0 * x),
    }
}
