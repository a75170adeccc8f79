//! Shared set-up for the integration tests.
#![allow(dead_code)]
use hybrid_rt::{ExecuteContext, InitSettings};
pub mod relit_scene;
use hybrid_rt_testkit::host::Host;

pub fn host_and_context(settings: InitSettings) -> (Host, ExecuteContext) {
    let host = Host::new().expect("a Vulkan device with ray tracing (run scripts/setup.sh)");
    let ctx = host.create_context(&settings).expect("context");
    (host, ctx)
}

/// Fails the test if the validation layer reported any error so far in this process.
pub fn assert_no_validation_errors() {
    let n = Host::validation_errors();
    assert_eq!(n, 0, "validation errors: {:#?}", Host::validation_messages());
}
