//! What each frame in flight owns (its views: G-buffer and lit image) and what the frames
//! share (the images written and read inside one frame, the denoising contexts), and which
//! image each display mode shows.
use super::many_lights::ManyLights;
use super::GENERAL;
use crate::gpu::GpuTimer;
use crate::lighting::LightingPass;
use crate::modes::Mode;
use crate::raster::{self, MeshBuffers, Targets};
use ash::vk;
use hybrid_rt::{DebugOutput, DenoisingContextHandle, GpuTicket};
use hybrid_rt_host::scene::Camera;
use hybrid_rt_host::{Host, HostBuffer, HostImage, HostResult};
use std::collections::HashMap;

const WORK_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// A G-buffer and the lit image made from it.
pub(super) struct View {
    pub(super) targets: Targets,
    pub(super) lit: HostImage,
}

impl View {
    pub(super) fn new(host: &Host, width: u32, height: u32) -> HostResult<View> {
        let targets = Targets::new(host, width, height)?;
        let lit = LightingPass::lit_image(host, &targets)?;
        Ok(View { targets, lit })
    }

    pub(super) fn destroy(self, host: &Host) {
        self.targets.destroy(host);
        host.destroy_image(self.lit);
    }
}

/// One frame in flight.
pub(super) struct Slot {
    pub(super) cmd: vk::CommandBuffer,
    pub(super) fence: vk::Fence,
    pub(super) ticket: Option<GpuTicket>,
    pub(super) timer: GpuTimer,
    pub(super) main: View,
    pub(super) lidar: View,
    /// The flag's vertices of this slot's frame (host-visible: the CPU writes them).
    pub(super) deformed: Option<HostBuffer>,
    /// The skinned meshes' vertices of this slot's frame (device-local: the skinning pass
    /// writes them), in `SkinningPass`'s order.
    pub(super) posed: Vec<HostBuffer>,
    pub(super) camera: Camera,
    pub(super) lidar_camera: Camera,
    pub(super) frame: u64,
    pub(super) recorded: bool,
}

/// Images written and read inside a frame.
pub(super) struct Work {
    pub(super) sun_noisy: HostImage,
    pub(super) sun: HostImage,
    pub(super) point_noisy: HostImage,
    pub(super) point: HostImage,
    pub(super) ao_noisy: HostImage,
    pub(super) ao: HostImage,
    pub(super) diffuse_noisy: HostImage,
    pub(super) diffuse: HostImage,
    pub(super) specular_noisy: HostImage,
    pub(super) specular: HostImage,
    pub(super) composite: HostImage,
    pub(super) lidar_sun: HostImage,
    pub(super) lidar_point: HostImage,
    /// The file's lights' shadows (a scene with `file_lights` only).
    pub(super) lights: Option<FileLightImages>,
    pub(super) debug: HashMap<DebugOutput, HostImage>,
    /// The view pass's outputs: linear RGBA32F and tone-mapped sRGB RGBA8.
    pub(super) linear: HostImage,
    pub(super) display: HostImage,
}

impl Slot {
    pub(super) fn new(
        host: &Host,
        width: u32,
        height: u32,
        lidar_size: u32,
        deformer_rest: Option<&[crate::mesh_buffers::Vertex]>,
        posed: Vec<HostBuffer>,
        camera: Camera,
    ) -> HostResult<Slot> {
        let deformed = match deformer_rest {
            Some(rest) => Some(host.buffer_with_data(bytemuck::cast_slice(rest), MeshBuffers::VERTEX_USAGE)?),
            None => None,
        };
        // SAFETY: plain object creation; destroyed in `destroy`. Signalled: a fresh slot has
        // no frame to wait for.
        let fence =
            unsafe { host.device.create_fence(&vk::FenceCreateInfo::default().flags(vk::FenceCreateFlags::SIGNALED), None) }
                .map_err(|e| format!("fence: {e:?}"))?;
        Ok(Slot {
            cmd: host.allocate_command_buffer()?,
            fence,
            ticket: None,
            timer: GpuTimer::new(host)?,
            main: View::new(host, width, height)?,
            lidar: View::new(host, lidar_size, lidar_size)?,
            deformed,
            posed,
            camera,
            lidar_camera: camera,
            frame: 0,
            recorded: false,
        })
    }

    /// After its frame finished.
    pub(super) fn destroy(self, host: &Host) {
        // SAFETY: the caller waited for the slot's frame.
        unsafe { host.device.destroy_fence(self.fence, None) };
        self.timer.destroy(host);
        self.main.destroy(host);
        self.lidar.destroy(host);
        if let Some(b) = self.deformed {
            host.destroy_buffer(b);
        }
        for b in self.posed {
            host.destroy_buffer(b);
        }
    }
}

/// One view's multi-light shadow trace: per-light visibility (lights 0..16 and 16..32) and the
/// weighted mean the denoiser takes (`TraceMultiShadowTask`).
pub(super) struct MultiShadowImages {
    pub(super) visibility: HostImage,
    pub(super) visibility_high: Option<HostImage>,
    pub(super) packed: HostImage,
}

impl MultiShadowImages {
    /// For `lights` lights (1..=32) at `w` x `h`.
    fn new(host: &Host, w: u32, h: u32, lights: usize) -> HostResult<MultiShadowImages> {
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        // Four lights fit one 32-bit texel, 16 four.
        let format = |n: usize| if n <= 4 { vk::Format::R32_UINT } else { vk::Format::R32G32B32A32_UINT };
        let high = lights.saturating_sub(16);
        Ok(MultiShadowImages {
            visibility: host.image_cleared(format(lights.min(16)), w, h, usage, GENERAL)?,
            visibility_high: if high > 0 { Some(host.image_cleared(format(high), w, h, usage, GENERAL)?) } else { None },
            packed: work_image(host, w, h)?,
        })
    }

    fn destroy(self, host: &Host) {
        for i in [Some(self.visibility), self.visibility_high, Some(self.packed)].into_iter().flatten() {
            host.destroy_image(i);
        }
    }
}

/// The file's lights' shadows: the main view's trace and its denoised mean visibility, the
/// lidar view's trace (raw, as its other shadows).
pub(super) struct FileLightImages {
    pub(super) main: MultiShadowImages,
    pub(super) denoised: HostImage,
    pub(super) lidar: MultiShadowImages,
}

impl Work {
    /// `file_lights`: how many lights the scene's file brings (0: none).
    pub(super) fn new(host: &Host, w: u32, h: u32, lidar_size: u32, file_lights: usize) -> HostResult<Work> {
        let ls = lidar_size;
        let out = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        Ok(Work {
            sun_noisy: work_image(host, w, h)?,
            sun: work_image(host, w, h)?,
            point_noisy: work_image(host, w, h)?,
            point: work_image(host, w, h)?,
            ao_noisy: work_image(host, w, h)?,
            ao: work_image(host, w, h)?,
            diffuse_noisy: work_image(host, w, h)?,
            diffuse: work_image(host, w, h)?,
            specular_noisy: work_image(host, w, h)?,
            specular: work_image(host, w, h)?,
            composite: work_image(host, w, h)?,
            lidar_sun: work_image(host, ls, ls)?,
            lidar_point: work_image(host, ls, ls)?,
            lights: match file_lights {
                0 => None,
                n => Some(FileLightImages {
                    main: MultiShadowImages::new(host, w, h, n)?,
                    denoised: work_image(host, w, h)?,
                    lidar: MultiShadowImages::new(host, ls, ls, n)?,
                }),
            },
            debug: HashMap::new(),
            linear: host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, w, h, out, GENERAL)?,
            display: host.image_cleared(vk::Format::R8G8B8A8_UNORM, w, h, out, GENERAL)?,
        })
    }

    /// After every frame that used them finished.
    pub(super) fn destroy(self, host: &Host) {
        let fixed = [
            self.sun_noisy,
            self.sun,
            self.point_noisy,
            self.point,
            self.ao_noisy,
            self.ao,
            self.diffuse_noisy,
            self.diffuse,
            self.specular_noisy,
            self.specular,
            self.composite,
            self.lidar_sun,
            self.lidar_point,
            self.linear,
            self.display,
        ];
        for i in fixed.into_iter().chain(self.debug.into_values()) {
            host.destroy_image(i);
        }
        if let Some(l) = self.lights {
            l.main.destroy(host);
            l.lidar.destroy(host);
            host.destroy_image(l.denoised);
        }
    }
}

pub(super) struct Denoisers {
    pub(super) sun: DenoisingContextHandle,
    pub(super) point: DenoisingContextHandle,
    pub(super) ao: DenoisingContextHandle,
    pub(super) radiance: DenoisingContextHandle,
    /// The file's lights' shadows (a scene with `file_lights` only).
    pub(super) lights: Option<DenoisingContextHandle>,
}

/// An RGBA16F image the SDK writes (STORAGE) and the sample's passes read (SAMPLED), in GENERAL.
pub(super) fn work_image(host: &Host, width: u32, height: u32) -> HostResult<HostImage> {
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
    host.image_cleared(WORK_FORMAT, width, height, usage, GENERAL)
}

/// The image behind `mode` and the layout it is in (from the last recorded frame); `many`:
/// the many-lights images, when the sample shades them.
pub(super) fn source<'a>(
    wk: &'a Work,
    s: &'a Slot,
    many: Option<&'a ManyLights>,
    mode: Mode,
) -> (&'a HostImage, vk::ImageLayout) {
    let read = raster::READ;
    match mode {
        Mode::Composite => (&wk.composite, GENERAL),
        Mode::Direct => (&s.main.lit, GENERAL),
        Mode::Albedo | Mode::Metalness => (&s.main.targets.albedo_metalness, read),
        Mode::Normals | Mode::Roughness => (&s.main.targets.normal_roughness, read),
        Mode::Motion => (&s.main.targets.motion, read),
        Mode::Emissive => (&s.main.targets.emissive, read),
        Mode::SunShadowNoisy => (&wk.sun_noisy, GENERAL),
        Mode::SunShadow => (&wk.sun, GENERAL),
        Mode::PointShadowNoisy => (&wk.point_noisy, GENERAL),
        Mode::PointShadow => (&wk.point, GENERAL),
        // A scene without lights of its own shows the sun's (denoised: the visibility in R).
        Mode::LightsShadowNoisy => (wk.lights.as_ref().map_or(&wk.sun, |l| &l.main.packed), GENERAL),
        Mode::LightsShadow => (wk.lights.as_ref().map_or(&wk.sun, |l| &l.denoised), GENERAL),
        Mode::AoNoisy => (&wk.ao_noisy, GENERAL),
        Mode::Ao => (&wk.ao, GENERAL),
        Mode::DiffuseNoisy => (&wk.diffuse_noisy, GENERAL),
        Mode::Diffuse => (&wk.diffuse, GENERAL),
        Mode::SpecularNoisy => (&wk.specular_noisy, GENERAL),
        Mode::Specular => (&wk.specular, GENERAL),
        Mode::Lidar => (&s.lidar.lit, GENERAL),
        Mode::ManyLightsNoisy | Mode::ManyLights | Mode::ManyLightsDebug => {
            (many.map_or(&wk.composite, |m| m.image(mode)), GENERAL)
        }
        Mode::Debug(d) => (wk.debug.get(&d).unwrap_or(&wk.composite), GENERAL),
    }
}
