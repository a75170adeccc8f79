//! The cache budget (`InitSettings::cache_budget_bytes`): with room for half the scene's
//! caches, the instances a camera uses keep theirs and render correctly, the others are
//! evicted (and reported), and evicted instances get their caches back when they are used.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{DebugOutput, DepthInput, DepthType, DirectLightingInjectionTask, InitSettings, SurfelSettings, Viewport};
use hybrid_rt_testkit::host::HostImage;
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 64;
const H: u32 = 48;
const UNLIT: [f32; 3] = [1.0, 0.0, 1.0];
const INJECTED: [f32; 3] = [0.2, 0.6, 0.3];
/// Eight 1 m tiles in a row, 2 m apart.
const TILES: usize = 8;

fn scene() -> Scene {
    let mut s = Scene::default();
    let m = s.add_mesh(Mesh::grid(1.0, 1));
    for i in 0..TILES {
        s.add_instance(m, Affine3A::from_translation(Vec3::new(2.0 * i as f32, 0.0, 0.0)));
    }
    s
}

/// Looking down on tiles `first..first + 4` (x = 2 first .. 2 first + 6).
fn camera_over(first: usize) -> Camera {
    let x = 2.0 * first as f32 + 3.0;
    // 4.5 m up, the 60 degree view spans x +- 3.46 m at 4:3: the four tiles, not their neighbours.
    Camera { up: Vec3::NEG_Z, ..Camera::look_at(Vec3::new(x, 4.5, 0.0), Vec3::new(x, 0.0, 0.0)) }
}

struct View {
    g: GBuffer,
    images: GBufferImages,
    lit: HostImage,
    camera: Camera,
}

#[test]
fn a_budget_of_half_the_caches_keeps_what_the_camera_uses() {
    let scene = scene();
    let tracer = Tracer::new(&scene);
    // Size one tile's cache with an unlimited context first (the same layout).
    let surfels = SurfelSettings { tile_unit_length: 0.1, ..Default::default() };
    let per_instance = {
        let (host, ctx) = host_and_context(InitSettings::default());
        let mut frame = ctx.create_task_container();
        let gpu = SceneOnGpu::register_with(&host, &ctx, &mut frame, &scene, surfels, UNLIT).unwrap();
        for _ in 0..2 {
            frame.schedule_bvh_build(&Default::default()).unwrap();
            run_frame(&host, &ctx, &mut frame).unwrap();
        }
        let bytes = ctx.instance_cache_bytes(gpu.instances[0]).unwrap();
        assert_eq!(ctx.cache_report().resident_bytes, bytes * TILES as u64);
        gpu.destroy(&host);
        bytes
    };
    let budget = per_instance * TILES as u64 / 2 + per_instance / 2;
    let (host, ctx) = host_and_context(InitSettings { cache_budget_bytes: budget, ..Default::default() });
    let mut frame = ctx.create_task_container();
    let gpu = SceneOnGpu::register_with(&host, &ctx, &mut frame, &scene, surfels, UNLIT).unwrap();
    for _ in 0..2 {
        frame.schedule_bvh_build(&Default::default()).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
    }
    let first = ctx.cache_report();
    eprintln!("{per_instance} bytes per cache, budget {budget}: after registration {first:?}");
    assert_eq!((first.resident_bytes, first.waiting_instances, first.evictions), (4 * per_instance, 4, 0));

    let view = |first: usize| -> View {
        let camera = camera_over(first);
        let g = GBuffer::render(&tracer, &camera, W, H);
        let images = GBufferImages::upload(&host, &g).unwrap();
        let texels: Vec<[f32; 4]> =
            (0..g.depth.len()).map(|i| if g.hit[i] { [INJECTED[0], INJECTED[1], INJECTED[2], 1.0] } else { [0.0; 4] }).collect();
        let lit = host
            .image_with_data(
                vk::Format::R32G32B32A32_SFLOAT,
                W,
                H,
                vk::ImageUsageFlags::SAMPLED,
                bytemuck::cast_slice(&texels),
                READ,
            )
            .unwrap();
        View { g, images, lit, camera }
    };
    // Frames of injection from a camera; then what the cache shows it (debug view).
    let mut look = |v: &View, frames: usize| -> f32 {
        for _ in 0..frames {
            frame
                .schedule_direct_lighting_injection(&DirectLightingInjectionTask {
                    depth: DepthInput { image: v.images.depth.input(READ), depth_type: DepthType::ClipSpace },
                    lit: v.lit.input(READ),
                    viewport: Viewport::full(W, H),
                    camera: v.camera.sdk_camera(W, H),
                    average_window: 1.0,
                    ..Default::default()
                })
                .unwrap();
            run_frame(&host, &ctx, &mut frame).unwrap();
        }
        let mode = DebugOutput::DirectLightingCache;
        let texels = debug_view(&host, &ctx, &mut frame, &v.images, &v.camera, mode, true, (W, H)).unwrap();
        let hits: Vec<usize> = (0..texels.len()).filter(|&i| v.g.hit[i]).collect();
        let right = hits.iter().filter(|&&i| (Vec3::from_slice(&texels[i][..3]) - Vec3::from(INJECTED)).length() < 1e-3).count();
        right as f32 / hits.len().max(1) as f32
    };

    // The camera sees the last four tiles, which registration left without caches: once
    // they are used their caches come in and the first four's go.
    let far = view(4);
    let shown = look(&far, 4);
    let after = ctx.cache_report();
    eprintln!("camera over tiles 4-7: {:.1}% of its pixels show the injected light; {after:?}", 100.0 * shown);
    assert!(shown > 0.98, "the visible tiles render their injected light ({shown})");
    assert!(after.resident_bytes <= budget, "{after:?}");
    assert_eq!((after.evictions, after.evicted_bytes, after.waiting_instances), (4, 4 * per_instance, 4), "{after:?}");
    for (i, &h) in gpu.instances.iter().enumerate() {
        let bytes = ctx.instance_cache_bytes(h).unwrap();
        assert_eq!(bytes, if i >= 4 { per_instance } else { 0 }, "instance {i}");
    }

    // Back to the first four: evicted, they get new caches when used, and the others go.
    let near = view(0);
    let shown = look(&near, 4);
    let back = ctx.cache_report();
    eprintln!("camera over tiles 0-3: {:.1}% of its pixels show the injected light; {back:?}", 100.0 * shown);
    assert!(shown > 0.98, "evicted tiles come back when used ({shown})");
    assert!(back.resident_bytes <= budget && back.evictions == 8 && back.evicted_bytes == 8 * per_instance, "{back:?}");

    for v in [far, near] {
        v.images.destroy(&host);
        host.destroy_image(v.lit);
    }
    gpu.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
