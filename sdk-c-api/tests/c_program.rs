//! Builds the C samples (samples/c: the tour of every entry point, and the page-long AO
//! example, each with the engine scaffolding of engine.c) against the static library with the
//! system C compiler and runs them on the test device. The programs check their own results
//! and exit 0 only if every check passed. Then a C++ translation unit that includes the header, linked
//! against the shared library of the build tree and run from there.
use std::process::Command;

/// The static library of this crate.
fn staticlib() -> std::path::PathBuf {
    library(".a")
}

/// The built library of this crate whose file name ends with `suffix`.
fn library(suffix: &str) -> std::path::PathBuf {
    // `cargo test` builds only the rlib, so build the staticlib of this crate explicitly.
    let out = Command::new(env!("CARGO"))
        .args(["build", "-p", "hybrid-rt-c", "--lib", "--message-format=json"])
        .output()
        .expect("run cargo build");
    assert!(out.status.success(), "cargo build failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    for line in stdout.lines().filter(|l| l.contains("\"hybrid-rt-c\"") || l.contains("hybrid_rt_c")) {
        if let Some(start) = line.find("\"filenames\":[") {
            let list = &line[start + 13..];
            let list = &list[..list.find(']').unwrap_or(list.len())];
            for f in list.split(',') {
                let f = f.trim_matches('"');
                if f.ends_with(suffix) {
                    return f.into();
                }
            }
        }
    }
    panic!("no {suffix} library in cargo's output");
}

/// Compiles `samples/c/{program}.c` with engine.c against the static library, runs it (with
/// synchronization validation when the layer is installed) and returns its output, having
/// checked that it exited 0.
fn build_and_run_c_sample(program: &str) -> String {
    let lib = staticlib();
    let dir = env!("CARGO_MANIFEST_DIR");
    let exe = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("c_{program}"));
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-Wno-missing-field-initializers", "-O1"])
        .arg(format!("-I{dir}/include"))
        .arg(format!("{dir}/../samples/c/{program}.c"))
        .arg(format!("{dir}/../samples/c/engine.c"))
        .arg(&lib)
        .args(["-lvulkan", "-lm", "-lpthread", "-ldl", "-o"])
        .arg(&exe)
        .status()
        .expect("run the C compiler (install gcc: scripts/setup.sh)");
    assert!(status.success(), "the C sample {program}.c did not compile");
    // The layer's own settings variable: synchronization validation always, best practices when
    // the suite runs with them (the C program makes its own instance). A ':'-separated list.
    let mut checks = vec!["VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT"];
    if std::env::var("HRT_BEST_PRACTICES").is_ok_and(|v| v != "0") {
        checks.push("VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT");
    }
    let out = Command::new(&exe).env("VK_LAYER_ENABLES", checks.join(":")).output().expect("run the C sample");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    eprintln!("{text}");
    assert!(out.status.success(), "the C sample {program}.c failed");
    text
}

#[test]
fn c_tour_checks_every_entry_point() {
    assert!(build_and_run_c_sample("tour").contains("c_api: all checks passed"));
}

#[test]
fn the_page_long_c_example_traces_ao() {
    let text = build_and_run_c_sample("ao");
    assert!(text.contains("c ao: passed"));
    // It stays a page: the integration, not the scaffolding.
    let lines = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../samples/c/ao.c")).unwrap().lines().count();
    assert!(lines <= 120, "samples/c/ao.c has grown to {lines} lines");
}

#[test]
fn a_cpp_program_includes_the_header_and_loads_the_build_trees_library() {
    let shared = library(".so");
    let lib_dir = shared.parent().unwrap();
    let dir = env!("CARGO_MANIFEST_DIR");
    let exe = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("header_check");
    let cxx = std::env::var("CXX").unwrap_or_else(|_| "c++".into());
    let status = Command::new(&cxx)
        .args(["-std=c++17", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1"])
        .arg(format!("-I{dir}/include"))
        .arg(format!("{dir}/tests/c/header_check.cpp"))
        .arg(format!("-L{}", lib_dir.display()))
        .args(["-lhybrid_rt_c", "-o"])
        .arg(&exe)
        .status()
        .expect("run the C++ compiler (install g++: scripts/setup.sh)");
    assert!(status.success(), "the header does not compile as C++");
    // Loaded from the build tree: the library names no SONAME there, so the program asks for
    // the file it was linked with.
    let out = Command::new(&exe).env("LD_LIBRARY_PATH", lib_dir).output().expect("run the C++ program");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    eprintln!("{text}");
    assert!(out.status.success(), "the C++ program failed: {text}");
    assert!(text.contains("c++: header checks passed"));
}
