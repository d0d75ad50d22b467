//! `oslf completions SHELL`: a completion script for the whole command tree.

use clap::CommandFactory;
use clap_complete::Shell;

/// Which shell to write completions for.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The shell: bash, zsh, fish, elvish or powershell.
    shell: Shell,
}

/// Writes the script to stdout, e.g. `oslf completions bash > ~/.local/share/bash-completion/completions/oslf`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut command = super::Cli::command();
    clap_complete::generate(args.shell, &mut command, "oslf", &mut std::io::stdout());
    Ok(())
}
