//! glTF 2.0 scenes (`.gltf` with `.bin` or data-URI buffers, or `.glb`), parsed by the `gltf`
//! crate: every triangle primitive (lists, strips and fans) of every node of the default scene
//! becomes an instance with the node's world transform, its normals (computed from the
//! triangles where the file has none), its texture coordinates, tangents and vertex colours, and its
//! metallic-roughness material: base colour, metallic, roughness, normal and emissive factors
//! with their PNG or JPEG textures (`gltf_textures`), and KHR_materials_emissive_strength.
//! Perspective cameras (with their roll) are kept for `--camera`; `KHR_lights_punctual` lights
//! become the scene's lights (`gltf_lights`). The camera path, surfel size and AO length are
//! fitted to the scene's bounds, and so are a sun and a point light where the file has no
//! lights of its own.
//!
//! `alphaMode: MASK` materials cut their meshes where the base-colour texture's alpha x the
//! factor's is below `alphaCutoff`, in the raster pass and in the SDK's rays (`BLEND` is drawn
//! masked at 0.5). Skins, morph targets and the first animation make a `Rig`. What a file uses
//! that the loader does not read (other extensions, more animations...) is named once each in
//! `SampleScene::warnings`, and printed.
//!
//! Any file gives a scene or an error that names the file and what is wrong in it — the node,
//! the primitive, the extension — and never hangs or panics: a node that is its own ancestor
//! (or has two parents) is refused, extensions the file requires and this loader lacks (Draco,
//! meshopt, quantized meshes) are named before validation buries them under its own errors,
//! and validation errors are summed up to the first three.
use crate::gltf_lights;
use crate::gltf_rig;
use crate::gltf_textures::TextureCache;
use crate::gltf_uri::read_uri;
use crate::lighting::Lights;
use crate::raster::{Material, MaterialTextures};
use crate::scene::{vertex_normals, CameraPath, Cutout, Motion, SampleScene};
use crate::skin::{Morph, MorphTarget, SkinnedMesh};
use crate::tangents;
use glam::{Affine3A, Mat4, Vec3, Vec4};
use hybrid_rt_host::scene::{Mesh, Scene};
use std::collections::HashMap;
use std::path::Path;

fn buffers(doc: &gltf::Document, blob: Option<Vec<u8>>, dir: &Path) -> Result<Vec<Vec<u8>>, String> {
    let mut blob = blob;
    doc.buffers()
        .map(|b| {
            let data = match b.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or("the GLB has no binary chunk")?,
                gltf::buffer::Source::Uri(uri) => read_uri(uri, dir)?,
            };
            if data.len() < b.length() {
                return Err(format!("buffer {} holds {} bytes, the file says {}", b.index(), data.len(), b.length()));
            }
            Ok(data)
        })
        .collect()
}

fn material(m: &gltf::Material) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let c = pbr.base_color_factor();
    // KHR_materials_emissive_strength scales the (0..1) factor past 1: HDR emitters.
    let e = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
    Material {
        albedo: [c[0], c[1], c[2]],
        roughness: pbr.roughness_factor(),
        metalness: pbr.metallic_factor(),
        emissive: e.to_array(),
    }
}

/// The material's textures, decoded into `cache` (colour textures sRGB, data textures linear).
fn material_textures_of(
    m: &gltf::Material,
    cache: &mut TextureCache,
    data: &[Vec<u8>],
    dir: &Path,
    name: &str,
) -> Result<MaterialTextures, String> {
    let pbr = m.pbr_metallic_roughness();
    let mut get = |t: Option<gltf::Texture>, linear| t.map_or(Ok(None), |t| cache.get(t, linear, data, dir, name));
    let normal = m.normal_texture();
    Ok(MaterialTextures {
        base_color: get(pbr.base_color_texture().map(|i| i.texture()), false)?,
        metallic_roughness: get(pbr.metallic_roughness_texture().map(|i| i.texture()), true)?,
        normal_scale: normal.as_ref().map_or(1.0, |n| n.scale()),
        normal: get(normal.map(|n| n.texture()), true)?,
        emissive: get(m.emissive_texture().map(|i| i.texture()), false)?,
    })
}

/// Mesh cut-outs of a material, from its base-colour texture (our index; None: it has none):
/// `Ok(None)` opaque, `Err(())` every texel a hole (the primitive is not drawn). The texture's
/// alpha is multiplied by the factor's, so the cutoff is divided by it instead.
fn cutout(m: &gltf::Material, base_color: Option<usize>, warnings: &mut Warnings) -> Result<Option<Cutout>, ()> {
    let cutoff = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => return Ok(None),
        gltf::material::AlphaMode::Mask => m.alpha_cutoff().unwrap_or(0.5),
        gltf::material::AlphaMode::Blend => {
            warnings.add("alphaMode BLEND (drawn as MASK with a cutoff of 0.5)");
            0.5
        }
    };
    let factor = m.pbr_metallic_roughness().base_color_factor()[3];
    let cutoff = if factor > 0.0 { cutoff / factor } else { f32::INFINITY };
    match base_color {
        _ if cutoff <= 0.0 => Ok(None),
        _ if cutoff > 1.0 => Err(()),
        None => Ok(None),
        Some(texture) => Ok(Some(Cutout { texture, cutoff })),
    }
}

/// The texture coordinates a material's textures are sampled with: the set and the
/// KHR_texture_transform of its base-colour texture (else of its metallic-roughness, emissive
/// or normal texture). The sample draws every texture of a material with one set of
/// coordinates; a material whose textures use different sets or transforms is named.
fn uv_mapping(m: &gltf::Material, warnings: &mut Warnings) -> (u32, Option<glam::Mat3>) {
    let pbr = m.pbr_metallic_roughness();
    // (set, transform) of each texture the material has.
    let mapping = |info: gltf::texture::Info| {
        let t = info.texture_transform();
        let set = t.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
        let matrix = t.map(|t| {
            let ([ox, oy], r, [sx, sy]) = (t.offset(), t.rotation(), t.scale());
            // KHR_texture_transform: translation x rotation x scale, the rotation
            // counter-clockwise in UV space.
            let rotation = glam::Mat3::from_cols(
                glam::Vec3::new(r.cos(), -r.sin(), 0.0),
                glam::Vec3::new(r.sin(), r.cos(), 0.0),
                glam::Vec3::Z,
            );
            glam::Mat3::from_translation(glam::Vec2::new(ox, oy)) * rotation * glam::Mat3::from_scale(glam::Vec2::new(sx, sy))
        });
        (set, matrix)
    };
    let mut all: Vec<(u32, Option<glam::Mat3>)> =
        [pbr.base_color_texture(), pbr.metallic_roughness_texture(), m.emissive_texture()]
            .into_iter()
            .flatten()
            .map(mapping)
            .collect();
    if let Some(n) = m.normal_texture() {
        all.push((n.tex_coord(), None));
    }
    let Some(&lead) = all.first() else { return (0, None) };
    if all.iter().any(|&(set, matrix)| set != lead.0 || (matrix.is_some() && matrix != lead.1)) {
        warnings.add("materials whose textures use different UV sets or transforms (the base colour's is used)");
    }
    lead
}

/// What the file uses that the loader does not read, each named once.
#[derive(Default)]
struct Warnings(Vec<String>);

impl Warnings {
    fn add(&mut self, what: &str) {
        if !self.0.iter().any(|w| w == what) {
            self.0.push(what.to_string());
        }
    }
}

/// Extensions the loader reads (beyond the core), or that change nothing it draws.
const READ_EXTENSIONS: &[&str] = &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_texture_transform"];

/// The file-wide features the loader ignores.
fn unread_features(doc: &gltf::Document, warnings: &mut Warnings) {
    for x in doc.extensions_used().filter(|x| !READ_EXTENSIONS.contains(x)) {
        warnings.add(&format!("the extension {x} (not read)"));
    }
}

/// Extensions a file may require that this loader reads (beyond positions, indices and the
/// core metallic-roughness material).
const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_texture_transform"];

/// Validation errors shown in full; the rest are counted.
const SHOWN_ERRORS: usize = 3;

/// Parses and validates the file, naming required extensions this loader lacks first (the
/// crate's validation of, say, a Draco file lists every compressed buffer view as missing
/// data and never says why).
fn open(path: &Path) -> Result<gltf::Gltf, String> {
    let name = path.display();
    let bytes = std::fs::read(path).map_err(|e| format!("{name}: {e}"))?;
    let unvalidated = gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| format!("{name}: {e}"))?;
    let missing: Vec<&str> = unvalidated.extensions_required().filter(|x| !SUPPORTED_REQUIRED_EXTENSIONS.contains(x)).collect();
    if !missing.is_empty() {
        return Err(format!("{name}: requires the glTF extension(s) {}, which this loader does not support", missing.join(", ")));
    }
    // The gltf crate (1.4.1) panics on some invalid files its validation lets through or trips
    // over: a primitive's attribute past the accessors, an image with neither a URI nor a
    // buffer view and MIME type. Refuse those first, and turn any other panic of the parser
    // into an error, so no file takes the sample down.
    // (Read from the JSON: the document's own accessors index unchecked too.)
    let root = unvalidated.document.as_json();
    let accessors = root.accessors.len();
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            if let Some(k) = p.attributes.values().map(|a| a.value()).find(|&k| k >= accessors) {
                return Err(format!("{name}: mesh {mi} primitive {pi}: an attribute is accessor {k} of {accessors}"));
            }
        }
    }
    for (k, image) in root.images.iter().enumerate() {
        if image.uri.is_none() && (image.buffer_view.is_none() || image.mime_type.is_none()) {
            return Err(format!("{name}: image {k} has neither a URI nor a buffer view with a MIME type"));
        }
    }
    let parsed = std::panic::catch_unwind(|| gltf::Gltf::from_slice(&bytes))
        .map_err(|_| format!("{name}: the glTF parser failed on this file (an index or size out of range)"))?;
    parsed.map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let shown: Vec<String> = errors.iter().take(SHOWN_ERRORS).map(|(at, what)| format!("{at}: {what}")).collect();
            let more = errors.len().saturating_sub(SHOWN_ERRORS);
            let tail = if more > 0 { format!(" (and {more} more)") } else { String::new() };
            format!("{name}: invalid glTF: {}{tail}", shown.join("; "))
        }
        e => format!("{name}: {e}"),
    })
}

/// A primitive's triangles as a list: strips and fans unrolled (a strip's odd triangles
/// flipped back to the strip's winding); points and lines give none.
fn triangle_list(mode: gltf::mesh::Mode, indices: &[u32]) -> Vec<u32> {
    use gltf::mesh::Mode;
    let n = indices.len();
    match mode {
        Mode::Triangles => indices[..n - n % 3].to_vec(),
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .flat_map(|i| {
                let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
                if i & 1 == 0 {
                    [a, b, c]
                } else {
                    [b, a, c]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..n.saturating_sub(1)).flat_map(|i| [indices[0], indices[i], indices[i + 1]]).collect(),
        _ => Vec::new(),
    }
}

/// A skinned primitive's joints and weights, one of each per vertex.
struct Influences {
    joints: Vec<[u32; 4]>,
    weights: Vec<[f32; 4]>,
}

/// One primitive's triangles and vertex attributes, as the sample keeps a mesh.
struct Primitive {
    mesh: Mesh,
    normals: Vec<Vec3>,
    uvs: Vec<[f32; 2]>,
    tangents: Vec<Vec4>,
    colors: Vec<Vec4>,
    influences: Option<Influences>,
    morph_targets: Vec<MorphTarget>,
}

/// Reads a primitive (None: no triangles): its indices as a triangle list, its normals (the
/// file's, else computed), its texture coordinates (the material's set and transform), its
/// tangents (the file's, else MikkTSpace's where a normal map needs them), its `COLOR_0`
/// (linear RGBA; empty: none) and, when it is
/// skinned by a skin of `skin_joints` joints, its JOINTS_0 and WEIGHTS_0.
fn read_primitive(
    prim: &gltf::Primitive,
    data: &[Vec<u8>],
    skin_joints: Option<usize>,
    warnings: &mut Warnings,
) -> Result<Option<Primitive>, String> {
    let reader = prim.reader(|b| data.get(b.index()).map(|d| d.as_slice()));
    let positions: Vec<Vec3> = reader.read_positions().ok_or("no positions")?.map(Vec3::from).collect();
    let n = positions.len();
    let listed: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    if let Some(&bad) = listed.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} past its {n} vertices"));
    }
    let indices = triangle_list(prim.mode(), &listed);
    if indices.is_empty() {
        return Ok(None);
    }
    // The file's normals where it has them (one per vertex, finite).
    let file_normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
    let normals = match file_normals {
        Some(f) if f.len() == n && f.iter().all(|v| v.is_finite()) => {
            f.into_iter().map(|v| v.try_normalize().unwrap_or(Vec3::Y)).collect()
        }
        _ => vertex_normals(&positions, &indices),
    };
    let (set, transform) = uv_mapping(&prim.material(), warnings);
    let uvs: Vec<[f32; 2]> = reader
        .read_tex_coords(set)
        .map(|t| {
            t.into_f32()
                .map(|uv| match transform {
                    Some(m) => m.transform_point2(glam::Vec2::from(uv)).to_array(),
                    None => uv,
                })
                .collect::<Vec<_>>()
        })
        .filter(|t| t.len() == n)
        .unwrap_or_default();
    let file_tangents: Option<Vec<Vec4>> = reader.read_tangents().map(|t| t.map(Vec4::from).collect());
    let tangents = match file_tangents.filter(|t| t.len() == n && t.iter().all(|v| v.is_finite())) {
        Some(t) => t,
        // A normal map without the file's tangents: MikkTSpace's, as glTF asks.
        None if prim.material().normal_texture().is_some() && !uvs.is_empty() => {
            tangents::mikktspace(&positions, &normals, &uvs, &indices)
        }
        None => Vec::new(),
    };
    let colors: Vec<Vec4> = reader
        .read_colors(0)
        .map(|c| c.into_rgba_f32().map(Vec4::from).collect::<Vec<_>>())
        .filter(|c| c.len() == n && c.iter().all(|v| v.is_finite()))
        .unwrap_or_default();
    let influences = match skin_joints {
        None => None,
        Some(count) => {
            let joints: Option<Vec<[u32; 4]>> = reader.read_joints(0).map(|j| j.into_u16().map(|j| j.map(u32::from)).collect());
            let weights: Option<Vec<[f32; 4]>> = reader.read_weights(0).map(|w| w.into_f32().collect());
            let (Some(joints), Some(weights)) = (joints, weights) else {
                return Err("skinned without JOINTS_0 and WEIGHTS_0".into());
            };
            if joints.len() != n || weights.len() != n {
                return Err("JOINTS_0 or WEIGHTS_0 is not one per vertex".into());
            }
            if let Some(bad) = joints.iter().flatten().find(|&&j| j as usize >= count) {
                return Err(format!("joint {bad} past its skin's {count}"));
            }
            Some(Influences { joints, weights })
        }
    };
    let morph_targets = reader
        .read_morph_targets()
        .map(|(dp, dn, dt)| {
            // An attribute's displacements, one per vertex, or none.
            let list = |d: Option<Vec<Vec3>>| d.filter(|d| d.len() == n && d.iter().all(|v| v.is_finite())).unwrap_or_default();
            MorphTarget {
                positions: list(dp.map(|i| i.map(Vec3::from).collect())),
                normals: list(dn.map(|i| i.map(Vec3::from).collect())),
                tangents: list(dt.map(|i| i.map(Vec3::from).collect())),
            }
        })
        .collect();
    Ok(Some(Primitive { mesh: Mesh { positions, indices }, normals, uvs, tangents, colors, influences, morph_targets }))
}

/// Loads `path` into a `SampleScene`.
pub fn load(path: &Path) -> Result<SampleScene, String> {
    let name = path.display();
    let gltf::Gltf { document, blob } = open(path)?;
    let data = buffers(&document, blob, path.parent().unwrap_or(Path::new("."))).map_err(|e| format!("{name}: {e}"))?;
    let file = name.to_string();
    let mut scene = Scene::default();
    let dir = path.parent().unwrap_or(Path::new("."));
    let (mut normals, mut uvs, mut tangents, mut colors, mut cutouts) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut warnings = Warnings::default();
    unread_features(&document, &mut warnings);
    let mut rig = gltf_rig::rig(&document, &data, &mut |w| warnings.add(w)).map_err(|e| format!("{name}: {e}"))?;
    let animated = gltf_rig::animated_nodes(&rig);
    let mut motions = Vec::new();
    let mut materials = Vec::new();
    let (mut textures, mut material_textures) = (TextureCache::default(), Vec::new());
    // (glTF mesh, primitive) -> our mesh, so instanced glTF meshes share one BLAS.
    let mut meshes: HashMap<(usize, usize), usize> = HashMap::new();
    let root = document.default_scene().or_else(|| document.scenes().next()).ok_or(format!("{name}: the file has no scene"))?;
    let mut stack: Vec<(gltf::Node, Mat4)> = root.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    // Each node once: a node met again is its own ancestor (a cycle, which would never end)
    // or has two parents (which glTF forbids).
    let mut seen = vec![false; document.nodes().len()];
    let mut skipped = 0usize;
    // Perspective cameras: (eye, forward, up, vertical field of view).
    let mut cameras: Vec<(Vec3, Vec3, Vec3, f32)> = Vec::new();
    let mut placed_lights: Vec<gltf_lights::PlacedLight> = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(format!("{name}: node {} is its own ancestor or has two parents", node.index()));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        for child in node.children() {
            stack.push((child, world));
        }
        cameras.extend(perspective_camera(&node, world));
        if let Some(light) = node.light() {
            match gltf_lights::PlacedLight::new(&light, world) {
                Some(p) => placed_lights.push(p),
                None => warnings.add("lights whose node transform is degenerate (not drawn)"),
            }
        }
        let Some(mesh) = node.mesh() else { continue };
        // A skinned node's joints place it (its own transform is ignored, as glTF says).
        let skin = node.skin().map(|s| s.index()).filter(|&s| s < rig.skins.len());
        for prim in mesh.primitives() {
            let key = (mesh.index(), prim.index());
            let at = || format!("{name}: mesh {} primitive {}", mesh.index(), prim.index());
            // A skinned or morphed primitive deforms on its own: its mesh is not shared.
            let morphed = prim.morph_targets().next().is_some();
            let shared = if skin.is_some() || morphed { None } else { meshes.get(&key).copied() };
            let ours = match shared {
                Some(m) => Some(m),
                None => match read_primitive(&prim, &data, skin.map(|k| rig.skins[k].joints.len()), &mut warnings)
                    .map_err(|e| format!("{}: {e}", at()))?
                {
                    None => None,
                    Some(p) => {
                        normals.push(p.normals);
                        tangents.push(p.tangents);
                        colors.push(p.colors);
                        uvs.push(p.uvs);
                        let m = scene.add_mesh(p.mesh);
                        let morph = (!p.morph_targets.is_empty()).then(|| {
                            // The node's weights, else the mesh's, else 0 (one per target).
                            let defaults = node.weights().or(mesh.weights()).unwrap_or(&[]);
                            let weights = (0..p.morph_targets.len()).map(|k| defaults.get(k).copied().unwrap_or(0.0)).collect();
                            Morph { node: node.index(), targets: p.morph_targets, weights }
                        });
                        let (joints, weights) = p.influences.map(|i| (i.joints, i.weights)).unwrap_or_default();
                        match (skin, morph) {
                            (None, None) => {
                                meshes.insert(key, m);
                            }
                            (skin, morph) => rig.skinned.push(SkinnedMesh { mesh: m, skin, joints, weights, morph }),
                        }
                        Some(m)
                    }
                },
            };
            let Some(ours) = ours else {
                skipped += 1;
                continue;
            };
            let textures_of = material_textures_of(&prim.material(), &mut textures, &data, dir, &file)?;
            // A mesh's cut-out is its material's (one material per glTF primitive).
            let Ok(cut) = cutout(&prim.material(), textures_of.base_color, &mut warnings) else {
                warnings.add("masked materials whose alpha is below their cutoff everywhere (not drawn)");
                continue;
            };
            cutouts.resize(scene.meshes.len(), None);
            cutouts[ours] = cut;
            let (transform, motion) = match skin {
                Some(_) => (Affine3A::IDENTITY, Motion::Static),
                None if animated.get(node.index()).copied().unwrap_or(false) => {
                    (Affine3A::from_mat4(world), Motion::Node(node.index()))
                }
                None => (Affine3A::from_mat4(world), Motion::Static),
            };
            scene.add_instance(ours, transform);
            motions.push(motion);
            materials.push(material(&prim.material()));
            material_textures.push(textures_of);
        }
    }
    if scene.instances.is_empty() {
        return Err(format!("{name}: no triangles ({skipped} primitives of points or lines skipped)"));
    }
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut s = fitted(name, scene, normals, materials);
    s.motions = motions;
    s.rig = rig;
    cutouts.resize(s.scene.meshes.len(), None);
    s.file_lights = gltf_lights::lights(&placed_lights, s.sun_angular_extent, s.point_radius, &mut |w| warnings.add(w));
    if !s.file_lights.is_empty() {
        // The file's lights replace the fitted ones.
        (s.lights.sun_intensity, s.lights.point_intensity) = (0.0, 0.0);
    }
    (s.uvs, s.tangents, s.colors, s.textures, s.material_textures, s.cutouts) =
        (uvs, tangents, colors, textures.textures, material_textures, cutouts);
    for w in &warnings.0 {
        eprintln!("{file}: {w}");
    }
    s.warnings = warnings.0;
    // A glTF camera looks down its node's -Z with +Y up; the path's target sits a bounding
    // radius ahead (the near and far planes follow from that distance).
    let (lo, hi) = s.bounds();
    let reach = ((hi - lo).length() * 0.5).max(1e-3);
    s.file_cameras = cameras
        .into_iter()
        .map(|(eye, forward, up, fov_y_radians)| CameraPath {
            from: eye,
            to: eye,
            target: eye + forward * reach,
            up,
            fov_y_radians,
        })
        .collect();
    Ok(s)
}

/// `node`'s perspective camera at `world`, if it has a usable one: (eye, forward, up, vertical
/// field of view).
fn perspective_camera(node: &gltf::Node, world: Mat4) -> Option<(Vec3, Vec3, Vec3, f32)> {
    let yfov = node.camera().and_then(|c| match c.projection() {
        gltf::camera::Projection::Perspective(p) => Some(p.yfov()),
        gltf::camera::Projection::Orthographic(_) => None,
    })?;
    let (eye, forward) = (world.transform_point3(Vec3::ZERO), world.transform_vector3(Vec3::NEG_Z));
    let forward = forward.try_normalize().filter(|_| eye.is_finite() && yfov > 0.0 && yfov < 3.1)?;
    // Its up is the node's +Y, made perpendicular to the view (a sheared node's is not).
    let up = world.transform_vector3(Vec3::Y);
    let up = (up - forward * up.dot(forward)).try_normalize().unwrap_or(Vec3::Y);
    Some((eye, forward, up, yfov))
}

/// How much larger than the scene's bounding sphere the fitted camera's view is.
const FRAME_MARGIN: f32 = 1.1;

/// Wraps a static scene with a camera path, lights and sizes scaled to its bounds.
fn fitted(name: String, scene: Scene, normals: Vec<Vec<Vec3>>, materials: Vec<Material>) -> SampleScene {
    let motions = vec![Motion::Static; scene.instances.len()];
    let mut s = SampleScene {
        name,
        scene,
        normals,
        uvs: Vec::new(),
        tangents: Vec::new(),
        colors: Vec::new(),
        textures: Vec::new(),
        material_textures: Vec::new(),
        cutouts: Vec::new(),
        warnings: Vec::new(),
        materials,
        motions,
        deformer: None,
        rig: Default::default(),
        file_lights: Vec::new(),
        lights: Lights {
            sun_direction: Vec3::new(0.45, 1.0, 0.6),
            sun_intensity: 3.0,
            point_position: Vec3::ZERO,
            point_intensity: 0.0,
            ambient: 0.0,
        },
        sun_angular_extent: 0.03,
        point_radius: 0.0,
        sky: [0.35, 0.45, 0.6],
        camera_path: CameraPath {
            from: Vec3::ZERO,
            to: Vec3::ZERO,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_radians: 60f32.to_radians(),
        },
        file_cameras: Vec::new(),
        lidar_eye: Vec3::ZERO,
        tile_unit_length: 0.1,
        ao_ray_length: 0.5,
    };
    let (lo, hi) = s.bounds();
    let (center, radius) = ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3));
    // The bounding sphere fits the view with a 10% margin from anywhere on the path (an image
    // at least as wide as it is high): distance = 1.1 r / sin(fov / 2).
    let fov_y = 60f32.to_radians();
    let distance = FRAME_MARGIN * radius / (0.5 * fov_y).sin();
    s.camera_path = CameraPath {
        from: center + distance * Vec3::new(-0.45, 0.3, 1.1).normalize(),
        to: center + distance * Vec3::new(0.45, 0.3, 1.1).normalize(),
        target: center,
        up: Vec3::Y,
        fov_y_radians: fov_y,
    };
    // A point light a little above the middle, as bright at a radius as the sun.
    s.lights.point_position = center + Vec3::Y * 0.3 * radius;
    s.lights.point_intensity = 1.5 * radius * radius;
    s.point_radius = 0.02 * radius;
    s.lidar_eye = center;
    s.tile_unit_length = radius / 60.0;
    s.ao_ray_length = radius / 10.0;
    s
}
