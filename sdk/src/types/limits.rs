//! The SDK's fixed limits, in one place (the C header repeats them as `HRT_MAX_*`).

/// Most lights one `TraceMultiShadowTask` traces (Kickstart RT's limit).
pub const MAX_SHADOW_LIGHTS: usize = 32;

/// Lights whose visibility fits one `R32G32B32A32_UINT` image (8 bits each); the rest go to
/// `TraceMultiShadowTask::visibility_high`.
pub const LIGHTS_PER_VISIBILITY_IMAGE: usize = 16;

/// Most per-light outputs (`TraceMultiShadowTask::light_outputs`) of one task.
pub const MAX_LIGHT_OUTPUTS: usize = 4;

/// Largest `SurfelSettings::tile_resolution_limit`: cache samples along one triangle edge.
pub const MAX_TILE_RESOLUTION: u32 = 256;

/// Most direct-lighting cache samples of one geometry (64 Mi samples, 2 GiB per instance): a
/// geometry whose `SurfelSettings` would need more gets a coarser layout (its resolution limit
/// halved until it fits, with a warning in the log).
pub const MAX_CACHE_SAMPLES: u64 = 1 << 26;

/// Largest `DenoisingContextInput::max_width` / `max_height`.
pub const MAX_DENOISING_EXTENT: u32 = 16384;
