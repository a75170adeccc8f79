//! Cache transfer between two instances that cover the same surface (LOD switches): every
//! sample of the target takes the source's cached lighting where a ray along the sample's
//! normal meets the source (shaders/transfer.rgen). Kickstart RT traces two rays per source
//! primitive onto the destination; tracing from the destination's samples instead writes
//! every target sample exactly once per triangle, with no gaps where the target is finer.
use super::descriptors::Slot;
use super::program::{RtProgram, Shaders, Writes};
use super::{PassTask, Passes, Recording, World};
use crate::error::Result;
use crate::gpu::pipeline::{Binding, PipelineBuilder};
use crate::scene::Scene;
use crate::shaders;
use crate::types::{DirectLightTransferTask, InstanceHandle, SurfelType, TaskKind};
use ash::vk;
use bytemuck::{Pod, Zeroable};

#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct TransferConstantsGpu {
    table: [u32; 4],
    params: [f32; 4],
}

/// What one transfer needs to know about its two instances.
struct TransferJob {
    pub source_index: u32,
    pub target_index: u32,
    pub target_triangles: u32,
    /// Samples per target triangle at the largest resolution (the launch's y extent).
    pub samples_per_triangle: u32,
    pub distance: f32,
    pub bilinear: bool,
}

pub(crate) struct TransferPass {
    program: RtProgram,
}

impl TransferPass {
    /// Every pass is made with the G-buffer sampler (see `Passes`); this one samples nothing.
    pub fn new(b: &mut PipelineBuilder<'_>, _sampler: vk::Sampler) -> Result<TransferPass> {
        let program = RtProgram::new(
            b,
            &[
                Binding { ty: vk::DescriptorType::ACCELERATION_STRUCTURE_KHR, sampler: None },
                Binding { ty: vk::DescriptorType::UNIFORM_BUFFER, sampler: None },
            ],
            Shaders {
                raygen: shaders::TRANSFER_RGEN,
                misses: &[shaders::TRANSFER_RMISS],
                closest_hits: &[shaders::TRANSFER_RCHIT],
                any_hit: Some(shaders::TRANSFER_RAHIT),
                inline: None,
                floor: None,
            },
        )?;
        Ok(TransferPass { program })
    }

    fn record(&self, r: &mut Recording<'_>, job: &TransferJob) {
        let t = r.instance_table;
        let constants = TransferConstantsGpu {
            table: [t as u32, (t >> 32) as u32, job.source_index, job.target_index],
            params: [job.distance, job.bilinear as u32 as f32, 0.0, 0.0],
        };
        let ubo = r.ring.push(bytemuck::bytes_of(&constants), r.device.ubo_alignment);
        let slots = [Slot::Tlas(r.tlas), Slot::Uniform(ubo)];
        self.program.run(r, &slots, job.target_triangles, job.samples_per_triangle, Writes::Storage);
    }
}

impl TransferJob {
    /// The launch of a transfer, or None when either instance has no cache yet.
    fn new(scene: &Scene, t: &DirectLightTransferTask) -> Option<TransferJob> {
        let placed = |h: InstanceHandle| {
            let p = scene.instances.get(h).ok()?.placement?;
            p.cache?;
            Some((scene.instances.index_of(h).ok()?, p))
        };
        let (source_index, _) = placed(t.source)?;
        let (target_index, target) = placed(t.target)?;
        let g = scene.geometries.get(target.geometry).ok()?;
        let surfel = g.surfel.as_ref()?;
        let r = surfel.max_resolution;
        let samples_per_triangle = match surfel.surfel_type {
            SurfelType::Tiles => r * r,
            SurfelType::MeshColors => (r + 1) * (r + 2) / 2,
        };
        Some(TransferJob {
            source_index,
            target_index,
            target_triangles: g.layout?.primitive_count,
            samples_per_triangle,
            distance: t.max_distance,
            bilinear: t.enable_bilinear_sampling,
        })
    }
}

impl PassTask for DirectLightTransferTask {
    fn kind(&self) -> TaskKind {
        TaskKind::CacheTransfer
    }
    fn upload_bytes(&self) -> u64 {
        std::mem::size_of::<TransferConstantsGpu>() as u64
    }
    fn check(&self, world: &World<'_>) -> Result<()> {
        world.scene.instances.get(self.source).map_err(|e| e.for_field("DirectLightTransferTask.source"))?;
        world.scene.instances.get(self.target).map_err(|e| e.for_field("DirectLightTransferTask.target"))?;
        // One ray per target sample: the launch must fit the device.
        if let Some(job) = TransferJob::new(world.scene, self) {
            let rays = job.target_triangles as u64 * job.samples_per_triangle as u64;
            if rays > world.limits.max_ray_dispatch as u64 {
                return Err(crate::Error::invalid(
                    "DirectLightTransferTask.target",
                    format!(
                        "its cache needs {rays} rays, over the device's maxRayDispatchInvocationCount {}",
                        world.limits.max_ray_dispatch
                    ),
                ));
            }
        }
        Ok(())
    }
    fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        match TransferJob::new(world.scene, self) {
            Some(job) => passes.transfer.record(r, &job),
            None => log::debug!("cache transfer skipped: an instance has no cache yet"),
        }
    }
}
