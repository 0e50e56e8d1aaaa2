//! `baker bench`: transport throughput on the thesis's reference stack (30-year-old type II
//! face at 550 nm), with and without the non-planar junction, for each thread count.

use clap::Args;

use crate::skin::{self, BodyLocation, Gender, MelaninInput, SkinParams, SkinType};
use crate::spectral::WavelengthGrid;
use crate::transport::{self, McOptions, Stack};

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Photons per measurement.
    #[arg(long, default_value_t = 2_000_000)]
    pub photons: u64,
    /// Thread counts to measure, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Repetitions per measurement (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Write the table (Markdown) to FILE, atomically, instead of standard output.
    #[arg(short = 'o', long = "out", value_name = "FILE")]
    pub out: Option<std::path::PathBuf>,
    #[command(flatten)]
    pub progress: super::observer::ProgressArgs,
}

/// The 5-layer stack of a 30-year-old type II woman's face at 550 nm.
pub fn reference_stack() -> anyhow::Result<Stack> {
    let p = SkinParams::new(
        30.0,
        Gender::Female,
        BodyLocation::Face,
        MelaninInput::SkinType(SkinType::II),
        1.0,
    );
    let o = skin::evaluate(&p, &WavelengthGrid::from_list(vec![550.0]))?;
    let mut doc_entry = crate::skin::document::entry("bench", &p, &o);
    doc_entry.model = "five_layer".into();
    Ok(transport::stack::from_skin(&doc_entry, 0))
}

pub fn run(a: BenchArgs) -> anyhow::Result<()> {
    use std::fmt::Write as _;
    let wavy = reference_stack()?;
    let flat = Stack {
        junction: None,
        ..wavy.clone()
    };
    let cases = [
        ("planar junction", &flat),
        ("Eq. 1 junction (A = 50 µm)", &wavy),
    ];
    let total = cases.len() * a.threads.len() * a.repeat.max(1);
    let bar = a
        .progress
        .bar()
        .then(|| super::progress::bar(total as u64, "measurements"));
    let events = a.progress.events();
    let mut table = String::new();
    writeln!(table, "| stack | threads | photons | best s | photons/s | scattering events/s | ns/event/thread |")?;
    writeln!(table, "|---|---|---|---|---|---|---|")?;
    let mut done = 0;
    for (name, s) in cases {
        for &t in &a.threads {
            let mut best: Option<transport::McResult> = None;
            for rep in 0..a.repeat.max(1) {
                let mut o = McOptions::new(a.photons, 1 + rep as u64);
                o.threads = Some(t);
                let r = transport::run(s, &o)?;
                done += 1;
                events.emit(
                    serde_json::json!({"event": "measured", "stack": name, "threads": t,
                    "index": done - 1, "total": total, "photons_per_s": r.photons_per_s}),
                );
                if let Some(b) = &bar {
                    b.set_position(done as u64);
                }
                if best.as_ref().is_none_or(|b| r.seconds < b.seconds) {
                    best = Some(r);
                }
            }
            let r = best.unwrap();
            writeln!(
                table,
                "| {name} | {t} | {} | {:.3} | {:.0} | {:.3e} | {:.1} |",
                r.photons,
                r.seconds,
                r.photons_per_s,
                r.scattering_events_per_s,
                1e9 * t as f64 / r.scattering_events_per_s
            )?;
        }
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    super::emit_table(&table, a.out.as_deref(), &a.progress)
}
