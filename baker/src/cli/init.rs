//! `baker init skin|fiber`: a commented starter spec to begin from.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use crate::error::UsageError;
use crate::spec::SpecKind;

#[derive(Debug, Args)]
pub struct InitArgs {
    /// Kind of spec: skin (ch. 3: people's skin → diffusion profiles) or fiber (ch. 5: cloth
    /// fibers → BCSDF tables).
    #[arg(value_enum)]
    pub kind: super::schema::Kind,
    /// Where to write it (default: skin.yaml or fiber.yaml in the current directory; `-` for
    /// standard output). Its file name becomes the bake's output folder name.
    #[arg(short = 'o', long = "out", value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Replace an existing file.
    #[arg(long)]
    pub force: bool,
    /// No "wrote" line on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(a: InitArgs) -> anyhow::Result<()> {
    let kind = a.kind.spec_kind();
    let path = a.out.unwrap_or_else(|| {
        PathBuf::from(match kind {
            SpecKind::Skin => "skin.yaml",
            SpecKind::Fiber => "fiber.yaml",
        })
    });
    if path.as_os_str() != "-" && path.exists() && !a.force {
        return Err(UsageError(format!(
            "{} exists; choose another name with -o FILE, or replace it with --force",
            path.display()
        ))
        .into());
    }
    crate::output::atomic::write(&path, crate::spec::templates::template(kind).as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    if !a.quiet && path.as_os_str() != "-" {
        eprintln!(
            "wrote {}; check it with `baker validate {0}`, bake it with `baker bake {0}`",
            path.display()
        );
    }
    Ok(())
}
