//! `baker fiber trace`: one incoming direction through one fiber (§5.3.2), from a spec entry or
//! from a fiber described on the command line.

use std::path::PathBuf;

use clap::{Args, Subcommand};
use serde_json::json;

use crate::error::UsageError;
use crate::fiber::section::generate::{generate, Shape};
use crate::fiber::section::mask::{from_mask, MaskOptions};
use crate::fiber::slices::BakeSettings;
use crate::fiber::{trace, AngularGrid, Cuticle, Fiber, Incident, Section, Surface, TraceOptions};
use crate::spec::fiber::FiberEntry;

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
    /// With --thesis: override the spec's `bake.split` (draws per event met from outside).
    #[arg(long, requires = "thesis", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub split: Option<u32>,
    /// With --thesis: override the spec's `bake.exit_draws` (draws per event met from inside).
    #[arg(long, requires = "thesis", value_parser = clap::value_parser!(u32).range(1..=256))]
    pub exit_draws: Option<u32>,
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
    /// Photons launched across the beam.
    #[arg(long, default_value_t = 1_000_000)]
    pub photons: u64,
    /// Seed: the same inputs and seed give bit-identical output for any thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Bin size of θo and Δφ, degrees (must divide 180).
    #[arg(long, default_value_t = 2.0)]
    pub resolution_deg: f64,
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
    for (e, _) in spec_entries(&a.specs, &a.entries)? {
        cases.push((e.name.clone(), e.fiber(), e.mua_per_um(550.0)));
    }
    Ok(cases)
}

/// The entries of `specs` named in `names` (every entry when empty), each with its spec's
/// `bake:` settings; a name no spec has is a usage error that lists the entries.
fn spec_entries(
    specs: &[PathBuf],
    names: &[String],
) -> anyhow::Result<Vec<(FiberEntry, BakeSettings)>> {
    let mut found = Vec::new();
    let mut chosen = Vec::new();
    for spec in specs {
        let s = crate::spec::load_fiber(spec)
            .map_err(|e| usage(e.to_string().trim_end().to_string()))?;
        for e in s.fibers {
            found.push(e.name.clone());
            if names.is_empty() || names.contains(&e.name) {
                chosen.push((e, s.bake.clone()));
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
        "one cross-section at the thesis's noise (2° bins; per direction the noise 16 M plain photons give), {} threads; {} stored directions per entry measured, scaled up",
        rayon::current_num_threads(),
        a.directions
    )?;
    writeln!(
        s,
        "{:<20} {:>6} {:>9} {:>10} {:>11} {:>8} {:>9} {:>11} {:>9} {:>7}",
        "entry",
        "stored",
        "split:exit",
        "photons",
        "s/direction",
        "noise",
        "thesis",
        "estimated",
        "Table 10",
        "ratio"
    )?;
    for (i, (e, st)) in entries.iter().enumerate() {
        let st = BakeSettings {
            split: a.split.unwrap_or(st.split),
            exit_draws: a.exit_draws.unwrap_or(st.exit_draws),
            ..st.clone()
        };
        let c = thesis::measure(e, &st, a.directions, &crate::cancel::Cancel::NEVER)?;
        let t10 = c.table_10_minutes;
        writeln!(
            s,
            "{:<20} {:>6} {:>9} {:>10.3e} {:>11.2} {:>7.2}% {:>8.2}% {:>9.1} min {:>5} min {:>7}",
            c.entry,
            c.stored_directions,
            format!("{}:{}", c.split, c.exit_draws),
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
        "ratio: Table 10's time over the estimate (above 1: faster than the thesis). Noise: mean of each slice's median relative standard error (f̂ ≥ 1 % of its maximum); thesis: the same for 16 M plain photons."
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
            generate(shape, diameter.unwrap_or(10.0), a.seed, a.variant)?
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

/// The fibers to trace (spec entries, or the flags), each with its μa per µm and label.
fn fibers_of(a: &TraceArgs) -> anyhow::Result<Vec<(Fiber, f64, String)>> {
    if a.specs.is_empty() {
        return Ok(vec![fiber_from_flags(a)?]);
    }
    if a.entries.is_empty() {
        return Err(usage("--entry NAME is required with a spec"));
    }
    let mut fibers = Vec::new();
    for spec in &a.specs {
        let s = crate::spec::load_fiber(spec)
            .map_err(|e| usage(e.to_string().trim_end().to_string()))?;
        fibers.extend(s.fibers);
    }
    a.entries
        .iter()
        .map(|name| {
            let e = fibers.iter().find(|f| &f.name == name).ok_or_else(|| {
                let names: Vec<&str> = fibers.iter().map(|f| f.name.as_str()).collect();
                usage(crate::spec::names::unknown_entry(
                    &shown_list(&a.specs),
                    name,
                    &names,
                ))
            })?;
            let mua = a.mua_per_um.unwrap_or_else(|| e.mua_per_um(a.lambda_nm));
            Ok((e.fiber(), mua, e.name.clone()))
        })
        .collect()
}

/// Spec paths as a comma-separated list for messages.
fn shown_list(paths: &[PathBuf]) -> String {
    (paths.iter())
        .map(|p| crate::files::Shown(p).to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

fn run_trace(a: TraceArgs) -> anyhow::Result<()> {
    let fibers = fibers_of(&a)?;
    if !(-90.0..=90.0).contains(&a.theta_i) {
        return Err(usage(format!(
            "--theta-i {} out of range [-90, 90]",
            a.theta_i
        )));
    }
    if a.photons == 0 {
        return Err(usage("--photons must be at least 1"));
    }
    for (_, mua, _) in &fibers {
        if !(*mua >= 0.0 && mua.is_finite()) {
            return Err(usage(format!("--mua-per-um {mua} must be ≥ 0")));
        }
    }
    let grid = AngularGrid::new(a.resolution_deg).map_err(usage)?;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(t) = a.threads {
        builder = builder.num_threads(t);
    }
    let pool = builder.build()?;
    let events = a.progress.events();
    let total = fibers.len();
    for (index, (fiber, mua, label)) in fibers.into_iter().enumerate() {
        let png = match &a.out {
            Some(dir) if total > 1 => Some(dir.join(format!("{label}.png"))),
            o => o.clone(),
        };
        events.emit(
            json!({"event": "trace_started", "fiber": label, "index": index,
            "total": total, "photons": a.photons}),
        );
        trace_one(&a, &pool, grid, (&fiber, mua, &label), png.as_deref())?;
        events.emit(
            json!({"event": "trace_finished", "fiber": label, "index": index,
            "total": total}),
        );
    }
    Ok(())
}

/// Traces one fiber as `a` asks and reports it (summary or JSON line, and the PNG).
fn trace_one(
    a: &TraceArgs,
    pool: &rayon::ThreadPool,
    grid: AngularGrid,
    (fiber, mua, label): (&Fiber, f64, &str),
    png: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    let inc = Incident::from_deg(a.theta_i, a.phi_i);
    let bar =
        (!a.json && a.progress.bar()).then(|| crate::cli::progress::bar(a.photons, "photons"));
    let o = TraceOptions {
        photons: a.photons,
        seed: a.seed,
        grid,
        mua_per_um: vec![mua],
        progress: crate::cli::progress::reporter(&bar),
    };
    let r = pool.install(|| trace(fiber, inc, &o));
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let t = &r.tally;
    let (albedo, albedo_se) = t.albedo(0);
    let (h2, h2_se) = t.hist2d(0);
    let (dh, dh_se) = t.dphi_hist(0);
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
        crate::output::slice::write_slice_png(png, (nt, np), &density, 4)?;
    }
    let (iw, iw_se) = r.intercepted_width_um();
    if a.json {
        let rows: Vec<&[f64]> = h2.chunks(grid.n_phi).collect();
        let rows_se: Vec<&[f64]> = h2_se.chunks(grid.n_phi).collect();
        let v = json!({
            "fiber": label,
            "theta_i_deg": a.theta_i,
            "phi_i_deg": a.phi_i,
            "mua_per_um": mua,
            "albedo": albedo,
            "albedo_se": albedo_se,
            "projected_width_um": r.projected_width_um,
            "intercepted_width_um": iw,
            "intercepted_width_se_um": iw_se,
            "photons": t.intercepted,
            "photons_launched": t.launched,
            "photons_lost": t.lost,
            "surface_fallbacks": t.fallbacks,
            "mean_path_um": t.mean_path_um(),
            "seconds": r.seconds,
            "photons_per_s": r.photons_per_s(),
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
            "dphi_hist": dh,
            "dphi_hist_se": dh_se,
            "hist2d": rows,
            "hist2d_se": rows_se,
        });
        outln!("{v}")?;
    } else {
        outln!(
            "fiber {label}: θi = {}°, φi = {}°, μa = {mua} /µm",
            a.theta_i,
            a.phi_i
        )?;
        outln!("  albedo            {albedo:.6} ± {albedo_se:.6}")?;
        outln!(
            "  projected width   {:.4} µm (exact); intercepted {iw:.4} ± {iw_se:.4} µm",
            r.projected_width_um
        )?;
        outln!(
            "  photons           {} launched, {} intercepted, {} lost",
            t.launched,
            t.intercepted,
            t.lost
        )?;
        outln!("  mean path inside  {:.3} µm", t.mean_path_um())?;
        outln!(
            "  throughput        {:.3} M photons/s ({:.2} s)",
            r.photons_per_s() / 1e6,
            r.seconds
        )?;
        if let Some(png) = png.filter(|_| !a.progress.quiet) {
            outln!("  wrote {}", png.display())?;
        }
    }
    Ok(())
}
