//! The binaries' command lines (clap): mistakes are errors that name the flag, `--help` and
//! `--version` answer without rendering, and no input makes them panic.
use std::process::{Command, Output};

fn run(bin: &str, args: &[&str]) -> (Output, String) {
    let out = Command::new(bin).args(args).env_remove("DISPLAY").output().expect("run");
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out, text)
}

const SAMPLE: &str = env!("CARGO_BIN_EXE_sample");
const BENCH: &str = env!("CARGO_BIN_EXE_bench");
const QUALITY: &str = env!("CARGO_BIN_EXE_quality");

/// A usage error: exit status 2, a message naming `needle`, no panic, no render.
fn refused(bin: &str, args: &[&str], needle: &str) {
    let (out, text) = run(bin, args);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {text}");
    assert!(text.contains(needle), "{args:?}: {needle:?} missing from {text}");
    assert!(!text.contains("panicked") && !text.contains("device:"), "{args:?}: {text}");
}

#[test]
fn mistakes_are_errors_that_name_the_flag() {
    // A misspelt flag (the old parser ignored it) gets the right spelling suggested.
    refused(SAMPLE, &["--widht", "64"], "'--widht'");
    refused(SAMPLE, &["--widht", "64"], "--width");
    // `--width=64` is the same as `--width 64`; a value that is no number is an error.
    refused(SAMPLE, &["--width=abc"], "invalid value 'abc'");
    refused(SAMPLE, &["--width", "4"], "--width");
    refused(SAMPLE, &["--rays", "0"], "--rays");
    refused(SAMPLE, &["--headless", "--window"], "cannot be used with");
    refused(SAMPLE, &["a.glb", "b.glb"], "unexpected argument 'b.glb'");
    // The bench's list of ray counts (it panicked on these).
    refused(BENCH, &["--rays", "a,b"], "invalid value 'a'");
    refused(BENCH, &["--rays", "1,100"], "--rays");
    refused(BENCH, &["--frames", "0"], "--frames");
    refused(QUALITY, &["--bogus"], "'--bogus'");
    refused(SAMPLE, &["--camera", "x"], "--camera");
}

#[test]
fn help_and_version_answer_without_rendering() {
    for bin in [SAMPLE, BENCH, QUALITY] {
        let (out, text) = run(bin, &["--version"]);
        assert!(out.status.success(), "{text}");
        assert!(text.contains(env!("CARGO_PKG_VERSION")), "{text}");
        let (out, help) = run(bin, &["--help"]);
        assert!(out.status.success() && help.contains("Usage:"), "{help}");
        assert!(!help.contains("device:"), "--help rendered: {help}");
    }
    let (_, help) = run(SAMPLE, &["--help"]);
    for needle in ["--headless", "--frames", "modes:", "debug_barycentrics", "window keys:"] {
        assert!(help.contains(needle), "{needle} missing from the sample's --help:\n{help}");
    }
}

/// A file that does not load is an error that names it (exit status 1), not a panic; so is
/// a camera the scene does not have.
#[test]
fn a_missing_scene_file_is_named() {
    let (out, text) = run(SAMPLE, &["--headless", "no-such-scene.glb", "--frames", "2"]);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("no-such-scene.glb") && !text.contains("panicked"), "{text}");
    let (out, text) = run(SAMPLE, &["--headless", "--camera", "3", "--frames", "2"]);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("--camera 3: cornell room has 0 camera(s)"), "{text}");
}
