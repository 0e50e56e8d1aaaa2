//! `baker`: parses the command line and hands it to the library.

use clap::Parser;

fn main() {
    let cli = baker::cli::Cli::parse();
    if let Err(e) = baker::cli::run(cli) {
        // Spec errors carry their own multi-line listing; others print their cause chain.
        eprintln!("error: {e:#}");
        std::process::exit(e.downcast_ref::<baker::cli::UsageError>().map_or(1, |_| 2));
    }
}
