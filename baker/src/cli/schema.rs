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
}

/// The spec kinds, as the command line names them.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Kind {
    Skin,
    Fiber,
}

pub fn run(a: SchemaArgs) -> anyhow::Result<()> {
    let kind = match a.kind {
        Kind::Skin => SpecKind::Skin,
        Kind::Fiber => SpecKind::Fiber,
    };
    let text = crate::spec::schema::text(kind);
    match &a.out {
        Some(path) => crate::output::atomic::write(path, text.as_bytes())
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display())),
        None => Ok(out!("{text}")?),
    }
}
