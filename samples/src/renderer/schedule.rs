//! The SDK's part of a frame: everything goes into one task container, each task named as it
//! is scheduled (`TaskContainer::set_task_label`), which is what its GPU time is reported as
//! when the ticket comes back (`Renderer::retire`) and what RenderDoc and Nsight show.
use super::inputs::Inputs;
use super::resources::work_image;
use super::{sdk_err, FrameCameras, Renderer, GENERAL, SLOTS};
use glam::Affine3A;
use hybrid_rt::*;
use hybrid_rt_host::HostResult;

/// The label of the scene's changes and the BVH build: the BVH work's timing carries the label
/// of the frame's first scene task.
pub(super) const BVH_LABEL: &str = "BVH (updates, refit, TLAS)";

/// Schedules one task (`task` calls the container's `schedule_*`) and names it `label`.
pub(super) fn schedule(
    container: &mut TaskContainer,
    label: &str,
    task: impl FnOnce(&mut TaskContainer) -> hybrid_rt::Result<()>,
) -> HostResult<()> {
    task(container).map_err(sdk_err)?;
    container.set_task_label(label).map_err(sdk_err)
}

/// What the report calls a timing: its task's label, or its kind's name where it has none
/// (the BLAS and TLAS builds nested in the BVH work, the cache update).
pub(super) fn timing_label(done: &CompletedTask, timing: &TaskTiming) -> String {
    done.label(timing).map_or_else(|| format!("{:?}", timing.kind), str::to_owned)
}

impl Renderer<'_> {
    /// Schedules the SDK's tasks of the frame in `slot` (the moving instances at
    /// `transforms`; `deformed`: the deforming mesh and its vertex buffer of this frame) into
    /// the container.
    pub(super) fn schedule_frame(
        &mut self,
        slot: usize,
        transforms: &[Affine3A],
        deformed: &[(usize, ash::vk::Buffer)],
        cameras: &FrameCameras,
        debug: &[DebugOutput],
        time: f32,
    ) -> HostResult<()> {
        let (sun, point) = self.lights();
        self.schedule_scene_changes(transforms, deformed)?;
        if self.frame > 0 {
            self.schedule_injection((slot + SLOTS - 1) % SLOTS, cameras)?;
        }
        // Surfaces no camera has injected (the column's back, seen only in the mirror) take
        // the sun's and the point light's direct light and a bounce of the caches' light (the
        // walls', the sky's), before anything reads the cache.
        let shining = self.shining_lights();
        if self.settings.relight_samples > 0 && !shining.is_empty() {
            let task = RelightCacheTask {
                lights: shining.clone(),
                max_samples: self.settings.relight_samples,
                bounce: true,
                sky: self.scene.sky,
                ..Default::default()
            };
            schedule(&mut self.container, "cache relight", |c| c.schedule_cache_relight(&task))?;
        }
        let main = Inputs::of(&self.slots[slot].main.targets, &cameras.main);
        let lidar = Inputs::of(&self.slots[slot].lidar.targets, &cameras.lidar);
        self.schedule_shadows(&main, &lidar, sun, point)?;
        self.schedule_file_light_shadows(&main, &lidar)?;
        if let Some(many) = &mut self.many {
            let mut common = main.common;
            common.random_numbers = self.settings.random_numbers;
            many.schedule(&mut self.container, common, main.denoising, time, self.many_lights_debug)?;
        }
        self.schedule_gi_and_reflections(&main, shining)?;
        self.schedule_debug_views(&main, debug)
    }

    /// The scene's changes (the moving instances, the deforming mesh) and a throttled BVH
    /// build.
    fn schedule_scene_changes(&mut self, transforms: &[Affine3A], deformed: &[(usize, ash::vk::Buffer)]) -> HostResult<()> {
        let c = &mut self.container;
        for (i, t) in transforms.iter().enumerate() {
            if self.scene.is_dynamic(i) {
                let input = InstanceInput {
                    geometry: self.geometries[self.scene.scene.instances[i].mesh],
                    transform: *t,
                    initial_tile_color: self.settings.unlit_color,
                    albedo: self.scene.diffuse_albedo(i),
                    emission: self.scene.emission(i),
                    ..Default::default()
                };
                let task = InstanceTask { handle: self.instances[i], operation: InstanceOperation::Update, input };
                schedule(c, BVH_LABEL, |c| c.schedule_instance(&task))?;
            }
        }
        for &(mesh, buffer) in deformed {
            let base = super::sdk_geometry_input(&self.scene, &self.meshes, mesh, true);
            let input = GeometryInput { vertices: VertexBufferInput { buffer, ..base.vertices }, ..base };
            let task = GeometryTask { handle: self.geometries[mesh], operation: TaskOperation::Update, input };
            // SAFETY: the engine's buffers the task names are alive.
            schedule(c, BVH_LABEL, |c| unsafe { c.schedule_geometry(&task) })?;
        }
        let build = BvhBuildTask {
            max_blas_build_count: self.settings.max_blas_build_count,
            tlas_max_refits: self.settings.tlas_max_refits,
        };
        schedule(c, BVH_LABEL, |c| c.schedule_bvh_build(&build))
    }

    /// Light injection of last frame's lit images, main and lidar (the lit image of this frame
    /// needs this frame's shadows, so the cache runs a frame behind).
    fn schedule_injection(&mut self, prev: usize, cameras: &FrameCameras) -> HostResult<()> {
        let window = self.settings.injection_window;
        let main_stride = match self.settings.injection_stride {
            0 => (self.settings.height / 540).max(1),
            s => s,
        };
        let p = &self.slots[prev];
        for (view, cam, stride, label) in [
            (&p.main, &cameras.prev_main, main_stride, "inject main (last frame)"),
            (&p.lidar, &cameras.prev_lidar, 1, "inject lidar (last frame)"),
        ] {
            let inputs = Inputs::of(&view.targets, cam);
            let task = DirectLightingInjectionTask {
                depth: inputs.common.depth,
                lit: view.lit.input(GENERAL),
                viewport: inputs.common.viewport,
                camera: inputs.common.camera,
                average_window: window,
                injection_resolution_stride: stride,
                ..Default::default()
            };
            schedule(&mut self.container, label, |c| c.schedule_direct_lighting_injection(&task))?;
        }
        Ok(())
    }

    /// Shadows of the sun and the point light where they shine: the main view 1 ray (or the
    /// settings' rays) and denoised, the lidar view its own rays, undenoised (its image only
    /// feeds the cache's running average).
    fn schedule_shadows(&mut self, main: &Inputs, lidar: &Inputs, sun: LightInfo, point: LightInfo) -> HostResult<()> {
        let wk = &self.work;
        let c = &mut self.container;
        let mut common = main.common;
        common.half_resolution_mode =
            if self.settings.checkerboard { HalfResolutionMode::Checkerboard } else { HalfResolutionMode::Off };
        common.random_numbers = self.settings.random_numbers;
        for (light, noisy, out, context, labels) in [
            (sun, &wk.sun_noisy, &wk.sun, self.denoisers.sun, ["shadow sun", "denoise shadow sun"]),
            (point, &wk.point_noisy, &wk.point, self.denoisers.point, ["shadow point", "denoise shadow point"]),
        ]
        .into_iter()
        .filter(|l| l.0.intensity > 0.0)
        {
            let trace = TraceShadowTask {
                common,
                light,
                output: noisy.input(GENERAL),
                rays_per_pixel: self.settings.rays_per_pixel,
                ..Default::default()
            };
            schedule(c, labels[0], |c| c.schedule_shadow(&trace))?;
            let denoise = DenoiseShadowTask {
                context,
                common: main.denoising,
                light,
                input: noisy.input(GENERAL),
                output: out.input(GENERAL),
            };
            schedule(c, labels[1], |c| c.schedule_denoise_shadow(&denoise))?;
        }
        let lidar_rays = self.settings.lidar_rays;
        for (light, out) in [(sun, &wk.lidar_sun), (point, &wk.lidar_point)].into_iter().filter(|l| l.0.intensity > 0.0) {
            let trace = TraceShadowTask {
                common: lidar.common,
                light,
                output: out.input(GENERAL),
                rays_per_pixel: lidar_rays,
                ..Default::default()
            };
            schedule(c, "shadow lidar", |c| c.schedule_shadow(&trace))?;
        }
        Ok(())
    }

    /// The file's lights' shadows, all in one multi-light trace per view: the main view's
    /// denoised (the mean visibility weighted by each light's unshadowed irradiance, which the
    /// lighting pass multiplies into their summed light), the lidar view's raw.
    fn schedule_file_light_shadows(&mut self, main: &Inputs, lidar: &Inputs) -> HostResult<()> {
        let (Some(images), Some(context)) = (&self.work.lights, self.denoisers.lights) else { return Ok(()) };
        let c = &mut self.container;
        let mut common = main.common;
        common.half_resolution_mode =
            if self.settings.checkerboard { HalfResolutionMode::Checkerboard } else { HalfResolutionMode::Off };
        common.random_numbers = self.settings.random_numbers;
        let trace = |common: TraceCommon, out: &super::resources::MultiShadowImages, rays: u32| TraceMultiShadowTask {
            common,
            lights: self.scene.file_lights.clone(),
            visibility: out.visibility.input(GENERAL),
            visibility_high: out.visibility_high.as_ref().map_or_else(Default::default, |i| i.input(GENERAL)),
            packed: out.packed.input(GENERAL),
            rays_per_pixel: rays,
            ..Default::default()
        };
        let main_trace = trace(common, &images.main, self.settings.rays_per_pixel);
        schedule(c, "shadow file lights", |c| c.schedule_multi_shadow(&main_trace))?;
        let denoise = DenoiseMultiShadowTask {
            context,
            common: main.denoising,
            input: images.main.packed.input(GENERAL),
            output: images.denoised.input(GENERAL),
        };
        schedule(c, "denoise shadow file lights", |c| c.schedule_denoise_multi_shadow(&denoise))?;
        let lidar_trace = trace(lidar.common, &images.lidar, self.settings.lidar_rays);
        schedule(c, "shadow lidar", |c| c.schedule_multi_shadow(&lidar_trace))
    }

    /// AO, diffuse GI and reflections of the main view with their denoisers (specular and
    /// diffuse in one task).
    fn schedule_gi_and_reflections(&mut self, main: &Inputs, shining: Vec<LightInfo>) -> HostResult<()> {
        let (wk, rays, reach, sky) = (&self.work, self.settings.rays_per_pixel, self.reach, self.scene.sky);
        let c = &mut self.container;
        let mut common = main.common;
        common.half_resolution_mode =
            if self.settings.checkerboard { HalfResolutionMode::Checkerboard } else { HalfResolutionMode::Off };
        common.random_numbers = self.settings.random_numbers;
        let ao = TraceAmbientOcclusionTask {
            common,
            output: wk.ao_noisy.input(GENERAL),
            ray_length: self.scene.ao_ray_length,
            rays_per_pixel: rays,
            ..Default::default()
        };
        schedule(c, "AO", |c| c.schedule_ambient_occlusion(&ao))?;
        // A moving object changes the occlusion noticeably within half the AO rays' length.
        let mut denoising = main.denoising;
        denoising.settings.moving_object_reach = 0.5 * self.scene.ao_ray_length;
        let ao_denoise = DenoiseDiffuseOcclusionTask {
            context: self.denoisers.ao,
            common: denoising,
            input: wk.ao_noisy.input(GENERAL),
            output: wk.ao.input(GENERAL),
        };
        schedule(c, "denoise AO", |c| c.schedule_denoise_diffuse_occlusion(&ao_denoise))?;
        let diffuse = TraceDiffuseTask {
            common,
            output: wk.diffuse_noisy.input(GENERAL),
            rays_per_pixel: rays,
            ray_length: reach,
            miss_radiance: sky,
            ..Default::default()
        };
        schedule(c, "diffuse GI", |c| c.schedule_diffuse(&diffuse))?;
        let specular = TraceSpecularTask {
            common,
            output: wk.specular_noisy.input(GENERAL),
            rays_per_pixel: rays,
            ray_length: reach,
            miss_radiance: sky,
            // One sample of a glossy lobe that finds the sun-lit wall can be 50x its
            // neighbours; the denoiser spreads such a spike into a blotch.
            firefly_clamp: 8.0,
            // The mirror shows the column's shadow edges as sharp as the lights make them.
            hit_lighting: if self.settings.hit_lighting {
                HitLighting { lights: shining, ..Default::default() }
            } else {
                HitLighting::default()
            },
            ..Default::default()
        };
        schedule(c, "reflections", |c| c.schedule_specular(&specular))?;
        let mut denoising = main.denoising;
        denoising.settings.fresh_history_taps = self.settings.fresh_history_taps;
        let denoise = DenoiseSpecularAndDiffuseTask {
            context: self.denoisers.radiance,
            common: denoising,
            input_specular: wk.specular_noisy.input(GENERAL),
            input_diffuse: wk.diffuse_noisy.input(GENERAL),
            output_specular: wk.specular.input(GENERAL),
            output_diffuse: wk.diffuse.input(GENERAL),
        };
        schedule(c, "denoise reflections + GI", |c| c.schedule_denoise_specular_and_diffuse(&denoise))
    }

    /// The SDK debug visualisations asked for, each into its own image (made the first time).
    fn schedule_debug_views(&mut self, main: &Inputs, debug: &[DebugOutput]) -> HostResult<()> {
        let (w, h) = (self.settings.width, self.settings.height);
        for &mode in debug {
            let output = match self.work.debug.entry(mode) {
                std::collections::hash_map::Entry::Occupied(e) => e.get().input(GENERAL),
                std::collections::hash_map::Entry::Vacant(e) => e.insert(work_image(self.host, w, h)?).input(GENERAL),
            };
            let task = TraceAmbientOcclusionTask {
                common: TraceCommon { debug_output: mode, ..main.common },
                output,
                ..Default::default()
            };
            schedule(&mut self.container, "debug views", |c| c.schedule_ambient_occlusion(&task))?;
        }
        Ok(())
    }
}
