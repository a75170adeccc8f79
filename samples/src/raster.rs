//! The sample's own rasterizer: what an engine already has before it meets hybrid-rt. One
//! graphics pass (dynamic rendering) writes a G-buffer — hardware depth, world normal +
//! roughness, albedo + metalness, screen-space motion in pixels, emitted radiance — that the
//! SDK then reads as its `DepthInput`, `NormalInput`, `RoughnessInput` and `MotionInput` (and
//! the sample's lighting pass turns into the lit image the SDK injects). Materials follow glTF's
//! metallic-roughness model: factors times base-colour, metallic-roughness, normal and
//! emissive textures.
use crate::gpu::{self, spirv, UploadSlots};
pub use crate::mesh_buffers::{interleave, MaterialTextures, MeshBuffers, Texture, VertexAttributes, VERTEX_STRIDE};
use crate::mesh_buffers::{COLOR_OFFSET, TANGENT_OFFSET, TEXTURE_SLOTS, UV_OFFSET};
use ash::vk;
use glam::{Affine3A, Mat4};
use hybrid_rt_host::scene::{Camera, Scene};
use hybrid_rt_host::{Host, HostImage, HostResult};

pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
pub const NORMAL_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;
pub const MOTION_FORMAT: vk::Format = vk::Format::R16G16_SFLOAT;
/// Emitted radiance (emissive factor x texture x strength): unbounded, so half floats.
pub const EMISSIVE_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
/// The layout the targets are left in after a pass, ready for the SDK to sample.
pub use crate::gpu::READ;

/// A surface's material in the G-buffer: glTF's factors (its textures are
/// [`MaterialTextures`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub albedo: [f32; 3],
    pub roughness: f32,
    pub metalness: f32,
    /// Emitted radiance (glTF's emissive factor times KHR_materials_emissive_strength).
    pub emissive: [f32; 3],
}

impl Default for Material {
    /// A grey dielectric: albedo 0.8, roughness 0.5, no emission.
    fn default() -> Material {
        Material { albedo: [0.8; 3], roughness: 0.5, metalness: 0.0, emissive: [0.0; 3] }
    }
}

/// `Instance` in shaders/sample/gbuffer_common.glsl (std430).
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct InstanceGpu {
    model: [f32; 16],
    prev_model: [f32; 16],
    material: [f32; 4],
    extra: [f32; 4],
    emissive: [f32; 4],
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
    pub emissive: HostImage,
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
            emissive: host.create_image(EMISSIVE_FORMAT, width, height, color)?,
            width,
            height,
        })
    }

    fn colors(&self) -> [&HostImage; 4] {
        [&self.normal_roughness, &self.albedo_metalness, &self.motion, &self.emissive]
    }

    pub fn destroy(self, host: &Host) {
        for i in [self.depth, self.normal_roughness, self.albedo_metalness, self.motion, self.emissive] {
            host.destroy_image(i);
        }
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
    /// Where those vertices were last frame (buffer, byte offset): their positions' motion
    /// goes into the motion vectors. None: they did not move (but for `prev_transform`).
    pub prev_vertex_buffer: Option<(vk::Buffer, vk::DeviceSize)>,
    /// The material's textures (indices into the scene's).
    pub textures: MaterialTextures,
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
                .descriptor_count(TEXTURE_SLOTS as u32)
                .stage_flags(stages),
        ];
        let (set_layout, layout) = gpu::push_layout(host, &bindings, 4, stages)?;
        unsafe {
            let (vs, fs) = (gpu::shader_module(host, spirv::GBUFFER_VERT)?, gpu::shader_module(host, spirv::GBUFFER_FRAG)?);
            let stages_info = [
                vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
                vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
            ];
            // Binding 1: the same vertices a frame earlier (their positions alone).
            let vertex_bindings = [0, 1].map(|binding| vk::VertexInputBindingDescription {
                binding,
                stride: VERTEX_STRIDE,
                input_rate: vk::VertexInputRate::VERTEX,
            });
            let attribute = |location: u32, format: vk::Format, offset: u32| vk::VertexInputAttributeDescription {
                location,
                binding: 0,
                format,
                offset,
            };
            let vertex_attributes = [
                attribute(0, vk::Format::R32G32B32_SFLOAT, 0),
                attribute(1, vk::Format::R32G32B32_SFLOAT, 12),
                attribute(2, vk::Format::R32G32_SFLOAT, UV_OFFSET),
                attribute(3, vk::Format::R32G32B32A32_SFLOAT, TANGENT_OFFSET),
                attribute(4, vk::Format::R32G32B32A32_SFLOAT, COLOR_OFFSET),
                vk::VertexInputAttributeDescription { location: 5, binding: 1, format: vk::Format::R32G32B32_SFLOAT, offset: 0 },
            ];
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
                [vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA); 4];
            let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
            let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
            let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
            let color_formats = [NORMAL_FORMAT, ALBEDO_FORMAT, MOTION_FORMAT, EMISSIVE_FORMAT];
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
                extra: [
                    dr.material.metalness,
                    dr.alpha_cutoff,
                    dr.textures.normal.map_or(0.0, |_| dr.textures.normal_scale),
                    0.0,
                ],
                emissive: [dr.material.emissive[0], dr.material.emissive[1], dr.material.emissive[2], 0.0],
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
            let mut bound_textures = None;
            for (i, dr) in draws.iter().enumerate() {
                let (vb, ib, count) = meshes.mesh(dr.mesh);
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                    0,
                    &(i as u32).to_ne_bytes(),
                );
                // Pushed only when they change: the forest's 2,500 draws use two texture sets.
                let views = meshes.views(&dr.textures);
                if bound_textures != Some(views) {
                    bound_textures = Some(views);
                    let textures = views.map(|image_view| vk::DescriptorImageInfo {
                        sampler: meshes.sampler(),
                        image_view,
                        image_layout: READ,
                    });
                    let write = vk::WriteDescriptorSet::default()
                        .dst_binding(2)
                        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                        .image_info(&textures);
                    self.push.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[write]);
                }
                let current = dr.vertex_buffer.unwrap_or(vb);
                let (prev, offset) = dr.prev_vertex_buffer.unwrap_or((current, 0));
                d.cmd_bind_vertex_buffers(cmd, 0, &[current, prev], &[0, offset]);
                d.cmd_bind_index_buffer(cmd, ib, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cmd, count, 1, 0, 0, 0);
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
            prev_vertex_buffer: None,
            textures: MaterialTextures::default(),
            alpha_cutoff: 0.0,
        })
        .collect()
}
