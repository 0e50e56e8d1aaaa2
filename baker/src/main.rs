//! `baker`: parses the command line and hands it to the library.

use clap::Parser;

fn main() {
    let cli = baker::cli::Cli::parse();
    if let Err(e) = baker::cli::run(cli) {
        // A closed pipe (`baker … | head`) is a normal end, as for any Unix tool.
        let broken_pipe = e.chain().any(|c| {
            c.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
        });
        if broken_pipe {
            std::process::exit(0);
        }
        // Interrupted bakes have said how to resume.
        if e.downcast_ref::<baker::pipeline::interrupt::Interrupted>()
            .is_some()
        {
            std::process::exit(baker::cli::pipeline::EXIT_INTERRUPTED);
        }
        // Spec errors carry their own multi-line listing; others print their cause chain.
        eprintln!("error: {e:#}");
        std::process::exit(e.downcast_ref::<baker::cli::UsageError>().map_or(1, |_| 2));
    }
}
