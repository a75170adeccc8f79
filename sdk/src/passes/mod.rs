//! The passes: one module per GPU pass, and the registry that names them.
//!
//! A pass owns its pipelines (made in its module's `new`, owned by [`Passes`]' arena) and
//! records itself: it declares what it reads and writes to the hazard tracker (which emits the
//! barriers) and never reaches into another pass. What every pass builds on is in [`base`].
//!
//! Each render task kind has one description, [`PassTask`], implemented beside its pass, and
//! one row in the task table (`crate::tasks`), from which this module makes [`RenderTask`]
//! (a variant per row), its `describe`, and [`Passes`] (a field per pass, each made with its
//! label). The recorder (`context::record`) only walks `RenderTask`s and has no per-kind match.
pub(crate) mod ao;
pub(crate) mod base;
pub(crate) mod blue_noise;
pub(crate) mod cache_ops;
pub(crate) mod constants;
pub(crate) mod debug;
pub(crate) mod denoise;
pub(crate) mod denoise_guide;
pub(crate) mod descriptors;
pub(crate) mod diffuse;
pub(crate) mod geometry_pack;
pub(crate) mod inject;
pub(crate) mod many_lights;
pub(crate) mod program;
pub(crate) mod relight;
pub(crate) mod shadow;
pub(crate) mod specular;
pub(crate) mod surfel_layout;
pub(crate) mod transfer;

pub(crate) use base::{gbuffer_bindings, gbuffer_slots, input_mask_binding, input_mask_slot, PassTask, Recording, World};

use crate::error::{Error, Result};
use crate::gpu::device::Device;
use crate::gpu::memory::Memory;
use crate::gpu::pipeline::{PipelineArena, PipelineBuilder};
use crate::types::*;
use ash::vk;

/// Makes `RenderTask`, `Passes` and the bench floor's list from the task table.
macro_rules! passes {
    (
        other_kinds { $( $(#[$om:meta])* $OKind:ident = $on:literal, $oname:literal; )* }
        support_passes { $( $sfield:ident: $SPass:ty = $slabel:literal; )* }
        render_tasks { $(
            $Variant:ident($Payload:ty) {
                pass: $field:ident: $Pass:ty = $label:literal $(, floor $prog:ident)?;
                kinds: [ $( $(#[$km:meta])* $Kind:ident = $n:literal, $kname:literal; )+ ]
                schedule: [ $( $(#[$sm:meta])* $sched:ident($STask:ty); )+ ]
            }
        )* }
    ) => {
        /// Every render task kind: the tasks recorded in scheduled order after the BVH and
        /// cache work.
        #[derive(Debug, Clone)]
        pub(crate) enum RenderTask {
            $( $Variant($Payload), )*
        }

        impl RenderTask {
            pub fn describe(&self) -> &dyn PassTask {
                match self {
                    $( RenderTask::$Variant(t) => t, )*
                }
            }
        }

        /// Every pass, created together when the context is (an error leaves nothing behind),
        /// and the arena that owns their pipelines.
        pub(crate) struct Passes {
            $( pub $field: $Pass, )*
            $( pub $sfield: $SPass, )*
            /// The one sampler of every sampled G-buffer binding (nearest, clamped: texel fetches).
            sampler: vk::Sampler,
            arena: PipelineArena,
            /// Bench only: trace through the floor pipelines (see `program`).
            pub floor: bool,
            /// The engine's pipeline cache, for pipelines made later (the bench floor).
            #[cfg_attr(not(feature = "bench-floor"), allow(dead_code))]
            cache: vk::PipelineCache,
        }

        impl Passes {
            /// Makes every pass into the builder's arena (which `new` then moves into the
            /// result); each pass's objects are named after it (debug utils).
            fn make(b: &mut PipelineBuilder<'_>, sampler: vk::Sampler) -> Result<Passes> {
                $( b.label = $label; let $field = <$Pass>::new(b, sampler)?; )*
                $( b.label = $slabel; let $sfield = <$SPass>::new(b, sampler)?; )*
                Ok(Passes {
                    $( $field, )*
                    $( $sfield, )*
                    sampler,
                    arena: PipelineArena::default(),
                    floor: false,
                    cache: b.cache,
                })
            }

            /// Builds the bench's floor pipelines of every trace that has one (on first use).
            #[cfg(feature = "bench-floor")]
            pub fn ensure_floor(&mut self, device: &Device, memory: &Memory) -> Result<()> {
                let b = &mut PipelineBuilder { device, memory, arena: &mut self.arena, cache: self.cache, label: "bench floor" };
                $( $( self.$field.$prog.ensure_floor(b)?; )? )*
                Ok(())
            }
        }
    };
}
crate::tasks::task_table!(passes);

impl RenderTask {
    /// The debug visualisation this task records instead of itself, if it asks for one.
    fn debug_view(&self) -> Option<(&TraceCommon, &ImageInput)> {
        let t = self.describe();
        let common = t.trace_common().filter(|c| c.debug_output != DebugOutput::Default)?;
        Some((common, t.debug_target()?))
    }

    /// Upload-ring bytes its recording may push (itself or its debug view), before alignment.
    pub fn upload_bytes(&self) -> u64 {
        self.describe().upload_bytes().max(debug::UPLOAD_BYTES)
    }

    /// Records the task — or, for a trace task with a debug mode, the visualisation instead.
    pub fn record(&self, r: &mut Recording<'_>, passes: &Passes, world: &mut World<'_>) {
        match self.debug_view() {
            Some((common, output)) => passes.debug.record(r, common, output),
            None => self.describe().record(r, passes, world),
        }
    }
}

impl Passes {
    pub fn new(device: &Device, memory: &Memory, cache: vk::PipelineCache) -> Result<Passes> {
        let sampler_info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        // SAFETY: valid create info; destroyed in `destroy`.
        let sampler = unsafe { device.raw.create_sampler(&sampler_info, None) }.map_err(Error::vk("vkCreateSampler"))?;
        let mut arena = PipelineArena::default();
        device.name(sampler, "G-buffer sampler");
        match Self::make(&mut PipelineBuilder { device, memory, arena: &mut arena, cache, label: "" }, sampler) {
            Ok(passes) => Ok(Passes { arena, ..passes }),
            Err(e) => {
                arena.destroy(device, memory);
                // SAFETY: the sampler was just created and is not used yet.
                unsafe { device.raw.destroy_sampler(sampler, None) };
                Err(e)
            }
        }
    }

    /// Destroys every pass (no recording may still use them).
    pub fn destroy(&mut self, device: &Device, memory: &Memory) {
        self.arena.destroy(device, memory);
        // SAFETY: the context is destroyed after its tickets came back; destroyed once.
        unsafe { device.raw.destroy_sampler(self.sampler, None) };
        self.sampler = vk::Sampler::null();
    }
}
