//! hybrid-rt bench: GPU times from timestamp queries for the SDK's work on a synthetic scene.
//!
//! Prints a table and writes JSON (target/bench.json unless `--json` says otherwise):
//! - BLAS build throughput (triangles/s): one big mesh, and many small meshes in one frame
//! - TLAS build time for all instances
//! - `build_gpu_task` CPU time (recording only; no submission or wait is inside)
//! - AO GPU time per rays-per-pixel setting, beside the bare-ray floor: the same raygen
//!   tracing the same rays through empty hit/miss shaders. The ratio is our overhead.
//!
//! One function per measured section, in the order they run: `builds` (context creation, the
//! BLAS and TLAS rows), `traces` (AO, injection, shadows, GI, reflections), `denoisers` (the
//! denoisers and the memory rows); `timing` holds the medians they are made of.
use clap::Parser;
use hybrid_rt::{ExecuteContext, InitSettings, TaskContainer};
use hybrid_rt_host::scene::{Camera, Scene};
use hybrid_rt_host::Host;
use hybrid_rt_testkit::sdk_scene::{GBufferImages, SceneOnGpu};
use serde_json::json;
use std::time::Duration;

mod blas_floor;
mod builds;
mod denoisers;
mod many_lights;
mod timing;
mod traces;

/// GPU times of the SDK's tasks on a synthetic field (spheres on a ground plane), from its
/// timestamp queries: BLAS/TLAS builds, recording, every trace beside its bare-ray floor, the
/// denoisers, memory. Prints a table and writes JSON.
#[derive(Parser, Debug)]
#[command(name = "bench", version)]
struct Cli {
    /// Triangles of the field, spread over the instances.
    #[arg(long, default_value_t = 1 << 20, value_parser = clap::value_parser!(u64).range(12..=(1 << 28)))]
    triangles: u64,
    /// Instances of the field (each its own geometry).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u64).range(1..=(1 << 20)))]
    instances: u64,
    /// Triangles of the one big mesh whose BLAS build is timed alone.
    #[arg(long, default_value_t = 1 << 20, value_parser = clap::value_parser!(u64).range(12..=(1 << 28)))]
    big_mesh_triangles: u64,
    #[arg(long, default_value_t = 1920, value_parser = clap::value_parser!(u32).range(8..=16384))]
    width: u32,
    #[arg(long, default_value_t = 1080, value_parser = clap::value_parser!(u32).range(8..=16384))]
    height: u32,
    /// Rays per pixel of the AO rows, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,4", value_parser = clap::value_parser!(u32).range(1..=64))]
    rays: Vec<u32>,
    /// Frames per measurement (medians).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..=10_000))]
    frames: u64,
    /// Keep the GPU busy this long before the AO rows (clocks settle).
    #[arg(long, default_value_t = 1000)]
    warmup_ms: u64,
    /// Cache tile edge length (world units) for the injection rows.
    #[arg(long, default_value_t = 1.0)]
    tile_unit_length: f32,
    /// Bytes per vertex of the field's vertex buffers (positions first): the SDK's copy is
    /// compact either way.
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u64).range(12..=256))]
    vertex_stride: u64,
    /// Spatial passes of the denoise rows (default: DenoiserSettings's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=6))]
    denoise_passes: Option<u32>,
    /// Anti-lag in the denoise rows (1 on, 0 off; default: DenoiserSettings's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1))]
    anti_lag: Option<u32>,
    /// Where the JSON goes (its folder is made when missing).
    #[arg(long, default_value = "target/bench.json")]
    json: String,
}

/// What the sections measure, from the command line.
struct Settings {
    triangles: usize,
    instances: usize,
    big_mesh_triangles: usize,
    width: u32,
    height: u32,
    rays: Vec<u32>,
    frames: usize,
    warmup: Duration,
    tile_unit_length: f32,
    /// The engine's vertex layout (positions interleaved in vertices of this many bytes): the
    /// SDK's copy is compact either way, so trace times must not change with it.
    vertex_stride: u64,
    /// Denoiser settings of the denoise rows (what each pass costs: rerun with fewer spatial
    /// passes or without the anti-lag test). Defaults: DenoiserSettings's.
    denoise_passes: u32,
    anti_lag: bool,
}

impl Settings {
    fn new(cli: &Cli) -> Result<Settings, String> {
        if !(cli.tile_unit_length.is_finite() && cli.tile_unit_length > 0.0) {
            return Err(format!("--tile-unit-length {}: a positive number", cli.tile_unit_length));
        }
        let defaults = hybrid_rt::DenoiserSettings::default();
        Ok(Settings {
            triangles: cli.triangles as usize,
            instances: cli.instances as usize,
            big_mesh_triangles: cli.big_mesh_triangles as usize,
            width: cli.width,
            height: cli.height,
            rays: cli.rays.clone(),
            frames: cli.frames as usize,
            warmup: Duration::from_millis(cli.warmup_ms),
            tile_unit_length: cli.tile_unit_length,
            vertex_stride: cli.vertex_stride,
            denoise_passes: cli.denoise_passes.unwrap_or(defaults.spatial_passes),
            anti_lag: cli.anti_lag.map_or(defaults.anti_lag, |v| v != 0),
        })
    }
}

/// The table's rows in the order measured, and the JSON report, key by key (serde_json:
/// escaped, and valid whatever a row prints).
#[derive(Default)]
struct Report {
    rows: Vec<(String, String)>,
    json: serde_json::Map<String, serde_json::Value>,
}

impl Report {
    fn row(&mut self, name: impl Into<String>, value: impl Into<String>) {
        self.rows.push((name.into(), value.into()));
    }

    fn key(&mut self, key: &str, value: serde_json::Value) {
        self.json.insert(key.into(), value);
    }

    /// Prints the table and writes the JSON to `path`.
    fn print_and_write(self, path: &str) -> Result<(), String> {
        let wide = self.rows.iter().map(|r| r.0.len()).max().unwrap_or(0);
        println!("\n{:wide$}  result", "measurement");
        println!("{}", "-".repeat(wide + 50));
        for (k, v) in &self.rows {
            println!("{k:wide$}  {v}");
        }
        let text = serde_json::to_string_pretty(&serde_json::Value::Object(self.json)).map_err(|err| err.to_string())? + "\n";
        if let Some(dir) = std::path::Path::new(path).parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|err| format!("{}: {err}", dir.display()))?;
        }
        std::fs::write(path, text).map_err(|err| format!("{path}: {err}"))?;
        println!("\nwrote {path}");
        Ok(())
    }
}

/// What every section measures with: the engine's device, the SDK context, the container
/// each measured frame is scheduled into, the settings, and the report the rows go to.
struct Bench<'a> {
    host: &'a Host,
    ctx: &'a ExecuteContext,
    frame: TaskContainer,
    settings: Settings,
    report: Report,
}

/// The field the trace rows measure on: the scene, its camera, its G-buffer (rendered on the
/// CPU) and the scene as registered with the SDK.
struct Field {
    scene: Scene,
    camera: Camera,
    gbuffer: GBufferImages,
    gpu: SceneOnGpu,
}

fn sdk(e: hybrid_rt::Error) -> String {
    e.to_string()
}

fn main() {
    if let Err(e) = run() {
        eprintln!("bench failed: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let cli = Cli::parse();
    let settings = Settings::new(&cli)?;
    let host = Host::new()?;
    let creation = builds::context_creation(&host)?;
    // Passes timed: the denoise rows print each pass (the stamps sit between passes that a
    // barrier orders anyway).
    let ctx = host
        .create_context(&InitSettings { upload_ring_bytes: 4 << 20, time_passes: true, ..Default::default() })
        .map_err(sdk)?;
    println!(
        "device: {}{}",
        host.device_name,
        if host.validation_enabled { " (validation layer ON: timings are not representative)" } else { "" }
    );
    let mut bench = Bench { host: &host, ctx: &ctx, frame: ctx.create_task_container(), settings, report: Report::default() };
    bench.report.key("device", json!(host.device_name));
    bench.context_creation_rows(&creation);
    let floor = bench.big_mesh_blas()?;
    let (field, first_frame_ms) = bench.field(floor)?;
    bench.field_blas(&field, first_frame_ms)?;
    bench.tlas(&field)?;
    bench.ambient_occlusion(&field)?;
    bench.injection(&field)?;
    let traces = bench.traces(&field)?;
    bench.many_lights(&field, traces.multi_32_ms)?;
    bench.denoisers(&field, traces)?;
    bench.memory();

    let Bench { report, frame, .. } = bench;
    report.print_and_write(&cli.json)?;
    field.gbuffer.destroy(&host);
    field.gpu.destroy(&host);
    drop(frame);
    drop(ctx);
    if Host::validation_errors() > 0 {
        return Err(format!("{} validation errors", Host::validation_errors()));
    }
    Ok(())
}
