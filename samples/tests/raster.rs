//! The sample's rasterized G-buffer against the CPU reference's ray-cast one, and the SDK
//! reading it: what the sample hands the SDK is what an engine would. (Flat-shaded: no
//! vertex normals, so the G-buffer normals are the reference's triangle planes.)
use ash::vk;
use glam::Vec3;
use hybrid_rt_samples::raster::{self, Draw, GBufferPass, Material, MeshBuffers, Targets};
use hybrid_rt_samples::scenes;
use hybrid_rt_testkit::host::Host;
use hybrid_rt_testkit::reference::{Camera, GBuffer, Tracer};

const W: u32 = 96;
const H: u32 = 64;

fn halves(bytes: &[u8]) -> Vec<f32> {
    bytemuck::cast_slice::<u8, u16>(bytes).iter().map(|h| half::f16::from_bits(*h).to_f32()).collect()
}

#[test]
fn rasterized_gbuffer_matches_the_reference_and_motion_follows_the_camera() {
    let host = Host::new().expect("device");
    let (scene, camera) = scenes::room();
    let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
    let meshes = MeshBuffers::upload(&host, &scene, &[], &[]).unwrap();
    let targets = Targets::new(&host, W, H).unwrap();
    let mut pass = GBufferPass::new(&host).unwrap();
    let material =
        |i: usize| Material { albedo: [0.1 * i as f32 % 1.0, 0.5, 0.25], roughness: 0.5, metalness: 0.0, ..Default::default() };
    let draws: Vec<Draw> = raster::static_draws(&scene, material);
    // Last frame the camera was 0.1 m to the left: motion vectors point there.
    let prev = Camera { eye: camera.eye - Vec3::X * 0.1, target: camera.target - Vec3::X * 0.1, ..camera };
    host.run(|cmd| pass.record(&host, cmd, 0, &targets, &meshes, &draws, &camera, &prev)).unwrap().unwrap();

    let depth: Vec<f32> = bytemuck::cast_slice(&host.read_image(&targets.depth, raster::READ).unwrap()).to_vec();
    let normals = halves(&host.read_image(&targets.normal_roughness, raster::READ).unwrap());
    let motion = halves(&host.read_image(&targets.motion, raster::READ).unwrap());
    let prev_clip = prev.view_to_clip(W as f32 / H as f32) * prev.world_to_view();
    let (mut depth_ok, mut normal_ok, mut motion_ok, mut n) = (0, 0, 0, 0);
    for i in 0..(W * H) as usize {
        if !g.hit[i] {
            continue;
        }
        n += 1;
        depth_ok += ((depth[i] - g.depth[i]).abs() < 1e-4) as u32;
        let rn = Vec3::new(normals[4 * i], normals[4 * i + 1], normals[4 * i + 2]);
        normal_ok += (rn.dot(g.normal[i]) > 0.99) as u32;
        let c = prev_clip * g.position[i].extend(1.0);
        let expected = (
            (c.x / c.w * 0.5 + 0.5) * W as f32 - ((i as u32 % W) as f32 + 0.5),
            (c.y / c.w * 0.5 + 0.5) * H as f32 - ((i as u32 / W) as f32 + 0.5),
        );
        motion_ok += ((motion[2 * i] - expected.0).abs() < 0.02 && (motion[2 * i + 1] - expected.1).abs() < 0.02) as u32;
    }
    eprintln!("raster vs reference over {n} pixels: depth {depth_ok}, normals {normal_ok}, motion {motion_ok} agree");
    // Pixels on silhouettes may see different triangles (coverage rules vs the centre ray).
    for (what, ok) in [("depth", depth_ok), ("normals", normal_ok), ("motion", motion_ok)] {
        assert!(ok as f32 > 0.98 * n as f32, "{what}: {ok} of {n}");
    }
    assert!(motion.chunks(2).any(|m| m[0].abs() > 0.5), "the camera move shows in the motion vectors");

    // The SDK takes the rasterized buffers as they are (hardware depth, fp16 normals).
    let ctx = host.create_context(&Default::default()).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu = hybrid_rt_testkit::sdk_scene::SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    let ao = host.image_cleared(vk::Format::R32_SFLOAT, W, H, vk::ImageUsageFlags::STORAGE, vk::ImageLayout::GENERAL).unwrap();
    let common = hybrid_rt::TraceCommon {
        depth: hybrid_rt::DepthInput { image: targets.depth.input(raster::READ), depth_type: hybrid_rt::DepthType::ClipSpace },
        normals: hybrid_rt::NormalInput {
            image: targets.normal_roughness.input(raster::READ),
            normal_type: hybrid_rt::NormalType::RgbVector,
            space: hybrid_rt::NormalSpace::World,
            ..Default::default()
        },
        viewport: hybrid_rt::Viewport::full(W, H),
        camera: camera.sdk_camera(W, H),
        ..Default::default()
    };
    frame
        .schedule_ambient_occlusion(&hybrid_rt::TraceAmbientOcclusionTask {
            common,
            output: ao.input(vk::ImageLayout::GENERAL),
            rays_per_pixel: 4,
            ..Default::default()
        })
        .unwrap();
    hybrid_rt_testkit::sdk_scene::run_frame(&host, &ctx, &mut frame).unwrap();
    let values = host.read_image_f32(&ao, vk::ImageLayout::GENERAL).unwrap();
    let mean = values.iter().sum::<f32>() / values.len() as f32;
    assert!(
        values.iter().all(|v| (0.0..=1.0).contains(v)) && mean > 0.5 && mean < 0.99,
        "AO from the raster G-buffer: mean {mean}"
    );
    host.destroy_image(ao);
    gpu.destroy(&host);
    drop(ctx);
    pass.destroy(&host);
    targets.destroy(&host);
    meshes.destroy(&host);
    assert_eq!(Host::validation_errors(), 0, "{:#?}", Host::validation_messages());
}

#[test]
fn deferred_lighting_with_sdk_shadows_matches_the_reference_lit_frame() {
    use hybrid_rt::*;
    use hybrid_rt_samples::lighting::{LightingPass, Lights, Visibility};
    use hybrid_rt_testkit::reference::{direct_lighting, Sun};
    use hybrid_rt_testkit::sdk_scene::{run_frame, SceneOnGpu};
    let host = Host::new().expect("device");
    let (scene, camera) = scenes::room();
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let albedo = |i: u32| [0.2 + 0.05 * (i % 8) as f32, 0.6, 0.4];
    let meshes = MeshBuffers::upload(&host, &scene, &[], &[]).unwrap();
    let targets = Targets::new(&host, W, H).unwrap();
    let mut pass = GBufferPass::new(&host).unwrap();
    let mut lighting = LightingPass::new(&host).unwrap();
    let draws = raster::static_draws(&scene, |i| Material {
        albedo: albedo(i as u32),
        roughness: 0.5,
        metalness: 0.0,
        ..Default::default()
    });
    host.run(|cmd| pass.record(&host, cmd, 0, &targets, &meshes, &draws, &camera, &camera)).unwrap().unwrap();

    // The engine's frame: SDK shadows from its own G-buffer, denoised, then its lighting.
    let ctx = host.create_context(&Default::default()).unwrap();
    let mut frame = ctx.create_task_container();
    let gpu = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    let shadow = host.image_cleared(vk::Format::R32G32_SFLOAT, W, H, usage, vk::ImageLayout::GENERAL).unwrap();
    let visibility = host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, H, usage, vk::ImageLayout::GENERAL).unwrap();
    let lit = LightingPass::lit_image(&host, &targets).unwrap();
    let sun = Sun { to_light: Vec3::new(0.45, 1.0, 0.6), intensity: 2.5 };
    let light = LightInfo { direction: -sun.to_light, ..Default::default() };
    let depth = DepthInput { image: targets.depth.input(raster::READ), depth_type: DepthType::ClipSpace };
    let normals = NormalInput {
        image: targets.normal_roughness.input(raster::READ),
        normal_type: NormalType::RgbVector,
        space: NormalSpace::World,
        ..Default::default()
    };
    let (viewport, sdk_camera) = (Viewport::full(W, H), camera.sdk_camera(W, H));
    let dn = ctx
        .create_denoising_context(&DenoisingContextInput {
            max_width: W,
            max_height: H,
            signal: SignalType::Shadow,
            ..Default::default()
        })
        .unwrap();
    let general = vk::ImageLayout::GENERAL;
    frame
        .schedule_shadow(&TraceShadowTask {
            common: TraceCommon { depth, normals, viewport, camera: sdk_camera, ..Default::default() },
            light,
            output: shadow.input(general),
            rays_per_pixel: 1,
            ..Default::default()
        })
        .unwrap();
    let common = DenoisingCommon { depth, normals, viewport, camera: sdk_camera, ..Default::default() };
    frame
        .schedule_denoise_shadow(&DenoiseShadowTask {
            context: dn,
            common,
            light,
            input: shadow.input(general),
            output: visibility.input(general),
        })
        .unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let lights = Lights {
        sun_direction: sun.to_light,
        sun_intensity: sun.intensity,
        point_position: Vec3::ZERO,
        point_intensity: 0.0,
        ambient: 0.08,
    };
    host.run(|cmd| lighting.record(&host, cmd, 0, &targets, &camera, &lights, &[], Visibility::same(&visibility, general), &lit))
        .unwrap()
        .unwrap();

    let ours = halves(&host.read_image(&lit, general).unwrap());
    let reference = direct_lighting(&tracer, &g, sun, albedo);
    let (mut agree, mut n) = (0, 0);
    for (i, r) in reference.iter().enumerate() {
        if !g.hit[i] {
            continue;
        }
        n += 1;
        // 8-bit albedo and fp16 output: 1% of the value plus a little.
        agree += (0..3).all(|k| (ours[4 * i + k] - r[k]).abs() <= 0.01 * r[k] + 0.01) as u32;
    }
    eprintln!("lit frame: {agree} of {n} pixels agree with the reference");
    // Shadow-edge pixels may differ (the SDK's ray offset vs the reference's).
    assert!(agree as f32 > 0.97 * n as f32, "{agree} of {n}");
    assert!(reference.iter().zip(&g.hit).any(|(r, h)| *h && r[1] < 0.1), "the frame has shadows");
    ctx.destroy_denoising_context(dn).unwrap();
    for i in [shadow, visibility, lit] {
        host.destroy_image(i);
    }
    gpu.destroy(&host);
    drop(ctx);
    lighting.destroy(&host);
    pass.destroy(&host);
    targets.destroy(&host);
    meshes.destroy(&host);
    assert_eq!(Host::validation_errors(), 0, "{:#?}", Host::validation_messages());
}
