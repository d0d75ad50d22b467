//! `oslf`: the one command of the offset surface light field tools.
//!
//! Each subcommand lives in its own module under `cli/`; `oslf --help` lists them and
//! `oslf help <command>` shows one. Errors print as `error: ...` with their causes and exit 1.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    match cli::run(cli::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
