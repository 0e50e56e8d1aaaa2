//! Progress bars on stderr: drawn only on a terminal, so pipelines get clean logs.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressState, ProgressStyle};

/// A bar over `total` photons with elapsed time, percent, a message, the rate and ETA;
/// hidden when stderr is not a terminal.
pub fn bar(total: u64, msg: &str) -> ProgressBar {
    bar_of(total, msg, "photons")
}

/// A bar over `total` items named `unit` (photons, directions, profiles): elapsed time,
/// percent, a message, the rate with an SI prefix (`1.23 M photons/s`) and ETA; hidden when
/// stderr is not a terminal.
pub fn bar_of(total: u64, msg: &str, unit: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(total);
    let per_s = format!("{unit}/s");
    b.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {percent:>3}% {msg} {rate} eta {eta}",
        )
        .expect("valid template")
        .with_key(
            "rate",
            move |s: &ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = w.write_str(&crate::progress::si(s.per_sec(), &per_s));
            },
        )
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
