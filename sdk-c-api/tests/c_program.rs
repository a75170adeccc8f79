//! Builds the C sample (samples/c/ao_minimal.c) against the static library with the system C
//! compiler and runs it on the test device. The program checks its own results and exits 0
//! only if every check passed.
use std::process::Command;

fn staticlib() -> std::path::PathBuf {
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
                if f.ends_with(".a") {
                    return f.into();
                }
            }
        }
    }
    panic!("no staticlib in cargo's output");
}

#[test]
fn c_program_runs_ao_end_to_end() {
    let lib = staticlib();
    let dir = env!("CARGO_MANIFEST_DIR");
    let exe = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("ao_minimal");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-Wno-missing-field-initializers", "-O1"])
        .arg(format!("-I{dir}/include"))
        .arg(format!("{dir}/../samples/c/ao_minimal.c"))
        .arg(&lib)
        .args(["-lvulkan", "-lm", "-lpthread", "-ldl", "-o"])
        .arg(&exe)
        .status()
        .expect("run the C compiler (install gcc: scripts/setup.sh)");
    assert!(status.success(), "the C sample did not compile");
    // The layer's own settings variable: synchronization validation always, best practices when
    // the suite runs with them (the C program makes its own instance). A ':'-separated list.
    let mut checks = vec!["VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT"];
    if std::env::var("HRT_BEST_PRACTICES").is_ok_and(|v| v != "0") {
        checks.push("VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT");
    }
    let out = Command::new(&exe).env("VK_LAYER_ENABLES", checks.join(":")).output().expect("run the C sample");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    eprintln!("{text}");
    assert!(out.status.success(), "the C sample failed");
    assert!(text.contains("c_api: all checks passed"));
}
