//! Every trace task gives the same image through the ray-tracing pipeline and through inline
//! ray queries (where the device has them: lavapipe does, NVIDIA's driver does not).
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::{
    InitSettings, LightInfo, LightType, RoughnessInput, SurfelSettings, TraceDiffuseTask, TraceShadowTask, TraceSpecularTask,
};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 48;
const H: u32 = 48;

#[test]
fn pipeline_and_inline_ray_queries_give_the_same_images() {
    let (host, ctx) = host_and_context(InitSettings::default());
    if !ctx.supports_inline_rt() {
        eprintln!("no ray queries on this device: nothing to compare");
        return;
    }
    let mut scene = Scene::default();
    let ground = scene.add_mesh(Mesh::grid(6.0, 6));
    let sphere = scene.add_mesh(Mesh::sphere(0.6, 24, 12));
    scene.add_instance(ground, Affine3A::IDENTITY);
    scene.add_instance(sphere, Affine3A::from_translation(Vec3::new(0.0, 0.6, 0.0)));
    let camera = Camera::look_at(Vec3::new(0.0, 2.0, 2.5), Vec3::new(0.0, 0.3, 0.0));
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut frame = ctx.create_task_container();
    let s = SceneOnGpu::register_with(
        &host,
        &ctx,
        &mut frame,
        &scene,
        SurfelSettings { tile_unit_length: 0.3, ..Default::default() },
        [0.7, 0.4, 0.2],
    )
    .unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap(); // caches exist from here on

    let rgba = || {
        host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap()
    };
    let mut outs: Vec<_> = (0..6).map(|_| rgba()).collect();
    outs.extend((0..2).map(|_| rgba())); // multi-shadow packed outputs
    let vis: Vec<_> = (0..2)
        .map(|_| host.image_cleared(vk::Format::R32_UINT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap())
        .collect();
    let mut common = images.trace_common(&camera);
    common.roughness = RoughnessInput { global_roughness: 0.4, ..Default::default() };
    for (k, inline) in [(0usize, false), (1, true)] {
        let mut c = common;
        c.use_inline_rt = inline;
        let out = |i: usize| outs[i].input(vk::ImageLayout::GENERAL);
        let light =
            LightInfo { light_type: LightType::Point, position: Vec3::new(0.5, 3.0, 0.2), radius: 0.4, ..Default::default() };
        frame
            .schedule_shadow(&TraceShadowTask { common: c, light, output: out(k), rays_per_pixel: 4, ..Default::default() })
            .unwrap();
        frame
            .schedule_diffuse(&TraceDiffuseTask {
                common: c,
                output: out(2 + k),
                rays_per_pixel: 4,
                miss_radiance: [0.2; 3],
                ..Default::default()
            })
            .unwrap();
        frame
            .schedule_specular(&TraceSpecularTask {
                common: c,
                output: out(4 + k),
                rays_per_pixel: 4,
                miss_radiance: [0.2; 3],
                ..Default::default()
            })
            .unwrap();
        let sun = LightInfo { direction: Vec3::new(0.3, -1.0, 0.2), angular_extent: 0.1, ..Default::default() };
        frame
            .schedule_multi_shadow(&hybrid_rt::TraceMultiShadowTask {
                common: c,
                lights: vec![light, sun],
                visibility: vis[k].input(vk::ImageLayout::GENERAL),
                packed: out(6 + k),
                rays_per_pixel: 4,
                first_hit: false,
                ..Default::default()
            })
            .unwrap();
    }
    run_frame(&host, &ctx, &mut frame).unwrap();
    let words =
        |i: usize| -> Vec<u32> { bytemuck::cast_slice(&host.read_image(&vis[i], vk::ImageLayout::GENERAL).unwrap()).to_vec() };
    assert_eq!(words(0), words(1), "multi-shadow visibility");
    for (name, a, b) in [("shadow", 0, 1), ("diffuse", 2, 3), ("specular", 4, 5), ("multi-shadow packed", 6, 7)] {
        let read = |i: usize| -> Vec<[f32; 4]> {
            bytemuck::cast_slice(&host.read_image(&outs[i], vk::ImageLayout::GENERAL).unwrap()).to_vec()
        };
        let (pa, pb) = (read(a), read(b));
        let differ = pa.iter().zip(&pb).filter(|(x, y)| (0..4).any(|c| (x[c] - y[c]).abs() > 1e-4 * (1.0 + x[c].abs()))).count();
        eprintln!("{name}: {differ} of {} pixels differ between pipeline and inline", pa.len());
        assert!(differ * 100 <= pa.len(), "{name}: {differ} pixels differ");
    }
    for o in outs.into_iter().chain(vis) {
        host.destroy_image(o);
    }
    images.destroy(&host);
    s.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
