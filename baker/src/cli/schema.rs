//! `baker schema`: the JSON Schema of a spec kind ([`crate::spec::schema`]).

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::spec::SpecKind;

#[derive(Debug, Args)]
pub struct SchemaArgs {
    /// Spec kind: `skin` (entries, sweeps, profiles) or `fiber` (fibers, dyes, bake).
    #[arg(value_enum)]
    pub kind: Kind,
    /// Write the schema to FILE (atomically: a temporary file renamed over it) instead of
    /// standard output.
    #[arg(short, long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// No "wrote" line on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

/// The spec kinds, as the command line names them (`baker schema`, `baker init`).
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Kind {
    Skin,
    Fiber,
}

impl Kind {
    /// The library's spec kind.
    pub fn spec_kind(self) -> SpecKind {
        match self {
            Kind::Skin => SpecKind::Skin,
            Kind::Fiber => SpecKind::Fiber,
        }
    }
}

pub fn run(a: SchemaArgs) -> anyhow::Result<()> {
    let text = crate::spec::schema::text(a.kind.spec_kind());
    let note = super::observer::ProgressArgs {
        quiet: a.quiet,
        progress: super::observer::ProgressMode::None,
    };
    super::emit_table(&text, a.out.as_deref(), &note)
}
