//! Pipelines: shader modules from embedded SPIR-V, push-descriptor set layouts, ray-tracing
//! pipelines with their shader binding table, and compute pipelines — all made through a
//! [`PipelineArena`], which owns them, so a pass holds only plain handles and a group of passes
//! (or a half-made one, after an error) is destroyed in one call.
use super::device::Device;
use super::memory::{Buffer, Memory, MemoryKind};
use crate::error::{Error, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;

pub(crate) fn shader_module(device: &ash::Device, spirv: &[u8]) -> Result<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .map_err(|e| Error::Internal(format!("embedded SPIR-V unreadable: {e}")))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: the words are SPIR-V the build compiled and validated (`spirv` test).
    unsafe { device.create_shader_module(&info, None) }.map_err(Error::vk("vkCreateShaderModule"))
}

/// One binding of a push-descriptor set.
pub(crate) struct Binding {
    pub ty: vk::DescriptorType,
    /// Immutable sampler for COMBINED_IMAGE_SAMPLER bindings.
    pub sampler: Option<vk::Sampler>,
}

fn push_set_layout(device: &ash::Device, bindings: &[Binding], stages: vk::ShaderStageFlags) -> Result<vk::DescriptorSetLayout> {
    let samplers: Vec<[vk::Sampler; 1]> = bindings.iter().map(|b| [b.sampler.unwrap_or_default()]).collect();
    let vk_bindings: Vec<_> = bindings
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let mut d = vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(b.ty)
                .descriptor_count(1)
                .stage_flags(stages);
            if b.sampler.is_some() {
                d = d.immutable_samplers(&samplers[i]);
            }
            d
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default()
        .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
        .bindings(&vk_bindings);
    // SAFETY: valid create info; destroyed with the arena.
    unsafe { device.create_descriptor_set_layout(&info, None) }.map_err(Error::vk("vkCreateDescriptorSetLayout"))
}

/// A pipeline layout of an optional push-descriptor set and `push_bytes` of push constants
/// (0: none) visible to `stages`.
fn pipeline_layout(
    device: &ash::Device,
    set: Option<vk::DescriptorSetLayout>,
    push_bytes: u32,
    stages: vk::ShaderStageFlags,
) -> Result<vk::PipelineLayout> {
    let sets: Vec<_> = set.into_iter().collect();
    let ranges: Vec<_> = (push_bytes > 0)
        .then_some(vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_bytes })
        .into_iter()
        .collect();
    let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&sets).push_constant_ranges(&ranges);
    // SAFETY: valid create info; the set layouts outlive the call; destroyed with the arena.
    unsafe { device.create_pipeline_layout(&info, None) }.map_err(Error::vk("vkCreatePipelineLayout"))
}

/// A ray-tracing pipeline: one raygen, miss shaders, closest-hit groups, and the regions of
/// its SBT (the buffer belongs to the arena that made it).
#[derive(Clone, Copy)]
pub(crate) struct RtPipeline {
    pub pipeline: vk::Pipeline,
    pub raygen: vk::StridedDeviceAddressRegionKHR,
    pub miss: vk::StridedDeviceAddressRegionKHR,
    pub hit: vk::StridedDeviceAddressRegionKHR,
    pub callable: vk::StridedDeviceAddressRegionKHR,
}

/// The shaders of one ray-tracing pipeline.
#[derive(Clone, Copy)]
pub(crate) struct RtShaders<'a> {
    pub raygen: &'a [u8],
    pub misses: &'a [&'a [u8]],
    pub closest_hits: &'a [&'a [u8]],
    /// One any-hit shader shared by every hit group (a filter, e.g. "only this instance").
    pub any_hit: Option<&'a [u8]>,
}

fn rt_pipeline(
    device: &Device,
    memory: &Memory,
    cache: vk::PipelineCache,
    layout: vk::PipelineLayout,
    shaders: &RtShaders<'_>,
) -> Result<(RtPipeline, Buffer)> {
    let RtShaders { raygen, misses, closest_hits, any_hit } = *shaders;
    let d = &device.raw;
    let mut modules = vec![shader_module(d, raygen)?];
    for m in misses.iter().chain(closest_hits).chain(any_hit.as_slice()) {
        match shader_module(d, m) {
            Ok(m) => modules.push(m),
            Err(e) => {
                // SAFETY: the modules were just created and no pipeline uses them.
                modules.iter().for_each(|&m| unsafe { d.destroy_shader_module(m, None) });
                return Err(e);
            }
        }
    }
    let entry = c"main";
    let mut stages =
        vec![vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::RAYGEN_KHR).module(modules[0]).name(entry)];
    for i in 0..misses.len() {
        stages.push(
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::MISS_KHR).module(modules[1 + i]).name(entry),
        );
    }
    for i in 0..closest_hits.len() {
        stages.push(
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::CLOSEST_HIT_KHR)
                .module(modules[1 + misses.len() + i])
                .name(entry),
        );
    }
    // One any-hit shader shared by every hit group (a filter, e.g. "only this instance").
    let any_hit_stage = any_hit.map(|_| {
        stages.push(
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::ANY_HIT_KHR)
                .module(modules[1 + misses.len() + closest_hits.len()])
                .name(entry),
        );
        (stages.len() - 1) as u32
    });
    let general = |i: usize| {
        vk::RayTracingShaderGroupCreateInfoKHR::default()
            .ty(vk::RayTracingShaderGroupTypeKHR::GENERAL)
            .general_shader(i as u32)
            .closest_hit_shader(vk::SHADER_UNUSED_KHR)
            .any_hit_shader(vk::SHADER_UNUSED_KHR)
            .intersection_shader(vk::SHADER_UNUSED_KHR)
    };
    let mut groups: Vec<_> = (0..1 + misses.len()).map(general).collect();
    for i in 0..closest_hits.len() {
        groups.push(
            vk::RayTracingShaderGroupCreateInfoKHR::default()
                .ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
                .general_shader(vk::SHADER_UNUSED_KHR)
                .closest_hit_shader((1 + misses.len() + i) as u32)
                .any_hit_shader(any_hit_stage.unwrap_or(vk::SHADER_UNUSED_KHR))
                .intersection_shader(vk::SHADER_UNUSED_KHR),
        );
    }
    let info = vk::RayTracingPipelineCreateInfoKHR::default()
        .stages(&stages)
        .groups(&groups)
        .max_pipeline_ray_recursion_depth(1)
        .layout(layout);
    // SAFETY: valid create info: stages, groups and layout made on this device; the modules outlive the call.
    let result = unsafe {
        device.rt.create_ray_tracing_pipelines(vk::DeferredOperationKHR::null(), cache, std::slice::from_ref(&info), None)
    };
    // SAFETY: pipeline creation is over; the modules are no longer needed.
    modules.iter().for_each(|&m| unsafe { d.destroy_shader_module(m, None) });
    let pipeline = result.map_err(|(_, e)| Error::Vulkan { call: "vkCreateRayTracingPipelinesKHR", result: e })?[0];

    // Shader binding table: [raygen | misses | hits], each region aligned to the base alignment.
    let props = &device.rt_props;
    let handle_size = props.shader_group_handle_size as u64;
    let align_up = |v: u64, a: u64| v.div_ceil(a) * a;
    let stride = align_up(handle_size, props.shader_group_handle_alignment as u64);
    let base = props.shader_group_base_alignment as u64;
    let group_count = groups.len();
    // SAFETY: the pipeline has `group_count` groups; the buffer holds a handle for each.
    let handles = unsafe {
        device.rt.get_ray_tracing_shader_group_handles(pipeline, 0, group_count as u32, group_count * handle_size as usize)
    }
    .map_err(|e| {
        // SAFETY: the pipeline was just created and is not used yet.
        unsafe { d.destroy_pipeline(pipeline, None) };
        Error::Vulkan { call: "vkGetRayTracingShaderGroupHandlesKHR", result: e }
    })?;
    let raygen_size = align_up(stride, base);
    let miss_size = align_up(stride * misses.len() as u64, base);
    let hit_size = align_up(stride * closest_hits.len() as u64, base);
    let total = raygen_size + miss_size + hit_size + base;
    let mut sbt = match memory.create_buffer(
        "shader binding table",
        total,
        vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR,
        MemoryLocation::CpuToGpu,
        MemoryKind::Pipeline,
    ) {
        Ok(b) => b,
        Err(e) => {
            // SAFETY: the pipeline was just created and is not used yet.
            unsafe { d.destroy_pipeline(pipeline, None) };
            return Err(e);
        }
    };
    // The buffer's address may not meet the base alignment: start at the first aligned byte.
    let start = align_up(sbt.address, base) - sbt.address;
    let bytes = sbt.mapped();
    let mut put = |group: usize, offset: u64| {
        let src = &handles[group * handle_size as usize..(group + 1) * handle_size as usize];
        let o = (start + offset) as usize;
        bytes[o..o + src.len()].copy_from_slice(src);
    };
    put(0, 0);
    for i in 0..misses.len() {
        put(1 + i, raygen_size + stride * i as u64);
    }
    for i in 0..closest_hits.len() {
        put(1 + misses.len() + i, raygen_size + miss_size + stride * i as u64);
    }
    let addr = sbt.address + start;
    let region = |offset: u64, stride: u64, size: u64| vk::StridedDeviceAddressRegionKHR {
        device_address: if size == 0 { 0 } else { addr + offset },
        stride,
        size,
    };
    let rt = RtPipeline {
        pipeline,
        raygen: region(0, raygen_size, raygen_size),
        miss: region(raygen_size, stride, miss_size),
        hit: region(raygen_size + miss_size, stride, hit_size),
        callable: vk::StridedDeviceAddressRegionKHR::default(),
    };
    Ok((rt, sbt))
}

fn compute_pipeline(
    device: &ash::Device,
    cache: vk::PipelineCache,
    layout: vk::PipelineLayout,
    spirv: &[u8],
    constants: &[u32],
) -> Result<vk::Pipeline> {
    let module = shader_module(device, spirv)?;
    // Specialization constants 0, 1, ... take `constants` in order.
    let entries: Vec<vk::SpecializationMapEntry> =
        (0..constants.len() as u32).map(|i| vk::SpecializationMapEntry { constant_id: i, offset: 4 * i, size: 4 }).collect();
    let specialization = vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(constants));
    let mut stage =
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::COMPUTE).module(module).name(c"main");
    if !constants.is_empty() {
        stage = stage.specialization_info(&specialization);
    }
    let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
    // SAFETY: valid create info; the module and layout outlive the call.
    let result = unsafe { device.create_compute_pipelines(cache, &[info], None) };
    // SAFETY: pipeline creation is over; the module is no longer needed.
    unsafe { device.destroy_shader_module(module, None) };
    result.map(|p| p[0]).map_err(|(_, e)| Error::Vulkan { call: "vkCreateComputePipelines", result: e })
}

/// Owns every pipeline object made through it (see the module doc).
#[derive(Default)]
pub(crate) struct PipelineArena {
    set_layouts: Vec<vk::DescriptorSetLayout>,
    layouts: Vec<vk::PipelineLayout>,
    pipelines: Vec<vk::Pipeline>,
    sbts: Vec<Buffer>,
}

/// Makes pipeline objects on one device into one arena (what a pass's constructor gets).
pub(crate) struct PipelineBuilder<'a> {
    pub device: &'a Device,
    pub memory: &'a Memory,
    pub arena: &'a mut PipelineArena,
    /// The engine's pipeline cache (or null).
    pub cache: vk::PipelineCache,
    /// Names the objects made next (debug utils: "hybrid-rt <label> pipeline", ...).
    pub label: &'static str,
}

impl PipelineBuilder<'_> {
    /// A push-descriptor set layout with one descriptor per binding, visible to `stages`.
    pub fn set_layout(&mut self, bindings: &[Binding], stages: vk::ShaderStageFlags) -> Result<vk::DescriptorSetLayout> {
        let l = push_set_layout(&self.device.raw, bindings, stages)?;
        self.arena.set_layouts.push(l);
        self.device.name(l, &format!("{} descriptor set layout", self.label));
        Ok(l)
    }

    /// A pipeline layout: an optional push-descriptor set, `push_bytes` of push constants.
    pub fn layout(
        &mut self,
        set: Option<vk::DescriptorSetLayout>,
        push_bytes: u32,
        stages: vk::ShaderStageFlags,
    ) -> Result<vk::PipelineLayout> {
        let l = pipeline_layout(&self.device.raw, set, push_bytes, stages)?;
        self.arena.layouts.push(l);
        self.device.name(l, &format!("{} pipeline layout", self.label));
        Ok(l)
    }

    pub fn compute(&mut self, layout: vk::PipelineLayout, spirv: &[u8]) -> Result<vk::Pipeline> {
        self.compute_specialized(layout, spirv, &[])
    }

    /// `compute` with the shader's specialization constants 0, 1, ... set to `constants`.
    pub fn compute_specialized(&mut self, layout: vk::PipelineLayout, spirv: &[u8], constants: &[u32]) -> Result<vk::Pipeline> {
        let p = compute_pipeline(&self.device.raw, self.cache, layout, spirv, constants)?;
        self.arena.pipelines.push(p);
        self.device.name(p, &format!("{} pipeline", self.label));
        Ok(p)
    }

    pub fn ray_tracing(&mut self, layout: vk::PipelineLayout, shaders: &RtShaders<'_>) -> Result<RtPipeline> {
        let (p, sbt) = rt_pipeline(self.device, self.memory, self.cache, layout, shaders)?;
        self.arena.pipelines.push(p.pipeline);
        self.device.name(p.pipeline, &format!("{} pipeline", self.label));
        self.device.name(sbt.raw, &format!("{} shader binding table", self.label));
        self.arena.sbts.push(sbt);
        Ok(p)
    }
}

impl PipelineArena {
    /// Destroys everything made through the arena (no recording may still use it).
    pub fn destroy(&mut self, device: &Device, memory: &Memory) {
        let d = &device.raw;
        // SAFETY: the owner guarantees no pending GPU use; each object is destroyed once.
        unsafe {
            for p in self.pipelines.drain(..) {
                d.destroy_pipeline(p, None);
            }
            for l in self.layouts.drain(..) {
                d.destroy_pipeline_layout(l, None);
            }
            for l in self.set_layouts.drain(..) {
                d.destroy_descriptor_set_layout(l, None);
            }
        }
        for b in self.sbts.drain(..) {
            memory.destroy_buffer(b);
        }
    }
}
