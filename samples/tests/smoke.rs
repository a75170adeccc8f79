//! The sample and the bench run end to end on the test device (small sizes: CI is lavapipe).
use std::process::Command;

#[test]
fn sample_writes_a_plausible_ao_image() {
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("sample-smoke");
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(env!("CARGO_BIN_EXE_sample"))
        .args(["--width", "96", "--height", "54", "--rays", "4", "--frames", "3", "--out"])
        .arg(&out)
        .output()
        .expect("run sample");
    let text = String::from_utf8_lossy(&run.stdout).to_string() + &String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{text}");
    assert!(text.contains("GPU time") && text.contains("wrote"), "{text}");
    for name in ["ao.png", "lit.png", "debug_cache.png", "debug_cache_overview.png", "debug_random_tile.png", "debug_random_mesh.png", "debug_hit_t.png", "debug_barycentrics.png", "shadow.png", "diffuse_gi.png", "specular.png"] {
        assert!(out.join(name).metadata().map_or(0, |m| m.len()) > 100, "{name} written");
    }
    assert!(text.contains("injection"), "{text}");
    let image = exr::prelude::read_first_rgba_layer_from_file(
        out.join("ao.exr"),
        |res, _| vec![0f32; res.width() * res.height()],
        |px: &mut Vec<f32>, pos, (r, _g, _b, _a): (f32, f32, f32, f32)| px[pos.y() * 96 + pos.x()] = r,
    )
    .expect("read the EXR back");
    let ao = image.layer_data.channel_data.pixels;
    let mean = ao.iter().sum::<f32>() / ao.len() as f32;
    let min = ao.iter().cloned().fold(1.0, f32::min);
    assert!(ao.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)), "AO in [0, 1]");
    assert!(mean > 0.6 && mean < 0.99, "mostly open room with occluded corners: mean {mean}");
    assert!(min < 0.5, "contacts and corners are dark: min {min}");
}

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
    for key in ["blas_big_mesh", "triangles_per_s", "blas_field", "tlas", "build_gpu_task_cpu_us", "ratio_to_floor", "floor_gpu_ms", "memory_bytes", "injection", "cache_bytes_mean_per_instance", "shadow_gpu_ms", "diffuse_gpu_ms", "specular_gpu_ms", "multi_shadow_4_lights_gpu_ms"] {
        assert!(j.contains(key), "{key} missing from {j}");
    }
    assert!(text.contains("AO 64x36, 2 ray(s)/pixel"), "{text}");
}
