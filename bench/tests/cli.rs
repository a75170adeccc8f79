//! The bench's and the quality program's command lines (clap): mistakes are errors that name
//! the flag, `--help` and `--version` answer without rendering, and no input makes them panic.
//! The helpers are the sample's command-line tests' (the three programs parse alike).
#[path = "../../samples/tests/cli_support/mod.rs"]
mod cli_support;
use cli_support::{answers_help_and_version, refused};

const BENCH: &str = env!("CARGO_BIN_EXE_bench");
const QUALITY: &str = env!("CARGO_BIN_EXE_quality");

#[test]
fn mistakes_are_errors_that_name_the_flag() {
    // The bench's list of ray counts (it panicked on these).
    refused(BENCH, &["--rays", "a,b"], "invalid value 'a'");
    refused(BENCH, &["--rays", "1,100"], "--rays");
    refused(BENCH, &["--frames", "0"], "--frames");
    refused(QUALITY, &["--bogus"], "'--bogus'");
}

#[test]
fn help_and_version_answer_without_rendering() {
    for bin in [BENCH, QUALITY] {
        answers_help_and_version(bin);
    }
}
