//! The `solidtex` binary: parse arguments, run, map errors to exit codes.

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = solidtex::cli::Cli::parse();
    match solidtex::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", solidtex::cli::clip(&error.to_string()));
            ExitCode::from(error.exit_code())
        }
    }
}
