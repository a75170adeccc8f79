//! The C ABI's input checks under hostile values: an ambient-occlusion task made through the C
//! structs (defaults, then the engine's images), then one to four of its fields — enum values
//! as raw numbers, floats, counts, formats, layouts, usages, matrices, image handles — set at
//! random, 2,000 cases. Each call returns a status (no panic crosses the ABI), every refusal is
//! an input error whose message names a field, and the context records and completes an
//! ordinary frame afterwards. Pointer and bool fields stay valid: a C caller that breaks those
//! breaks the C language's rules before ours.
use ash::vk;
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

#[test]
fn the_c_abi_refuses_hostile_ambient_occlusion_tasks_by_name() {
    let host = Host::new().unwrap();
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
    // 4 m above the origin, looking down; a 1-radian perspective, depth 0..1 from 0.1 to 100 m.
    good.common.camera.world_to_view = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -4.0, 1.0];
    let (f, n, z) = (1.0 / 0.5f32.tan(), 0.1f32, 100.0f32);
    good.common.camera.view_to_clip =
        [f, 0.0, 0.0, 0.0, 0.0, f, 0.0, 0.0, 0.0, 0.0, z / (n - z), -1.0, 0.0, 0.0, n * z / (n - z), 0.0];
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
    assert_eq!(unsafe { hrt_schedule_ambient_occlusion(container, &good) }, HrtStatus::HRT_OK);
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
    for img in [depth, normals, out] {
        host.destroy_image(img);
    }
}
