//! The bench runs end to end on the test device (small sizes: CI is lavapipe).
use std::process::Command;

#[test]
fn bench_prints_and_writes_json() {
    let json = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench-smoke.json");
    let run = Command::new(env!("CARGO_BIN_EXE_bench"))
        .args(["--triangles", "4000", "--instances", "8", "--big-mesh-triangles", "4000", "--width", "64", "--height", "36"])
        .args(["--rays", "1,2", "--frames", "1", "--warmup-ms", "0", "--json"])
        .arg(&json)
        .output()
        .expect("run bench");
    let text = String::from_utf8_lossy(&run.stdout).to_string() + &String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{text}");
    let j = std::fs::read_to_string(&json).unwrap();
    for key in [
        "blas_big_mesh",
        "triangles_per_s",
        "blas_field",
        "tlas",
        "build_gpu_task_cpu_us",
        "ratio_to_floor",
        "floor_gpu_ms",
        "memory_bytes",
        "injection",
        "cache_bytes_mean_per_instance",
        "shadow_gpu_ms",
        "diffuse_gpu_ms",
        "specular_gpu_ms",
        "multi_shadow_4_lights_gpu_ms",
        "passes_gpu_ms",
        "blur_1",
        "shadow_blur",
    ] {
        assert!(j.contains(key), "{key} missing from {j}");
    }
    assert!(text.contains("AO 64x36, 2 ray(s)/pixel"), "{text}");
    assert!(text.contains("  pass temporal"), "{text}");
}

/// The field registered with positions interleaved in 32-byte vertices gets the same compact
/// copy as packed positions: the caches sized from it (edge lengths read back from the copy)
/// match byte for byte. (A bench that re-registered interleaved buffers as packed once
/// measured a 15x slower, wrong field.)
#[test]
fn interleaved_field_gets_the_packed_copy() {
    let cache_bytes = |stride: &str| {
        let json = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("bench-stride-{stride}.json"));
        let run = Command::new(env!("CARGO_BIN_EXE_bench"))
            .args(["--triangles", "4000", "--instances", "8", "--big-mesh-triangles", "2000", "--width", "32", "--height", "18"])
            .args(["--rays", "1", "--frames", "1", "--warmup-ms", "0", "--vertex-stride", stride, "--json"])
            .arg(&json)
            .output()
            .expect("run bench");
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        let j = std::fs::read_to_string(&json).unwrap();
        let at = j.find("\"cache_bytes_total\": ").expect("cache_bytes_total") + 21;
        j[at..].chars().take_while(|c| c.is_ascii_digit()).collect::<String>()
    };
    assert_eq!(cache_bytes("12"), cache_bytes("32"));
}
