//! The textures of a glTF file's materials: PNG and JPEG images (in a buffer view, a data URI
//! or a file beside it) decoded to RGBA8, each decoded once per colour space it is sampled in
//! (a base-colour or emissive texture is sRGB, a metallic-roughness or normal map linear).
//! Other formats (KTX2, WebP) draw the material's factor alone, with a warning. Only the first
//! texture coordinate set is read; a texture on another set is drawn as if it were on it.
use crate::gltf_uri::read_uri;
use crate::raster::Texture;
use std::collections::HashMap;
use std::path::Path;

/// The scene's textures so far, and which glTF image (in which colour space) became which.
#[derive(Default)]
pub struct TextureCache {
    pub textures: Vec<Texture>,
    /// (glTF image, linear) -> our texture (None: a format that is not read).
    decoded: HashMap<(usize, bool), Option<usize>>,
}

impl TextureCache {
    /// Our texture for `texture`'s image, decoding it the first time. `name`: the file, for
    /// messages.
    pub fn get(
        &mut self,
        texture: gltf::Texture,
        linear: bool,
        data: &[Vec<u8>],
        dir: &Path,
        name: &str,
    ) -> Result<Option<usize>, String> {
        let image = texture.source();
        let key = (image.index(), linear);
        if let Some(&t) = self.decoded.get(&key) {
            return Ok(t);
        }
        let decoded = decode(&image, data, dir, linear).map_err(|e| format!("{name}: image {}: {e}", image.index()))?;
        if decoded.is_none() && !self.decoded.contains_key(&(image.index(), !linear)) {
            eprintln!("{name}: image {} is neither PNG nor JPEG: its materials use their factors alone", image.index());
        }
        let t = decoded.map(|tex| {
            self.textures.push(tex);
            self.textures.len() - 1
        });
        self.decoded.insert(key, t);
        Ok(t)
    }
}

fn decode(image: &gltf::Image, data: &[Vec<u8>], dir: &Path, linear: bool) -> Result<Option<Texture>, String> {
    let bytes: Vec<u8> = match image.source() {
        gltf::image::Source::View { view, .. } => {
            let buffer = data.get(view.buffer().index()).ok_or("its buffer is missing")?;
            let end =
                view.offset().checked_add(view.length()).filter(|&e| e <= buffer.len()).ok_or("its view is past its buffer")?;
            buffer[view.offset()..end].to_vec()
        }
        gltf::image::Source::Uri { uri, .. } => read_uri(uri, dir)?,
    };
    let texture = if bytes.starts_with(b"\x89PNG") {
        png_rgba(bytes)?
    } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        jpeg_rgba(&bytes)?
    } else {
        return Ok(None);
    };
    Ok(Some(Texture { linear, ..texture }))
}

fn png_rgba(bytes: Vec<u8>) -> Result<Texture, String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // Palettes and low bit depths expanded, 16-bit channels cut to 8: RGB(A) or grey(+alpha).
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| format!("PNG: {e}"))?;
    let mut texels = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut texels).map_err(|e| format!("PNG: {e}"))?;
    let texels = &texels[..info.buffer_size()];
    let rgba: Vec<u8> = match info.color_type {
        png::ColorType::Rgba => texels.to_vec(),
        png::ColorType::Rgb => texels.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2], 255]).collect(),
        png::ColorType::GrayscaleAlpha => texels.chunks_exact(2).flat_map(|c| [c[0], c[0], c[0], c[1]]).collect(),
        png::ColorType::Grayscale => texels.iter().flat_map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::Indexed => return Err("PNG: a palette left unexpanded".into()),
    };
    Ok(Texture { width: info.width, height: info.height, rgba, linear: false })
}

fn jpeg_rgba(bytes: &[u8]) -> Result<Texture, String> {
    use zune_jpeg::zune_core::{colorspace::ColorSpace, options::DecoderOptions};
    // Grey, YCbCr and CMYK files all come out as RGBA.
    let options = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGBA);
    let mut decoder = zune_jpeg::JpegDecoder::new_with_options(std::io::Cursor::new(bytes), options);
    let rgba = decoder.decode().map_err(|e| format!("JPEG: {e:?}"))?;
    let info = decoder.info().ok_or("JPEG: no header")?;
    let (width, height) = (info.width as u32, info.height as u32);
    if rgba.len() as u64 != width as u64 * height as u64 * 4 {
        return Err(format!("JPEG: {} bytes for {width}x{height} RGBA texels", rgba.len()));
    }
    Ok(Texture { width, height, rgba, linear: false })
}
