//! Engine mesh layouts: the same sphere registered the ways engines hold meshes — tightly
//! packed with 32-bit indices; interleaved 32-byte vertices with the position at byte 8 and
//! 16-bit indices at an unaligned offset of a shared buffer; non-indexed; split into two parts
//! with a transform; and a vertex range of a larger shared buffer — traces the same AO image,
//! which matches the CPU reference. The SDK keeps the same compact copy for all of them (12
//! bytes per vertex whatever the engine's stride).
mod common;
use ash::vk;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostBuffer};
use hybrid_rt_testkit::reference::{reference_ao, sphere_on_plane, AoParams, GBuffer, Mesh, Tracer};
use hybrid_rt_testkit::sdk_scene::*;
use hybrid_rt_testkit::stats;

const W: u32 = 48;
const H: u32 = 48;
const RAYS: u32 = 16;

/// Engine buffers of one layout, kept alive until the geometry's ticket is back.
struct Layout {
    name: &'static str,
    input: GeometryInput,
    buffers: Vec<HostBuffer>,
}

fn buffer(host: &Host, bytes: &[u8]) -> HostBuffer {
    host.buffer_with_data(bytes, vk::BufferUsageFlags::TRANSFER_SRC).unwrap()
}

fn f32s(v: &[f32]) -> Vec<u8> {
    bytemuck::cast_slice(v).to_vec()
}

/// (a) Tightly packed RGB32F positions, R32 indices, offset 0.
fn packed(host: &Host, m: &Mesh) -> Layout {
    let vb = buffer(host, bytemuck::cast_slice(&m.positions));
    let ib = buffer(host, bytemuck::cast_slice(&m.indices));
    let input = GeometryInput {
        vertices: VertexBufferInput { buffer: vb.buffer, count: m.positions.len() as u32, ..Default::default() },
        indices: IndexBufferInput { buffer: ib.buffer, count: m.indices.len() as u32, ..Default::default() },
        ..Default::default()
    };
    Layout { name: "packed R32", input, buffers: vec![vb, ib] }
}

/// (b) 32-byte interleaved vertices (uv at 0, position at 8, a normal-ish tail) in a buffer
/// that starts with 64 bytes of another mesh, and R16 indices 6 bytes into a shared buffer.
fn interleaved(host: &Host, m: &Mesh) -> Layout {
    let mut v = vec![-7.0f32; 16]; // someone else's data
    for p in &m.positions {
        v.extend([0.25, 0.75, p.x, p.y, p.z, 9.0, 9.0, 9.0]);
    }
    let vb = buffer(host, &f32s(&v));
    let mut ix: Vec<u16> = vec![0xdead, 0xbeef, 0xffff]; // 6 bytes of another mesh's indices
    ix.extend(m.indices.iter().map(|&i| i as u16));
    let ib = buffer(host, bytemuck::cast_slice(&ix));
    let input = GeometryInput {
        vertices: VertexBufferInput {
            buffer: vb.buffer,
            offset: 64 + 8,
            stride: 32,
            count: m.positions.len() as u32,
            ..Default::default()
        },
        indices: IndexBufferInput { buffer: ib.buffer, offset: 6, count: m.indices.len() as u32, format: vk::Format::R16_UINT },
        build_hint: BuildHint::PreferFastBuild,
        ..Default::default()
    };
    Layout { name: "interleaved stride 32 + R16 at offset 6, fast build", input, buffers: vec![vb, ib] }
}

/// (c) Non-indexed: three RGBA32F vertices per triangle.
fn non_indexed(host: &Host, m: &Mesh) -> Layout {
    let v: Vec<f32> = m.indices.iter().flat_map(|&i| m.positions[i as usize].extend(1.0).to_array()).collect();
    let vb = buffer(host, &f32s(&v));
    let input = GeometryInput {
        vertices: VertexBufferInput {
            buffer: vb.buffer,
            stride: 16,
            count: m.indices.len() as u32,
            format: vk::Format::R32G32B32A32_SFLOAT,
            ..Default::default()
        },
        build_hint: BuildHint::PreferNone,
        ..Default::default()
    };
    // No preference flag: the driver's trade-off, compacted (static).
    assert_eq!(input.build_hint.build_flags(false, false), vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION);
    Layout { name: "non-indexed RGBA32F, no build preference", input, buffers: vec![vb] }
}

/// (d) Two parts: the first half of the triangles as is, the second half stored 10 units up
/// and rotated, with a transform that puts it back.
fn two_parts(host: &Host, m: &Mesh) -> Layout {
    let half = m.indices.len() / 6 * 3;
    let stored = Affine3A::from_rotation_translation(glam::Quat::from_rotation_y(1.0), Vec3::new(0.0, 10.0, 0.0));
    let back = stored.inverse();
    let moved: Vec<Vec3> = m.positions.iter().map(|&p| stored.transform_point3(p)).collect();
    let vb0 = buffer(host, bytemuck::cast_slice(&m.positions));
    let ib0 = buffer(host, bytemuck::cast_slice(&m.indices[..half]));
    let vb1 = buffer(host, bytemuck::cast_slice(&moved));
    let ib1 = buffer(host, bytemuck::cast_slice(&m.indices[half..]));
    let count = m.positions.len() as u32;
    let input = GeometryInput {
        vertices: VertexBufferInput { buffer: vb0.buffer, count, ..Default::default() },
        indices: IndexBufferInput { buffer: ib0.buffer, count: half as u32, ..Default::default() },
        extra_components: vec![GeometryComponent {
            vertices: VertexBufferInput { buffer: vb1.buffer, count, ..Default::default() },
            indices: IndexBufferInput { buffer: ib1.buffer, count: (m.indices.len() - half) as u32, ..Default::default() },
            transform: Some(back),
            vertex_range: None,
            uvs: None,
            colors: None,
        }],
        ..Default::default()
    };
    Layout { name: "two parts, one transformed", input, buffers: vec![vb0, ib0, vb1, ib1] }
}

/// (e) The sphere's vertices at 500.. of a 2,000-vertex shared buffer, its indices relative to
/// the buffer's start, and a vertex range: only its own vertices are copied.
fn vertex_range(host: &Host, m: &Mesh) -> Layout {
    let first = 500u32;
    let mut v = vec![Vec3::splat(1.0e6); 2000];
    v[first as usize..first as usize + m.positions.len()].copy_from_slice(&m.positions);
    let vb = buffer(host, bytemuck::cast_slice(&v));
    let ix: Vec<u32> = m.indices.iter().map(|&i| i + first).collect();
    let ib = buffer(host, bytemuck::cast_slice(&ix));
    let input = GeometryInput {
        vertices: VertexBufferInput { buffer: vb.buffer, count: v.len() as u32, ..Default::default() },
        indices: IndexBufferInput { buffer: ib.buffer, count: ix.len() as u32, ..Default::default() },
        vertex_range: Some(VertexRange { first, last: first + m.positions.len() as u32 - 1 }),
        build_hint: BuildHint::LowMemory,
        ..Default::default()
    };
    Layout { name: "vertex range of a shared buffer, low memory", input, buffers: vec![vb, ib] }
}

#[test]
fn every_engine_layout_traces_the_same_ao() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let (scene, camera) = sphere_on_plane();
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let sphere = &scene.meshes[scene.instances[1].mesh];
    let sphere_at = scene.instances[1].transform;

    // The plane as the test kit registers it; the sphere's instance is placed on each layout in
    // turn.
    let plane_only = {
        let mut s = hybrid_rt_testkit::reference::Scene::default();
        let m = s.add_mesh(scene.meshes[scene.instances[0].mesh].clone());
        s.add_instance(m, scene.instances[0].transform);
        s
    };
    let mut frame = ctx.create_task_container();
    let plane = SceneOnGpu::register(&host, &ctx, &mut frame, &plane_only).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let layouts = [
        packed(&host, sphere),
        interleaved(&host, sphere),
        non_indexed(&host, sphere),
        two_parts(&host, sphere),
        vertex_range(&host, sphere),
    ];
    let geometries = ctx.create_geometry_handles(layouts.len());
    let instance = ctx.create_instance_handles(1)[0];
    let mut copy_bytes = Vec::new();
    for (l, &h) in layouts.iter().zip(&geometries) {
        let before = ctx.resource_allocations().geometry_copies.bytes;
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { frame.schedule_geometry(&GeometryTask { handle: h, input: l.input.clone(), ..Default::default() }) }.unwrap();
        frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 8, ..Default::default() }).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        copy_bytes.push(ctx.resource_allocations().geometry_copies.bytes - before);
        assert_eq!(ctx.geometry_invalid_triangles(h).unwrap(), 0, "{}: no bad triangles", l.name);
    }
    let images = GBufferImages::upload(&host, &g).unwrap();
    let mut images_by_layout = Vec::new();
    for (k, (l, &h)) in layouts.iter().zip(&geometries).enumerate() {
        let operation = if k == 0 { InstanceOperation::Register } else { InstanceOperation::Update };
        let input = InstanceInput { geometry: h, transform: sphere_at, ..Default::default() };
        frame.schedule_instance(&InstanceTask { handle: instance, operation, input }).unwrap();
        frame.schedule_bvh_build(&Default::default()).unwrap();
        frame.set_frame_index(7); // the same rays for every layout
        frame.schedule_ambient_occlusion(&images.ao_task(&camera, 1.0, RAYS)).unwrap();
        run_frame(&host, &ctx, &mut frame).unwrap();
        images_by_layout.push((l.name, images.read_output(&host).unwrap()));
    }

    // The same compact copy whatever the layout: 12 bytes per vertex and per triangle (the
    // non-indexed sphere has three vertices per triangle; the split one its vertices twice).
    let (v, t) = (sphere.positions.len() as u64, sphere.triangle_count() as u64);
    let expected = [12 * (v + t), 12 * (v + t), 12 * (3 * t + t), 12 * (2 * v + t), 12 * (v + t)];
    for ((l, bytes), want) in layouts.iter().zip(&copy_bytes).zip(expected) {
        assert!(*bytes >= want && *bytes < want + 256, "{}: copy of {bytes} bytes, {want} expected (compact)", l.name);
    }

    // Every layout: the reference's AO within sampling error, and the packed layout's image
    // within rounding (the transformed part's positions differ in the last bits).
    let params = AoParams { ray_length: 1.0, falloff_power: 1.0, ray_offset: RayOffset::default() };
    let strata = 16;
    let reference = reference_ao(&tracer, &g, camera.eye, &params, strata);
    let sigma = stats::sample_sigma(RAYS, strata * strata);
    let packed_image = images_by_layout[0].1.clone();
    for (name, image) in &images_by_layout {
        let report = stats::compare_blocks(image, &reference, W, H, 8, sigma, 0.01);
        let same = image.iter().zip(&packed_image).filter(|(a, b)| (*a - *b).abs() < 1e-4).count();
        eprintln!(
            "{name}: worst block error {:.4} (tolerance {:.4}); {same}/{} pixels equal to the packed layout's",
            report.worst_block_error,
            report.tolerance,
            image.len()
        );
        assert!(report.worst_block_error <= report.tolerance, "{name} against the reference");
        assert!(same as f32 >= 0.99 * image.len() as f32, "{name}: the same rays give the same image");
    }
    assert!(reference.iter().cloned().fold(1.0, f32::min) < 0.5, "the contact shadow is there");

    images.destroy(&host);
    plane.destroy(&host);
    for l in layouts {
        for b in l.buffers {
            host.destroy_buffer(b);
        }
    }
    drop(frame);
    drop(ctx);
    assert_no_validation_errors();
}

/// Bad input in a part is refused with the part named, and an index outside a vertex range is
/// a bad triangle (degenerate, counted), never a read outside the range.
#[test]
fn parts_and_ranges_are_checked() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let m = Mesh::grid(1.0, 1);
    let good = packed(&host, &m);
    let h = ctx.create_geometry_handles(1)[0];
    let mut frame = ctx.create_task_container();
    let with = |input: GeometryInput| GeometryTask { handle: h, input, ..Default::default() };
    let message = |e: Error| e.to_string();

    let bad_part = GeometryComponent { vertices: VertexBufferInput { stride: 6, ..good.input.vertices }, ..Default::default() };
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe { frame.schedule_geometry(&with(GeometryInput { extra_components: vec![bad_part], ..good.input.clone() })) }
        .unwrap_err();
    let text = message(e);
    assert!(text.contains("part 0") && text.contains("stride"), "{text}");
    let range = Some(VertexRange { first: 2, last: 9 });
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe { frame.schedule_geometry(&with(GeometryInput { vertex_range: range, ..good.input.clone() })) }.unwrap_err();
    assert!(message(e).contains("vertex range"));
    let nan = Some(Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)));
    // SAFETY: the engine's buffers the task names are alive.
    let e = unsafe { frame.schedule_geometry(&with(GeometryInput { transform: nan, ..good.input.clone() })) }.unwrap_err();
    assert!(matches!(e, Error::InvalidTransform { .. }));
    assert!(frame.is_empty());

    // The grid's 4 vertices with a range of the first 3: the triangle using vertex 3 is bad.
    let range = Some(VertexRange { first: 0, last: 2 });
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { frame.schedule_geometry(&with(GeometryInput { vertex_range: range, ..good.input.clone() })) }.unwrap();
    frame.schedule_bvh_build(&Default::default()).unwrap();
    run_frame(&host, &ctx, &mut frame).unwrap();
    let uses_last = m.indices.chunks(3).filter(|t| t.contains(&3)).count() as u32;
    assert_eq!(ctx.geometry_invalid_triangles(h).unwrap(), uses_last);

    // A named geometry is quoted in the errors about it.
    ctx.set_geometry_name(h, "grid").unwrap();
    // SAFETY: the engine's buffers the task names are alive.
    unsafe { frame.schedule_geometry(&with(good.input.clone())) }.unwrap();
    let e = run_frame(&host, &ctx, &mut frame).unwrap_err();
    assert!(e.contains("\"grid\"") && e.contains("already registered"), "{e}");
    frame.clear();
    for b in good.buffers {
        host.destroy_buffer(b);
    }
    drop(frame);
    drop(ctx);
    assert_no_validation_errors();
}
