//! A Bevy scene built in code with ray-traced AO from hybrid-rt in place of Bevy's SSAO: rendered
//! headless to a PNG, or shown in a window (`--window`; the T key toggles the ray-traced AO,
//! Bevy's SSAO showing while it is off; `--window --deferred`: AO, sun shadow, GI and
//! reflections all in the lit image, keys 1 to 4 toggling each). `--ssao`: Bevy's own SSAO
//! alone, for comparison. `--shadow-out PATH` (headless): the sun's ray-traced shadow too, its visible fraction
//! written as a grey PNG. `--gi-out PATH` (headless): diffuse GI from the lit frame too
//! (the camera then renders in HDR), written as a PNG (Reinhard-mapped). `--deferred`: the
//! camera renders deferred, and the GI is added to its lit image (the screenshot shows it).
//! `--reflections-out PATH` (headless, deferred): ray-traced reflections too, off a glossy
//! floor and a chrome sphere, added to the lit image and written as a PNG (Reinhard-mapped);
//! `--shiny`: the same floor and sphere without them (with `--plain --deferred`: Bevy's frame).
//! `--cost FRAMES` (headless): renders that many frames after a warm-up and prints Bevy's GPU
//! time per render pass beside the plugin's (timestamp queries), with the ray-traced AO, sun
//! shadow and GI (and reflections, `--deferred`), with `--ssao` (Bevy's SSAO instead), or with
//! `--plain` (neither: Bevy's frame alone).
//!
//! ```sh
//! cargo run --example bevy_ao -- --out ao.png
//! cargo run --example bevy_ao -- --out ao.png --shadow-out sun_shadow.png
//! cargo run --example bevy_ao -- --out ao.png --gi-out gi.png
//! cargo run --example bevy_ao -- --deferred --out lit.png --gi-out gi.png --reflections-out reflections.png
//! cargo run --example bevy_ao -- --ssao --out ssao.png
//! cargo run --example bevy_ao -- --window            # until the window is closed
//! cargo run --example bevy_ao -- --window --frames 60
//! cargo run --example bevy_ao -- --cost 300 --width 1920 --height 1080
//! ```
use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::material::OpaqueRendererMethod;
use bevy::prelude::*;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::TextureFormat;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureUsages};
use bevy::render::settings::{RenderCreation, WgpuFeatures};
use bevy::render::view::screenshot::{save_to_disk, Screenshot};
use bevy::window::ExitCondition;
use hybrid_rt_bevy::{
    render_plugin, HybridRtInitPlugin, HybridRtPlugin, RayTracedAo, RayTracedGi, RayTracedReflections, RayTracedShadow,
    DIAGNOSTIC_PATHS, DIAGNOSTIC_TASK_PREFIX,
};

/// Frames rendered before the screenshot (the scene's BVH is built on the first; the AO
/// denoiser's history fills over the others).
const FRAMES: u32 = 16;

/// The GI image's brightness before it is mapped to 8 bits (one bounce is dim beside the
/// direct light).
const GI_EXPOSURE: f32 = 4.0;

struct Args {
    out: String,
    ssao: bool,
    width: u32,
    height: u32,
    window: bool,
    /// Window mode: exit after this many frames (None: when the window closes).
    frames: Option<u32>,
    /// Headless: also trace the sun's shadow and write it here.
    shadow_out: Option<String>,
    /// Headless: also trace diffuse GI and write it here.
    gi_out: Option<String>,
    /// Headless: also trace reflections (deferred) and write them here.
    reflections_out: Option<String>,
    /// Deferred rendering (the GI composited into the lit image).
    deferred: bool,
    /// A glossy floor and a chrome sphere (with reflections, or to compare without them).
    shiny: bool,
    /// Headless: measure this many frames' GPU times instead of writing images.
    cost: Option<u32>,
    /// No AO of either kind and no shadow: Bevy's own frame.
    plain: bool,
}

fn args() -> Args {
    let mut a = Args {
        out: "bevy_ao.png".into(),
        ssao: false,
        width: 320,
        height: 180,
        window: false,
        frames: None,
        shadow_out: None,
        gi_out: None,
        reflections_out: None,
        deferred: false,
        shiny: false,
        cost: None,
        plain: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--out" => a.out = it.next().expect("--out PATH"),
            "--ssao" => a.ssao = true,
            "--width" => a.width = it.next().and_then(|v| v.parse().ok()).expect("--width N"),
            "--height" => a.height = it.next().and_then(|v| v.parse().ok()).expect("--height N"),
            "--window" => a.window = true,
            "--frames" => a.frames = Some(it.next().and_then(|v| v.parse().ok()).expect("--frames N")),
            "--shadow-out" => a.shadow_out = Some(it.next().expect("--shadow-out PATH")),
            "--gi-out" => a.gi_out = Some(it.next().expect("--gi-out PATH")),
            "--reflections-out" => a.reflections_out = Some(it.next().expect("--reflections-out PATH")),
            "--deferred" => a.deferred = true,
            "--shiny" => a.shiny = true,
            "--cost" => a.cost = Some(it.next().and_then(|v| v.parse().ok()).expect("--cost FRAMES")),
            "--plain" => a.plain = true,
            other => panic!("unknown argument {other}"),
        }
    }
    // Reflections need Bevy's deferred G-buffer (the pixels' roughness and specular colour).
    a.deferred |= a.reflections_out.is_some();
    a.shiny |= a.reflections_out.is_some();
    a
}

#[derive(Resource)]
struct Settings {
    ssao: bool,
    /// Neither AO nor the sun's ray-traced shadow.
    plain: bool,
    /// Headless: the image the camera renders to (None: the window).
    target: Option<Handle<Image>>,
    /// The image the sun's shadow is traced into (None: no shadow traced).
    shadow: Option<Handle<Image>>,
    /// The image diffuse GI is traced into (None: no GI traced).
    gi: Option<Handle<Image>>,
    /// The image reflections are traced into (None: none traced).
    reflections: Option<Handle<Image>>,
    /// A glossy floor and a chrome sphere.
    shiny: bool,
    /// Deferred rendering: the GI is added to the lit image.
    deferred: bool,
}

fn main() {
    let a = args();
    if a.window {
        return window(&a);
    }
    if let Some(frames) = a.cost {
        return cost(&a, frames);
    }
    let mut app = App::new();
    app.add_plugins(HybridRtInitPlugin)
        .add_plugins(
            DefaultPlugins
                // Pipelines compiled before the frame that needs them: the screenshot's frame
                // shows every mesh.
                .set(bevy::render::RenderPlugin { synchronous_pipeline_compilation: true, ..render_plugin() })
                .set(WindowPlugin { primary_window: None, exit_condition: ExitCondition::DontExit, ..default() })
                // One frame rendered per update, so the screenshot's frame is known.
                .disable::<PipelinedRenderingPlugin>()
                .disable::<bevy::winit::WinitPlugin>(),
        )
        .add_plugins(HybridRtPlugin)
        .add_systems(Startup, setup);
    let target = {
        let mut images = app.world_mut().resource_mut::<Assets<Image>>();
        images.add(Image::new_target_texture(a.width, a.height, TextureFormat::Rgba8UnormSrgb, None))
    };
    let shadow =
        a.shadow_out.as_ref().map(|_| app.world_mut().resource_mut::<Assets<Image>>().add(shadow_image(a.width, a.height)));
    let mut radiance = |path: &Option<String>| {
        path.as_ref().map(|_| app.world_mut().resource_mut::<Assets<Image>>().add(radiance_image(a.width, a.height)))
    };
    let (gi, reflections) = (radiance(&a.gi_out), radiance(&a.reflections_out));
    app.insert_resource(Settings {
        ssao: a.ssao,
        plain: false,
        target: Some(target.clone()),
        shadow: shadow.clone(),
        gi: gi.clone(),
        reflections: reflections.clone(),
        deferred: a.deferred,
        shiny: a.shiny,
    });
    app.finish();
    app.cleanup();
    for _ in 0..FRAMES {
        app.update();
    }
    let _ = std::fs::remove_file(&a.out);
    app.world_mut().spawn(Screenshot::image(target)).observe(save_to_disk(a.out.clone()));
    if let (Some(shadow), Some(path)) = (shadow, a.shadow_out.clone()) {
        let _ = std::fs::remove_file(&path);
        let (w, h) = (a.width, a.height);
        app.world_mut().spawn(Readback::texture(shadow)).observe(move |ev: On<ReadbackComplete>, mut commands: Commands| {
            write_grey_png(&ev.data, w, h, &path);
            commands.entity(ev.entity).despawn();
        });
    }
    for (image, path, exposure) in [(gi, a.gi_out.clone(), GI_EXPOSURE), (reflections, a.reflections_out.clone(), 1.0)] {
        let (Some(image), Some(path)) = (image, path) else { continue };
        let _ = std::fs::remove_file(&path);
        let (w, h) = (a.width, a.height);
        app.world_mut().spawn(Readback::texture(image)).observe(move |ev: On<ReadbackComplete>, mut commands: Commands| {
            write_radiance_png(&ev.data, w, h, exposure, &path);
            commands.entity(ev.entity).despawn();
        });
    }
    // The screenshot is read back and written a few updates later.
    for _ in 0..60 {
        app.update();
        let written = |p: &str| std::fs::metadata(p).is_ok_and(|m| m.len() > 0);
        let outputs = [&a.shadow_out, &a.gi_out, &a.reflections_out];
        if written(&a.out) && outputs.iter().all(|p| p.as_deref().is_none_or(written)) {
            println!("wrote {}", a.out);
            print_gpu_times(&app);
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    eprintln!("error: no screenshot came back");
    std::process::exit(1);
}

/// Headless: `frames` frames after a warm-up, then Bevy's GPU time per render pass (its render
/// diagnostics, timestamp queries around each pass) beside the plugin's, and the wall time of
/// an update (not paced by a display).
fn cost(a: &Args, frames: u32) {
    let mut render = render_plugin();
    if let RenderCreation::Automatic(settings) = &mut render.render_creation {
        settings.features |= WgpuFeatures::TIMESTAMP_QUERY
            | WgpuFeatures::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | WgpuFeatures::TIMESTAMP_QUERY_INSIDE_PASSES;
    }
    let mut app = App::new();
    app.add_plugins(HybridRtInitPlugin)
        .add_plugins(
            DefaultPlugins
                .set(bevy::render::RenderPlugin { synchronous_pipeline_compilation: true, ..render })
                .set(WindowPlugin { primary_window: None, exit_condition: ExitCondition::DontExit, ..default() })
                .disable::<PipelinedRenderingPlugin>()
                .disable::<bevy::winit::WinitPlugin>(),
        )
        .add_plugins((HybridRtPlugin, RenderDiagnosticsPlugin))
        .add_systems(Startup, setup);
    let mut images = app.world_mut().resource_mut::<Assets<Image>>();
    let target = images.add(Image::new_target_texture(a.width, a.height, TextureFormat::Rgba8UnormSrgb, None));
    let shadow = (!a.plain && !a.ssao).then(|| images.add(shadow_image(a.width, a.height)));
    let gi = (!a.plain && !a.ssao).then(|| images.add(radiance_image(a.width, a.height)));
    let reflections = (!a.plain && !a.ssao && a.deferred).then(|| images.add(radiance_image(a.width, a.height)));
    let target = Some(target);
    let (ssao, plain, deferred, shiny) = (a.ssao, a.plain, a.deferred, a.shiny);
    app.insert_resource(Settings { ssao, plain, target, shadow, gi, reflections, deferred, shiny });
    app.finish();
    app.cleanup();
    // Warm-up: pipelines, the BVH, the denoisers' histories, the GPU's clocks.
    for _ in 0..60 {
        app.update();
    }
    let start = std::time::Instant::now();
    for _ in 0..frames {
        app.update();
    }
    let update_ms = start.elapsed().as_secs_f64() * 1e3 / f64::from(frames.max(1));
    let store = app.world().resource::<bevy::diagnostic::DiagnosticsStore>();
    let mut bevy_total = 0.0;
    println!("{}x{}, {frames} frames, GPU ms (mean of the last frames):", a.width, a.height);
    for d in store.iter() {
        let path = d.path().as_str();
        let Some(ms) = d.average() else { continue };
        // Bevy's passes: render/<pass>/elapsed_gpu; nested spans have more components.
        let top_level_pass = path.starts_with("render/") && path.ends_with("/elapsed_gpu") && path.matches('/').count() == 2;
        if top_level_pass {
            bevy_total += ms;
            println!("  {path}: {ms:.3}");
        } else if DIAGNOSTIC_PATHS.contains(&path) || path.starts_with(DIAGNOSTIC_TASK_PREFIX) {
            println!("  {path}: {ms:.3}");
        }
    }
    println!("  Bevy's passes, total: {bevy_total:.3}");
    println!("update wall time: {update_ms:.3} ms");
}

/// The image diffuse GI or reflections are traced into: RGBA32F (radiance, hit distance).
fn radiance_image(width: u32, height: u32) -> Image {
    let extent = Extent3d { width, height, depth_or_array_layers: 1 };
    let mut image =
        Image::new_fill(extent, TextureDimension::D2, &[0u8; 16], TextureFormat::Rgba32Float, RenderAssetUsages::RENDER_WORLD);
    image.texture_descriptor.usage |= TextureUsages::STORAGE_BINDING | TextureUsages::COPY_SRC;
    image
}

/// Writes a read-back RGBA32F radiance image (rows at a 256-byte pitch) as an sRGB PNG,
/// Reinhard-mapped (x / (1 + x)) and scaled by `exposure` first.
fn write_radiance_png(bytes: &[u8], width: u32, height: u32, exposure: f32, path: &str) {
    let pitch = bytes.len() / height as usize;
    let mut texels = Vec::with_capacity((width * height * 4) as usize);
    for y in 0..height as usize {
        for t in bytes[y * pitch..y * pitch + width as usize * 16].chunks_exact(16) {
            for c in 0..3 {
                let v = f32::from_ne_bytes([t[4 * c], t[4 * c + 1], t[4 * c + 2], t[4 * c + 3]]).max(0.0) * exposure;
                texels.push(((v / (1.0 + v)).powf(1.0 / 2.2) * 255.0).round() as u8);
            }
            texels.push(255);
        }
    }
    let extent = Extent3d { width, height, depth_or_array_layers: 1 };
    let image = Image::new(extent, TextureDimension::D2, texels, TextureFormat::Rgba8UnormSrgb, RenderAssetUsages::MAIN_WORLD);
    save_png(image, path);
}

/// Writes an 8-bit image (made on the CPU) as a PNG, saying where, or why not.
fn save_png(image: Image, path: &str) {
    match image.try_into_dynamic().map(|d| d.save(path)) {
        Ok(Ok(())) => println!("wrote {path}"),
        Ok(Err(e)) => eprintln!("error: {path}: {e}"),
        Err(e) => eprintln!("error: {path}: {e}"),
    }
}

/// The image the sun's shadow is traced into: one float per pixel (its visible fraction).
fn shadow_image(width: u32, height: u32) -> Image {
    let extent = Extent3d { width, height, depth_or_array_layers: 1 };
    let texel = 1f32.to_ne_bytes();
    let mut image =
        Image::new_fill(extent, TextureDimension::D2, &texel, TextureFormat::R32Float, RenderAssetUsages::RENDER_WORLD);
    image.texture_descriptor.usage |= TextureUsages::STORAGE_BINDING | TextureUsages::COPY_SRC;
    image
}

/// Writes a read-back R32Float image (rows at a 256-byte pitch) as a grey PNG.
fn write_grey_png(bytes: &[u8], width: u32, height: u32, path: &str) {
    let pitch = bytes.len() / height as usize;
    let mut grey = Vec::with_capacity((width * height) as usize);
    for y in 0..height as usize {
        for t in bytes[y * pitch..y * pitch + width as usize * 4].chunks_exact(4) {
            let v = (f32::from_ne_bytes([t[0], t[1], t[2], t[3]]).clamp(0.0, 1.0) * 255.0).round() as u8;
            grey.push(v);
        }
    }
    let extent = Extent3d { width, height, depth_or_array_layers: 1 };
    let image = Image::new(extent, TextureDimension::D2, grey, TextureFormat::R8Unorm, RenderAssetUsages::MAIN_WORLD);
    save_png(image, path);
}

/// The scene in a window, the SDK's GPU times printed every second.
fn window(a: &Args) {
    let title = match a.deferred {
        true => "hybrid-rt in Bevy (keys 1-4: AO, sun shadow, GI, reflections on / off)",
        false => "hybrid-rt in Bevy (T: ray-traced AO on / off)",
    };
    // The effects' images are of the window's size in pixels, whatever the display's scale.
    let (width, height) = (1280, 720);
    let resolution = bevy::window::WindowResolution::new(width, height).with_scale_factor_override(1.0);
    let window = Window { title: title.into(), resolution, ..default() };
    let mut app = App::new();
    app.add_plugins(HybridRtInitPlugin)
        .add_plugins(DefaultPlugins.set(render_plugin()).set(WindowPlugin { primary_window: Some(window), ..default() }))
        .add_plugins(HybridRtPlugin);
    // Deferred, every effect reaches the lit image: all four traced, each toggled by its key.
    let mut images = app.world_mut().resource_mut::<Assets<Image>>();
    let mut image = |on: bool, make: fn(u32, u32) -> Image| on.then(|| images.add(make(width, height)));
    let (shadow, gi, reflections) =
        (image(a.deferred, shadow_image), image(a.deferred, radiance_image), image(a.deferred, radiance_image));
    app.insert_resource(Settings {
        ssao: a.ssao,
        plain: false,
        target: None,
        shadow,
        gi,
        reflections,
        deferred: a.deferred,
        shiny: a.shiny || a.deferred,
    })
    .add_systems(Startup, setup)
    .add_systems(Update, toggle_and_report);
    if let Some(frames) = a.frames {
        app.add_systems(Update, move |mut n: Local<u32>, mut exit: MessageWriter<AppExit>| {
            *n += 1;
            if *n >= frames {
                exit.write(AppExit::Success);
            }
        });
    }
    app.run();
}

/// A camera's effects, as the keys toggle them.
type Effects = (
    &'static mut RayTracedAo,
    Option<&'static mut RayTracedShadow>,
    Option<&'static mut RayTracedGi>,
    Option<&'static mut RayTracedReflections>,
);

/// T or 1 toggles the ray-traced AO, 2 the sun's shadow, 3 the GI, 4 the reflections; every
/// second the SDK's GPU times are printed.
fn toggle_and_report(
    keys: Res<ButtonInput<KeyCode>>,
    mut cameras: Query<Effects>,
    diagnostics: Res<bevy::diagnostic::DiagnosticsStore>,
    time: Res<Time>,
    mut last: Local<f32>,
) {
    let toggle = |enabled: &mut bool, name: &str| {
        *enabled = !*enabled;
        println!("ray-traced {name} {}", if *enabled { "on" } else { "off" });
    };
    for (mut ao, shadow, gi, reflections) in &mut cameras {
        if keys.just_pressed(KeyCode::KeyT) || keys.just_pressed(KeyCode::Digit1) {
            toggle(&mut ao.enabled, "AO (off: Bevy's SSAO)");
        }
        if let (Some(mut s), true) = (shadow, keys.just_pressed(KeyCode::Digit2)) {
            toggle(&mut s.enabled, "sun shadow");
        }
        if let (Some(mut g), true) = (gi, keys.just_pressed(KeyCode::Digit3)) {
            toggle(&mut g.enabled, "GI");
        }
        if let (Some(mut r), true) = (reflections, keys.just_pressed(KeyCode::Digit4)) {
            toggle(&mut r.enabled, "reflections");
        }
    }
    if time.elapsed_secs() - *last >= 1.0 {
        *last = time.elapsed_secs();
        let ms = |p: &str| diagnostics.get(&bevy::diagnostic::DiagnosticPath::new(p.to_string())).and_then(|d| d.average());
        if let Some(frame) = ms("hybrid_rt/frame") {
            let parts: Vec<String> = ["ao", "shadow", "gi", "reflections"]
                .iter()
                .filter_map(|p| ms(&format!("hybrid_rt/{p}")).map(|t| format!("{p} {t:.3}")))
                .collect();
            println!("hybrid-rt GPU time: frame {frame:.3} ms ({} ms)", parts.join(", "));
        }
    }
}

/// The SDK's GPU times of the last frames, as the plugin publishes them (Bevy diagnostics).
fn print_gpu_times(app: &App) {
    let store = app.world().resource::<bevy::diagnostic::DiagnosticsStore>();
    for path in DIAGNOSTIC_PATHS {
        if let Some(ms) = store.get(&bevy::diagnostic::DiagnosticPath::new(path)).and_then(|d| d.average()) {
            println!("{path}: {ms:.3} ms (GPU, mean of the last frames)");
        }
    }
}

fn setup(
    mut commands: Commands,
    settings: Res<Settings>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let method = if settings.deferred { OpaqueRendererMethod::Deferred } else { OpaqueRendererMethod::Auto };
    let material = |base_color, perceptual_roughness, metallic| StandardMaterial {
        base_color,
        perceptual_roughness,
        metallic,
        opaque_render_method: method,
        ..default()
    };
    let shiny = settings.shiny;
    let floor = materials.add(material(Color::srgb(0.8, 0.8, 0.8), if shiny { 0.25 } else { 0.9 }, 0.0));
    let red = materials.add(material(Color::srgb(0.8, 0.2, 0.2), 0.6, 0.0));
    let ball = match shiny {
        true => materials.add(material(Color::srgb(0.95, 0.93, 0.88), 0.05, 1.0)),
        false => floor.clone(),
    };
    commands.spawn((Mesh3d(meshes.add(Plane3d::default().mesh().size(8.0, 8.0))), MeshMaterial3d(floor)));
    commands.spawn((Mesh3d(meshes.add(Cuboid::new(1.0, 1.0, 1.0))), MeshMaterial3d(red), Transform::from_xyz(0.0, 0.5, 0.0)));
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(0.5).mesh().uv(32, 18))),
        MeshMaterial3d(ball),
        Transform::from_xyz(1.3, 0.5, 0.6),
    ));
    commands.spawn((
        // Deferred with the ray-traced shadow, Bevy's shadow maps make way for it.
        DirectionalLight {
            illuminance: 3000.0,
            shadow_maps_enabled: !(settings.deferred && settings.shadow.is_some()),
            ..default()
        },
        Transform::from_xyz(2.0, 4.0, 1.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    // Deferred, the GI takes most of the ambient light's place (added to the lit image).
    let ambient = if settings.deferred { 300.0 } else { 2000.0 };
    commands.insert_resource(GlobalAmbientLight { color: Color::WHITE, brightness: ambient, ..default() });
    let camera = (
        Camera3d::default(),
        settings.target.clone().map_or_else(RenderTarget::default, RenderTarget::from),
        Tonemapping::Reinhard,
        Transform::from_xyz(2.5, 2.2, 3.5).looking_at(Vec3::new(0.3, 0.3, 0.0), Vec3::Y),
    );
    if settings.plain {
        commands.spawn((camera, Msaa::Off, bevy::core_pipeline::prepass::MotionVectorPrepass));
    } else if settings.ssao {
        commands.spawn((camera, bevy::pbr::ScreenSpaceAmbientOcclusion::default(), Msaa::Off));
    } else {
        // Motion vectors let the AO denoiser follow moving objects (without them it reprojects
        // with the cameras).
        let mut camera =
            commands.spawn((camera, RayTracedAo::default(), Msaa::Off, bevy::core_pipeline::prepass::MotionVectorPrepass));
        if let Some(shadow) = &settings.shadow {
            camera.insert(RayTracedShadow { output: shadow.clone(), ..default() });
        }
        if let Some(gi) = &settings.gi {
            camera.insert(RayTracedGi { output: gi.clone(), ..default() });
        }
        if let Some(reflections) = &settings.reflections {
            camera.insert(RayTracedReflections { output: reflections.clone(), ..default() });
        }
        if settings.deferred {
            // HDR: the sun's shadow is taken out of the lit image before tonemapping.
            camera.insert((bevy::core_pipeline::prepass::DeferredPrepass, bevy::camera::Hdr));
        }
    }
}
