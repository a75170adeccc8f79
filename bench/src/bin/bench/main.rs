//! hybrid-rt bench: GPU times from timestamp queries for the SDK's work on a synthetic scene.
//!
//! Prints a table and writes JSON:
//! - BLAS build throughput (triangles/s): one big mesh, and many small meshes in one frame
//! - TLAS build time for all instances
//! - `build_gpu_task` CPU time (recording only; no submission or wait is inside)
//! - AO GPU time per rays-per-pixel setting, beside the bare-ray floor: the same raygen
//!   tracing the same rays through empty hit/miss shaders. The ratio is our overhead.
use clap::Parser;
use hybrid_rt::{
    BuildHint, BvhBuildTask, ExecuteContext, GeometryInput, GeometryTask, IndexBufferInput, InitSettings, InstanceInput,
    InstanceOperation, InstanceTask, SurfelSettings, SurfelType, TaskKind, TaskOperation, VertexBufferInput,
};
use hybrid_rt_host::Host;
use hybrid_rt_samples::scenes;
use hybrid_rt_testkit::reference::{GBuffer, Mesh, Tracer};
use hybrid_rt_testkit::sdk_scene::{run_frame, GBufferImages, SceneOnGpu};
use serde_json::json;
use std::time::Instant;

mod blas_floor;

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
    /// À-trous iterations of the denoise rows (default: DenoiserSettings's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=6))]
    denoise_passes: Option<u32>,
    /// Anti-lag in the denoise rows (1 on, 0 off; default: DenoiserSettings's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=1))]
    anti_lag: Option<u32>,
    /// Where the JSON goes.
    #[arg(long, default_value = "bench.json")]
    json: String,
}

fn main() {
    if let Err(e) = run() {
        eprintln!("bench failed: {e}");
        std::process::exit(1);
    }
}

/// Median GPU time of `kind` over `frames` frames (after 3 warm-up frames), each frame
/// scheduled by `schedule`.
fn time_frames(
    host: &Host,
    ctx: &ExecuteContext,
    frame: &mut hybrid_rt::TaskContainer,
    frames: usize,
    kind: TaskKind,
    mut schedule: impl FnMut(&mut hybrid_rt::TaskContainer) -> Result<(), String>,
) -> Result<f64, String> {
    let mut times = Vec::new();
    for i in 0..frames + 3 {
        schedule(frame)?;
        let ms = run_frame(host, ctx, frame)?.gpu_ms(kind);
        if i >= 3 {
            times.push(ms);
        }
    }
    Ok(median(times))
}

/// Median GPU times of `kind` with the real shaders and with the bare-ray floor (empty hit and
/// miss shaders), alternating frame by frame after 4 warm-up frames.
fn time_vs_floor(
    host: &Host,
    ctx: &ExecuteContext,
    frame: &mut hybrid_rt::TaskContainer,
    frames: usize,
    kind: TaskKind,
    mut schedule: impl FnMut(&mut hybrid_rt::TaskContainer) -> Result<(), String>,
) -> Result<(f64, f64), String> {
    let mut times = [Vec::new(), Vec::new()];
    for i in 0..2 * frames + 4 {
        let floor = i % 2 == 1;
        ctx.set_bench_floor_mode(floor).map_err(|e| e.to_string())?;
        schedule(frame)?;
        let ms = run_frame(host, ctx, frame)?.gpu_ms(kind);
        if i >= 4 {
            times[floor as usize].push(ms);
        }
    }
    ctx.set_bench_floor_mode(false).map_err(|e| e.to_string())?;
    let [t, f] = times;
    Ok((median(t), median(f)))
}

/// Median GPU times of two task kinds recorded in the same frames (a trace and its denoiser).
fn time_pair(
    host: &Host,
    ctx: &ExecuteContext,
    frame: &mut hybrid_rt::TaskContainer,
    frames: usize,
    kinds: [TaskKind; 2],
    mut schedule: impl FnMut(&mut hybrid_rt::TaskContainer) -> Result<(), String>,
) -> Result<[f64; 2], String> {
    let mut times = [Vec::new(), Vec::new()];
    for i in 0..frames + 3 {
        schedule(frame)?;
        let done = run_frame(host, ctx, frame)?;
        if i >= 3 {
            for k in 0..2 {
                times[k].push(done.gpu_ms(kinds[k]));
            }
        }
    }
    let [a, b] = times;
    Ok([median(a), median(b)])
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

/// Milliseconds to create a context with an empty pipeline cache and with the data that left
/// in it, and the cache's size.
fn context_creation(host: &Host) -> Result<(f64, f64, usize), String> {
    let d = &host.device;
    let e = |e: ash::vk::Result| format!("pipeline cache: {e:?}");
    let empty = unsafe { d.create_pipeline_cache(&ash::vk::PipelineCacheCreateInfo::default(), None) }.map_err(e)?;
    let t = std::time::Instant::now();
    drop(host.create_context(&InitSettings { pipeline_cache: empty, ..Default::default() }).map_err(|e| e.to_string())?);
    let cold = t.elapsed().as_secs_f64() * 1e3;
    let data = unsafe { d.get_pipeline_cache_data(empty) }.map_err(e)?;
    let warm_cache =
        unsafe { d.create_pipeline_cache(&ash::vk::PipelineCacheCreateInfo::default().initial_data(&data), None) }.map_err(e)?;
    let t = std::time::Instant::now();
    drop(host.create_context(&InitSettings { pipeline_cache: warm_cache, ..Default::default() }).map_err(|e| e.to_string())?);
    let warm = t.elapsed().as_secs_f64() * 1e3;
    unsafe {
        d.destroy_pipeline_cache(empty, None);
        d.destroy_pipeline_cache(warm_cache, None);
    }
    Ok((cold, warm, data.len()))
}

fn run() -> Result<(), String> {
    let cli = Cli::parse();
    if !(cli.tile_unit_length.is_finite() && cli.tile_unit_length > 0.0) {
        return Err(format!("--tile-unit-length {}: a positive number", cli.tile_unit_length));
    }
    let (triangles, instances, big) = (cli.triangles as usize, cli.instances as usize, cli.big_mesh_triangles as usize);
    let (width, height) = (cli.width, cli.height);
    let rays_list = cli.rays.clone();
    let frames = cli.frames as usize;
    let json_path = cli.json.clone();
    let warmup_ms = cli.warmup_ms;
    let tile_unit = cli.tile_unit_length;
    // The engine's vertex layout (positions interleaved in vertices of this many bytes): the
    // SDK's copy is compact either way, so trace times must not change with it.
    let vertex_stride = cli.vertex_stride;
    // Denoiser settings of the denoise rows (what each pass costs: rerun with fewer à-trous
    // iterations or without the anti-lag test). Defaults: DenoiserSettings's.
    let defaults = hybrid_rt::DenoiserSettings::default();
    let denoise_passes = cli.denoise_passes.unwrap_or(defaults.spatial_passes);
    let anti_lag = cli.anti_lag.map_or(defaults.anti_lag, |v| v != 0);
    let e = |e: hybrid_rt::Error| e.to_string();

    let host = Host::new()?;
    // ---- 0. Context creation, cold (an empty pipeline cache) and warm (the cache saved by the
    // cold one, as an engine reloads it on its next run).
    let (cold_ms, warm_ms, cache_bytes) = context_creation(&host)?;
    let ctx = host.create_context(&InitSettings { upload_ring_bytes: 4 << 20, ..Default::default() }).map_err(e)?;
    println!(
        "device: {}{}",
        host.device_name,
        if host.validation_enabled { " (validation layer ON: timings are not representative)" } else { "" }
    );
    // The JSON report, key by key (serde_json: escaped, and valid whatever a row prints).
    let mut json = serde_json::Map::new();
    json.insert("device".into(), json!(host.device_name));
    let mut rows: Vec<(String, String)> = Vec::new();
    rows.push((
        "Context creation (every pipeline), cold / warm pipeline cache".into(),
        format!("{cold_ms:.1} ms / {warm_ms:.1} ms ({} KiB of cache)", cache_bytes / 1024),
    ));
    json.insert("context_creation_cold_ms".into(), json!(cold_ms));
    json.insert("context_creation_warm_ms".into(), json!(warm_ms));
    rows.push(("Engine vertex layout".into(), format!("positions in {vertex_stride}-byte vertices")));
    json.insert("vertex_stride".into(), json!(vertex_stride));

    // ---- 1. One big mesh: BLAS build throughput.
    let n = ((big as f64 / 2.0).sqrt().ceil() as u32).max(1);
    let mesh = Mesh::grid(100.0, n);
    let usage = ash::vk::BufferUsageFlags::TRANSFER_SRC;
    // In device memory, as an engine keeps a static mesh (on the H200 the registration frame
    // measured the same from host-visible memory: 8.75 ms).
    let vb = host.device_buffer_with_data(bytemuck::cast_slice(&mesh.positions), usage)?;
    let ib = host.device_buffer_with_data(bytemuck::cast_slice(&mesh.indices), usage)?;
    let mut frame = ctx.create_task_container();
    // The driver alone on the same triangles (see blas_floor), interleaved with the SDK's
    // registration frames below: how much of each row is the SDK's.
    let mut floor = blas_floor::BlasFloor::new(&host, &mesh.positions, &mesh.indices)?;
    // The registration frame with each surfel layout (both sized on the GPU), and with the
    // fast-build hints (what a level streaming in would ask for).
    for (surfel_type, build_hint, what, key) in [
        (SurfelType::MeshColors, BuildHint::Auto, "mesh-colors layout sized on the GPU", "blas_big_mesh"),
        (SurfelType::Tiles, BuildHint::Auto, "tiles layout sized on the GPU", "blas_big_mesh_tiles"),
        (SurfelType::Tiles, BuildHint::PreferFastBuild, "tiles, PreferFastBuild", "blas_big_mesh_tiles_fast_build"),
        (SurfelType::Tiles, BuildHint::FastThenTrace, "tiles, FastThenTrace's first build", "blas_big_mesh_fast_then_trace"),
    ] {
        let geo = ctx.create_geometry_handles(1)[0];
        let input = GeometryInput {
            vertices: VertexBufferInput { buffer: vb.buffer, count: mesh.positions.len() as u32, ..Default::default() },
            indices: IndexBufferInput { buffer: ib.buffer, count: mesh.indices.len() as u32, ..Default::default() },
            surfels: SurfelSettings { surfel_type, ..Default::default() },
            build_hint,
            ..Default::default()
        };
        // Warm-up first (clocks ramp up over hundreds of milliseconds of load), then the
        // median of the last 4 of 6 builds, each beside a floor build with the same flags.
        // The flags the SDK builds this hint's first BLAS of static geometry with.
        let flags = build_hint.build_flags(false, true);
        let warm_until = Instant::now() + std::time::Duration::from_millis(warmup_ms);
        while Instant::now() < warm_until {
            floor.build(&host, flags)?;
        }
        let (mut big_ms, mut bvh_ms, mut compact_ms, mut floor_ms) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..6 {
            let operation = if i == 0 { TaskOperation::Register } else { TaskOperation::Update };
            frame.schedule_geometry(&GeometryTask { handle: geo, operation, input: input.clone() }).map_err(e)?;
            frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 1 }).map_err(e)?;
            let done = run_frame(&host, &ctx, &mut frame)?;
            // The compaction of a fast-trace build happens in the next build's frame (its size
            // is read when this ticket is back): give it a frame of its own, so the measured
            // frame is the registration's alone, as an engine's first frame with the mesh.
            frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 0 }).map_err(e)?;
            let compaction = run_frame(&host, &ctx, &mut frame)?;
            let floor_build = floor.build(&host, flags)?;
            if i >= 2 {
                floor_ms.push(floor_build);
                big_ms.push(done.gpu_ms(TaskKind::BlasBuild));
                bvh_ms.push(done.gpu_ms(TaskKind::Bvh));
                compact_ms.push(compaction.gpu_ms(TaskKind::BlasBuild));
            }
        }
        let (big_ms, bvh_ms, compact_ms, floor_ms) = (median(big_ms), median(bvh_ms), median(compact_ms), median(floor_ms));
        let big_rate = mesh.triangle_count() as f64 / (big_ms * 1e-3);
        rows.push((
            format!("BLAS build, 1 mesh of {} triangles ({what})", mesh.triangle_count()),
            format!(
                "{big_ms:.3} ms ({:.1} M tri/s); floor {floor_ms:.3} ms ({:.1} M tri/s); the frame's BVH work {bvh_ms:.3} ms; compaction, next frame {compact_ms:.3} ms",
                big_rate / 1e6,
                mesh.triangle_count() as f64 / (floor_ms * 1e-3) / 1e6
            ),
        ));
        json.insert(
            key.into(),
            json!({"triangles": mesh.triangle_count(), "gpu_ms": big_ms, "floor_gpu_ms": floor_ms, "bvh_ms": bvh_ms, "compaction_ms": compact_ms, "triangles_per_s": big_rate}),
        );
        ctx.destroy_geometry_handles(&[geo]).map_err(e)?;
    }
    host.destroy_buffer(vb);
    host.destroy_buffer(ib);

    // ---- 2. The field: many BLASes in one frame, then the TLAS alone.
    let t0 = Instant::now();
    let (scene, camera) = scenes::field(triangles, instances);
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, width, height);
    println!(
        "scene: {} triangles in {} instances (G-buffer on the CPU in {:.1} s)",
        scene.triangle_count(),
        scene.instances.len(),
        t0.elapsed().as_secs_f64()
    );
    let gbuffer = GBufferImages::upload(&host, &g)?;
    let surfels = hybrid_rt::SurfelSettings { tile_unit_length: tile_unit, ..Default::default() };
    let colours = vec![[0.0; 3]; scene.instances.len()];
    let gpu_scene = SceneOnGpu::register_interleaved(&host, &ctx, &mut frame, &scene, surfels, &colours, vertex_stride)?;
    frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: u32::MAX }).map_err(e)?;
    // Warm clocks for this frame too (the floor's builds keep the GPU busy until it starts).
    let warm_until = Instant::now() + std::time::Duration::from_millis(warmup_ms);
    while Instant::now() < warm_until {
        floor.build(&host, BuildHint::Auto.build_flags(false, true))?;
    }
    floor.destroy(&host);
    let first_ms = run_frame(&host, &ctx, &mut frame)?.gpu_ms(TaskKind::Bvh);
    // Steady state: rebuild every BLAS again (static geometry: an update queues a rebuild).
    // The first frame also pays for first use of freshly allocated memory.
    let mut rebuild = Vec::new();
    let mut rebuild_blas = Vec::new();
    for _ in 0..3 {
        for (mesh, &handle) in scene.meshes.iter().zip(&gpu_scene.geometries) {
            let (vb, ib) = &gpu_scene.buffers[gpu_scene.geometries.iter().position(|h| *h == handle).unwrap()];
            // The same engine layout as the registration (an update re-reads the engine's buffer).
            let stride = vertex_stride.max(12).next_multiple_of(4);
            let input = GeometryInput {
                vertices: VertexBufferInput {
                    buffer: vb.buffer,
                    count: mesh.positions.len() as u32,
                    stride,
                    ..Default::default()
                },
                indices: IndexBufferInput { buffer: ib.buffer, count: mesh.indices.len() as u32, ..Default::default() },
                ..Default::default()
            };
            frame.schedule_geometry(&GeometryTask { handle, operation: TaskOperation::Update, input }).map_err(e)?;
        }
        frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: u32::MAX }).map_err(e)?;
        let done = run_frame(&host, &ctx, &mut frame)?;
        rebuild.push(done.gpu_ms(TaskKind::Bvh));
        rebuild_blas.push(done.gpu_ms(TaskKind::BlasBuild));
    }
    let field_ms = median(rebuild);
    let field_blas_ms = median(rebuild_blas);
    let field_rate = scene.triangle_count() as f64 / (field_ms * 1e-3);
    rows.push((
        format!("BLAS builds, {} meshes, {} triangles, one frame", scene.instances.len(), scene.triangle_count()),
        format!(
            "{field_ms:.3} ms ({:.1} M tri/s); BLAS builds alone {field_blas_ms:.3} ms; first frame {first_ms:.3} ms",
            field_rate / 1e6
        ),
    ));
    json.insert(
        "blas_field".into(),
        json!({
            "meshes": scene.instances.len(),
            "triangles": scene.triangle_count(),
            "gpu_ms": field_ms,
            "first_frame_gpu_ms": first_ms,
            "blas_builds_gpu_ms": field_blas_ms,
            "triangles_per_s": field_rate,
        }),
    );

    // TLAS rebuild: move one instance back and forth, no BLAS work.
    let mut tlas_ms = Vec::new();
    let mut record_us = Vec::new();
    for i in 0..frames {
        let inst = &scene.instances[1];
        let nudge = glam::Affine3A::from_translation(glam::Vec3::new(0.0, (i % 2) as f32 * 1e-3, 0.0));
        frame
            .schedule_instance(&InstanceTask {
                handle: gpu_scene.instances[1],
                operation: InstanceOperation::Update,
                input: InstanceInput {
                    geometry: gpu_scene.geometries[inst.mesh],
                    transform: nudge * inst.transform,
                    ..Default::default()
                },
            })
            .map_err(e)?;
        frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 0 }).map_err(e)?;
        let cmd = host.allocate_command_buffer()?;
        host.begin(cmd)?;
        let t = Instant::now();
        let ticket = ctx.build_gpu_task(&mut frame, cmd).map_err(e)?;
        record_us.push(t.elapsed().as_secs_f64() * 1e6);
        let fence = host.submit(cmd)?;
        host.wait(fence)?;
        tlas_ms.push(ctx.mark_gpu_task_completed(ticket).map_err(e)?.gpu_ms(TaskKind::Bvh));
    }
    let tlas_ms = median(tlas_ms);
    let tlas_record_us = median(record_us);
    rows.push((format!("TLAS build, {} instances", scene.instances.len()), format!("{tlas_ms:.3} ms")));
    rows.push(("build_gpu_task CPU, instance update + TLAS".into(), format!("{tlas_record_us:.1} us")));
    json.insert(
        "tlas".into(),
        json!({"instances": scene.instances.len(), "gpu_ms": tlas_ms, "build_gpu_task_cpu_us": tlas_record_us}),
    );

    // ---- 3. AO beside the bare-ray floor.
    let mut ao_json = Vec::new();
    for &rays in &rays_list {
        let mut times = [Vec::new(), Vec::new()];
        let mut record = Vec::new();
        // Warm-up first: GPU clocks ramp up over hundreds of milliseconds of load, and single
        // short frames with waits between them measured up to 2.8x slower on the H100. Then
        // ours and the floor alternate frame by frame so any drift hits both alike.
        let warm_until = Instant::now() + std::time::Duration::from_millis(warmup_ms);
        while Instant::now() < warm_until {
            frame.schedule_ambient_occlusion(&gbuffer.ao_task(&camera, 1.0, rays)).map_err(e)?;
            run_frame(&host, &ctx, &mut frame)?;
        }
        for i in 0..(2 * frames + 8) {
            let floor = i % 2 == 1;
            ctx.set_bench_floor_mode(floor).map_err(e)?;
            frame.schedule_ambient_occlusion(&gbuffer.ao_task(&camera, 1.0, rays)).map_err(e)?;
            let cmd = host.allocate_command_buffer()?;
            host.begin(cmd)?;
            let t = Instant::now();
            let ticket = ctx.build_gpu_task(&mut frame, cmd).map_err(e)?;
            let cpu_us = t.elapsed().as_secs_f64() * 1e6;
            let fence = host.submit(cmd)?;
            host.wait(fence)?;
            let ms = ctx.mark_gpu_task_completed(ticket).map_err(e)?.gpu_ms(TaskKind::AmbientOcclusion);
            if i >= 8 {
                times[floor as usize].push(ms);
                if !floor {
                    record.push(cpu_us);
                }
            }
        }
        ctx.set_bench_floor_mode(false).map_err(e)?;
        let (ao, fl) = (median(times[0].clone()), median(times[1].clone()));
        let rays_total = width as f64 * height as f64 * rays as f64;
        rows.push((
            format!("AO {width}x{height}, {rays} ray(s)/pixel"),
            format!("{ao:.3} ms ({:.0} M rays/s); floor {fl:.3} ms; ratio {:.2}", rays_total / (ao * 1e-3) / 1e6, ao / fl),
        ));
        ao_json.push(json!({
            "width": width,
            "height": height,
            "rays_per_pixel": rays,
            "gpu_ms": ao,
            "floor_gpu_ms": fl,
            "ratio_to_floor": ao / fl,
            "rays_per_s": rays_total / (ao * 1e-3),
            "build_gpu_task_cpu_us": median(record),
        }));
    }
    json.insert("ao".into(), json!(ao_json));

    // ---- 4. Direct-lighting injection of a full-resolution lit frame, with its resolve.
    let lit_texels = vec![[0.5f32, 0.4, 0.3, 1.0]; (width * height) as usize];
    let lit = host.image_with_data(
        ash::vk::Format::R32G32B32A32_SFLOAT,
        width,
        height,
        ash::vk::ImageUsageFlags::SAMPLED,
        bytemuck::cast_slice(&lit_texels),
        hybrid_rt_testkit::sdk_scene::READ,
    )?;
    let inject = hybrid_rt::DirectLightingInjectionTask {
        depth: hybrid_rt::DepthInput {
            image: gbuffer.depth.input(hybrid_rt_testkit::sdk_scene::READ),
            depth_type: hybrid_rt::DepthType::ClipSpace,
        },
        lit: lit.input(hybrid_rt_testkit::sdk_scene::READ),
        viewport: hybrid_rt::Viewport::full(width, height),
        camera: camera.sdk_camera(width, height),
        ..Default::default()
    };
    let inject_ms = time_frames(&host, &ctx, &mut frame, frames, TaskKind::DirectLightingInjection, |f| {
        f.schedule_direct_lighting_injection(&inject).map_err(e)
    })?;
    let cache_bytes: Vec<u64> = gpu_scene.instances.iter().map(|h| ctx.instance_cache_bytes(*h).unwrap_or(0)).collect();
    let cache_total: u64 = cache_bytes.iter().sum();
    let cache_mean = cache_total as f64 / cache_bytes.len().max(1) as f64;
    rows.push((format!("Direct-lighting injection {width}x{height} (+ resolve)"), format!("{inject_ms:.3} ms")));
    rows.push((
        format!("Cache per instance (tile_unit_length {tile_unit})"),
        format!(
            "{:.1} KiB mean, {:.1} MiB over {} instances",
            cache_mean / 1024.0,
            cache_total as f64 / 1048576.0,
            cache_bytes.len()
        ),
    ));
    json.insert(
        "injection".into(),
        json!({
            "width": width,
            "height": height,
            "gpu_ms": inject_ms,
            "tile_unit_length": tile_unit,
            "cache_bytes_total": cache_total,
            "cache_bytes_mean_per_instance": cache_mean,
        }),
    );
    host.destroy_image(lit);

    // ---- 5. Shadows, diffuse GI and specular at one ray per pixel.
    let rgba = host.image_cleared(
        ash::vk::Format::R16G16B16A16_SFLOAT,
        width,
        height,
        ash::vk::ImageUsageFlags::STORAGE,
        ash::vk::ImageLayout::GENERAL,
    )?;
    let common = gbuffer.trace_common(&camera);
    let output = rgba.input(ash::vk::ImageLayout::GENERAL);
    let shadow = hybrid_rt::TraceShadowTask {
        common,
        light: hybrid_rt::LightInfo { direction: glam::Vec3::new(0.5, -1.0, 0.3), angular_extent: 0.02, ..Default::default() },
        output,
        rays_per_pixel: 1,
        first_hit: false,
    };
    let (shadow_ms, shadow_floor) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::Shadow, |f| f.schedule_shadow(&shadow).map_err(e))?;
    // First-hit traversal: the same visibility, an occluder's distance instead of the closest.
    let shadow_first = hybrid_rt::TraceShadowTask { first_hit: true, ..shadow };
    let (shadow_first_ms, _) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::Shadow, |f| f.schedule_shadow(&shadow_first).map_err(e))?;
    let diffuse = hybrid_rt::TraceDiffuseTask { common, output, ray_length: 100.0, ..Default::default() };
    let (diffuse_ms, diffuse_floor) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::Diffuse, |f| f.schedule_diffuse(&diffuse).map_err(e))?;
    let mut glossy = common;
    glossy.roughness.global_roughness = 0.3;
    let specular = hybrid_rt::TraceSpecularTask { common: glossy, output, ray_length: 100.0, ..Default::default() };
    let (specular_ms, specular_floor) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::Specular, |f| f.schedule_specular(&specular).map_err(e))?;
    // Mirrors shaded from the cache, and hit-lit from a sun and a point light (a shadow ray
    // each) with one gather ray: what hit lighting costs per mirror pixel.
    let mut mirror_common = common;
    mirror_common.roughness.global_roughness = 0.0;
    let mirror = hybrid_rt::TraceSpecularTask { common: mirror_common, output, ray_length: 100.0, ..Default::default() };
    let (mirror_ms, _) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::Specular, |f| f.schedule_specular(&mirror).map_err(e))?;
    let hit_lit = hybrid_rt::TraceSpecularTask {
        hit_lighting: hybrid_rt::HitLighting {
            lights: vec![
                shadow.light,
                hybrid_rt::LightInfo {
                    light_type: hybrid_rt::LightType::Point,
                    position: glam::Vec3::new(0.0, 4.0, 0.0),
                    radius: 0.3,
                    ..Default::default()
                },
            ],
            max_roughness: 0.0,
            ..Default::default()
        },
        ..mirror.clone()
    };
    let (hit_lit_ms, _) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::Specular, |f| f.schedule_specular(&hit_lit).map_err(e))?;
    rows.push((
        format!("Specular mirrors {width}x{height}: from the cache / hit-lit (2 lights, the cache's residual)"),
        format!("{mirror_ms:.3} ms / {hit_lit_ms:.3} ms"),
    ));
    json.insert("specular_mirror".into(), json!({"cache_gpu_ms": mirror_ms, "hit_lit_gpu_ms": hit_lit_ms}));
    let vis = host.image_cleared(
        ash::vk::Format::R32_UINT,
        width,
        height,
        ash::vk::ImageUsageFlags::STORAGE,
        ash::vk::ImageLayout::GENERAL,
    )?;
    let multi = hybrid_rt::TraceMultiShadowTask {
        common,
        lights: (0..4)
            .map(|k| hybrid_rt::LightInfo {
                light_type: hybrid_rt::LightType::Point,
                position: glam::Vec3::new(-6.0 + 4.0 * k as f32, 4.0, 0.0),
                radius: 0.3,
                ..Default::default()
            })
            .collect(),
        visibility: vis.input(ash::vk::ImageLayout::GENERAL),
        packed: output,
        rays_per_pixel: 1,
        first_hit: false,
        ..Default::default()
    };
    let (multi_ms, multi_floor) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::MultiShadow, |f| f.schedule_multi_shadow(&multi).map_err(e))?;
    let multi_first = hybrid_rt::TraceMultiShadowTask { first_hit: true, ..multi.clone() };
    let (multi_first_ms, _) = time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::MultiShadow, |f| {
        f.schedule_multi_shadow(&multi_first).map_err(e)
    })?;
    // 32 lights (Kickstart RT's limit): an 8 x 4 grid of point lights 4 m apart, each reaching
    // 6 m (rays only where a light reaches), and the same lights unlimited.
    let (vis_low, vis_high) = (
        host.image_cleared(
            ash::vk::Format::R32G32B32A32_UINT,
            width,
            height,
            ash::vk::ImageUsageFlags::STORAGE,
            ash::vk::ImageLayout::GENERAL,
        )?,
        host.image_cleared(
            ash::vk::Format::R32G32B32A32_UINT,
            width,
            height,
            ash::vk::ImageUsageFlags::STORAGE,
            ash::vk::ImageLayout::GENERAL,
        )?,
    );
    let grid: Vec<hybrid_rt::LightInfo> = (0..32)
        .map(|k| hybrid_rt::LightInfo {
            light_type: hybrid_rt::LightType::Point,
            position: glam::Vec3::new(-14.0 + 4.0 * (k % 8) as f32, 4.0, -6.0 + 4.0 * (k / 8) as f32),
            radius: 0.3,
            range: 6.0,
            ..Default::default()
        })
        .collect();
    let multi32 = hybrid_rt::TraceMultiShadowTask {
        lights: grid.clone(),
        visibility: vis_low.input(ash::vk::ImageLayout::GENERAL),
        visibility_high: vis_high.input(ash::vk::ImageLayout::GENERAL),
        ..multi.clone()
    };
    let (multi32_ms, _) =
        time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::MultiShadow, |f| f.schedule_multi_shadow(&multi32).map_err(e))?;
    let unlimited = hybrid_rt::TraceMultiShadowTask {
        lights: grid.iter().map(|l| hybrid_rt::LightInfo { range: 0.0, ..*l }).collect(),
        ..multi32.clone()
    };
    let (multi32_unlimited_ms, _) = time_vs_floor(&host, &ctx, &mut frame, frames, TaskKind::MultiShadow, |f| {
        f.schedule_multi_shadow(&unlimited).map_err(e)
    })?;
    rows.push((
        format!("Multi-light shadows (32 point lights reaching 6 m, 1 ray/pixel each) {width}x{height}"),
        format!("{multi32_ms:.3} ms; unlimited range {multi32_unlimited_ms:.3} ms"),
    ));
    host.destroy_image(vis_low);
    host.destroy_image(vis_high);
    for (name, ms, fl) in [
        ("Multi-light shadows (4 point lights, 1 ray/pixel each)", multi_ms, multi_floor),
        ("Shadow (sun, 1 ray/pixel)", shadow_ms, shadow_floor),
        ("Diffuse GI (1 ray/pixel)", diffuse_ms, diffuse_floor),
        ("Specular (roughness 0.3, 1 ray/pixel)", specular_ms, specular_floor),
    ] {
        rows.push((format!("{name} {width}x{height}"), format!("{ms:.3} ms; floor {fl:.3} ms; ratio {:.2}", ms / fl)));
    }
    for (name, first, closest) in [
        ("Shadow (sun), first-hit mode", shadow_first_ms, shadow_ms),
        ("Multi-light shadows, first-hit mode", multi_first_ms, multi_ms),
    ] {
        rows.push((
            format!("{name} {width}x{height}"),
            format!("{first:.3} ms; closest-hit {closest:.3} ms; speed-up {:.2}x", closest / first),
        ));
    }
    json.insert(
        "traces".into(),
        json!({
            "width": width,
            "height": height,
            "shadow_gpu_ms": shadow_ms,
            "shadow_floor_gpu_ms": shadow_floor,
            "diffuse_gpu_ms": diffuse_ms,
            "diffuse_floor_gpu_ms": diffuse_floor,
            "specular_gpu_ms": specular_ms,
            "specular_floor_gpu_ms": specular_floor,
            "multi_shadow_4_lights_gpu_ms": multi_ms,
            "multi_shadow_floor_gpu_ms": multi_floor,
            "shadow_first_hit_gpu_ms": shadow_first_ms,
            "multi_shadow_first_hit_gpu_ms": multi_first_ms,
            "multi_shadow_32_lights_ranged_gpu_ms": multi32_ms,
            "multi_shadow_32_lights_unlimited_gpu_ms": multi32_unlimited_ms,
        }),
    );
    host.destroy_image(rgba);

    // ---- 6. Denoisers, each beside the 1-ray trace it cleans (same frames).
    let sampled = |format| {
        host.image_cleared(
            format,
            width,
            height,
            ash::vk::ImageUsageFlags::STORAGE | ash::vk::ImageUsageFlags::SAMPLED,
            ash::vk::ImageLayout::GENERAL,
        )
    };
    let f16 = ash::vk::Format::R16G16B16A16_SFLOAT;
    let (in_a, in_b, out_a, out_b) = (sampled(f16)?, sampled(f16)?, sampled(f16)?, sampled(f16)?);
    let general = ash::vk::ImageLayout::GENERAL;
    let (ia, ib, oa, ob) = (in_a.input(general), in_b.input(general), out_a.input(general), out_b.input(general));
    let settings = hybrid_rt::DenoiserSettings { spatial_passes: denoise_passes, anti_lag, ..Default::default() };
    let dcommon = hybrid_rt::DenoisingCommon { roughness: glossy.roughness, settings, ..gbuffer.denoising_common(&camera) };
    let mut denoise_rows = Vec::new();
    let mut denoise_json = serde_json::Map::new();
    let mut measure =
        |name: &str,
         signal: hybrid_rt::SignalType,
         kinds: [TaskKind; 2],
         schedule: &mut dyn FnMut(&mut hybrid_rt::TaskContainer, hybrid_rt::DenoisingContextHandle) -> Result<(), String>|
         -> Result<(), String> {
            let dn = ctx
                .create_denoising_context(&hybrid_rt::DenoisingContextInput {
                    max_width: width,
                    max_height: height,
                    signal,
                    ..Default::default()
                })
                .map_err(e)?;
            let [trace, denoise] = time_pair(&host, &ctx, &mut frame, frames, kinds, |f| schedule(f, dn))?;
            ctx.destroy_denoising_context(dn).map_err(e)?;
            denoise_rows
                .push((format!("Denoise {name} {width}x{height}"), format!("{denoise:.3} ms (its 1-ray trace: {trace:.3} ms)")));
            denoise_json.insert(name.replace(' ', "_"), json!({"denoise_gpu_ms": denoise, "trace_gpu_ms": trace}));
            Ok(())
        };
    use hybrid_rt::SignalType as S;
    let ao1 = hybrid_rt::TraceAmbientOcclusionTask { output: ia, ..gbuffer.ao_task(&camera, 1.0, 1) };
    measure("AO", S::DiffuseOcclusion, [TaskKind::AmbientOcclusion, TaskKind::DenoiseDiffuseOcclusion], &mut |f, dn| {
        f.schedule_ambient_occlusion(&ao1).map_err(e)?;
        f.schedule_denoise_diffuse_occlusion(&hybrid_rt::DenoiseDiffuseOcclusionTask {
            context: dn,
            common: dcommon,
            input: ia,
            output: oa,
        })
        .map_err(e)
    })?;
    let shadow1 = hybrid_rt::TraceShadowTask { output: ia, ..shadow };
    measure("shadow", S::Shadow, [TaskKind::Shadow, TaskKind::DenoiseShadow], &mut |f, dn| {
        f.schedule_shadow(&shadow1).map_err(e)?;
        f.schedule_denoise_shadow(&hybrid_rt::DenoiseShadowTask {
            context: dn,
            common: dcommon,
            light: shadow.light,
            input: ia,
            output: oa,
        })
        .map_err(e)
    })?;
    let multi1 = hybrid_rt::TraceMultiShadowTask { packed: ia, ..multi.clone() };
    measure(
        "multi-light shadow (4 lights)",
        S::MultiShadow,
        [TaskKind::MultiShadow, TaskKind::DenoiseMultiShadow],
        &mut |f, dn| {
            f.schedule_multi_shadow(&multi1).map_err(e)?;
            f.schedule_denoise_multi_shadow(&hybrid_rt::DenoiseMultiShadowTask {
                context: dn,
                common: dcommon,
                input: ia,
                output: oa,
            })
            .map_err(e)
        },
    )?;
    let diffuse1 = hybrid_rt::TraceDiffuseTask { output: ib, ..diffuse };
    measure("diffuse", S::Diffuse, [TaskKind::Diffuse, TaskKind::DenoiseDiffuse], &mut |f, dn| {
        f.schedule_diffuse(&diffuse1).map_err(e)?;
        f.schedule_denoise_diffuse(&hybrid_rt::DenoiseDiffuseTask { context: dn, common: dcommon, input: ib, output: ob })
            .map_err(e)
    })?;
    let specular1 = hybrid_rt::TraceSpecularTask { output: ia, ..specular };
    measure("specular (roughness 0.3)", S::Specular, [TaskKind::Specular, TaskKind::DenoiseSpecular], &mut |f, dn| {
        f.schedule_specular(&specular1).map_err(e)?;
        f.schedule_denoise_specular(&hybrid_rt::DenoiseSpecularTask { context: dn, common: dcommon, input: ia, output: oa })
            .map_err(e)
    })?;
    measure(
        "specular + diffuse",
        S::SpecularAndDiffuse,
        [TaskKind::Specular, TaskKind::DenoiseSpecularAndDiffuse],
        &mut |f, dn| {
            f.schedule_specular(&specular1).map_err(e)?;
            f.schedule_diffuse(&diffuse1).map_err(e)?;
            f.schedule_denoise_specular_and_diffuse(&hybrid_rt::DenoiseSpecularAndDiffuseTask {
                context: dn,
                common: dcommon,
                input_specular: ia,
                input_diffuse: ib,
                output_specular: oa,
                output_diffuse: ob,
            })
            .map_err(e)
        },
    )?;
    rows.extend(denoise_rows);
    // Free the measured contexts first (destroyed contexts wait for their tickets).
    ctx.release_device_resources_immediately().map_err(e)?;
    let dn_ctx = ctx
        .create_denoising_context(&hybrid_rt::DenoisingContextInput {
            max_width: width,
            max_height: height,
            signal: S::SpecularAndDiffuse,
            ..Default::default()
        })
        .map_err(e)?;
    let dn_bytes = ctx.resource_allocations().denoiser.bytes;
    ctx.destroy_denoising_context(dn_ctx).map_err(e)?;
    rows.push((
        format!("Denoiser history, specular + diffuse context {width}x{height}"),
        format!("{:.1} MiB", dn_bytes as f64 / 1048576.0),
    ));
    denoise_json.insert("specular_and_diffuse_context_bytes".into(), json!(dn_bytes));
    json.insert("denoisers".into(), serde_json::Value::Object(denoise_json));
    for i in [in_a, in_b, out_a, out_b, vis] {
        host.destroy_image(i);
    }

    let mem = ctx.resource_allocations();
    json.insert(
        "memory_bytes".into(),
        json!({
            "total": mem.total_bytes(),
            "blas": mem.blas.bytes,
            "geometry_copies": mem.geometry_copies.bytes,
            "tlas": mem.tlas.bytes,
            "build_scratch": mem.build_scratch.bytes,
            "upload_rings": mem.upload_rings.bytes,
            "cache": mem.cache.bytes,
        }),
    );
    rows.push((
        "SDK device memory".into(),
        format!("{:.1} MiB (BLAS {:.1} MiB)", mem.total_bytes() as f64 / 1048576.0, mem.blas.bytes as f64 / 1048576.0),
    ));

    let wide = rows.iter().map(|r| r.0.len()).max().unwrap_or(0);
    println!("\n{:wide$}  result", "measurement");
    println!("{}", "-".repeat(wide + 50));
    for (k, v) in &rows {
        println!("{k:wide$}  {v}");
    }
    let text = serde_json::to_string_pretty(&serde_json::Value::Object(json)).map_err(|err| err.to_string())? + "\n";
    std::fs::write(&json_path, text).map_err(|err| format!("{json_path}: {err}"))?;
    println!("\nwrote {json_path}");
    gbuffer.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    if Host::validation_errors() > 0 {
        return Err(format!("{} validation errors", Host::validation_errors()));
    }
    Ok(())
}
