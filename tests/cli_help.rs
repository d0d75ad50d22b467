//! The command tree: every subcommand answers `--help`, `oslf --help` lists them, completion
//! scripts cover them, a wrong subcommand is a clear error, and a closed output pipe is no panic.

use crate::common;

use common::oslf;

const SUBCOMMANDS: [&str; 10] = [
    "bake",
    "render",
    "view",
    "store",
    "truth",
    "compare",
    "tables",
    "sweep",
    "cache-stats",
    "completions",
];

const STORE_SUBCOMMANDS: [&str; 4] = ["info", "verify", "export-cube", "export-sample-map"];

fn stdout_of(sub: &str, args: &[&str]) -> String {
    let out = oslf(sub).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "oslf {sub} {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn every_subcommand_is_listed_and_has_help() {
    let top = stdout_of("", &["--help"]);
    for sub in SUBCOMMANDS {
        assert!(
            top.contains(&format!("  {sub} ")),
            "{sub} missing from:\n{top}"
        );
        let help = stdout_of(sub, &["--help"]);
        assert!(help.contains(&format!("Usage: oslf {sub}")), "{help}");
    }
    let store = stdout_of("store", &["--help"]);
    for sub in STORE_SUBCOMMANDS {
        assert!(
            store.contains(&format!("  {sub} ")),
            "{sub} missing from:\n{store}"
        );
        stdout_of(&format!("store {sub}"), &["--help"]);
    }
    assert!(stdout_of("", &["--version"]).starts_with("oslf "));
}

#[test]
fn completion_scripts_cover_the_tree() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let script = stdout_of("completions", &[shell]);
        for word in SUBCOMMANDS.iter().chain(&STORE_SUBCOMMANDS) {
            assert!(script.contains(word), "{shell} completions lack {word}");
        }
    }
    // Flags of a subcommand are completed too.
    assert!(stdout_of("completions", &["bash"]).contains("--preview-spp"));
}

#[test]
fn a_wrong_subcommand_or_shell_is_a_clear_error() {
    let out = oslf("bak").output().unwrap();
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("unrecognized subcommand 'bak'") && e.contains("bake"),
        "{e}"
    );
    let out = oslf("completions tcsh").output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("tcsh"));
}

/// Output into a pipe whose reader has gone (`oslf store info S | head -1`) ends the process quietly,
/// killed by SIGPIPE as any Unix tool, never with a panic about printing to stdout.
#[cfg(unix)]
#[test]
fn a_closed_output_pipe_ends_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;

    let store = common::runtime_fixture::store_path();
    for args in [vec!["store", "info"], vec!["store", "verify"]] {
        let mut cmd = common::oslf(args[0]);
        let mut child = cmd
            .args(&args[1..])
            .arg(&store)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Close the read end before the program writes (it is still starting).
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(
            out.status.success() || out.status.signal() == Some(libc::SIGPIPE),
            "{args:?}: {:?}: {stderr}",
            out.status
        );
    }
}
