//! The hybrid-rt sample: a rasterizing renderer with ray-traced shadows, AO, diffuse GI and
//! reflections from the SDK, integrated as an engine would (see `hybrid_rt_samples::renderer`).
//!
//! Headless (the default without a display, or `--headless`): renders `--frames` frames along
//! the scene's camera path and writes every chosen mode of the last frame as EXR (linear) and
//! PNG (tone-mapped), then prints per-task GPU times (means over the frames after the first)
//! and the SDK's memory. With a display (or `--window`): a window; keys switch modes and move
//! the camera, the title shows the GPU times.
use hybrid_rt_samples::args::Args;
use hybrid_rt_samples::modes::{self, Mode};
use hybrid_rt_samples::renderer::{Renderer, Settings};
use hybrid_rt_samples::{gltf_scene, images, report, scenes, window};
use hybrid_rt_testkit::host::Host;
use std::path::PathBuf;

const USAGE: &str = "sample [scene.gltf|scene.glb] [--headless | --window] [--width 640] [--height 360] [--frames 16]
       [--modes all|composite,ao,...] [--out out] [--rays 1] [--checkerboard] [--blas-per-frame 4]
       [--lidar-size 256] [--exposure 1.0] [--magenta-unlit] [--json timings.json]
modes: composite direct albedo normals roughness metalness motion sun_shadow_noisy sun_shadow
       point_shadow_noisy point_shadow ao_noisy ao diffuse_noisy diffuse specular_noisy specular
       lidar debug_cache debug_random_tile debug_random_mesh debug_hit_t debug_barycentrics
window keys: Tab / Shift+Tab next / previous mode, 1-9 first modes, W A S D Q E move, arrows look,
       Space pause the animation, P write the current mode to --out, Esc quit";

fn main() {
    if let Err(e) = run() {
        eprintln!("sample failed: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = Args::parse(USAGE);
    let settings = Settings {
        width: args.get("width", 640u32).max(8),
        height: args.get("height", 360u32).max(8),
        lidar_size: args.get("lidar-size", 256u32).max(8),
        unlit_color: if args.flag("magenta-unlit") { [1.0, 0.0, 1.0] } else { [0.0; 3] },
        max_blas_build_count: args.get("blas-per-frame", 4u32),
        rays_per_pixel: args.get("rays", 1u32).clamp(1, 64),
        checkerboard: args.flag("checkerboard"),
        exposure: args.get("exposure", 1.0f32),
        ..Default::default()
    };
    let scene = match args.positional.first() {
        Some(path) => gltf_scene::load(std::path::Path::new(path))?,
        None => scenes::cornell_room(),
    };
    let out = PathBuf::from(args.string("out", "out"));
    let windowed = if args.flag("headless") { false } else { args.flag("window") || std::env::var_os("DISPLAY").is_some() };
    if windowed {
        let frames = args.named("frames").and_then(|v| v.parse().ok());
        return window::run(scene, settings, frames, out);
    }

    let chosen: Vec<Mode> = match args.string("modes", "all").as_str() {
        "all" => modes::ALL.to_vec(),
        list => list
            .split(',')
            .map(|n| Mode::parse(n.trim()).ok_or(format!("unknown mode {n:?} (see --help)")))
            .collect::<Result<_, _>>()?,
    };
    let frames = args.get("frames", 16u32).max(2);

    let host = Host::new()?;
    println!("device: {}{}", host.device_name, if host.validation_enabled { " (validation on)" } else { "" });
    println!(
        "scene: {}, {} triangles in {} instances; {}x{}, {frames} frames",
        scene.name,
        scene.scene.triangle_count(),
        scene.scene.instances.len(),
        settings.width,
        settings.height
    );
    let debug: Vec<hybrid_rt::DebugOutput> =
        chosen.iter().filter_map(|m| if let Mode::Debug(d) = m { Some(*d) } else { None }).collect();
    let mut r = Renderer::new(&host, scene, settings)?;
    for f in 0..frames {
        let u = f as f32 / (frames - 1) as f32;
        let camera = r.scene.camera_path.at(u);
        // Animation at 30 frames per second of scene time, whatever the real frame rate.
        let last = f + 1 == frames;
        r.render(camera, f as f32 / 30.0, if last { &debug } else { &[] }, None)?;
    }
    r.finish()?;
    let mut written = Vec::new();
    for mode in &chosen {
        let (linear, display) = r.capture(*mode)?;
        images::write_capture(&out, mode.name(), settings.width, settings.height, &linear, &display)?;
        written.push(mode.name());
    }
    let report = report::Report::new(&r);
    print!("{}", report.text());
    if let Some(path) = args.named("json") {
        std::fs::write(&path, report.json()).map_err(|e| format!("{path}: {e}"))?;
    }
    println!("wrote {} modes as EXR + PNG to {}: {}", written.len(), out.display(), written.join(", "));
    r.destroy()?;
    let errors = Host::validation_errors();
    if errors > 0 {
        return Err(format!(
            "{errors} Vulkan validation errors, the first: {:#?}",
            Host::validation_messages().iter().take(3).collect::<Vec<_>>()
        ));
    }
    Ok(())
}
