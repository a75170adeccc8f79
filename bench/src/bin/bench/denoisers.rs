//! The last sections: each denoiser beside the 1-ray trace it cleans (same frames), the
//! history one denoising context keeps, and the SDK's device memory.
use crate::traces::Traces;
use crate::{sdk, Bench, Field};
use ash::vk;
use hybrid_rt::SignalType as S;
use hybrid_rt::{DenoisingContextHandle, DenoisingContextInput, TaskContainer, TaskKind};
use serde_json::{json, Map, Value};

impl Bench<'_> {
    /// A denoising context for `signal` at the bench's size.
    fn denoising_context(&self, signal: S) -> Result<DenoisingContextHandle, String> {
        let (width, height) = (self.settings.width, self.settings.height);
        self.ctx
            .create_denoising_context(&DenoisingContextInput {
                max_width: width,
                max_height: height,
                signal,
                ..Default::default()
            })
            .map_err(sdk)
    }

    /// One denoise row: `schedule` puts a trace and its denoiser (`kinds`) into each frame,
    /// with a fresh context for `signal`.
    fn denoise_row(
        &mut self,
        json: &mut Map<String, Value>,
        name: &str,
        signal: S,
        kinds: [TaskKind; 2],
        mut schedule: impl FnMut(&mut TaskContainer, DenoisingContextHandle) -> Result<(), String>,
    ) -> Result<(), String> {
        let (width, height) = (self.settings.width, self.settings.height);
        let dn = self.denoising_context(signal)?;
        let ([trace, denoise], passes) = self.time_pair(kinds, |f| schedule(f, dn))?;
        self.ctx.destroy_denoising_context(dn).map_err(sdk)?;
        self.report.row(format!("Denoise {name} {width}x{height}"), format!("{denoise:.3} ms (its 1-ray trace: {trace:.3} ms)"));
        for (pass, ms) in &passes {
            self.report.row(format!("  pass {pass}"), format!("{ms:.3} ms"));
        }
        let passes: Map<String, Value> = passes.into_iter().map(|(pass, ms)| (pass.to_string(), json!(ms))).collect();
        json.insert(name.replace(' ', "_"), json!({"denoise_gpu_ms": denoise, "trace_gpu_ms": trace, "passes_gpu_ms": passes}));
        Ok(())
    }

    /// Every denoiser beside its 1-ray trace, then the history of a specular + diffuse
    /// context.
    pub fn denoisers(&mut self, field: &Field, traces: Traces) -> Result<(), String> {
        let (width, height) = (self.settings.width, self.settings.height);
        let sampled = |format| {
            let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
            self.host.image_cleared(format, width, height, usage, vk::ImageLayout::GENERAL)
        };
        let f16 = vk::Format::R16G16B16A16_SFLOAT;
        let images = [sampled(f16)?, sampled(f16)?, sampled(f16)?, sampled(f16)?];
        let [ia, ib, oa, ob] = [0, 1, 2, 3].map(|i| images[i].input(vk::ImageLayout::GENERAL));
        let settings = hybrid_rt::DenoiserSettings {
            spatial_passes: self.settings.denoise_passes,
            anti_lag: self.settings.anti_lag,
            ..Default::default()
        };
        let common = hybrid_rt::DenoisingCommon {
            roughness: traces.specular.common.roughness,
            settings,
            ..field.gbuffer.denoising_common(&field.camera)
        };
        let mut json = Map::new();
        let ao1 = hybrid_rt::TraceAmbientOcclusionTask { output: ia, ..field.gbuffer.ao_task(&field.camera, 1.0, 1) };
        self.denoise_row(
            &mut json,
            "AO",
            S::DiffuseOcclusion,
            [TaskKind::AmbientOcclusion, TaskKind::DenoiseDiffuseOcclusion],
            |f, dn| {
                f.schedule_ambient_occlusion(&ao1).map_err(sdk)?;
                f.schedule_denoise_diffuse_occlusion(&hybrid_rt::DenoiseDiffuseOcclusionTask {
                    context: dn,
                    common,
                    input: ia,
                    output: oa,
                })
                .map_err(sdk)
            },
        )?;
        let shadow1 = hybrid_rt::TraceShadowTask { output: ia, ..traces.shadow };
        self.denoise_row(&mut json, "shadow", S::Shadow, [TaskKind::Shadow, TaskKind::DenoiseShadow], |f, dn| {
            f.schedule_shadow(&shadow1).map_err(sdk)?;
            let light = shadow1.light;
            f.schedule_denoise_shadow(&hybrid_rt::DenoiseShadowTask { context: dn, common, light, input: ia, output: oa })
                .map_err(sdk)
        })?;
        let multi1 = hybrid_rt::TraceMultiShadowTask { packed: ia, ..traces.multi.clone() };
        let kinds = [TaskKind::MultiShadow, TaskKind::DenoiseMultiShadow];
        self.denoise_row(&mut json, "multi-light shadow (4 lights)", S::MultiShadow, kinds, |f, dn| {
            f.schedule_multi_shadow(&multi1).map_err(sdk)?;
            f.schedule_denoise_multi_shadow(&hybrid_rt::DenoiseMultiShadowTask { context: dn, common, input: ia, output: oa })
                .map_err(sdk)
        })?;
        let diffuse1 = hybrid_rt::TraceDiffuseTask { output: ib, ..traces.diffuse };
        self.denoise_row(&mut json, "diffuse", S::Diffuse, [TaskKind::Diffuse, TaskKind::DenoiseDiffuse], |f, dn| {
            f.schedule_diffuse(&diffuse1).map_err(sdk)?;
            f.schedule_denoise_diffuse(&hybrid_rt::DenoiseDiffuseTask { context: dn, common, input: ib, output: ob }).map_err(sdk)
        })?;
        let specular1 = hybrid_rt::TraceSpecularTask { output: ia, ..traces.specular.clone() };
        let kinds = [TaskKind::Specular, TaskKind::DenoiseSpecular];
        self.denoise_row(&mut json, "specular (roughness 0.3)", S::Specular, kinds, |f, dn| {
            f.schedule_specular(&specular1).map_err(sdk)?;
            f.schedule_denoise_specular(&hybrid_rt::DenoiseSpecularTask { context: dn, common, input: ia, output: oa })
                .map_err(sdk)
        })?;
        let kinds = [TaskKind::Specular, TaskKind::DenoiseSpecularAndDiffuse];
        self.denoise_row(&mut json, "specular + diffuse", S::SpecularAndDiffuse, kinds, |f, dn| {
            f.schedule_specular(&specular1).map_err(sdk)?;
            f.schedule_diffuse(&diffuse1).map_err(sdk)?;
            f.schedule_denoise_specular_and_diffuse(&hybrid_rt::DenoiseSpecularAndDiffuseTask {
                context: dn,
                common,
                input_specular: ia,
                input_diffuse: ib,
                output_specular: oa,
                output_diffuse: ob,
            })
            .map_err(sdk)
        })?;
        self.denoiser_history(&mut json)?;
        self.report.key("denoisers", Value::Object(json));
        for image in images.into_iter().chain([traces.visibility]) {
            self.host.destroy_image(image);
        }
        Ok(())
    }

    /// The denoisers' device memory at the bench's size, with nothing else of theirs alive: per
    /// signal, what one context of a view keeps (a second context of the view, over the first:
    /// its histories), and what the first context made besides (the view's guide and the
    /// intermediates every context shares).
    fn denoiser_history(&mut self, json: &mut Map<String, Value>) -> Result<(), String> {
        let (width, height) = (self.settings.width, self.settings.height);
        // Free the measured contexts first (destroyed contexts wait for their tickets).
        self.ctx.release_device_resources_immediately().map_err(sdk)?;
        let mib = |b: u64| b as f64 / 1048576.0;
        for (name, signal) in [("specular + diffuse", S::SpecularAndDiffuse), ("shadow", S::Shadow), ("AO", S::DiffuseOcclusion)]
        {
            let bytes = || self.ctx.resource_allocations().denoiser.bytes;
            let input = DenoisingContextInput { max_width: width, max_height: height, signal, view_id: 1, ..Default::default() };
            let first = self.ctx.create_denoising_context(&input).map_err(sdk)?;
            let with_first = bytes();
            let second = self.ctx.create_denoising_context(&input).map_err(sdk)?;
            let kept = bytes() - with_first;
            for h in [first, second] {
                self.ctx.destroy_denoising_context(h).map_err(sdk)?;
            }
            self.ctx.release_device_resources_immediately().map_err(sdk)?;
            let shared = with_first - kept;
            self.report.row(
                format!("Denoiser memory, {name} context {width}x{height}"),
                format!(
                    "{:.1} MiB kept ({:.1} bytes/pixel); the view's guide and the shared intermediates {:.1} MiB",
                    mib(kept),
                    kept as f64 / (width as f64 * height as f64),
                    mib(shared)
                ),
            );
            let key = name.replace(" + ", "_and_").to_lowercase();
            json.insert(format!("{key}_context_kept_bytes"), json!(kept));
            json.insert(format!("{key}_guide_and_shared_bytes"), json!(shared));
        }
        Ok(())
    }

    /// The SDK's device memory at the end, by kind.
    pub fn memory(&mut self) {
        let mem = self.ctx.resource_allocations();
        self.report.key(
            "memory_bytes",
            json!({
                "total": mem.total_bytes(),
                "blas": mem.blas.bytes,
                "geometry_copies": mem.geometry_copies.bytes,
                "tlas": mem.tlas.bytes,
                "build_scratch": mem.build_scratch.bytes,
                "upload_rings": mem.upload_rings.bytes,
                "cache": mem.cache.bytes,
            }),
        );
        self.report.row(
            "SDK device memory",
            format!("{:.1} MiB (BLAS {:.1} MiB)", mem.total_bytes() as f64 / 1048576.0, mem.blas.bytes as f64 / 1048576.0),
        );
    }
}
