//! Alpha-tested geometry: a quad with a checker alpha texture (an 8 x 8 grate: every other
//! cell a hole) above a floor must cast the shadows, occlude the AO and show in the reflections
//! exactly as the same grate modelled as geometry — the opaque cells as 32 small quads — does.
//! The shadow is also compared with the CPU reference (hard sun: one ray, binary), and the
//! inline ray-query path (its candidate loop) with the any-hit path.
//!
//! The texture's cells and the modelled cells share their edges, so the two can differ only
//! where a ray crosses the grate within float rounding of an edge: a few pixels.
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostBuffer, HostImage};
use hybrid_rt_testkit::reference::{self, Camera, GBuffer, Mesh, Rng, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 64;
const H: u32 = 64;
const GRATE_Y: f32 = 0.6;
const HALF: f32 = 0.8;
const CELLS: u32 = 8;
const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;
const RED: [f32; 3] = [1.0, 0.0, 0.0];

fn opaque_cell(i: u32, j: u32) -> bool {
    (i + j) & 1 == 0
}

/// The grate's opaque cells as geometry (facing +Y, as Mesh::grid).
fn cells() -> Mesh {
    let mut m = Mesh::default();
    let size = 2.0 * HALF / CELLS as f32;
    for j in 0..CELLS {
        for i in 0..CELLS {
            if !opaque_cell(i, j) {
                continue;
            }
            let (x0, z0) = (-HALF + i as f32 * size, -HALF + j as f32 * size);
            let base = m.positions.len() as u32;
            m.positions.extend([
                Vec3::new(x0, GRATE_Y, z0),
                Vec3::new(x0 + size, GRATE_Y, z0),
                Vec3::new(x0 + size, GRATE_Y, z0 + size),
                Vec3::new(x0, GRATE_Y, z0 + size),
            ]);
            m.indices.extend([base, base + 2, base + 1, base, base + 3, base + 2]);
        }
    }
    m
}

fn floor() -> Mesh {
    Mesh::grid(8.0, 2)
}

fn camera() -> Camera {
    Camera::look_at(Vec3::new(0.4, 2.4, 2.2), Vec3::new(0.0, 0.0, 0.0))
}

/// The grate as an engine has it: one quad, positions and texture coordinates interleaved in
/// 20-byte vertices, 16-bit indices, an RGBA8 texture whose A is the checker.
struct Grate {
    vertices: HostBuffer,
    indices: HostBuffer,
    texture: HostImage,
    /// The same texture coordinates as R16G16_UNORM in a buffer of their own.
    uv16: HostBuffer,
}

impl Grate {
    fn new(host: &Host) -> Grate {
        let corners = [(-HALF, -HALF), (HALF, -HALF), (HALF, HALF), (-HALF, HALF)];
        let mut v = Vec::new();
        for (x, z) in corners {
            v.extend([x, GRATE_Y, z, (x + HALF) / (2.0 * HALF), (z + HALF) / (2.0 * HALF)]);
        }
        let usage = vk::BufferUsageFlags::TRANSFER_SRC;
        let vertices = host.buffer_with_data(bytemuck::cast_slice(&v), usage).unwrap();
        let indices = host.buffer_with_data(bytemuck::cast_slice(&[0u16, 2, 1, 0, 3, 2]), usage).unwrap();
        let uv16: Vec<u16> =
            v.chunks(5).flat_map(|c| [(c[3] * 65535.0).round() as u16, (c[4] * 65535.0).round() as u16]).collect();
        let uv16 = host.buffer_with_data(bytemuck::cast_slice(&uv16), usage).unwrap();
        let mut texels = Vec::new();
        for j in 0..CELLS {
            for i in 0..CELLS {
                texels.extend([128u8, 128, 128, if opaque_cell(i, j) { 255 } else { 0 }]);
            }
        }
        let texture =
            host.image_with_data(vk::Format::R8G8B8A8_UNORM, CELLS, CELLS, vk::ImageUsageFlags::SAMPLED, &texels, READ).unwrap();
        Grate { vertices, indices, texture, uv16 }
    }

    fn input(&self) -> GeometryInput {
        GeometryInput {
            vertices: VertexBufferInput { buffer: self.vertices.buffer, stride: 20, count: 4, ..Default::default() },
            indices: IndexBufferInput {
                buffer: self.indices.buffer,
                count: 6,
                format: vk::Format::R16_UINT,
                ..Default::default()
            },
            uvs: Some(VertexBufferInput {
                buffer: self.vertices.buffer,
                offset: 12,
                stride: 20,
                count: 4,
                format: vk::Format::R32G32_SFLOAT,
            }),
            alpha_test: Some(AlphaTestInput { texture: self.texture.input(READ), ..Default::default() }),
            ..Default::default()
        }
    }

    /// `input` with the R16G16_UNORM texture coordinates.
    fn input_unorm16(&self) -> GeometryInput {
        let uvs = VertexBufferInput {
            buffer: self.uv16.buffer,
            stride: 4,
            count: 4,
            format: vk::Format::R16G16_UNORM,
            ..Default::default()
        };
        GeometryInput { uvs: Some(uvs), ..self.input() }
    }

    fn destroy(self, host: &Host) {
        host.destroy_buffer(self.uv16);
        host.destroy_buffer(self.vertices);
        host.destroy_buffer(self.indices);
        host.destroy_image(self.texture);
    }
}

/// One context's outputs, all traced in its second ticket.
struct Images {
    shadow: Vec<f32>,
    ao: Vec<f32>,
    mirror: Vec<[f32; 4]>,
    ao_inline: Vec<f32>,
    mirror_inline: Vec<[f32; 4]>,
}

/// How the grate is registered.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// Its opaque cells as geometry.
    Modelled,
    /// One alpha-tested quad, f32 texture coordinates interleaved with the positions.
    Cut,
    /// The same with R16G16_UNORM texture coordinates in a buffer of their own.
    CutUnorm16,
}

/// Registers the floor and the grate, then traces everything from the same G-buffer, in
/// tickets numbered alike (so with the same random numbers in every context).
fn trace(kind: Kind, g: &GBuffer, sun: LightInfo) -> Images {
    let alpha = kind != Kind::Modelled;
    let (host, ctx) = host_and_context(InitSettings::default());
    if alpha {
        eprintln!(
            "inline ray queries: {}",
            if ctx.supports_inline_rt() { "yes (candidate loop tested)" } else { "no (pipeline twice)" }
        );
    }
    let mut scene = Scene::default();
    let f = scene.add_mesh(floor());
    scene.add_instance(f, Affine3A::IDENTITY);
    if !alpha {
        let c = scene.add_mesh(cells());
        scene.add_instance(c, Affine3A::IDENTITY);
    }
    let mut frame = ctx.create_task_container();
    let gpu_scene = SceneOnGpu::register_coloured(&host, &ctx, &mut frame, &scene, Default::default(), &[[0.0; 3], RED]).unwrap();
    let grate = Grate::new(&host);
    if alpha {
        let gh = ctx.create_geometry_handles(1)[0];
        let input = if kind == Kind::Cut { grate.input() } else { grate.input_unorm16() };
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { frame.schedule_geometry(&GeometryTask { handle: gh, operation: TaskOperation::Register, input }) }.unwrap();
        let ih = ctx.create_instance_handles(1)[0];
        let input = InstanceInput { geometry: gh, initial_tile_color: RED, ..Default::default() };
        frame.schedule_instance(&InstanceTask { handle: ih, operation: InstanceOperation::Register, input }).unwrap();
    }
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();

    let images = GBufferImages::upload(&host, g).unwrap();
    let cam = camera();
    let target = |format| host.image_cleared(format, W, H, vk::ImageUsageFlags::STORAGE, GENERAL).unwrap();
    let outs: Vec<HostImage> = vec![
        target(vk::Format::R32G32_SFLOAT),
        target(vk::Format::R32_SFLOAT),
        target(vk::Format::R32G32B32A32_SFLOAT),
        target(vk::Format::R32_SFLOAT),
        target(vk::Format::R32G32B32A32_SFLOAT),
    ];
    let common = images.trace_common(&cam);
    frame.schedule_shadow(&TraceShadowTask { common, light: sun, output: outs[0].input(GENERAL), ..Default::default() }).unwrap();
    for (inline, ao_out, mirror_out) in [(false, &outs[1], &outs[2]), (true, &outs[3], &outs[4])] {
        let mut c = common;
        c.use_inline_rt = inline;
        frame
            .schedule_ambient_occlusion(&TraceAmbientOcclusionTask {
                common: c,
                output: ao_out.input(GENERAL),
                ray_length: 1.0,
                rays_per_pixel: 8,
                ..Default::default()
            })
            .unwrap();
        c.roughness.global_roughness = 0.0;
        frame
            .schedule_specular(&TraceSpecularTask {
                common: c,
                output: mirror_out.input(GENERAL),
                ray_length: 100.0,
                miss_radiance: [0.0, 0.0, 1.0],
                ..Default::default()
            })
            .unwrap();
    }
    run_frame(&host, &ctx, &mut frame).unwrap();
    let rg: Vec<[f32; 2]> = bytemuck::cast_slice(&host.read_image(&outs[0], GENERAL).unwrap()).to_vec();
    let rgba = |i: &HostImage| -> Vec<[f32; 4]> { bytemuck::cast_slice(&host.read_image(i, GENERAL).unwrap()).to_vec() };
    let result = Images {
        shadow: rg.iter().map(|t| t[1]).collect(),
        ao: host.read_image_f32(&outs[1], GENERAL).unwrap(),
        mirror: rgba(&outs[2]),
        ao_inline: host.read_image_f32(&outs[3], GENERAL).unwrap(),
        mirror_inline: rgba(&outs[4]),
    };
    for o in outs {
        host.destroy_image(o);
    }
    images.destroy(&host);
    grate.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
    result
}

/// Fraction of pixels where two images differ by more than `tolerance` (any channel).
fn differing(a: &[f32], b: &[f32], tolerance: f32) -> f32 {
    a.iter().zip(b).filter(|(x, y)| (*x - *y).abs() > tolerance).count() as f32 / a.len() as f32
}

fn flat(v: &[[f32; 4]]) -> Vec<f32> {
    v.iter().flat_map(|t| [t[0], t[1], t[2]]).collect()
}

#[test]
fn a_cut_out_grate_shadows_occludes_and_reflects_like_its_geometry() {
    let mut scene = Scene::default();
    let f = scene.add_mesh(floor());
    scene.add_instance(f, Affine3A::IDENTITY);
    let c = scene.add_mesh(cells());
    scene.add_instance(c, Affine3A::IDENTITY);
    let tracer = Tracer::new(&scene);
    let cam = camera();
    let g = GBuffer::render(&tracer, &cam, W, H);
    let sun = LightInfo { light_type: LightType::Directional, direction: Vec3::new(0.35, -1.0, 0.25), ..Default::default() };

    let cut = trace(Kind::Cut, &g, sun);
    let modelled = trace(Kind::Modelled, &g, sun);
    let unorm16 = trace(Kind::CutUnorm16, &g, sun);
    // 16-bit unorm texture coordinates of 0 and 1 are exact: the same images.
    assert!(unorm16.shadow == cut.shadow && unorm16.ao == cut.ao, "R16G16_UNORM texture coordinates trace alike");

    // Shadows against the CPU reference (a hard sun: one ray per pixel, binary).
    let mut rng = Rng::new(3);
    let reference: Vec<f32> = (0..g.depth.len())
        .map(|i| {
            if !g.hit[i] {
                return 1.0;
            }
            reference::shadow_visibility(&tracer, g.position[i], g.normal[i], cam.eye, &sun, &RayOffset::default(), 1, &mut rng).0
        })
        .collect();
    let floor_px: Vec<usize> = (0..g.depth.len()).filter(|&i| g.hit[i] && g.instance[i] == 0).collect();
    let shadowed = floor_px.iter().filter(|&&i| reference[i] < 0.5).count();
    assert!(shadowed > 200 && shadowed < floor_px.len() - 200, "the grate shadows part of the floor ({shadowed} px)");
    let vs_reference = differing(&cut.shadow, &reference, 0.5);
    let vs_geometry = differing(&cut.shadow, &modelled.shadow, 0.5);
    eprintln!(
        "shadow: {shadowed} floor pixels in the reference's shadow; the cut-out differs from the reference in {:.2}%, from the modelled grate in {:.2}%",
        vs_reference * 100.0,
        vs_geometry * 100.0
    );
    // ~1.5% of the pixels lie within a pixel of a shadow edge of the 8x8 checker.
    assert!(vs_reference < 0.02 && vs_geometry < 0.02, "the cut-out casts the grate's shadow");

    // AO and mirror reflections: the cut-out against the modelled grate, and the inline path
    // against the any-hit path.
    for (what, a, b, tolerance, limit) in [
        ("AO (any-hit vs geometry)", cut.ao.clone(), modelled.ao.clone(), 0.13, 0.03),
        ("AO (inline vs any-hit)", cut.ao_inline.clone(), cut.ao.clone(), 1e-4, 0.01),
        ("mirror (any-hit vs geometry)", flat(&cut.mirror), flat(&modelled.mirror), 0.5, 0.02),
        ("mirror (inline vs any-hit)", flat(&cut.mirror_inline), flat(&cut.mirror), 1e-4, 0.01),
    ] {
        let d = differing(&a, &b, tolerance);
        eprintln!("{what}: {:.2}% of values differ by more than {tolerance}", d * 100.0);
        assert!(d < limit, "{what}: {d}");
    }
    // The reflections see both the grate's red cells and the sky through its holes.
    let red = cut.mirror.iter().filter(|t| t[0] > 0.5 && t[2] < 0.5).count();
    let sky_through = cut.mirror.iter().zip(&g.instance).filter(|(t, inst)| **inst == 0 && t[2] > 0.5).count();
    assert!(red > 100 && sky_through > 100, "red cells {red}, sky through the holes {sky_through}");
}

#[test]
fn bad_alpha_inputs_are_refused() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let grate = Grate::new(&host);
    let mut frame = ctx.create_task_container();
    let handle = ctx.create_geometry_handles(1)[0];
    let good = grate.input();
    let schedule = |frame: &mut TaskContainer, input: GeometryInput| {
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { frame.schedule_geometry(&GeometryTask { handle, operation: TaskOperation::Register, input }) }
    };
    schedule(&mut frame, good.clone()).unwrap();
    frame.clear();
    let mut bad = good.clone();
    bad.uvs = None;
    assert!(schedule(&mut frame, bad).is_err(), "alpha testing needs texture coordinates");
    let mut bad = good.clone();
    bad.alpha_test = None;
    assert!(schedule(&mut frame, bad).is_err(), "texture coordinates without alpha testing");
    let mut bad = good.clone();
    bad.uvs.as_mut().unwrap().format = vk::Format::R8G8_UNORM;
    assert!(matches!(schedule(&mut frame, bad), Err(Error::UnsupportedFormat { .. })));
    let mut bad = good.clone();
    bad.uvs.as_mut().unwrap().count = 3;
    assert!(schedule(&mut frame, bad).is_err(), "fewer texture coordinates than vertices");
    let mut bad = good.clone();
    bad.uvs.as_mut().unwrap().offset = 1 << 20;
    assert!(schedule(&mut frame, bad).is_err(), "texture coordinates past the buffer's end");
    for cutoff in [f32::NAN, -0.1, 1.5] {
        let mut bad = good.clone();
        bad.alpha_test.as_mut().unwrap().cutoff = cutoff;
        assert!(schedule(&mut frame, bad).is_err(), "cutoff {cutoff}");
    }
    let mut bad = good.clone();
    bad.alpha_test.as_mut().unwrap().texture.format = vk::Format::R32_UINT;
    assert!(matches!(schedule(&mut frame, bad), Err(Error::UnsupportedFormat { .. })));
    let mut bad = good.clone();
    bad.alpha_test.as_mut().unwrap().texture.usage = vk::ImageUsageFlags::STORAGE;
    assert!(schedule(&mut frame, bad).is_err(), "a texture without SAMPLED usage");
    let mut bad = good.clone();
    let a = bad.alpha_test.as_mut().unwrap();
    a.texture.format = vk::Format::R8_UNORM;
    a.channel = 3;
    assert!(schedule(&mut frame, bad).is_err(), "channel A of a one-channel format");
    assert!(frame.is_empty());
    grate.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
