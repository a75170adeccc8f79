//! Glue between reference scenes and the SDK: vertex/index buffers in engine memory, handle
//! registration, G-buffer images, and one-frame submission, as an engine would do it.
use crate::host::{Host, HostBuffer, HostImage, HostResult};
use crate::reference::{Camera, GBuffer, Scene};
use ash::vk;
use hybrid_rt::*;

/// A reference scene registered with the SDK. Engine-side buffers are kept until `destroy`.
pub struct SceneOnGpu {
    pub geometries: Vec<GeometryHandle>,
    pub instances: Vec<InstanceHandle>,
    pub buffers: Vec<(HostBuffer, HostBuffer)>,
}

impl SceneOnGpu {
    /// Creates handles and schedules register tasks for every mesh and instance of `scene`.
    pub fn register(host: &Host, ctx: &ExecuteContext, container: &mut TaskContainer, scene: &Scene) -> HostResult<SceneOnGpu> {
        Self::register_with(host, ctx, container, scene, SurfelSettings::default(), [0.0; 3])
    }

    /// `register` with the surfel settings of every geometry and the initial cache colour of
    /// every instance.
    pub fn register_with(
        host: &Host,
        ctx: &ExecuteContext,
        container: &mut TaskContainer,
        scene: &Scene,
        surfels: SurfelSettings,
        initial_tile_color: [f32; 3],
    ) -> HostResult<SceneOnGpu> {
        Self::register_coloured(host, ctx, container, scene, surfels, &vec![initial_tile_color; scene.instances.len()])
    }

    /// `register_with` with one initial cache colour per instance (its cache holds that colour
    /// until something is injected: a known radiance for tests).
    pub fn register_coloured(
        host: &Host,
        ctx: &ExecuteContext,
        container: &mut TaskContainer,
        scene: &Scene,
        surfels: SurfelSettings,
        colours: &[[f32; 3]],
    ) -> HostResult<SceneOnGpu> {
        Self::register_interleaved(host, ctx, container, scene, surfels, colours, 12)
    }

    /// `register_coloured` with the positions interleaved in `vertex_stride`-byte vertices
    /// (position first, then zeroed attributes), as an engine's vertex buffer holds them.
    pub fn register_interleaved(
        host: &Host,
        ctx: &ExecuteContext,
        container: &mut TaskContainer,
        scene: &Scene,
        surfels: SurfelSettings,
        colours: &[[f32; 3]],
        vertex_stride: u64,
    ) -> HostResult<SceneOnGpu> {
        let geometries = ctx.create_geometry_handles(scene.meshes.len());
        let mut buffers = Vec::new();
        for (mesh, &handle) in scene.meshes.iter().zip(&geometries) {
            let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::VERTEX_BUFFER;
            let words = (vertex_stride / 4).max(3) as usize;
            let mut vertices = vec![0.0f32; mesh.positions.len() * words];
            for (v, p) in vertices.chunks_mut(words).zip(&mesh.positions) {
                v[..3].copy_from_slice(&p.to_array());
            }
            let vb = host.buffer_with_data(bytemuck::cast_slice(&vertices), usage)?;
            let ib = host.buffer_with_data(bytemuck::cast_slice(&mesh.indices), usage | vk::BufferUsageFlags::INDEX_BUFFER)?;
            let input = GeometryInput {
                vertices: VertexBufferInput {
                    buffer: vb.buffer,
                    count: mesh.positions.len() as u32,
                    stride: words as u64 * 4,
                    ..Default::default()
                },
                indices: IndexBufferInput { buffer: ib.buffer, count: mesh.indices.len() as u32, ..Default::default() },
                surfels,
                ..Default::default()
            };
            // SAFETY: the buffers were just made and live in `SceneOnGpu` until it is destroyed.
            unsafe { container.schedule_geometry(&GeometryTask { handle, operation: TaskOperation::Register, input }) }
                .map_err(|e| e.to_string())?;
            buffers.push((vb, ib));
        }
        let instances = ctx.create_instance_handles(scene.instances.len());
        for ((inst, &handle), &initial_tile_color) in scene.instances.iter().zip(&instances).zip(colours) {
            let input = InstanceInput {
                geometry: geometries[inst.mesh],
                transform: inst.transform,
                initial_tile_color,
                ..Default::default()
            };
            container
                .schedule_instance(&InstanceTask { handle, operation: InstanceOperation::Register, input })
                .map_err(|e| e.to_string())?;
        }
        Ok(SceneOnGpu { geometries, instances, buffers })
    }

    pub fn destroy(self, host: &Host) {
        for (v, i) in self.buffers {
            host.destroy_buffer(v);
            host.destroy_buffer(i);
        }
    }
}

/// Depth, normals and an AO output image for a reference G-buffer.
pub struct GBufferImages {
    pub depth: HostImage,
    pub normals: HostImage,
    pub output: HostImage,
    pub width: u32,
    pub height: u32,
}

pub const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

impl GBufferImages {
    pub fn upload(host: &Host, g: &GBuffer) -> HostResult<GBufferImages> {
        let sampled = vk::ImageUsageFlags::SAMPLED;
        let depth = host.image_with_data(vk::Format::R32_SFLOAT, g.width, g.height, sampled, &g.depth_bytes(), READ)?;
        let normals =
            host.image_with_data(vk::Format::R32G32B32A32_SFLOAT, g.width, g.height, sampled, &g.normal_bytes_rgba32f(), READ)?;
        let output = host.image_cleared(
            vk::Format::R32_SFLOAT,
            g.width,
            g.height,
            vk::ImageUsageFlags::STORAGE,
            vk::ImageLayout::GENERAL,
        )?;
        Ok(GBufferImages { depth, normals, output, width: g.width, height: g.height })
    }

    pub fn trace_common(&self, camera: &Camera) -> TraceCommon {
        TraceCommon {
            depth: DepthInput { image: self.depth.input(READ), depth_type: DepthType::ClipSpace },
            normals: NormalInput {
                image: self.normals.input(READ),
                normal_type: NormalType::RgbVector,
                space: NormalSpace::World,
                ..Default::default()
            },
            viewport: Viewport::full(self.width, self.height),
            camera: camera.sdk_camera(self.width, self.height),
            ..Default::default()
        }
    }

    pub fn ao_task(&self, camera: &Camera, ray_length: f32, rays_per_pixel: u32) -> TraceAmbientOcclusionTask {
        TraceAmbientOcclusionTask {
            common: self.trace_common(camera),
            output: self.output.input(vk::ImageLayout::GENERAL),
            ray_length,
            rays_per_pixel,
            ..Default::default()
        }
    }

    /// The denoisers' common inputs for this G-buffer (no motion vectors: the cameras
    /// reproject).
    pub fn denoising_common(&self, camera: &Camera) -> DenoisingCommon {
        let t = self.trace_common(camera);
        DenoisingCommon { depth: t.depth, normals: t.normals, viewport: t.viewport, camera: t.camera, ..Default::default() }
    }

    pub fn read_output(&self, host: &Host) -> HostResult<Vec<f32>> {
        host.read_image_f32(&self.output, vk::ImageLayout::GENERAL)
    }

    pub fn destroy(self, host: &Host) {
        host.destroy_image(self.depth);
        host.destroy_image(self.normals);
        host.destroy_image(self.output);
    }
}

/// Records `container` into a fresh command buffer, submits, waits, and hands the ticket back.
pub fn run_frame(host: &Host, ctx: &ExecuteContext, container: &mut TaskContainer) -> Result<CompletedTask, String> {
    let cmd = host.allocate_command_buffer()?;
    host.begin(cmd)?;
    host.full_barrier(cmd);
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = match unsafe { ctx.build_gpu_task(container, cmd) } {
        Ok(t) => t,
        Err(e) => {
            // Leave the command buffer submittable-free: end it and drop it.
            unsafe {
                let _ = host.device.end_command_buffer(cmd);
            }
            return Err(e.to_string());
        }
    };
    host.full_barrier(cmd);
    let fence = host.submit(cmd)?;
    host.wait(fence)?;
    ctx.mark_gpu_task_completed(ticket).map_err(|e| e.to_string())
}

/// Gives `schedule` a fresh `width` x `height` RGBA32F storage image (GENERAL) to write, runs
/// the container in one frame, and reads the image back: the tests' way to see one task's
/// output.
pub fn render_rgba(
    host: &Host,
    ctx: &ExecuteContext,
    container: &mut TaskContainer,
    (width, height): (u32, u32),
    schedule: impl FnOnce(&mut TaskContainer, ImageInput) -> Result<(), String>,
) -> HostResult<Vec<[f32; 4]>> {
    let out = host.image_cleared(
        vk::Format::R32G32B32A32_SFLOAT,
        width,
        height,
        vk::ImageUsageFlags::STORAGE,
        vk::ImageLayout::GENERAL,
    )?;
    let ran = schedule(container, out.input(vk::ImageLayout::GENERAL)).and_then(|()| run_frame(host, ctx, container).map(|_| ()));
    let bytes = ran.and_then(|()| host.read_image(&out, vk::ImageLayout::GENERAL));
    host.destroy_image(out);
    Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes?).to_vec())
}

/// A debug visualisation (`mode`) of `camera`'s view of `images` (through an AO task).
#[allow(clippy::too_many_arguments)]
pub fn debug_view(
    host: &Host,
    ctx: &ExecuteContext,
    container: &mut TaskContainer,
    images: &GBufferImages,
    camera: &Camera,
    mode: DebugOutput,
    bilinear: bool,
    size: (u32, u32),
) -> HostResult<Vec<[f32; 4]>> {
    render_rgba(host, ctx, container, size, |c, output| {
        let mut task = images.ao_task(camera, 1.0, 1);
        task.common.debug_output = mode;
        task.common.enable_bilinear_sampling = bilinear;
        task.output = output;
        c.schedule_ambient_occlusion(&task).map_err(|e| e.to_string())
    })
}
