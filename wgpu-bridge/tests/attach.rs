//! `RtDevice::attach` refuses a wgpu device that lacks what the SDK needs, naming it, before
//! the SDK touches the device: one made without the SDK's wgpu features, and one made with
//! them but without `add_sdk_requirements` (its extensions are missing).
use hybrid_rt::InitSettings;
use hybrid_rt_wgpu::{BridgeError, RtDevice, SDK_WGPU_FEATURES};

fn adapter() -> wgpu::Adapter {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
    adapters
        .into_iter()
        .find(|a| hybrid_rt_wgpu::check_adapter(a).is_ok())
        .expect("a Vulkan adapter with ray tracing (run scripts/setup.sh)")
}

fn refusal(adapter: &wgpu::Adapter, desc: &wgpu::DeviceDescriptor<'_>) -> String {
    let (device, queue) = pollster::block_on(adapter.request_device(desc)).expect("wgpu opens the device");
    match RtDevice::attach(adapter, &device, &queue, &InitSettings::default()) {
        Err(BridgeError::Unsupported(why)) => why,
        Err(other) => panic!("expected Unsupported, got {other}"),
        Ok(_) => panic!("attached to a device without what the SDK needs"),
    }
}

#[test]
fn a_device_without_the_sdk_s_needs_is_refused_naming_them() {
    let adapter = adapter();
    let why = refusal(&adapter, &wgpu::DeviceDescriptor::default());
    assert!(why.contains("EXPERIMENTAL_RAY_TRACING_PIPELINES") && why.contains("SHADER_FLOAT32_ATOMIC"), "{why}");

    let desc = wgpu::DeviceDescriptor {
        required_features: SDK_WGPU_FEATURES,
        // SAFETY: only to have the device's ray-tracing features enabled; no wgpu ray tracing.
        experimental_features: unsafe { wgpu::ExperimentalFeatures::enabled() },
        ..Default::default()
    };
    let why = refusal(&adapter, &desc);
    assert!(why.contains("VK_KHR_push_descriptor") && why.contains("add_sdk_requirements"), "{why}");
}
