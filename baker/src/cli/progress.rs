//! Progress bars on stderr: drawn only on a terminal, so pipelines get clean logs.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

/// A bar over `total` units with elapsed time, percent, a message, the rate (photons/s for
/// skin bakes, directions/s for fibers) and ETA; hidden when stderr is not a terminal.
pub fn bar(total: u64, msg: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(total);
    b.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {percent:>3}% {msg} {per_sec} eta {eta}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    b.set_message(msg.to_string());
    b
}

impl crate::progress::Progress for ProgressBar {
    fn advance(&self, n: u64) {
        self.inc(n);
    }
}

/// `bar` as the library's progress sink.
pub fn reporter(bar: &Option<ProgressBar>) -> crate::progress::Reporter {
    bar.clone()
        .map(|b| std::sync::Arc::new(b) as std::sync::Arc<dyn crate::progress::Progress>)
}
