//! The C ABI's input checks under hostile values: an ambient-occlusion task made through the C
//! structs (defaults, then the engine's images), then one to four of its fields — enum values
//! as raw numbers, floats, counts, formats, layouts, usages, matrices, image handles — set at
//! random, 2,000 cases. Each call returns a status (no panic crosses the ABI), every refusal is
//! an input error whose message names a field, and the context records and completes an
//! ordinary frame afterwards. Pointer and bool fields stay valid: a C caller that breaks those
//! breaks the C language's rules before ours.
//!
//! Then every schedule entry point, 3,000 cases each, with raw bytes in any field of its struct
//! (nested structs and arrays included, read from the generated header by `c_layout`). Vulkan
//! handles are only ever nulled: the SDK hands them to the driver and cannot tell a stale one
//! from a live one, which is why the functions that take them are unsafe to call.
mod common;
use ash::vk;
use common::c_layout;
use hybrid_rt_c::*;
use hybrid_rt_host::Host;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use std::ffi::c_char;

const W: u32 = 16;

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![Just(f32::NAN), Just(f32::INFINITY), Just(-f32::INFINITY), Just(0.0), Just(f32::MAX), Just(-1.0), -1e4f32..1e4f32]
}

fn image(
    img: &hybrid_rt_host::HostImage,
    format: vk::Format,
    usage: vk::ImageUsageFlags,
    layout: vk::ImageLayout,
) -> HrtImageInput {
    HrtImageInput {
        image: vk::Handle::as_raw(img.image),
        view: vk::Handle::as_raw(img.view),
        format: format.as_raw(),
        width: W,
        height: W,
        layout: layout.as_raw(),
        usage: usage.as_raw(),
    }
}

fn last_error() -> String {
    let mut buffer = [0 as c_char; 512];
    unsafe { hrt_last_error_message(buffer.as_mut_ptr(), buffer.len() as u32) };
    unsafe { std::ffi::CStr::from_ptr(buffer.as_ptr()) }.to_string_lossy().into_owned()
}

/// The context records, runs and completes an ordinary AO frame; then it and its container
/// are destroyed.
fn usable_afterwards(host: &Host, ctx: *mut HrtContext, container: *mut HrtTaskContainer, ao: &HrtTraceAmbientOcclusionTask) {
    assert_eq!(unsafe { hrt_schedule_ambient_occlusion(container, ao) }, HrtStatus::HRT_OK);
    let cmd = host.allocate_command_buffer().unwrap();
    host.begin(cmd).unwrap();
    host.full_barrier(cmd);
    let mut ticket = HrtTicket::default();
    let raw_cmd = vk::Handle::as_raw(cmd) as *mut std::ffi::c_void;
    assert_eq!(unsafe { hrt_build_gpu_task(ctx, container, raw_cmd, &mut ticket) }, HrtStatus::HRT_OK, "{}", last_error());
    host.full_barrier(cmd);
    let fence = host.submit(cmd).unwrap();
    host.wait(fence).unwrap();
    let status = unsafe { hrt_mark_gpu_task_completed(ctx, ticket, std::ptr::null_mut(), 0, std::ptr::null_mut()) };
    assert_eq!(status, HrtStatus::HRT_OK, "{}", last_error());
    assert_eq!(unsafe { hrt_task_container_destroy(container) }, HrtStatus::HRT_OK);
    assert_eq!(unsafe { hrt_context_destroy(ctx) }, HrtStatus::HRT_OK);
}

/// A context on `host`'s device, made through the C ABI.
fn create_context(host: &Host) -> *mut HrtContext {
    let d = host.device_desc();
    let extensions: Vec<*const c_char> = d.enabled_extensions.iter().map(|e| e.as_ptr()).collect();
    let mut desc = HrtContextDesc {
        api_version: HRT_API_VERSION,
        get_instance_proc_addr: host.entry.static_fn().get_instance_proc_addr as *const std::ffi::c_void,
        instance: vk::Handle::as_raw(host.instance.handle()) as *mut _,
        physical_device: vk::Handle::as_raw(host.physical_device) as *mut _,
        device: vk::Handle::as_raw(host.device.handle()) as *mut _,
        enabled_extensions: extensions.as_ptr(),
        enabled_extension_count: extensions.len() as u32,
        instance_api_version: d.instance_api_version,
        enabled_features: d.enabled_features,
        debug_utils: false,
        settings: hrt_init_settings_default(),
    };
    desc.settings.supported_working_sets = 2;
    let mut ctx = std::ptr::null_mut();
    assert_eq!(unsafe { hrt_context_create(&desc, &mut ctx) }, HrtStatus::HRT_OK, "{}", last_error());
    ctx
}

/// A camera 4 m above the origin, looking down; a 1-radian perspective, depth 0..1 from 0.1
/// to 100 m.
fn camera() -> HrtCamera {
    let (f, n, z) = (1.0 / 0.5f32.tan(), 0.1f32, 100.0f32);
    HrtCamera {
        world_to_view: [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -4.0, 1.0],
        view_to_clip: [f, 0.0, 0.0, 0.0, 0.0, f, 0.0, 0.0, 0.0, 0.0, z / (n - z), -1.0, 0.0, 0.0, n * z / (n - z), 0.0],
    }
}

#[test]
fn the_c_abi_refuses_hostile_ambient_occlusion_tasks_by_name() {
    let host = Host::new().unwrap();
    let ctx = create_context(&host);
    let mut container = std::ptr::null_mut();
    assert_eq!(unsafe { hrt_task_container_create(ctx, &mut container) }, HrtStatus::HRT_OK);

    let sampled = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let storage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST;
    let read = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    let general = vk::ImageLayout::GENERAL;
    let depth = host.image_cleared(vk::Format::R32_SFLOAT, W, W, sampled, read).unwrap();
    let normals = host.image_cleared(vk::Format::R32G32B32A32_SFLOAT, W, W, sampled, read).unwrap();
    let out = host.image_cleared(vk::Format::R32_SFLOAT, W, W, storage, general).unwrap();
    let mut good = hrt_trace_ambient_occlusion_task_default();
    good.common.depth.image = image(&depth, vk::Format::R32_SFLOAT, sampled, read);
    good.common.normals.image = image(&normals, vk::Format::R32G32B32A32_SFLOAT, sampled, read);
    good.common.viewport.width = W;
    good.common.viewport.height = W;
    good.common.camera = camera();
    good.output = image(&out, vk::Format::R32_SFLOAT, storage, general);
    assert_eq!(unsafe { hrt_schedule_ambient_occlusion(container, &good) }, HrtStatus::HRT_OK, "{}", last_error());
    unsafe { hrt_task_container_clear(container) };

    let spoil = (any::<usize>(), any_f32(), any::<u32>(), prop::array::uniform16(any_f32()));
    let mut runner = TestRunner::new(Config { cases: 2000, failure_persistence: None, ..Config::default() });
    let refused = std::cell::Cell::new(0u32);
    runner
        .run(&prop::collection::vec(spoil, 1..=4), |spoils| {
            let mut t = good;
            for (index, float, int, matrix) in spoils {
                let c = &mut t.common;
                match index % 22 {
                    0 => c.depth.depth_type = int,
                    1 => c.normals.normal_type = int,
                    2 => c.normals.space = int,
                    3 => c.normals.normal_to_world = matrix[..9].try_into().unwrap(),
                    4 => c.ray_offset.offset_type = int,
                    5 => c.debug_output = int,
                    6 => c.viewport.width = int,
                    7 => c.viewport.x = int,
                    8 => c.viewport.max_depth = float,
                    9 => c.camera.world_to_view = matrix,
                    10 => c.camera.view_to_clip = matrix,
                    11 => c.depth.image.format = int as i32,
                    12 => c.normals.image.layout = int as i32,
                    13 => c.depth.image.usage = int,
                    14 => c.input_mask = HrtImageInput { format: int as i32, ..c.depth.image },
                    15 => c.roughness.min_roughness = float,
                    16 => c.roughness.global_roughness = float,
                    17 => t.output.format = int as i32,
                    18 => t.output.image = u64::from(int),
                    19 => t.rays_per_pixel = int,
                    20 => t.ray_length = float,
                    _ => t.falloff_power = float,
                }
            }
            let status = unsafe { hrt_schedule_ambient_occlusion(container, &t) };
            unsafe { hrt_task_container_clear(container) };
            if status != HrtStatus::HRT_OK {
                refused.set(refused.get() + 1);
                let message = last_error();
                use HrtStatus::*;
                prop_assert!(
                    matches!(status, HRT_ERROR_INVALID_INPUT | HRT_ERROR_UNSUPPORTED_FORMAT | HRT_ERROR_INVALID_TRANSFORM),
                    "{status:?}: {message}"
                );
                prop_assert!(message.contains('.'), "the message names no field: {message}");
            }
            Ok::<(), TestCaseError>(())
        })
        .unwrap();
    // Most hostile values are refused; the rest (a finite float where any is allowed) pass.
    assert!(refused.get() > 1000, "only {} of 2000 cases refused", refused.get());

    // An ordinary frame afterwards: recorded, run, handed back.
    usable_afterwards(&host, ctx, container, &good);
    for img in [depth, normals, out] {
        host.destroy_image(img);
    }
}

/// The bytes of `words` (positions, or indices as their bit patterns).
fn bytes(words: &[f32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_ne_bytes()).collect()
}

/// One raw value for a field: the edges of every type (zero, one, all bits, the sign bit, NaN
/// and the infinities as floats, 1.0 and -1.0) and random bits.
fn raw_value() -> impl Strategy<Value = u64> {
    prop_oneof![
        Just(0u64),
        Just(1),
        Just(2),
        Just(u64::from(u32::MAX)),
        Just(u64::MAX),
        Just(0x8000_0000),
        Just(u64::from(f32::NAN.to_bits())),
        Just(u64::from(f32::INFINITY.to_bits())),
        Just(u64::from(f32::NEG_INFINITY.to_bits())),
        Just(u64::from(1.0f32.to_bits())),
        Just(u64::from((-1.0f32).to_bits())),
        Just(u64::from(1e30f32.to_bits())),
        any::<u64>(),
    ]
}

/// Fuzzes one schedule entry point: `good` (which it accepts) with one to four of its fields
/// overwritten by raw bytes, `CASES` times. Returns how many cases it refused.
fn fuzz_entry<T: Copy>(
    header: &c_layout::Header,
    name: &str,
    good: &T,
    schedule: impl Fn(&T) -> HrtStatus,
    clear: impl Fn(),
) -> u32 {
    const CASES: u32 = 3000;
    let leaves = header.leaves(name, std::mem::size_of::<T>());
    let open: Vec<usize> = (0..leaves.len()).filter(|&i| !leaves[i].protected).collect();
    assert_eq!(schedule(good), HrtStatus::HRT_OK, "{name}: the good task is refused: {}", last_error());
    clear();
    let mut runner = TestRunner::new(Config { cases: CASES, failure_persistence: None, ..Config::default() });
    let refused = std::cell::Cell::new(0u32);
    let edits = prop::collection::vec((0..open.len(), raw_value()), 1..=4);
    runner
        .run(&edits, |edits| {
            let edits: Vec<(usize, u64)> = edits.into_iter().map(|(i, v)| (open[i], v)).collect();
            let t = c_layout::overwrite(good, &leaves, &edits);
            let status = schedule(&t);
            clear();
            if status != HrtStatus::HRT_OK {
                refused.set(refused.get() + 1);
                let message = last_error();
                let fields: Vec<&str> = edits.iter().map(|&(i, _)| leaves[i].path.as_str()).collect();
                use HrtStatus::*;
                prop_assert!(
                    matches!(
                        status,
                        HRT_ERROR_INVALID_INPUT
                            | HRT_ERROR_UNSUPPORTED_FORMAT
                            | HRT_ERROR_INVALID_TRANSFORM
                            | HRT_ERROR_INVALID_HANDLE
                            | HRT_ERROR_BUFFER_TOO_SMALL
                    ),
                    "{name} with {fields:?}: {status:?}: {message}"
                );
                prop_assert!(message.contains('.'), "{name} with {fields:?}: the message names no field: {message}");
            }
            Ok::<(), TestCaseError>(())
        })
        .unwrap();
    refused.get()
}

/// Every schedule entry point of the C ABI, with raw bytes in any of its struct's fields
/// (nested structs and arrays included; pointers and the counts of their arrays excepted):
/// every call returns a status, every refusal is an input error whose message names a field,
/// and the context then records and completes an ordinary frame.
#[test]
fn every_c_schedule_entry_point_refuses_raw_bytes_by_name() {
    let host = Host::new().unwrap();
    let header = c_layout::Header::parse(include_str!("../include/hybrid_rt.h"));
    let ctx = create_context(&host);
    let mut container = std::ptr::null_mut();
    assert_eq!(unsafe { hrt_task_container_create(ctx, &mut container) }, HrtStatus::HRT_OK);
    let clear = || unsafe { hrt_task_container_clear(container) };

    let sampled = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let storage = vk::ImageUsageFlags::STORAGE | sampled | vk::ImageUsageFlags::TRANSFER_SRC;
    let (read, general) = (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, vk::ImageLayout::GENERAL);
    let (r32, rgba16, rgba32) = (vk::Format::R32_SFLOAT, vk::Format::R16G16B16A16_SFLOAT, vk::Format::R32G32B32A32_SFLOAT);
    let depth = host.image_cleared(r32, W, W, sampled, read).unwrap();
    let normals = host.image_cleared(rgba32, W, W, sampled, read).unwrap();
    let scalar = host.image_cleared(r32, W, W, storage, general).unwrap();
    let scalar_out = host.image_cleared(r32, W, W, storage, general).unwrap();
    let color = host.image_cleared(rgba16, W, W, storage, general).unwrap();
    let color_out = host.image_cleared(rgba16, W, W, storage, general).unwrap();
    let color2 = host.image_cleared(rgba16, W, W, storage, general).unwrap();
    let color2_out = host.image_cleared(rgba16, W, W, storage, general).unwrap();
    let (color2_io, color2_o) = (image(&color2, rgba16, storage, general), image(&color2_out, rgba16, storage, general));
    let bits = host.image_cleared(vk::Format::R32_UINT, W, W, storage, general).unwrap();
    let bits_io = image(&bits, vk::Format::R32_UINT, storage, general);
    let (depth_in, normals_in) = (image(&depth, r32, sampled, read), image(&normals, rgba32, sampled, read));
    let (scalar_io, scalar_o) = (image(&scalar, r32, storage, general), image(&scalar_out, r32, storage, general));
    let (color_io, color_o) = (image(&color, rgba16, storage, general), image(&color_out, rgba16, storage, general));

    let viewport = HrtViewport { x: 0, y: 0, width: W, height: W, min_depth: 0.0, max_depth: 0.0 };
    let mut trace = hrt_trace_common_default();
    trace.depth.image = depth_in;
    trace.normals.image = normals_in;
    trace.viewport = viewport;
    trace.camera = camera();
    let mut denoise = hrt_denoising_common_default();
    denoise.depth.image = depth_in;
    denoise.normals.image = normals_in;
    denoise.viewport = viewport;
    denoise.camera = camera();

    // The allocation log (C: a file) records the denoisers' images made below.
    let log_path = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz_allocations.csv");
    let c_path = std::ffi::CString::new(log_path.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { hrt_begin_logging_resource_allocations(ctx, c_path.as_ptr()) }, HrtStatus::HRT_OK, "{}", last_error());
    let nowhere = c"/nonexistent-dir/allocations.csv";
    assert_eq!(unsafe { hrt_begin_logging_resource_allocations(ctx, nowhere.as_ptr()) }, HrtStatus::HRT_ERROR_INVALID_INPUT);
    assert!(last_error().contains("path"), "{}", last_error());

    // Handles to name: a geometry, two instances, a denoising context per signal.
    let mut geometry = 0;
    assert_eq!(unsafe { hrt_create_geometry_handles(ctx, 1, &mut geometry) }, HrtStatus::HRT_OK);
    let mut instances = [0; 2];
    assert_eq!(unsafe { hrt_create_instance_handles(ctx, 2, instances.as_mut_ptr()) }, HrtStatus::HRT_OK);
    let denoiser = |signal: u32| {
        let mut input = hrt_denoising_context_input_default();
        (input.max_width, input.max_height, input.signal) = (W, W, signal);
        let mut handle = 0;
        assert_eq!(unsafe { hrt_create_denoising_context(ctx, &input, &mut handle) }, HrtStatus::HRT_OK, "{}", last_error());
        handle
    };
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    let vertices = host.buffer_with_data(&bytes(&positions), vk::BufferUsageFlags::TRANSFER_SRC).unwrap();
    let indices =
        host.buffer_with_data(&bytes(&[0.0, f32::from_bits(1), f32::from_bits(2)]), vk::BufferUsageFlags::TRANSFER_SRC).unwrap();
    let lights = [HrtLightInfo {
        light_type: HrtLightType::HRT_LIGHT_POINT as u32,
        position: [0.0, 2.0, 0.0],
        direction: [0.0, -1.0, 0.0],
        angular_extent: 0.0,
        radius: 0.1,
        inner_cone: 0.0,
        outer_cone: 0.0,
        range: 10.0,
        intensity: 1.0,
        color: [1.0; 3],
    }];

    let mut refused = Vec::new();
    macro_rules! entry {
        ($name:literal, $good:expr, $schedule:ident) => {{
            let good = $good;
            let n = fuzz_entry(&header, $name, &good, |t| unsafe { $schedule(container, t) }, clear);
            refused.push(($name, n));
        }};
    }

    let mut ao = hrt_trace_ambient_occlusion_task_default();
    (ao.common, ao.output) = (trace, scalar_io);
    entry!("HrtTraceAmbientOcclusionTask", ao, hrt_schedule_ambient_occlusion);
    let mut shadow = hrt_trace_shadow_task_default();
    (shadow.common, shadow.output) = (trace, scalar_io);
    entry!("HrtTraceShadowTask", shadow, hrt_schedule_shadow);
    let mut multi = hrt_trace_multi_shadow_task_default();
    (multi.common, multi.lights, multi.light_count, multi.visibility) = (trace, lights.as_ptr(), 1, bits_io);
    multi.packed = color_io;
    entry!("HrtTraceMultiShadowTask", multi, hrt_schedule_multi_shadow);
    let mut specular = hrt_trace_specular_task_default();
    (specular.common, specular.output) = (trace, color_io);
    (specular.hit_lighting.lights, specular.hit_lighting.light_count) = (lights.as_ptr(), 1);
    entry!("HrtTraceSpecularTask", specular, hrt_schedule_specular);
    let mut diffuse = hrt_trace_diffuse_task_default();
    (diffuse.common, diffuse.output) = (trace, color_io);
    entry!("HrtTraceDiffuseTask", diffuse, hrt_schedule_diffuse);

    let mut inject = hrt_direct_lighting_injection_task_default();
    (inject.depth.image, inject.lit, inject.viewport, inject.camera) = (depth_in, normals_in, viewport, camera());
    entry!("HrtDirectLightingInjectionTask", inject, hrt_schedule_direct_lighting_injection);
    let mut transfer = hrt_direct_light_transfer_task_default();
    (transfer.source, transfer.target) = (instances[0], instances[1]);
    entry!("HrtDirectLightTransferTask", transfer, hrt_schedule_direct_light_transfer);
    entry!("HrtClearCacheTask", HrtClearCacheTask { instance: instances[0] }, hrt_schedule_clear_cache);
    let mut relight = hrt_relight_cache_task_default();
    (relight.lights, relight.light_count) = (lights.as_ptr(), 1);
    entry!("HrtRelightCacheTask", relight, hrt_schedule_cache_relight);

    let mut many_input = hrt_many_lights_context_input_default();
    (many_input.max_width, many_input.max_height, many_input.max_lights) = (W, W, 16);
    let mut many_context = 0;
    assert_eq!(
        unsafe { hrt_create_many_lights_context(ctx, &many_input, &mut many_context) },
        HrtStatus::HRT_OK,
        "{}",
        last_error()
    );
    let mut many = hrt_trace_many_lights_task_default();
    (many.context, many.common, many.diffuse_output, many.specular_output) = (many_context, trace, color_io, color2_io);
    (many.light_operation, many.lights, many.light_count) =
        (HrtLightListOperation::HRT_LIGHT_LIST_REPLACE as u32, lights.as_ptr(), 1);
    entry!("HrtTraceManyLightsTask", many, hrt_schedule_many_lights);

    let mut geometry_task = hrt_geometry_task_default();
    geometry_task.handle = geometry;
    (geometry_task.input.vertices.buffer, geometry_task.input.vertices.count) = (vk::Handle::as_raw(vertices.buffer), 3);
    (geometry_task.input.indices.buffer, geometry_task.input.indices.count) = (vk::Handle::as_raw(indices.buffer), 3);
    entry!("HrtGeometryTask", geometry_task, hrt_schedule_geometry);
    let mut instance = hrt_instance_task_default();
    (instance.handle, instance.input.geometry) = (instances[0], geometry);
    entry!("HrtInstanceTask", instance, hrt_schedule_instance);
    entry!("HrtBvhBuildTask", hrt_bvh_build_task_default(), hrt_schedule_bvh_build);

    let task = |signal: u32, input: HrtImageInput, output: HrtImageInput| HrtDenoiseTask {
        context: denoiser(signal),
        common: denoise,
        input,
        output,
    };
    entry!("HrtDenoiseTask", task(HrtSignalType::HRT_SIGNAL_SPECULAR as u32, color_io, color_o), hrt_schedule_denoise_specular);
    entry!("HrtDenoiseTask", task(HrtSignalType::HRT_SIGNAL_DIFFUSE as u32, color_io, color_o), hrt_schedule_denoise_diffuse);
    let ao_signal = HrtSignalType::HRT_SIGNAL_DIFFUSE_OCCLUSION as u32;
    entry!("HrtDenoiseTask", task(ao_signal, scalar_io, scalar_o), hrt_schedule_denoise_diffuse_occlusion);
    let multi_signal = HrtSignalType::HRT_SIGNAL_MULTI_SHADOW as u32;
    entry!("HrtDenoiseTask", task(multi_signal, color_io, color_o), hrt_schedule_denoise_multi_shadow);
    let mut shadow_denoise = hrt_denoise_shadow_task_default();
    shadow_denoise.context = denoiser(HrtSignalType::HRT_SIGNAL_SHADOW as u32);
    (shadow_denoise.common, shadow_denoise.input, shadow_denoise.output) = (denoise, scalar_io, scalar_o);
    entry!("HrtDenoiseShadowTask", shadow_denoise, hrt_schedule_denoise_shadow);
    let mut both = hrt_denoise_specular_and_diffuse_task_default();
    both.context = denoiser(HrtSignalType::HRT_SIGNAL_SPECULAR_AND_DIFFUSE as u32);
    both.common = denoise;
    (both.input_specular, both.input_diffuse, both.output_specular, both.output_diffuse) =
        (color_io, color2_io, color_o, color2_o);
    entry!("HrtDenoiseSpecularAndDiffuseTask", both, hrt_schedule_denoise_specular_and_diffuse);

    eprintln!("refused of 3000 cases: {refused:?}");
    assert_eq!(unsafe { hrt_end_logging_resource_allocations(ctx) }, HrtStatus::HRT_OK, "{}", last_error());
    assert_eq!(unsafe { hrt_end_logging_resource_allocations(ctx) }, HrtStatus::HRT_ERROR_INVALID_INPUT);
    let log = std::fs::read_to_string(&log_path).unwrap();
    assert!(log.starts_with("time_ms,event,kind,name,bytes,kind_live_bytes\n"), "{log}");
    let denoiser_images = log.lines().filter(|l| l.split(',').nth(1) == Some("alloc") && l.contains(",Denoiser,")).count();
    assert!(denoiser_images >= 6, "six denoising contexts' images logged: {log}");
    // Random bytes are refused far more often than not; a struct whose refusals are rare has
    // checks missing (the BVH build task has two counts, any value of which is valid).
    for (name, n) in &refused {
        assert!(*name == "HrtBvhBuildTask" || *n > 600, "{name}: only {n} of 3000 cases refused");
    }

    // An ordinary frame afterwards: recorded, run, handed back.
    usable_afterwards(&host, ctx, container, &ao);
    for img in [depth, normals, scalar, scalar_out, color, color_out, color2, color2_out, bits] {
        host.destroy_image(img);
    }
    host.destroy_buffer(vertices);
    host.destroy_buffer(indices);
}
