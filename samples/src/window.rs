//! The sample in a window (winit + a Vulkan swapchain): the renderer's view of the chosen mode
//! is blitted to the swapchain image in the frame's own command buffer; the frame waits on the
//! image's acquire semaphore and signals the one `vkQueuePresentKHR` waits on. The SDK sees
//! none of this: its work is recorded into the same command buffer as ever.
use crate::modes::{self, Mode};
use crate::renderer::{Renderer, Settings, Stats};
use crate::scene::SampleScene;
use ash::vk;
use glam::Vec3;
use hybrid_rt_host::scene::Camera;
use hybrid_rt_host::{Host, HostResult, WORK_STAGES};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use std::path::PathBuf;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, ModifiersState, PhysicalKey};
use winit::window::{Window, WindowId};

fn vkerr(what: &'static str) -> impl Fn(vk::Result) -> String {
    move |e| format!("{what}: {e:?}")
}

struct Swapchain {
    loader: ash::khr::swapchain::Device,
    swapchain: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    extent: vk::Extent2D,
    /// Signalled by the frame, waited on by present: one per swapchain image.
    rendered: Vec<vk::Semaphore>,
}

impl Swapchain {
    fn new(
        host: &Host,
        surface: &ash::khr::surface::Instance,
        sk: vk::SurfaceKHR,
        size: (u32, u32),
        old: vk::SwapchainKHR,
    ) -> HostResult<Swapchain> {
        let pd = host.physical_device;
        // SAFETY: valid surface and device; the swapchain is destroyed in `destroy`.
        unsafe {
            let caps = surface.get_physical_device_surface_capabilities(pd, sk).map_err(vkerr("surface capabilities"))?;
            let formats = surface.get_physical_device_surface_formats(pd, sk).map_err(vkerr("surface formats"))?;
            // The display image is already sRGB-encoded: a UNORM swapchain takes it as is.
            let format = formats
                .iter()
                .find(|f| f.format == vk::Format::B8G8R8A8_UNORM || f.format == vk::Format::R8G8B8A8_UNORM)
                .or(formats.first())
                .copied()
                .ok_or("the surface has no formats")?;
            let extent = if caps.current_extent.width != u32::MAX {
                caps.current_extent
            } else {
                vk::Extent2D {
                    width: size.0.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                    height: size.1.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
                }
            };
            let count = if caps.max_image_count == 0 {
                caps.min_image_count + 1
            } else {
                (caps.min_image_count + 1).min(caps.max_image_count)
            };
            let info = vk::SwapchainCreateInfoKHR::default()
                .surface(sk)
                .min_image_count(count)
                .image_format(format.format)
                .image_color_space(format.color_space)
                .image_extent(extent)
                .image_array_layers(1)
                .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
                .pre_transform(caps.current_transform)
                .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
                .present_mode(vk::PresentModeKHR::FIFO)
                .clipped(true)
                .old_swapchain(old);
            let loader = ash::khr::swapchain::Device::new(&host.instance, &host.device);
            let swapchain = loader.create_swapchain(&info, None).map_err(vkerr("swapchain"))?;
            let images = loader.get_swapchain_images(swapchain).map_err(vkerr("swapchain images"))?;
            let rendered = images
                .iter()
                .map(|_| host.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None).map_err(vkerr("semaphore")))
                .collect::<HostResult<Vec<_>>>()?;
            Ok(Swapchain { loader, swapchain, images, extent, rendered })
        }
    }

    fn destroy(self, host: &Host) {
        // SAFETY: the device is idle (callers wait first).
        unsafe {
            for s in self.rendered {
                host.device.destroy_semaphore(s, None);
            }
            self.loader.destroy_swapchain(self.swapchain, None);
        }
    }
}

/// A free-flying camera: position, yaw and pitch.
struct FlyCamera {
    eye: Vec3,
    yaw: f32,
    pitch: f32,
    fov: f32,
    speed: f32,
}

impl FlyCamera {
    fn from(c: &Camera, speed: f32) -> FlyCamera {
        let d = (c.target - c.eye).normalize();
        FlyCamera { eye: c.eye, yaw: d.z.atan2(d.x), pitch: d.y.asin(), fov: c.fov_y_radians, speed }
    }

    fn forward(&self) -> Vec3 {
        Vec3::new(self.yaw.cos() * self.pitch.cos(), self.pitch.sin(), self.yaw.sin() * self.pitch.cos())
    }

    fn camera(&self) -> Camera {
        Camera { fov_y_radians: self.fov, ..Camera::look_at(self.eye, self.eye + self.forward()) }
    }

    fn key(&mut self, key: KeyCode, dt: f32) {
        let (f, r) = (self.forward(), self.forward().cross(Vec3::Y).normalize());
        let step = self.speed * dt;
        match key {
            KeyCode::KeyW => self.eye += f * step,
            KeyCode::KeyS => self.eye -= f * step,
            KeyCode::KeyD => self.eye += r * step,
            KeyCode::KeyA => self.eye -= r * step,
            KeyCode::KeyE => self.eye += Vec3::Y * step,
            KeyCode::KeyQ => self.eye -= Vec3::Y * step,
            KeyCode::ArrowLeft => self.yaw -= 1.5 * dt,
            KeyCode::ArrowRight => self.yaw += 1.5 * dt,
            KeyCode::ArrowUp => self.pitch = (self.pitch + 1.5 * dt).min(1.5),
            KeyCode::ArrowDown => self.pitch = (self.pitch - 1.5 * dt).max(-1.5),
            _ => {}
        }
    }
}

struct App<'h> {
    host: &'h Host,
    window: &'h Window,
    renderer: Renderer<'h>,
    surface: &'h ash::khr::surface::Instance,
    surface_khr: vk::SurfaceKHR,
    swapchain: Option<Swapchain>,
    acquired: Vec<vk::Semaphore>,
    mode: usize,
    camera: FlyCamera,
    modifiers: ModifiersState,
    paused: bool,
    time: f32,
    last: Instant,
    title_at: Instant,
    frame_limit: Option<u64>,
    presented: u64,
    out: PathBuf,
    error: Option<String>,
}

impl App<'_> {
    fn frame(&mut self) -> HostResult<()> {
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f32().min(0.1);
        self.last = now;
        if !self.paused {
            self.time += dt;
        }
        let host = self.host;
        if self.swapchain.is_none() {
            return Ok(());
        }
        let slot = self.renderer.begin_frame()?;
        let Some(sc) = &self.swapchain else { unreachable!("checked above") };
        // SAFETY: the acquire semaphore of this slot is unsignalled: its last frame finished.
        let acquired = unsafe { sc.loader.acquire_next_image(sc.swapchain, u64::MAX, self.acquired[slot], vk::Fence::null()) };
        let index = match acquired {
            Ok((i, _)) => i,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                // Leave the slot's command buffer empty but submitted, so its fence signals.
                self.renderer.submit_frame(slot, &[], &[])?;
                return self.recreate();
            }
            Err(e) => return Err(vkerr("acquire")(e)),
        };
        let mode = modes::ALL[self.mode];
        let debug: Vec<_> = if let Mode::Debug(d) = mode { vec![d] } else { vec![] };
        self.renderer.many_lights_debug = mode == Mode::ManyLightsDebug;
        self.renderer.record_frame(slot, self.camera.camera(), self.time, &debug, Some(mode))?;
        let cmd = self.renderer.command_buffer(slot);
        let image = sc.images[index as usize];
        let display = self.renderer.display_image();
        let range = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let barrier_of = |image, from, to, src: vk::AccessFlags2, dst: vk::AccessFlags2| {
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(WORK_STAGES)
                .src_access_mask(src)
                .dst_stage_mask(WORK_STAGES)
                .dst_access_mask(dst)
                .old_layout(from)
                .new_layout(to)
                .image(image)
                .subresource_range(range)
        };
        let barrier = |from, to, src, dst| barrier_of(image, from, to, src, dst);
        let blit = vk::ImageBlit {
            src_subresource: layers,
            src_offsets: [vk::Offset3D::default(), vk::Offset3D { x: display.width as i32, y: display.height as i32, z: 1 }],
            dst_subresource: layers,
            dst_offsets: [vk::Offset3D::default(), vk::Offset3D { x: sc.extent.width as i32, y: sc.extent.height as i32, z: 1 }],
        };
        // SAFETY: cmd is recording; the swapchain image was acquired for this frame.
        unsafe {
            host.full_barrier(cmd);
            // The view image lives in GENERAL (a storage image); blits read best from
            // TRANSFER_SRC_OPTIMAL, and it goes back to GENERAL for the next frame's view pass.
            let to_dst = [
                barrier(
                    vk::ImageLayout::UNDEFINED,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::AccessFlags2::NONE,
                    vk::AccessFlags2::TRANSFER_WRITE,
                ),
                barrier_of(
                    display.image,
                    vk::ImageLayout::GENERAL,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    vk::AccessFlags2::SHADER_STORAGE_WRITE,
                    vk::AccessFlags2::TRANSFER_READ,
                ),
            ];
            host.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&to_dst));
            host.device.cmd_blit_image(
                cmd,
                display.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[blit],
                vk::Filter::LINEAR,
            );
            let to_present = [
                barrier(
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::ImageLayout::PRESENT_SRC_KHR,
                    vk::AccessFlags2::TRANSFER_WRITE,
                    vk::AccessFlags2::NONE,
                ),
                barrier_of(
                    display.image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    vk::ImageLayout::GENERAL,
                    vk::AccessFlags2::NONE,
                    vk::AccessFlags2::SHADER_STORAGE_WRITE,
                ),
            ];
            host.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&to_present));
        }
        let rendered = sc.rendered[index as usize];
        // The acquired image is first touched by the blit (transfer stage).
        self.renderer.submit_frame(slot, &[(self.acquired[slot], vk::PipelineStageFlags::TRANSFER)], &[rendered])?;
        let (swapchains, indices, waits) = ([sc.swapchain], [index], [rendered]);
        let present = vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        // SAFETY: the image was acquired and the submit signals `rendered`.
        match unsafe { sc.loader.queue_present(host.queue, &present) } {
            Ok(false) => {}
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.recreate()?,
            Err(e) => return Err(vkerr("present")(e)),
        }
        self.presented += 1;
        if (now - self.title_at).as_secs_f32() > 0.5 && self.renderer.stats.frames > 0 {
            self.title_at = now;
            let report = crate::report::Report::new(&self.renderer);
            self.window.set_title(&format!("hybrid-rt: {} (Tab: next mode) | {}", mode.name(), report.title()));
            // Rolling means: start over after each title update.
            let first = self.renderer.stats.first_frame_bvh_ms;
            self.renderer.stats = Stats { first_frame_bvh_ms: first, ..Default::default() };
        }
        Ok(())
    }

    fn recreate(&mut self) -> HostResult<()> {
        self.renderer.finish()?;
        // SAFETY: idle device: no frame uses the old swapchain.
        unsafe { self.host.device.device_wait_idle() }.map_err(vkerr("wait idle"))?;
        let size = self.window.inner_size();
        let old = self.swapchain.take();
        let fresh = Swapchain::new(
            self.host,
            self.surface,
            self.surface_khr,
            (size.width, size.height),
            old.as_ref().map_or(vk::SwapchainKHR::null(), |s| s.swapchain),
        )?;
        if let Some(o) = old {
            o.destroy(self.host);
        }
        self.swapchain = Some(fresh);
        Ok(())
    }

    fn capture(&mut self) -> HostResult<()> {
        self.renderer.finish()?;
        let mode = modes::ALL[self.mode];
        let (w, h) = (self.renderer.settings.width, self.renderer.settings.height);
        let (linear, display) = self.renderer.capture(mode)?;
        let base = crate::images::write_capture(&self.out, mode.name(), w, h, &linear, &display)?;
        println!("wrote {}.exr and .png", base.display());
        Ok(())
    }

    fn key(&mut self, event_loop: &ActiveEventLoop, key: KeyCode) -> HostResult<()> {
        let n = modes::ALL.len();
        match key {
            KeyCode::Escape => event_loop.exit(),
            KeyCode::Tab if self.modifiers.shift_key() => self.mode = (self.mode + n - 1) % n,
            KeyCode::Tab => self.mode = (self.mode + 1) % n,
            KeyCode::Space => self.paused = !self.paused,
            KeyCode::KeyP => self.capture()?,
            k => {
                let digits = [
                    KeyCode::Digit1,
                    KeyCode::Digit2,
                    KeyCode::Digit3,
                    KeyCode::Digit4,
                    KeyCode::Digit5,
                    KeyCode::Digit6,
                    KeyCode::Digit7,
                    KeyCode::Digit8,
                    KeyCode::Digit9,
                ];
                match digits.iter().position(|d| *d == k) {
                    Some(i) => self.mode = i,
                    None => self.camera.key(k, 1.0 / 30.0),
                }
            }
        }
        // Show the new mode in the title at the next frame.
        self.title_at = Instant::now().checked_sub(std::time::Duration::from_secs(1)).unwrap_or(self.title_at);
        Ok(())
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, _: &ActiveEventLoop) {}

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::ModifiersChanged(m) => {
                self.modifiers = m.state();
                Ok(())
            }
            WindowEvent::KeyboardInput {
                event: KeyEvent { physical_key: PhysicalKey::Code(k), state: ElementState::Pressed, .. },
                ..
            } => self.key(event_loop, k),
            WindowEvent::Resized(_) => self.recreate(),
            WindowEvent::RedrawRequested => self.frame(),
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.error = Some(e);
            event_loop.exit();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.frame_limit.is_some_and(|n| self.presented >= n) {
            event_loop.exit();
        } else {
            self.window.request_redraw();
        }
    }
}

/// Opens a window on `scene` and renders until it closes (or `frame_limit` frames).
pub fn run(scene: SampleScene, settings: Settings, frame_limit: Option<u64>, out: PathBuf) -> HostResult<()> {
    let event_loop = EventLoop::new().map_err(|e| format!("no display: {e} (run with --headless)"))?;
    let attributes = Window::default_attributes()
        .with_title("hybrid-rt")
        .with_inner_size(winit::dpi::PhysicalSize::new(settings.width, settings.height));
    // winit 0.30 wants windows made inside the loop; making it first keeps the Vulkan objects
    // plain locals the app borrows (the renderer borrows the device).
    #[allow(deprecated)]
    let window = event_loop.create_window(attributes).map_err(|e| format!("window: {e}"))?;
    let display_handle = window.display_handle().map_err(|e| e.to_string())?.as_raw();
    let window_handle = window.window_handle().map_err(|e| e.to_string())?.as_raw();
    let surface_exts = ash_window::enumerate_required_extensions(display_handle).map_err(vkerr("surface extensions"))?;
    // SAFETY: the names are static strings of ash-window.
    let surface_exts: Vec<&std::ffi::CStr> = surface_exts.iter().map(|p| unsafe { std::ffi::CStr::from_ptr(*p) }).collect();
    let host = Host::with_extensions(&surface_exts, &[ash::khr::swapchain::NAME])?;
    println!("device: {}{}", host.device_name, if host.validation_enabled { " (validation on)" } else { "" });
    let surface = ash::khr::surface::Instance::new(&host.entry, &host.instance);
    // SAFETY: the handles come from a live window; the surface is destroyed before the host.
    let surface_khr = unsafe { ash_window::create_surface(&host.entry, &host.instance, display_handle, window_handle, None) }
        .map_err(vkerr("surface"))?;
    let result = (|| {
        // SAFETY: valid physical device, queue family and surface.
        let presents =
            unsafe { surface.get_physical_device_surface_support(host.physical_device, host.queue_family, surface_khr) }
                .unwrap_or(false);
        if !presents {
            return Err("the device's queue cannot present to this window".to_string());
        }
        let speed = (scene.camera_path.from - scene.camera_path.target).length() * 0.5;
        let camera = FlyCamera::from(&scene.camera_path.at(0.5), speed);
        let renderer = Renderer::new(&host, scene, settings)?;
        let size = window.inner_size();
        let swapchain = Swapchain::new(&host, &surface, surface_khr, (size.width, size.height), vk::SwapchainKHR::null())?;
        let acquired = (0..2)
            // SAFETY: plain object creation; destroyed below.
            .map(|_| {
                unsafe { host.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.map_err(vkerr("semaphore"))
            })
            .collect::<HostResult<Vec<_>>>()?;
        let mut app = App {
            host: &host,
            window: &window,
            renderer,
            surface: &surface,
            surface_khr,
            swapchain: Some(swapchain),
            acquired,
            mode: 0,
            camera,
            modifiers: ModifiersState::empty(),
            paused: false,
            time: 0.0,
            last: Instant::now(),
            title_at: Instant::now(),
            frame_limit,
            presented: 0,
            out,
            error: None,
        };
        let run = event_loop.run_app(&mut app).map_err(|e| format!("event loop: {e}"));
        app.renderer.finish()?;
        // SAFETY: idle device before destroying what frames used.
        unsafe { host.device.device_wait_idle() }.map_err(vkerr("wait idle"))?;
        println!("presented {} frames", app.presented);
        if app.renderer.stats.frames > 0 {
            print!("{}", crate::report::Report::new(&app.renderer).text());
        }
        for s in app.acquired {
            // SAFETY: idle device.
            unsafe { host.device.destroy_semaphore(s, None) };
        }
        if let Some(s) = app.swapchain.take() {
            s.destroy(&host);
        }
        app.renderer.destroy()?;
        run?;
        app.error.map_or(Ok(()), Err)
    })();
    // SAFETY: nothing uses the surface any more.
    unsafe { surface.destroy_surface(surface_khr, None) };
    result?;
    let errors = Host::validation_errors();
    if errors > 0 {
        return Err(format!(
            "{errors} Vulkan validation errors, the first: {:#?}",
            Host::validation_messages().iter().take(3).collect::<Vec<_>>()
        ));
    }
    Ok(())
}
