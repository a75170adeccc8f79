//! The hybrid-rt sample, headless: the built-in room, integrated as an engine would.
//!
//! Each frame: BVH tasks, direct-lighting injection of the "rasterized" lit frame from the main
//! camera and from a low-resolution secondary ("lidar") camera that looks back at the room,
//! and ray-traced AO. Then one image per debug visualisation, and the soft sun shadow, diffuse
//! GI and glossy reflections shaded from the cache and the lit frame, and each of AO, shadow, GI and
//! reflections at 1 ray/pixel noisy and denoised side by side. Writes EXR + PNG, prints per-task
//! GPU times (from the SDK's timestamp queries) and the SDK's memory.
//!
//! The G-buffer and the lit frame come from the CPU reference renderer for now (the full
//! sample rasterizes its own); everything the SDK sees goes through its public API: its own
//! device (`Host`), one task container per frame, tickets handed back after the fence.
use ash::vk;
use glam::Vec3;
use hybrid_rt::{
    DebugOutput, DepthInput, DepthType, DirectLightingInjectionTask, ExecuteContext, InitSettings, SurfelSettings, TaskKind, Viewport,
};
use hybrid_rt_samples::{args::Args, images, scenes};
use hybrid_rt_testkit::host::{Host, HostImage};
use hybrid_rt_testkit::reference::{direct_lighting, Camera, GBuffer, Sun, Tracer};
use hybrid_rt_testkit::sdk_scene::{run_frame, GBufferImages, SceneOnGpu, READ};
use std::path::PathBuf;

const USAGE: &str = "sample [--width 640] [--height 360] [--rays 16] [--ray-length 1.0] [--frames 4] [--tile-unit-length 0.1] [--denoise-frames 16] [--out out]";
const MAGENTA: [f32; 3] = [1.0, 0.0, 1.0];

fn main() {
    if let Err(e) = run() {
        eprintln!("sample failed: {e}");
        std::process::exit(1);
    }
}

/// Albedo per instance of the room (walls, then objects).
fn albedo(instance: u32) -> [f32; 3] {
    match instance {
        0 => [0.75, 0.72, 0.68],
        1 => [0.7, 0.7, 0.75],
        2 => [0.75, 0.2, 0.15],
        3 => [0.2, 0.45, 0.75],
        4 => [0.8, 0.8, 0.8],
        5 => [0.85, 0.65, 0.2],
        6 => [0.3, 0.7, 0.35],
        _ => [0.6, 0.6, 0.6],
    }
}

struct View {
    camera: Camera,
    width: u32,
    height: u32,
    gbuffer: GBufferImages,
    lit: HostImage,
}

fn view(host: &Host, tracer: &Tracer, camera: Camera, width: u32, height: u32, sun: Sun) -> Result<View, String> {
    let g = GBuffer::render(tracer, &camera, width, height);
    let gbuffer = GBufferImages::upload(host, &g)?;
    let lit_texels = direct_lighting(tracer, &g, sun, albedo);
    let lit = host.image_with_data(vk::Format::R32G32B32A32_SFLOAT, width, height, vk::ImageUsageFlags::SAMPLED, bytemuck::cast_slice(&lit_texels), READ)?;
    Ok(View { camera, width, height, gbuffer, lit })
}

impl View {
    fn injection(&self) -> DirectLightingInjectionTask {
        DirectLightingInjectionTask {
            depth: DepthInput { image: self.gbuffer.depth.input(READ), depth_type: DepthType::ClipSpace },
            lit: self.lit.input(READ),
            viewport: Viewport::full(self.width, self.height),
            camera: self.camera.sdk_camera(self.width, self.height),
            average_window: 8.0,
            ..Default::default()
        }
    }
}

fn run() -> Result<(), String> {
    let args = Args::parse(USAGE);
    let (width, height) = (args.get("width", 640u32), args.get("height", 360u32));
    let rays = args.get("rays", 16u32);
    let ray_length = args.get("ray-length", 1.0f32);
    let frames = args.get("frames", 4u32).max(3);
    let unit = args.get("tile-unit-length", 0.1f32);
    let out = PathBuf::from(args.string("out", "out"));
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let e = |e: hybrid_rt::Error| e.to_string();

    let host = Host::new()?;
    println!("device: {}{}", host.device_name, if host.validation_enabled { " (validation on)" } else { "" });
    let ctx = ExecuteContext::new(&host.device_desc(), &InitSettings::default()).map_err(e)?;
    let (scene, camera) = scenes::room();
    println!("scene: room, {} triangles in {} instances", scene.triangle_count(), scene.instances.len());
    let tracer = Tracer::new(&scene);
    let sun = Sun { to_light: Vec3::new(0.45, 1.0, 0.6), intensity: 2.5 };
    let main = view(&host, &tracer, camera, width, height, sun)?;
    // The lidar camera: 256x256 from the front-left corner looking back into the room, so
    // surfaces the main camera misses get lit too (the integration guide's advice).
    let lidar_camera = Camera { fov_y_radians: 100f32.to_radians(), ..Camera::look_at(Vec3::new(-2.5, 4.5, 2.5), Vec3::new(1.0, 0.5, -1.5)) };
    let lidar = view(&host, &tracer, lidar_camera, 256, 256, sun)?;
    // A second lidar view sweeps the ceiling, which no other camera sees but every GI ray
    // from the floor does.
    let ceiling_camera = Camera {
        fov_y_radians: 120f32.to_radians(),
        up: Vec3::Z,
        ..Camera::look_at(Vec3::new(0.0, 0.3, 0.5), Vec3::new(0.0, 6.0, -0.5))
    };
    let ceiling = view(&host, &tracer, ceiling_camera, 256, 256, sun)?;

    let mut frame = ctx.create_task_container();
    let surfels = SurfelSettings { tile_unit_length: unit, ..Default::default() };
    let gpu_scene = SceneOnGpu::register_with(&host, &ctx, &mut frame, &scene, surfels, MAGENTA)?;
    let (mut ao_ms, mut inject_ms, mut bvh_ms) = (Vec::new(), Vec::new(), 0.0);
    for i in 0..frames {
        frame.schedule_bvh_build(&Default::default()).map_err(e)?;
        // Caches exist from the second frame on (layouts come back with the first ticket).
        if i >= 1 {
            frame.schedule_direct_lighting_injection(&main.injection()).map_err(e)?;
            frame.schedule_direct_lighting_injection(&lidar.injection()).map_err(e)?;
            frame.schedule_direct_lighting_injection(&ceiling.injection()).map_err(e)?;
        }
        frame.schedule_ambient_occlusion(&main.gbuffer.ao_task(&camera, ray_length, rays)).map_err(e)?;
        let done = run_frame(&host, &ctx, &mut frame)?;
        if i == 0 {
            bvh_ms = done.gpu_ms(TaskKind::Bvh);
        } else {
            ao_ms.push(done.gpu_ms(TaskKind::AmbientOcclusion));
            inject_ms.push(done.gpu_ms(TaskKind::DirectLightingInjection));
        }
    }
    let ao = main.gbuffer.read_output(&host)?;
    images::write_exr_gray(&out.join("ao.exr"), width, height, &ao)?;
    images::write_png_gray(&out.join("ao.png"), width, height, &ao)?;
    let lit_bytes = host.read_image(&main.lit, READ)?;
    images::write_png_rgb(&out.join("lit.png"), width, height, bytemuck::cast_slice(&lit_bytes), 1.0)?;

    // One image per debug visualisation, from the main camera; the cache also from above the
    // room, where magenta shows what no camera has lit yet.
    let overview = Camera { fov_y_radians: 80f32.to_radians(), ..Camera::look_at(Vec3::new(0.5, 5.6, 2.9), Vec3::new(0.0, 0.0, -0.5)) };
    let modes = [
        ("debug_cache", DebugOutput::DirectLightingCache, camera, 1.0),
        ("debug_cache_overview", DebugOutput::DirectLightingCache, overview, 1.0),
        ("debug_random_tile", DebugOutput::RandomTileColor, camera, 1.0),
        ("debug_random_mesh", DebugOutput::RandomMeshColor, camera, 1.0),
        ("debug_hit_t", DebugOutput::HitT, camera, 1.0 / 10.0),
        ("debug_barycentrics", DebugOutput::Barycentrics, camera, 1.0),
    ];
    let debug_out = host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, width, height, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL)?;
    let mut written = vec![out.join("ao.png").display().to_string(), out.join("lit.png").display().to_string()];
    for (name, mode, cam, scale) in modes {
        let mut task = main.gbuffer.ao_task(&cam, ray_length, 1);
        task.common.debug_output = mode;
        task.output = debug_out.input(vk::ImageLayout::GENERAL);
        frame.schedule_ambient_occlusion(&task).map_err(e)?;
        run_frame(&host, &ctx, &mut frame)?;
        let bytes = host.read_image(&debug_out, vk::ImageLayout::GENERAL)?;
        let path = out.join(format!("{name}.png"));
        images::write_png_rgb(&path, width, height, bytemuck::cast_slice(&bytes), scale)?;
        written.push(path.display().to_string());
    }

    // The ray-traced outputs, shaded from the cache and the lit frame (16 rays per pixel so
    // the raw images read well without a denoiser).
    let mut common = main.gbuffer.trace_common(&camera);
    common.direct_lighting = main.lit.input(READ);
    let traced = [
        ("shadow", 1.0),
        ("diffuse_gi", 1.0),
        ("specular", 1.0),
    ];
    let mut glossy = common;
    glossy.roughness.global_roughness = 0.25;
    for (name, scale) in traced {
        let output = debug_out.input(vk::ImageLayout::GENERAL);
        match name {
            "shadow" => frame
                .schedule_shadow(&hybrid_rt::TraceShadowTask {
                    common,
                    light: hybrid_rt::LightInfo { direction: -sun.to_light, angular_extent: 0.05, ..Default::default() },
                    output,
                    rays_per_pixel: 16,
                })
                .map_err(e)?,
            "diffuse_gi" => frame
                .schedule_diffuse(&hybrid_rt::TraceDiffuseTask { common, output, rays_per_pixel: 16, ray_length: 20.0, ..Default::default() })
                .map_err(e)?,
            _ => frame
                .schedule_specular(&hybrid_rt::TraceSpecularTask { common: glossy, output, rays_per_pixel: 16, ray_length: 20.0, ..Default::default() })
                .map_err(e)?,
        }
        run_frame(&host, &ctx, &mut frame)?;
        let bytes = host.read_image(&debug_out, vk::ImageLayout::GENERAL)?;
        let mut texels: Vec<[f32; 4]> = bytemuck::cast_slice(&bytes).to_vec();
        if name == "shadow" {
            // G holds the visible fraction: show it as grey.
            texels.iter_mut().for_each(|t| *t = [t[1], t[1], t[1], 1.0]);
        }
        let path = out.join(format!("{name}.png"));
        images::write_png_rgb(&path, width, height, &texels, scale)?;
        written.push(path.display().to_string());
    }

    let mean = |v: &[f64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
    // Noisy (1 ray/pixel) and denoised side by side: each trace and its denoise task in one
    // container per frame, as an engine schedules them; the denoisers accumulate over frames.
    let sampled_storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    let noisy = host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, width, height, sampled_storage, vk::ImageLayout::GENERAL)?;
    let clean = host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, width, height, sampled_storage, vk::ImageLayout::GENERAL)?;
    let (ni, ci) = (noisy.input(vk::ImageLayout::GENERAL), clean.input(vk::ImageLayout::GENERAL));
    let dcommon = hybrid_rt::DenoisingCommon { roughness: glossy.roughness, ..main.gbuffer.denoising_common(&camera) };
    let light = hybrid_rt::LightInfo { direction: -sun.to_light, angular_extent: 0.05, ..Default::default() };
    let denoise_frames = args.get("denoise-frames", 16u32).max(1);
    let mut denoise_ms: Vec<(&str, f64)> = Vec::new();
    for (name, signal) in [
        ("ao", hybrid_rt::SignalType::DiffuseOcclusion),
        ("shadow", hybrid_rt::SignalType::Shadow),
        ("diffuse_gi", hybrid_rt::SignalType::Diffuse),
        ("specular", hybrid_rt::SignalType::Specular),
    ] {
        let dn = ctx
            .create_denoising_context(&hybrid_rt::DenoisingContextInput { max_width: width, max_height: height, signal, ..Default::default() })
            .map_err(e)?;
        let mut times = Vec::new();
        for _ in 0..denoise_frames {
            let c = dcommon;
            match signal {
                hybrid_rt::SignalType::DiffuseOcclusion => {
                    let trace = hybrid_rt::TraceAmbientOcclusionTask { output: ni, ..main.gbuffer.ao_task(&camera, ray_length, 1) };
                    frame.schedule_ambient_occlusion(&trace).map_err(e)?;
                    frame.schedule_denoise_diffuse_occlusion(&hybrid_rt::DenoiseDiffuseOcclusionTask { context: dn, common: c, input: ni, output: ci }).map_err(e)?;
                }
                hybrid_rt::SignalType::Shadow => {
                    frame.schedule_shadow(&hybrid_rt::TraceShadowTask { common, light, output: ni, rays_per_pixel: 1 }).map_err(e)?;
                    frame.schedule_denoise_shadow(&hybrid_rt::DenoiseShadowTask { context: dn, common: c, light, input: ni, output: ci }).map_err(e)?;
                }
                hybrid_rt::SignalType::Diffuse => {
                    frame.schedule_diffuse(&hybrid_rt::TraceDiffuseTask { common, output: ni, ray_length: 20.0, ..Default::default() }).map_err(e)?;
                    frame.schedule_denoise_diffuse(&hybrid_rt::DenoiseDiffuseTask { context: dn, common: c, input: ni, output: ci }).map_err(e)?;
                }
                _ => {
                    frame.schedule_specular(&hybrid_rt::TraceSpecularTask { common: glossy, output: ni, ray_length: 20.0, ..Default::default() }).map_err(e)?;
                    frame.schedule_denoise_specular(&hybrid_rt::DenoiseSpecularTask { context: dn, common: c, input: ni, output: ci }).map_err(e)?;
                }
            }
            let done = run_frame(&host, &ctx, &mut frame)?;
            times.push(done.timings.iter().filter(|t| format!("{:?}", t.kind).starts_with("Denoise")).map(|t| t.gpu_ms).sum::<f64>());
        }
        ctx.destroy_denoising_context(dn).map_err(e)?;
        denoise_ms.push((name, mean(&times)));
        let read = |img: &HostImage| -> Result<Vec<[f32; 4]>, String> {
            let mut t: Vec<[f32; 4]> = bytemuck::cast_slice(&host.read_image(img, vk::ImageLayout::GENERAL)?).to_vec();
            if name == "shadow" && std::ptr::eq(img, &noisy) {
                t.iter_mut().for_each(|v| *v = [v[1], v[1], v[1], 1.0]); // G: visible fraction
            }
            if name == "ao" && std::ptr::eq(img, &noisy) {
                t.iter_mut().for_each(|v| *v = [v[0], v[0], v[0], 1.0]);
            }
            Ok(t)
        };
        let (left, right) = (read(&noisy)?, read(&clean)?);
        let pair: Vec<[f32; 4]> = (0..height as usize)
            .flat_map(|y| left[y * width as usize..(y + 1) * width as usize].iter().chain(&right[y * width as usize..(y + 1) * width as usize]).copied().collect::<Vec<_>>())
            .collect();
        let path = out.join(format!("{name}_noisy_vs_denoised.png"));
        images::write_png_rgb(&path, width * 2, height, &pair, 1.0)?;
        written.push(path.display().to_string());
    }
    host.destroy_image(noisy);
    host.destroy_image(clean);

    let mem = ctx.resource_allocations();
    let cache_bytes: u64 = gpu_scene.instances.iter().map(|h| ctx.instance_cache_bytes(*h).unwrap_or(0)).sum();
    println!(
        "GPU time: BVH build (first frame) {bvh_ms:.3} ms; AO {width}x{height} x {rays} rays {:.3} ms; injection (main {width}x{height} + two lidar views of 256x256, with resolves) {:.3} ms (means of {} frames)",
        mean(&ao_ms),
        mean(&inject_ms),
        ao_ms.len()
    );
    println!(
        "GPU time of the denoisers {width}x{height} (means of {denoise_frames} frames): {}",
        denoise_ms.iter().map(|(n, ms)| format!("{n} {ms:.3} ms")).collect::<Vec<_>>().join(", ")
    );
    println!(
        "SDK memory: {:.2} MiB (BLAS {:.2} MiB, cache pages {:.2} MiB holding {:.2} MiB of instance caches, {} instances)",
        mem.total_bytes() as f64 / 1048576.0,
        mem.blas.bytes as f64 / 1048576.0,
        mem.cache.bytes as f64 / 1048576.0,
        cache_bytes as f64 / 1048576.0,
        gpu_scene.instances.len()
    );
    println!("wrote {}", written.join(", "));
    println!("(magenta in the cache, GI and reflections: surfaces no camera has lit yet — their initial colour, as the guide suggests while integrating)");
    host.destroy_image(debug_out);
    for v in [main, lidar, ceiling] {
        v.gbuffer.destroy(&host);
        host.destroy_image(v.lit);
    }
    gpu_scene.destroy(&host);
    drop(ctx);
    let errors = Host::validation_errors();
    if errors > 0 {
        return Err(format!("{errors} Vulkan validation errors"));
    }
    Ok(())
}
