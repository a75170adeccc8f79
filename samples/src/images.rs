//! Writing results: EXR (linear float, for inspection in any HDR viewer) and an 8-bit PNG
//! preview (sRGB-encoded).
use std::path::Path;

/// Writes a single-channel float image as a grey RGB EXR.
pub fn write_exr_gray(path: &Path, width: u32, height: u32, values: &[f32]) -> Result<(), String> {
    exr::prelude::write_rgb_file(path, width as usize, height as usize, |x, y| {
        let v = values[y * width as usize + x];
        (v, v, v)
    })
    .map_err(|e| format!("{}: {e}", path.display()))
}

fn srgb(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.0031308 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Writes a single-channel float image as an sRGB 8-bit grey PNG.
pub fn write_png_gray(path: &Path, width: u32, height: u32, values: &[f32]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    let bytes: Vec<u8> = values.iter().map(|v| srgb(*v)).collect();
    w.write_image_data(&bytes).map_err(|e| e.to_string())
}

/// Writes RGBA float texels as an sRGB 8-bit RGB PNG (values scaled by `scale` first).
pub fn write_png_rgb(path: &Path, width: u32, height: u32, texels: &[[f32; 4]], scale: f32) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    let bytes: Vec<u8> = texels.iter().flat_map(|t| [srgb(t[0] * scale), srgb(t[1] * scale), srgb(t[2] * scale)]).collect();
    w.write_image_data(&bytes).map_err(|e| e.to_string())
}

/// Writes linear RGBA float texels as an RGBA EXR.
pub fn write_exr_rgba(path: &Path, width: u32, height: u32, texels: &[[f32; 4]]) -> Result<(), String> {
    exr::prelude::write_rgba_file(path, width as usize, height as usize, |x, y| {
        let t = texels[y * width as usize + x];
        (t[0], t[1], t[2], t[3])
    })
    .map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes RGBA8 texels (already sRGB-encoded) as an RGB PNG.
pub fn write_png_rgba8(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    let rgb: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    w.write_image_data(&rgb).map_err(|e| e.to_string())
}

/// Reads an RGBA EXR written by `write_exr_rgba` (tests check the sample's output with it).
pub fn read_exr_rgba(path: &Path) -> Result<(u32, u32, Vec<[f32; 4]>), String> {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| (resolution.width(), vec![[0f32; 4]; resolution.width() * resolution.height()]),
        |(width, texels), pos, (r, g, b, a): (f32, f32, f32, f32)| texels[pos.y() * *width + pos.x()] = [r, g, b, a],
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    let size = image.layer_data.size;
    Ok((size.width() as u32, size.height() as u32, image.layer_data.channel_data.pixels.1))
}
