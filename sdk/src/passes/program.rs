//! A ray-tracing program: a push-descriptor set layout, its pipeline layout, and one
//! ray-tracing pipeline with its SBT. Passes that are "bind these, trace that many rays" are a
//! program plus their constants.
use super::descriptors::{self, Slot};
use super::Recording;
use crate::error::Result;
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::{self, Binding, RtPipeline};
use ash::vk;

pub(crate) struct RtProgram {
    set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub rt: RtPipeline,
    /// The same body as a compute shader with ray queries (devices that have them).
    inline: Option<vk::Pipeline>,
    raygen: &'static [u8],
    /// Bench only: the raygen with empty hit and miss shaders (every ray reads as a miss),
    /// built on demand by `ExecuteContext::set_bench_floor_mode`.
    floor: Option<RtPipeline>,
}

/// The shaders of a program.
pub(crate) struct Shaders<'a> {
    pub raygen: &'static [u8],
    pub misses: &'a [&'a [u8]],
    pub closest_hits: &'a [&'a [u8]],
    pub any_hit: Option<&'a [u8]>,
    /// The compute + ray-query twin of the raygen (same bindings), if the pass has one.
    pub inline: Option<&'a [u8]>,
}

impl RtProgram {
    pub fn new(
        device: &Device,
        memory: &Memory,
        bindings: &[Binding],
        stages: vk::ShaderStageFlags,
        shaders: Shaders<'_>,
    ) -> Result<RtProgram> {
        let d = &device.raw;
        let set_layout = pipeline::push_set_layout(d, bindings, stages)?;
        let layout = pipeline::pipeline_layout(d, set_layout)?;
        let rt =
            pipeline::rt_pipeline(device, memory, layout, shaders.raygen, shaders.misses, shaders.closest_hits, shaders.any_hit)?;
        let inline = match (shaders.inline, device.ray_query) {
            (Some(spirv), true) => Some(pipeline::compute_pipeline(d, layout, spirv)?),
            _ => None,
        };
        Ok(RtProgram { set_layout, layout, rt, inline, raygen: shaders.raygen, floor: None })
    }

    /// Builds the bench's floor pipeline (programs whose hits are HitRecord payloads).
    pub fn ensure_floor(&mut self, device: &Device, memory: &Memory) -> Result<()> {
        if self.floor.is_none() {
            let s = Shaders {
                raygen: self.raygen,
                misses: &[crate::shaders::EMPTY_RECORD_RMISS],
                closest_hits: &[crate::shaders::EMPTY_RECORD_RCHIT],
                any_hit: None,
                inline: None,
            };
            self.floor = Some(self.variant(device, memory, s)?);
        }
        Ok(())
    }

    /// The stage the pass's shaders run in (for its barriers).
    pub fn stage(&self, inline: bool) -> vk::PipelineStageFlags2 {
        if inline && self.inline.is_some() {
            vk::PipelineStageFlags2::COMPUTE_SHADER
        } else {
            vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR
        }
    }

    /// Traces width x height through the pipeline, or with ray queries when `inline` is
    /// asked for and available (8x8 compute groups); both give the same image.
    pub fn run(&self, r: &mut Recording<'_>, slots: &[Slot<'_>], width: u32, height: u32, inline: bool) {
        if let (true, Some(floor)) = (r.floor, self.floor.as_ref()) {
            return self.trace_with(r, floor, slots, width, height);
        }
        match self.inline.filter(|_| inline) {
            Some(p) => {
                let bind = vk::PipelineBindPoint::COMPUTE;
                unsafe { r.device.raw.cmd_bind_pipeline(r.cmd, bind, p) };
                descriptors::push(r.device, r.cmd, bind, self.layout, slots);
                unsafe { r.device.raw.cmd_dispatch(r.cmd, width.div_ceil(8), height.div_ceil(8), 1) };
            }
            None => self.trace(r, slots, width, height),
        }
    }

    /// Another pipeline over the same layout (e.g. a variant with other hit shaders).
    pub fn variant(&self, device: &Device, memory: &Memory, shaders: Shaders<'_>) -> Result<RtPipeline> {
        pipeline::rt_pipeline(device, memory, self.layout, shaders.raygen, shaders.misses, shaders.closest_hits, shaders.any_hit)
    }

    /// Binds `pipeline` (this program's or a variant), pushes `slots` and traces width x height.
    pub fn trace_with(&self, r: &mut Recording<'_>, pipeline: &RtPipeline, slots: &[Slot<'_>], width: u32, height: u32) {
        let bind = vk::PipelineBindPoint::RAY_TRACING_KHR;
        unsafe { r.device.raw.cmd_bind_pipeline(r.cmd, bind, pipeline.pipeline) };
        descriptors::push(r.device, r.cmd, bind, self.layout, slots);
        let p = pipeline;
        // SAFETY: the slots match the set layout; the command buffer is recording.
        unsafe { r.device.rt.cmd_trace_rays(r.cmd, &p.raygen, &p.miss, &p.hit, &p.callable, width, height, 1) };
    }

    pub fn trace(&self, r: &mut Recording<'_>, slots: &[Slot<'_>], width: u32, height: u32) {
        self.trace_with(r, &self.rt, slots, width, height);
    }

    pub fn destroy_pipeline(device: &Device, memory: &Memory, p: RtPipeline) {
        unsafe { device.raw.destroy_pipeline(p.pipeline, None) };
        memory.destroy_buffer(p.sbt);
    }

    pub fn destroy(self, device: &Device, memory: &Memory) {
        if let Some(p) = self.inline {
            unsafe { device.raw.destroy_pipeline(p, None) };
        }
        if let Some(p) = self.floor {
            Self::destroy_pipeline(device, memory, p);
        }
        Self::destroy_pipeline(device, memory, self.rt);
        unsafe {
            device.raw.destroy_pipeline_layout(self.layout, None);
            device.raw.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
