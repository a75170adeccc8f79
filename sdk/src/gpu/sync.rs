//! Barriers derived from what each step declares it reads and writes, so no pass hand-writes
//! one. The SDK never changes an image layout (inputs and outputs stay in the layouts the
//! engine gave), so every hazard is a memory hazard and a global `VkMemoryBarrier2` covers
//! buffers, acceleration structures and images alike.
use super::commands::Commands;
use ash::vk;

/// One declared use: the stages and access types of a step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Use {
    pub stages: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
}

pub(crate) const TRANSFER_WRITE: Use = Use { stages: vk::PipelineStageFlags2::COPY, access: vk::AccessFlags2::TRANSFER_WRITE };
pub(crate) const TRANSFER_READ: Use = Use { stages: vk::PipelineStageFlags2::COPY, access: vk::AccessFlags2::TRANSFER_READ };
pub(crate) const AS_BUILD_READ: Use = Use {
    stages: vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR.as_raw() | vk::AccessFlags2::SHADER_READ.as_raw(),
    ),
};
pub(crate) const AS_BUILD_WRITE: Use = Use {
    stages: vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
    access: vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR,
};
/// Acceleration-structure copies (compaction). They run in the build stage: the dedicated
/// copy stage needs VK_KHR_ray_tracing_maintenance1, which not every driver has.
pub(crate) const AS_COPY: Use = Use {
    stages: vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR,
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR.as_raw() | vk::AccessFlags2::ACCELERATION_STRUCTURE_WRITE_KHR.as_raw(),
    ),
};

/// Host reads after the ticket's fence (read-backs, counters): a barrier to the host domain.
pub(crate) const HOST_READ: Use = Use { stages: vk::PipelineStageFlags2::HOST, access: vk::AccessFlags2::HOST_READ };

/// Every stage the SDK's own commands run in (what its persistent state was written by).
pub(crate) const SDK_STAGES: vk::PipelineStageFlags2 = vk::PipelineStageFlags2::from_raw(
    vk::PipelineStageFlags2::COPY.as_raw()
        | vk::PipelineStageFlags2::ACCELERATION_STRUCTURE_BUILD_KHR.as_raw()
        | vk::PipelineStageFlags2::COMPUTE_SHADER.as_raw()
        | vk::PipelineStageFlags2::RAY_TRACING_SHADER_KHR.as_raw(),
);

/// Reads and writes of a trace or compute pass at `stage`.
pub(crate) fn shader_read(stage: vk::PipelineStageFlags2) -> Use {
    Use {
        stages: stage,
        access: vk::AccessFlags2::SHADER_SAMPLED_READ
            | vk::AccessFlags2::SHADER_STORAGE_READ
            | vk::AccessFlags2::UNIFORM_READ
            | vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
    }
}
/// Atomic read-modify-writes from shaders (injection's accumulation).
pub(crate) fn shader_atomic(stage: vk::PipelineStageFlags2) -> Use {
    Use { stages: stage, access: vk::AccessFlags2::SHADER_STORAGE_WRITE | vk::AccessFlags2::SHADER_STORAGE_READ }
}
pub(crate) fn shader_write(stage: vk::PipelineStageFlags2) -> Use {
    Use { stages: stage, access: vk::AccessFlags2::SHADER_STORAGE_WRITE }
}

/// Tracks the last write and the reads since, across one recording.
#[derive(Default)]
pub(crate) struct Hazards {
    write: Option<Use>,
    visible: (vk::PipelineStageFlags2, vk::AccessFlags2),
    read_stages: vk::PipelineStageFlags2,
}

impl Hazards {
    /// The start of a recording: SDK state that outlives a ticket (caches, denoiser history,
    /// the TLAS) was written by earlier command buffers. Submission order alone does not make
    /// those writes visible, so the first use in this recording waits on them (one barrier).
    pub fn after_earlier_submissions() -> Hazards {
        Hazards { write: Some(Use { stages: SDK_STAGES, access: vk::AccessFlags2::MEMORY_WRITE }), ..Default::default() }
    }

    /// Declares that the next commands read with `u`; records a barrier if an earlier write is
    /// not yet visible to them.
    pub fn read(&mut self, cmd: &Commands, u: Use) {
        if let Some(w) = self.write {
            if !(self.visible.0.contains(u.stages) && self.visible.1.contains(u.access)) {
                cmd.barrier(w, u);
                self.visible.0 |= u.stages;
                self.visible.1 |= u.access;
            }
        }
        self.read_stages |= u.stages;
    }

    /// Declares that the next commands write with `u` (after any reads they also do: declare
    /// those first). Orders them after the previous write (WAW) and the reads since (WAR).
    pub fn write(&mut self, cmd: &Commands, u: Use) {
        let mut src = Use { stages: self.read_stages, access: vk::AccessFlags2::NONE };
        if let Some(w) = self.write {
            src.stages |= w.stages;
            src.access |= w.access;
        }
        if !src.stages.is_empty() {
            cmd.barrier(src, u);
        }
        self.write = Some(u);
        self.visible = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);
        self.read_stages = vk::PipelineStageFlags2::NONE;
    }

    /// A step that reads and writes (a build that reads inputs and writes its result).
    pub fn read_write(&mut self, cmd: &Commands, r: Use, w: Use) {
        self.read(cmd, r);
        self.write(cmd, w);
    }
}
