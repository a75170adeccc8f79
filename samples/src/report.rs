//! The sample's account of a run: the frame's GPU time broken down per SDK task (from the
//! SDK's timestamp queries, handed back with each ticket) and per pass of the sample's own
//! (its timestamp queries), means over the frames after the first; and the SDK's memory.
use crate::renderer::{Renderer, Stats};
use serde::Serialize;

pub struct Report {
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub frames: u64,
    pub first_frame_bvh_ms: f64,
    pub sdk: Vec<(String, f64)>,
    /// ("task label: pass", mean ms) with `--time-passes`.
    pub sdk_passes: Vec<(String, f64)>,
    pub passes: Vec<(String, f64)>,
    pub sdk_bytes: u64,
    /// The SDK's device memory by kind (`ResourceAllocations`), in bytes.
    pub sdk_by_kind: Vec<(&'static str, u64)>,
    pub cache_bytes: u64,
    pub denoiser_bytes: u64,
    pub blas_bytes: u64,
    pub triangles: usize,
    /// The caches under `InitSettings::cache_budget_bytes` (`--cache-budget-mib`).
    pub cache: hybrid_rt::CacheReport,
}

impl Report {
    pub fn new(r: &Renderer) -> Report {
        let mem = r.ctx.resource_allocations();
        Report {
            device: r.ctx.device_name().to_string(),
            width: r.settings.width,
            height: r.settings.height,
            frames: r.stats.frames,
            first_frame_bvh_ms: r.stats.first_frame_bvh_ms,
            sdk: Stats::means(&r.stats.sdk),
            sdk_passes: Stats::means(&r.stats.sdk_passes),
            passes: Stats::means(&r.stats.passes),
            sdk_bytes: mem.total_bytes(),
            sdk_by_kind: vec![
                ("geometry copies", mem.geometry_copies.bytes),
                ("BLAS", mem.blas.bytes),
                ("build scratch", mem.build_scratch.bytes),
                ("TLAS", mem.tlas.bytes),
                ("upload rings", mem.upload_rings.bytes),
                ("shader binding tables", mem.pipelines.bytes),
                ("caches", mem.cache.bytes),
                ("read-back", mem.readback.bytes),
                ("denoisers", mem.denoiser.bytes),
                ("many lights", mem.many_lights.bytes),
            ],
            cache_bytes: r.cache_bytes(),
            denoiser_bytes: mem.denoiser.bytes,
            blas_bytes: mem.blas.bytes,
            triangles: r.scene.scene.triangle_count(),
            cache: r.ctx.cache_report(),
        }
    }

    /// The whole frame: the sample's passes, of which "SDK (all tasks)" spans the SDK's.
    pub fn frame_ms(&self) -> f64 {
        self.passes.iter().map(|(_, ms)| ms).sum()
    }

    /// SDK task times without the parts the BVH total already contains.
    fn sdk_tasks(&self) -> impl Iterator<Item = &(String, f64)> {
        self.sdk.iter().filter(|(l, _)| l != "BlasBuild" && l != "TlasBuild")
    }

    pub fn text(&self) -> String {
        let mib = |b: u64| b as f64 / 1048576.0;
        let mut s = format!(
            "GPU time per frame on {} at {}x{} (mean of {} frames after the first; the first frame's BVH build took {:.3} ms):\n",
            self.device, self.width, self.height, self.frames, self.first_frame_bvh_ms
        );
        for (label, ms) in &self.passes {
            s += &format!("  {label:<40} {ms:8.3} ms\n");
            if label.starts_with("SDK") {
                for (task, ms) in self.sdk_tasks() {
                    s += &format!("    {task:<38} {ms:8.3} ms\n");
                    let prefix = format!("{task}: ");
                    for (pass, ms) in self.sdk_passes.iter().filter(|(p, _)| p.starts_with(&prefix)) {
                        s += &format!("      {:<36} {ms:8.3} ms\n", &pass[prefix.len()..]);
                    }
                }
            }
        }
        s += &format!("  {:<40} {:8.3} ms\n", "frame", self.frame_ms());
        s += &format!(
            "SDK memory: {:.1} MiB ({} triangles: BLAS {:.1} MiB; direct-lighting caches {:.1} MiB; denoiser history {:.1} MiB)\n",
            mib(self.sdk_bytes),
            self.triangles,
            mib(self.blas_bytes),
            mib(self.cache_bytes),
            mib(self.denoiser_bytes)
        );
        let kinds: Vec<String> = self.sdk_by_kind.iter().map(|(k, b)| format!("{k} {:.1}", mib(*b))).collect();
        s += &format!("SDK memory by kind (MiB): {}\n", kinds.join(", "));
        let c = &self.cache;
        s += &format!(
            "Direct-lighting caches: {:.1} MiB resident, budget {}; {} instances waiting for a cache, {} evictions ({:.1} MiB)\n",
            mib(c.resident_bytes),
            if c.budget_bytes == 0 { "none".to_string() } else { format!("{:.1} MiB", mib(c.budget_bytes)) },
            c.waiting_instances,
            c.evictions,
            mib(c.evicted_bytes)
        );
        s
    }

    /// A compact line for a window title.
    pub fn title(&self) -> String {
        let sdk: f64 = self.passes.iter().filter(|(l, _)| l.starts_with("SDK")).map(|(_, ms)| ms).sum();
        format!("frame {:.2} ms (SDK {:.2} ms)", self.frame_ms(), sdk)
    }

    /// The report as JSON (serde_json: names are escaped whatever the device calls itself).
    /// `frames` counts every frame rendered; the times are means over `measured_frames`, the
    /// frames after the first (which builds the BVH).
    pub fn json(&self) -> String {
        #[derive(Serialize)]
        struct Json<'a> {
            device: &'a str,
            width: u32,
            height: u32,
            frames: u64,
            measured_frames: u64,
            first_frame_bvh_ms: f64,
            frame_gpu_ms: f64,
            passes: Vec<Timing<'a>>,
            sdk_tasks: Vec<Timing<'a>>,
            sdk_passes: Vec<Timing<'a>>,
            sdk_bytes: u64,
            sdk_bytes_by_kind: std::collections::BTreeMap<&'a str, u64>,
            cache_bytes: u64,
            denoiser_bytes: u64,
            blas_bytes: u64,
            triangles: usize,
            cache_resident_bytes: u64,
            cache_budget_bytes: u64,
            cache_evicted_bytes: u64,
        }
        let j = Json {
            device: &self.device,
            width: self.width,
            height: self.height,
            frames: self.frames + 1,
            measured_frames: self.frames,
            first_frame_bvh_ms: self.first_frame_bvh_ms,
            frame_gpu_ms: self.frame_ms(),
            passes: timings(self.passes.iter()),
            sdk_tasks: timings(self.sdk_tasks()),
            sdk_passes: timings(self.sdk_passes.iter()),
            sdk_bytes: self.sdk_bytes,
            sdk_bytes_by_kind: self.sdk_by_kind.iter().copied().collect(),
            cache_bytes: self.cache_bytes,
            denoiser_bytes: self.denoiser_bytes,
            blas_bytes: self.blas_bytes,
            triangles: self.triangles,
            cache_resident_bytes: self.cache.resident_bytes,
            cache_budget_bytes: self.cache.budget_bytes,
            cache_evicted_bytes: self.cache.evicted_bytes,
        };
        // Serialising plain numbers and strings cannot fail.
        serde_json::to_string_pretty(&j).unwrap_or_default() + "\n"
    }
}

#[derive(Serialize)]
struct Timing<'a> {
    label: &'a str,
    gpu_ms: f64,
}

fn timings<'a>(v: impl Iterator<Item = &'a (String, f64)>) -> Vec<Timing<'a>> {
    v.map(|(l, ms)| Timing { label: l, gpu_ms: *ms }).collect()
}
