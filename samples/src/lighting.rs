//! The sample's deferred direct lighting, a compute pass over its G-buffer: the sun (its
//! visibility from the SDK's shadow task, denoised), a point light and an ambient term. Its
//! output is the "rasterized lit frame" the engine hands the SDK for light injection and as
//! the direct-lighting input of GI and reflections.
use crate::gpu::{self, spirv, UploadSlots};
use crate::raster::Targets;
use ash::vk;
use glam::{Mat4, Vec3};
use hybrid_rt_testkit::host::{Host, HostImage, HostResult};
use hybrid_rt_testkit::reference::Camera;

pub const LIT_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// The lights of the scene.
#[derive(Clone, Copy, Debug)]
pub struct Lights {
    /// Direction towards the sun, and its irradiance at normal incidence.
    pub sun_direction: Vec3,
    pub sun_intensity: f32,
    pub point_position: Vec3,
    /// Point light: irradiance = intensity / d².
    pub point_intensity: f32,
    pub ambient: f32,
}

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct LightingGpu {
    clip_to_world: [f32; 16],
    sun: [f32; 4],
    point: [f32; 4],
    ambient: [f32; 4],
}

pub struct LightingPass {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    sampler: vk::Sampler,
    push: ash::khr::push_descriptor::Device,
    constants: UploadSlots,
}

impl LightingPass {
    pub fn new(host: &Host) -> HostResult<LightingPass> {
        let d = &host.device;
        let ty = |i: u32| match i {
            0..=3 => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            4 => vk::DescriptorType::STORAGE_IMAGE,
            _ => vk::DescriptorType::UNIFORM_BUFFER,
        };
        // SAFETY: plain object creation; everything is destroyed in `destroy`.
        let sampler = unsafe { d.create_sampler(&vk::SamplerCreateInfo::default(), None) }.map_err(|e| format!("sampler: {e:?}"))?;
        let samplers = [sampler];
        let bindings: Vec<_> = (0..6)
            .map(|i| {
                let b = vk::DescriptorSetLayoutBinding::default().binding(i).descriptor_type(ty(i)).descriptor_count(1).stage_flags(vk::ShaderStageFlags::COMPUTE);
                if i < 4 { b.immutable_samplers(&samplers) } else { b }
            })
            .collect();
        let (set_layout, layout) = gpu::push_layout(host, &bindings, 0, vk::ShaderStageFlags::COMPUTE)?;
        let module = gpu::shader_module(host, spirv::LIGHTING_COMP)?;
        let stage = vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::COMPUTE).module(module).name(c"main");
        let pipeline = unsafe {
            let p = d.create_compute_pipelines(vk::PipelineCache::null(), &[vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)], None);
            d.destroy_shader_module(module, None);
            p.map_err(|(_, e)| format!("compute pipeline: {e:?}"))?[0]
        };
        let push = ash::khr::push_descriptor::Device::new(&host.instance, d);
        Ok(LightingPass { set_layout, layout, pipeline, sampler, push, constants: UploadSlots::new(vk::BufferUsageFlags::UNIFORM_BUFFER) })
    }

    /// A lit image for `targets` (STORAGE for this pass, SAMPLED for the SDK), in GENERAL.
    pub fn lit_image(host: &Host, targets: &Targets) -> HostResult<HostImage> {
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
        host.image_cleared(LIT_FORMAT, targets.width, targets.height, usage, vk::ImageLayout::GENERAL)
    }

    /// Lights the G-buffer into `lit` (GENERAL). `sun_visibility` (R) is read in
    /// `visibility_layout`. `slot`: the frame-in-flight index (its constants are rewritten).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        host: &Host,
        cmd: vk::CommandBuffer,
        slot: usize,
        targets: &Targets,
        camera: &Camera,
        lights: &Lights,
        sun_visibility: &HostImage,
        visibility_layout: vk::ImageLayout,
        lit: &HostImage,
    ) -> HostResult<()> {
        let aspect = targets.width as f32 / targets.height as f32;
        let clip_to_world: Mat4 = (camera.view_to_clip(aspect) * camera.world_to_view()).inverse();
        let c = LightingGpu {
            clip_to_world: clip_to_world.to_cols_array(),
            sun: lights.sun_direction.normalize().extend(lights.sun_intensity).to_array(),
            point: lights.point_position.extend(lights.point_intensity).to_array(),
            ambient: [lights.ambient, targets.width as f32, targets.height as f32, 0.0],
        };
        let ubo = self.constants.write(host, slot, bytemuck::bytes_of(&c))?;
        let image = |i: &HostImage, layout| [vk::DescriptorImageInfo { sampler: self.sampler, image_view: i.view, image_layout: layout }];
        let read = crate::raster::READ;
        let infos = [
            image(&targets.depth, read),
            image(&targets.normal_roughness, read),
            image(&targets.albedo_metalness, read),
            image(sun_visibility, visibility_layout),
            image(lit, vk::ImageLayout::GENERAL),
        ];
        let ubo_info = [vk::DescriptorBufferInfo { buffer: ubo, offset: 0, range: std::mem::size_of::<LightingGpu>() as u64 }];
        let mut writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(i, info)| {
                let ty = if i < 4 { vk::DescriptorType::COMBINED_IMAGE_SAMPLER } else { vk::DescriptorType::STORAGE_IMAGE };
                vk::WriteDescriptorSet::default().dst_binding(i as u32).descriptor_type(ty).image_info(info)
            })
            .collect();
        writes.push(vk::WriteDescriptorSet::default().dst_binding(5).descriptor_type(vk::DescriptorType::UNIFORM_BUFFER).buffer_info(&ubo_info));
        // SAFETY: cmd is recording; the images and buffer outlive the frame.
        unsafe {
            host.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline);
            self.push.cmd_push_descriptor_set(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &writes);
            host.device.cmd_dispatch(cmd, targets.width.div_ceil(8), targets.height.div_ceil(8), 1);
        }
        Ok(())
    }

    pub fn destroy(self, host: &Host) {
        self.constants.destroy(host);
        unsafe {
            host.device.destroy_pipeline(self.pipeline, None);
            host.device.destroy_pipeline_layout(self.layout, None);
            host.device.destroy_descriptor_set_layout(self.set_layout, None);
            host.device.destroy_sampler(self.sampler, None);
        }
    }
}
