//! The task table: the one declaration of every render task kind.
//!
//! A row names the render task's variant and payload, the pass that records it (its field in
//! `passes::Passes`, its type, the label its Vulkan objects get, and the program the bench's
//! floor swaps in), the [`TaskKind`](crate::TaskKind)s its timings are reported under, and
//! the `TaskContainer` functions that schedule it. Three generators read the table, each in
//! the layer it belongs to:
//!
//! - `types::ticket` makes the public `TaskKind` (with `ALL` and `name`, which the C ABI's
//!   constants are checked against);
//! - `passes` makes `RenderTask` (one variant per row, and `describe`), `Passes` (one field
//!   per pass, each made with its label) and the bench floor's list;
//! - `context::container` makes the public `schedule_*` functions, each of which converts the
//!   task into the row's payload, validates it (`context::validate::Check`) and queues it.
//!
//! So a new render task is its public struct, its `Check` impl, its pass file (the pass and
//! its `PassTask` impl, declared in `passes`), a row here, its shaders and its C mirror.
//! A generator matches the whole grammar and uses the parts it needs; the tokens of a row are
//! resolved where a generator expands them, so payload and pass types are named as `passes`
//! and `context::container` see them.

/// Expands `$generate! { ... }` with the task table (see the module doc).
macro_rules! task_table {
    ($generate:ident) => {
        $generate! {
            // Kinds of the work every recording does around the render tasks.
            other_kinds {
                /// All BVH work of the ticket: geometry copies, BLAS builds/refits/compactions, TLAS.
                Bvh = 0, "bvh";
                /// Inside `Bvh`: the batched BLAS builds and refits (and compaction copies).
                BlasBuild = 2, "blas_build";
                /// Inside `Bvh`: the TLAS build (only when the scene changed since the working set's last).
                TlasBuild = 3, "tlas_build";
                /// Cache maintenance of the ticket: new layouts, new and cleared caches.
                CacheUpdate = 5, "cache_update";
            }
            // Passes that record for the SDK itself, not for one task.
            support_passes {
                debug: debug::DebugPass = "debug view";
                cache_ops: cache_ops::CacheOps = "cache fill/resolve";
                geometry_pack: geometry_pack::GeometryPack = "index check";
                surfel_layout: surfel_layout::SurfelLayoutPass = "surfel layout";
            }
            render_tasks {
                AmbientOcclusion(TraceAmbientOcclusionTask) {
                    pass: ao: ao::AoPass = "ambient occlusion", floor program;
                    kinds: [
                        /// `TraceAmbientOcclusionTask` (or its debug view).
                        AmbientOcclusion = 1, "ambient_occlusion";
                    ]
                    schedule: [
                        /// Ambient occlusion from the G-buffer (see `TraceAmbientOcclusionTask`).
                        schedule_ambient_occlusion(TraceAmbientOcclusionTask);
                    ]
                }
                Shadow(TraceShadowTask) {
                    pass: shadow: shadow::ShadowPass = "shadow", floor program;
                    kinds: [
                        /// `TraceShadowTask`.
                        Shadow = 7, "shadow";
                    ]
                    schedule: [
                        /// Shadows from one light (see `TraceShadowTask`).
                        schedule_shadow(TraceShadowTask);
                    ]
                }
                MultiShadow(TraceMultiShadowTask) {
                    pass: multi_shadow: shadow::MultiShadowPass = "multi-light shadow", floor program;
                    kinds: [
                        /// `TraceMultiShadowTask`.
                        MultiShadow = 10, "multi_shadow";
                    ]
                    schedule: [
                        /// Shadows from several lights in one pass (see `TraceMultiShadowTask`).
                        schedule_multi_shadow(TraceMultiShadowTask);
                    ]
                }
                Diffuse(TraceDiffuseTask) {
                    pass: diffuse: diffuse::DiffusePass = "diffuse GI", floor program;
                    kinds: [
                        /// `TraceDiffuseTask`.
                        Diffuse = 8, "diffuse";
                    ]
                    schedule: [
                        /// Diffuse GI shaded from the cache (see `TraceDiffuseTask`).
                        schedule_diffuse(TraceDiffuseTask);
                    ]
                }
                Specular(TraceSpecularTask) {
                    pass: specular: specular::SpecularPass = "specular", floor program;
                    kinds: [
                        /// `TraceSpecularTask`.
                        Specular = 9, "specular";
                    ]
                    schedule: [
                        /// Specular reflections shaded from the cache (see `TraceSpecularTask`).
                        schedule_specular(TraceSpecularTask);
                    ]
                }
                ManyLights(TraceManyLightsTask) {
                    pass: many_lights: many_lights::ManyLightsPass = "many lights";
                    kinds: [
                        /// `TraceManyLightsTask`.
                        ManyLights = 18, "many_lights";
                    ]
                    schedule: [
                        /// Direct lighting from many shadowed lights by resampling (see `TraceManyLightsTask`).
                        schedule_many_lights(TraceManyLightsTask);
                    ]
                }
                DirectLightingInjection(DirectLightingInjectionTask) {
                    pass: inject: inject::InjectPass = "injection";
                    kinds: [
                        /// A direct-lighting injection and its cache resolve.
                        DirectLightingInjection = 4, "direct_lighting_injection";
                    ]
                    schedule: [
                        /// Bakes a lit view into the direct-lighting caches (see `DirectLightingInjectionTask`).
                        schedule_direct_lighting_injection(DirectLightingInjectionTask);
                    ]
                }
                DirectLightTransfer(DirectLightTransferTask) {
                    pass: transfer: transfer::TransferPass = "cache transfer";
                    kinds: [
                        /// A cache transfer between two instances.
                        CacheTransfer = 6, "cache_transfer";
                    ]
                    schedule: [
                        /// Copies one instance's cached lighting onto another covering the same surface.
                        schedule_direct_light_transfer(DirectLightTransferTask);
                    ]
                }
                CacheRelight(RelightCacheTask) {
                    pass: relight: relight::RelightPass = "cache relight";
                    kinds: [
                        /// `RelightCacheTask`.
                        CacheRelight = 17, "cache_relight";
                    ]
                    schedule: [
                        /// Lights cache samples no camera has injected from the engine's lights (see
                        /// `RelightCacheTask`).
                        schedule_cache_relight(RelightCacheTask);
                    ]
                }
                // Boxed: a denoise job is several times larger than the other tasks.
                Denoise(Box<DenoiseJob>) {
                    pass: denoise: denoise::DenoisePass = "denoiser";
                    kinds: [
                        /// `DenoiseSpecularTask`.
                        DenoiseSpecular = 11, "denoise_specular";
                        /// `DenoiseDiffuseTask`.
                        DenoiseDiffuse = 12, "denoise_diffuse";
                        /// `DenoiseSpecularAndDiffuseTask`.
                        DenoiseSpecularAndDiffuse = 13, "denoise_specular_and_diffuse";
                        /// `DenoiseDiffuseOcclusionTask`.
                        DenoiseDiffuseOcclusion = 14, "denoise_diffuse_occlusion";
                        /// `DenoiseShadowTask`.
                        DenoiseShadow = 15, "denoise_shadow";
                        /// `DenoiseMultiShadowTask`.
                        DenoiseMultiShadow = 16, "denoise_multi_shadow";
                    ]
                    schedule: [
                        /// Denoises a specular trace (see `DenoiseSpecularTask`).
                        schedule_denoise_specular(DenoiseSpecularTask);
                        /// Denoises a diffuse GI trace (see `DenoiseDiffuseTask`).
                        schedule_denoise_diffuse(DenoiseDiffuseTask);
                        /// Denoises specular and diffuse traces in one set of passes.
                        schedule_denoise_specular_and_diffuse(DenoiseSpecularAndDiffuseTask);
                        /// Denoises an ambient-occlusion trace.
                        schedule_denoise_diffuse_occlusion(DenoiseDiffuseOcclusionTask);
                        /// Denoises a single-light shadow trace.
                        schedule_denoise_shadow(DenoiseShadowTask);
                        /// Denoises a multi-light shadow trace's packed output.
                        schedule_denoise_multi_shadow(DenoiseMultiShadowTask);
                    ]
                }
            }
        }
    };
}
pub(crate) use task_table;
