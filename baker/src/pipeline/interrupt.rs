//! SIGINT/SIGTERM: the first signal asks the bake to stop after the units that are running
//! (their results are cached, so the next run resumes); a second one exits at once.

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
/// Set with `--progress json|none` or `--quiet`: the handler writes nothing (the bake emits
/// its `interrupted` event).
static SILENT: AtomicBool = AtomicBool::new(false);

pub fn set_silent(silent: bool) {
    SILENT.store(silent, Ordering::SeqCst);
}

/// The error a bake returns when it stopped on a signal (exit code 130).
#[derive(Debug, thiserror::Error)]
#[error("interrupted")]
pub struct Interrupted;

/// Installs the handler (once per process; later calls do nothing).
pub fn install() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            let silent = SILENT.load(Ordering::SeqCst);
            if REQUESTED.swap(true, Ordering::SeqCst) {
                if !silent {
                    eprintln!("\nsecond interrupt: exiting now (finished units are cached)");
                }
                std::process::exit(130);
            }
            if !silent {
                eprintln!(
                    "\ninterrupt: finishing the running units (press Ctrl-C again to stop now)"
                );
            }
        });
    });
}

pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
