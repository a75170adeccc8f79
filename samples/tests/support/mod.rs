//! Helpers the sample's test binaries share: writing the files a test builds, and the loader
//! under mutated files.
pub mod fuzz;

use std::path::PathBuf;

/// Writes `text` as `name` in the tests' directory; returns its path.
pub fn written(name: &str, text: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, text).unwrap();
    path
}
