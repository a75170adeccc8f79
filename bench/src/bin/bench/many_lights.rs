//! Many shadowed lights by resampling (`TraceManyLightsTask`): the task's GPU time and each
//! pass's at 4,096 and 65,536 lights over the field, beside what brute force would cost (the
//! 32-light multi-shadow task's time for every 32 lights).
use crate::timing::median;
use crate::{sdk, Bench, Field};
use ash::vk;
use hybrid_rt::{LightInfo, LightListUpdate, LightType, ManyLightsContextInput, TaskKind, TraceManyLightsTask};
use hybrid_rt_testkit::reference::Rng;
use hybrid_rt_testkit::sdk_scene::run_frame;
use serde_json::json;

const GENERAL: vk::ImageLayout = vk::ImageLayout::GENERAL;

/// `count` small sphere lights of random colour over the field's ground, 0.8-3 m up, each
/// reaching 6 m.
fn lights(field: &Field, count: usize) -> Vec<LightInfo> {
    let extent = field
        .scene
        .instances
        .iter()
        .map(|i| i.transform.translation.x.abs().max(i.transform.translation.z.abs()))
        .fold(4.0f32, f32::max);
    let mut rng = Rng::new(5);
    (0..count)
        .map(|_| LightInfo {
            light_type: LightType::Point,
            position: glam::Vec3::new(
                (2.0 * rng.next_f32() - 1.0) * extent,
                0.8 + 2.2 * rng.next_f32(),
                (2.0 * rng.next_f32() - 1.0) * extent,
            ),
            radius: 0.05,
            range: 6.0,
            intensity: 0.2 + rng.next_f32(),
            color: [0.3 + rng.next_f32(), 0.3 + rng.next_f32(), 0.3 + rng.next_f32()],
            ..Default::default()
        })
        .collect()
}

impl Bench<'_> {
    /// The task at 4,096 and 65,536 lights (biased mode, the defaults), and per pass; beside
    /// brute force estimated from the 32-light multi-shadow time `multi_32_ms`.
    pub fn many_lights(&mut self, field: &Field, multi_32_ms: f64) -> Result<(), String> {
        let (width, height) = (self.settings.width, self.settings.height);
        let rgba =
            || self.host.image_cleared(vk::Format::R16G16B16A16_SFLOAT, width, height, vk::ImageUsageFlags::STORAGE, GENERAL);
        let (diffuse, specular) = (rgba()?, rgba()?);
        let mut rows = Vec::new();
        for count in [4096usize, 65536] {
            let context = self
                .ctx
                .create_many_lights_context(&ManyLightsContextInput {
                    max_width: width,
                    max_height: height,
                    max_lights: count as u32,
                })
                .map_err(sdk)?;
            let task = TraceManyLightsTask {
                context,
                common: field.gbuffer.trace_common(&field.camera),
                diffuse_output: diffuse.input(GENERAL),
                specular_output: specular.input(GENERAL),
                ..Default::default()
            };
            let mut times = Vec::new();
            let mut passes: Vec<(&'static str, Vec<f64>)> = Vec::new();
            for i in 0..self.settings.frames + 4 {
                let lights = if i == 0 { LightListUpdate::Replace(lights(field, count)) } else { LightListUpdate::Keep };
                self.frame.schedule_many_lights(&TraceManyLightsTask { lights, ..task.clone() }).map_err(sdk)?;
                let done = run_frame(self.host, self.ctx, &mut self.frame)?;
                if i < 4 {
                    continue;
                }
                times.push(done.gpu_ms(TaskKind::ManyLights));
                for p in done.pass_timings.iter().filter(|p| p.kind == TaskKind::ManyLights) {
                    match passes.iter_mut().find(|(name, _)| *name == p.pass) {
                        Some((_, v)) => v.push(p.gpu_ms),
                        None => passes.push((p.pass, vec![p.gpu_ms])),
                    }
                }
            }
            self.ctx.destroy_many_lights_context(context).map_err(sdk)?;
            let ms = median(times);
            let passes: Vec<(&str, f64)> = passes.into_iter().map(|(name, v)| (name, median(v))).collect();
            let brute = multi_32_ms * count as f64 / 32.0;
            self.report.row(
                format!("Many lights, resampled ({count} lights reaching 6 m) {width}x{height}"),
                format!(
                    "{ms:.3} ms ({}); brute force (32-light multi-shadow x {}) ~{brute:.1} ms",
                    passes.iter().map(|(n, t)| format!("{n} {t:.3}")).collect::<Vec<_>>().join(", "),
                    count / 32
                ),
            );
            rows.push(json!({
                "lights": count,
                "gpu_ms": ms,
                "passes": passes.iter().map(|(n, t)| json!({"pass": n, "gpu_ms": t})).collect::<Vec<_>>(),
                "brute_force_estimate_gpu_ms": brute,
            }));
        }
        self.report.key("many_lights", json!({ "width": width, "height": height, "rows": rows }));
        self.host.destroy_image(diffuse);
        self.host.destroy_image(specular);
        Ok(())
    }
}
