//! SIGINT/SIGTERM: the first signal sets the process's [`Cancel`] flag, so running units stop
//! at their next photon batch (they are not cached; finished units are) and the bake exits
//! with 130; a second signal exits at once. Schedulers (Slurm, Kubernetes, CI) send SIGTERM and
//! then SIGKILL after a grace period of seconds: the bake is gone well within it.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::cancel::Cancel;
pub use crate::cancel::Cancelled as Interrupted;

static REQUESTED: AtomicBool = AtomicBool::new(false);
/// Set with `--progress json|none` or `--quiet`: the handler writes nothing (the bake emits
/// its `interrupted` event).
static SILENT: AtomicBool = AtomicBool::new(false);

pub fn set_silent(silent: bool) {
    SILENT.store(silent, Ordering::SeqCst);
}

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
                    "\ninterrupt: stopping at the next batch (press Ctrl-C again to stop now)"
                );
            }
        });
    });
}

/// The flag the handler sets, as a token for the work it should stop.
pub fn cancel() -> Cancel {
    Cancel::new(&REQUESTED)
}

pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
