//! The `solidtex` binary: parse arguments, run, map errors to exit codes.

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    use solidtex::cli::Command;
    use std::path::Path;
    let cli = solidtex::cli::Cli::parse();
    // Two front ends: the terminal UI (no command, or `tui`) and every other command.
    let result = match cli.command {
        None => solidtex::tui::run(Path::new("exemplars/library.toml"), Path::new("out")),
        Some(Command::Tui { manifest, output }) => solidtex::tui::run(&manifest, &output),
        Some(command) => solidtex::cli::run(command),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", solidtex::cli::clip(&error.to_string()));
            ExitCode::from(error.exit_code())
        }
    }
}
