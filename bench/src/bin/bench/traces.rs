//! The trace sections: AO beside the bare-ray floor per rays-per-pixel setting, direct-lighting
//! injection, then shadows, diffuse GI, reflections and multi-light shadows at one ray per
//! pixel.
use crate::timing::{median, warm_up};
use crate::{sdk, Bench, Field};
use ash::vk;
use hybrid_rt::{
    HitLighting, LightInfo, LightType, TaskKind, TraceCommon, TraceDiffuseTask, TraceMultiShadowTask, TraceShadowTask,
    TraceSpecularTask,
};
use hybrid_rt_host::HostImage;
use hybrid_rt_testkit::sdk_scene::{run_frame, READ};
use serde_json::json;

const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;

/// The 1-ray traces of the field (the denoise rows clean them again) and the multi-light
/// shadows' visibility image they write.
pub struct Traces {
    pub shadow: TraceShadowTask,
    pub diffuse: TraceDiffuseTask,
    pub specular: TraceSpecularTask,
    pub multi: TraceMultiShadowTask,
    pub visibility: HostImage,
    /// GPU time of 32 ranged point lights in one multi-shadow task (brute force's unit).
    pub multi_32_ms: f64,
}

/// Median GPU times of the 1-ray traces (with their floors where the row shows one).
struct TraceTimes {
    shadow: (f64, f64),
    shadow_first_hit: f64,
    diffuse: (f64, f64),
    specular: (f64, f64),
    multi: (f64, f64),
    multi_first_hit: f64,
    multi_32_ranged: f64,
    multi_32_unlimited: f64,
}

impl Bench<'_> {
    fn storage_image(&self, format: vk::Format) -> Result<HostImage, String> {
        let (w, h) = (self.settings.width, self.settings.height);
        self.host.image_cleared(format, w, h, vk::ImageUsageFlags::STORAGE, GENERAL)
    }

    /// AO beside the bare-ray floor, one row per rays-per-pixel setting.
    pub fn ambient_occlusion(&mut self, field: &Field) -> Result<(), String> {
        let mut rows = Vec::new();
        for rays in self.settings.rays.clone() {
            rows.push(self.ambient_occlusion_row(field, rays)?);
        }
        self.report.key("ao", json!(rows));
        Ok(())
    }

    /// AO at `rays` per pixel: after a warm-up, ours and the floor alternate frame by frame so
    /// any drift hits both alike; medians after 8 frames, with the recording's CPU time.
    fn ambient_occlusion_row(&mut self, field: &Field, rays: u32) -> Result<serde_json::Value, String> {
        let (width, height) = (self.settings.width, self.settings.height);
        let task = field.gbuffer.ao_task(&field.camera, 1.0, rays);
        warm_up(self.settings.warmup, || {
            self.frame.schedule_ambient_occlusion(&task).map_err(sdk)?;
            run_frame(self.host, self.ctx, &mut self.frame).map(drop)
        })?;
        let mut times = [Vec::new(), Vec::new()];
        let mut record = Vec::new();
        for i in 0..(2 * self.settings.frames + 8) {
            let floor = i % 2 == 1;
            self.ctx.set_bench_floor_mode(floor).map_err(sdk)?;
            self.frame.schedule_ambient_occlusion(&task).map_err(sdk)?;
            let (done, cpu_us) = self.recorded_frame()?;
            let ms = done.gpu_ms(TaskKind::AmbientOcclusion);
            if i >= 8 {
                times[floor as usize].push(ms);
                if !floor {
                    record.push(cpu_us);
                }
            }
        }
        self.ctx.set_bench_floor_mode(false).map_err(sdk)?;
        let [ao, fl] = times.map(median);
        let rays_total = width as f64 * height as f64 * rays as f64;
        self.report.row(
            format!("AO {width}x{height}, {rays} ray(s)/pixel"),
            format!("{ao:.3} ms ({:.0} M rays/s); floor {fl:.3} ms; ratio {:.2}", rays_total / (ao * 1e-3) / 1e6, ao / fl),
        );
        Ok(json!({
            "width": width,
            "height": height,
            "rays_per_pixel": rays,
            "gpu_ms": ao,
            "floor_gpu_ms": fl,
            "ratio_to_floor": ao / fl,
            "rays_per_s": rays_total / (ao * 1e-3),
            "build_gpu_task_cpu_us": median(record),
        }))
    }

    /// Direct-lighting injection of a full-resolution lit frame, with its resolve; and the
    /// caches' size that made.
    pub fn injection(&mut self, field: &Field) -> Result<(), String> {
        let (width, height) = (self.settings.width, self.settings.height);
        let tile_unit = self.settings.tile_unit_length;
        let lit_texels = vec![[0.5f32, 0.4, 0.3, 1.0]; (width * height) as usize];
        let lit = self.host.image_with_data(
            vk::Format::R32G32B32A32_SFLOAT,
            width,
            height,
            vk::ImageUsageFlags::SAMPLED,
            bytemuck::cast_slice(&lit_texels),
            READ,
        )?;
        let inject = hybrid_rt::DirectLightingInjectionTask {
            depth: hybrid_rt::DepthInput { image: field.gbuffer.depth.input(READ), depth_type: hybrid_rt::DepthType::ClipSpace },
            lit: lit.input(READ),
            viewport: hybrid_rt::Viewport::full(width, height),
            camera: field.camera.sdk_camera(width, height),
            ..Default::default()
        };
        let inject_ms =
            self.time_frames(TaskKind::DirectLightingInjection, |f| f.schedule_direct_lighting_injection(&inject).map_err(sdk))?;
        let cache_bytes: Vec<u64> = field.gpu.instances.iter().map(|h| self.ctx.instance_cache_bytes(*h).unwrap_or(0)).collect();
        let cache_total: u64 = cache_bytes.iter().sum();
        let cache_mean = cache_total as f64 / cache_bytes.len().max(1) as f64;
        self.report.row(format!("Direct-lighting injection {width}x{height} (+ resolve)"), format!("{inject_ms:.3} ms"));
        self.report.row(
            format!("Cache per instance (tile_unit_length {tile_unit})"),
            format!(
                "{:.1} KiB mean, {:.1} MiB over {} instances",
                cache_mean / 1024.0,
                cache_total as f64 / 1048576.0,
                cache_bytes.len()
            ),
        );
        self.report.key(
            "injection",
            json!({
                "width": width,
                "height": height,
                "gpu_ms": inject_ms,
                "tile_unit_length": tile_unit,
                "cache_bytes_total": cache_total,
                "cache_bytes_mean_per_instance": cache_mean,
            }),
        );
        self.host.destroy_image(lit);
        Ok(())
    }

    /// Shadows (closest and first hit), diffuse GI, specular, mirrors and multi-light shadows
    /// at one ray per pixel, each beside its floor where the row shows one. Returns the traces
    /// for the denoise rows.
    pub fn traces(&mut self, field: &Field) -> Result<Traces, String> {
        let rgba = self.storage_image(vk::Format::R16G16B16A16_SFLOAT)?;
        let common = field.gbuffer.trace_common(&field.camera);
        let output = rgba.input(GENERAL);
        let shadow = TraceShadowTask {
            common,
            light: LightInfo { direction: glam::Vec3::new(0.5, -1.0, 0.3), angular_extent: 0.02, ..Default::default() },
            output,
            rays_per_pixel: 1,
            ..Default::default()
        };
        let shadow_ms = self.time_vs_floor(TaskKind::Shadow, |f| f.schedule_shadow(&shadow).map_err(sdk))?;
        // First-hit traversal: the same visibility, an occluder's distance instead of the closest.
        let shadow_first = TraceShadowTask { first_hit: true, ..shadow };
        let (shadow_first_hit, _) = self.time_vs_floor(TaskKind::Shadow, |f| f.schedule_shadow(&shadow_first).map_err(sdk))?;
        let diffuse = TraceDiffuseTask { common, output, ray_length: 100.0, ..Default::default() };
        let diffuse_ms = self.time_vs_floor(TaskKind::Diffuse, |f| f.schedule_diffuse(&diffuse).map_err(sdk))?;
        let mut glossy = common;
        glossy.roughness.global_roughness = 0.3;
        let specular = TraceSpecularTask { common: glossy, output, ray_length: 100.0, ..Default::default() };
        let specular_ms = self.time_vs_floor(TaskKind::Specular, |f| f.schedule_specular(&specular).map_err(sdk))?;
        self.mirrors(common, output, shadow.light)?;
        let visibility = self.storage_image(vk::Format::R32_UINT)?;
        let multi = TraceMultiShadowTask {
            common,
            lights: (0..4)
                .map(|k| LightInfo {
                    light_type: LightType::Point,
                    position: glam::Vec3::new(-6.0 + 4.0 * k as f32, 4.0, 0.0),
                    radius: 0.3,
                    ..Default::default()
                })
                .collect(),
            visibility: visibility.input(GENERAL),
            packed: output,
            rays_per_pixel: 1,
            first_hit: false,
            ..Default::default()
        };
        let multi_ms = self.time_vs_floor(TaskKind::MultiShadow, |f| f.schedule_multi_shadow(&multi).map_err(sdk))?;
        let multi_first = TraceMultiShadowTask { first_hit: true, ..multi.clone() };
        let (multi_first_hit, _) =
            self.time_vs_floor(TaskKind::MultiShadow, |f| f.schedule_multi_shadow(&multi_first).map_err(sdk))?;
        let (multi_32_ranged, multi_32_unlimited) = self.multi_light_32(&multi)?;
        self.trace_rows(&TraceTimes {
            shadow: shadow_ms,
            shadow_first_hit,
            diffuse: diffuse_ms,
            specular: specular_ms,
            multi: multi_ms,
            multi_first_hit,
            multi_32_ranged,
            multi_32_unlimited,
        });
        self.host.destroy_image(rgba);
        Ok(Traces { shadow, diffuse, specular, multi, visibility, multi_32_ms: multi_32_ranged })
    }

    /// Mirrors shaded from the cache, and hit-lit from a sun and a point light (a shadow ray
    /// each) with one gather ray: what hit lighting costs per mirror pixel.
    fn mirrors(&mut self, common: TraceCommon, output: hybrid_rt::ImageInput, sun: LightInfo) -> Result<(), String> {
        let (width, height) = (self.settings.width, self.settings.height);
        let mut mirror_common = common;
        mirror_common.roughness.global_roughness = 0.0;
        let mirror = TraceSpecularTask { common: mirror_common, output, ray_length: 100.0, ..Default::default() };
        let (mirror_ms, _) = self.time_vs_floor(TaskKind::Specular, |f| f.schedule_specular(&mirror).map_err(sdk))?;
        let hit_lit = TraceSpecularTask {
            hit_lighting: HitLighting {
                lights: vec![
                    sun,
                    LightInfo {
                        light_type: LightType::Point,
                        position: glam::Vec3::new(0.0, 4.0, 0.0),
                        radius: 0.3,
                        ..Default::default()
                    },
                ],
                max_roughness: 0.0,
                ..Default::default()
            },
            ..mirror.clone()
        };
        let (hit_lit_ms, _) = self.time_vs_floor(TaskKind::Specular, |f| f.schedule_specular(&hit_lit).map_err(sdk))?;
        self.report.row(
            format!("Specular mirrors {width}x{height}: from the cache / hit-lit (2 lights, the cache's residual)"),
            format!("{mirror_ms:.3} ms / {hit_lit_ms:.3} ms"),
        );
        self.report.key("specular_mirror", json!({"cache_gpu_ms": mirror_ms, "hit_lit_gpu_ms": hit_lit_ms}));
        Ok(())
    }

    /// 32 lights (Kickstart RT's limit): an 8 x 4 grid of point lights 4 m apart, each reaching
    /// 6 m (rays only where a light reaches), and the same lights unlimited. Returns both
    /// times.
    fn multi_light_32(&mut self, multi: &TraceMultiShadowTask) -> Result<(f64, f64), String> {
        let (width, height) = (self.settings.width, self.settings.height);
        let vis_low = self.storage_image(vk::Format::R32G32B32A32_UINT)?;
        let vis_high = self.storage_image(vk::Format::R32G32B32A32_UINT)?;
        let grid: Vec<LightInfo> = (0..32)
            .map(|k| LightInfo {
                light_type: LightType::Point,
                position: glam::Vec3::new(-14.0 + 4.0 * (k % 8) as f32, 4.0, -6.0 + 4.0 * (k / 8) as f32),
                radius: 0.3,
                range: 6.0,
                ..Default::default()
            })
            .collect();
        let ranged = TraceMultiShadowTask {
            lights: grid.clone(),
            visibility: vis_low.input(GENERAL),
            visibility_high: vis_high.input(GENERAL),
            ..multi.clone()
        };
        let (ranged_ms, _) = self.time_vs_floor(TaskKind::MultiShadow, |f| f.schedule_multi_shadow(&ranged).map_err(sdk))?;
        let unlimited =
            TraceMultiShadowTask { lights: grid.iter().map(|l| LightInfo { range: 0.0, ..*l }).collect(), ..ranged.clone() };
        let (unlimited_ms, _) =
            self.time_vs_floor(TaskKind::MultiShadow, |f| f.schedule_multi_shadow(&unlimited).map_err(sdk))?;
        self.report.row(
            format!("Multi-light shadows (32 point lights reaching 6 m, 1 ray/pixel each) {width}x{height}"),
            format!("{ranged_ms:.3} ms; unlimited range {unlimited_ms:.3} ms"),
        );
        self.host.destroy_image(vis_low);
        self.host.destroy_image(vis_high);
        Ok((ranged_ms, unlimited_ms))
    }

    /// The 1-ray traces' rows beside their floors, the first-hit speed-ups, and their JSON.
    fn trace_rows(&mut self, t: &TraceTimes) {
        let (width, height) = (self.settings.width, self.settings.height);
        for (name, (ms, fl)) in [
            ("Multi-light shadows (4 point lights, 1 ray/pixel each)", t.multi),
            ("Shadow (sun, 1 ray/pixel)", t.shadow),
            ("Diffuse GI (1 ray/pixel)", t.diffuse),
            ("Specular (roughness 0.3, 1 ray/pixel)", t.specular),
        ] {
            self.report.row(format!("{name} {width}x{height}"), format!("{ms:.3} ms; floor {fl:.3} ms; ratio {:.2}", ms / fl));
        }
        for (name, first, closest) in [
            ("Shadow (sun), first-hit mode", t.shadow_first_hit, t.shadow.0),
            ("Multi-light shadows, first-hit mode", t.multi_first_hit, t.multi.0),
        ] {
            self.report.row(
                format!("{name} {width}x{height}"),
                format!("{first:.3} ms; closest-hit {closest:.3} ms; speed-up {:.2}x", closest / first),
            );
        }
        self.report.key(
            "traces",
            json!({
                "width": width,
                "height": height,
                "shadow_gpu_ms": t.shadow.0,
                "shadow_floor_gpu_ms": t.shadow.1,
                "diffuse_gpu_ms": t.diffuse.0,
                "diffuse_floor_gpu_ms": t.diffuse.1,
                "specular_gpu_ms": t.specular.0,
                "specular_floor_gpu_ms": t.specular.1,
                "multi_shadow_4_lights_gpu_ms": t.multi.0,
                "multi_shadow_floor_gpu_ms": t.multi.1,
                "shadow_first_hit_gpu_ms": t.shadow_first_hit,
                "multi_shadow_first_hit_gpu_ms": t.multi_first_hit,
                "multi_shadow_32_lights_ranged_gpu_ms": t.multi_32_ranged,
                "multi_shadow_32_lights_unlimited_gpu_ms": t.multi_32_unlimited,
            }),
        );
    }
}
