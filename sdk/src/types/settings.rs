//! Context-wide settings.
use ash::vk;

/// Settings fixed when the context is created.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct InitSettings {
    /// How many tickets may be in flight at once (default 2: one frame recording while one
    /// runs). Each working set owns its upload ring, query pools, build scratch and TLAS, so
    /// in-flight frames never share mutable GPU memory. Range 1..=16.
    pub supported_working_sets: u32,
    /// Initial size of each working set's upload ring in bytes (default 1 MiB). It grows when a
    /// frame needs more (64 bytes per TLAS instance plus 256 per render task), so this only
    /// avoids early reallocations.
    pub upload_ring_bytes: u64,
    /// Timed intervals per ticket, besides two for the BVH and cache work (default 64; with
    /// `time_passes` each task's passes come on top). Tasks past the limit run untimed.
    pub max_timed_tasks: u32,
    /// An engine-owned `VkPipelineCache` the SDK creates its pipelines through (null: none,
    /// the default). Save it with `vkGetPipelineCacheData` and create it from that data on the
    /// next run: context creation then skips shader compilation (docs/benchmarks.md has the
    /// cold and warm times). The SDK only reads and adds to it, during `ExecuteContext::new`
    /// (and the bench floor's pipelines).
    pub pipeline_cache: vk::PipelineCache,
    /// The queue families whose command buffers the engine records SDK work into (the first
    /// `queue_family_count` entries; default 0: one family). With two or more — BVH work on an
    /// async-compute queue, tracing on graphics — every SDK buffer and image is created with
    /// `VK_SHARING_MODE_CONCURRENT` over them, so no ownership transfer is needed; the engine
    /// orders the two submissions with a semaphore. Indices must be the device's families.
    pub queue_family_indices: [u32; 4],
    /// How many entries of `queue_family_indices` are used (0..=4). Default 0.
    pub queue_family_count: u32,
    /// Most bytes the direct-lighting caches may hold (0: no limit, the default). When a cache
    /// would not fit, the caches of the instances unused for longest are evicted — "used":
    /// a camera's injection, a GI or reflection ray, or a debug view reached the instance in a
    /// ticket that came back — and an evicted instance gets a new cache (its initial colour,
    /// relit or injected again) once it is used again. `ExecuteContext::cache_report` says
    /// what is resident, waiting and evicted. A single cache larger than the budget never
    /// gets one.
    pub cache_budget_bytes: u64,
    /// Time every pass of the tasks made of several (the denoisers) as well as the task
    /// (default false): `CompletedTask::pass_timings`. Costs two timestamps per pass, which
    /// also order the passes' starts after the previous pass's end, as its barrier does anyway.
    pub time_passes: bool,
}

impl Default for InitSettings {
    fn default() -> Self {
        InitSettings {
            supported_working_sets: 2,
            upload_ring_bytes: 1 << 20,
            max_timed_tasks: 64,
            pipeline_cache: vk::PipelineCache::null(),
            queue_family_indices: [0; 4],
            queue_family_count: 0,
            cache_budget_bytes: 0,
            time_passes: false,
        }
    }
}
