//! The sections before any trace: context creation, the BLAS build of one big mesh beside the
//! driver floor, the field's BLAS builds in one frame, the TLAS alone.
use crate::blas_floor::BlasFloor;
use crate::timing::{median, warm_up};
use crate::{sdk, Bench, Field};
use hybrid_rt::{
    BuildHint, BvhBuildTask, GeometryInput, GeometryTask, IndexBufferInput, InitSettings, InstanceInput, InstanceOperation,
    InstanceTask, SurfelSettings, SurfelType, TaskKind, TaskOperation, VertexBufferInput,
};
use hybrid_rt_host::scene::Mesh;
use hybrid_rt_host::Host;
use hybrid_rt_samples::scenes;
use hybrid_rt_testkit::reference::{GBuffer, Tracer};
use hybrid_rt_testkit::sdk_scene::{run_frame, GBufferImages, SceneOnGpu};
use serde_json::json;
use std::time::Instant;

/// Milliseconds to create a context with an empty pipeline cache and with the data that left
/// in it, and the cache's size.
pub struct ContextCreation {
    cold_ms: f64,
    warm_ms: f64,
    cache_bytes: usize,
}

/// Context creation, cold (an empty pipeline cache) and warm (the cache saved by the cold
/// one, as an engine reloads it on its next run).
pub fn context_creation(host: &Host) -> Result<ContextCreation, String> {
    let d = &host.device;
    let e = |e: ash::vk::Result| format!("pipeline cache: {e:?}");
    let empty = unsafe { d.create_pipeline_cache(&ash::vk::PipelineCacheCreateInfo::default(), None) }.map_err(e)?;
    let t = std::time::Instant::now();
    drop(host.create_context(&InitSettings { pipeline_cache: empty, ..Default::default() }).map_err(sdk)?);
    let cold_ms = t.elapsed().as_secs_f64() * 1e3;
    let data = unsafe { d.get_pipeline_cache_data(empty) }.map_err(e)?;
    let warm_cache =
        unsafe { d.create_pipeline_cache(&ash::vk::PipelineCacheCreateInfo::default().initial_data(&data), None) }.map_err(e)?;
    let t = std::time::Instant::now();
    drop(host.create_context(&InitSettings { pipeline_cache: warm_cache, ..Default::default() }).map_err(sdk)?);
    let warm_ms = t.elapsed().as_secs_f64() * 1e3;
    unsafe {
        d.destroy_pipeline_cache(empty, None);
        d.destroy_pipeline_cache(warm_cache, None);
    }
    Ok(ContextCreation { cold_ms, warm_ms, cache_bytes: data.len() })
}

/// Medians of one registration setting's frames: the BLAS interval, the frame's BVH work, the
/// compaction in the next frame, the driver floor.
struct Registration {
    blas_ms: f64,
    bvh_ms: f64,
    compaction_ms: f64,
    floor_ms: f64,
}

impl Bench<'_> {
    /// The rows of context creation and of the engine's vertex layout.
    pub fn context_creation_rows(&mut self, c: &ContextCreation) {
        let r = &mut self.report;
        r.row(
            "Context creation (every pipeline), cold / warm pipeline cache",
            format!("{:.1} ms / {:.1} ms ({} KiB of cache)", c.cold_ms, c.warm_ms, c.cache_bytes / 1024),
        );
        r.key("context_creation_cold_ms", json!(c.cold_ms));
        r.key("context_creation_warm_ms", json!(c.warm_ms));
        let stride = self.settings.vertex_stride;
        r.row("Engine vertex layout", format!("positions in {stride}-byte vertices"));
        r.key("vertex_stride", json!(stride));
    }

    /// One big mesh: the registration frame's BLAS build with each surfel layout (both sized
    /// on the GPU), and with the fast-build hints (what a level streaming in would ask for),
    /// each beside the driver alone on the same triangles (see blas_floor). Returns the floor:
    /// its builds warm the clocks for the field's frame.
    pub fn big_mesh_blas(&mut self) -> Result<BlasFloor, String> {
        let host = self.host;
        let n = ((self.settings.big_mesh_triangles as f64 / 2.0).sqrt().ceil() as u32).max(1);
        let mesh = Mesh::grid(100.0, n);
        let usage = ash::vk::BufferUsageFlags::TRANSFER_SRC;
        // In device memory, as an engine keeps a static mesh (on the H200 the registration frame
        // measured the same from host-visible memory: 8.75 ms).
        let vb = host.device_buffer_with_data(bytemuck::cast_slice(&mesh.positions), usage)?;
        let ib = host.device_buffer_with_data(bytemuck::cast_slice(&mesh.indices), usage)?;
        let mut floor = BlasFloor::new(host, &mesh.positions, &mesh.indices)?;
        for (surfel_type, build_hint, what, key) in [
            (SurfelType::MeshColors, BuildHint::Auto, "mesh-colors layout sized on the GPU", "blas_big_mesh"),
            (SurfelType::Tiles, BuildHint::Auto, "tiles layout sized on the GPU", "blas_big_mesh_tiles"),
            (SurfelType::Tiles, BuildHint::PreferFastBuild, "tiles, PreferFastBuild", "blas_big_mesh_tiles_fast_build"),
            (SurfelType::Tiles, BuildHint::FastThenTrace, "tiles, FastThenTrace's first build", "blas_big_mesh_fast_then_trace"),
        ] {
            let input = GeometryInput {
                vertices: VertexBufferInput { buffer: vb.buffer, count: mesh.positions.len() as u32, ..Default::default() },
                indices: IndexBufferInput { buffer: ib.buffer, count: mesh.indices.len() as u32, ..Default::default() },
                surfels: SurfelSettings { surfel_type, ..Default::default() },
                build_hint,
                ..Default::default()
            };
            let Registration { blas_ms, bvh_ms, compaction_ms, floor_ms } = self.registrations(&mut floor, input)?;
            let triangles = mesh.triangle_count();
            let rate = triangles as f64 / (blas_ms * 1e-3);
            self.report.row(
                format!("BLAS build, 1 mesh of {triangles} triangles ({what})"),
                format!(
                    "{blas_ms:.3} ms ({:.1} M tri/s); floor {floor_ms:.3} ms ({:.1} M tri/s); the frame's BVH work {bvh_ms:.3} ms; compaction, next frame {compaction_ms:.3} ms",
                    rate / 1e6,
                    triangles as f64 / (floor_ms * 1e-3) / 1e6
                ),
            );
            self.report.key(
                key,
                json!({"triangles": triangles, "gpu_ms": blas_ms, "floor_gpu_ms": floor_ms, "bvh_ms": bvh_ms, "compaction_ms": compaction_ms, "triangles_per_s": rate}),
            );
        }
        host.destroy_buffer(vb);
        host.destroy_buffer(ib);
        Ok(floor)
    }

    /// Registers `input` as a new geometry 6 times (a registration, then updates), each frame
    /// beside a floor build with the flags the SDK builds this hint's first BLAS of static
    /// geometry with: medians of the last 4, after a warm-up (clocks ramp up over hundreds of
    /// milliseconds of load).
    fn registrations(&mut self, floor: &mut BlasFloor, input: GeometryInput) -> Result<Registration, String> {
        let host = self.host;
        let geo = self.ctx.create_geometry_handles(1)[0];
        let flags = input.build_hint.build_flags(false, true);
        warm_up(self.settings.warmup, || floor.build(host, flags).map(drop))?;
        let (mut blas, mut bvh, mut compaction, mut floor_ms) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..6 {
            let operation = if i == 0 { TaskOperation::Register } else { TaskOperation::Update };
            // SAFETY: the engine's buffers the task names are alive.
            unsafe { self.frame.schedule_geometry(&GeometryTask { handle: geo, operation, input: input.clone() }) }
                .map_err(sdk)?;
            self.frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 1, ..Default::default() }).map_err(sdk)?;
            let done = run_frame(host, self.ctx, &mut self.frame)?;
            // The compaction of a fast-trace build happens in the next build's frame (its size
            // is read when this ticket is back): give it a frame of its own, so the measured
            // frame is the registration's alone, as an engine's first frame with the mesh.
            self.frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 0, ..Default::default() }).map_err(sdk)?;
            let compacted = run_frame(host, self.ctx, &mut self.frame)?;
            let floor_build = floor.build(host, flags)?;
            if i >= 2 {
                floor_ms.push(floor_build);
                blas.push(done.gpu_ms(TaskKind::BlasBuild));
                bvh.push(done.gpu_ms(TaskKind::Bvh));
                compaction.push(compacted.gpu_ms(TaskKind::BlasBuild));
            }
        }
        self.ctx.destroy_geometry_handles(&[geo]).map_err(sdk)?;
        Ok(Registration {
            blas_ms: median(blas),
            bvh_ms: median(bvh),
            compaction_ms: median(compaction),
            floor_ms: median(floor_ms),
        })
    }

    /// The field: its scene and CPU G-buffer, registered with every BLAS built in one frame
    /// (after the floor's builds warm the clocks; the floor goes then). Returns the field and
    /// that first frame's BVH time, which also pays for first use of fresh memory.
    pub fn field(&mut self, mut floor: BlasFloor) -> Result<(Field, f64), String> {
        let host = self.host;
        let s = &self.settings;
        let t0 = Instant::now();
        let (scene, camera) = scenes::field(s.triangles, s.instances);
        let tracer = Tracer::new(&scene);
        let g = GBuffer::render(&tracer, &camera, s.width, s.height);
        println!(
            "scene: {} triangles in {} instances (G-buffer on the CPU in {:.1} s)",
            scene.triangle_count(),
            scene.instances.len(),
            t0.elapsed().as_secs_f64()
        );
        let gbuffer = GBufferImages::upload(host, &g)?;
        let surfels = SurfelSettings { tile_unit_length: s.tile_unit_length, ..Default::default() };
        let colours = vec![[0.0; 3]; scene.instances.len()];
        let gpu = SceneOnGpu::register_interleaved(host, self.ctx, &mut self.frame, &scene, surfels, &colours, s.vertex_stride)?;
        self.frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: u32::MAX, ..Default::default() }).map_err(sdk)?;
        // Warm clocks for this frame too (the floor's builds keep the GPU busy until it starts).
        warm_up(s.warmup, || floor.build(host, BuildHint::Auto.build_flags(false, true)).map(drop))?;
        floor.destroy(host);
        let first_ms = run_frame(host, self.ctx, &mut self.frame)?.gpu_ms(TaskKind::Bvh);
        Ok((Field { scene, camera, gbuffer, gpu }, first_ms))
    }

    /// The field's BLAS builds in one frame, steady state: every BLAS rebuilt again (static
    /// geometry: an update queues a rebuild), median of 3 frames.
    pub fn field_blas(&mut self, field: &Field, first_ms: f64) -> Result<(), String> {
        let (scene, gpu) = (&field.scene, &field.gpu);
        let mut rebuild = Vec::new();
        let mut rebuild_blas = Vec::new();
        for _ in 0..3 {
            for (mesh, &handle) in scene.meshes.iter().zip(&gpu.geometries) {
                let (vb, ib) = &gpu.buffers[gpu.geometries.iter().position(|h| *h == handle).unwrap()];
                // The same engine layout as the registration (an update re-reads the engine's buffer).
                let stride = self.settings.vertex_stride.max(12).next_multiple_of(4);
                let input = GeometryInput {
                    vertices: VertexBufferInput {
                        buffer: vb.buffer,
                        count: mesh.positions.len() as u32,
                        stride,
                        ..Default::default()
                    },
                    indices: IndexBufferInput { buffer: ib.buffer, count: mesh.indices.len() as u32, ..Default::default() },
                    ..Default::default()
                };
                // SAFETY: the engine's buffers the task names are alive.
                unsafe { self.frame.schedule_geometry(&GeometryTask { handle, operation: TaskOperation::Update, input }) }
                    .map_err(sdk)?;
            }
            self.frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: u32::MAX, ..Default::default() }).map_err(sdk)?;
            let done = run_frame(self.host, self.ctx, &mut self.frame)?;
            rebuild.push(done.gpu_ms(TaskKind::Bvh));
            rebuild_blas.push(done.gpu_ms(TaskKind::BlasBuild));
        }
        let field_ms = median(rebuild);
        let field_blas_ms = median(rebuild_blas);
        let field_rate = scene.triangle_count() as f64 / (field_ms * 1e-3);
        self.report.row(
            format!("BLAS builds, {} meshes, {} triangles, one frame", scene.instances.len(), scene.triangle_count()),
            format!(
                "{field_ms:.3} ms ({:.1} M tri/s); BLAS builds alone {field_blas_ms:.3} ms; first frame {first_ms:.3} ms",
                field_rate / 1e6
            ),
        );
        self.report.key(
            "blas_field",
            json!({
                "meshes": scene.instances.len(),
                "triangles": scene.triangle_count(),
                "gpu_ms": field_ms,
                "first_frame_gpu_ms": first_ms,
                "blas_builds_gpu_ms": field_blas_ms,
                "triangles_per_s": field_rate,
            }),
        );
        Ok(())
    }

    /// The TLAS rebuilt alone: one instance moved back and forth, no BLAS work; and the CPU
    /// time of recording that frame.
    pub fn tlas(&mut self, field: &Field) -> Result<(), String> {
        let (scene, gpu) = (&field.scene, &field.gpu);
        let mut tlas_ms = Vec::new();
        let mut record_us = Vec::new();
        for i in 0..self.settings.frames {
            let inst = &scene.instances[1];
            let nudge = glam::Affine3A::from_translation(glam::Vec3::new(0.0, (i % 2) as f32 * 1e-3, 0.0));
            self.frame
                .schedule_instance(&InstanceTask {
                    handle: gpu.instances[1],
                    operation: InstanceOperation::Update,
                    input: InstanceInput {
                        geometry: gpu.geometries[inst.mesh],
                        transform: nudge * inst.transform,
                        ..Default::default()
                    },
                })
                .map_err(sdk)?;
            self.frame.schedule_bvh_build(&BvhBuildTask { max_blas_build_count: 0, ..Default::default() }).map_err(sdk)?;
            let (done, cpu_us) = self.recorded_frame()?;
            record_us.push(cpu_us);
            tlas_ms.push(done.gpu_ms(TaskKind::Bvh));
        }
        let tlas_ms = median(tlas_ms);
        let tlas_record_us = median(record_us);
        self.report.row(format!("TLAS build, {} instances", scene.instances.len()), format!("{tlas_ms:.3} ms"));
        self.report.row("build_gpu_task CPU, instance update + TLAS", format!("{tlas_record_us:.1} us"));
        self.report
            .key("tlas", json!({"instances": scene.instances.len(), "gpu_ms": tlas_ms, "build_gpu_task_cpu_us": tlas_record_us}));
        Ok(())
    }
}
