//! The errors the command line tells apart, and their exit codes.
//!
//! Library code returns `anyhow::Error`; a [`UsageError`] (bad spec, bad flag combination, a
//! file that is not what it should be) or [`Cancelled`] anywhere in the chain decides the exit
//! code in [`exit_code`].

pub use crate::cancel::Cancelled;

/// Exit code of a failed command (I/O, a damaged table, a bug).
pub const EXIT_FAILURE: i32 = 1;
/// Exit code of a usage error: the input is wrong, not the program.
pub const EXIT_USAGE: i32 = 2;
/// Exit code of a bake stopped by SIGINT/SIGTERM (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: i32 = 130;

/// A user error (bad spec, bad flag combination): exit code [`EXIT_USAGE`].
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// The exit code for `e`: 130 when interrupted, 2 for a usage error, else 1.
pub fn exit_code(e: &anyhow::Error) -> i32 {
    if e.downcast_ref::<Cancelled>().is_some() {
        EXIT_INTERRUPTED
    } else if e.downcast_ref::<UsageError>().is_some() {
        EXIT_USAGE
    } else {
        EXIT_FAILURE
    }
}
