//! Runs the wgpu example end to end on the machine's device (lavapipe in CI): wgpu's device
//! opened through the bridge, the SDK's AO recorded into a wgpu command buffer and read by a
//! wgpu compute shader; the example checks the AO and that no validation message appeared.
#[path = "../examples/wgpu_ao.rs"]
mod example;

/// Both ways of opening the device, one after the other: the bridge opening it, and wgpu-hal
/// opening it for the engine (its create-device callback adding the SDK's extensions and
/// synchronization2) with the SDK attached afterwards. One test, not two: the example sets
/// the validation layer's environment and counts its messages process-wide.
#[test]
fn sdk_ao_in_a_wgpu_frame() {
    for attach in [false, true] {
        let report = example::run(None, attach).unwrap_or_else(|e| panic!("the wgpu example's checks (attach: {attach}): {e}"));
        assert!(report.covered < 0.6 && report.open > 0.999, "attach: {attach}: {report:?}");
        assert!(report.timings.iter().any(|(k, _)| *k == hybrid_rt::TaskKind::AmbientOcclusion), "attach: {attach}: {report:?}");
    }
}
