//! How a bake's progress reaches the terminal: the [`Observer`] the command line gives the
//! bake library, chosen by `--progress` and `--quiet`.

use std::io::{IsTerminal, Write as _};
use std::sync::Arc;

use indicatif::ProgressBar;

use crate::pipeline::{Bar, Events, Observer};

/// `--progress`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ProgressMode {
    /// A bar on a terminal, periodic lines otherwise.
    Auto,
    Bar,
    /// One JSON event per line on stderr, for pipeline tools.
    Json,
    None,
}

/// Messages and bars on stderr, or JSON event lines.
#[derive(Debug, Clone, Copy)]
pub struct Terminal {
    pub mode: ProgressMode,
    /// `--quiet`: errors and warnings only.
    pub quiet: bool,
}

impl Terminal {
    /// The events of a bake with these flags.
    pub fn events(mode: ProgressMode, quiet: bool) -> Events {
        let mode = if quiet { ProgressMode::None } else { mode };
        Events::new(Arc::new(Terminal { mode, quiet }))
    }
}

impl Observer for Terminal {
    fn event(&self, v: &serde_json::Value) {
        if self.mode == ProgressMode::Json {
            let _ = writeln!(std::io::stderr().lock(), "{v}");
        }
    }

    fn human(&self) -> bool {
        matches!(self.mode, ProgressMode::Auto | ProgressMode::Bar)
    }

    fn say(&self, msg: &str) {
        eprintln!("{msg}");
    }

    fn notice(&self, msg: &str) {
        if !self.quiet {
            eprintln!("{msg}");
        }
    }

    fn warn(&self, msg: &str) {
        eprintln!("warning: {msg}");
    }

    fn bar(&self, total: u64, label: &str, unit: &str) -> Option<Arc<dyn Bar>> {
        std::io::stderr()
            .is_terminal()
            .then(|| Arc::new(super::progress::bar_of(total, label, unit)) as Arc<dyn Bar>)
    }
}

impl Bar for ProgressBar {
    fn set_position(&self, pos: u64) {
        ProgressBar::set_position(self, pos);
    }

    fn set_length(&self, total: u64) {
        ProgressBar::set_length(self, total);
    }

    fn set_message(&self, msg: &str) {
        ProgressBar::set_message(self, msg.to_string());
    }

    fn finish(&self) {
        self.finish_and_clear();
    }
}

/// `-q/--quiet` and `--progress`, the same on every long-running command.
#[derive(Debug, Clone, clap::Args)]
pub struct ProgressArgs {
    /// Print nothing but errors and warnings: no progress, no summary, no "wrote" lines.
    #[arg(short, long)]
    pub quiet: bool,
    /// Progress on stderr: `auto` (a bar on a terminal, a line every ~5 % otherwise), `bar`,
    /// `json` (one JSON event per line, for pipeline tools), `none`.
    #[arg(long, value_enum, default_value = "auto")]
    pub progress: ProgressMode,
}

impl ProgressArgs {
    /// The events these flags ask for.
    pub fn events(&self) -> Events {
        Terminal::events(self.progress, self.quiet)
    }

    /// Whether a progress bar may be drawn (a terminal, `auto` or `bar`, not quiet).
    pub fn bar(&self) -> bool {
        !self.quiet
            && matches!(self.progress, ProgressMode::Auto | ProgressMode::Bar)
            && std::io::stderr().is_terminal()
    }

    /// Prints a note on stderr unless quiet.
    pub fn note(&self, msg: impl AsRef<str>) {
        if !self.quiet {
            eprintln!("{}", msg.as_ref());
        }
    }
}
