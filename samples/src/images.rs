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
