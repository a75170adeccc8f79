//! `quality`: the denoisers' image quality on small scenes built here, against converged
//! references (the SDK's own trace at 256 rays per pixel), printed as docs/benchmarks.md's
//! quality table, with noisy | denoised | reference strips as PNGs.
//!
//! Usage: `quality [--out DIR]` (default target/quality; `--help`). Runs anywhere the tests run (lavapipe
//! included: about two minutes on two cores). Measures, per signal: relative RMSE of one raw
//! frame and of the denoised image after 1, 8 and 32 frames, bias (mean ratio - 1), flicker
//! (mean frame-to-frame change after 32 frames), penumbra-only error; a camera pan; thin
//! features; a moving object's residual k frames after it moved; an object sliding over a
//! floor; GI after a light switch. `--only SECTION` runs one of them. `--only sample-motion`
//! (not part of the default run: 64 rays per pixel at 640x360 is minutes on a CPU) renders the
//! sample room along its camera path at 1 and 64 rays per pixel and compares each signal's
//! last frame (`--sample-width`, `--sample-height`, `--sample-frames`).
mod sample_motion;

use glam::{Affine3A, Vec3};
use hybrid_rt::{DenoiserSettings, LightInfo};
use hybrid_rt_samples::images::write_png_rgba8;
use hybrid_rt_testkit::quality::*;
use hybrid_rt_testkit::reference::{self, Camera, Mesh, Scene};
use std::path::{Path, PathBuf};

const SIZE: u32 = 96;
const CHECKPOINTS: [u32; 3] = [1, 8, 32];
/// Converged references: this many frames of 64 rays per pixel.
const CONVERGED_FRAMES: u32 = 4;

/// The denoisers' image quality on small scenes against converged references (tables as
/// markdown on stdout, noisy | denoised | reference pictures as PNG).
#[derive(clap::Parser, Debug)]
#[command(name = "quality", version)]
struct Cli {
    /// Directory for the pictures.
    #[arg(long, default_value = "target/quality")]
    out: PathBuf,
    /// Measure one section only (default: all of them).
    #[arg(long, value_enum)]
    only: Option<Section>,
    /// The sample-motion section's image width.
    #[arg(long, default_value_t = 640)]
    sample_width: u32,
    /// The sample-motion section's image height.
    #[arg(long, default_value_t = 360)]
    sample_height: u32,
    /// The sample-motion section's frames along the camera path (at least 2).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(2..=1000))]
    sample_frames: u32,
}

/// The measurements, in the order they print.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Section {
    Static,
    Pan,
    Thin,
    Moving,
    Sliding,
    Switch,
    /// The sample room in motion at 1 and 64 rays per pixel (only when asked for).
    SampleMotion,
}

fn main() {
    let cli = <Cli as clap::Parser>::parse();
    let out = cli.out;
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("{}: {e}", out.display());
        std::process::exit(1);
    }
    let run = |s: Section| cli.only.is_none_or(|o| o == s);
    if run(Section::Static) {
        static_views(&out);
    }
    if run(Section::Pan) {
        camera_pan();
    }
    if run(Section::Thin) {
        thin_features();
    }
    if run(Section::Moving) {
        moving_objects();
    }
    if run(Section::Sliding) {
        sliding_object();
    }
    if run(Section::Switch) {
        light_switch();
    }
    if cli.only == Some(Section::SampleMotion) {
        if let Err(e) = sample_motion::sample_in_motion(&out, cli.sample_width, cli.sample_height, cli.sample_frames) {
            eprintln!("sample in motion: {e}");
            std::process::exit(1);
        }
    }
    println!("\nimages: {}", out.display());
}

fn sun(angular_extent: f32) -> LightInfo {
    LightInfo { direction: Vec3::new(-0.5, -1.0, -0.3), angular_extent, ..Default::default() }
}

/// One static view: its picture's file name, what is traced, the scene with its instances'
/// cache colours (None: black), the camera.
struct View<'a> {
    file: &'static str,
    signal: Signal,
    scene: &'a Scene,
    colours: Option<&'a [[f32; 3]]>,
    camera: Camera,
}

/// Static views: AO, GI and glossy reflections in the coloured room; a soft and a sharp sun's
/// shadow of a sphere.
fn static_views(out: &Path) {
    println!("## Static views ({SIZE}x{SIZE}, 1 ray per pixel, reference 256 rays per pixel)\n");
    println!("| signal | raw frame | denoised, 1 frame | 8 frames | 32 frames | bias (32) | flicker (32) |");
    println!("|---|---|---|---|---|---|---|");
    let sky = [0.1, 0.2, 0.3];
    let (room, colours, room_camera) = reference::coloured_room(true);
    let (sphere, sphere_camera) = reference::sphere_on_plane();
    let (lit_room, no_colours) = (Some(colours.as_slice()), None);
    let cases = [
        View { file: "ao", signal: Signal::Ao, scene: &room, colours: no_colours, camera: room_camera },
        View { file: "diffuse", signal: Signal::Diffuse { sky }, scene: &room, colours: lit_room, camera: room_camera },
        View {
            file: "glossy",
            signal: Signal::Specular { sky, roughness: 0.5 },
            scene: &room,
            colours: lit_room,
            camera: room_camera,
        },
        View {
            file: "soft_shadow",
            signal: Signal::Shadow(sun(0.2)),
            scene: &sphere,
            colours: no_colours,
            camera: sphere_camera,
        },
        View {
            file: "sun_shadow",
            signal: Signal::Shadow(sun(0.03)),
            scene: &sphere,
            colours: no_colours,
            camera: sphere_camera,
        },
    ];
    let mut penumbrae = Vec::new();
    for View { file, signal, scene, colours, camera } in cases {
        let mut st = Stage::new(scene, colours, camera, SIZE, signal.signal_type(), SEEDS[0]);
        let c = convergence(&mut st, signal, &CHECKPOINTS, CONVERGED_FRAMES, None);
        let label = match signal {
            Signal::Shadow(l) => format!("shadow, {} rad sun", l.angular_extent),
            _ => signal.name().to_string(),
        };
        println!(
            "| {label} | {:.3} | {:.3} | {:.3} | {:.3} | {:+.2}% | {:.2}% |",
            c.raw[0],
            c.denoised[0],
            c.denoised[1],
            c.denoised[2],
            c.bias * 100.0,
            c.flicker * 100.0
        );
        if let Signal::Shadow(_) = signal {
            penumbrae.push((label, c.raw_penumbra.clone(), c.denoised_penumbra.clone()));
        }
        write_strip(&out.join(format!("{file}.png")), &c.images, matches!(signal, Signal::Diffuse { .. }));
        st.finish();
    }
    println!("\nPenumbra only (0.02 < reference < 0.98):\n");
    println!("| signal | raw frame | denoised, 1 frame | 8 frames | 32 frames |");
    println!("|---|---|---|---|---|");
    for (label, raw, den) in penumbrae {
        println!("| {label} | {:.3} | {:.3} | {:.3} | {:.3} |", raw[0], den[0], den[1], den[2]);
    }
}

/// AO in the room while the camera pans sideways 1 cm a frame (the denoiser reprojects with
/// the previous camera): the error after 32 frames against the reference at the last camera.
fn camera_pan() {
    let (room, _, camera) = reference::coloured_room(true);
    let at = |f: u32| Camera::look_at(camera.eye + Vec3::new(0.01 * f as f32, 0.0, 0.0), Vec3::new(0.01 * f as f32, 0.6, -1.0));
    let mut st = Stage::new(&room, None, at(0), SIZE, Signal::Ao.signal_type(), SEEDS[0]);
    for f in 1..=32 {
        st.move_camera(&room, at(f));
        Signal::Ao.frame(&mut st, 1, true);
    }
    let d = Signal::Ao.denoised(&st);
    let reference = Signal::Ao.converged(&mut st, CONVERGED_FRAMES);
    let pan = relative_rmse(&d, &reference, &st.g.hit);
    st.finish();
    println!("\n## Camera pan\n\nAO, camera moving 1 cm a frame sideways, after 32 frames: relative RMSE {pan:.3}");
}

/// Five poles 3 cm thick on a plane: AO on the poles' pixels after 32 frames.
fn thin_features() {
    let mut scene = Scene::default();
    let plane = scene.add_mesh(Mesh::grid(8.0, 8));
    let pole = scene.add_mesh(Mesh::cuboid(Vec3::new(0.015, 0.6, 0.015)));
    scene.add_instance(plane, Affine3A::IDENTITY);
    for k in 0..5 {
        scene.add_instance(pole, Affine3A::from_translation(Vec3::new(-0.6 + 0.3 * k as f32, 0.6, -0.2 * k as f32)));
    }
    let camera = Camera::look_at(Vec3::new(0.0, 1.0, 2.0), Vec3::new(0.0, 0.5, 0.0));
    let mut st = Stage::new(&scene, None, camera, SIZE, Signal::Ao.signal_type(), SEEDS[0]);
    let poles: Vec<bool> = st.g.hit.iter().zip(&st.g.instance).map(|(h, i)| *h && *i > 0).collect();
    let n = poles.iter().filter(|p| **p).count();
    let c = convergence(&mut st, Signal::Ao, &CHECKPOINTS, CONVERGED_FRAMES, Some(&poles));
    st.finish();
    println!(
        "\n## Thin features\n\nAO on 3 cm poles ({n} px): relative RMSE raw {:.3}, denoised {:.3} / {:.3} / {:.3} after 1 / 8 / 32 frames, bias {:+.2}%",
        c.raw[0],
        c.denoised[0],
        c.denoised[1],
        c.denoised[2],
        c.bias * 100.0
    );
}

/// A sphere moves away: the old contact AO and shadow left in the denoised image k frames
/// later (mean over four seeds).
fn moving_objects() {
    println!("\n## A moving object (share of the old occlusion, or the old reflection, kept; mean of 4 seeds)\n");
    println!("| signal | 1 frame after | 2 | 4 | 8 | 12 |");
    println!("|---|---|---|---|---|---|");
    let sun = LightInfo { direction: Vec3::new(0.4, -1.0, -0.3), angular_extent: 0.1, ..Default::default() };
    // The glossy floor's reflection of the sphere (unlit: black against the sky) moves away.
    let glossy = Signal::Specular { sky: [1.0; 3], roughness: 0.3 };
    for signal in [Signal::Ao, Signal::Shadow(sun), glossy] {
        let r = mean_over_seeds(|seed| moving_object_residual(signal, seed));
        let p = |k: usize| r[k - 1] * 100.0;
        println!("| {} | {:.0}% | {:.0}% | {:.0}% | {:.0}% | {:.0}% |", signal.name(), p(1), p(2), p(4), p(8), p(12));
    }
}

/// A 0.4 m cube sliding over the floor, 2.6 pixels a frame: the share of the change since k
/// frames ago that the denoised contact AO and shadow still miss, and the mean absolute error
/// over the pixels the last frame changed (mean of 4 seeds); AO also without its moving-object
/// restart (`moving_object_reach` 0).
fn sliding_object() {
    println!("\n## An object sliding over a floor (share of the change since k frames ago still missing; mean of 4 seeds)\n");
    println!("| signal | k = 1 | 2 | 4 | 8 | mean abs. error (k = 1 pixels) |");
    println!("|---|---|---|---|---|---|");
    let lags = [1, 2, 4, 8];
    let no_reach = DenoiserSettings { moving_object_reach: 0.0, ..Default::default() };
    for (signal, settings, name) in [
        (Signal::Ao, DenoiserSettings::default(), "AO"),
        (Signal::Ao, no_reach, "AO, moving_object_reach 0"),
        (Signal::Shadow(sun(0.1)), DenoiserSettings::default(), "shadow"),
    ] {
        let r = mean_over_seeds(|seed| sliding_object_residual(signal, seed, &lags, settings));
        let p = |i: usize| r[i] * 100.0;
        println!("| {name} | {:.0}% | {:.0}% | {:.0}% | {:.0}% | {:.3} |", p(0), p(1), p(2), p(3), r[4]);
    }
}

/// The sky brightens 5x: the share of the old GI left k frames later (mean over four seeds).
fn light_switch() {
    let r = mean_over_seeds(gi_switch_residual);
    let p = |k: usize| r[k - 1] * 100.0;
    println!(
        "\n## A light switched on\n\nDiffuse GI, old lighting kept 1 / 4 / 12 frames after the sky brightened 5x: {:.0}% / {:.0}% / {:.0}%",
        p(1),
        p(4),
        p(12)
    );
}

/// noisy | denoised | reference side by side, sRGB, each pixel drawn 2x2 (the images are
/// small); `expose` scales GI (dim in this room) up.
fn write_strip(path: &Path, images: &[Vec<[f32; 3]>; 3], expose: bool) {
    const ZOOM: usize = 2;
    let gain = if expose { 4.0 } else { 1.0 };
    let (w, out_w) = (SIZE as usize, SIZE as usize * ZOOM);
    let mut rgba = vec![0u8; 3 * out_w * out_w * 4];
    for (k, img) in images.iter().enumerate() {
        for y in 0..out_w {
            for x in 0..out_w {
                let t = img[(y / ZOOM) * w + x / ZOOM];
                let o = (y * 3 * out_w + k * out_w + x) * 4;
                for c in 0..3 {
                    let v = (t[c] * gain).clamp(0.0, 1.0);
                    let s = if v <= 0.0031308 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
                    rgba[o + c] = (s * 255.0 + 0.5) as u8;
                }
                rgba[o + 3] = 255;
            }
        }
    }
    if let Err(e) = write_png_rgba8(path, (3 * out_w) as u32, out_w as u32, &rgba) {
        eprintln!("{e}");
    }
}
