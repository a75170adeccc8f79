//! Task labels: the engine names the tasks it schedules, and every timing of a completed
//! ticket carries its task's name (the debug-utils regions in the command buffer too).
mod common;
use common::*;
use glam::{Affine3A, Vec3};
use hybrid_rt::*;
use hybrid_rt_testkit::reference::{Camera, GBuffer, Mesh, Scene, Tracer};
use hybrid_rt_testkit::sdk_scene::*;

#[test]
fn timings_carry_the_labels_their_tasks_were_given() {
    let (host, ctx) = host_and_context(InitSettings::default());
    let mut scene = Scene::default();
    let m = scene.add_mesh(Mesh::grid(20.0, 4));
    scene.add_instance(m, Affine3A::IDENTITY);
    let camera = Camera::look_at(Vec3::new(0.0, 4.0, 1.0), Vec3::ZERO);
    let g = GBuffer::render(&Tracer::new(&scene), &camera, 16, 16);

    let mut frame = ctx.create_task_container();
    let e = frame.set_task_label("nothing yet").unwrap_err();
    assert!(matches!(e, Error::InvalidInput { .. }), "an empty container has no task to label: {e}");

    // Scene tasks apply before the BVH build wherever they stand, so the build can come
    // first: the BVH work is reported under the first BVH task, and carries its label.
    frame.schedule_bvh_build(&Default::default()).unwrap();
    frame.set_task_label("BVH").unwrap();
    let gpu_scene = SceneOnGpu::register(&host, &ctx, &mut frame, &scene).unwrap();
    let images = GBufferImages::upload(&host, &g).unwrap();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 2.0, 1)).unwrap();
    frame.set_task_label("first name").unwrap();
    frame.set_task_label("AO, main view").unwrap();
    let e = frame.set_task_label("AO\0main").unwrap_err();
    assert!(matches!(e, Error::InvalidInput { .. }), "a NUL would cut the C and Vulkan labels: {e}");
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 2.0, 1)).unwrap();
    let done = run_frame(&host, &ctx, &mut frame).unwrap();

    let aos: Vec<_> = done.timings.iter().filter(|t| t.kind == TaskKind::AmbientOcclusion).collect();
    assert_eq!(aos.len(), 2, "{:?}", done.timings);
    assert_eq!(done.label(aos[0]), Some("AO, main view"), "a second label replaces the first");
    assert_eq!(done.label(aos[1]), None, "an unlabelled task has no label");
    let bvh = done.timings.iter().find(|t| t.kind == TaskKind::Bvh).expect("a BVH timing");
    assert_eq!(done.label(bvh), Some("BVH"));
    // The intervals nested in it have no label of their own: labelled times add up.
    let blas = done.timings.iter().find(|t| t.kind == TaskKind::BlasBuild).expect("a BLAS timing");
    assert_eq!(done.label(blas), None);

    // Labels go with the tasks: a cleared container, and the next frame, start without.
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 2.0, 1)).unwrap();
    frame.set_task_label("dropped").unwrap();
    frame.clear();
    frame.schedule_ambient_occlusion(&images.ao_task(&camera, 2.0, 1)).unwrap();
    let done = run_frame(&host, &ctx, &mut frame).unwrap();
    assert!(done.timings.iter().all(|t| done.label(t).is_none()), "{:?}", done.timings);

    images.destroy(&host);
    gpu_scene.destroy(&host);
    drop(ctx);
    assert_no_validation_errors();
}
