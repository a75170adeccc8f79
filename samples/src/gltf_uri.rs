//! The bytes a glTF file's URIs name, for its buffers (`gltf_scene`) and its images
//! (`gltf_textures`).
use base64::Engine;
use std::path::Path;

/// The bytes a buffer's or an image's URI names: a base64 data URI, or a file beside the glTF.
pub(crate) fn read_uri(uri: &str, dir: &Path) -> Result<Vec<u8>, String> {
    if uri.starts_with("data:") {
        let (_, payload) = uri
            .split_once(";base64,")
            .ok_or_else(|| format!("unsupported data URI {}", uri.chars().take(40).collect::<String>()))?;
        return base64::engine::general_purpose::STANDARD.decode(payload).map_err(|e| format!("data URI: {e}"));
    }
    // A relative reference: percent-escapes decoded (bytes, so any escaped UTF-8 name).
    let decoded = percent_encoding::percent_decode_str(uri)
        .decode_utf8()
        .map_err(|_| format!("the URI {uri} escapes bytes that are not UTF-8"))?;
    let path = dir.join(decoded.as_ref());
    std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))
}
