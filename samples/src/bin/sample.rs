//! The hybrid-rt sample, headless: renders ray-traced AO of the built-in room and writes it as
//! EXR and PNG, printing the per-task GPU times and the SDK's memory use.
//!
//! It integrates the SDK as an engine would: its own device (`Host`), its own G-buffer (for
//! now from the CPU reference renderer; the rasterized G-buffer comes with the full sample),
//! one task container per frame, tickets handed back after its fence.
use hybrid_rt::{ExecuteContext, InitSettings, TaskKind};
use hybrid_rt_samples::{args::Args, images, scenes};
use hybrid_rt_testkit::host::Host;
use hybrid_rt_testkit::reference::{GBuffer, Tracer};
use hybrid_rt_testkit::sdk_scene::{run_frame, GBufferImages, SceneOnGpu};
use std::path::PathBuf;

const USAGE: &str = "sample [--width 640] [--height 360] [--rays 16] [--ray-length 1.0] [--frames 4] [--out out]";

fn main() {
    if let Err(e) = run() {
        eprintln!("sample failed: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = Args::parse(USAGE);
    let (width, height) = (args.get("width", 640u32), args.get("height", 360u32));
    let rays = args.get("rays", 16u32);
    let ray_length = args.get("ray-length", 1.0f32);
    let frames = args.get("frames", 4u32).max(1);
    let out = PathBuf::from(args.string("out", "out"));
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;

    let host = Host::new()?;
    println!("device: {}{}", host.device_name, if host.validation_enabled { " (validation on)" } else { "" });
    let ctx = ExecuteContext::new(&host.device_desc(), &InitSettings::default()).map_err(|e| e.to_string())?;
    let (scene, camera) = scenes::room();
    println!("scene: room, {} triangles in {} instances", scene.triangle_count(), scene.instances.len());
    let g = GBuffer::render(&Tracer::new(&scene), &camera, width, height);
    let gbuffer = GBufferImages::upload(&host, &g)?;

    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene)?;
    let mut ao_ms = Vec::new();
    let mut bvh_ms = 0.0;
    for i in 0..frames {
        frame.schedule_bvh_build(&Default::default()).map_err(|e| e.to_string())?;
        frame.schedule_ambient_occlusion(&gbuffer.ao_task(&camera, ray_length, rays)).map_err(|e| e.to_string())?;
        let done = run_frame(&host, &ctx, &mut frame)?;
        if i == 0 {
            bvh_ms = done.gpu_ms(TaskKind::Bvh);
        } else {
            ao_ms.push(done.gpu_ms(TaskKind::AmbientOcclusion));
        }
    }
    let ao = gbuffer.read_output(&host)?;
    let exr = out.join("ao.exr");
    let png = out.join("ao.png");
    images::write_exr_gray(&exr, width, height, &ao)?;
    images::write_png_gray(&png, width, height, &ao)?;

    let mean_ao = if ao_ms.is_empty() { f64::NAN } else { ao_ms.iter().sum::<f64>() / ao_ms.len() as f64 };
    let mem = ctx.resource_allocations();
    println!("GPU time: BVH build (first frame) {bvh_ms:.3} ms; AO {width}x{height} x {rays} rays {mean_ao:.3} ms (mean of {} frames)", ao_ms.len());
    println!(
        "SDK memory: {:.2} MiB (BLAS {:.2} MiB in {}, geometry copies {:.2} MiB, TLAS {:.2} MiB, scratch {:.2} MiB)",
        mem.total_bytes() as f64 / 1048576.0,
        mem.blas.bytes as f64 / 1048576.0,
        mem.blas.count,
        mem.geometry_copies.bytes as f64 / 1048576.0,
        mem.tlas.bytes as f64 / 1048576.0,
        mem.build_scratch.bytes as f64 / 1048576.0
    );
    println!("wrote {} and {}", exr.display(), png.display());
    gbuffer.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    let errors = Host::validation_errors();
    if errors > 0 {
        return Err(format!("{errors} Vulkan validation errors"));
    }
    Ok(())
}
