//! `baker completions` and `baker man`: the command line described for shells and `man`,
//! generated from the same clap definitions that parse it.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::{Args, CommandFactory as _};

use super::observer::ProgressArgs;
use crate::error::UsageError;

#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell: bash, zsh, fish, elvish or powershell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
    /// Write the script to FILE, atomically (default: standard output). Bash: source it from
    /// ~/.bashrc or put it in ~/.local/share/bash-completion/completions/baker; zsh: a
    /// `_baker` file on $fpath; fish: ~/.config/fish/completions/baker.fish.
    #[arg(short = 'o', long = "out", value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// No "wrote" line on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct ManArgs {
    /// Write every page (baker.1 and one baker-<command>.1 per command) into DIR, e.g.
    /// ~/.local/share/man/man1 (default: baker.1 on standard output).
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// No "wrote" lines on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `baker completions SHELL`.
pub fn completions(a: CompletionsArgs) -> anyhow::Result<()> {
    let mut cmd = super::Cli::command();
    let mut script = Vec::new();
    clap_complete::generate(a.shell, &mut cmd, "baker", &mut script);
    let text = String::from_utf8(script).context("completion script is not UTF-8")?;
    let note = ProgressArgs {
        quiet: a.quiet,
        progress: super::observer::ProgressMode::None,
    };
    super::emit_table(&text, a.out.as_deref(), &note)
}

/// `baker man`.
pub fn man(a: ManArgs) -> anyhow::Result<()> {
    let cmd = super::Cli::command();
    let Some(dir) = a.out else {
        let mut page = Vec::new();
        clap_mangen::Man::new(cmd).render(&mut page)?;
        use std::io::Write as _;
        return Ok(std::io::stdout().lock().write_all(&page)?);
    };
    if dir.exists() && !dir.is_dir() {
        return Err(UsageError(format!("-o {}: not a folder", dir.display())).into());
    }
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    for (name, page) in pages(cmd)? {
        let path = dir.join(format!("{name}.1"));
        crate::output::atomic::write(&path, &page)
            .with_context(|| format!("writing {}", path.display()))?;
        if !a.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// The page of `cmd` and of each of its subcommands, depth first: (`baker-fiber-trace`, roff).
fn pages(cmd: clap::Command) -> anyhow::Result<Vec<(String, Vec<u8>)>> {
    let mut out = Vec::new();
    let mut stack = vec![(cmd.get_name().to_string(), cmd)];
    while let Some((name, cmd)) = stack.pop() {
        let mut page = Vec::new();
        clap_mangen::Man::new(
            cmd.clone()
                .display_name(name.clone())
                .bin_name(name.replace('-', " ")),
        )
        .title(name.clone())
        .render(&mut page)?;
        out.push((name.clone(), page));
        for sub in cmd.get_subcommands().filter(|s| s.get_name() != "help") {
            stack.push((format!("{name}-{}", sub.get_name()), sub.clone()));
        }
    }
    Ok(out)
}
