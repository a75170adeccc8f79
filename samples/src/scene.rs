//! What the sample renders: triangle meshes and their instances (the test kit's `Scene`), one
//! material per instance, what moves, the lights, and the camera path of a headless run.
//! Built by `scenes::cornell_room` or loaded from glTF (`gltf_scene`).
use crate::lighting::Lights;
use crate::raster::{Material, MaterialTextures, Texture, VertexAttributes};
use crate::skin::Rig;
use glam::{Affine3A, Quat, Vec3, Vec4};
use hybrid_rt_host::scene::{Camera, Scene};

/// How an instance moves over time (seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    Static,
    /// Circles `center` at `radius` once every `period` seconds, spinning as it goes.
    Orbit {
        center: Vec3,
        radius: f32,
        period: f32,
    },
    /// Where node `n` of the scene's rig is (an animated glTF node).
    Node(usize),
}

/// A mesh whose vertices move every frame (cloth, skinning): its BLAS is refit each frame.
#[derive(Clone, Debug)]
pub struct Deformer {
    /// The instance that shows it (its mesh is the deformed one).
    pub instance: usize,
    /// Vertex positions at rest.
    pub rest: Vec<Vec3>,
    /// Largest displacement along the mesh's normal (+Z of the rest mesh).
    pub amplitude: f32,
}

impl Deformer {
    /// A travelling wave across the mesh, pinned along its left edge (a flag).
    pub fn positions(&self, time: f32) -> Vec<Vec3> {
        let min_x = self.rest.iter().map(|p| p.x).fold(f32::INFINITY, f32::min);
        self.rest
            .iter()
            .map(|p| {
                let along = p.x - min_x;
                let wave = (along * 4.0 - time * 3.0).sin() + 0.4 * (p.y * 3.0 + time * 1.7).sin();
                *p + Vec3::Z * (self.amplitude * along.min(1.0) * wave)
            })
            .collect()
    }
}

/// An alpha-tested mesh's holes: where its texture's alpha is below `cutoff`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutout {
    pub texture: usize,
    /// In [0, 1].
    pub cutoff: f32,
}

/// A camera moving from `from` to `to` (eye positions) while looking at `target`.
#[derive(Clone, Copy, Debug)]
pub struct CameraPath {
    pub from: Vec3,
    pub to: Vec3,
    pub target: Vec3,
    /// The camera's up (a glTF camera's roll); Y for the built-in paths.
    pub up: Vec3,
    pub fov_y_radians: f32,
}

impl CameraPath {
    /// The camera at `u` in [0, 1] along the path (eased at both ends).
    pub fn at(&self, u: f32) -> Camera {
        let s = u.clamp(0.0, 1.0);
        let s = s * s * (3.0 - 2.0 * s);
        let eye = self.from.lerp(self.to, s);
        let far = (self.to - self.target).length().max((self.from - self.target).length()) * 20.0;
        let near = ((eye - self.target).length() * 0.01).min(0.05);
        Camera { fov_y_radians: self.fov_y_radians, near, far: far.max(100.0), up: self.up, ..Camera::look_at(eye, self.target) }
    }
}

/// Everything the sample draws and traces.
pub struct SampleScene {
    pub name: String,
    pub scene: Scene,
    /// Shading normals, one list per mesh of `scene` (one per vertex): the file's where it has
    /// them, else [`vertex_normals`]. (The deforming mesh's are recomputed every frame.)
    pub normals: Vec<Vec<Vec3>>,
    /// Texture coordinates, one list per mesh (empty: none), for `textures`.
    pub uvs: Vec<Vec<[f32; 2]>>,
    /// Tangents (xyz, bitangent sign), one list per mesh: the file's where it has them (empty:
    /// none; normal maps then take their frame from screen derivatives).
    pub tangents: Vec<Vec<Vec4>>,
    /// Vertex colours (linear RGBA, glTF's `COLOR_0`), one list per mesh (empty: white).
    pub colors: Vec<Vec<Vec4>>,
    /// Material textures, and which each instance's material samples (one per instance, or
    /// empty: none).
    pub textures: Vec<Texture>,
    pub material_textures: Vec<MaterialTextures>,
    /// Alpha-tested meshes (foliage, glTF's `MASK` materials): per mesh, the texture and
    /// cutoff that cut it, in the raster pass and in every ray the SDK traces (one per mesh,
    /// or empty).
    pub cutouts: Vec<Option<Cutout>>,
    /// One per instance of `scene`.
    pub materials: Vec<Material>,
    /// One per instance of `scene`.
    pub motions: Vec<Motion>,
    pub deformer: Option<Deformer>,
    /// Animated nodes and skinned meshes (empty: none).
    pub rig: Rig,
    pub lights: Lights,
    /// The file's own lights (glTF `KHR_lights_punctual`; empty for the built-in scenes): up
    /// to the SDK's 32 shadowed lights, shaded by the lighting pass and shadowed through one
    /// multi-light shadow task and its denoiser. Where there are any, `lights`' sun and point
    /// light are off (intensity 0).
    pub file_lights: Vec<hybrid_rt::LightInfo>,
    /// Angular diameter of the sun (radians) and radius of the point light (world units): the
    /// SDK's shadow rays sample them, so penumbrae widen with distance to the occluder.
    pub sun_angular_extent: f32,
    pub point_radius: f32,
    /// Radiance of GI and reflection rays that leave the scene.
    pub sky: [f32; 3],
    pub camera_path: CameraPath,
    /// The file's own cameras (glTF perspective cameras), as still paths: `--camera N` picks
    /// one instead of `camera_path`.
    pub file_cameras: Vec<CameraPath>,
    /// Where the low-resolution "lidar" camera sits while it sweeps the scene.
    pub lidar_eye: Vec3,
    /// Surfel tile size (world units) for every geometry.
    pub tile_unit_length: f32,
    /// Longest AO ray (world units).
    pub ao_ray_length: f32,
    /// What the loader could not draw as the file says — a feature it does not read, a value
    /// it changed — one line each, what it did instead in brackets (empty for the built-in
    /// scenes).
    pub warnings: Vec<String>,
}

impl SampleScene {
    /// A scene of untextured meshes (smooth normals computed), one material and motion per
    /// instance, seen along `camera_path` and lit by `lights`; nothing deforms. The built-in
    /// scenes start here and set what differs.
    pub fn of_meshes(
        name: &str,
        scene: Scene,
        materials: Vec<Material>,
        motions: Vec<Motion>,
        lights: Lights,
        camera_path: CameraPath,
    ) -> SampleScene {
        SampleScene {
            name: name.into(),
            normals: scene.meshes.iter().map(|m| vertex_normals(&m.positions, &m.indices)).collect(),
            scene,
            uvs: Vec::new(),
            tangents: Vec::new(),
            colors: Vec::new(),
            textures: Vec::new(),
            material_textures: Vec::new(),
            cutouts: Vec::new(),
            materials,
            motions,
            deformer: None,
            rig: Rig::default(),
            lights,
            file_lights: Vec::new(),
            sun_angular_extent: 0.03,
            point_radius: 0.1,
            sky: [0.35, 0.45, 0.6],
            camera_path,
            file_cameras: Vec::new(),
            lidar_eye: camera_path.target,
            tile_unit_length: 0.1,
            ao_ray_length: 0.5,
            warnings: Vec::new(),
        }
    }

    /// Instance `i`'s diffuse albedo as the SDK's relighting and hit lighting take it
    /// (`InstanceInput::albedo`): its material's albedo x (1 - metalness) (metals have no
    /// diffuse) — a tint of the base-colour texture its geometry hands the SDK
    /// (`mesh_albedo_texture`) — or, when its material's texture is not its geometry's, times
    /// that texture's mean (in linear light); times the mean of its mesh's vertex colours.
    pub fn diffuse_albedo(&self, i: usize) -> [f32; 3] {
        let Some(m) = self.materials.get(i) else { return [0.5; 3] };
        let own = self.material_textures.get(i).and_then(|t| t.base_color);
        let mesh = self.scene.instances.get(i).map(|inst| inst.mesh);
        let mean = match own {
            Some(k) if mesh.and_then(|k| self.mesh_albedo_texture(k)) != Some(k) => {
                self.textures.get(k).map_or(Vec3::ONE, |t| t.mean_linear_rgb())
            }
            _ => Vec3::ONE,
        };
        // The SDK takes no per-vertex colour: a mesh's vertex colours tint it by their mean.
        let colors = mesh.and_then(|k| self.colors.get(k)).filter(|c| !c.is_empty());
        let tint = colors.map_or(Vec3::ONE, |c| c.iter().map(|v| v.truncate()).sum::<Vec3>() / c.len() as f32);
        let a = Vec3::from(m.albedo) * (1.0 - m.metalness.clamp(0.0, 1.0)) * mean * tint;
        a.clamp(Vec3::ZERO, Vec3::ONE).to_array()
    }

    /// The base-colour texture mesh `k` hands the SDK (`GeometryInput::albedo_texture`): that
    /// of the material of the first instance that draws it.
    pub fn mesh_albedo_texture(&self, k: usize) -> Option<usize> {
        let i = self.scene.instances.iter().position(|inst| inst.mesh == k)?;
        self.material_textures.get(i).and_then(|t| t.base_color)
    }

    /// Instance `i`'s emitted radiance as relighting and hit lighting take it: its material's
    /// emissive factor x the mean of its emissive texture (in linear light).
    pub fn emission(&self, i: usize) -> [f32; 3] {
        let Some(m) = self.materials.get(i) else { return [0.0; 3] };
        let texture = self.material_textures.get(i).and_then(|t| t.emissive).and_then(|k| self.textures.get(k));
        let mean = texture.map_or(Vec3::ONE, |t| t.mean_linear_rgb());
        (Vec3::from(m.emissive) * mean).max(Vec3::ZERO).to_array()
    }

    /// Mesh `k`'s normals, texture coordinates and tangents (what `MeshBuffers` interleaves).
    pub fn vertex_attributes(&self, k: usize) -> VertexAttributes<'_> {
        fn of<T>(lists: &[Vec<T>], k: usize) -> &[T] {
            lists.get(k).map_or(&[][..], |l| l.as_slice())
        }
        VertexAttributes {
            normals: of(&self.normals, k),
            uvs: of(&self.uvs, k),
            tangents: of(&self.tangents, k),
            colors: of(&self.colors, k),
        }
    }

    /// Every instance's transform at `time` seconds (the rig posed once).
    pub fn transforms(&self, time: f32) -> Vec<Affine3A> {
        self.transforms_posed(time, &self.rig.pose(time))
    }

    /// Every instance's transform at `time` seconds, the rig's nodes at `pose`
    /// (`rig.pose(time)`, computed once a frame for the instances and the skinning alike).
    pub fn transforms_posed(&self, time: f32, pose: &[glam::Mat4]) -> Vec<Affine3A> {
        (0..self.scene.instances.len())
            .map(|i| match self.motions[i] {
                Motion::Node(n) => Affine3A::from_mat4(pose.get(n).copied().unwrap_or(glam::Mat4::IDENTITY)),
                _ => self.transform(i, time),
            })
            .collect()
    }

    /// The transform of instance `i` at `time` seconds.
    pub fn transform(&self, i: usize, time: f32) -> Affine3A {
        let rest = self.scene.instances[i].transform;
        match self.motions[i] {
            Motion::Static => rest,
            Motion::Node(n) => self.rig.node_transform(n, time),
            Motion::Orbit { center, radius, period } => {
                let a = std::f32::consts::TAU * time / period;
                let offset = Vec3::new(a.cos(), 0.0, a.sin()) * radius;
                Affine3A::from_rotation_translation(Quat::from_rotation_y(-2.0 * a), center + offset)
            }
        }
    }

    /// The scene as it stands at `time`: moved instances, the deformed mesh (what a frame
    /// at `time` rasterizes and the SDK traces; tests trace it on the CPU).
    pub fn at(&self, time: f32) -> Scene {
        let mut s = self.scene.clone();
        let pose = self.rig.pose(time);
        for (inst, t) in s.instances.iter_mut().zip(self.transforms_posed(time, &pose)) {
            inst.transform = t;
        }
        if let Some(d) = &self.deformer {
            let mesh = s.instances[d.instance].mesh;
            s.meshes[mesh].positions = d.positions(time);
        }
        for m in &self.rig.skinned {
            s.meshes[m.mesh].positions = self.rig.deform_positions(m, time, &pose, &self.scene.meshes[m.mesh].positions);
        }
        s
    }

    /// Whether mesh `k` changes shape over time (the flag, a skinned mesh): its BLAS is refit.
    pub fn is_deforming(&self, k: usize) -> bool {
        self.deformer.as_ref().is_some_and(|d| self.scene.instances[d.instance].mesh == k)
            || self.rig.skinned.iter().any(|m| m.mesh == k)
    }

    /// Whether instance `i` moves (its transform changes over time).
    pub fn is_dynamic(&self, i: usize) -> bool {
        self.motions[i] != Motion::Static
    }

    /// Axis-aligned bounds of every instance at rest.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for inst in &self.scene.instances {
            for p in &self.scene.meshes[inst.mesh].positions {
                let w = inst.transform.transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
            }
        }
        (lo, hi)
    }
}

/// Smooth shading normals of a mesh: per vertex, the area-weighted mean of the normals of the
/// triangles that share it — and of those of other vertices at the same position whose own
/// normals are within 60 degrees of its own. So a UV sphere's seam and its poles (one vertex
/// per segment there, each touching one thin triangle: 7 degrees off on a 12-ring sphere)
/// shade as the rest of it, while a cuboid's corners (three vertices, 90 degrees apart) keep
/// their faces flat. A vertex no triangle uses, or one where they cancel, gets +Y.
pub fn vertex_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let own = area_weighted_normals(positions, indices);
    let mut at: std::collections::HashMap<[u32; 3], Vec<usize>> = std::collections::HashMap::new();
    for (v, p) in positions.iter().enumerate() {
        at.entry(p.to_array().map(f32::to_bits)).or_default().push(v);
    }
    let crease = 60f32.to_radians().cos();
    (0..positions.len())
        .map(|v| {
            let unit = own[v].try_normalize().unwrap_or(Vec3::Y);
            let same = &at[&positions[v].to_array().map(f32::to_bits)];
            let sum: Vec3 =
                same.iter().map(|&u| own[u]).filter(|n| n.try_normalize().is_some_and(|n| n.dot(unit) >= crease)).sum();
            sum.try_normalize().unwrap_or(unit)
        })
        .collect()
}

/// Per vertex, the sum of its triangles' normals, each as long as twice its area.
fn area_weighted_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut sum = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
        if a >= positions.len() || b >= positions.len() || c >= positions.len() {
            continue;
        }
        // The cross product's length is twice the area: the weighting.
        let n = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        for v in [a, b, c] {
            sum[v] += n;
        }
    }
    sum
}
