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
        let code = baker::error::exit_code(&e);
        // Interrupted bakes have said how to resume; spec errors carry their own multi-line
        // listing; others print their cause chain.
        if code != baker::error::EXIT_INTERRUPTED {
            eprintln!("error: {e:#}");
        }
        std::process::exit(code);
    }
}
