//! hybrid-rt's ambient occlusion in a wgpu renderer.
//!
//! A wgpu program (Vulkan backend) opens its device through `hybrid_rt_wgpu::RtDevice` (wgpu's
//! device, with the SDK's extensions and features), keeps its meshes and G-buffer in wgpu
//! buffers and textures, has the SDK trace AO into a wgpu storage texture, and then shows that
//! texture with a wgpu compute shader of its own (WGSL), whose output it writes as a PNG.
//! One submission: wgpu's state transitions, the SDK's command buffer, wgpu's display pass.
//!
//! The scene is the C sample's: a camera looking straight down at a ground quad with a small
//! quad 0.2 above its centre, so the AO is dark under the small quad and open elsewhere.
//!
//! ```sh
//! cargo run -p hybrid-rt-wgpu --example wgpu_ao -- ao.png
//! ```
//! Exit code 0 = the checks passed and no validation message was logged (the Khronos layer
//! is on, with synchronization validation, when installed; HRT_VALIDATION=0 turns it off).
use hybrid_rt::glam::{self, Affine3A, Vec3, Vec4};
use hybrid_rt::*;
use hybrid_rt_wgpu::{prepare, RtDevice, SDK_READ, SDK_WRITE};
use std::sync::atomic::{AtomicU32, Ordering};
use wgpu::util::DeviceExt;

const W: u32 = 64;
const H: u32 = 64;

#[allow(dead_code)] // the test calls `run` instead
fn main() {
    // `--attach`: the device is opened the way an engine or Bevy opens its own (wgpu-hal's
    // create-device callback), and the SDK attaches to it.
    let attach = std::env::args().any(|a| a == "--attach");
    let out = std::env::args().skip(1).find(|a| a != "--attach").unwrap_or_else(|| "wgpu_ao.png".into());
    match run(Some(std::path::Path::new(&out)), attach) {
        Ok(report) => println!("{report:?}\nwrote {out}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}

/// What the run measured.
#[derive(Debug)]
pub struct Report {
    /// AO at the centre pixel (under the small quad).
    pub covered: f32,
    /// AO at a corner pixel (open sky).
    pub open: f32,
    /// The SDK's per-task GPU times.
    pub timings: Vec<(TaskKind, f64)>,
}

/// Counts the validation layer's warnings and errors (wgpu-hal logs them through `log`).
struct ValidationLog;
static VALIDATION_MESSAGES: AtomicU32 = AtomicU32::new(0);

impl log::Log for ValidationLog {
    fn enabled(&self, m: &log::Metadata<'_>) -> bool {
        m.level() <= log::Level::Warn
    }
    fn log(&self, r: &log::Record<'_>) {
        if !self.enabled(r.metadata()) {
            return;
        }
        let text = r.args().to_string();
        if text.starts_with("VALIDATION") || text.contains("VUID") || text.contains("SYNC-HAZARD") {
            VALIDATION_MESSAGES.fetch_add(1, Ordering::Relaxed);
        }
        eprintln!("[{} {}] {text}", r.level(), r.target());
    }
    fn flush(&self) {}
}

/// Opens the device, traces, shows, checks. `out`: where the shown texture goes as a PNG;
/// `attach`: open wgpu's device first and attach the SDK to it (else the bridge opens it).
pub fn run(out: Option<&std::path::Path>, attach: bool) -> Result<Report, Box<dyn std::error::Error>> {
    let _ = log::set_logger(&ValidationLog).map(|()| log::set_max_level(log::LevelFilter::Warn));
    let validation = std::env::var("HRT_VALIDATION").as_deref() != Ok("0");
    if validation {
        // SAFETY: set while no Vulkan object is alive, on the only thread touching it.
        unsafe { std::env::set_var("VK_LAYER_ENABLES", "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT") };
    }
    let flags = if validation { wgpu::InstanceFlags::VALIDATION } else { wgpu::InstanceFlags::empty() };
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        flags,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });

    // ---- The adapter: the first the SDK can run on (lavapipe on a machine without a GPU).
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
    let adapter = adapters
        .into_iter()
        .find(|a| hybrid_rt_wgpu::check_adapter(a).is_ok())
        .ok_or("no Vulkan adapter with ray tracing (run scripts/setup.sh)")?;
    println!("adapter: {}", adapter.get_info().name);
    let rt = if attach {
        open_and_attach(&adapter)?
    } else {
        RtDevice::new(&adapter, &wgpu::DeviceDescriptor::default(), &InitSettings::default())?
    };
    let (device, queue, ctx) = (&rt.device, &rt.queue, rt.context());

    // ---- Geometry in wgpu buffers: a 20x20 ground quad and a 1x1 quad 0.2 above its centre.
    let ground: [[f32; 3]; 4] = [[-10.0, 0.0, -10.0], [10.0, 0.0, -10.0], [10.0, 0.0, 10.0], [-10.0, 0.0, 10.0]];
    let roof: [[f32; 3]; 4] = [[-0.5, 0.2, -0.5], [0.5, 0.2, -0.5], [0.5, 0.2, 0.5], [-0.5, 0.2, 0.5]];
    let indices: [u32; 6] = [0, 2, 1, 0, 3, 2];
    let buffer = |label, bytes: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: wgpu::BufferUsages::COPY_SRC,
        })
    };
    let vertex_buffers = [buffer("ground", bytemuck::cast_slice(&ground)), buffer("roof", bytemuck::cast_slice(&roof))];
    let index_buffer = buffer("indices", bytemuck::cast_slice(&indices));

    // ---- The G-buffer in wgpu textures: the camera 3 above the origin, looking down.
    let world_to_view = glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::NEG_Z);
    let view_to_clip = glam::camera::rh::proj::vulkan::perspective(60f32.to_radians(), W as f32 / H as f32, 0.05, 100.0);
    let camera = Camera { world_to_view, view_to_clip };
    let ground_clip = view_to_clip * world_to_view * Vec4::new(0.0, 0.0, 0.0, 1.0);
    let depth_texels = vec![ground_clip.z / ground_clip.w; (W * H) as usize];
    let normal_texels = vec![[0.0f32, 1.0, 0.0, 0.0]; (W * H) as usize];
    let texture = |label, format, usage, data: Option<&[u8]>| {
        let desc = wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: W, height: H, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        };
        match data {
            Some(d) => device.create_texture_with_data(queue, &desc, wgpu::util::TextureDataOrder::LayerMajor, d),
            None => device.create_texture(&desc),
        }
    };
    use wgpu::TextureUsages as U;
    let depth = texture("depth", wgpu::TextureFormat::R32Float, U::TEXTURE_BINDING, Some(bytemuck::cast_slice(&depth_texels)));
    let normals =
        texture("normals", wgpu::TextureFormat::Rgba32Float, U::TEXTURE_BINDING, Some(bytemuck::cast_slice(&normal_texels)));
    // Created with contents: wgpu zero-fills a texture it never saw written before its first
    // tracked read, and it does not see the SDK's writes (see the bridge's contract).
    let zeros = vec![0u8; (W * H * 4) as usize];
    let ao_usage = U::STORAGE_BINDING | U::TEXTURE_BINDING | U::COPY_SRC | U::COPY_DST;
    let ao = texture("ao", wgpu::TextureFormat::R32Float, ao_usage, Some(&zeros));
    let shown = texture("shown", wgpu::TextureFormat::Rgba8Unorm, U::STORAGE_BINDING | U::COPY_SRC, None);
    let view = |t: &wgpu::Texture| t.create_view(&Default::default());
    let (depth_view, normals_view, ao_view, shown_view) = (view(&depth), view(&normals), view(&ao), view(&shown));

    // ---- The SDK's tasks: register both quads, build, trace AO into the wgpu texture.
    let geometries = ctx.create_geometry_handles(2);
    let instances = ctx.create_instance_handles(2);
    let mut tasks = ctx.create_task_container();
    for (k, vb) in vertex_buffers.iter().enumerate() {
        let input = GeometryInput {
            vertices: VertexBufferInput { buffer: rt.buffer(vb)?, count: 4, ..Default::default() },
            indices: IndexBufferInput { buffer: rt.buffer(&index_buffer)?, count: 6, ..Default::default() },
            ..Default::default()
        };
        // SAFETY: the engine's buffers the task names are alive.
        unsafe { tasks.schedule_geometry(&GeometryTask { handle: geometries[k], input, ..Default::default() }) }?;
        let input = InstanceInput { geometry: geometries[k], transform: Affine3A::IDENTITY, ..Default::default() };
        tasks.schedule_instance(&InstanceTask { handle: instances[k], input, ..Default::default() })?;
    }
    tasks.schedule_bvh_build(&BvhBuildTask::default())?;
    let common = TraceCommon {
        depth: DepthInput { image: rt.image(&depth, &depth_view, SDK_READ)?, ..Default::default() },
        normals: NormalInput {
            image: rt.image(&normals, &normals_view, SDK_READ)?,
            normal_type: NormalType::RgbVector,
            ..Default::default()
        },
        viewport: Viewport { width: W, height: H, ..Default::default() },
        camera,
        use_inline_rt: ctx.supports_inline_rt(),
        ..Default::default()
    };
    let output = rt.image(&ao, &ao_view, SDK_WRITE)?;
    tasks.schedule_ambient_occlusion(&TraceAmbientOcclusionTask {
        common,
        output,
        ray_length: 1.0,
        rays_per_pixel: 32,
        ..Default::default()
    })?;

    // ---- One submission: wgpu puts the resources in the SDK's states, the SDK traces, wgpu
    // shows the AO with its own compute shader and copies both images out.
    let mut before = device.create_command_encoder(&Default::default());
    let copies: Vec<&wgpu::Buffer> = vertex_buffers.iter().chain([&index_buffer]).collect();
    prepare(&mut before, &[&depth, &normals], &[&ao], &copies);
    // SAFETY: the textures and buffers the tasks name live until the end of `main`, after the
    // ticket is back.
    let (sdk_commands, ticket) = unsafe { rt.record(&mut tasks, Some("hybrid-rt")) }?;
    let mut after = device.create_command_encoder(&Default::default());
    show(device, &mut after, &ao_view, &shown_view);
    let readback = |bytes_per_texel: u32| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: (W * H * bytes_per_texel) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        })
    };
    let (ao_bytes, shown_bytes) = (readback(4), readback(4));
    for (t, b) in [(&ao, &ao_bytes), (&shown, &shown_bytes)] {
        after.copy_texture_to_buffer(
            t.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: b,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(W * 4), rows_per_image: None },
            },
            wgpu::Extent3d { width: W, height: H, depth_or_array_layers: 1 },
        );
    }
    let index = queue.submit([before.finish(), sdk_commands, after.finish()]);
    device.poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: None })?;
    // The GPU is done with the ticket's work: hand it back.
    let done = ctx.mark_gpu_task_completed(ticket)?;

    let read = |b: &wgpu::Buffer| -> Result<Vec<u8>, Box<dyn std::error::Error>> {
        b.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None })?;
        let bytes = b.slice(..).get_mapped_range()?.to_vec();
        b.unmap();
        Ok(bytes)
    };
    let ao_values: Vec<f32> = bytemuck::cast_slice(&read(&ao_bytes)?).to_vec();
    let rgba = read(&shown_bytes)?;
    if let Some(path) = out {
        let file = std::fs::File::create(path)?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), W, H);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.write_header()?.write_image_data(&rgba)?;
    }

    let report = Report {
        covered: ao_values[((H / 2) * W + W / 2) as usize],
        open: ao_values[0],
        timings: done.timings.iter().map(|t| (t.kind, t.gpu_ms)).collect(),
    };
    // The shown texture is the AO through wgpu's own shader: its green channel is ao.
    let shown_centre = rgba[(((H / 2) * W + W / 2) * 4 + 1) as usize] as f32 / 255.0;
    drop(tasks);
    drop(rt);
    let mut failures = Vec::new();
    if report.covered > 0.6 {
        failures.push(format!("no occlusion under the small quad (AO {})", report.covered));
    }
    if report.open < 0.999 {
        failures.push(format!("the open corner is occluded (AO {})", report.open));
    }
    if (shown_centre - report.covered).abs() > 2.0 / 255.0 {
        failures.push(format!("wgpu's shader did not read the SDK's AO ({shown_centre} vs {})", report.covered));
    }
    let messages = VALIDATION_MESSAGES.load(Ordering::Relaxed);
    if messages > 0 {
        failures.push(format!("{messages} validation messages"));
    }
    if failures.is_empty() {
        Ok(report)
    } else {
        Err(failures.join("; ").into())
    }
}

/// The engine's own use of the SDK's output: a wgpu compute pass that colours the AO.
fn show(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, ao: &wgpu::TextureView, shown: &wgpu::TextureView) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("show ao"),
        source: wgpu::ShaderSource::Wgsl(
            r#"
@group(0) @binding(0) var ao: texture_2d<f32>;
@group(0) @binding(1) var shown: texture_storage_2d<rgba8unorm, write>;
@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let a = textureLoad(ao, vec2<i32>(id.xy), 0).r;
    // Warm where open, blue where occluded; green is the AO itself (the example checks it).
    textureStore(shown, vec2<i32>(id.xy), vec4<f32>(mix(0.1, 1.0, a), a, mix(0.6, 0.8, a), 1.0));
}
"#
            .into(),
        ),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("show ao"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(ao) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(shown) },
        ],
    });
    let mut pass = encoder.begin_compute_pass(&Default::default());
    pass.set_pipeline(&pipeline);
    pass.set_bind_group(0, &bind, &[]);
    pass.dispatch_workgroups(W / 8, H / 8, 1);
}

/// Opens wgpu's device as an engine (or Bevy's raw Vulkan initialisation) would — wgpu-hal's
/// create-device callback adding what the SDK needs — and attaches the SDK to it.
fn open_and_attach(adapter: &wgpu::Adapter) -> Result<RtDevice, Box<dyn std::error::Error>> {
    use hybrid_rt_wgpu::{add_sdk_requirements, SDK_WGPU_FEATURES};
    use wgpu::hal::api::Vulkan;
    let desc = wgpu::DeviceDescriptor {
        required_features: SDK_WGPU_FEATURES,
        // SAFETY: the experimental ray-tracing features only get the device's features enabled;
        // this program makes no wgpu ray-tracing pipeline.
        experimental_features: unsafe { wgpu::ExperimentalFeatures::enabled() },
        ..Default::default()
    };
    // SAFETY: the callback only adds extensions and a feature struct.
    let open = unsafe {
        adapter.as_hal::<Vulkan>().ok_or("not a Vulkan adapter")?.open_with_callback(
            desc.required_features,
            &desc.required_limits,
            &desc.memory_hints,
            Some(Box::new(|mut args| add_sdk_requirements(&mut args))),
        )?
    };
    // SAFETY: `open` is a device of this adapter, made for `desc`.
    let (device, queue) = unsafe { adapter.create_device_from_hal(open, &desc) }?;
    Ok(RtDevice::attach(adapter, &device, &queue, &InitSettings::default())?)
}
