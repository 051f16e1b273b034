//! The `solidtex` binary: parse arguments, run, map errors to exit codes.

use std::process::ExitCode;

fn main() -> ExitCode {
    use solidtex::cli::Command;
    use std::io::Write;
    use std::path::Path;
    let cli = solidtex::cli::Cli::parse_numbers_from(arguments());
    #[cfg(unix)]
    stop_cleanly_on_signals();
    // Two front ends: the terminal UI (no command, or `tui`) and every other command.
    let result = match cli.command {
        None => solidtex::tui::run(Path::new("exemplars/library.toml"), Path::new("out")),
        Some(Command::Tui { manifest, output }) => solidtex::tui::run(&manifest, &output),
        Some(command) => solidtex::cli::run(command),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // a closed error stream must not turn the exit code into a panic's
            let _ = writeln!(std::io::stderr(), "error: {}", solidtex::cli::clip(&error.to_string()));
            ExitCode::from(error.exit_code())
        }
    }
}

/// On SIGINT, SIGTERM or SIGHUP, give the terminal back if the UI holds it, remove the
/// temporary files and folders being written and exit with 128 plus the signal's number
/// (130, 143, 129), as a shell reports a command it stopped. The terminal UI reads Ctrl-C
/// as a key in raw mode, so SIGINT reaches it only from `kill`.
#[cfg(unix)]
fn stop_cleanly_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else { return };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            // whatever happens while giving the terminal back, the process exits: a write to
            // a terminal that is closing can block (the UI thread may hold the output's
            // lock), so the restore gets half a second
            let (restored, wait) = std::sync::mpsc::channel();
            std::thread::spawn(move || {
                let _ = std::panic::catch_unwind(solidtex::tui::restore_terminal);
                let _ = restored.send(());
            });
            let _ = wait.recv_timeout(std::time::Duration::from_millis(500));
            solidtex::io::atomic::remove_live_temporaries();
            std::process::exit(128 + signal);
        }
    });
}

/// The command line, with `--help` or `-h` after `help` left out (`help --help` is read as
/// `help help`): clap's own help subcommand takes no flags and would refuse them as a usage
/// error.
fn arguments() -> Vec<std::ffi::OsString> {
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args.get(1).is_some_and(|a| a == "help") {
        args.retain(|a| a != "--help" && a != "-h");
        if args.len() == 2 {
            args.push("help".into());
        }
    }
    args
}
