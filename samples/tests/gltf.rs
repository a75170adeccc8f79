//! The glTF loader on hand-made files: strips and fans load; broken files (a node cycle, an
//! index past the vertices, a missing buffer, a required extension it lacks, nothing but
//! points) give one short error that names the file and what is wrong, never a hang or panic.
use base64::Engine;
mod support;
use hybrid_rt_samples::gltf_scene;
use std::path::PathBuf;
use support::written;

/// One quad's four corners, and a primitive over them.
struct File {
    mode: u32,
    indices: Vec<u16>,
    nodes: &'static str,
    buffer_uri: Option<&'static str>,
    required: &'static [&'static str],
    /// The default scene's root nodes, and more top-level properties (cameras).
    roots: &'static str,
    extra: &'static str,
}

impl Default for File {
    fn default() -> File {
        File {
            mode: 4,
            indices: vec![0, 1, 2, 2, 1, 3],
            nodes: r#"[{"mesh": 0}]"#,
            buffer_uri: None,
            required: &[],
            roots: "[0]",
            extra: "",
        }
    }
}

impl File {
    /// The buffer: the four corners, then the indices.
    fn bytes(&self) -> Vec<u8> {
        let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let mut bytes: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        bytes.extend(self.indices.iter().flat_map(|i| i.to_le_bytes()));
        while bytes.len() & 3 != 0 {
            bytes.push(0);
        }
        bytes
    }

    /// Writes `name` in the test directory; returns its path.
    fn write(&self, name: &str) -> PathBuf {
        let bytes = self.bytes();
        let uri = match self.buffer_uri {
            Some(u) => u.to_string(),
            None => format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bytes)),
        };
        let ext: Vec<String> = self.required.iter().map(|e| format!("\"{e}\"")).collect();
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": {roots}}}], "nodes": {nodes}, {extra}
  "extensionsUsed": [{ext}], "extensionsRequired": [{ext}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "mode": {mode}}}]}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": {count}, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": {ilen}}}],
  "buffers": [{{"byteLength": {blen}, "uri": "{uri}"}}]}}"#,
            nodes = self.nodes,
            roots = self.roots,
            extra = self.extra,
            ext = ext.join(", "),
            mode = self.mode,
            count = self.indices.len(),
            ilen = 2 * self.indices.len(),
            blen = bytes.len(),
        );
        written(name, &json)
    }
}

fn triangles(file: &File, name: &str) -> Vec<u32> {
    let scene = gltf_scene::load(&file.write(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(scene.scene.meshes.len(), 1);
    scene.scene.meshes[0].indices.clone()
}

#[test]
fn strips_and_fans_load_as_triangle_lists() {
    // The quad as a list, a strip (0 1 2 3) and a fan (0 1 3 2): two triangles of the same
    // winding each (a strip's second triangle is flipped back).
    assert_eq!(triangles(&File::default(), "list.gltf"), [0, 1, 2, 2, 1, 3]);
    assert_eq!(triangles(&File { mode: 5, indices: vec![0, 1, 2, 3], ..Default::default() }, "strip.gltf"), [0, 1, 2, 2, 1, 3]);
    assert_eq!(triangles(&File { mode: 6, indices: vec![0, 1, 3, 2], ..Default::default() }, "fan.gltf"), [0, 1, 3, 0, 3, 2]);
}

/// The error for `file`: it names the file and holds every one of `needles`, in a line or two.
fn refused(file: &File, name: &str, needles: &[&str]) {
    let path = file.write(name);
    let err = match gltf_scene::load(&path) {
        Ok(_) => panic!("{name} loaded"),
        Err(e) => e,
    };
    assert!(err.contains(name), "{name}: the error does not name the file: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: {n:?} missing from: {err}");
    }
    assert!(err.len() < 400, "{name}: a {}-byte error: {err}", err.len());
}

#[test]
fn broken_files_are_refused_with_errors_that_say_why() {
    refused(
        &File { nodes: r#"[{"mesh": 0, "children": [1]}, {"children": [0]}]"#, ..Default::default() },
        "cycle.gltf",
        &["node"],
    );
    refused(
        &File { indices: vec![0, 1, 7], ..Default::default() },
        "index.gltf",
        &["mesh 0 primitive 0", "index 7", "4 vertices"],
    );
    refused(&File { buffer_uri: Some("missing.bin"), ..Default::default() }, "buffer.gltf", &["missing.bin"]);
    refused(
        &File { required: &["KHR_draco_mesh_compression"], ..Default::default() },
        "draco.gltf",
        &["KHR_draco_mesh_compression", "does not support"],
    );
    refused(&File { mode: 0, ..Default::default() }, "points.gltf", &["no triangles", "1 primitives of points or lines"]);
}

/// The fitted camera frames the model with a margin from anywhere on its path: every corner of
/// the quad projects inside the image, none closer than 5% of the half-width to its edge
/// (the old path, 1.2 bounding radii away, filled the frame with a compact model's face).
#[test]
fn the_fitted_camera_frames_the_model() {
    let scene = gltf_scene::load(&File::default().write("framed.gltf")).unwrap();
    for u in [0.0, 0.5, 1.0] {
        let camera = scene.camera_path.at(u);
        let clip = camera.view_to_clip(16.0 / 9.0) * camera.world_to_view();
        for p in &scene.scene.meshes[0].positions {
            let c = clip * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            assert!(ndc.x.abs() < 0.95 && ndc.y.abs() < 0.95, "u = {u}: corner {p} at {ndc}");
        }
    }
}

/// A file's perspective camera becomes a still camera path that `--camera 0` picks: at the
/// node's translation, looking down its -Z, with its vertical field of view.
#[test]
fn file_cameras_are_read() {
    let file = File {
        nodes: r#"[{"mesh": 0}, {"camera": 0, "translation": [0.5, 0.5, 3.0]}]"#,
        roots: "[0, 1]",
        extra: r#""cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],"#,
        ..Default::default()
    };
    let scene = gltf_scene::load(&file.write("camera.gltf")).unwrap();
    assert_eq!(scene.file_cameras.len(), 1);
    let c = scene.file_cameras[0];
    assert!((c.from - glam::Vec3::new(0.5, 0.5, 3.0)).length() < 1e-5 && c.from == c.to, "{c:?}");
    assert!((c.target - c.from).normalize().dot(glam::Vec3::NEG_Z) > 0.9999 && (c.fov_y_radians - 0.8).abs() < 1e-6, "{c:?}");
}

/// A quad with texture coordinates and a 2x2 PNG base-colour texture (red, green / blue,
/// white), embedded as data URIs.
fn write_textured_quad(name: &str) -> PathBuf {
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, 2, 2);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255]).unwrap();
    }
    let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [0.0, 0.0], [1.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 2, 1, 3];
    let mut bytes: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(uvs.iter().flatten().flat_map(|v| v.to_le_bytes()));
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "indices": 2, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "roughnessFactor": 0.8, "metallicFactor": 0.0}}}}],
  "textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{png}"}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 12}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        png = b64(&png_bytes),
        len = bytes.len(),
        data = b64(&bytes),
    );
    written(name, &json)
}

/// The loader reads texture coordinates and the PNG base-colour texture, texel for texel.
#[test]
fn base_colour_textures_are_read() {
    let scene = gltf_scene::load(&write_textured_quad("textured.gltf")).unwrap();
    assert_eq!(scene.uvs[0], [[0.0, 1.0], [1.0, 1.0], [0.0, 0.0], [1.0, 0.0]]);
    assert_eq!(scene.material_textures.len(), 1);
    assert_eq!(scene.material_textures[0].base_color, Some(0));
    let t = &scene.textures[0];
    assert_eq!((t.width, t.height), (2, 2));
    assert_eq!(t.rgba, [255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255]);
}

/// Rendered, the texture is in the G-buffer's albedo: red, green and blue corners.
#[test]
fn a_textured_gltf_renders_its_texture() {
    let file = write_textured_quad("textured-render.gltf");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("sample-textured");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_sample"))
        .args([
            "--headless",
            file.to_str().unwrap(),
            "--width",
            "48",
            "--height",
            "32",
            "--frames",
            "2",
            "--modes",
            "albedo",
            "--out",
        ])
        .arg(&out)
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&run.stdout).to_string() + &String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{text}");
    let (_, _, albedo) = hybrid_rt_samples::images::read_exr_rgba(&out.join("albedo.exr")).unwrap();
    let count = |f: &dyn Fn(&[f32; 4]) -> bool| albedo.iter().filter(|t| f(t)).count();
    let (red, green, blue) = (
        count(&|t| t[0] > 0.6 && t[1] < 0.25 && t[2] < 0.25),
        count(&|t| t[1] > 0.6 && t[0] < 0.25 && t[2] < 0.25),
        count(&|t| t[2] > 0.6 && t[0] < 0.25 && t[1] < 0.25),
    );
    assert!(red > 5 && green > 5 && blue > 5, "texture colours in the albedo: red {red}, green {green}, blue {blue}");
}

/// PNG bytes of a `w`x`h` RGB image of one colour.
fn png_of(w: u32, h: u32, rgb: [u8; 3]) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let texels: Vec<u8> = (0..w * h).flat_map(|_| rgb).collect();
    enc.write_header().unwrap().write_image_data(&texels).unwrap();
    bytes
}

/// JPEG bytes (quality 100) of an 8x8 RGB image of one colour.
fn jpeg_of(rgb: [u8; 3]) -> Vec<u8> {
    let mut bytes = Vec::new();
    let texels: Vec<u8> = (0..64).flat_map(|_| rgb).collect();
    jpeg_encoder::Encoder::new(&mut bytes, 100).encode(&texels, 8, 8, jpeg_encoder::ColorType::Rgb).unwrap();
    bytes
}

/// The normal map's one texel: the tangent-space normal (0.6, 0.48, 0.64), tilted towards +U
/// and glTF's up (-V).
const NORMAL_TEXEL: [u8; 3] = [204, 189, 209];

/// A unit quad in the XY plane facing +Z (U along +X, V down along -Y, glTF's convention)
/// with every texture of the metallic-roughness material: a PNG base colour, a JPEG
/// metallic-roughness (roughness 128/255, metalness 1), a PNG normal map tilting the normal
/// towards +X and +Y, a JPEG emissive (1, 0.5, 0 in sRGB) at KHR_materials_emissive_strength 4 (a
/// required extension), with or without TANGENT vertices; and a camera rolled 90 degrees.
fn write_material_quad(name: &str, tangents: bool) -> PathBuf {
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [0.0, 0.0], [1.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 2, 1, 3];
    let mut bytes: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(uvs.iter().flatten().flat_map(|v| v.to_le_bytes()));
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    bytes.extend([0u8; 4]);
    bytes.extend([[1.0f32, 0.0, 0.0, 1.0]; 4].iter().flatten().flat_map(|v| v.to_le_bytes()));
    let tangent_attribute = if tangents { r#", "TANGENT": 3"# } else { "" };
    let png = |rgb| format!("data:image/png;base64,{}", b64(&png_of(1, 1, rgb)));
    let jpeg = |rgb| format!("data:image/jpeg;base64,{}", b64(&jpeg_of(rgb)));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1]}}],
  "extensionsUsed": ["KHR_materials_emissive_strength"], "extensionsRequired": ["KHR_materials_emissive_strength"],
  "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0.5, 0.5, 3.0], "rotation": [0.0, 0.0, 0.7071068, 0.7071068]}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1{tangent_attribute}}}, "indices": 2, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicRoughnessTexture": {{"index": 1}},
      "roughnessFactor": 0.8, "metallicFactor": 1.0}},
    "normalTexture": {{"index": 2, "scale": 1.0}}, "emissiveTexture": {{"index": 3}}, "emissiveFactor": [1.0, 1.0, 1.0],
    "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": 4.0}}}}}}],
  "textures": [{{"source": 0}}, {{"source": 1}}, {{"source": 2}}, {{"source": 3}}],
  "images": [{{"uri": "{base}"}}, {{"uri": "{mr}"}}, {{"uri": "{normal}"}}, {{"uri": "{emissive}"}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}},
    {{"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC4"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 12}}, {{"buffer": 0, "byteOffset": 96, "byteLength": 64}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        base = png([200, 100, 50]),
        mr = jpeg([0, 128, 255]),
        normal = png(NORMAL_TEXEL),
        emissive = jpeg([255, 128, 0]),
        len = bytes.len(),
        data = b64(&bytes),
    );
    written(name, &json)
}

/// Every texture of the material is read, colour textures as sRGB and data textures as
/// linear, JPEG as well as PNG; the emissive strength scales the factor; the file's tangents
/// are kept; the camera keeps its roll.
#[test]
fn material_textures_tangents_and_camera_roll_are_read() {
    let scene = gltf_scene::load(&write_material_quad("material.gltf", true)).unwrap();
    let t = scene.material_textures[0];
    let (base, mr, normal, emissive) =
        (t.base_color.unwrap(), t.metallic_roughness.unwrap(), t.normal.unwrap(), t.emissive.unwrap());
    let linear: Vec<bool> = [base, mr, normal, emissive].iter().map(|&k| scene.textures[k].linear).collect();
    assert_eq!(linear, [false, true, true, false]);
    assert_eq!(scene.textures[normal].rgba, [NORMAL_TEXEL[0], NORMAL_TEXEL[1], NORMAL_TEXEL[2], 255]);
    // JPEG at quality 100: within two levels of what was written.
    let close = |k: usize, rgb: [u8; 3]| scene.textures[k].rgba.chunks(4).all(|c| (0..3).all(|i| c[i].abs_diff(rgb[i]) <= 2));
    assert!(close(mr, [0, 128, 255]) && close(emissive, [255, 128, 0]), "JPEG texels");
    assert_eq!((scene.textures[mr].width, scene.textures[mr].height), (8, 8));
    assert_eq!(scene.materials[0].emissive, [4.0; 3]);
    assert_eq!(scene.tangents[0], [glam::Vec4::new(1.0, 0.0, 0.0, 1.0); 4]);
    let up = scene.file_cameras[0].up;
    assert!((up - glam::Vec3::NEG_X).length() < 1e-5, "a camera rolled 90 degrees about its view: up {up}");
}

/// Renders `file` headless at 48x32 and returns each mode's EXR texels.
fn render_modes(file: &std::path::Path, out: &str, modes: &str) -> Vec<Vec<[f32; 4]>> {
    render_modes_sized(file, out, modes, 48, 32)
}

/// Renders `file` headless at `width` x `height` and returns each mode's EXR texels.
fn render_modes_sized(file: &std::path::Path, out: &str, modes: &str, width: u32, height: u32) -> Vec<Vec<[f32; 4]>> {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(out);
    let (width, height) = (width.to_string(), height.to_string());
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_sample"))
        .args(["--headless", file.to_str().unwrap(), "--width", &width, "--height", &height, "--frames", "2", "--modes", modes])
        .arg("--out")
        .arg(&out)
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&run.stdout).to_string() + &String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{text}");
    modes.split(',').map(|m| hybrid_rt_samples::images::read_exr_rgba(&out.join(format!("{m}.exr"))).unwrap().2).collect()
}

/// Rendered, every texture lands in the G-buffer and the lit image: the normal map tilts the
/// quad's normal to (0.6, 0.48, 0.64) whether the tangent frame comes from the file's tangents or
/// from screen derivatives; roughness is factor x texture; the metal has no diffuse, so its
/// direct light is its emission alone (4 x (1, sRGB 128, 0)).
#[test]
fn a_gltf_with_every_texture_renders_them() {
    let texel = NORMAL_TEXEL.map(|c| 2.0 * c as f32 / 255.0 - 1.0);
    let expected = glam::Vec3::from(texel).normalize();
    let srgb_128 = ((128.0f32 / 255.0 + 0.055) / 1.055).powf(2.4);
    for tangents in [true, false] {
        let file = write_material_quad(&format!("material-render-{tangents}.gltf"), tangents);
        let images = render_modes(&file, &format!("sample-material-{tangents}"), "normals,roughness,metalness,emissive,direct");
        let [normals, roughness, metalness, emissive, direct] = &images[..] else { unreachable!() };
        // Pixels on the quad: the ones that emit.
        let on: Vec<usize> = (0..emissive.len()).filter(|&i| emissive[i][0] > 1.0).collect();
        assert!(on.len() > 150, "{} of {} pixels see the quad", on.len(), emissive.len());
        for &i in &on {
            let n = glam::Vec3::new(normals[i][0], normals[i][1], normals[i][2]) * 2.0 - 1.0;
            assert!(n.normalize().dot(expected) > 0.999, "tangents {tangents}: normal {n} at {i}, expected {expected}");
            assert!((roughness[i][0] - 0.8 * 128.0 / 255.0).abs() < 0.01, "roughness {}", roughness[i][0]);
            assert!(metalness[i][0] > 0.99, "metalness {}", metalness[i][0]);
            let e = [4.0, 4.0 * srgb_128, 0.0];
            for c in 0..3 {
                // fp16 targets; JPEG within two levels (1.5% at 128).
                assert!((emissive[i][c] - e[c]).abs() < 0.02 * e[c] + 0.01, "emissive {:?} vs {e:?}", emissive[i]);
                assert!((direct[i][c] - e[c]).abs() < 0.03 * e[c] + 0.02, "direct {:?} vs emitted {e:?}", direct[i]);
            }
        }
    }
}

/// A 4x4 ground (grey) under a 2x2 quad at height 0.5 whose base-colour texture is 2x1 texels,
/// transparent on the left and opaque on the right, times a base-colour factor of alpha
/// `factor`, with material `quad_material` (JSON members beside its pbrMetallicRoughness).
fn write_cutout_scene(name: &str, factor: f32, quad_material: &str) -> PathBuf {
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let mut png_bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut png_bytes, 2, 1);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header().unwrap().write_image_data(&[255, 255, 255, 0, 255, 255, 255, 255]).unwrap();
    }
    let ground: [[f32; 3]; 4] = [[-2.0, 0.0, -2.0], [2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 2.0]];
    let quad: [[f32; 3]; 4] = [[-1.0, 0.5, -1.0], [1.0, 0.5, -1.0], [-1.0, 0.5, 1.0], [1.0, 0.5, 1.0]];
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    let indices: [u16; 6] = [0, 1, 2, 2, 1, 3];
    let mut bytes: Vec<u8> = ground.iter().chain(&quad).flatten().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(uvs.iter().flatten().flat_map(|v| v.to_le_bytes()));
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1]}}], "nodes": [{{"mesh": 0}}, {{"mesh": 1}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 3, "material": 0}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 1, "TEXCOORD_0": 2}}, "indices": 3, "material": 1}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}}}},
    {{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "baseColorFactor": [1, 1, 1, {factor}], "metallicFactor": 0}}{quad_material}}}],
  "textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{png}"}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-2, 0, -2], "max": [2, 0, 2]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0.5, -1], "max": [1, 0.5, 1]}},
    {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 32}}, {{"buffer": 0, "byteOffset": 128, "byteLength": 12}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        png = b64(&png_bytes),
        len = bytes.len(),
        data = b64(&bytes),
    );
    written(name, &json)
}

/// `alphaMode: MASK` cuts the mesh where texture alpha x factor alpha < `alphaCutoff` (the
/// cutoff the SDK and the raster pass compare the texture with is divided by the factor);
/// `BLEND` is drawn masked, with a warning; a factor below the cutoff hides the mesh.
#[test]
fn masked_materials_become_cutouts() {
    use hybrid_rt_samples::scene::Cutout;
    let mask = r#", "alphaMode": "MASK", "alphaCutoff": 0.3"#;
    let masked = gltf_scene::load(&write_cutout_scene("mask.gltf", 1.0, mask)).unwrap();
    // (Which of the two meshes is the quad is the loader's business.)
    let cut = |s: &hybrid_rt_samples::scene::SampleScene| s.cutouts.iter().flatten().copied().collect::<Vec<Cutout>>();
    assert_eq!(masked.cutouts.len(), 2);
    assert_eq!(cut(&masked), [Cutout { texture: 0, cutoff: 0.3 }]);
    assert!(masked.warnings.is_empty(), "{:?}", masked.warnings);
    let half = gltf_scene::load(&write_cutout_scene("mask-factor.gltf", 0.5, mask)).unwrap();
    assert_eq!(cut(&half), [Cutout { texture: 0, cutoff: 0.6 }]);
    let hidden = gltf_scene::load(&write_cutout_scene("mask-hidden.gltf", 0.2, mask)).unwrap();
    assert_eq!(hidden.scene.instances.len(), 1, "only the ground is drawn");
    assert!(hidden.warnings.iter().any(|w| w.contains("not drawn")), "{:?}", hidden.warnings);
    let blend = gltf_scene::load(&write_cutout_scene("blend.gltf", 1.0, r#", "alphaMode": "BLEND""#)).unwrap();
    assert_eq!(cut(&blend), [Cutout { texture: 0, cutoff: 0.5 }]);
    assert!(blend.warnings.iter().any(|w| w.contains("BLEND")), "{:?}", blend.warnings);
    let opaque = gltf_scene::load(&write_cutout_scene("opaque.gltf", 1.0, "")).unwrap();
    assert_eq!(opaque.cutouts, [None, None]);
}

/// Rendered, a masked quad's holes are holes: half of it is drawn, and its shadow on the
/// ground (the SDK's sun shadow rays run the alpha test) is half the opaque quad's.
#[test]
fn a_masked_quad_casts_the_cut_out_shadow() {
    let mut counts = Vec::new();
    for (name, material) in [("opaque", ""), ("masked", r#", "alphaMode": "MASK""#)] {
        let file = write_cutout_scene(&format!("cutout-render-{name}.gltf"), 1.0, material);
        let images = render_modes_sized(&file, &format!("sample-cutout-{name}"), "albedo,sun_shadow_noisy,normals", 192, 128);
        let [albedo, shadow, normals] = &images[..] else { unreachable!() };
        // The quad is white, the ground grey, the sky has no normal.
        let quad = albedo.iter().filter(|t| t[0] > 0.9).count();
        let surface = |i: usize| (0..3).map(|c| (2.0 * normals[i][c] - 1.0).powi(2)).sum::<f32>() > 0.25;
        let shadowed = (0..shadow.len()).filter(|&i| surface(i) && albedo[i][0] < 0.9 && shadow[i][0] < 0.5).count();
        eprintln!("{name}: {quad} quad pixels, {shadowed} shadowed ground pixels");
        counts.push((quad as f32, shadowed as f32));
    }
    let ((quad, shade), (masked_quad, masked_shade)) = (counts[0], counts[1]);
    assert!(quad > 100.0 && shade > 50.0, "the opaque quad and its shadow are in view: {quad}, {shade}");
    let (drawn, cast) = (masked_quad / quad, masked_shade / shade);
    assert!((0.3..0.7).contains(&drawn), "the masked quad draws {drawn} of the opaque one's pixels");
    assert!((0.3..0.7).contains(&cast), "the masked quad's shadow is {cast} of the opaque one's");
}

/// URIs are percent-decoded: a buffer named "quad data+1.bin" is "quad%20data%2B1.bin".
#[test]
fn percent_escaped_uris_load() {
    let file = File { buffer_uri: Some("quad%20data%2B1.bin"), ..Default::default() };
    std::fs::write(PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("quad data+1.bin"), file.bytes()).unwrap();
    let scene = gltf_scene::load(&file.write("escaped.gltf")).unwrap();
    assert_eq!(scene.scene.meshes[0].indices, [0, 1, 2, 2, 1, 3]);
}

/// What a file uses that the loader does not read is named, once each.
#[test]
fn unread_features_are_named_once() {
    let path = File::default().write("unread.gltf");
    let json = std::fs::read_to_string(&path)
        .unwrap()
        .replace(r#""extensionsUsed": []"#, r#""extensionsUsed": ["KHR_materials_clearcoat", "KHR_materials_clearcoat"]"#)
        .replace(
            r#""asset":"#,
            r#""animations": [{"channels": [], "samplers": []}, {"channels": [], "samplers": []}], "asset":"#,
        );
    std::fs::write(&path, json).unwrap();
    let scene = gltf_scene::load(&path).unwrap();
    assert_eq!(
        scene.warnings,
        ["the extension KHR_materials_clearcoat (not read)", "more than one animation (the first is played)"],
        "each feature once, in the order found"
    );
}

/// A normal-mapped quad whose file has no tangents gets MikkTSpace's: +X along u, as the
/// file's own would say (the render test above draws the same normal either way).
#[test]
fn missing_tangents_are_mikktspace() {
    let scene = gltf_scene::load(&write_material_quad("material-no-tangents.gltf", false)).unwrap();
    assert_eq!(scene.tangents[0].len(), 4);
    for t in &scene.tangents[0] {
        assert!((*t - glam::Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-5, "{t}");
    }
}

/// A base-colour texture on TEXCOORD_1 with a KHR_texture_transform (offset, rotation, scale):
/// the quad's coordinates are set 1's, transformed (translation x rotation x scale, the
/// rotation counter-clockwise: u' = cos u + sin v, v' = -sin u + cos v).
#[test]
fn texture_transforms_and_the_second_uv_set_are_read() {
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let set0: [[f32; 2]; 4] = [[9.0, 9.0]; 4];
    let set1: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [0.0, 0.0], [1.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 2, 1, 3];
    let mut bytes: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(set0.iter().chain(&set1).flatten().flat_map(|v| v.to_le_bytes()));
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "extensionsUsed": ["KHR_texture_transform"],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 2}}, "indices": 3, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0, "texCoord": 1,
    "extensions": {{"KHR_texture_transform": {{"offset": [0.5, 0.25], "rotation": 1.5707964, "scale": [2, 3]}}}}}}}}}}],
  "textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{png}"}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 32}}, {{"buffer": 0, "byteOffset": 112, "byteLength": 12}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        png = b64(&png_of(2, 2, [200, 100, 50])),
        len = bytes.len(),
        data = b64(&bytes),
    );
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("transformed.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = gltf_scene::load(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Scaled (2u, 3v), turned 90 degrees (u' = v, v' = -u), offset (0.5, 0.25).
    let expected: Vec<[f32; 2]> = set1.iter().map(|&[u, v]| [3.0 * v + 0.5, -2.0 * u + 0.25]).collect();
    for (got, want) in scene.uvs[0].iter().zip(&expected) {
        assert!((got[0] - want[0]).abs() < 1e-5 && (got[1] - want[1]).abs() < 1e-5, "{got:?} vs {want:?}");
    }
}

/// The spot light of `write_spot_scene`: 2 units above the middle of the ground, pointing
/// down, and its cones.
const SPOT: [f32; 3] = [0.0, 2.0, 0.0];
const SPOT_INTENSITY: f32 = 10.0;
const SPOT_INNER: f32 = 0.45;
const SPOT_OUTER: f32 = 0.6;
/// The occluder: a quad at height 1 over x in 0..0.7, z in -0.35..0.35.
const OCCLUDER: [[f32; 2]; 2] = [[0.0, 0.7], [-0.35, 0.35]];
/// The camera: 5 units above the ground's middle, looking down, this vertical field of view.
const TOP_CAMERA_HEIGHT: f32 = 5.0;
const TOP_CAMERA_FOV: f32 = 0.9;

/// A 4x4 grey ground (albedo 0.5) and a white quad over it, lit only by a KHR_lights_punctual
/// spot light pointing down and seen by a camera looking straight down (its up is -Z). With
/// `extra_lights`, a directional and a point light follow the spot in the file's light list,
/// and after them `ring` dim point lights on a circle above the ground.
fn write_spot_scene(name: &str, extra_lights: bool, ring: usize) -> PathBuf {
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let [[x0, x1], [z0, z1]] = OCCLUDER;
    let ground: [[f32; 3]; 4] = [[-2.0, 0.0, -2.0], [2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 2.0]];
    // Wound so that the face normal is +Y (towards the light and the camera).
    let quad: [[f32; 3]; 4] = [[x0, 1.0, z0], [x1, 1.0, z0], [x0, 1.0, z1], [x1, 1.0, z1]];
    let indices: [u16; 6] = [0, 2, 1, 1, 2, 3];
    let mut bytes: Vec<u8> = ground.iter().chain(&quad).flatten().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    // Looking down: a rotation of -90 degrees about X takes -Z to -Y.
    let down = format!("[{}, 0, 0, {}]", -std::f32::consts::FRAC_1_SQRT_2, std::f32::consts::FRAC_1_SQRT_2);
    let more = if extra_lights {
        r#", {"type": "directional", "intensity": 2, "color": [1, 0.5, 0.25]}, {"type": "point", "intensity": 3, "range": 10}"#
    } else {
        ""
    };
    let more_nodes = if extra_lights {
        r#", {"rotation": [-0.3, 0, 0, 0.954], "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"translation": [1, 1, 1], "extensions": {"KHR_lights_punctual": {"light": 2}}}"#
    } else {
        ""
    };
    let first = if extra_lights { 3 } else { 1 };
    let more = more.to_string()
        + &(0..ring).map(|k| format!(r#", {{"type": "point", "intensity": 0.01, "name": "ring {k}"}}"#)).collect::<String>();
    let more_nodes = more_nodes.to_string()
        + &(0..ring)
            .map(|k| {
                let a = k as f32 / ring as f32 * std::f32::consts::TAU;
                let (x, z) = (1.5 * a.cos(), 1.5 * a.sin());
                format!(
                    r#", {{"translation": [{x}, 1.5, {z}], "extensions": {{"KHR_lights_punctual": {{"light": {}}}}}}}"#,
                    first + k
                )
            })
            .collect::<String>();
    let nodes = 4 + if extra_lights { 2 } else { 0 } + ring;
    let roots = format!("[{}]", (0..nodes).map(|n| n.to_string()).collect::<Vec<_>>().join(", "));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": {roots}}}],
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
    {{"type": "spot", "intensity": {SPOT_INTENSITY}, "spot": {{"innerConeAngle": {SPOT_INNER}, "outerConeAngle": {SPOT_OUTER}}}}}{more}]}}}},
  "nodes": [{{"mesh": 0}}, {{"mesh": 1}},
    {{"translation": [{sx}, {sy}, {sz}], "rotation": {down}, "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}},
    {{"translation": [0, {TOP_CAMERA_HEIGHT}, 0], "rotation": {down}, "camera": 0}}{more_nodes}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": {TOP_CAMERA_FOV}, "znear": 0.1}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 2, "material": 0}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 1}}, "indices": 2, "material": 1}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}}}},
    {{"pbrMetallicRoughness": {{"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0}}}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-2, 0, -2], "max": [2, 0, 2]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3", "min": [{x0}, 1, {z0}], "max": [{x1}, 1, {z1}]}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 12}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        sx = SPOT[0],
        sy = SPOT[1],
        sz = SPOT[2],
        len = bytes.len(),
        data = b64(&bytes),
    );
    written(name, &json)
}

/// KHR_lights_punctual lights are read where their nodes put them (a light shines down its
/// node's -Z), with their colour, intensity, range and cones; they replace the fitted lights.
#[test]
fn punctual_lights_are_read() {
    use hybrid_rt::LightType;
    let scene = gltf_scene::load(&write_spot_scene("lights.gltf", true, 0)).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!((scene.lights.sun_intensity, scene.lights.point_intensity), (0.0, 0.0), "the fitted lights are off");
    assert_eq!(scene.file_lights.len(), 3);
    let of = |t: LightType| scene.file_lights.iter().find(|l| l.light_type == t).unwrap();
    let (spot, sun, point) = (of(LightType::Spot), of(LightType::Directional), of(LightType::Point));
    assert_eq!(spot.light_type, LightType::Spot);
    assert!(spot.position.distance(glam::Vec3::from(SPOT)) < 1e-5, "{}", spot.position);
    assert!(spot.direction.normalize().distance(glam::Vec3::NEG_Y) < 1e-5, "{}", spot.direction);
    assert_eq!((spot.inner_cone, spot.outer_cone, spot.intensity, spot.range), (SPOT_INNER, SPOT_OUTER, SPOT_INTENSITY, 0.0));
    assert!(spot.radius > 0.0, "a sized light: soft shadows");
    assert_eq!((sun.light_type, sun.intensity, sun.color), (LightType::Directional, 2.0, [1.0, 0.5, 0.25]));
    assert!(sun.angular_extent > 0.0);
    // A rotation of -2 asin(0.3) about X turns -Z towards -Y.
    let angle = 2.0 * 0.3f32.asin();
    assert!(sun.direction.normalize().distance(glam::Vec3::new(0.0, -angle.sin(), -angle.cos())) < 1e-2, "{}", sun.direction);
    assert_eq!((point.light_type, point.position, point.intensity, point.range), (LightType::Point, glam::Vec3::ONE, 3.0, 10.0));
    // A file without lights keeps the fitted ones.
    let fitted = gltf_scene::load(&write_cutout_scene("no-lights.gltf", 1.0, "")).unwrap();
    assert!(fitted.file_lights.is_empty() && fitted.lights.sun_intensity > 0.0);
}

/// Rendered through the file's camera, the spot light from the file lights the ground inside
/// its cone as the lighting pass's falloffs say (irradiance I cos / d² x the smoothstep from the
/// outer to the inner cone, times the albedo), nothing outside it, and the occluder's shadow
/// (the SDK's multi-light trace, denoised) lies where the light's geometry puts it. Pixels
/// within a penumbra's width (plus a pixel) of an edge are not judged.
#[test]
fn a_punctual_spot_light_casts_its_shadow() {
    let (w, h) = (128u32, 96u32);
    let file = write_spot_scene("spot-render.gltf", false, 0);
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("sample-spot");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_sample"))
        .args(["--headless", file.to_str().unwrap(), "--camera", "0", "--width", &w.to_string(), "--height", &h.to_string()])
        .args(["--frames", "2", "--modes", "direct,albedo,lights_shadow"])
        .arg("--out")
        .arg(&out)
        .env_remove("DISPLAY")
        .output()
        .unwrap();
    assert!(run.status.success(), "{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    let read = |m: &str| hybrid_rt_samples::images::read_exr_rgba(&out.join(format!("{m}.exr"))).unwrap().2;
    let (direct, albedo, shadow) = (read("direct"), read("albedo"), read("lights_shadow"));
    let [[x0, x1], [z0, z1]] = OCCLUDER;
    // World units per pixel on the ground, and the penumbra's half-width there (the light's
    // radius, as large at the ground as at the light: the occluder is halfway).
    let half = TOP_CAMERA_HEIGHT * (0.5 * TOP_CAMERA_FOV).tan();
    let pixel = 2.0 * half / h as f32;
    let scene = gltf_scene::load(&file).unwrap();
    let margin = scene.file_lights[0].radius + pixel;
    let (mut lit, mut shade, mut dark, mut quad) = (0, 0, 0, 0);
    for py in 0..h {
        for px in 0..w {
            let i = (py * w + px) as usize;
            let ndc = [(px as f32 + 0.5) / w as f32 * 2.0 - 1.0, (py as f32 + 0.5) / h as f32 * 2.0 - 1.0];
            // The camera's right is +X, its up -Z.
            let g = [half * w as f32 / h as f32 * ndc[0], half * ndc[1]];
            // Seen through the quad's plane (height 1, 4/5 of the way down) the pixel is on the quad.
            let v = [0.8 * g[0], 0.8 * g[1]];
            let inside = |p: [f32; 2], m: f32| p[0] > x0 + m && p[0] < x1 - m && p[1] > z0 + m && p[1] < z1 - m;
            let on_quad = inside(v, 0.0);
            let near_quad = inside(v, -0.8 * margin) && !inside(v, 0.8 * margin);
            if near_quad {
                continue;
            }
            let off_ground = g[0].abs().max(g[1].abs()) > 2.0 - margin;
            if off_ground && !on_quad {
                continue;
            }
            if on_quad {
                assert!(albedo[i][0] > 0.99, "pixel {px},{py} sees the white quad: albedo {:?}", albedo[i]);
                quad += 1;
                continue;
            }
            assert!((albedo[i][0] - 0.5).abs() < 0.01, "pixel {px},{py} sees the grey ground: albedo {:?}", albedo[i]);
            // The ray to the light crosses the quad's plane halfway, at g / 2.
            let s = [0.5 * g[0], 0.5 * g[1]];
            let (umbra, penumbra) = (inside(s, 0.5 * margin), inside(s, -0.5 * margin));
            let to_light = glam::Vec3::from(SPOT) - glam::Vec3::new(g[0], 0.0, g[1]);
            let d = to_light.length();
            let c = to_light.y / d;
            let (cos_outer, cos_inner) = (SPOT_OUTER.cos(), SPOT_INNER.cos());
            let t = ((c - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
            let expected = 0.5 * SPOT_INTENSITY * c / (d * d) * t * t * (3.0 - 2.0 * t);
            let e = direct[i][0];
            if (c - cos_outer).abs() < 0.01 || (penumbra && !umbra) {
                continue;
            }
            if umbra && c > cos_outer {
                // (Within a few pixels of the cone's edge, where the light fades out, the
                // denoiser blurs in the visibility 1 the trace reports where no light reaches:
                // a few percent of a light that is nearly gone there. Judged against the
                // spot's peak, 1/4 x I x albedo under the light, that is under 0.4%.)
                let peak = 0.5 * SPOT_INTENSITY / 4.0;
                assert!(e < 0.004 * peak, "pixel {px},{py} in the umbra: {e} (lit {expected})");
                shade += 1;
            } else if c < cos_outer {
                assert!(e < 1e-4, "pixel {px},{py} outside the cone: {e}");
                dark += 1;
            } else {
                assert!((e - expected).abs() < 0.02 * expected + 2e-3, "pixel {px},{py} lit: {e}, expected {expected}");
                assert!(shadow[i][0] > 0.98, "pixel {px},{py} lit: visibility {}", shadow[i][0]);
                lit += 1;
            }
        }
    }
    eprintln!("{lit} lit, {shade} umbra, {dark} outside the cone, {quad} on the occluder");
    assert!(lit > 1000 && shade > 50 && dark > 1000 && quad > 50, "{lit} lit, {shade} umbra, {dark} dark, {quad} quad");
}

/// A file with more lights than the SDK shadows in one task: the first 32 are drawn (the
/// visibility of lights 16.. in the trace's second image) with a warning; the frame renders.
#[test]
fn more_than_32_lights_draw_the_first_32() {
    let file = write_spot_scene("many-lights.gltf", true, 31);
    let scene = gltf_scene::load(&file).unwrap();
    assert_eq!(scene.file_lights.len(), 32);
    assert!(scene.warnings.iter().any(|w| w.contains("more than 32 lights")), "{:?}", scene.warnings);
    let images = render_modes_sized(&file, "sample-many-lights", "direct,lights_shadow_noisy,normals", 64, 48);
    // Every surface is lit (the ring's lights are all around), and every value is a number.
    let surface = images[2].iter().filter(|t| (0..3).map(|c| (2.0 * t[c] - 1.0).powi(2)).sum::<f32>() > 0.25).count();
    let lit = images[0].iter().filter(|t| t[0] > 0.0).count();
    assert!(surface > 100 && lit as f32 > 0.95 * surface as f32, "{lit} lit pixels of {surface}");
    assert!(images.iter().flatten().all(|t| t.iter().all(|c| c.is_finite())));
}

/// `COLOR_0` tints the base colour in the raster pass (the albedo target reads factor x colour)
/// and, by its mean, the albedo the SDK relights the mesh with.
#[test]
fn vertex_colours_tint_the_base_colour() {
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let quad: [[f32; 3]; 4] = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let color = [0.25f32, 0.5, 1.0];
    let indices: [u16; 6] = [0, 1, 2, 2, 1, 3];
    let mut bytes: Vec<u8> = quad.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend([color; 4].iter().flatten().flat_map(|v| v.to_le_bytes()));
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "COLOR_0": 1}}, "indices": 2, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0}}}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 96, "byteLength": 12}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        len = bytes.len(),
        data = b64(&bytes),
    );
    let path = written("colours.gltf", &json);
    let scene = gltf_scene::load(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let expected = color.map(|c| 0.8 * c);
    let sdk = scene.diffuse_albedo(0);
    assert!((0..3).all(|c| (sdk[c] - expected[c]).abs() < 1e-6), "the SDK's albedo {sdk:?}, expected {expected:?}");
    let images = render_modes(&path, "sample-colours", "albedo");
    let on: Vec<&[f32; 4]> = images[0].iter().filter(|t| t[2] > 0.1).collect();
    assert!(on.len() > 200, "{} pixels see the quad", on.len());
    for t in on {
        // The albedo target is RGBA8: within a level.
        assert!((0..3).all(|c| (t[c] - expected[c]).abs() < 0.006), "albedo {t:?}, expected {expected:?}");
    }
}

/// No file makes the loader panic: 300 mutants each of the spot-light, material and cut-out
/// files (numbers set to edge values, members removed, arrays emptied) load or are refused,
/// and the first two of each that load render or fail with an error.
#[test]
fn mutated_files_load_or_are_refused() {
    let host = hybrid_rt_host::Host::new().expect("a Vulkan device with ray tracing");
    let files = [
        write_spot_scene("fuzz-lights.gltf", true, 2),
        write_material_quad("fuzz-material.gltf", true),
        write_cutout_scene("fuzz-cutout.gltf", 1.0, r#", "alphaMode": "MASK""#),
    ];
    for (k, file) in files.iter().enumerate() {
        let (loaded, refused) = support::fuzz::fuzz_loader(file, 300, 17 + k as u64, &host, 2);
        eprintln!("{}: {loaded} mutants loaded, {refused} refused", file.display());
    }
}
