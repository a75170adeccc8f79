//! Direct-lighting injection (see `DirectLightingInjectionTask`): a ray-tracing pass that adds
//! each lit pixel's radiance to the cache sample under it (float atomics), followed by the
//! cache resolve (passes::cache_ops) that applies the running average.
use super::constants::TraceCommonGpu;
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::shaders;
use crate::types::{DirectLightingInjectionTask, InstanceInclusionMask, TaskKind, TraceCommon};
use ash::vk;
use bytemuck::{Pod, Zeroable};

/// `InjectConstants` in shaders/inject.rgen.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct InjectConstantsGpu {
    pub common: TraceCommonGpu,
    pub table: [u32; 4],
}

pub(crate) struct InjectPass {
    program: RtProgram,
}

impl InjectPass {
    pub fn new(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<InjectPass> {
        let program = RtProgram::new(
            b,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, sampler: Some(sampler) },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            Shaders::hit_record(shaders::INJECT_RGEN),
        )?;
        Ok(InjectPass { program })
    }

    pub fn record(&self, r: &mut Recording<'_>, task: &DirectLightingInjectionTask) {
        let common = TraceCommon { depth: task.depth, viewport: task.viewport, camera: task.camera, ..Default::default() };
        let table = r.instance_table;
        // Validated to 1..=16, so the offsets fit 16 bits each.
        let stride = task.injection_resolution_stride.max(1);
        let (ox, oy) = stride_offset(stride, r.seed);
        let constants = InjectConstantsGpu {
            common: TraceCommonGpu::new(&common, r.seed, InstanceInclusionMask::LIGHT_INJECTION.bits()),
            table: [table as u32, (table >> 32) as u32, stride, ox | (oy << 16)],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let slots = [Slot::Tlas(r.tlas), Slot::Sampled(&task.depth.image), Slot::Sampled(&task.lit), Slot::Uniform(ubo)];
        let (w, h) = (task.viewport.width.div_ceil(stride), task.viewport.height.div_ceil(stride));
        self.program.run(r, &slots, w, h, Writes::Atomics);
    }
}

/// The pixel of each `stride x stride` block injected in frame `frame`: the block's `n =
/// stride²` positions visited in the order `k * step mod n`, `step` coprime to `n` and near
/// `0.618 n`, so any `n` consecutive frames visit all of them and consecutive frames land
/// far apart (for 2: (0,0), (1,1), (0,1), (1,0)). Kickstart RT picks a random position per
/// frame, which leaves some pixels unvisited for many frames.
fn stride_offset(stride: u32, frame: u32) -> (u32, u32) {
    let n = stride * stride;
    if n == 1 {
        return (0, 0);
    }
    let gcd = |mut a: u32, mut b: u32| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let mut step = ((n as f32 * 0.618).round() as u32).max(1);
    while gcd(step, n) != 1 {
        step += 1;
    }
    let k = ((frame % n) as u64 * step as u64 % n as u64) as u32;
    (k % stride, k / stride)
}

/// Injection, then the resolve of every cache page in use.
impl PassTask for DirectLightingInjectionTask {
    fn kind(&self) -> TaskKind {
        TaskKind::DirectLightingInjection
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<InjectConstantsGpu>() as u64
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        passes.inject.record(r, self);
        for (address, count) in world.cache_pool.spans() {
            passes.cache_ops.resolve(r, address, count, self.average_window);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::stride_offset;

    #[test]
    fn stride_offsets_visit_every_position_of_the_block() {
        for stride in 1..=16u32 {
            for start in [0u32, 7, u32::MAX - 3] {
                let mut seen = vec![false; (stride * stride) as usize];
                for f in 0..stride * stride {
                    let (x, y) = stride_offset(stride, start.wrapping_add(f));
                    assert!(x < stride && y < stride);
                    seen[(y * stride + x) as usize] = true;
                }
                // Frames wrap at u32::MAX, where the cycle restarts: only unbroken runs count.
                if start != u32::MAX - 3 {
                    assert!(seen.iter().all(|&s| s), "stride {stride}: a position never visited");
                }
            }
        }
        assert_eq!((0..4).map(|f| stride_offset(2, f)).collect::<Vec<_>>(), [(0, 0), (1, 1), (0, 1), (1, 0)]);
    }
}
