//! The sample's command line (clap): mistakes are errors that name the flag, `--help` and
//! `--version` answer without rendering, and no input makes it panic. The bench's and the
//! quality program's are checked in bench/tests/cli.rs.
mod cli_support;
use cli_support::{answers_help_and_version, refused, run};

const SAMPLE: &str = env!("CARGO_BIN_EXE_sample");

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
    refused(SAMPLE, &["--camera", "x"], "--camera");
    refused(SAMPLE, &["--random-numbers", "purple"], "blue-noise");
}

#[test]
fn help_and_version_answer_without_rendering() {
    answers_help_and_version(SAMPLE);
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
