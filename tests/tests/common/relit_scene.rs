//! The relighting tests' scene (tests/tests/relight.rs, hit_lighting.rs): a ground plane and
//! a floating box under two hard lights, its caches registered with known albedos, and the
//! CPU reference's direct light.
use super::{assert_no_validation_errors, host_and_context};
use glam::{Affine3A, Vec3};
use hybrid_rt::{
    DebugOutput, InitSettings, InstanceInput, InstanceOperation, InstanceTask, LightInfo, LightType, RelightCacheTask,
    SurfelSettings, TraceSpecularTask,
};
use hybrid_rt_testkit::host::{Host, HostImage};
use hybrid_rt_testkit::reference::*;
use hybrid_rt_testkit::sdk_scene::*;

pub const W: u32 = 64;
pub const H: u32 = 64;
/// What a sample no light has reached yet holds: far from any lit value.
pub const UNLIT: [f32; 3] = [1.0, 0.0, 1.0];
pub const ALBEDO: [[f32; 3]; 2] = [[0.7, 0.6, 0.5], [0.3, 0.5, 0.8]];
pub const TILE: f32 = 0.05;

/// A ground plane and a floating box that shadows it; a sun and a coloured point light, both
/// hard (radius 0), so one relit frame is the converged answer and every difference from the
/// reference is the cache's own resolution.
pub fn scene() -> Scene {
    let mut s = Scene::default();
    let ground = s.add_mesh(Mesh::grid(4.0, 8));
    let cube = s.add_mesh(Mesh::cuboid(Vec3::splat(0.35)));
    s.add_instance(ground, Affine3A::IDENTITY);
    s.add_instance(cube, Affine3A::from_translation(Vec3::new(0.2, 0.9, -0.1)));
    s
}

pub fn lights() -> Vec<LightInfo> {
    vec![
        LightInfo { direction: Vec3::new(-0.4, -1.0, -0.3), intensity: 1.5, color: [1.0, 0.95, 0.9], ..Default::default() },
        LightInfo {
            light_type: LightType::Point,
            position: Vec3::new(-1.0, 1.6, 0.8),
            intensity: 2.0,
            color: [0.4, 0.6, 1.0],
            ..Default::default()
        },
    ]
}

pub fn camera() -> Camera {
    Camera::look_at(Vec3::new(0.0, 3.2, 2.4), Vec3::new(0.0, 0.0, -0.2))
}

/// The reference: albedo x sum of colour x irradiance x visibility (one ray to each hard light).
pub fn reference_radiance(tracer: &Tracer, p: Vec3, n: Vec3, albedo: [f32; 3]) -> Vec3 {
    reference_light(tracer, p, n, albedo).0
}

/// `reference_radiance`, and whether a light that faces the point is occluded there.
pub fn reference_light(tracer: &Tracer, p: Vec3, n: Vec3, albedo: [f32; 3]) -> (Vec3, bool) {
    let (mut e, mut occluded) = (Vec3::ZERO, false);
    for l in lights() {
        let w = light_weight(&l, p, n);
        if w <= 0.0 {
            continue;
        }
        let (dir, tmax) = match l.light_type {
            LightType::Directional => (-l.direction.normalize(), f32::MAX),
            _ => ((l.position - p).normalize(), (l.position - p).length() * 0.999),
        };
        if tracer.closest_hit(p + n * 1e-3, dir, 0.0, tmax).is_none() {
            e += Vec3::from(l.color) * w;
        } else {
            occluded = true;
        }
    }
    (Vec3::from(albedo) * e, occluded)
}

pub struct Fixture {
    pub host: Host,
    pub ctx: hybrid_rt::ExecuteContext,
    pub frame: hybrid_rt::TaskContainer,
    pub gpu_scene: SceneOnGpu,
    pub scene: Scene,
}

impl Fixture {
    /// Registers the scene with the albedos above (two frames: BVH and read-back, then the caches).
    pub fn new() -> Fixture {
        Fixture::with(scene(), &ALBEDO)
    }

    /// `new` for another scene, instance i with albedo `albedos[i]`.
    pub fn with(scene: Scene, albedos: &[[f32; 3]]) -> Fixture {
        let (host, ctx) = host_and_context(InitSettings::default());
        let mut frame = ctx.create_task_container();
        let surfels = SurfelSettings { tile_unit_length: TILE, ..Default::default() };
        let gpu_scene = SceneOnGpu::register_with(&host, &ctx, &mut frame, &scene, surfels, UNLIT).unwrap();
        for (i, inst) in scene.instances.iter().enumerate() {
            let input = InstanceInput {
                geometry: gpu_scene.geometries[inst.mesh],
                transform: inst.transform,
                initial_tile_color: UNLIT,
                albedo: albedos[i],
                ..Default::default()
            };
            let task = InstanceTask { handle: gpu_scene.instances[i], operation: InstanceOperation::Update, input };
            frame.schedule_instance(&task).unwrap();
        }
        for _ in 0..2 {
            frame.schedule_bvh_build(&Default::default()).unwrap();
            run_frame(&host, &ctx, &mut frame).unwrap();
        }
        Fixture { host, ctx, frame, gpu_scene, scene }
    }

    pub fn relight(&mut self, max_samples: u32) {
        self.relight_with(&RelightCacheTask { lights: lights(), max_samples, ..Default::default() });
    }

    pub fn relight_with(&mut self, task: &RelightCacheTask) {
        self.frame.schedule_cache_relight(task).unwrap();
        let done = run_frame(&self.host, &self.ctx, &mut self.frame).unwrap();
        assert!(done.timings.iter().any(|t| t.kind == hybrid_rt::TaskKind::CacheRelight) || done.timings.is_empty());
    }

    /// The cache as the camera sees it (`DebugOutput::DirectLightingCache`).
    pub fn cache_view(&mut self, images: &GBufferImages) -> Vec<[f32; 4]> {
        self.cache_view_from(images, &camera())
    }

    pub fn cache_view_from(&mut self, images: &GBufferImages, camera: &Camera) -> Vec<[f32; 4]> {
        let mode = DebugOutput::DirectLightingCache;
        debug_view(&self.host, &self.ctx, &mut self.frame, images, camera, mode, false, (W, H)).unwrap()
    }

    /// Runs `task` once, into a fresh RGBA32F output, and reads that back.
    pub fn trace_specular(&mut self, task: TraceSpecularTask) -> Vec<[f32; 4]> {
        render_rgba(&self.host, &self.ctx, &mut self.frame, (W, H), |c, output| {
            c.schedule_specular(&TraceSpecularTask { output, ..task }).map_err(|e| e.to_string())
        })
        .unwrap()
    }

    pub fn finish(self, images: GBufferImages, lits: Vec<HostImage>) {
        images.destroy(&self.host);
        for l in lits {
            self.host.destroy_image(l);
        }
        self.gpu_scene.destroy(&self.host);
        drop(self.ctx);
        assert_no_validation_errors();
    }
}
