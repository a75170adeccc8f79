//! The hybrid-rt sample: a rasterizing renderer with ray-traced shadows, AO, diffuse GI and
//! reflections from the SDK, integrated as an engine would (see `hybrid_rt_samples::renderer`).
//!
//! Headless (the default without a display, or `--headless`): renders `--frames` frames along
//! the scene's camera path and writes every chosen mode of the last frame as EXR (linear) and
//! PNG (tone-mapped), then prints per-task GPU times (means over the frames after the first)
//! and the SDK's memory. With a display (or `--window`): a window; keys switch modes and move
//! the camera, the title shows the GPU times.
use clap::Parser;
use hybrid_rt_host::Host;
use hybrid_rt_samples::modes::{self, Mode};
use hybrid_rt_samples::progress::Progress;
use hybrid_rt_samples::renderer::{Renderer, Settings};
use hybrid_rt_samples::{gltf_scene, images, report, scenes, window};
use std::path::PathBuf;

const AFTER_HELP: &str = "modes: composite direct albedo normals roughness metalness motion emissive sun_shadow_noisy
       sun_shadow point_shadow_noisy point_shadow lights_shadow_noisy lights_shadow ao_noisy ao diffuse_noisy
       diffuse specular_noisy specular lidar debug_cache debug_random_tile debug_random_mesh debug_hit_t debug_barycentrics
window keys: Tab / Shift+Tab next / previous mode, 1-9 first modes, W A S D Q E move, arrows look,
       Space pause the animation, P write the current mode to --out, Esc quit";

/// `--random-numbers`: `TraceCommon::random_numbers`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq)]
enum RandomNumbersArg {
    Default,
    WhiteNoise,
    BlueNoise,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq)]
enum Builtin {
    Room,
    Forest,
    /// A skinned figure waving (GPU skinning and a BLAS refit every frame).
    Figure,
}

/// The hybrid-rt sample: a rasterizing renderer with the SDK's ray-traced shadows, AO,
/// diffuse GI and reflections, on a built-in room or a glTF file.
#[derive(Parser, Debug)]
#[command(name = "sample", version, after_help = AFTER_HELP)]
struct Cli {
    /// A glTF file (.gltf or .glb) to render instead of a built-in scene.
    #[arg(conflicts_with = "builtin")]
    scene: Option<PathBuf>,
    /// The built-in scene: the cornell room, a forest of 2,500 instances (alpha-tested ferns
    /// among them) on a 1M-triangle terrain, or a skinned figure waving.
    #[arg(long = "scene", value_enum, default_value_t = Builtin::Room)]
    builtin: Builtin,
    /// Render without a window (the default when no display is set), write the last frame's
    /// modes to --out.
    #[arg(long, conflicts_with = "window")]
    headless: bool,
    /// Open a window (the default when a display is set).
    #[arg(long)]
    window: bool,
    #[arg(long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(8..=16384))]
    width: u32,
    #[arg(long, default_value_t = 360, value_parser = clap::value_parser!(u32).range(8..=16384))]
    height: u32,
    /// Frames along the scene's camera path (headless: at least 2; a window: run until closed
    /// when not given).
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=100_000))]
    frames: Option<u32>,
    /// Comma-separated modes to write (see below), or "all".
    #[arg(long, default_value = "all")]
    modes: String,
    /// Directory for the EXR and PNG files.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Rays per pixel of every trace.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    rays: u32,
    /// Trace half the pixels each frame (checkerboard).
    #[arg(long)]
    checkerboard: bool,
    /// The rays' random numbers: the default sequences, or white or blue noise to compare
    /// image quality.
    #[arg(long, value_enum, default_value_t = RandomNumbersArg::Default)]
    random_numbers: RandomNumbersArg,
    /// BLAS builds per frame (the SDK's max_blas_build_count; 0: no limit).
    #[arg(long, default_value_t = 4)]
    blas_per_frame: u32,
    /// Size of the lidar view that fills the cache around the camera (pixels).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(8..=4096))]
    lidar_size: u32,
    /// Shadow rays per pixel and light of the lidar view (its lit image feeds the cache).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=64))]
    lidar_rays: u32,
    /// Frames in a row the TLAS may be refit instead of rebuilt while only instance
    /// transforms change (BvhBuildTask::tlas_max_refits); 0 rebuilds it every frame.
    #[arg(long, default_value_t = 15)]
    tlas_max_refits: u32,
    /// Exposure of the tone-mapped PNGs (the EXRs are linear). Default: automatic in headless
    /// runs (the last frame's log-average luminance to mid-grey), 1 in a window.
    #[arg(long)]
    exposure: Option<f32>,
    /// Inject one pixel of every NxN block of the main view per frame
    /// (DirectLightingInjectionTask::injection_resolution_stride). 0: the view's height over
    /// 540 (2 at 1080p).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=16))]
    injection_stride: u32,
    /// Show surfaces the cache has not lit in magenta instead of black.
    #[arg(long)]
    magenta_unlit: bool,
    /// Cache samples relit from the scene's lights per frame (RelightCacheTask); 0 turns
    /// relighting off, leaving what no camera saw unlit.
    #[arg(long, default_value_t = 65_536, value_parser = clap::value_parser!(u32).range(0..=16_777_216))]
    relight_samples: u32,
    /// Extra blur taps where diffuse GI's history is fresh, in the reflections + GI denoiser
    /// (DenoiserSettings::fresh_history_taps): a moving view's GI less blotchy, at a cost.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=32))]
    fresh_history_taps: u32,
    /// Hit-light the mirror's reflections from the scene's lights instead of shading them from
    /// the cache (TraceSpecularTask::hit_lighting).
    #[arg(long)]
    hit_lighting: bool,
    /// Hold the direct-lighting caches under this many MiB (InitSettings::cache_budget_bytes):
    /// the caches of instances unused longest are evicted and the report counts them. 0: none.
    #[arg(long, default_value_t = 0)]
    cache_budget_mib: u64,
    /// Time each pass of the denoisers (InitSettings::time_passes): the report lists them
    /// under their tasks.
    #[arg(long)]
    time_passes: bool,
    /// Look through the file's camera N (glTF perspective cameras, in node order) instead of
    /// the fitted camera path.
    #[arg(long)]
    camera: Option<usize>,
    /// Scatter N small lights (2,048 without a number) through the scene, shaded by the SDK's
    /// resampled direct lighting (TraceManyLightsTask) and denoised; 64 of them circle.
    #[arg(long, num_args = 0..=1, default_missing_value = "2048", value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    many_lights: Option<u32>,
    /// Write the GPU times and memory as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

fn main() {
    if let Err(e) = run() {
        eprintln!("sample failed: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let cli = Cli::parse();
    if let Some(e) = cli.exposure.filter(|e| !(e.is_finite() && *e > 0.0)) {
        return Err(format!("--exposure {e}: a positive number"));
    }
    let settings = Settings {
        width: cli.width,
        height: cli.height,
        lidar_size: cli.lidar_size,
        lidar_rays: cli.lidar_rays,
        tlas_max_refits: cli.tlas_max_refits,
        unlit_color: if cli.magenta_unlit { [1.0, 0.0, 1.0] } else { [0.0; 3] },
        relight_samples: cli.relight_samples,
        injection_stride: cli.injection_stride,
        hit_lighting: cli.hit_lighting,
        cache_budget_bytes: cli.cache_budget_mib.saturating_mul(1 << 20),
        time_passes: cli.time_passes,
        many_lights: cli.many_lights.unwrap_or(0),
        fresh_history_taps: cli.fresh_history_taps,
        max_blas_build_count: cli.blas_per_frame,
        rays_per_pixel: cli.rays,
        checkerboard: cli.checkerboard,
        random_numbers: match cli.random_numbers {
            RandomNumbersArg::Default => hybrid_rt::RandomNumbers::Default,
            RandomNumbersArg::WhiteNoise => hybrid_rt::RandomNumbers::WhiteNoise,
            RandomNumbersArg::BlueNoise => hybrid_rt::RandomNumbers::BlueNoise,
        },
        exposure: cli.exposure.unwrap_or(1.0),
        ..Default::default()
    };
    let chosen: Vec<Mode> = match cli.modes.as_str() {
        "all" => modes::ALL.to_vec(),
        list => list
            .split(',')
            .map(|n| Mode::parse(n.trim()).ok_or(format!("unknown mode {n:?} (see --help)")))
            .collect::<Result<_, _>>()?,
    };
    let mut scene = match &cli.scene {
        Some(path) => gltf_scene::load(path)?,
        None => match cli.builtin {
            Builtin::Room => scenes::cornell_room(),
            Builtin::Forest => scenes::forest(),
            Builtin::Figure => hybrid_rt_samples::figure::waving_figure(),
        },
    };
    if let Some(k) = cli.camera {
        let n = scene.file_cameras.len();
        scene.camera_path = *scene.file_cameras.get(k).ok_or(format!("--camera {k}: {} has {n} camera(s)", scene.name))?;
    }
    let out = cli.out;
    let windowed = !cli.headless && (cli.window || std::env::var_os("DISPLAY").is_some());
    if windowed {
        return window::run(scene, settings, cli.frames.map(u64::from), out);
    }
    let frames = cli.frames.unwrap_or(16);

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
    let mut progress = Progress::new("rendering", frames as u64);
    for f in 0..frames {
        let u = f as f32 / (frames - 1) as f32;
        let camera = r.scene.camera_path.at(u);
        // Animation at 30 frames per second of scene time, whatever the real frame rate.
        let last = f + 1 == frames;
        r.many_lights_debug = last && chosen.contains(&Mode::ManyLightsDebug);
        r.render(camera, f as f32 / 30.0, if last { &debug } else { &[] }, None)?;
        progress.set(f as u64 + 1);
    }
    progress.finish();
    r.finish()?;
    if cli.exposure.is_none() {
        println!("exposure: {:.3} (automatic; --exposure sets it)", r.auto_expose()?);
    }
    let mut written = Vec::new();
    for mode in &chosen {
        let (linear, display) = r.capture(*mode)?;
        images::write_capture(&out, mode.name(), settings.width, settings.height, &linear, &display)?;
        written.push(mode.name());
    }
    let report = report::Report::new(&r);
    print!("{}", report.text());
    if let Some(path) = &cli.json {
        std::fs::write(path, report.json()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    println!("wrote {} modes as EXR + PNG to {}: {}", written.len(), out.display(), written.join(", "));
    if written.contains(&"composite") {
        println!("the frame: {}", out.join("composite.png").display());
    }
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
