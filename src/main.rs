//! `oslf`: the one command of the offset surface light field tools.
//!
//! Each subcommand lives in its own module under `cli/`; `oslf --help` lists them and
//! `oslf help <command>` shows one. Errors print as `error: ...` with their causes and exit 1.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    restore_sigpipe();
    match cli::run(cli::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Output piped into a program that stops reading (`oslf compare a.exr b.exr | head -1`) ends
/// the process quietly, as for any Unix tool, instead of a panic from `println!`: Rust starts
/// programs with SIGPIPE ignored, so restore the default action.
#[cfg(unix)]
fn restore_sigpipe() {
    // SAFETY: called first thing in `main`, before any thread exists; `signal` with SIG_DFL
    // installs no handler code, it only resets the disposition of SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn restore_sigpipe() {}
