//! A build that fails halfway changes nothing. Every frame of a small scene's life (registration
//! with throttled BLAS builds, compactions, surfel layouts and caches arriving, a moved, a
//! removed and a re-registered instance, a refit, a rebuild, cache clears, injection, AO and
//! its denoiser) is built once with an allocation failure injected at each allocation the
//! build makes, in turn: each attempt must fail with `OutOfMemory`, leave the context's whole
//! state (`debug_state_digest`) and the container as they were, and the next attempt then
//! builds the same container. The images of that context, frame by frame, must equal those of
//! a twin context that never failed — bit for bit, since seeds follow the ticket serials and a
//! failed build issues none.
//!
//! The engine's command buffer is never reset: like an engine that records its own passes and
//! the SDK's into one buffer, the test records a command of its own before every attempt and
//! retries in the same buffer, then ends and submits it. A failed build must have recorded
//! nothing there (under validation, a command naming an object the rollback destroyed fails the
//! test), and every command of the engine's must have run.
mod common;
use ash::vk;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::host::{Host, HostBuffer, HostImage};
use hybrid_rt_testkit::reference::{Camera, GBuffer, Mesh, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;

const W: u32 = 48;
const H: u32 = 32;
const FRAMES: usize = 4;

/// A ground plane, three boxes and a deforming quad (allow_update).
fn scene() -> (Scene, Camera) {
    let mut s = Scene::default();
    let ground = s.add_mesh(Mesh::grid(12.0, 2));
    s.add_instance(ground, Affine3A::IDENTITY);
    for i in 0..3 {
        let b = s.add_mesh(Mesh::cuboid(Vec3::splat(0.5)));
        s.add_instance(b, Affine3A::from_translation(Vec3::new(-2.0 + 2.0 * i as f32, 0.5, 0.0)));
    }
    let quad = s.add_mesh(Mesh::quad(1.0));
    s.add_instance(quad, Affine3A::from_translation(Vec3::new(0.0, 1.5, 1.5)));
    (s, Camera::look_at(Vec3::new(0.0, 5.0, 6.0), Vec3::ZERO))
}

/// One context and everything a frame of it needs.
struct World<'h> {
    host: &'h Host,
    ctx: ExecuteContext,
    geometries: Vec<GeometryHandle>,
    instances: Vec<InstanceHandle>,
    buffers: Vec<(HostBuffer, HostBuffer)>,
    images: GBufferImages,
    lit: HostImage,
    /// AO output, also the denoiser's input (so storage and sampled).
    noisy: HostImage,
    denoised: HostImage,
    denoiser: DenoisingContextHandle,
    scene: Scene,
    camera: Camera,
}

impl<'h> World<'h> {
    fn new(host: &'h Host) -> World<'h> {
        let (scene, camera) = scene();
        let ctx = host.create_context(&InitSettings::default()).unwrap();
        let g = GBuffer::render(&Tracer::new(&scene), &camera, W, H);
        let images = GBufferImages::upload(host, &g).unwrap();
        let lit = host
            .image_with_data(vk::Format::R32G32B32A32_SFLOAT, W, H, vk::ImageUsageFlags::SAMPLED, &g.normal_bytes_rgba32f(), READ)
            .unwrap();
        let storage = vk::ImageUsageFlags::STORAGE;
        let noisy = host
            .image_cleared(vk::Format::R32_SFLOAT, W, H, storage | vk::ImageUsageFlags::SAMPLED, vk::ImageLayout::GENERAL)
            .unwrap();
        let denoised = host.image_cleared(vk::Format::R32_SFLOAT, W, H, storage, vk::ImageLayout::GENERAL).unwrap();
        let denoiser = ctx
            .create_denoising_context(&DenoisingContextInput {
                max_width: W,
                max_height: H,
                signal: SignalType::DiffuseOcclusion,
                ..Default::default()
            })
            .unwrap();
        let geometries = ctx.create_geometry_handles(scene.meshes.len());
        let instances = ctx.create_instance_handles(scene.instances.len());
        let usage = vk::BufferUsageFlags::TRANSFER_SRC;
        let buffers = scene
            .meshes
            .iter()
            .map(|m| {
                (
                    host.buffer_with_data(bytemuck::cast_slice(&m.positions), usage).unwrap(),
                    host.buffer_with_data(bytemuck::cast_slice(&m.indices), usage).unwrap(),
                )
            })
            .collect();
        World { host, ctx, geometries, instances, buffers, images, lit, noisy, denoised, denoiser, scene, camera }
    }

    fn geometry_task(&self, i: usize, operation: TaskOperation) -> GeometryTask {
        let (m, (vb, ib)) = (&self.scene.meshes[i], &self.buffers[i]);
        GeometryTask {
            handle: self.geometries[i],
            operation,
            input: GeometryInput {
                vertices: VertexBufferInput { buffer: vb.buffer, count: m.positions.len() as u32, ..Default::default() },
                indices: IndexBufferInput { buffer: ib.buffer, count: m.indices.len() as u32, ..Default::default() },
                allow_update: i == 4,
                surfels: SurfelSettings { tile_unit_length: 0.5, ..Default::default() },
                ..Default::default()
            },
        }
    }

    fn instance_task(&self, i: usize, operation: InstanceOperation, lift: f32) -> InstanceTask {
        let inst = &self.scene.instances[i];
        let transform = Affine3A::from_translation(Vec3::Y * lift) * inst.transform;
        InstanceTask {
            handle: self.instances[i],
            operation,
            input: InstanceInput { geometry: self.geometries[inst.mesh], transform, ..Default::default() },
        }
    }

    /// Frame `f` of the scene's life.
    fn container(&self, f: usize) -> TaskContainer {
        let mut c = self.ctx.create_task_container();
        let n = self.scene.meshes.len();
        match f {
            0 => {
                for i in 0..n {
                    // SAFETY: the engine's buffers the task names are alive.
                    unsafe { c.schedule_geometry(&self.geometry_task(i, TaskOperation::Register)) }.unwrap();
                    c.schedule_instance(&self.instance_task(i, InstanceOperation::Register, 0.0)).unwrap();
                }
            }
            1 => c.schedule_instance(&self.instance_task(1, InstanceOperation::Update, 0.3)).unwrap(),
            2 => {
                // SAFETY: the engine's buffers the task names are alive.
                unsafe { c.schedule_geometry(&self.geometry_task(4, TaskOperation::Update)) }.unwrap();
                c.schedule_instance(&self.instance_task(2, InstanceOperation::Remove, 0.0)).unwrap();
            }
            _ => {
                c.schedule_instance(&self.instance_task(2, InstanceOperation::Register, 0.0)).unwrap();
                // SAFETY: the engine's buffers the task names are alive.
                unsafe { c.schedule_geometry(&self.geometry_task(3, TaskOperation::Update)) }.unwrap();
                c.schedule_clear_cache(&ClearCacheTask { instance: self.instances[0] }).unwrap();
            }
        }
        c.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 2, ..Default::default() }).unwrap();
        if f > 0 {
            c.schedule_direct_lighting_injection(&DirectLightingInjectionTask {
                depth: DepthInput { image: self.images.depth.input(READ), depth_type: DepthType::ClipSpace },
                lit: self.lit.input(READ),
                viewport: Viewport::full(W, H),
                camera: self.camera.sdk_camera(W, H),
                ..Default::default()
            })
            .unwrap();
        }
        let ao = TraceAmbientOcclusionTask {
            output: self.noisy.input(vk::ImageLayout::GENERAL),
            ..self.images.ao_task(&self.camera, 1.0, 2)
        };
        c.schedule_ambient_occlusion(&ao).unwrap();
        c.schedule_denoise_diffuse_occlusion(&DenoiseDiffuseOcclusionTask {
            context: self.denoiser,
            common: self.images.denoising_common(&self.camera),
            input: self.noisy.input(vk::ImageLayout::GENERAL),
            output: self.denoised.input(vk::ImageLayout::GENERAL),
        })
        .unwrap();
        c
    }

    /// Submits a recorded command buffer, hands the ticket back, and reads AO and denoised AO.
    fn finish(&self, cmd: vk::CommandBuffer, ticket: GpuTicket) -> (Vec<f32>, Vec<f32>) {
        self.host.full_barrier(cmd);
        let fence = self.host.submit(cmd).unwrap();
        self.host.wait(fence).unwrap();
        self.ctx.mark_gpu_task_completed(ticket).unwrap();
        let read = |img| self.host.read_image_f32(img, vk::ImageLayout::GENERAL).unwrap();
        (read(&self.noisy), read(&self.denoised))
    }

    fn destroy(self) {
        drop(self.ctx);
        for (v, i) in self.buffers {
            self.host.destroy_buffer(v);
            self.host.destroy_buffer(i);
        }
        self.images.destroy(self.host);
        self.host.destroy_image(self.lit);
        self.host.destroy_image(self.noisy);
        self.host.destroy_image(self.denoised);
    }
}

#[test]
fn a_build_failing_at_any_allocation_changes_nothing() {
    let host = Host::new().expect("a Vulkan device with ray tracing (run scripts/setup.sh)");

    // The twin that never fails.
    let twin = World::new(&host);
    let mut expected = Vec::new();
    for f in 0..FRAMES {
        let mut c = twin.container(f);
        let cmd = host.allocate_command_buffer().unwrap();
        host.begin(cmd).unwrap();
        // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
        let ticket = unsafe { twin.ctx.build_gpu_task(&mut c, cmd) }.unwrap();
        expected.push(twin.finish(cmd, ticket));
    }
    twin.destroy();

    let w = World::new(&host);
    // The engine's own commands: one fill per attempt, each writing its attempt's number.
    const MAX_ATTEMPTS: u64 = 200;
    let engine_marks = host.buffer_with_data(&[0; MAX_ATTEMPTS as usize * 4], vk::BufferUsageFlags::TRANSFER_DST).unwrap();
    let mut failures_per_frame = Vec::new();
    for (f, expected) in expected.iter().enumerate() {
        let mut c = w.container(f);
        let tasks = c.len();
        let cmd = host.allocate_command_buffer().unwrap();
        host.begin(cmd).unwrap();
        let mut failures = 0;
        let ticket = loop {
            let before = w.ctx.debug_state_digest();
            // SAFETY: the buffer holds MAX_ATTEMPTS words; cmd is recording.
            unsafe { host.device.cmd_fill_buffer(cmd, engine_marks.buffer, failures * 4, 4, failures as u32 + 1) };
            w.ctx.inject_allocation_failure(Some(failures));
            // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
            let built = unsafe { w.ctx.build_gpu_task(&mut c, cmd) };
            w.ctx.inject_allocation_failure(None);
            match built {
                Ok(ticket) => break ticket,
                Err(e) => {
                    assert!(matches!(e, Error::OutOfMemory { .. }), "frame {f}, allocation {failures}: {e}");
                    assert_eq!(c.len(), tasks, "frame {f}: the container keeps its tasks");
                    let after = w.ctx.debug_state_digest();
                    assert!(
                        before == after,
                        "frame {f}, failure at allocation {failures} changed the state:\n{}",
                        diff(&before, &after)
                    );
                    // The engine goes on recording into the same buffer and tries again.
                    failures += 1;
                    assert!(failures < MAX_ATTEMPTS, "frame {f}: the build never succeeds");
                }
            }
        };
        failures_per_frame.push(failures);
        let got = w.finish(cmd, ticket);
        assert!(got.0 == expected.0, "frame {f}: AO differs from the twin that never failed");
        assert!(got.1 == expected.1, "frame {f}: denoised AO differs from the twin that never failed");
        let marks: Vec<u32> = engine_marks.mapped_bytes().unwrap()[..(failures as usize + 1) * 4]
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let wanted: Vec<u32> = (1..=failures as u32 + 1).collect();
        assert_eq!(marks, wanted, "frame {f}: the engine's own commands around the failed builds all ran");
        let problems = host.take_validation_problems();
        assert!(problems.is_empty(), "frame {f}: validation after failed builds in the engine's buffer: {problems:?}");
    }
    eprintln!("allocations per frame (each failed once): {failures_per_frame:?}");
    host.destroy_buffer(engine_marks);
    // Registration allocates geometry copies, read-backs, BLASes, scratch, TLAS and the
    // denoiser's nothing; frame 1 the surfel layouts, staging and caches; frames 2-3 BLAS
    // compactions and rebuilds.
    assert!(failures_per_frame[0] >= 10, "registration frame allocates copies, read-backs, BLASes: {failures_per_frame:?}");
    assert!(failures_per_frame.iter().skip(1).all(|&n| n >= 1), "every frame allocates: {failures_per_frame:?}");
    w.destroy();
}

/// The lines of `a` and `b` that differ.
fn diff(a: &str, b: &str) -> String {
    a.lines().zip(b.lines()).filter(|(x, y)| x != y).map(|(x, y)| format!("- {x}\n+ {y}")).collect::<Vec<_>>().join("\n")
}
