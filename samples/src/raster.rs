//! The sample's own rasterizer: what an engine already has before it meets hybrid-rt. One
//! graphics pass (dynamic rendering) writes a G-buffer — hardware depth, world normal +
//! roughness, albedo + metalness, screen-space motion in pixels — that the SDK then reads as
//! its `DepthInput`, `NormalInput`, `RoughnessInput` and `MotionInput`.
use crate::gpu::{self, spirv, UploadSlots};
use ash::vk;
use glam::{Affine3A, Mat4, Vec3};
use hybrid_rt_testkit::host::{Host, HostBuffer, HostImage, HostResult};
use hybrid_rt_testkit::reference::{Camera, Scene};

pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
pub const NORMAL_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
pub const MOTION_FORMAT: vk::Format = vk::Format::R16G16_SFLOAT;
/// The layout the targets are left in after a pass, ready for the SDK to sample.
pub const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

/// A surface's material in the G-buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub albedo: [f32; 3],
    pub roughness: f32,
    pub metalness: f32,
}

/// `Instance` in shaders/sample/gbuffer_common.glsl (std430).
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct InstanceGpu {
    model: [f32; 16],
    prev_model: [f32; 16],
    material: [f32; 4],
    extra: [f32; 4],
}

/// `Camera` in shaders/sample/gbuffer_common.glsl (std140).
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct CameraGpu {
    view_proj: [f32; 16],
    prev_view_proj: [f32; 16],
    eye: [f32; 4],
    viewport: [f32; 4],
}

/// The G-buffer images of one view.
pub struct Targets {
    pub depth: HostImage,
    pub normal_roughness: HostImage,
    pub albedo_metalness: HostImage,
    pub motion: HostImage,
    pub width: u32,
    pub height: u32,
}

impl Targets {
    pub fn new(host: &Host, width: u32, height: u32) -> HostResult<Targets> {
        let sampled = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        let color = sampled | vk::ImageUsageFlags::COLOR_ATTACHMENT;
        Ok(Targets {
            depth: host.create_image(DEPTH_FORMAT, width, height, sampled | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?,
            normal_roughness: host.create_image(NORMAL_FORMAT, width, height, color)?,
            albedo_metalness: host.create_image(ALBEDO_FORMAT, width, height, color)?,
            motion: host.create_image(MOTION_FORMAT, width, height, color)?,
            width,
            height,
        })
    }

    fn colors(&self) -> [&HostImage; 3] {
        [&self.normal_roughness, &self.albedo_metalness, &self.motion]
    }

    pub fn destroy(self, host: &Host) {
        for i in [self.depth, self.normal_roughness, self.albedo_metalness, self.motion] {
            host.destroy_image(i);
        }
    }
}

/// Vertex and index buffers of every mesh of a scene, in engine memory.
pub struct MeshBuffers {
    /// Vertex buffer, index buffer, index count, vertex count.
    meshes: Vec<(HostBuffer, HostBuffer, u32, u32)>,
    /// Base-colour textures: a white texel first (what untextured draws sample), then the
    /// scene's (`Draw::albedo_texture` k is image k + 1).
    textures: Vec<HostImage>,
    sampler: vk::Sampler,
}

/// Bytes per vertex: a position, a shading normal (RGB32F each) and a texture coordinate
/// (RG32F), interleaved. The SDK reads the positions out of the same buffer
/// (`VertexBufferInput::stride`), as an engine's.
pub const VERTEX_STRIDE: u32 = 32;

/// Interleaves positions, normals and texture coordinates (one each per vertex) into
/// vertices. Vertices past the normals' end get a zero normal, which the G-buffer pass shades
/// flat (the triangle's plane, as the CPU reference does); past the coordinates' end, (0, 0).
pub fn interleave(positions: &[Vec3], normals: &[Vec3], uvs: &[[f32; 2]]) -> Vec<[f32; 8]> {
    let normals = normals.iter().chain(std::iter::repeat(&Vec3::ZERO));
    let uvs = uvs.iter().chain(std::iter::repeat(&[0.0; 2]));
    positions.iter().zip(normals).zip(uvs).map(|((p, n), t)| [p.x, p.y, p.z, n.x, n.y, n.z, t[0], t[1]]).collect()
}

/// A base-colour texture: sRGB-encoded RGBA8 texels, row by row.
#[derive(Clone, Debug, Default)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl MeshBuffers {
    /// Vertex buffers are drawn and copied by the SDK into its BLAS inputs.
    pub const VERTEX_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
        vk::BufferUsageFlags::VERTEX_BUFFER.as_raw() | vk::BufferUsageFlags::TRANSFER_SRC.as_raw(),
    );

    /// `normals` and `uvs`: one list per mesh, one entry per vertex (no normals: flat shading;
    /// no coordinates: (0, 0)); `textures`: the scene's base-colour textures.
    pub fn upload(
        host: &Host,
        scene: &Scene,
        normals: &[Vec<Vec3>],
        uvs: &[Vec<[f32; 2]>],
        textures: &[Texture],
    ) -> HostResult<MeshBuffers> {
        let mut meshes = Vec::new();
        for (k, m) in scene.meshes.iter().enumerate() {
            let vertices = interleave(
                &m.positions,
                normals.get(k).map_or(&[][..], |n| n.as_slice()),
                uvs.get(k).map_or(&[][..], |t| t.as_slice()),
            );
            let vb = host.buffer_with_data(bytemuck::cast_slice(&vertices), Self::VERTEX_USAGE)?;
            let ib_usage = vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
            let ib = host.buffer_with_data(bytemuck::cast_slice(&m.indices), ib_usage)?;
            meshes.push((vb, ib, m.indices.len() as u32, m.positions.len() as u32));
        }
        let white = Texture { width: 1, height: 1, rgba: vec![255; 4] };
        let mut images = Vec::new();
        for t in std::iter::once(&white).chain(textures) {
            if t.width == 0 || t.height == 0 || t.rgba.len() as u64 != t.width as u64 * t.height as u64 * 4 {
                return Err(format!("a {}x{} texture with {} bytes", t.width, t.height, t.rgba.len()));
            }
            let usage = vk::ImageUsageFlags::SAMPLED;
            images.push(host.image_with_data(vk::Format::R8G8B8A8_SRGB, t.width, t.height, usage, &t.rgba, READ)?);
        }
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(vk::SamplerAddressMode::REPEAT)
            .address_mode_w(vk::SamplerAddressMode::REPEAT);
        // SAFETY: plain object creation; destroyed in `destroy`.
        let sampler = unsafe { host.device.create_sampler(&info, None) }.map_err(|e| format!("sampler: {e:?}"))?;
        Ok(MeshBuffers { meshes, textures: images, sampler })
    }

    /// Scene texture `k` as an SDK input (an alpha-tested geometry's cut-out), if it exists.
    pub fn texture_input(&self, k: usize) -> Option<hybrid_rt::ImageInput> {
        self.textures.get(k + 1).map(|t| t.input(READ))
    }

    /// Mesh `i`'s texture coordinates inside its vertices, for an alpha-tested geometry.
    pub fn uv_input(&self, i: usize) -> hybrid_rt::VertexBufferInput {
        let (vb, _, _, vertex_count) = &self.meshes[i];
        hybrid_rt::VertexBufferInput {
            buffer: vb.buffer,
            offset: 24,
            stride: VERTEX_STRIDE as u64,
            count: *vertex_count,
            format: vk::Format::R32G32_SFLOAT,
        }
    }

    /// The texture a draw samples (white without one, or with an index past the scene's).
    fn albedo(&self, texture: Option<usize>) -> &HostImage {
        texture.and_then(|k| self.textures.get(k + 1)).unwrap_or(&self.textures[0])
    }

    /// The SDK's view of mesh `i`: the same buffers the rasterizer draws (RGB32F positions
    /// interleaved with normals, u32 indices).
    pub fn geometry_input(&self, i: usize) -> hybrid_rt::GeometryInput {
        let (vb, ib, index_count, vertex_count) = &self.meshes[i];
        hybrid_rt::GeometryInput {
            vertices: hybrid_rt::VertexBufferInput {
                buffer: vb.buffer,
                count: *vertex_count,
                stride: VERTEX_STRIDE as u64,
                ..Default::default()
            },
            indices: hybrid_rt::IndexBufferInput { buffer: ib.buffer, count: *index_count, ..Default::default() },
            ..Default::default()
        }
    }

    pub fn destroy(self, host: &Host) {
        for (v, i, _, _) in self.meshes {
            host.destroy_buffer(v);
            host.destroy_buffer(i);
        }
        for t in self.textures {
            host.destroy_image(t);
        }
        // SAFETY: the frames that sampled with it are finished (the caller's rule).
        unsafe { host.device.destroy_sampler(self.sampler, None) };
    }
}

/// One object to draw: a mesh of the scene, its transform now and last frame, its material.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub mesh: usize,
    pub transform: Affine3A,
    pub prev_transform: Affine3A,
    pub material: Material,
    /// Vertices to draw instead of the mesh's own (a deforming mesh's of this frame).
    pub vertex_buffer: Option<vk::Buffer>,
    /// Base-colour texture (an index into the scene's), multiplied into the albedo.
    pub albedo_texture: Option<usize>,
    /// Alpha-tested: fragments whose texture alpha is below this are holes (0: opaque).
    pub alpha_cutoff: f32,
}

/// The G-buffer pass: one pipeline, push descriptors for the camera and the instance table.
pub struct GBufferPass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    push: ash::khr::push_descriptor::Device,
    cameras: UploadSlots,
    instances: UploadSlots,
}

impl GBufferPass {
    pub fn new(host: &Host) -> HostResult<GBufferPass> {
        let d = &host.device;
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let bindings = [
            vk::DescriptorSetLayoutBinding::default()
                .binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(1)
                .stage_flags(stages),
            vk::DescriptorSetLayoutBinding::default()
                .binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(1)
                .stage_flags(stages),
            vk::DescriptorSetLayoutBinding::default()
                .binding(2)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(1)
                .stage_flags(stages),
        ];
        let (set_layout, layout) = gpu::push_layout(host, &bindings, 4, stages)?;
        unsafe {
            let (vs, fs) = (gpu::shader_module(host, spirv::GBUFFER_VERT)?, gpu::shader_module(host, spirv::GBUFFER_FRAG)?);
            let stages_info = [
                vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
                vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
            ];
            let vertex_bindings = [vk::VertexInputBindingDescription {
                binding: 0,
                stride: VERTEX_STRIDE,
                input_rate: vk::VertexInputRate::VERTEX,
            }];
            let attribute = |location: u32, offset: u32| vk::VertexInputAttributeDescription {
                location,
                binding: 0,
                format: vk::Format::R32G32B32_SFLOAT,
                offset,
            };
            let uv =
                vk::VertexInputAttributeDescription { location: 2, binding: 0, format: vk::Format::R32G32_SFLOAT, offset: 24 };
            let vertex_attributes = [attribute(0, 0), attribute(1, 12), uv];
            let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&vertex_bindings)
                .vertex_attribute_descriptions(&vertex_attributes);
            let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
            let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
            let raster = vk::PipelineRasterizationStateCreateInfo::default()
                .polygon_mode(vk::PolygonMode::FILL)
                .cull_mode(vk::CullModeFlags::NONE)
                .line_width(1.0);
            let multisample =
                vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
            let depth = vk::PipelineDepthStencilStateCreateInfo::default()
                .depth_test_enable(true)
                .depth_write_enable(true)
                .depth_compare_op(vk::CompareOp::LESS);
            let attachments =
                [vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA); 3];
            let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
            let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
            let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
            let color_formats = [NORMAL_FORMAT, ALBEDO_FORMAT, MOTION_FORMAT];
            let mut rendering = vk::PipelineRenderingCreateInfo::default()
                .color_attachment_formats(&color_formats)
                .depth_attachment_format(DEPTH_FORMAT);
            let info = vk::GraphicsPipelineCreateInfo::default()
                .push_next(&mut rendering)
                .stages(&stages_info)
                .vertex_input_state(&vertex_input)
                .input_assembly_state(&assembly)
                .viewport_state(&viewport)
                .rasterization_state(&raster)
                .multisample_state(&multisample)
                .depth_stencil_state(&depth)
                .color_blend_state(&blend)
                .dynamic_state(&dynamic)
                .layout(layout);
            let pipeline = d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None);
            d.destroy_shader_module(vs, None);
            d.destroy_shader_module(fs, None);
            let pipeline = pipeline.map_err(|(_, e)| format!("graphics pipeline: {e:?}"))?[0];
            let push = ash::khr::push_descriptor::Device::new(&host.instance, d);
            Ok(GBufferPass {
                set_layout,
                layout,
                pipeline,
                push,
                cameras: UploadSlots::new(vk::BufferUsageFlags::UNIFORM_BUFFER),
                instances: UploadSlots::new(vk::BufferUsageFlags::STORAGE_BUFFER),
            })
        }
    }

    /// Records the G-buffer of `draws` seen by `camera` (and `prev_camera` for motion) into
    /// `targets`, leaving them in `READ` for the SDK. `slot` is the frame-in-flight index: its
    /// constant buffers are rewritten, so the frame that last used the slot must be finished.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        host: &Host,
        cmd: vk::CommandBuffer,
        slot: usize,
        targets: &Targets,
        meshes: &MeshBuffers,
        draws: &[Draw],
        camera: &Camera,
        prev_camera: &Camera,
    ) -> HostResult<()> {
        let d = &host.device;
        let aspect = targets.width as f32 / targets.height as f32;
        let view_proj = |c: &Camera| -> Mat4 { c.view_to_clip(aspect) * c.world_to_view() };
        let cam = CameraGpu {
            view_proj: view_proj(camera).to_cols_array(),
            prev_view_proj: view_proj(prev_camera).to_cols_array(),
            eye: camera.eye.extend(1.0).to_array(),
            viewport: [targets.width as f32, targets.height as f32, 0.0, 0.0],
        };
        let instances: Vec<InstanceGpu> = draws
            .iter()
            .map(|dr| InstanceGpu {
                model: Mat4::from(dr.transform).to_cols_array(),
                prev_model: Mat4::from(dr.prev_transform).to_cols_array(),
                material: [dr.material.albedo[0], dr.material.albedo[1], dr.material.albedo[2], dr.material.roughness],
                extra: [dr.material.metalness, dr.alpha_cutoff, 0.0, 0.0],
            })
            .collect();
        let ubo = self.cameras.write(host, slot, bytemuck::bytes_of(&cam))?;
        let ssbo = self.instances.write(host, slot, bytemuck::cast_slice(&instances))?;

        for t in targets.colors().into_iter().chain([&targets.depth]) {
            let to = if t.format == DEPTH_FORMAT {
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL
            } else {
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
            };
            host.transition(cmd, t, vk::ImageLayout::UNDEFINED, to);
        }
        let clear = vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } };
        let color_attachments: Vec<_> = targets
            .colors()
            .iter()
            .map(|t| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(t.view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(clear)
            })
            .collect();
        let depth_attachment = vk::RenderingAttachmentInfo::default()
            .image_view(targets.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
        let area =
            vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: targets.width, height: targets.height } };
        let rendering = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&color_attachments)
            .depth_attachment(&depth_attachment);
        let ubo_info = [vk::DescriptorBufferInfo { buffer: ubo, offset: 0, range: std::mem::size_of::<CameraGpu>() as u64 }];
        let ssbo_info = [vk::DescriptorBufferInfo { buffer: ssbo, offset: 0, range: vk::WHOLE_SIZE }];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&ubo_info),
            vk::WriteDescriptorSet::default()
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&ssbo_info),
        ];
        // SAFETY: cmd is recording; every referenced object outlives the frame.
        unsafe {
            d.cmd_begin_rendering(cmd, &rendering);
            d.cmd_set_viewport(
                cmd,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: targets.width as f32,
                    height: targets.height as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.cmd_set_scissor(cmd, 0, &[area]);
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
            self.push.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &writes);
            let mut bound_texture: Option<vk::ImageView> = None;
            for (i, dr) in draws.iter().enumerate() {
                let (vb, ib, count, _) = &meshes.meshes[dr.mesh];
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                    0,
                    &(i as u32).to_ne_bytes(),
                );
                // Pushed only when it changes: the forest's 2,500 draws use two textures.
                let view = meshes.albedo(dr.albedo_texture).view;
                if bound_texture != Some(view) {
                    bound_texture = Some(view);
                    let texture = [vk::DescriptorImageInfo { sampler: meshes.sampler, image_view: view, image_layout: READ }];
                    let write = vk::WriteDescriptorSet::default()
                        .dst_binding(2)
                        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                        .image_info(&texture);
                    self.push.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[write]);
                }
                d.cmd_bind_vertex_buffers(cmd, 0, &[dr.vertex_buffer.unwrap_or(vb.buffer)], &[0]);
                d.cmd_bind_index_buffer(cmd, ib.buffer, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cmd, *count, 1, 0, 0, 0);
            }
            d.cmd_end_rendering(cmd);
        }
        for t in targets.colors().into_iter().chain([&targets.depth]) {
            let from = if t.format == DEPTH_FORMAT {
                vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL
            } else {
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
            };
            host.transition(cmd, t, from, READ);
        }
        Ok(())
    }

    pub fn destroy(self, host: &Host) {
        self.cameras.destroy(host);
        self.instances.destroy(host);
        unsafe {
            host.device.destroy_pipeline(self.pipeline, None);
            host.device.destroy_pipeline_layout(self.layout, None);
            host.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// Every instance of `scene` as a static draw with one material per instance.
pub fn static_draws(scene: &Scene, material: impl Fn(usize) -> Material) -> Vec<Draw> {
    scene
        .instances
        .iter()
        .enumerate()
        .map(|(i, inst)| Draw {
            mesh: inst.mesh,
            transform: inst.transform,
            prev_transform: inst.transform,
            material: material(i),
            vertex_buffer: None,
            albedo_texture: None,
            alpha_cutoff: 0.0,
        })
        .collect()
}
