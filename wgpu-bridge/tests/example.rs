//! Runs the wgpu example end to end on the machine's device (lavapipe in CI): wgpu's device
//! opened through the bridge, the SDK's AO recorded into a wgpu command buffer and read by a
//! wgpu compute shader; the example checks the AO and that no validation message appeared.
#[path = "../examples/wgpu_ao.rs"]
mod example;

#[test]
fn sdk_ao_in_a_wgpu_frame() {
    let report = example::run(None, false).expect("the wgpu example's checks");
    assert!(report.covered < 0.6 && report.open > 0.999, "{report:?}");
    assert!(report.timings.iter().any(|(k, _)| *k == hybrid_rt::TaskKind::AmbientOcclusion), "{report:?}");
}

/// The same frame on a device wgpu-hal created for the engine (its create-device callback
/// adding the SDK's extensions and synchronization2), the SDK attached afterwards.
#[test]
fn sdk_ao_on_a_device_the_engine_created() {
    let report = example::run(None, true).expect("the wgpu example's checks, attached");
    assert!(report.covered < 0.6 && report.open > 0.999, "{report:?}");
    assert!(report.timings.iter().any(|(k, _)| *k == hybrid_rt::TaskKind::AmbientOcclusion), "{report:?}");
}
