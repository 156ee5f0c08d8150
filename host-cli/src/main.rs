//! `ember`: parse the command line, run the command, report errors as text and exit
//! with 0 (success, `--help`, `--version`) or 1 (any error).

use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;

use ember_cli::app;
use ember_cli::cli::Cli;

fn main() -> ExitCode {
    // The --time budget counts from here.
    let start = Instant::now();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { ExitCode::FAILURE } else { ExitCode::SUCCESS };
        }
    };
    match app::run(&cli, start) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
