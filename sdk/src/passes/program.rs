//! A ray-tracing program: a push-descriptor set layout, its pipeline layout, one ray-tracing
//! pipeline with its SBT, and optionally the same raygen body as a compute shader with ray
//! queries. Passes that are "bind these, trace that many rays" are a program plus their
//! constants.
//!
//! Which pipeline a trace runs through is decided here and nowhere else: the bench's bare-ray
//! floor (empty hit and miss shaders) when it is on, else the inline ray-query twin when the
//! task asked for it and the device has ray queries, else the ray-tracing pipeline. Both real
//! variants give the same image (tests/tests/inline.rs).
use super::descriptors::{self, Slot};
use super::Recording;
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder, RtPipeline, RtShaders};
use crate::gpu::sync;
use crate::shaders;
use ash::vk;

/// The payload a program's hit and miss shaders write: it picks the empty shaders of the bench
/// floor (they must write the same payload so the raygen reads "miss").
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Payload {
    /// `float` hit distance (AO).
    HitT,
    /// `HitRecord` (instance, primitive, barycentrics, distance).
    HitRecord,
}

/// The shaders of a program.
pub(crate) struct Shaders {
    pub raygen: &'static [u8],
    pub misses: &'static [&'static [u8]],
    pub closest_hits: &'static [&'static [u8]],
    pub any_hit: Option<&'static [u8]>,
    /// The compute + ray-query twin of the raygen (same bindings), if the pass has one.
    pub inline: Option<&'static [u8]>,
    /// The payload, when the pass has a bare-ray floor for the bench (None: it has none).
    pub floor: Option<Payload>,
}

impl Shaders {
    /// A raygen whose rays report through the HitRecord miss and closest-hit shaders (the
    /// alpha test's any-hit for alpha-tested geometry), with no inline twin and no floor.
    pub fn hit_record(raygen: &'static [u8]) -> Shaders {
        Shaders {
            raygen,
            misses: &[shaders::HIT_RECORD_RMISS],
            closest_hits: &[shaders::HIT_RECORD_RCHIT],
            any_hit: Some(shaders::ALPHA_TEST_RAHIT),
            inline: None,
            floor: None,
        }
    }

    /// `hit_record` for a trace task: its ray-query twin, and the bench's bare-ray floor.
    pub fn hit_record_trace(raygen: &'static [u8], inline: &'static [u8]) -> Shaders {
        Shaders { inline: Some(inline), floor: Some(Payload::HitRecord), ..Shaders::hit_record(raygen) }
    }
}

/// What a program's shaders write besides reading their inputs (for the barrier before them).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Writes {
    /// Plain storage writes (trace outputs).
    Storage,
    /// Atomic read-modify-writes (injection's accumulation).
    Atomics,
}

/// The push constants of every trace program (`HrtTracePush` in shaders/include/trace_push.glsl):
/// the instance table, which the alpha test of any-hit shaders and ray-query loops reads, and
/// the per-instance usage flags of the cache budget (0: none), and the blue-noise tile of
/// `RandomNumbers::BlueNoise` (0 when no task of the recording asked for it).
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct TracePush {
    instance_table: u64,
    usage: u64,
    blue_noise: u64,
}

pub(crate) struct RtProgram {
    pub layout: vk::PipelineLayout,
    /// The stages the push constants are visible to.
    push_stages: vk::ShaderStageFlags,
    rt: RtPipeline,
    /// The compute twin, only on devices with ray queries.
    inline: Option<vk::Pipeline>,
    #[cfg_attr(not(feature = "bench-floor"), allow(dead_code))]
    raygen: &'static [u8],
    #[cfg_attr(not(feature = "bench-floor"), allow(dead_code))]
    floor_payload: Option<Payload>,
    /// The bench's floor pipeline, built on demand (`ExecuteContext::set_bench_floor_mode`).
    floor: Option<RtPipeline>,
}

/// The pipeline one trace runs through.
#[derive(Clone, Copy)]
enum Variant {
    RayTracing(RtPipeline),
    Inline(vk::Pipeline),
}

impl RtProgram {
    pub fn new(b: &mut PipelineBuilder<'_>, bindings: &[Binding], shaders: Shaders) -> Result<RtProgram> {
        let stages = if shaders.inline.is_some() {
            vk::ShaderStageFlags::RAYGEN_KHR | vk::ShaderStageFlags::COMPUTE
        } else {
            vk::ShaderStageFlags::RAYGEN_KHR
        };
        let set_layout = b.set_layout(bindings, stages)?;
        let push_stages = stages | vk::ShaderStageFlags::ANY_HIT_KHR;
        let layout = b.layout(Some(set_layout), std::mem::size_of::<TracePush>() as u32, push_stages)?;
        let rt = b.ray_tracing(
            layout,
            &RtShaders {
                raygen: shaders.raygen,
                misses: shaders.misses,
                closest_hits: shaders.closest_hits,
                any_hit: shaders.any_hit,
            },
        )?;
        let inline = match (shaders.inline, b.device.ray_query) {
            (Some(spirv), true) => Some(b.compute(layout, spirv)?),
            _ => None,
        };
        Ok(RtProgram { layout, push_stages, rt, inline, raygen: shaders.raygen, floor_payload: shaders.floor, floor: None })
    }

    /// Builds the bench's floor pipeline, if this program has one.
    #[cfg(feature = "bench-floor")]
    pub fn ensure_floor(&mut self, b: &mut PipelineBuilder<'_>) -> Result<()> {
        let Some(payload) = self.floor_payload.filter(|_| self.floor.is_none()) else { return Ok(()) };
        let (miss, hit) = match payload {
            Payload::HitT => (shaders::EMPTY_RMISS, shaders::EMPTY_RCHIT),
            Payload::HitRecord => (shaders::EMPTY_RECORD_RMISS, shaders::EMPTY_RECORD_RCHIT),
        };
        let shaders = RtShaders { raygen: self.raygen, misses: &[miss], closest_hits: &[hit], any_hit: None };
        self.floor = Some(b.ray_tracing(self.layout, &shaders)?);
        Ok(())
    }

    fn variant(&self, r: &Recording<'_>) -> Variant {
        if let (true, Some(floor)) = (r.floor, self.floor) {
            return Variant::RayTracing(floor);
        }
        match self.inline.filter(|_| r.inline) {
            Some(p) => Variant::Inline(p),
            None => Variant::RayTracing(self.rt),
        }
    }

    /// Declares the pass's reads and `writes` to the hazard tracker, then traces width x height
    /// (8x8 compute groups for the inline variant).
    pub fn run(&self, r: &mut Recording<'_>, slots: &[Slot<'_>], width: u32, height: u32, writes: Writes) {
        let variant = self.variant(r);
        let stage = match variant {
            Variant::Inline(_) => vk::PipelineStageFlags2::COMPUTE_SHADER,
            Variant::RayTracing(_) => vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR,
        };
        let write = match writes {
            Writes::Storage => sync::shader_write(stage),
            Writes::Atomics => sync::shader_atomic(stage),
        };
        r.hazards.read_write(r.cmd, sync::shader_read(stage), write);
        let push = TracePush { instance_table: r.instance_table, usage: r.usage, blue_noise: r.blue_noise };
        r.cmd.push_constants(self.layout, self.push_stages, bytemuck::bytes_of(&push));
        match variant {
            Variant::Inline(p) => {
                let bind = vk::PipelineBindPoint::COMPUTE;
                r.cmd.bind_pipeline(bind, p);
                descriptors::push(r.cmd, bind, self.layout, slots);
                r.cmd.dispatch(width.div_ceil(8), height.div_ceil(8), 1);
            }
            Variant::RayTracing(p) => {
                let bind = vk::PipelineBindPoint::RAY_TRACING_KHR;
                r.cmd.bind_pipeline(bind, p.pipeline);
                descriptors::push(r.cmd, bind, self.layout, slots);
                r.cmd.trace_rays([p.raygen, p.miss, p.hit, p.callable], width, height);
            }
        }
    }
}
