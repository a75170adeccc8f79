//! Ambient occlusion against the CPU reference.
mod common;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::InitSettings;
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;
use hybrid_rt_testkit::stats;

const W: u32 = 64;
const H: u32 = 64;

fn ao_params(ray_length: f32) -> AoParams {
    AoParams { ray_length, falloff_power: 1.0, ray_offset: hybrid_rt::RayOffset::default() }
}

#[test]
fn open_plane_is_unoccluded() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let m = scene.add_mesh(Mesh::grid(20.0, 4));
    scene.add_instance(m, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 4.0, 1.0), Vec3::ZERO);
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    assert!(g.hit.iter().all(|h| *h), "the plane fills the view");

    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let images = GBufferImages::upload(&host, &g).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 2.0, 4)).unwrap();
    let done = run_frame(&host, &ctx, &mut frame).unwrap();
    let ao = images.read_output(&host).unwrap();
    let min = ao.iter().cloned().fold(f32::MAX, f32::min);
    assert!(min > 0.9999, "an open plane has AO 1 everywhere; min {min}");
    assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::AmbientOcclusion));
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}

/// A sphere resting on a plane: contact darkening under the sphere, matching the reference.
#[test]
fn sphere_on_plane_matches_reference() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let plane = scene.add_mesh(Mesh::grid(8.0, 8));
    let sphere = scene.add_mesh(Mesh::sphere(0.5, 24, 12));
    scene.add_instance(plane, Affine3A::IDENTITY);
    scene.add_instance(sphere, Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)));
    let camera = Camera::look_at(Vec3::new(0.0, 1.6, 2.2), Vec3::new(0.0, 0.2, 0.0));
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);

    let rays = 16;
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let images = GBufferImages::upload(&host, &g).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, rays)).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let gpu = images.read_output(&host).unwrap();

    let strata = 16; // 256 reference samples per pixel
    let reference = reference_ao(&tracer, &g, camera.eye, &ao_params(1.0), strata);
    let sigma = stats::sample_sigma(rays, strata * strata);
    let report = stats::compare_blocks(&gpu, &reference, W, H, 8, sigma, 0.01);
    eprintln!(
        "sphere on plane: worst 8x8 block error {:.4} at {:?} (tolerance {:.4}), mean abs error {:.4}",
        report.worst_block_error, report.worst_block, report.tolerance, report.mean_abs_error
    );
    assert!(report.worst_block_error <= report.tolerance);
    // The contact region under the sphere is really occluded (the test is not vacuous).
    assert!(reference.iter().cloned().fold(1.0, f32::min) < 0.5);
    assert!(gpu.iter().cloned().fold(1.0, f32::min) < 0.5);
    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
