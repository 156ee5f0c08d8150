//! `ember`: parse the command line, run the command, report errors as text and exit
//! with 0 (success, `--help`, `--version`), 1 (any error) or 128 + the signal that
//! stopped a render (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP: the image of the completed
//! passes is written, if there is one).

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
        Err(e @ app::AppError::Interrupted(_)) => {
            eprintln!("{e}");
            ExitCode::from(ember_host::interrupt::exit_code())
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
