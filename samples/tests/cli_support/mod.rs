//! Running a binary for its command line's tests: the sample's (samples/tests/cli.rs) and the
//! bench's and quality program's (bench/tests/cli.rs) parse their options the same way (clap).
use std::process::{Command, Output};

pub fn run(bin: &str, args: &[&str]) -> (Output, String) {
    let out = Command::new(bin).args(args).env_remove("DISPLAY").output().expect("run");
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out, text)
}

/// A usage error: exit status 2, a message naming `needle`, no panic, no render.
pub fn refused(bin: &str, args: &[&str], needle: &str) {
    let (out, text) = run(bin, args);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {text}");
    assert!(text.contains(needle), "{args:?}: {needle:?} missing from {text}");
    assert!(!text.contains("panicked") && !text.contains("device:"), "{args:?}: {text}");
}

/// `--version` names the version and `--help` prints a usage, both without rendering.
pub fn answers_help_and_version(bin: &str) {
    let (out, text) = run(bin, &["--version"]);
    assert!(out.status.success(), "{text}");
    assert!(text.contains(env!("CARGO_PKG_VERSION")), "{text}");
    let (out, help) = run(bin, &["--help"]);
    assert!(out.status.success() && help.contains("Usage:"), "{help}");
    assert!(!help.contains("device:"), "--help rendered: {help}");
}
