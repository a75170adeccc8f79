//! Writing results: EXR (linear float, for inspection in any HDR viewer) and an 8-bit PNG
//! preview (the view pass's tone-mapped, sRGB-encoded copy); reading EXRs back for tests.
use std::path::{Path, PathBuf};

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

/// Writes one captured mode as `dir/name.exr` (linear) and `dir/name.png` (display); returns
/// the path without extension.
pub fn write_capture(
    dir: &Path,
    name: &str,
    width: u32,
    height: u32,
    linear: &[[f32; 4]],
    display: &[u8],
) -> Result<PathBuf, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let base = dir.join(name);
    write_exr_rgba(&base.with_extension("exr"), width, height, linear)?;
    write_png_rgba8(&base.with_extension("png"), width, height, display)?;
    Ok(base)
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
