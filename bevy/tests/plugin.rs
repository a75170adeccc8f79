//! The plugin inside a headless Bevy app on lavapipe: the AO, the shadows and the GI it traces
//! from Bevy's prepass against the CPU reference renderer on the same scene and camera, an entity
//! moved and one despawned, effects toggled — with the validation layer on (wgpu enables it in debug builds
//! where it is installed), and no validation message allowed.
use bevy::asset::RenderAssetUsages;
use bevy::log::tracing_subscriber::layer::{Context, Layer};
use bevy::log::tracing_subscriber::Registry;
use bevy::log::{BoxedLayer, LogPlugin};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::window::ExitCondition;
use hybrid_rt_bevy::{
    render_plugin, AoOutput, HybridRtInitPlugin, HybridRtPlugin, RayTracedAo, RayTracedGi, RayTracedReflections, RayTracedShadow,
};
use hybrid_rt_testkit::reference::{self, AoParams, GBuffer, Mesh as RefMesh, Scene as RefScene, Tracer};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};

const W: u32 = 96;
const H: u32 = 64;
const RAYS: u32 = 64;
const RAY_LENGTH: f32 = 1.0;
const EYE: [f32; 3] = [0.0, 1.6, 2.2];
const TARGET: [f32; 3] = [0.0, 0.2, 0.0];
/// Where the sun's light travels: low from behind the cube's left, so its shadow falls on the
/// ground in view.
const SUN: [f32; 3] = [0.6, -1.0, 0.5];
/// A sun wider than the real one (0.1 rad), so its penumbrae are several pixels wide.
const SOFT_SUN: f32 = 0.1;

/// Validation messages seen (wgpu-hal logs the layer's messages), less two that the layer of
/// Debian 12 (1.3.239) reports about Bevy's own objects because it predates them: a device
/// feature struct from a newer Vulkan header, and the WGSL source-language tag of naga's SPIR-V.
static VALIDATION: AtomicU32 = AtomicU32::new(0);
/// The two known messages, counted to show the layer is on.
static KNOWN: AtomicU32 = AtomicU32::new(0);

struct CountValidation;
impl Layer<Registry> for CountValidation {
    fn on_event(&self, event: &bevy::log::tracing::Event<'_>, _: Context<'_, Registry>) {
        // (wgpu-hal logs through the `log` crate: its target arrives as a field.)
        if *event.metadata().level() > bevy::log::Level::WARN {
            return;
        }
        let mut text = String::new();
        event.record(&mut |_: &bevy::log::tracing::field::Field, v: &dyn std::fmt::Debug| text += &format!("{v:?}"));
        let known = text.contains("unknown VkStructureType") || text.contains("Invalid source language operand");
        if text.contains("VALIDATION") && known {
            KNOWN.fetch_add(1, Ordering::Relaxed);
        } else if text.contains("VALIDATION") {
            eprintln!("validation: {text}");
            VALIDATION.fetch_add(1, Ordering::Relaxed);
        }
    }
}

fn count_validation(_: &mut App) -> Option<BoxedLayer> {
    Some(Box::new(CountValidation))
}

/// The latest image the app read back, and how many frames came back.
#[derive(Resource, Clone, Default)]
struct Latest(Arc<Mutex<(Vec<f32>, u32)>>);

/// The images read back every frame: AO, the shadow's visible fraction and the GI's red
/// channel (and the GI's image, which the camera takes later).
#[derive(Clone, Default)]
struct Readbacks {
    ao: Latest,
    shadow: Latest,
    gi: Latest,
    gi_image: Handle<Image>,
    /// The reflections' red channel (the camera takes them later).
    reflections: Latest,
    reflections_image: Handle<Image>,
    /// The camera's render target.
    target: Handle<Image>,
}

#[derive(Component)]
struct Cube;

/// A headless app: an 8 m ground and a unit cube on it, a sun, a camera with ray-traced AO into
/// an R32Float image and the sun's hard shadow, raw, into an Rgba16Float one (G: the visible
/// fraction), both read back every frame.
fn app() -> (App, Readbacks) {
    // Synchronization validation too (the SDK's commands sit between Bevy's).
    std::env::set_var("VK_LAYER_ENABLES", "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT");
    let mut app = App::new();
    app.add_plugins(HybridRtInitPlugin)
        .add_plugins(
            DefaultPlugins
                .set(bevy::render::RenderPlugin { synchronous_pipeline_compilation: true, ..render_plugin() })
                .set(WindowPlugin { primary_window: None, exit_condition: ExitCondition::DontExit, ..default() })
                .set(LogPlugin { custom_layer: count_validation, ..default() })
                .disable::<PipelinedRenderingPlugin>()
                .disable::<bevy::winit::WinitPlugin>(),
        )
        .add_plugins(HybridRtPlugin);
    let mut latest = Readbacks::default();
    let storage_image = |texel: &[u8], format: TextureFormat, app: &mut App| {
        let extent = Extent3d { width: W, height: H, depth_or_array_layers: 1 };
        let mut image = Image::new_fill(extent, TextureDimension::D2, texel, format, RenderAssetUsages::RENDER_WORLD);
        image.texture_descriptor.usage |= TextureUsages::STORAGE_BINDING | TextureUsages::COPY_SRC;
        app.world_mut().resource_mut::<Assets<Image>>().add(image)
    };
    let ao = storage_image(&0.5f32.to_ne_bytes(), TextureFormat::R32Float, &mut app);
    let shadow = storage_image(&[0u8; 8], TextureFormat::Rgba16Float, &mut app);
    latest.gi_image = storage_image(&[0u8; 16], TextureFormat::Rgba32Float, &mut app);
    latest.reflections_image = storage_image(&[0u8; 16], TextureFormat::Rgba32Float, &mut app);
    let world = app.world_mut();
    world.spawn((
        DirectionalLight { shadow_maps_enabled: false, ..default() },
        Transform::default().looking_to(Vec3::from(SUN), Vec3::Y),
    ));
    let mesh = |m: Mesh, w: &mut World| w.resource_mut::<Assets<Mesh>>().add(m);
    let (ground, cube) =
        (mesh(Plane3d::default().mesh().size(8.0, 8.0).into(), world), mesh(Cuboid::new(1.0, 1.0, 1.0).into(), world));
    let material = world.resource_mut::<Assets<StandardMaterial>>().add(StandardMaterial::default());
    world.spawn((Mesh3d(ground), MeshMaterial3d(material.clone())));
    world.spawn((Mesh3d(cube), MeshMaterial3d(material), Transform::from_xyz(0.0, 0.5, 0.0), Cube));
    let target = world.resource_mut::<Assets<Image>>().add(Image::new_target_texture(W, H, TextureFormat::Rgba8UnormSrgb, None));
    latest.target = target.clone();
    world.spawn((
        Camera3d::default(),
        bevy::camera::RenderTarget::from(target),
        bevy::core_pipeline::tonemapping::Tonemapping::Reinhard,
        Projection::Perspective(PerspectiveProjection { fov: 60f32.to_radians(), near: 0.05, ..default() }),
        Transform::from_translation(Vec3::from(EYE)).looking_at(Vec3::from(TARGET), Vec3::Y),
        Msaa::Off,
        RayTracedAo {
            ray_length: RAY_LENGTH,
            rays_per_pixel: RAYS,
            denoise: false,
            output: AoOutput::Image(ao.clone()),
            ..default()
        },
        RayTracedShadow { angular_diameter: 0.0, denoise: false, output: shadow.clone(), ..default() },
    ));
    let l = latest.ao.clone();
    world.spawn(Readback::texture(ao)).observe(move |ev: On<ReadbackComplete>| {
        let mut g = l.0.lock().unwrap();
        g.0 = bytemuck_f32(&ev.data);
        g.1 += 1;
    });
    let l = latest.shadow.clone();
    world.spawn(Readback::texture(shadow)).observe(move |ev: On<ReadbackComplete>| {
        let mut g = l.0.lock().unwrap();
        g.0 = green_f16(&ev.data);
        g.1 += 1;
    });
    for (l, image) in [(&latest.gi, &latest.gi_image), (&latest.reflections, &latest.reflections_image)] {
        let l = l.clone();
        world.spawn(Readback::texture(image.clone())).observe(move |ev: On<ReadbackComplete>| {
            let mut g = l.0.lock().unwrap();
            g.0 = red_f32(&ev.data, 16);
            g.1 += 1;
        });
    }
    app.finish();
    app.cleanup();
    (app, latest)
}

/// A deferred mirror: white metal, roughness 0 (the environment BRDF is 1 at every angle).
fn mirror() -> StandardMaterial {
    StandardMaterial {
        base_color: Color::WHITE,
        metallic: 1.0,
        perceptual_roughness: 0.0,
        opaque_render_method: bevy::material::OpaqueRendererMethod::Deferred,
        ..default()
    }
}

/// The red channel of the camera's next frame (a screenshot of its 8-bit sRGB target), linear.
fn screenshot_red(app: &mut App, target: &Handle<Image>) -> Vec<f32> {
    let shot: Arc<Mutex<Option<Vec<u8>>>> = Arc::default();
    let into = shot.clone();
    app.world_mut().spawn(Screenshot::image(target.clone())).observe(move |ev: On<ScreenshotCaptured>| {
        *into.lock().unwrap() = ev.image.data.clone();
    });
    for _ in 0..10 {
        app.update();
        if shot.lock().unwrap().is_some() {
            break;
        }
    }
    let shot = shot.lock().unwrap().clone().expect("the screenshot came back");
    assert_eq!(shot.len(), (W * H * 4) as usize, "the screenshot's size");
    let linear = |b: u8| {
        let c = b as f32 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    shot.chunks_exact(4).map(|t| linear(t[0])).collect()
}

/// The plugin's count of cameras holding a denoiser history of one effect (a diagnostic of
/// `DIAGNOSTIC_*_HISTORIES`).
fn histories(app: &App, path: &'static str) -> f64 {
    let store = app.world().resource::<bevy::diagnostic::DiagnosticsStore>();
    store.get(&bevy::diagnostic::DiagnosticPath::new(path)).and_then(|d| d.value()).unwrap_or(-1.0)
}

/// The texels of a read-back R32Float image, without the rows' padding (rows are copied at a
/// 256-byte pitch).
fn bytemuck_f32(bytes: &[u8]) -> Vec<f32> {
    red_f32(bytes, 4)
}

/// The R channel of a read-back 32-bit float image of `texel` bytes a texel (rows at a
/// 256-byte pitch).
fn red_f32(bytes: &[u8], texel: usize) -> Vec<f32> {
    let pitch = bytes.len() / H as usize;
    (0..H as usize)
        .flat_map(|y| bytes[y * pitch..y * pitch + W as usize * texel].chunks_exact(texel))
        .map(|c| f32::from_ne_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// The G channel of a read-back Rgba16Float image (rows at a 256-byte pitch), as f32.
fn green_f16(bytes: &[u8]) -> Vec<f32> {
    let pitch = bytes.len() / H as usize;
    (0..H as usize)
        .flat_map(|y| bytes[y * pitch..y * pitch + W as usize * 8].chunks_exact(8))
        .map(|t| f16_to_f32(u16::from_ne_bytes([t[2], t[3]])))
        .collect()
}

/// IEEE half to single (the read-back texels; no crate for one conversion).
fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let frac = (h & 0x3ff) as f32;
    sign * match exp {
        0 => frac * 2f32.powi(-24),
        31 => f32::INFINITY,
        e => (1.0 + frac / 1024.0) * 2f32.powi(e - 15),
    }
}

/// Runs `n` frames and returns the image read back last.
fn frames(app: &mut App, latest: &Latest, n: u32) -> Vec<f32> {
    let before = latest.0.lock().unwrap().1;
    for _ in 0..n {
        app.update();
    }
    let (ao, count) = latest.0.lock().unwrap().clone();
    assert!(count > before, "no image came back in {n} frames");
    assert_eq!(ao.len(), (W * H) as usize, "the image's size");
    ao
}

/// The sun as the SDK takes it, `angular_diameter` wide.
fn sun(angular_diameter: f32) -> hybrid_rt::LightInfo {
    hybrid_rt::LightInfo { direction: glam::Vec3::from(SUN), angular_extent: angular_diameter, ..Default::default() }
}

/// The CPU reference's shadow of `light` (the visible fraction; `strata`² samples a pixel, one
/// for a hard shadow's 0 or 1) on the same scene, G-buffer and camera as `reference`. Beyond a
/// light's range, and outside a spot light's outer cone, pixels are unlit (0), as the SDK
/// documents.
fn reference_shadow(cube_x: Option<f32>, light: &hybrid_rt::LightInfo, strata: u32) -> (GBuffer, Vec<f32>) {
    let (scene, camera) = reference_scene(cube_x);
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let offset = hybrid_rt::TraceShadowTask::default().common.ray_offset;
    let mut rng = reference::Rng::new(7);
    let reaches = |p: glam::Vec3| {
        if light.light_type == hybrid_rt::LightType::Directional {
            return true;
        }
        let v = p - light.position;
        let in_cone = light.light_type != hybrid_rt::LightType::Spot
            || (v.normalize()).dot(light.direction.normalize()) > light.outer_cone.cos();
        (light.range <= 0.0 || v.length() < light.range) && in_cone
    };
    let vis = (0..g.hit.len())
        .map(|i| match (g.hit[i], reaches(g.position[i])) {
            (true, true) => {
                reference::shadow_visibility(&tracer, g.position[i], g.normal[i], camera.eye, light, &offset, strata, &mut rng).0
            }
            (true, false) => 0.0,
            (false, _) => 1.0,
        })
        .collect();
    (g, vis)
}

/// The test's scene for the CPU reference (the cube at `cube_x`, or none) and its camera.
fn reference_scene(cube_x: Option<f32>) -> (RefScene, reference::Camera) {
    reference_scene_with_cube_at(cube_x.map(|x| glam::Vec3::new(x, 0.5, 0.0)))
}

/// The test's scene for the CPU reference with the cube's centre at `cube`, and its camera.
fn reference_scene_with_cube_at(cube: Option<glam::Vec3>) -> (RefScene, reference::Camera) {
    let mut scene = RefScene::default();
    let ground = scene.add_mesh(RefMesh::quad(8.0));
    scene.add_instance(ground, glam::Affine3A::IDENTITY);
    if let Some(at) = cube {
        let cube = scene.add_mesh(RefMesh::cuboid(glam::Vec3::splat(0.5)));
        scene.add_instance(cube, glam::Affine3A::from_translation(at));
    }
    (scene, reference::Camera::look_at(glam::Vec3::from(EYE), glam::Vec3::from(TARGET)))
}

/// The CPU reference of the same scene (cube at `cube_x`, or none), G-buffer and AO.
fn reference(cube_x: Option<f32>) -> (GBuffer, Vec<f32>) {
    let (scene, camera) = reference_scene(cube_x);
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &camera, W, H);
    let defaults = hybrid_rt::TraceAmbientOcclusionTask::default();
    let params =
        AoParams { ray_length: RAY_LENGTH, falloff_power: defaults.falloff_power, ray_offset: defaults.common.ray_offset };
    let ao = reference::reference_ao(&tracer, &g, camera.eye, &params, 16);
    (g, ao)
}

/// Pixels whose 3x3 neighbourhood shows one instance of the reference (no silhouette, where
/// Bevy's rasterizer and the reference's primary rays may pick different surfaces).
fn interior(g: &GBuffer) -> Vec<bool> {
    let (w, h) = (W as i32, H as i32);
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            g.hit[i as usize]
                && (-1..=1).all(|dy| {
                    (-1..=1).all(|dx| {
                        let (qx, qy) = (x + dx, y + dy);
                        qx >= 0 && qy >= 0 && qx < w && qy < h && {
                            let q = (qy * w + qx) as usize;
                            g.hit[q] && g.instance[q] == g.instance[i as usize]
                        }
                    })
                })
        })
        .collect()
}

/// RMSE and the mean difference over a mask.
fn compare(ours: &[f32], reference: &[f32], mask: &[bool]) -> (f32, f32, usize) {
    let (mut se, mut d, mut n) = (0.0f64, 0.0f64, 0usize);
    for i in 0..ours.len() {
        if mask[i] {
            let e = (ours[i] - reference[i]) as f64;
            se += e * e;
            d += e;
            n += 1;
        }
    }
    (((se / n as f64).sqrt()) as f32, (d / n as f64) as f32, n)
}

/// The AO's errors against the reference with the cube at `cube_x`: over the interior pixels,
/// and over the contact region (reference below 0.8).
struct Errors {
    rmse: f32,
    pixels: usize,
    contact_rmse: f32,
    contact_bias: f32,
    contact_pixels: usize,
}

fn against_reference(ao: &[f32], cube_x: Option<f32>) -> Errors {
    let (g, want) = reference(cube_x);
    let mask = interior(&g);
    let (rmse, _, pixels) = compare(ao, &want, &mask);
    let contact: Vec<bool> = mask.iter().zip(&want).map(|(m, r)| *m && *r < 0.8).collect();
    let (contact_rmse, contact_bias, contact_pixels) = compare(ao, &want, &contact);
    Errors { rmse, pixels, contact_rmse, contact_bias, contact_pixels }
}

/// A hard shadow against the reference's with the cube at `cube_x`, over the interior pixels:
/// the fraction of them that disagree (one in shadow, the other lit), and how many each puts
/// in shadow.
fn shadow_against_reference(shadow: &[f32], cube_x: Option<f32>, light: &hybrid_rt::LightInfo) -> (f32, usize, usize) {
    let (g, want) = reference_shadow(cube_x, light, 1);
    let mask = interior(&g);
    let (mut differ, mut ours, mut theirs, mut n) = (0usize, 0usize, 0usize, 0usize);
    for i in 0..shadow.len() {
        if mask[i] {
            let (a, b) = (shadow[i] < 0.5, want[i] < 0.5);
            differ += (a != b) as usize;
            ours += a as usize;
            theirs += b as usize;
            n += 1;
        }
    }
    (differ as f32 / n.max(1) as f32, ours, theirs)
}

/// The shadow read back last.
fn latest_shadow(latest: &Readbacks) -> Vec<f32> {
    let (shadow, count) = latest.shadow.0.lock().unwrap().clone();
    assert!(count > 0 && shadow.len() == (W * H) as usize, "no sun shadow came back");
    shadow
}

/// One test, so Bevy's app (and its log subscriber) is made once per process.
#[test]
fn ray_traced_ao_in_a_bevy_frame() {
    let (mut app, latest) = app();

    // 1. The AO the plugin traced from Bevy's prepass against the CPU reference. Per pixel,
    // 64 rays against 256: the difference's deviation is sqrt(p(1-p)) x sqrt(1/64 + 1/256),
    // at most 0.07 (p = 0.5). Over the contact region's hundred-odd pixels the mean difference
    // is within 0.02 (sampling alone: 0.07 / sqrt(120) = 0.006; the rest for the rasterizer's
    // and the reference's primary rays, which hit a pixel's surface at different points).
    let ao = frames(&mut app, &latest.ao, 6);
    let e = against_reference(&ao, Some(0.0));
    eprintln!(
        "AO vs the CPU reference: RMSE {:.3} over {} px; contact region ({} px) mean difference {:+.3}",
        e.rmse, e.pixels, e.contact_pixels, e.contact_bias
    );
    assert!(
        e.pixels > 1000 && e.contact_pixels > 100,
        "the view shows the ground and the cube's contact ({}, {} px)",
        e.pixels,
        e.contact_pixels
    );
    assert!(e.rmse <= 0.08, "AO RMSE {} against the reference", e.rmse);
    assert!(e.contact_bias.abs() <= 0.02, "contact AO off by {}", e.contact_bias);
    // The sun's hard shadow (one ray is exact): it lies where the reference puts it, but for
    // pixels along its edge, where Bevy's rasterizer and the reference's primary rays hit a
    // pixel's surface at different points (an edge of ~60 pixels in ~4,000).
    let (differ, ours, theirs) = shadow_against_reference(&latest_shadow(&latest), Some(0.0), &sun(0.0));
    eprintln!("sun shadow vs the CPU reference: {:.2}% of pixels differ; {ours} px in shadow ({theirs})", differ * 100.0);
    assert!(theirs > 200, "the view shows the cube's shadow ({theirs} px)");
    assert!(differ <= 0.02 && ours.abs_diff(theirs) * 20 <= theirs, "sun shadow: {differ} differ, {ours} vs {theirs} px");

    // 2. The cube moved 1 m along x: the next frames' AO follows it.
    let cube = app.world_mut().query_filtered::<Entity, With<Cube>>().single(app.world()).unwrap();
    let cube_mesh = app.world().get::<Mesh3d>(cube).unwrap().0.clone();
    let material = app.world().get::<MeshMaterial3d<StandardMaterial>>(cube).unwrap().0.clone();
    app.world_mut().entity_mut(cube).insert(Transform::from_xyz(1.0, 0.5, 0.0));
    let ao = frames(&mut app, &latest.ao, 3);
    let (g, want) = reference(Some(1.0));
    let mask = interior(&g);
    let (rmse, _, _) = compare(&ao, &want, &mask);
    let (_, old) = reference(Some(0.0));
    let (rmse_old, _, _) = compare(&ao, &old, &mask);
    eprintln!("after the move: RMSE {rmse:.3} against the moved cube's reference, {rmse_old:.3} against the old one");
    assert!(rmse <= 0.08 && rmse_old > 2.0 * rmse, "AO after the cube moved: RMSE {rmse} (old place {rmse_old})");
    let shadow = latest_shadow(&latest);
    let ((moved, _, _), (old, _, _)) =
        (shadow_against_reference(&shadow, Some(1.0), &sun(0.0)), shadow_against_reference(&shadow, Some(0.0), &sun(0.0)));
    eprintln!("after the move: the shadow differs from the moved cube's in {moved:.3}, the old one's in {old:.3}");
    assert!(moved <= 0.02 && old > 4.0 * moved, "sun shadow after the cube moved: {moved} (old place {old})");

    // 3. Despawned: no occlusion left on the open ground.
    app.world_mut().despawn(cube);
    let ao = frames(&mut app, &latest.ao, 3);
    let (g, want) = reference(None);
    let mask = interior(&g);
    let (rmse, bias, _) = compare(&ao, &want, &mask);
    eprintln!("after the despawn: RMSE {rmse:.4}, mean difference {bias:+.4}");
    assert!(rmse <= 0.01, "occlusion left after the cube was despawned: RMSE {rmse}");
    let (_, ours, _) = shadow_against_reference(&latest_shadow(&latest), None, &sun(0.0));
    assert_eq!(ours, 0, "shadow left after the cube was despawned");

    // 4. Toggled off and on again, then 1 ray per pixel, denoised (the SDK's AO denoiser on
    // Bevy's G-buffer, reprojecting with the cameras): after 16 frames within the bounds of
    // the 64-ray trace, from a 1-ray trace (its per-pixel RMSE about 0.3 in the contact).
    let camera = app.world_mut().query_filtered::<Entity, With<RayTracedAo>>().single(app.world()).unwrap();
    app.world_mut().get_mut::<RayTracedAo>(camera).unwrap().enabled = false;
    frames(&mut app, &latest.ao, 6);
    // The disabled camera's denoiser history is freed after a few frames.
    assert_eq!(histories(&app, hybrid_rt_bevy::DIAGNOSTIC_AO_HISTORIES), 0.0, "a disabled camera kept its AO history");
    {
        let mut e = app.world_mut().entity_mut(camera);
        let mut ao = e.get_mut::<RayTracedAo>().unwrap();
        ao.enabled = true;
        ao.rays_per_pixel = 1;
        ao.denoise = true;
        let mut shadow = e.get_mut::<RayTracedShadow>().unwrap();
        shadow.angular_diameter = SOFT_SUN;
        shadow.denoise = true;
    }
    let cube =
        app.world_mut().spawn((Mesh3d(cube_mesh), MeshMaterial3d(material.clone()), Transform::from_xyz(0.0, 0.5, 0.0))).id();
    let ao = frames(&mut app, &latest.ao, 16);
    assert_eq!(histories(&app, hybrid_rt_bevy::DIAGNOSTIC_AO_HISTORIES), 1.0, "the camera's AO history");
    let e = against_reference(&ao, Some(0.0));
    eprintln!(
        "1 ray, denoised, 16 frames: RMSE {:.3}; contact RMSE {:.3}, mean difference {:+.3}",
        e.rmse, e.contact_rmse, e.contact_bias
    );
    assert!(
        e.rmse <= 0.08 && e.contact_rmse <= 0.12 && e.contact_bias.abs() <= 0.03,
        "denoised AO: RMSE {}, contact {}, off by {}",
        e.rmse,
        e.contact_rmse,
        e.contact_bias
    );
    // The soft sun's shadow, 1 ray denoised over the same 16 frames, against the reference's 256
    // rays a pixel. In the penumbra 16 frames of one ray leave a deviation of sqrt(p(1-p)/16),
    // at most 0.125, before any spatial filtering, and the reference's own is at most 0.03:
    // the denoised penumbra within 0.15 RMSE, its mean over ~160 pixels within 0.05 (the
    // rasterizer's and the reference's surface points differ along the penumbra too).
    let (g, want) = reference_shadow(Some(0.0), &sun(SOFT_SUN), 16);
    let mask = interior(&g);
    let shadow = latest_shadow(&latest);
    let (rmse, bias, _) = compare(&shadow, &want, &mask);
    let penumbra: Vec<bool> = mask.iter().zip(&want).map(|(m, r)| *m && *r > 0.05 && *r < 0.95).collect();
    let (p_rmse, p_bias, p_pixels) = compare(&shadow, &want, &penumbra);
    eprintln!(
        "soft sun shadow, 1 ray, denoised, 16 frames: RMSE {rmse:.3} (mean difference {bias:+.3}); penumbra ({p_pixels} px) RMSE {p_rmse:.3}, mean difference {p_bias:+.3}"
    );
    assert_eq!(histories(&app, hybrid_rt_bevy::DIAGNOSTIC_SHADOW_HISTORIES), 1.0, "the camera's shadow history");
    assert!(p_pixels > 100, "the view shows the soft shadow's penumbra ({p_pixels} px)");
    assert!(
        rmse <= 0.05 && p_rmse <= 0.15 && p_bias.abs() <= 0.05,
        "denoised sun shadow: RMSE {rmse}, penumbra {p_rmse}, off by {p_bias}"
    );

    // 5. A point light, then a spot light, named by entity: their hard shadows (radius 0; one
    // ray is exact) lie where the reference puts them — the spot light's cone too, outside
    // which the ground is unlit — but for pixels along the edges, as for the sun's.
    let at = Vec3::new(-1.2, 2.0, -0.6);
    let towards = Transform::from_translation(at).looking_at(Vec3::new(0.6, 0.0, 0.5), Vec3::Y);
    let point = app.world_mut().spawn((PointLight { radius: 0.0, range: 20.0, ..default() }, towards)).id();
    let spot = SpotLight { radius: 0.0, range: 20.0, inner_angle: 0.4, outer_angle: 0.5, ..default() };
    let spot = app.world_mut().spawn((spot, towards)).id();
    let v = |v: Vec3| glam::Vec3::new(v.x, v.y, v.z);
    let point_light =
        hybrid_rt::LightInfo { light_type: hybrid_rt::LightType::Point, position: v(at), range: 20.0, ..Default::default() };
    let spot_light = hybrid_rt::LightInfo {
        light_type: hybrid_rt::LightType::Spot,
        direction: v(*towards.forward()),
        inner_cone: 0.4,
        outer_cone: 0.5,
        ..point_light
    };
    for (entity, light, name) in [(point, point_light, "point"), (spot, spot_light, "spot")] {
        {
            let mut shadow = app.world_mut().get_mut::<RayTracedShadow>(camera).unwrap();
            shadow.light = Some(entity);
            shadow.denoise = false;
        }
        frames(&mut app, &latest.shadow, 3);
        let (differ, ours, theirs) = shadow_against_reference(&latest_shadow(&latest), Some(0.0), &light);
        eprintln!(
            "{name} light's shadow vs the CPU reference: {:.2}% of pixels differ; {ours} px unlit ({theirs})",
            differ * 100.0
        );
        assert!(theirs > 200, "the view shows the {name} light's shadow ({theirs} px)");
        assert!(differ <= 0.02 && ours.abs_diff(theirs) * 20 <= theirs, "{name} light: {differ} differ, {ours} vs {theirs} px");
    }

    // 6. GI from Bevy's lit frame: with unlit materials the HDR view target holds each
    // surface's colour as its radiance, so the cache the plugin injects it into must give the
    // ground in front of the cube the cube's front face's light — the only face of it the
    // camera shows, so the only one the cache knows (its sides stay black). The reference
    // shades its hits so: a surface's colour where the camera sees it, black elsewhere. Per
    // pixel, 64 rays against 256 stratified: at most 0.5 x sqrt(1/64 + 1/256) = 0.07 of the
    // red channel (1.0) apart; over the ~1,000 ground pixels the means within 0.02 (the rest
    // for the rasterizer's and the reference's surface points).
    let colour = [1.0f32, 0.5, 0.25];
    {
        let mut materials = app.world_mut().resource_mut::<Assets<StandardMaterial>>();
        let mut m = materials.get_mut(&material).unwrap();
        m.unlit = true;
        m.base_color = Color::linear_rgb(colour[0], colour[1], colour[2]);
    }
    // A one-frame cache average: the cache holds the last frame's colours, not a blend with
    // those of the frames before the materials turned unlit.
    let gi = RayTracedGi {
        rays_per_pixel: RAYS,
        cache_average_frames: 1.0,
        denoise: false,
        output: latest.gi_image.clone(),
        ..default()
    };
    app.world_mut().entity_mut(camera).insert(gi);
    let gi = frames(&mut app, &latest.gi, 4);
    let (scene, eye) = reference_scene(Some(0.0));
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &eye, W, H);
    let seen = |p: glam::Vec3| {
        let to = p - eye.eye;
        tracer.closest_hit(eye.eye, to.normalize(), 0.0, to.length() * 0.999).is_none()
    };
    let radiance = |hit: Option<(glam::Vec3, u32)>| match hit {
        Some((p, 1)) if seen(p) => colour,
        _ => [0.0; 3],
    };
    let want: Vec<f32> = reference::diffuse_reference_with(&tracer, &g, eye.eye, radiance, 100.0, 16, |_, _, _| 1.0)
        .iter()
        .map(|c| c[0])
        .collect();
    let interior = interior(&g);
    let front: Vec<bool> = (0..g.hit.len())
        .map(|i| {
            let p = g.position[i];
            interior[i] && g.normal[i].y > 0.9 && p.z > 0.55 && p.z < 1.5 && p.x.abs() < 1.0
        })
        .collect();
    let (rmse, bias, pixels) = compare(&gi, &want, &front);
    let lit = want.iter().zip(&front).filter(|(w, m)| **m && **w > 0.05).count();
    let mean = |v: &[f32]| v.iter().zip(&front).filter(|(_, m)| **m).map(|(x, _)| *x as f64).sum::<f64>() / pixels as f64;
    eprintln!(
        "GI on the ground in front of the cube ({pixels} px, {lit} lit by it): RMSE {rmse:.3}, mean difference {bias:+.3} (means {:.3} / {:.3})",
        mean(&gi),
        mean(&want)
    );
    assert!(pixels > 300 && lit > 100, "the view shows the ground in front of the cube ({pixels} px, {lit} lit)");
    assert!(rmse <= 0.1 && bias.abs() <= 0.02, "GI from Bevy's lit frame: RMSE {rmse}, off by {bias}");
    assert_eq!(histories(&app, hybrid_rt_bevy::DIAGNOSTIC_GI_HISTORIES), 0.0, "a raw GI trace keeps no denoiser history");
    // 1 ray a pixel, denoised, 16 frames: the temporal average alone leaves at most
    // 0.5 / sqrt(16) = 0.125 of deviation, the spatial filter at least halves it; the means
    // within 0.01 (sampling: 0.35 / sqrt(1,162 px x 16 frames) = 0.003, the rest for the
    // spatial filter at the contact) — light seen by few of a pixel's rays is not cut as
    // fireflies.
    {
        let mut gi = app.world_mut().get_mut::<RayTracedGi>(camera).unwrap();
        gi.rays_per_pixel = 1;
        gi.denoise = true;
    }
    let gi = frames(&mut app, &latest.gi, 16);
    let (rmse, bias, _) = compare(&gi, &want, &front);
    eprintln!("GI, 1 ray, denoised, 16 frames: RMSE {rmse:.3}, mean difference {bias:+.3}");
    assert_eq!(histories(&app, hybrid_rt_bevy::DIAGNOSTIC_GI_HISTORIES), 1.0, "the camera's GI history");
    assert!(rmse <= 0.06 && bias.abs() <= 0.01, "denoised GI: RMSE {rmse}, off by {bias}");

    // 7. A deferred camera: the GI, times each pixel's diffuse colour from Bevy's deferred
    // G-buffer, is added to the lit image. Every light off and no ambient light: the floor's
    // only light is then the composite's — an emissive cube's light bounced off the floor
    // (grey 0.5) — so the floor's final colour is 0.5 x the GI the plugin traced. Over the
    // ~1,000 floor pixels the two means agree within 3% (8-bit output, and the GI read back
    // a frame or two apart from the screenshot: 16 rays, denoised).
    {
        let world = app.world_mut();
        for mut sun in world.query::<&mut DirectionalLight>().iter_mut(world) {
            sun.illuminance = 0.0;
        }
        world.despawn(point);
        world.despawn(spot);
        world.insert_resource(GlobalAmbientLight { brightness: 0.0, ..default() });
        let deferred = bevy::material::OpaqueRendererMethod::Deferred;
        let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
        let grey = StandardMaterial { base_color: Color::linear_rgb(0.5, 0.5, 0.5), opaque_render_method: deferred, ..default() };
        let glowing = StandardMaterial {
            base_color: Color::BLACK,
            emissive: LinearRgba::rgb(colour[0], colour[1], colour[2]),
            opaque_render_method: deferred,
            ..default()
        };
        let (grey, glowing) = (materials.add(grey), materials.add(glowing));
        let ground = world.query_filtered::<Entity, With<Mesh3d>>().iter(world).find(|e| *e != cube).unwrap();
        world.entity_mut(ground).insert(MeshMaterial3d(grey));
        world.entity_mut(cube).insert(MeshMaterial3d(glowing));
        world
            .entity_mut(camera)
            .insert((bevy::core_pipeline::prepass::DeferredPrepass, bevy::core_pipeline::tonemapping::Tonemapping::None));
        // The spot light it traced is gone.
        world.get_mut::<RayTracedShadow>(camera).unwrap().enabled = false;
        let mut gi = world.get_mut::<RayTracedGi>(camera).unwrap();
        gi.rays_per_pixel = 16;
        assert!(gi.composite, "the composite is on by default");
    }
    frames(&mut app, &latest.gi, 8);
    let floor = screenshot_red(&mut app, &latest.target);
    let gi = frames(&mut app, &latest.gi, 1);
    let mean = |v: &[f32]| v.iter().zip(&front).filter(|(_, m)| **m).map(|(x, _)| *x as f64).sum::<f64>() / pixels as f64;
    let (lit, want) = (mean(&floor), 0.5 * mean(&gi));
    eprintln!("deferred camera, lights off: the floor's mean {lit:.4}, 0.5 x its GI {want:.4}");
    assert!(want > 0.02, "the floor receives the cube's light ({want})");
    assert!((lit / want - 1.0).abs() <= 0.03, "the composite added {lit}, not 0.5 x the GI ({want})");

    // 8. Reflections: the floor turns into a mirror (white metal, roughness 0), the cube unlit
    // again, the GI off (the reflections inject the lit frame themselves). A mirror's one ray
    // is exact: the trace's red channel is the cube's colour where the reference's mirror ray
    // from the floor hits the cube's front face (the only face the camera shows: the lit frame
    // gives it), black elsewhere — but for pixels along the reflection's edges. The composite
    // adds the reflection times the environment BRDF, 1 for a white metal, to a floor otherwise
    // black (lights off): the final floor is the reflection.
    {
        let world = app.world_mut();
        let deferred = bevy::material::OpaqueRendererMethod::Deferred;
        let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
        let mirror = mirror();
        let unlit = StandardMaterial {
            base_color: Color::linear_rgb(colour[0], colour[1], colour[2]),
            unlit: true,
            opaque_render_method: deferred,
            ..default()
        };
        let (mirror, unlit) = (materials.add(mirror), materials.add(unlit));
        let ground = world.query_filtered::<Entity, With<Mesh3d>>().iter(world).find(|e| *e != cube).unwrap();
        world.entity_mut(ground).insert(MeshMaterial3d(mirror));
        world.entity_mut(cube).insert(MeshMaterial3d(unlit));
        world.get_mut::<RayTracedGi>(camera).unwrap().enabled = false;
        let reflections = RayTracedReflections {
            cache_average_frames: 1.0,
            denoise: false,
            output: latest.reflections_image.clone(),
            ..default()
        };
        world.entity_mut(camera).insert(reflections);
    }
    let reflected = frames(&mut app, &latest.reflections, 4);
    let want: Vec<f32> = (0..g.hit.len())
        .map(|i| {
            let (p, n) = (g.position[i], g.normal[i]);
            let d = (p - eye.eye).normalize();
            let r = d - 2.0 * d.dot(n) * n;
            match tracer.closest_hit(p + n * 1e-3, r, 0.0, 100.0) {
                Some(hit) if hit.instance == 1 && seen(p + r * hit.t) => colour[0],
                _ => 0.0,
            }
        })
        .collect();
    let floor_mask: Vec<bool> = (0..g.hit.len()).map(|i| interior[i] && g.normal[i].y > 0.9 && g.position[i].y < 0.01).collect();
    let (differ, shows) =
        floor_mask.iter().enumerate().filter(|(_, m)| **m).fold((0, 0), |(d, s), (i, _)| {
            (d + usize::from((reflected[i] - want[i]).abs() > 0.25), s + usize::from(want[i] > 0.5))
        });
    let pixels = floor_mask.iter().filter(|m| **m).count();
    eprintln!("mirror floor: {differ} of {pixels} px differ from the reference's reflection ({shows} px show the cube)");
    assert!(shows > 100, "the mirror shows the cube ({shows} px)");
    assert!(differ * 50 <= pixels, "reflections: {differ} of {pixels} floor pixels differ from the reference");
    let floor = screenshot_red(&mut app, &latest.target);
    let reflected = frames(&mut app, &latest.reflections, 1);
    let mean =
        |v: &[f32]| v.iter().zip(&floor_mask).filter(|(_, m)| **m).map(|(x, _)| x.min(1.0) as f64).sum::<f64>() / pixels as f64;
    let (lit, want) = (mean(&floor), mean(&reflected));
    eprintln!("mirror floor composited: the floor's mean {lit:.4}, its reflection's {want:.4}");
    assert!(want > 0.05 && (lit / want - 1.0).abs() <= 0.03, "the composite added {lit}, not the reflection ({want})");
    assert_eq!(histories(&app, hybrid_rt_bevy::DIAGNOSTIC_REFLECTIONS_HISTORIES), 0.0, "a raw trace keeps no history");
    // A glossy floor (perceptual roughness 0.3, read from the G-buffer): the reflection's edge
    // spreads over many pixels where the mirror's was a step.
    let blurred = |v: &[f32]| v.iter().zip(&floor_mask).filter(|(x, m)| **m && **x > 0.1 && **x < 0.9).count();
    let mirror_edge = blurred(&reflected);
    let floor_material = |app: &mut App| {
        let world = app.world_mut();
        let ground = world.query_filtered::<Entity, With<Mesh3d>>().iter(world).find(|e| *e != cube).unwrap();
        world.get::<MeshMaterial3d<StandardMaterial>>(ground).unwrap().0.clone()
    };
    let glossy_floor = floor_material(&mut app);
    app.world_mut().resource_mut::<Assets<StandardMaterial>>().get_mut(&glossy_floor).unwrap().perceptual_roughness = 0.3;
    app.world_mut().get_mut::<RayTracedReflections>(camera).unwrap().rays_per_pixel = RAYS;
    let glossy = frames(&mut app, &latest.reflections, 3);
    let glossy_edge = blurred(&glossy);
    eprintln!("glossy floor, 64 rays: {glossy_edge} px between 0.1 and 0.9 (the mirror: {mirror_edge})");
    assert!(
        glossy_edge > 100 && glossy_edge > 4 * mirror_edge,
        "the roughness blurs the reflection ({glossy_edge} px, mirror {mirror_edge})"
    );
    // 1 ray a pixel, denoised, 16 frames, against the 64-ray trace: the temporal average alone
    // leaves at most 0.5 / sqrt(16) = 0.125 of deviation where the lobe straddles the cube's
    // edge (the 64-ray trace's own: 0.06), the spatial filter at least halves it; the means
    // within 0.01 (sampling: 0.35 / sqrt(300 edge px x 16 frames) = 0.005).
    {
        let mut r = app.world_mut().get_mut::<RayTracedReflections>(camera).unwrap();
        r.rays_per_pixel = 1;
        r.denoise = true;
    }
    let denoised = frames(&mut app, &latest.reflections, 16);
    let (rmse, bias, _) = compare(&denoised, &glossy, &floor_mask);
    eprintln!("glossy floor, 1 ray, denoised, 16 frames: RMSE {rmse:.3}, mean difference {bias:+.4} against 64 rays");
    assert_eq!(histories(&app, hybrid_rt_bevy::DIAGNOSTIC_REFLECTIONS_HISTORIES), 1.0, "the camera's reflections history");
    assert!(rmse <= 0.06 && bias.abs() <= 0.01, "denoised glossy reflections: RMSE {rmse}, off by {bias}");
    // Rougher than `max_roughness`: the floor is left out (no rays, nothing reflected).
    {
        let mut r = app.world_mut().get_mut::<RayTracedReflections>(camera).unwrap();
        r.max_roughness = 0.2;
        r.denoise = false;
    }
    let left_out = frames(&mut app, &latest.reflections, 4);
    let reflecting = left_out.iter().zip(&floor_mask).filter(|(x, m)| **m && **x > 0.01).count();
    assert_eq!(reflecting, 0, "{reflecting} floor pixels rougher than max_roughness reflect");

    // 9. A light's shadow in the lit image: a grey floor lit by a light and a dim ambient
    // light, the light's shadow maps off (Bevy lights the floor unshadowed), the cube's hard
    // ray-traced shadow composited — the occluded part of the light, computed as Bevy's
    // lighting computes it, taken out. Where the reference puts the shadow the floor keeps the
    // ambient light alone, as Bevy renders it with the light off (what differs is the mismatch
    // of the two computations of the light, either way: within 2% of the light's part, 8-bit
    // rounding included); elsewhere it keeps Bevy's colour (within 8-bit rounding). The sun,
    // then a point light and a spot light (its cone: outside it Bevy gives no light, and the
    // shadow no visibility).
    {
        let world = app.world_mut();
        for mut sun in world.query::<&mut DirectionalLight>().iter_mut(world) {
            sun.illuminance = 3000.0;
        }
        world.insert_resource(GlobalAmbientLight { brightness: 300.0, ..default() });
        let deferred = bevy::material::OpaqueRendererMethod::Deferred;
        let grey = StandardMaterial { base_color: Color::linear_rgb(0.5, 0.5, 0.5), opaque_render_method: deferred, ..default() };
        let grey = world.resource_mut::<Assets<StandardMaterial>>().add(grey);
        let ground = world.query_filtered::<Entity, With<Mesh3d>>().iter(world).find(|e| *e != cube).unwrap();
        world.entity_mut(ground).insert(MeshMaterial3d(grey));
        world.get_mut::<RayTracedReflections>(camera).unwrap().enabled = false;
        let mut shadow = world.get_mut::<RayTracedShadow>(camera).unwrap();
        *shadow = RayTracedShadow { angular_diameter: 0.0, denoise: false, output: shadow.output.clone(), ..default() };
        assert!(shadow.composite, "the shadow's composite is on by default");
    }
    let sun_entity = app.world_mut().query_filtered::<Entity, With<DirectionalLight>>().single(app.world()).unwrap();
    let lumens = 150_000.0;
    let point = PointLight { intensity: lumens, radius: 0.0, range: 20.0, shadow_maps_enabled: false, ..default() };
    let spot = SpotLight {
        intensity: lumens,
        radius: 0.0,
        range: 20.0,
        inner_angle: 0.4,
        outer_angle: 0.5,
        shadow_maps_enabled: false,
        ..default()
    };
    let lights = [
        ("sun", sun_entity, sun(0.0)),
        ("point light", app.world_mut().spawn((point, towards)).id(), point_light),
        ("spot light", app.world_mut().spawn((spot, towards)).id(), spot_light),
    ];
    // Off: no light; on: each light its brightness.
    let brightness = |app: &mut App, entity: Entity, on: bool| {
        let mut e = app.world_mut().entity_mut(entity);
        if let Some(mut l) = e.get_mut::<DirectionalLight>() {
            l.illuminance = if on { 3000.0 } else { 0.0 };
        } else if let Some(mut l) = e.get_mut::<PointLight>() {
            l.intensity = if on { lumens } else { 0.0 };
        } else if let Some(mut l) = e.get_mut::<SpotLight>() {
            l.intensity = if on { lumens } else { 0.0 };
        }
    };
    for (_, entity, _) in &lights[1..] {
        brightness(&mut app, *entity, false);
    }
    for (name, entity, light) in lights {
        brightness(&mut app, entity, true);
        {
            let mut shadow = app.world_mut().get_mut::<RayTracedShadow>(camera).unwrap();
            shadow.light = Some(entity);
            shadow.composite = true;
        }
        frames(&mut app, &latest.shadow, 4);
        let shadowed = screenshot_red(&mut app, &latest.target);
        app.world_mut().get_mut::<RayTracedShadow>(camera).unwrap().composite = false;
        frames(&mut app, &latest.shadow, 4);
        let unshadowed = screenshot_red(&mut app, &latest.target);
        brightness(&mut app, entity, false);
        frames(&mut app, &latest.shadow, 2);
        let ambient = screenshot_red(&mut app, &latest.target);
        let (_, visible) = reference_shadow(Some(0.0), &light, 1);
        let mean_over = |v: &[f32], lit: bool| {
            let pick = |i: usize| floor_mask[i] && (visible[i] > 0.5) == lit;
            let n = (0..v.len()).filter(|i| pick(*i)).count();
            ((0..v.len()).filter(|i| pick(*i)).map(|i| v[i] as f64).sum::<f64>() / n.max(1) as f64, n)
        };
        let ((in_shadow, n_shadow), (before, _)) = (mean_over(&shadowed, false), mean_over(&unshadowed, false));
        let ((lit_after, n_lit), (lit_before, _)) = (mean_over(&shadowed, true), mean_over(&unshadowed, true));
        let (ambient, _) = mean_over(&ambient, false);
        eprintln!(
            "{name}'s shadow composited: {n_shadow} floor px in the reference's shadow {before:.4} -> {in_shadow:.4} (the ambient light alone: {ambient:.4}); {n_lit} lit px {lit_before:.4} -> {lit_after:.4}"
        );
        assert!(
            n_shadow > 200 && n_lit > 200 && before - ambient > 0.02 && ambient > 0.02,
            "{name}: the floor's light {before} with it, {ambient} without ({n_shadow} px in its shadow, {n_lit} lit)"
        );
        assert!(
            (in_shadow - ambient).abs() <= 0.02 * (before - ambient),
            "{name}: the shadow leaves {in_shadow}, not the ambient {ambient}"
        );
        assert!((lit_after - lit_before).abs() <= 1.0 / 255.0, "{name}: lit floor changed: {lit_before} -> {lit_after}");
    }
    app.world_mut().despawn(lights[1].1);
    app.world_mut().despawn(lights[2].1);

    // 10. Hit lighting: the cube floats (its bottom 0.5 m up), a point light under it, the
    // floor a mirror. The mirror shows the cube's bottom face, which the camera never sees (the
    // cache knows nothing of it): its reflection is lit by the light itself — the cube's grey
    // base colour (0.5) as albedo x the light's irradiance, Bevy's lumens / 4 pi / pi (Bevy's
    // diffuse is albedo / pi x irradiance) x the camera's exposure, one exact shadow ray.
    // Against the same computed at the reference's mirror rays' hits: the means within 1%,
    // each pixel within 5% (the rasterizer's and the reference's floor points differ by up to
    // half a pixel, ~1 cm: the reflected point moves as much, and the irradiance a third of a
    // metre from the light changes by 1/d² with it).
    let lumens = 10_000.0;
    let light_at = Vec3::new(0.0, 0.2, 0.0);
    {
        let world = app.world_mut();
        let deferred = bevy::material::OpaqueRendererMethod::Deferred;
        let mut materials = world.resource_mut::<Assets<StandardMaterial>>();
        let mirror = mirror();
        let grey = StandardMaterial { base_color: Color::linear_rgb(0.5, 0.5, 0.5), opaque_render_method: deferred, ..default() };
        let (mirror, grey) = (materials.add(mirror), materials.add(grey));
        let ground = world.query_filtered::<Entity, With<Mesh3d>>().iter(world).find(|e| *e != cube).unwrap();
        world.entity_mut(ground).insert(MeshMaterial3d(mirror));
        world.entity_mut(cube).insert((MeshMaterial3d(grey), Transform::from_xyz(0.0, 1.0, 0.0)));
        world.insert_resource(GlobalAmbientLight { brightness: 0.0, ..default() });
        world.spawn((
            PointLight { intensity: lumens, radius: 0.0, range: 20.0, ..default() },
            Transform::from_translation(light_at),
        ));
        world.get_mut::<RayTracedShadow>(camera).unwrap().enabled = false;
        let mut r = world.get_mut::<RayTracedReflections>(camera).unwrap();
        *r = RayTracedReflections { denoise: false, output: r.output.clone(), ..default() };
    }
    let reflected = frames(&mut app, &latest.reflections, 4);
    let (scene, eye) = reference_scene_with_cube_at(Some(glam::Vec3::new(0.0, 1.0, 0.0)));
    let tracer = Tracer::new(&scene);
    let g = GBuffer::render(&tracer, &eye, W, H);
    let exposure = bevy::camera::Exposure::default().exposure();
    let intensity = lumens / (4.0 * std::f32::consts::PI * std::f32::consts::PI) * exposure;
    let light = glam::Vec3::new(light_at.x, light_at.y, light_at.z);
    let inside = self::interior(&g);
    let (mut shows, mut worst, mut sum, mut want_sum) = (0, 0.0f32, 0.0f64, 0.0f64);
    for i in 0..g.hit.len() {
        let (p, n) = (g.position[i], g.normal[i]);
        if !inside[i] || n.y < 0.9 || p.y > 0.01 {
            continue;
        }
        let d = (p - eye.eye).normalize();
        let r = d - 2.0 * d.dot(n) * n;
        let Some(hit) = tracer.closest_hit(p + n * 1e-3, r, 0.0, 100.0) else { continue };
        let q = p + r * hit.t;
        // The cube's bottom face, away from its edges (where the rasterized and the traced
        // floor points may see different faces).
        if hit.instance != 1 || hit.normal.y > -0.9 || q.x.abs() > 0.45 || q.z.abs() > 0.45 {
            continue;
        }
        let to_light = light - q;
        let want = 0.5 * intensity * -to_light.normalize().y / to_light.length_squared()
            * (1.0 - (to_light.length() / 20.0).powi(4)).powi(2);
        shows += 1;
        worst = worst.max((reflected[i] - want).abs() / want);
        sum += reflected[i] as f64;
        want_sum += want as f64;
    }
    eprintln!(
        "hit lighting: the cube's unseen bottom face in the mirror, {shows} px, means {:.4} / {:.4}, worst pixel {:.2}% off",
        sum / shows.max(1) as f64,
        want_sum / shows.max(1) as f64,
        worst * 100.0
    );
    assert!(shows > 50, "the mirror shows the cube's bottom face ({shows} px)");
    let (mean, want_mean) = (sum / shows.max(1) as f64, want_sum / shows.max(1) as f64);
    assert!(
        (mean / want_mean - 1.0).abs() <= 0.01 && worst <= 0.05,
        "hit-lit reflection: mean {mean} (the light's {want_mean}), worst pixel {:.2}% off",
        worst * 100.0
    );
    app.world_mut().despawn(cube);

    // 11. The SDK's GPU times reached Bevy's diagnostics.
    let store = app.world().resource::<bevy::diagnostic::DiagnosticsStore>();
    for path in hybrid_rt_bevy::DIAGNOSTIC_PATHS {
        let d = store.get(&bevy::diagnostic::DiagnosticPath::new(path)).expect("registered");
        let ms = d.value().unwrap_or(-1.0);
        eprintln!("{path}: {ms:.3} ms");
        assert!(path == "hybrid_rt/scene" || ms > 0.0, "no GPU time measured for {path}");
    }
    // Split per task: the lighting's injection, trace and denoiser of the last frames.
    for kind in
        [hybrid_rt::TaskKind::DirectLightingInjection, hybrid_rt::TaskKind::Specular, hybrid_rt::TaskKind::DenoiseSpecular]
    {
        let path = format!("{}{}", hybrid_rt_bevy::DIAGNOSTIC_TASK_PREFIX, kind.name());
        let ms = store.get(&bevy::diagnostic::DiagnosticPath::new(path.clone())).and_then(|d| d.value()).unwrap_or(-1.0);
        eprintln!("{path}: {ms:.3} ms");
        assert!(ms > 0.0, "no GPU time measured for {path}");
    }

    let messages = VALIDATION.load(Ordering::Relaxed);
    eprintln!("validation layer: {} known messages about Bevy's objects, {messages} others", KNOWN.load(Ordering::Relaxed));
    assert_eq!(messages, 0, "{messages} validation messages");
}
