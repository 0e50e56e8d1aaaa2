//! The command line's conventions, checked over every subcommand's clap definition (in the
//! style of ripgrep, fd and cargo): `-o/--out` is the only output-location flag, `-q/--quiet`
//! is everywhere, `--progress` is on every long-running command, `--entry` is repeatable,
//! every flag has a help line. `cargo test -p baker conventions -- --nocapture` prints the
//! table of subcommands × conventions.

use clap::{ArgAction, Command, CommandFactory as _};

/// Commands that run long enough (seconds to hours) to report progress. (`plan` calibrates
/// for about a second per spec; the rest answer at once.)
const LONG_RUNNING: [&str; 6] = ["bake", "merge", "mc", "bench", "fiber trace", "fiber bench"];

/// Output-location flag names of the past; each is at most a hidden alias of `--out` now.
const RETIRED: [&str; 6] = ["output", "png", "mco", "mci-out", "plot", "csv-dir"];

/// Every leaf subcommand with its full name (`fiber trace`).
fn leaves() -> Vec<(String, Command)> {
    let mut out = Vec::new();
    let mut stack: Vec<(String, Command)> = super::Cli::command()
        .get_subcommands()
        .map(|c| (c.get_name().to_string(), c.clone()))
        .collect();
    while let Some((name, c)) = stack.pop() {
        let subs: Vec<_> = c
            .get_subcommands()
            .filter(|s| s.get_name() != "help")
            .collect();
        if subs.is_empty() {
            out.push((name, c));
        } else {
            stack.extend(
                subs.into_iter()
                    .map(|s| (format!("{name} {}", s.get_name()), s.clone())),
            );
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

/// One command's row: (output flag, quiet, progress, entry, help complete), each `Some(ok)`
/// or `None` where the convention does not apply.
struct Row {
    out: Option<bool>,
    quiet: bool,
    progress: Option<bool>,
    entry: Option<bool>,
    help: bool,
    problems: Vec<String>,
}

fn row(name: &str, c: &Command) -> Row {
    let mut problems = Vec::new();
    let args: Vec<_> = c.get_arguments().filter(|a| !a.is_global_set()).collect();
    let find = |long: &str| args.iter().find(|a| a.get_long() == Some(long));
    let out = find("out").map(|a| a.get_short() == Some('o'));
    for a in &args {
        if let Some(l) = a.get_long() {
            // A hidden flag is a compatibility name kept for old scripts, not in the help.
            if RETIRED.contains(&l) && !a.is_hide_set() {
                problems.push(format!("--{l} is an output flag; it is -o/--out now"));
            }
        }
        let id = a.get_id().as_str();
        if id != "help" && id != "version" && a.get_help().is_none_or(|h| h.to_string().is_empty())
        {
            problems.push(format!("{id} has no help line"));
        }
    }
    let quiet = find("quiet").is_some_and(|a| a.get_short() == Some('q'));
    let progress = LONG_RUNNING
        .contains(&name)
        .then(|| find("progress").is_some());
    let entry = find("entry").map(|a| matches!(a.get_action(), ArgAction::Append));
    let help = problems.iter().all(|p| !p.contains("help line"));
    if out == Some(false) {
        problems.push("--out has no -o".into());
    }
    if !quiet {
        problems.push("no -q/--quiet".into());
    }
    if progress == Some(false) {
        problems.push("runs long but has no --progress".into());
    }
    if entry == Some(false) {
        problems.push("--entry takes one value; it is repeatable everywhere".into());
    }
    Row {
        out,
        quiet,
        progress,
        entry,
        help,
        problems,
    }
}

#[test]
fn every_subcommand_follows_the_conventions() {
    let mark = |v: Option<bool>| match v {
        Some(true) => "✓",
        Some(false) => "✗",
        None => "n/a",
    };
    let mut table = String::from(
        "| command | -o/--out | -q/--quiet | --progress | --entry (repeatable) | help complete |\n\
         |---|---|---|---|---|---|\n",
    );
    let mut problems = Vec::new();
    for (name, c) in leaves() {
        let r = row(&name, &c);
        table.push_str(&format!(
            "| `{name}` | {} | {} | {} | {} | {} |\n",
            mark(r.out),
            mark(Some(r.quiet)),
            mark(r.progress),
            mark(r.entry),
            mark(Some(r.help))
        ));
        problems.extend(r.problems.into_iter().map(|p| format!("baker {name}: {p}")));
    }
    eprintln!("{table}");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_check_catches_a_command_that_breaks_a_convention() {
    // A planted violation: an output flag without -o, a one-value --entry, a flag with no help.
    let c = Command::new("bake")
        .arg(clap::Arg::new("out").long("out"))
        .arg(clap::Arg::new("entry").long("entry").action(ArgAction::Set))
        .arg(clap::Arg::new("x").long("x"));
    let r = row("bake", &c);
    assert_eq!(r.out, Some(false));
    assert_eq!(r.entry, Some(false));
    assert_eq!(r.progress, Some(false));
    assert!(!r.quiet && !r.help, "{:?}", r.problems);
}
