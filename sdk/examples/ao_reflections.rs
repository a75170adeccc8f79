//! hybrid-rt from Rust: the whole integration in one file.
//!
//! The "engine" here is this program. It creates its own Vulkan instance and device with the
//! SDK's helpers (`query_device_support`, `REQUIRED_DEVICE_EXTENSIONS`, `DeviceFeatures`),
//! registers three meshes (a floor and two boxes) with the SDK, fills a G-buffer and a lit
//! image — on the CPU, by casting one ray per pixel, where a real engine would rasterize —
//! and, in one command buffer it owns: builds the BVH, injects the lit image into the
//! direct-lighting cache, traces ambient occlusion and glossy reflections (whose hits are
//! shaded from that cache). It submits, waits on its own fence, hands the ticket back, checks
//! the images make sense (contact shadows under the boxes, the red box seen in the floor, sky
//! where nothing is) and writes `lit | AO | reflections | composite` as a PNG.
//!
//! ```sh
//! cargo run -p hybrid-rt --example ao_reflections -- out.png
//! ```
//!
//! Exit code 0 = every check passed. With the Khronos validation layer installed (unless
//! HRT_VALIDATION=0), any validation error or warning fails the run.
//! docs/integration.md walks through the same steps.
// The engine side of this example is plain ash set-up (instance, device, images, submits),
// each call's contract met by construction in the lines around it; the SDK's own code documents
// every unsafe block.
#![allow(clippy::undocumented_unsafe_blocks)]
use hybrid_rt::ash::{self, vk};
use hybrid_rt::glam::{self, Affine3A, Vec3, Vec4};
use hybrid_rt::*;
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicU32, Ordering};

const W: u32 = 320;
const H: u32 = 240;
/// Radiance reflected rays that leave the scene return (a pale blue sky).
const SKY: [f32; 3] = [0.35, 0.55, 0.9];

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "ao_reflections.png".to_string());
    if let Err(e) = run(&out) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

type Failure = Box<dyn std::error::Error>;

// ---------------------------------------------------------------------------------------
// The scene, as the engine knows it: meshes with a colour, placed by a transform.

struct Mesh {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    transform: Affine3A,
    albedo: [f32; 3],
}

/// A unit cube centred on the origin (24 vertices: flat faces, 12 outward-facing triangles).
fn cube() -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut p = Vec::new();
    let mut i = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|k| if k == axis { sign } else { 0.0 }));
            let u = Vec3::from_array(std::array::from_fn(|k| if k == (axis + 1) % 3 { 1.0 } else { 0.0 }));
            let v = n.cross(u);
            let base = p.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                p.push((0.5 * (n + a * u + b * v)).to_array());
            }
            i.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    (p, i)
}

fn scene() -> Vec<Mesh> {
    let (cube_p, cube_i) = cube();
    vec![
        Mesh {
            positions: vec![[-6.0, 0.0, -6.0], [6.0, 0.0, -6.0], [6.0, 0.0, 6.0], [-6.0, 0.0, 6.0]],
            indices: vec![0, 2, 1, 0, 3, 2],
            transform: Affine3A::IDENTITY,
            albedo: [0.6, 0.6, 0.6],
        },
        Mesh {
            positions: cube_p.clone(),
            indices: cube_i.clone(),
            transform: Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)),
            albedo: [0.85, 0.1, 0.08],
        },
        Mesh {
            positions: cube_p,
            indices: cube_i,
            transform: Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.7),
                glam::Quat::from_rotation_y(0.6),
                Vec3::new(1.6, 0.35, -1.2),
            ),
            albedo: [0.1, 0.3, 0.85],
        },
    ]
}

/// The G-buffer and lit image a rasterizer would produce (here: one CPU ray per pixel).
struct Frame {
    /// Hardware depth (clip z / w; 1 = far plane = background).
    depth: Vec<f32>,
    /// World-space normals (xyz, w unused).
    normals: Vec<[f32; 4]>,
    /// The direct lighting: albedo x (sun N.L + a little ambient).
    lit: Vec<[f32; 4]>,
    /// Which mesh each pixel shows (engine-side knowledge, for the composite).
    mesh: Vec<Option<usize>>,
}

fn camera() -> Camera {
    let world_to_view = glam::camera::rh::view::look_at_mat4(Vec3::new(-0.4, 1.5, 3.3), Vec3::new(0.4, 0.35, 0.0), Vec3::Y);
    // Vulkan clip space: y points down the image, depth 0..1.
    let view_to_clip = glam::camera::rh::proj::vulkan::perspective(50f32.to_radians(), W as f32 / H as f32, 0.05, 100.0);
    Camera { world_to_view, view_to_clip }
}

fn sun() -> Vec3 {
    Vec3::new(0.5, 1.0, 0.3).normalize()
}

/// Where pixel (x, y)'s centre projects to in world space at clip depth `z`.
fn unproject(camera: &Camera, x: f32, y: f32, z: f32) -> Vec3 {
    let ndc = Vec4::new((x + 0.5) / W as f32 * 2.0 - 1.0, (y + 0.5) / H as f32 * 2.0 - 1.0, z, 1.0);
    let p = (camera.view_to_clip * camera.world_to_view).inverse() * ndc;
    p.truncate() / p.w
}

/// The pixel a world point projects to, if it is in view.
fn project(camera: &Camera, p: Vec3) -> Option<(u32, u32)> {
    let c = camera.view_to_clip * camera.world_to_view * p.extend(1.0);
    let (x, y) = ((c.x / c.w + 1.0) * 0.5 * W as f32, (c.y / c.w + 1.0) * 0.5 * H as f32);
    (c.w > 0.0 && (0.0..W as f32).contains(&x) && (0.0..H as f32).contains(&y)).then_some((x as u32, y as u32))
}

/// Möller–Trumbore: the distance along `d` to the triangle, if it is hit in front.
fn hit(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let t0 = o - a;
    let u = t0.dot(p) / det;
    let q = t0.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 1e-4).then_some(t)
}

/// The engine's direct lighting: a sun (N.L) and a little ambient.
fn shade(albedo: [f32; 3], normal: Vec3) -> Vec3 {
    Vec3::from(albedo) * (normal.dot(sun()).max(0.0) * 1.3 + 0.1)
}

fn rasterize(meshes: &[Mesh], camera: &Camera) -> Frame {
    let n = (W * H) as usize;
    let mut f = Frame { depth: vec![1.0; n], normals: vec![[0.0; 4]; n], lit: vec![[0.0; 4]; n], mesh: vec![None; n] };
    let world_to_clip = camera.view_to_clip * camera.world_to_view;
    for y in 0..H {
        for x in 0..W {
            let o = unproject(camera, x as f32, y as f32, 0.0);
            let d = (unproject(camera, x as f32, y as f32, 1.0) - o).normalize();
            let mut best: Option<(f32, Vec3, usize)> = None;
            for (m, mesh) in meshes.iter().enumerate() {
                for t in mesh.indices.chunks(3) {
                    let [a, b, c] =
                        [t[0], t[1], t[2]].map(|i| mesh.transform.transform_point3(Vec3::from(mesh.positions[i as usize])));
                    if let Some(dist) = hit(o, d, a, b, c) {
                        if best.is_none_or(|(bd, _, _)| dist < bd) {
                            best = Some((dist, (b - a).cross(c - a).normalize(), m));
                        }
                    }
                }
            }
            let i = (y * W + x) as usize;
            if let Some((dist, normal, m)) = best {
                let p = world_to_clip * (o + d * dist).extend(1.0);
                f.depth[i] = p.z / p.w;
                f.normals[i] = normal.extend(0.0).to_array();
                f.lit[i] = shade(meshes[m].albedo, normal).extend(1.0).to_array();
                f.mesh[i] = Some(m);
            }
        }
    }
    f
}

// ---------------------------------------------------------------------------------------
// The engine's Vulkan objects.

static VALIDATION_MESSAGES: AtomicU32 = AtomicU32::new(0);

unsafe extern "system" fn on_validation(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    if severity.intersects(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        VALIDATION_MESSAGES.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the layer passes a valid callback-data struct (or null, checked) whose
        // message is null (checked) or NUL-terminated, alive for the call.
        let message = unsafe {
            if data.is_null() || (*data).p_message.is_null() {
                "?".into()
            } else {
                CStr::from_ptr((*data).p_message).to_string_lossy()
            }
        };
        eprintln!("[validation {severity:?}] {message}");
    }
    vk::FALSE
}

struct Gpu {
    entry: ash::Entry,
    instance: ash::Instance,
    pdev: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    pool: vk::CommandPool,
    memory: vk::PhysicalDeviceMemoryProperties,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// How the device was made, for the SDK: its extensions, whether the instance has
    /// VK_EXT_debug_utils, and the feature chain (boxed: the chain points into it).
    extensions: Vec<&'static CStr>,
    debug_utils: bool,
    features: Box<DeviceFeatures>,
}

/// An image with its memory and view, and the usage it was created with (the SDK checks it).
struct Image {
    image: vk::Image,
    view: vk::ImageView,
    memory: vk::DeviceMemory,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
}

impl Image {
    fn input(&self, layout: vk::ImageLayout) -> ImageInput {
        ImageInput { image: self.image, view: self.view, format: self.format, width: W, height: H, layout, usage: self.usage }
    }
}

struct Buffer {
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    ptr: *mut u8,
    size: u64,
}

impl Buffer {
    /// The mapped contents (host-coherent: what the GPU wrote, once its fence has signalled).
    fn bytes(&self) -> &[u8] {
        // SAFETY: `ptr` maps all `size` bytes of the buffer's memory until it is freed.
        unsafe { std::slice::from_raw_parts(self.ptr, self.size as usize) }
    }
}

impl Gpu {
    /// The engine's start-up: an instance (with validation when installed) and a device with
    /// what the SDK asks for merged into the engine's own feature chain.
    fn new() -> Result<Gpu, Failure> {
        let entry = unsafe { ash::Entry::load()? };
        let layers = unsafe { entry.enumerate_instance_layer_properties()? };
        let validation = std::env::var("HRT_VALIDATION").as_deref() != Ok("0")
            && layers.iter().any(|l| l.layer_name_as_c_str() == Ok(c"VK_LAYER_KHRONOS_validation"));
        let layer_names = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let ext_names = [ash::ext::debug_utils::NAME.as_ptr()];
        let app = vk::ApplicationInfo::default().application_name(c"hybrid-rt example").api_version(vk::API_VERSION_1_3);
        let n = if validation { 1 } else { 0 };
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layer_names[..n])
            .enabled_extension_names(&ext_names[..n]);
        let instance = unsafe { entry.create_instance(&info, None)? };
        let messenger = if validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING)
                .message_type(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL)
                .pfn_user_callback(Some(on_validation));
            let m = unsafe { loader.create_debug_utils_messenger(&info, None)? };
            Some((loader, m))
        } else {
            None
        };
        println!("validation layer: {}", if validation { "on" } else { "not installed (or HRT_VALIDATION=0)" });

        // The first physical device the SDK can run on.
        let mut chosen = None;
        for pdev in unsafe { instance.enumerate_physical_devices()? } {
            let support = query_device_support(&instance, pdev);
            if support.supported {
                chosen = Some((pdev, support.ray_query));
                break;
            }
            println!("skipping a device that lacks: {}", support.missing.join(", "));
        }
        let (pdev, ray_query) = chosen.ok_or("no Vulkan device with ray tracing (run scripts/setup.sh)")?;
        let family = unsafe { instance.get_physical_device_queue_family_properties(pdev) }
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or("no compute queue")? as u32;

        // The SDK's extensions (and ray queries where the device has them: inline tracing).
        let mut exts: Vec<&'static CStr> = REQUIRED_DEVICE_EXTENSIONS.to_vec();
        if ray_query {
            exts.extend(OPTIONAL_DEVICE_EXTENSIONS);
        }
        let ext_ptrs: Vec<_> = exts.iter().map(|e| e.as_ptr()).collect();
        // No feature chain of our own here, so the SDK's becomes the chain (`push_to`). An engine
        // with its own VkPhysicalDeviceFeatures2 calls `merge_into` instead. Boxed: the chain
        // points into it, and the context reads it at creation.
        let mut features = Box::new(DeviceFeatures::required(ray_query));
        let priority = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priority)];
        let info =
            features.push_to(vk::DeviceCreateInfo::default().queue_create_infos(&queues).enabled_extension_names(&ext_ptrs));
        let device = unsafe { instance.create_device(pdev, &info, None)? };
        let queue = unsafe { device.get_device_queue(family, 0) };
        let pool = unsafe { device.create_command_pool(&vk::CommandPoolCreateInfo::default().queue_family_index(family), None)? };
        let memory = unsafe { instance.get_physical_device_memory_properties(pdev) };
        Ok(Gpu {
            entry,
            instance,
            pdev,
            device,
            queue,
            pool,
            memory,
            messenger,
            extensions: exts,
            debug_utils: validation,
            features,
        })
    }

    fn memory_type(&self, bits: u32, flags: vk::MemoryPropertyFlags) -> Result<u32, Failure> {
        (0..self.memory.memory_type_count)
            .find(|&i| bits & (1 << i) != 0 && self.memory.memory_types[i as usize].property_flags.contains(flags))
            .ok_or_else(|| "no suitable memory type".into())
    }

    /// A host-visible buffer (vertex data for the SDK to copy from, uploads, read-backs).
    fn buffer(&self, size: u64, usage: vk::BufferUsageFlags) -> Result<Buffer, Failure> {
        unsafe {
            let buffer = self.device.create_buffer(&vk::BufferCreateInfo::default().size(size).usage(usage), None)?;
            let req = self.device.get_buffer_memory_requirements(buffer);
            let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let info = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(self.memory_type(req.memory_type_bits, host)?);
            let memory = self.device.allocate_memory(&info, None)?;
            self.device.bind_buffer_memory(buffer, memory, 0)?;
            let ptr = self.device.map_memory(memory, 0, size, vk::MemoryMapFlags::empty())? as *mut u8;
            Ok(Buffer { buffer, memory, ptr, size })
        }
    }

    fn buffer_with<T: bytemuck::Pod>(&self, data: &[T], usage: vk::BufferUsageFlags) -> Result<Buffer, Failure> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let b = self.buffer(bytes.len() as u64, usage)?;
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), b.ptr, bytes.len()) };
        Ok(b)
    }

    fn image(&self, format: vk::Format, usage: vk::ImageUsageFlags) -> Result<Image, Failure> {
        let usage = usage | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC;
        unsafe {
            let info = vk::ImageCreateInfo::default()
                .image_type(vk::ImageType::TYPE_2D)
                .format(format)
                .extent(vk::Extent3D { width: W, height: H, depth: 1 })
                .mip_levels(1)
                .array_layers(1)
                .samples(vk::SampleCountFlags::TYPE_1)
                .usage(usage);
            let image = self.device.create_image(&info, None)?;
            let req = self.device.get_image_memory_requirements(image);
            let alloc = vk::MemoryAllocateInfo::default()
                .allocation_size(req.size)
                .memory_type_index(self.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::DEVICE_LOCAL)?);
            let memory = self.device.allocate_memory(&alloc, None)?;
            self.device.bind_image_memory(image, memory, 0)?;
            let view_info = vk::ImageViewCreateInfo::default()
                .image(image)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(COLOR);
            let view = self.device.create_image_view(&view_info, None)?;
            Ok(Image { image, view, memory, format, usage })
        }
    }

    fn begin(&self) -> Result<vk::CommandBuffer, Failure> {
        unsafe {
            let info = vk::CommandBufferAllocateInfo::default().command_pool(self.pool).command_buffer_count(1);
            let cmd = self.device.allocate_command_buffers(&info)?[0];
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            self.device.begin_command_buffer(cmd, &begin)?;
            Ok(cmd)
        }
    }

    fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> Result<(), Failure> {
        unsafe {
            self.device.end_command_buffer(cmd)?;
            let fence = self.device.create_fence(&vk::FenceCreateInfo::default(), None)?;
            let cmds = [cmd];
            self.device.queue_submit(self.queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence)?;
            self.device.wait_for_fences(&[fence], true, u64::MAX)?;
            self.device.destroy_fence(fence, None);
            self.device.free_command_buffers(self.pool, &cmds);
        }
        Ok(())
    }

    /// A full barrier and layout change: the engine's own work before or after the SDK's.
    fn transition(&self, cmd: vk::CommandBuffer, image: &Image, from: vk::ImageLayout, to: vk::ImageLayout) {
        let b = vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
            .old_layout(from)
            .new_layout(to)
            .image(image.image)
            .subresource_range(COLOR);
        let barriers = [b];
        unsafe { self.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers)) };
    }

    fn copy(&self, cmd: vk::CommandBuffer, image: &Image, buffer: &Buffer, to_image: bool) {
        let region = [vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D { width: W, height: H, depth: 1 })];
        unsafe {
            if to_image {
                self.device.cmd_copy_buffer_to_image(
                    cmd,
                    buffer.buffer,
                    image.image,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &region,
                );
            } else {
                self.device.cmd_copy_image_to_buffer(
                    cmd,
                    image.image,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buffer.buffer,
                    &region,
                );
            }
        }
    }

    fn free_buffer(&self, b: Buffer) {
        unsafe {
            self.device.destroy_buffer(b.buffer, None);
            self.device.free_memory(b.memory, None);
        }
    }

    fn free_image(&self, i: Image) {
        unsafe {
            self.device.destroy_image_view(i.view, None);
            self.device.destroy_image(i.image, None);
            self.device.free_memory(i.memory, None);
        }
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        unsafe {
            self.device.destroy_command_pool(self.pool, None);
            self.device.destroy_device(None);
            if let Some((loader, m)) = self.messenger.take() {
                loader.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

const COLOR: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};
const READ: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

// ---------------------------------------------------------------------------------------
// The frame.

fn run(out: &str) -> Result<(), Failure> {
    let gpu = Gpu::new()?;
    let chain = gpu.features.chain();
    let desc = DeviceDesc::new(&gpu.entry, &gpu.instance, gpu.pdev, &gpu.device)
        .enabled_extensions(&gpu.extensions)
        .instance_api_version(vk::API_VERSION_1_3)
        .enabled_features(chain)
        .with_debug_utils(gpu.debug_utils);
    // SAFETY: the handles are this program's live instance, physical device and device, made
    // with these extensions and this feature chain; the context is destroyed before them.
    let ctx = unsafe { ExecuteContext::new(&desc, &InitSettings::default())? };
    println!("hybrid-rt {}.{}.{} on {}", VERSION.0, VERSION.1, VERSION.2, ctx.device_name());

    // ---- The engine's data: meshes in its own buffers, the G-buffer and lit image.
    let meshes = scene();
    let camera = camera();
    let frame = rasterize(&meshes, &camera);
    let probes = Probes::new(&camera)?;
    let res = Resources::upload(&gpu, &meshes, &frame)?;

    // ---- The SDK's tasks: the scene in frame 1, the traces in frame 2.
    let mut tasks = ctx.create_task_container();
    register_scene(&ctx, &gpu, &mut tasks, &meshes, &res.buffers)?;
    let (ao_px, refl_px) = trace_frame(&ctx, &gpu, &mut tasks, &res, camera)?;

    let failures = check(&probes, &ao_px, &refl_px);
    write_png(out, &meshes, &frame, &ao_px, &refl_px)?;
    println!("wrote {out}");

    // ---- Shut down: the SDK first (it holds objects of the device), then the engine's objects.
    drop(tasks);
    ctx.destroy().map_err(|(_, e)| e)?;
    res.free(&gpu);
    if failures.is_empty() {
        println!("all checks passed");
        Ok(())
    } else {
        Err(failures.join("; ").into())
    }
}

/// What the engine hands the SDK: its meshes' vertex and index buffers, the G-buffer and lit
/// image (uploaded, in SHADER_READ_ONLY_OPTIMAL), and the two output images (in GENERAL).
struct Resources {
    buffers: Vec<(Buffer, Buffer)>,
    depth: Image,
    normals: Image,
    lit: Image,
    ao: Image,
    reflections: Image,
}

impl Resources {
    fn upload(gpu: &Gpu, meshes: &[Mesh], frame: &Frame) -> Result<Resources, Failure> {
        let mut buffers = Vec::new();
        for m in meshes {
            let usage = vk::BufferUsageFlags::TRANSFER_SRC; // the SDK copies what it needs out of them
            buffers.push((gpu.buffer_with(&m.positions, usage)?, gpu.buffer_with(&m.indices, usage)?));
        }
        let sampled = vk::ImageUsageFlags::SAMPLED;
        let res = Resources {
            buffers,
            depth: gpu.image(vk::Format::R32_SFLOAT, sampled)?,
            normals: gpu.image(vk::Format::R32G32B32A32_SFLOAT, sampled)?,
            lit: gpu.image(vk::Format::R32G32B32A32_SFLOAT, sampled)?,
            ao: gpu.image(vk::Format::R32_SFLOAT, vk::ImageUsageFlags::STORAGE)?,
            reflections: gpu.image(vk::Format::R32G32B32A32_SFLOAT, vk::ImageUsageFlags::STORAGE)?,
        };
        let uploads = [
            (&res.depth, gpu.buffer_with(&frame.depth, vk::BufferUsageFlags::TRANSFER_SRC)?),
            (&res.normals, gpu.buffer_with(&frame.normals, vk::BufferUsageFlags::TRANSFER_SRC)?),
            (&res.lit, gpu.buffer_with(&frame.lit, vk::BufferUsageFlags::TRANSFER_SRC)?),
        ];
        let cmd = gpu.begin()?;
        for (image, staging) in &uploads {
            gpu.transition(cmd, image, vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
            gpu.copy(cmd, image, staging, true);
            gpu.transition(cmd, image, vk::ImageLayout::TRANSFER_DST_OPTIMAL, READ);
        }
        for image in [&res.ao, &res.reflections] {
            gpu.transition(cmd, image, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
        }
        gpu.submit_and_wait(cmd)?;
        for (_, staging) in uploads {
            gpu.free_buffer(staging);
        }
        Ok(res)
    }

    fn free(self, gpu: &Gpu) {
        for (vb, ib) in self.buffers {
            gpu.free_buffer(vb);
            gpu.free_buffer(ib);
        }
        for image in [self.depth, self.normals, self.lit, self.ao, self.reflections] {
            gpu.free_image(image);
        }
    }
}

/// Frame 1: the scene goes in (geometry copies, BLAS and TLAS builds). A new geometry's
/// cache is laid out on the GPU by this ticket and allocated once it is back (nothing
/// stalls), so light can be injected from the next frame on.
fn register_scene(
    ctx: &ExecuteContext,
    gpu: &Gpu,
    tasks: &mut TaskContainer,
    meshes: &[Mesh],
    buffers: &[(Buffer, Buffer)],
) -> Result<(), Failure> {
    let geometries = ctx.create_geometry_handles(meshes.len());
    let instances = ctx.create_instance_handles(meshes.len());
    for (k, (m, (vb, ib))) in meshes.iter().zip(buffers).enumerate() {
        let input = GeometryInput {
            vertices: VertexBufferInput { buffer: vb.buffer, count: m.positions.len() as u32, ..Default::default() },
            indices: IndexBufferInput { buffer: ib.buffer, count: m.indices.len() as u32, ..Default::default() },
            ..Default::default()
        };
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { tasks.schedule_geometry(&GeometryTask { handle: geometries[k], input, ..Default::default() }) }?;
        // What the cache reads where no view injected light yet (here: the floor behind the
        // camera, which reflected rays reach). The engine's best guess — an upward-facing
        // surface's light — beats black.
        let guess = shade(m.albedo, Vec3::Y).to_array();
        let input =
            InstanceInput { geometry: geometries[k], transform: m.transform, initial_tile_color: guess, ..Default::default() };
        tasks.schedule_instance(&InstanceTask { handle: instances[k], input, ..Default::default() })?;
    }
    tasks.schedule_bvh_build(&BvhBuildTask::default())?;
    let cmd = gpu.begin()?;
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(tasks, cmd) }?;
    gpu.submit_and_wait(cmd)?;
    ctx.mark_gpu_task_completed(ticket)?;
    Ok(())
}

/// Frame 2: the lit image injected into the caches, AO and glossy reflections traced, and both
/// outputs read back in the same submission. Returns the AO and reflection pixels.
fn trace_frame(
    ctx: &ExecuteContext,
    gpu: &Gpu,
    tasks: &mut TaskContainer,
    res: &Resources,
    camera: Camera,
) -> Result<(Vec<f32>, Vec<[f32; 4]>), Failure> {
    // What every trace reads: the G-buffer (floor and boxes: slightly glossy dielectrics).
    let common = TraceCommon {
        depth: DepthInput { image: res.depth.input(READ), ..Default::default() },
        normals: NormalInput { image: res.normals.input(READ), normal_type: NormalType::RgbVector, ..Default::default() },
        viewport: Viewport { width: W, height: H, ..Default::default() },
        camera,
        roughness: RoughnessInput { global_roughness: 0.15, ..Default::default() },
        use_inline_rt: ctx.supports_inline_rt(),
        ..Default::default()
    };
    // Bake the lit frame into the instances' caches: reflections are shaded from them, also
    // where the reflected surface is off screen. Tasks run in the order they are scheduled.
    let inject = DirectLightingInjectionTask {
        depth: common.depth,
        lit: res.lit.input(READ),
        viewport: common.viewport,
        camera,
        ..Default::default()
    };
    tasks.schedule_direct_lighting_injection(&inject)?;
    let ao_task = TraceAmbientOcclusionTask {
        common,
        output: res.ao.input(vk::ImageLayout::GENERAL),
        ray_length: 0.5,
        rays_per_pixel: 16,
        ..Default::default()
    };
    tasks.schedule_ambient_occlusion(&ao_task)?;
    let specular = TraceSpecularTask {
        common,
        output: res.reflections.input(vk::ImageLayout::GENERAL),
        rays_per_pixel: 8,
        miss_radiance: SKY,
        ..Default::default()
    };
    tasks.schedule_specular(&specular)?;

    // Record into our command buffer, then read the outputs back in the same submission.
    let cmd = gpu.begin()?;
    // SAFETY: the buffer is recording; what the tasks name lives until the ticket is back.
    let ticket = unsafe { ctx.build_gpu_task(tasks, cmd) }?;
    let ao_readback = gpu.buffer((W * H * 4) as u64, vk::BufferUsageFlags::TRANSFER_DST)?;
    let refl_readback = gpu.buffer((W * H * 16) as u64, vk::BufferUsageFlags::TRANSFER_DST)?;
    for (image, readback) in [(&res.ao, &ao_readback), (&res.reflections, &refl_readback)] {
        gpu.transition(cmd, image, vk::ImageLayout::GENERAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL);
        gpu.copy(cmd, image, readback, false);
    }
    gpu.submit_and_wait(cmd)?;
    // The GPU is done with the ticket's work: hand it back (its resources are recycled).
    let done = ctx.mark_gpu_task_completed(ticket)?;
    for t in &done.timings {
        println!("  {:?} (task {}): {:.3} ms", t.kind, t.task_index, t.gpu_ms);
    }
    let ao_px: Vec<f32> = bytemuck::cast_slice(ao_readback.bytes()).to_vec();
    let refl_px: Vec<[f32; 4]> = bytemuck::cast_slice(refl_readback.bytes()).to_vec();
    gpu.free_buffer(ao_readback);
    gpu.free_buffer(refl_readback);
    Ok((ao_px, refl_px))
}

/// The pixels checked at the end: the red box's foot, open floor, the floor in front of the
/// red box (it reflects the box's front face) and the floor far behind (it reflects the sky).
struct Probes {
    foot: usize,
    open: usize,
    mirror_red: usize,
    mirror_sky: usize,
}

impl Probes {
    fn new(camera: &Camera) -> Result<Probes, Failure> {
        let at = |p: Vec3| -> Result<usize, Failure> {
            let (x, y) = project(camera, p).ok_or_else(|| format!("{p} is out of view"))?;
            Ok((y * W + x) as usize)
        };
        Ok(Probes {
            foot: at(Vec3::new(-0.3, 0.0, 0.56))?,
            open: at(Vec3::new(1.0, 0.0, 1.2))?,
            mirror_red: at(Vec3::new(0.0, 0.0, 0.75))?,
            mirror_sky: at(Vec3::new(-1.5, 0.0, -2.0))?,
        })
    }
}

/// Is it right? Contact shadows under the boxes, the red box seen in the floor, sky where
/// nothing is, and no validation message. Returns what failed.
fn check(probes: &Probes, ao_px: &[f32], refl_px: &[[f32; 4]]) -> Vec<String> {
    // AO is a 16-ray estimate: judge a 5x5 neighbourhood (400 rays, noise ~0.02).
    let window = |i: usize| {
        let (x, y) = ((i as u32 % W) as i32, (i as u32 / W) as i32);
        let mut sum = 0.0;
        for (dx, dy) in (-2..=2).flat_map(|dx| (-2..=2).map(move |dy| (dx, dy))) {
            let (xx, yy) = ((x + dx).clamp(0, W as i32 - 1), (y + dy).clamp(0, H as i32 - 1));
            sum += ao_px[(yy as u32 * W + xx as u32) as usize];
        }
        sum / 25.0
    };
    let (ao_foot, ao_open) = (window(probes.foot), window(probes.open));
    let (mirror_red, mirror_sky) = (refl_px[probes.mirror_red], refl_px[probes.mirror_sky]);
    println!("AO at the red box's foot {ao_foot:.3}, on open floor {ao_open:.3}");
    println!("reflection in front of the red box {:?}, far from it {:?}", &mirror_red[..3], &mirror_sky[..3]);
    let mut failures = Vec::new();
    if ao_foot > 0.85 {
        failures.push(format!("no contact shadow at the box's foot (AO {ao_foot})"));
    }
    if ao_open < 0.98 {
        failures.push(format!("open floor is occluded (AO {ao_open})"));
    }
    let [r, g, b, _] = mirror_red;
    if !(r > 2.0 * g && r > 2.0 * b && r > 0.05) {
        failures.push(format!("the floor does not reflect the red box: {:?}", [r, g, b]));
    }
    if (0..3).any(|c| (mirror_sky[c] - SKY[c]).abs() > 0.1) {
        failures.push(format!("the floor far from the boxes does not reflect the sky: {:?}", &mirror_sky[..3]));
    }
    let messages = VALIDATION_MESSAGES.load(Ordering::Relaxed);
    if messages > 0 {
        failures.push(format!("{messages} validation messages"));
    }
    failures
}

/// `lit | AO | reflections | composite`, side by side. The composite is what an engine would
/// do with the outputs: ambient x AO added to the direct light, reflections weighted by a
/// Schlick Fresnel term (F0 = 0.04 dielectrics) over the diffuse.
fn write_png(path: &str, meshes: &[Mesh], frame: &Frame, ao: &[f32], refl: &[[f32; 4]]) -> Result<(), Failure> {
    let encode = |v: f32| (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0 + 0.5) as u8;
    let camera = camera();
    let eye = camera.world_to_view.inverse().w_axis.truncate();
    let mut rgb = vec![0u8; (4 * W * H * 3) as usize];
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let panels: [[f32; 3]; 4] = match frame.mesh[i] {
                None => [SKY, [1.0; 3], SKY, SKY],
                Some(m) => {
                    let albedo = meshes[m].albedo;
                    let lit: [f32; 3] = std::array::from_fn(|c| frame.lit[i][c]);
                    let p = unproject(&camera, x as f32, y as f32, frame.depth[i]);
                    let n = Vec3::from_slice(&frame.normals[i][..3]);
                    let cos = n.dot((eye - p).normalize()).clamp(0.0, 1.0);
                    let fresnel = 0.04 + 0.96 * (1.0 - cos).powi(5);
                    let composite = std::array::from_fn(|c| {
                        (1.0 - fresnel) * (lit[c] + 0.25 * albedo[c] * ao[i]) * (0.4 + 0.6 * ao[i]) + fresnel * refl[i][c]
                    });
                    [lit, [ao[i]; 3], std::array::from_fn(|c| refl[i][c]), composite]
                }
            };
            for (k, colour) in panels.iter().enumerate() {
                let o = ((y * 4 * W + k as u32 * W + x) * 3) as usize;
                for c in 0..3 {
                    rgb[o + c] = encode(colour[c]);
                }
            }
        }
    }
    let file = std::fs::File::create(path)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), 4 * W, H);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header()?.write_image_data(&rgb)?;
    Ok(())
}
