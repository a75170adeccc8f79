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

/// A 10 m ground grid seen from 4 m above, its 16x16 G-buffer uploaded: the small scene the
/// input-check tests schedule against and render after refusing bad input.
pub fn ground_view(
    host: &Host,
) -> (hybrid_rt_testkit::reference::Scene, hybrid_rt_testkit::reference::Camera, hybrid_rt_testkit::sdk_scene::GBufferImages) {
    use hybrid_rt_testkit::reference::{Camera, GBuffer, Mesh, Scene, Tracer};
    let mut scene = Scene::default();
    let m = scene.add_mesh(Mesh::grid(10.0, 1));
    scene.add_instance(m, glam::Affine3A::IDENTITY);
    let camera = Camera::look_at(glam::Vec3::new(0.0, 4.0, 0.01), glam::Vec3::ZERO);
    let g = GBuffer::render(&Tracer::new(&scene), &camera, 16, 16);
    let images = hybrid_rt_testkit::sdk_scene::GBufferImages::upload(host, &g).unwrap();
    (scene, camera, images)
}
