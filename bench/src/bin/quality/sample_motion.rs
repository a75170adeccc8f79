//! The sample in motion: the picture a new user sees first (the sample room along its camera
//! path), rendered twice — at 1 ray per pixel and at 64 — and each signal's last frame
//! compared with the 64-ray trace of that frame: the raw 1-ray trace's error, the denoised
//! output's error and bias, and the 64-ray run's own denoised error (what denoised GI is held
//! to). Static views hide what motion shows: history that trails, reprojection that darkens.
use hybrid_rt_host::Host;
use hybrid_rt_samples::images::write_png_rgba8;
use hybrid_rt_samples::modes::Mode;
use hybrid_rt_samples::renderer::{Renderer, Settings};
use hybrid_rt_samples::scenes;
use std::path::Path;

/// The rays per pixel of the reference run.
const REFERENCE_RAYS: u32 = 64;

/// Each signal's modes: (name, raw trace, denoised output).
const SIGNALS: [(&str, Mode, Mode); 5] = [
    ("sun shadow", Mode::SunShadowNoisy, Mode::SunShadow),
    ("point-light shadow", Mode::PointShadowNoisy, Mode::PointShadow),
    ("AO", Mode::AoNoisy, Mode::Ao),
    ("diffuse GI", Mode::DiffuseNoisy, Mode::Diffuse),
    ("reflections", Mode::SpecularNoisy, Mode::Specular),
];

/// One run's last frame: per signal (raw, denoised) as linear RGB and as the display's sRGB;
/// the surface mask; per signal, a second raw trace of the same view (see `render`).
struct Run {
    linear: Vec<[Vec<[f32; 4]>; 2]>,
    display: Vec<[Vec<u8>; 2]>,
    surface: Vec<bool>,
    retrace: Vec<Vec<[f32; 4]>>,
}

/// Renders `frames` frames along the camera path and captures the last. With `retrace`, then
/// renders the last view once more (same camera, same time: only the rays' sequence moves on)
/// and keeps its raw traces: two traces of one view tell the trace's own noise.
fn render(host: &Host, rays: u32, width: u32, height: u32, frames: u32, retrace: bool) -> Result<Run, String> {
    let settings = Settings { width, height, rays_per_pixel: rays, ..Default::default() };
    let mut r = Renderer::new(host, scenes::cornell_room(), settings)?;
    for f in 0..frames {
        let camera = r.scene.camera_path.at(f as f32 / (frames - 1) as f32);
        r.render(camera, f as f32 / 30.0, &[], None)?;
    }
    r.finish()?;
    let mut run = Run { linear: Vec::new(), display: Vec::new(), surface: Vec::new(), retrace: Vec::new() };
    for (_, raw, denoised) in SIGNALS {
        let (raw_linear, raw_display) = r.capture(raw)?;
        let (den_linear, den_display) = r.capture(denoised)?;
        run.linear.push([raw_linear, den_linear]);
        run.display.push([raw_display, den_display]);
    }
    // Surfaces: the normals mode maps a unit normal n to 0.5 n + 0.5, the sky's zero to 0.5.
    let (normals, _) = r.capture(Mode::Normals)?;
    run.surface = normals.iter().map(|t| (0..3).map(|c| (2.0 * t[c] - 1.0).powi(2)).sum::<f32>() > 0.25).collect();
    if retrace {
        let camera = r.scene.camera_path.at(1.0);
        r.render(camera, (frames - 1) as f32 / 30.0, &[], None)?;
        r.finish()?;
        for (_, raw, _) in SIGNALS {
            run.retrace.push(r.capture(raw)?.0);
        }
    }
    r.destroy()?;
    Ok(run)
}

/// Mean of the RGB channels (the shadow and AO modes are grey).
fn grey(v: &[[f32; 4]]) -> Vec<f32> {
    v.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect()
}

/// Renders both runs and prints the table; writes raw | denoised | 64-ray strips to `out`.
pub fn sample_in_motion(out: &Path, width: u32, height: u32, frames: u32) -> Result<(), String> {
    let host = Host::new()?;
    println!(
        "\n## The sample in motion (the room, {width}x{height}, {frames} frames along its camera path; reference: the last frame traced at {REFERENCE_RAYS} rays per pixel)\n"
    );
    let one = render(&host, 1, width, height, frames, false)?;
    let many = render(&host, REFERENCE_RAYS, width, height, frames, true)?;
    println!(
        "| signal | raw frame | denoised | gain (raw / denoised) | bias | the {REFERENCE_RAYS}-ray run denoised (bias) | the reference's own noise |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (k, (name, _, _)) in SIGNALS.iter().enumerate() {
        let reference = grey(&many.linear[k][0]);
        let (raw, denoised, denoised_many) = (grey(&one.linear[k][0]), grey(&one.linear[k][1]), grey(&many.linear[k][1]));
        let mask = &one.surface;
        let e_raw = hybrid_rt_testkit::stats::relative_rmse(&raw, &reference, mask);
        let e_den = hybrid_rt_testkit::stats::relative_rmse(&denoised, &reference, mask);
        let e_many = hybrid_rt_testkit::stats::relative_rmse(&denoised_many, &reference, mask);
        // Two independent traces differ by sqrt(2) times either's noise. Every error above
        // holds the reference's noise too (in quadrature where the output is independent of
        // it, as the 1-ray run's is).
        let e_ref = hybrid_rt_testkit::stats::relative_rmse(&grey(&many.retrace[k]), &reference, mask) / std::f32::consts::SQRT_2;
        let sum = |v: &[f32]| v.iter().zip(mask).filter(|(_, m)| **m).map(|(x, _)| *x as f64).sum::<f64>();
        let bias = |v: &[f32]| (sum(v) / sum(&reference).max(1e-12) - 1.0) * 100.0;
        // The 64-ray run's bias tells the denoiser's own (history, reprojection) from what it
        // does to 1-ray noise (edge stops, firefly cuts, anti-lag decisions).
        println!(
            "| {name} | {e_raw:.3} | {e_den:.3} | {:.1}x | {:+.1}% | {e_many:.3} ({:+.1}%) | {e_ref:.3} |",
            e_raw / e_den.max(1e-9),
            bias(&denoised),
            bias(&denoised_many)
        );
        let strip = [&one.display[k][0], &one.display[k][1], &many.display[k][0]];
        let file = out.join(format!("sample_motion_{}.png", name.replace([' ', '-'], "_").to_lowercase()));
        write_strip(&file, width, height, strip)?;
    }
    Ok(())
}

/// Three RGBA8 images of `width` x `height` side by side.
fn write_strip(path: &Path, width: u32, height: u32, images: [&Vec<u8>; 3]) -> Result<(), String> {
    let (w, h) = (width as usize, height as usize);
    let mut rgba = vec![0u8; 3 * w * h * 4];
    for (k, img) in images.iter().enumerate() {
        for y in 0..h {
            let src = &img[y * w * 4..(y + 1) * w * 4];
            let o = (y * 3 * w + k * w) * 4;
            rgba[o..o + w * 4].copy_from_slice(src);
        }
    }
    write_png_rgba8(path, 3 * width, height, &rgba)
}
