//! Soak: 2,000 frames of an engine's life at tiny resolution — geometries, instances and
//! denoising contexts created, moved, updated and destroyed at random every frame, three frames
//! in flight with each ticket handed back two frames late — and the SDK's memory stays flat:
//! no per-frame growth across the run, and once everything is destroyed and every ticket is
//! back, exactly what a fresh context holds. Validation (sync included) must stay silent.
//!
//! Ignored in the debug suite; `.ci/run` runs it in release: `cargo test --release -p
//! hybrid-rt-testkit --test soak -- --ignored`.
mod common;
use ash::vk;
use glam::{Affine3A, Quat, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostBuffer, HostImage};
use hybrid_rt_testkit::reference::{Camera, GBuffer, Mesh, Rng, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;
use std::collections::VecDeque;

const FRAMES: usize = 2000;
const S: u32 = 16;
const MAX_GEOMETRIES: usize = 12;
const MAX_INSTANCES: usize = 24;
const MAX_DENOISERS: usize = 3;

struct Shape {
    mesh: Mesh,
    vertices: HostBuffer,
    indices: HostBuffer,
}

struct Live {
    geometry: GeometryHandle,
    shape: usize,
    deforming: bool,
}

#[test]
#[ignore = "soak: .ci/run runs it in release (cargo test --release -p hybrid-rt-testkit --test soak -- --ignored)"]
fn two_thousand_frames_of_churn_keep_memory_flat() {
    let host = Host::new().expect("a Vulkan device with ray tracing (run scripts/setup.sh)");
    let ctx = host.create_context(&InitSettings { supported_working_sets: 3, ..Default::default() }).unwrap();
    let fresh = ctx.resource_allocations();
    let usage = vk::BufferUsageFlags::TRANSFER_SRC;
    let shapes: Vec<Shape> = [Mesh::cuboid(Vec3::splat(0.3)), Mesh::grid(1.0, 3), Mesh::quad(0.8)]
        .into_iter()
        .map(|mesh| Shape {
            vertices: host.buffer_with_data(bytemuck::cast_slice(&mesh.positions), usage).unwrap(),
            indices: host.buffer_with_data(bytemuck::cast_slice(&mesh.indices), usage).unwrap(),
            mesh,
        })
        .collect();

    // The engine's G-buffer: a ground plane seen from above (the SDK's scene changes under it).
    let mut ground = Scene::default();
    let g = ground.add_mesh(Mesh::grid(8.0, 1));
    ground.add_instance(g, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 5.0, 0.01), Vec3::ZERO);
    let gbuffer = GBuffer::render(&Tracer::new(&ground), &camera, S, S);
    let images = GBufferImages::upload(&host, &gbuffer).unwrap();
    let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
    let noisy: HostImage = host.image_cleared(vk::Format::R32_SFLOAT, S, S, storage, vk::ImageLayout::GENERAL).unwrap();

    let mut rng = Rng::new(7);
    let mut pick = |n: usize| ((rng.next_f32() * n as f32) as usize).min(n.saturating_sub(1));
    let mut geometries: Vec<Live> = Vec::new();
    let mut instances: Vec<(InstanceHandle, usize)> = Vec::new(); // (handle, index into geometries)
    let mut denoisers: Vec<DenoisingContextHandle> = Vec::new();
    let mut in_flight: VecDeque<(GpuTicket, vk::Fence, vk::CommandBuffer)> = VecDeque::new();
    let mut frame = ctx.create_task_container();
    let mut totals = Vec::with_capacity(FRAMES);
    let retire = |in_flight: &mut VecDeque<(GpuTicket, vk::Fence, vk::CommandBuffer)>| {
        let (ticket, fence, cmd) = in_flight.pop_front().unwrap();
        host.wait(fence).unwrap();
        ctx.mark_gpu_task_completed(ticket).unwrap();
        host.free_command_buffer(cmd);
    };

    for f in 0..FRAMES {
        let t = f as f32 * 0.05;
        let geometry_input = |shape: &Shape, deforming: bool| GeometryInput {
            vertices: VertexBufferInput {
                buffer: shape.vertices.buffer,
                count: shape.mesh.positions.len() as u32,
                ..Default::default()
            },
            indices: IndexBufferInput {
                buffer: shape.indices.buffer,
                count: shape.mesh.indices.len() as u32,
                ..Default::default()
            },
            allow_update: deforming,
            surfels: SurfelSettings { tile_unit_length: 0.25, ..Default::default() },
            ..Default::default()
        };
        // Destructions first, while this frame's container is still empty (a destroyed handle
        // must not be named by a task scheduled before it): an instance, a geometry with its
        // instances, a denoiser (with tickets in flight).
        if pick(4) == 0 && !instances.is_empty() {
            let (h, _) = instances.swap_remove(pick(instances.len()));
            ctx.destroy_instance_handles(&[h]).unwrap();
        }
        if pick(10) == 0 && geometries.len() > 2 {
            let k = pick(geometries.len());
            let mine: Vec<InstanceHandle> = instances.iter().filter(|(_, g)| *g == k).map(|(h, _)| *h).collect();
            ctx.destroy_instance_handles(&mine).unwrap();
            instances.retain(|(_, g)| *g != k);
            for (_, g) in instances.iter_mut() {
                if *g > k {
                    *g -= 1;
                }
            }
            ctx.destroy_geometry_handles(&[geometries.remove(k).geometry]).unwrap();
        }
        if pick(20) == 0 && !denoisers.is_empty() {
            ctx.destroy_denoising_context(denoisers.swap_remove(pick(denoisers.len()))).unwrap();
        }
        // Geometries come, and are updated.
        match pick(10) {
            0 | 1 if geometries.len() < MAX_GEOMETRIES => {
                let shape = pick(shapes.len());
                let deforming = pick(3) == 0;
                let h = ctx.create_geometry_handles(1)[0];
                let input = geometry_input(&shapes[shape], deforming);
                // SAFETY: the engine's buffers the task names are alive.
                unsafe { frame.schedule_geometry(&GeometryTask { handle: h, operation: TaskOperation::Register, input }) }
                    .unwrap();
                geometries.push(Live { geometry: h, shape, deforming });
            }
            3 if !geometries.is_empty() => {
                // An update: a refit for deforming geometry, a queued rebuild otherwise.
                let g = &geometries[pick(geometries.len())];
                let input = geometry_input(&shapes[g.shape], g.deforming);
                // SAFETY: the engine's buffers the task names are alive.
                unsafe { frame.schedule_geometry(&GeometryTask { handle: g.geometry, operation: TaskOperation::Update, input }) }
                    .unwrap();
            }
            _ => {}
        }
        // Instances: registered and moved.
        for _ in 0..3 {
            if geometries.is_empty() {
                break;
            }
            let place = |k: usize| {
                Affine3A::from_rotation_translation(
                    Quat::from_rotation_y(t + k as f32),
                    Vec3::new((k % 5) as f32 - 2.0, 0.3, (k / 5) as f32 - 2.0),
                )
            };
            match pick(3) {
                0 if instances.len() < MAX_INSTANCES => {
                    let g = pick(geometries.len());
                    let h = ctx.create_instance_handles(1)[0];
                    let input = InstanceInput {
                        geometry: geometries[g].geometry,
                        transform: place(instances.len()),
                        ..Default::default()
                    };
                    frame.schedule_instance(&InstanceTask { handle: h, operation: InstanceOperation::Register, input }).unwrap();
                    instances.push((h, g));
                }
                1 if !instances.is_empty() => {
                    let k = pick(instances.len());
                    let (h, g) = instances[k];
                    let input = InstanceInput { geometry: geometries[g].geometry, transform: place(k), ..Default::default() };
                    frame.schedule_instance(&InstanceTask { handle: h, operation: InstanceOperation::Update, input }).unwrap();
                }
                _ => {}
            }
        }
        if pick(20) == 0 && denoisers.len() < MAX_DENOISERS {
            denoisers.push(
                ctx.create_denoising_context(&DenoisingContextInput {
                    max_width: S,
                    max_height: S,
                    signal: SignalType::DiffuseOcclusion,
                    ..Default::default()
                })
                .unwrap(),
            );
        }
        frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 2, ..Default::default() }).unwrap();
        frame
            .schedule_ambient_occlusion(&TraceAmbientOcclusionTask {
                output: noisy.input(vk::ImageLayout::GENERAL),
                ..images.ao_task(&camera, 1.0, 1)
            })
            .unwrap();
        if let Some(&dn) = denoisers.get(f % denoisers.len().max(1)) {
            frame
                .schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask {
                    context: dn,
                    common: images.denoising_common(&camera),
                    input: noisy.input(vk::ImageLayout::GENERAL),
                    output: images.output.input(vk::ImageLayout::GENERAL),
                })
                .unwrap();
        }
        // Three frames in flight: the ticket of frame f - 2 is handed back now.
        if in_flight.len() == 3 {
            retire(&mut in_flight);
        }
        let cmd = host.allocate_command_buffer().unwrap();
        host.begin(cmd).unwrap();
        host.full_barrier(cmd);
        // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
        let ticket = unsafe { ctx.build_gpu_task(&mut frame, cmd) }.unwrap_or_else(|e| panic!("frame {f}: {e}"));
        host.full_barrier(cmd);
        in_flight.push_back((ticket, host.submit(cmd).unwrap(), cmd));
        totals.push(ctx.resource_allocations().total_bytes());
    }
    while !in_flight.is_empty() {
        retire(&mut in_flight);
    }

    // No growth: the second half of the run never needs more than the first half did.
    let (first, second) = totals[200..].split_at((FRAMES - 200) / 2);
    let (max1, max2) = (first.iter().max().unwrap(), second.iter().max().unwrap());
    eprintln!("SDK memory: fresh {} B, peak {max1} B (frames 200-1100), {max2} B (1100-2000)", fresh.total_bytes());
    assert!(*max2 <= max1 + max1 / 20, "memory grows: peak {max1} then {max2}");
    let ao = host.read_image_f32(&noisy, vk::ImageLayout::GENERAL).unwrap();
    assert!(ao.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)), "AO stays in [0, 1]");

    // Everything destroyed and every ticket back: exactly what a fresh context holds (the
    // rings, scratch and query pools a working set keeps are reused, not grown per frame).
    ctx.destroy_all_instance_handles();
    ctx.destroy_geometry_handles(&geometries.iter().map(|g| g.geometry).collect::<Vec<_>>()).unwrap();
    for dn in denoisers {
        ctx.destroy_denoising_context(dn).unwrap();
    }
    ctx.release_device_resources_immediately().unwrap();
    let end = ctx.resource_allocations();
    for (what, a, b) in [
        ("geometry copies", end.geometry_copies, fresh.geometry_copies),
        ("BLASes", end.blas, fresh.blas),
        ("caches", end.cache, fresh.cache),
        ("denoisers", end.denoiser, fresh.denoiser),
    ] {
        assert_eq!(a.count, b.count, "{what} left behind: {a:?}");
    }
    assert!(
        end.readback.count <= fresh.readback.count + 3,
        "read-backs left: {:?} (a working set keeps its index counters)",
        end.readback
    );
    drop(ctx);
    host.destroy_image(noisy);
    images.destroy(&host);
    for s in shapes {
        host.destroy_buffer(s.vertices);
        host.destroy_buffer(s.indices);
    }
}
