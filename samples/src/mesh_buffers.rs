//! The sample's meshes and textures in device memory, laid out as an engine's: interleaved
//! vertices that the raster pass draws and the SDK reads its positions (and, for alpha-tested
//! geometry, its texture coordinates) out of, u32 indices, and the material textures the
//! G-buffer pass samples.
use crate::gpu::READ;
use ash::vk;
use glam::{Vec3, Vec4};
use hybrid_rt_host::scene::Scene;
use hybrid_rt_host::{Host, HostBuffer, HostImage, HostResult};

/// One vertex: a position, a shading normal (RGB32F each), a texture coordinate (RG32F), a
/// tangent (RGBA32F: xyz and the bitangent's sign, glTF's convention) and a colour (RGBA32F,
/// linear, multiplying the base colour as glTF's `COLOR_0`), interleaved: 64 bytes, all
/// floats, which the skinning pass copies as they are.
pub type Vertex = [f32; 16];

/// Bytes per [`Vertex`]. The SDK reads the positions out of the same buffer
/// (`VertexBufferInput::stride`), as an engine's.
pub const VERTEX_STRIDE: u32 = std::mem::size_of::<Vertex>() as u32;
/// Where the texture coordinate sits in a vertex.
pub const UV_OFFSET: u32 = 24;
/// Where the tangent sits in a vertex.
pub const TANGENT_OFFSET: u32 = 32;
/// Where the colour sits in a vertex.
pub const COLOR_OFFSET: u32 = 48;

/// Per-vertex attributes of one mesh besides its positions. Empty lists, or lists shorter
/// than the positions, leave the missing vertices' entries at zero: a zero normal shades
/// flat (the triangle's plane, as the CPU reference does); a zero tangent makes a normal map
/// use a tangent frame from the screen derivatives of position and texture coordinate;
/// a missing coordinate is (0, 0), a missing colour white.
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexAttributes<'a> {
    pub normals: &'a [Vec3],
    pub uvs: &'a [[f32; 2]],
    pub tangents: &'a [Vec4],
    pub colors: &'a [Vec4],
}

/// Interleaves positions with their attributes into vertices.
pub fn interleave(positions: &[Vec3], a: VertexAttributes) -> Vec<Vertex> {
    let normals = a.normals.iter().copied().chain(std::iter::repeat(Vec3::ZERO));
    let uvs = a.uvs.iter().copied().chain(std::iter::repeat([0.0; 2]));
    let tangents = a.tangents.iter().copied().chain(std::iter::repeat(Vec4::ZERO));
    let colors = a.colors.iter().copied().chain(std::iter::repeat(Vec4::ONE));
    positions
        .iter()
        .zip(normals)
        .zip(uvs)
        .zip(tangents)
        .zip(colors)
        .map(|((((p, n), t), g), c)| [p.x, p.y, p.z, n.x, n.y, n.z, t[0], t[1], g.x, g.y, g.z, g.w, c.x, c.y, c.z, c.w])
        .collect()
}

/// A material texture: RGBA8 texels, row by row. Colour textures (base colour, emissive) are
/// sRGB-encoded; data textures (metallic-roughness, normal maps) are `linear`.
#[derive(Clone, Debug, Default)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub linear: bool,
}

impl Texture {
    /// The mean colour in linear light of the texels with alpha >= 0.5 (sRGB decoded unless
    /// `linear`); white for a texture without any.
    pub fn mean_linear_rgb(&self) -> Vec3 {
        let decode = |c: u8| {
            let v = c as f32 / 255.0;
            if self.linear {
                v
            } else if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        let (sum, n) = self
            .rgba
            .chunks_exact(4)
            .filter(|t| t[3] >= 128)
            .fold((Vec3::ZERO, 0u32), |(s, n), t| (s + Vec3::new(decode(t[0]), decode(t[1]), decode(t[2])), n + 1));
        if n == 0 {
            Vec3::ONE
        } else {
            sum / n as f32
        }
    }
}

/// The textures a draw's material samples, each an index into the scene's textures (None:
/// the material's factor alone). glTF's metallic-roughness layout: roughness in G, metalness in
/// B; normal maps in tangent space, scaled in X and Y by `normal_scale`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    pub base_color: Option<usize>,
    pub metallic_roughness: Option<usize>,
    pub normal: Option<usize>,
    pub emissive: Option<usize>,
    pub normal_scale: f32,
}

impl MaterialTextures {
    /// A base-colour texture alone.
    pub fn base_color(k: usize) -> MaterialTextures {
        MaterialTextures { base_color: Some(k), ..Default::default() }
    }
}

/// The four sampler slots of the G-buffer pass, in binding order (`u_textures` in
/// shaders/sample/gbuffer.frag).
pub const TEXTURE_SLOTS: usize = 4;

/// Vertex and index buffers of every mesh of a scene, and its textures, in device memory.
pub struct MeshBuffers {
    /// Vertex buffer, index buffer, index count, vertex count.
    meshes: Vec<(HostBuffer, HostBuffer, u32, u32)>,
    /// What a slot samples when the material has no texture there (white colour, white data,
    /// a flat normal), then the scene's textures (scene texture k is image k + DEFAULTS).
    textures: Vec<HostImage>,
    sampler: vk::Sampler,
}

/// Default textures before the scene's: sRGB white (base colour, emissive), linear white
/// (metallic-roughness: the factors alone), a linear flat normal.
const DEFAULTS: usize = 3;

impl MeshBuffers {
    /// Vertex buffers are drawn and copied by the SDK into its BLAS inputs.
    pub const VERTEX_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
        vk::BufferUsageFlags::VERTEX_BUFFER.as_raw() | vk::BufferUsageFlags::TRANSFER_SRC.as_raw(),
    );

    /// `attributes`: one per mesh (missing meshes: none); `textures`: the scene's.
    pub fn upload(host: &Host, scene: &Scene, attributes: &[VertexAttributes], textures: &[Texture]) -> HostResult<MeshBuffers> {
        let mut buffers = MeshBuffers { meshes: Vec::new(), textures: Vec::new(), sampler: vk::Sampler::null() };
        // On an error, whatever was made so far is destroyed with the struct.
        match buffers.fill(host, scene, attributes, textures) {
            Ok(()) => Ok(buffers),
            Err(e) => {
                buffers.destroy(host);
                Err(e)
            }
        }
    }

    fn fill(&mut self, host: &Host, scene: &Scene, attributes: &[VertexAttributes], textures: &[Texture]) -> HostResult<()> {
        for (k, m) in scene.meshes.iter().enumerate() {
            let vertices = interleave(&m.positions, attributes.get(k).copied().unwrap_or_default());
            // Static geometry lives in device memory (uploaded once through a staging buffer).
            let vb = host.device_buffer_with_data(bytemuck::cast_slice(&vertices), Self::VERTEX_USAGE)?;
            let ib_usage = vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
            let ib = match host.device_buffer_with_data(bytemuck::cast_slice(&m.indices), ib_usage) {
                Ok(ib) => ib,
                Err(e) => {
                    host.destroy_buffer(vb);
                    return Err(e);
                }
            };
            self.meshes.push((vb, ib, m.indices.len() as u32, m.positions.len() as u32));
        }
        let white = Texture { width: 1, height: 1, rgba: vec![255; 4], linear: false };
        let data_white = Texture { linear: true, ..white.clone() };
        let flat = Texture { width: 1, height: 1, rgba: vec![128, 128, 255, 255], linear: true };
        for t in [&white, &data_white, &flat].into_iter().chain(textures) {
            if t.width == 0 || t.height == 0 || t.rgba.len() as u64 != t.width as u64 * t.height as u64 * 4 {
                return Err(format!("a {}x{} texture with {} bytes", t.width, t.height, t.rgba.len()));
            }
            let format = if t.linear { vk::Format::R8G8B8A8_UNORM } else { vk::Format::R8G8B8A8_SRGB };
            self.textures.push(host.image_with_data(format, t.width, t.height, vk::ImageUsageFlags::SAMPLED, &t.rgba, READ)?);
        }
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(vk::SamplerAddressMode::REPEAT)
            .address_mode_w(vk::SamplerAddressMode::REPEAT);
        // SAFETY: plain object creation; destroyed in `destroy`.
        self.sampler = unsafe { host.device.create_sampler(&info, None) }.map_err(|e| format!("sampler: {e:?}"))?;
        Ok(())
    }

    pub(crate) fn sampler(&self) -> vk::Sampler {
        self.sampler
    }

    pub(crate) fn mesh(&self, i: usize) -> (vk::Buffer, vk::Buffer, u32) {
        let (vb, ib, count, _) = &self.meshes[i];
        (vb.buffer, ib.buffer, *count)
    }

    /// Scene texture `k` as an SDK input (an alpha-tested geometry's cut-out), if it exists.
    pub fn texture_input(&self, k: usize) -> Option<hybrid_rt::ImageInput> {
        self.textures.get(k + DEFAULTS).map(|t| t.input(READ))
    }

    /// Mesh `i`'s texture coordinates inside its vertices, for an alpha-tested geometry.
    pub fn uv_input(&self, i: usize) -> hybrid_rt::VertexBufferInput {
        let (vb, _, _, vertex_count) = &self.meshes[i];
        hybrid_rt::VertexBufferInput {
            buffer: vb.buffer,
            offset: UV_OFFSET as u64,
            stride: VERTEX_STRIDE as u64,
            count: *vertex_count,
            format: vk::Format::R32G32_SFLOAT,
        }
    }

    /// The image views a draw's material samples, in slot order (the defaults where it has
    /// no texture, or an index past the scene's).
    pub(crate) fn views(&self, t: &MaterialTextures) -> [vk::ImageView; TEXTURE_SLOTS] {
        let pick = |k: Option<usize>, default: usize| {
            k.and_then(|k| self.textures.get(k + DEFAULTS)).unwrap_or(&self.textures[default]).view
        };
        [pick(t.base_color, 0), pick(t.metallic_roughness, 1), pick(t.normal, 2), pick(t.emissive, 0)]
    }

    /// The SDK's view of mesh `i`: the same buffers the rasterizer draws (RGB32F positions
    /// at the start of each vertex, u32 indices).
    pub fn geometry_input(&self, i: usize) -> hybrid_rt::GeometryInput {
        let (vb, ib, index_count, vertex_count) = &self.meshes[i];
        hybrid_rt::GeometryInput {
            vertices: hybrid_rt::VertexBufferInput {
                buffer: vb.buffer,
                count: *vertex_count,
                stride: VERTEX_STRIDE as u64,
                ..Default::default()
            },
            indices: hybrid_rt::IndexBufferInput { buffer: ib.buffer, count: *index_count, ..Default::default() },
            ..Default::default()
        }
    }

    pub fn destroy(self, host: &Host) {
        for (v, i, _, _) in self.meshes {
            host.destroy_buffer(v);
            host.destroy_buffer(i);
        }
        for t in self.textures {
            host.destroy_image(t);
        }
        // SAFETY: the frames that sampled with it are finished (the caller's rule); a null
        // sampler (a failed upload) is ignored.
        unsafe { host.device.destroy_sampler(self.sampler, None) };
    }
}
