//! The triangle scenes the sample renders and the test kit's reference renderer traces: meshes
//! (positions and indices) with a few builders, instances of them, a camera in Vulkan's clip
//! conventions, and a small random number generator for scenes made in code.
use glam::{Affine3A, Mat4, Vec3};

#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// An `n`x`n`-cell grid in the XZ plane, centred, facing +Y, `size` wide.
    pub fn grid(size: f32, n: u32) -> Mesh {
        let mut m = Mesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let u = i as f32 / n as f32 - 0.5;
                let v = j as f32 / n as f32 - 0.5;
                m.positions.push(Vec3::new(u * size, 0.0, v * size));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = j * (n + 1) + i;
                let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
                // Counter-clockwise seen from +Y.
                m.indices.extend_from_slice(&[a, c, b, b, c, d]);
            }
        }
        m
    }

    pub fn quad(size: f32) -> Mesh {
        Mesh::grid(size, 1)
    }

    /// A closed axis-aligned box with outward faces.
    pub fn cuboid(half: Vec3) -> Mesh {
        let mut m = Mesh::default();
        let faces: [(Vec3, Vec3, Vec3); 6] = [
            (Vec3::X, Vec3::Y, Vec3::Z),
            (Vec3::NEG_X, Vec3::Z, Vec3::Y),
            (Vec3::Y, Vec3::Z, Vec3::X),
            (Vec3::NEG_Y, Vec3::X, Vec3::Z),
            (Vec3::Z, Vec3::X, Vec3::Y),
            (Vec3::NEG_Z, Vec3::Y, Vec3::X),
        ];
        for (n, u, v) in faces {
            let base = m.positions.len() as u32;
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                m.positions.push((n + u * su + v * sv) * half);
            }
            // Orient each triangle so its normal is n.
            let (a, b, c) = (m.positions[base as usize], m.positions[base as usize + 1], m.positions[base as usize + 2]);
            if (b - a).cross(c - a).dot(n) > 0.0 {
                m.indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
            } else {
                m.indices.extend_from_slice(&[base, base + 2, base + 1, base, base + 3, base + 2]);
            }
        }
        m
    }

    /// A UV sphere of `radius` around the origin.
    pub fn sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
        let mut m = Mesh::default();
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
                m.positions.push(radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
            }
        }
        for r in 0..rings {
            for s in 0..segments {
                let a = r * (segments + 1) + s;
                let (b, c, d) = (a + 1, a + segments + 1, a + segments + 2);
                m.indices.extend_from_slice(&[a, b, c, b, d, c]);
            }
        }
        m
    }
}

#[derive(Clone, Copy, Debug)]
pub struct SceneInstance {
    pub mesh: usize,
    pub transform: Affine3A,
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub meshes: Vec<Mesh>,
    pub instances: Vec<SceneInstance>,
}

impl Scene {
    pub fn add_mesh(&mut self, m: Mesh) -> usize {
        self.meshes.push(m);
        self.meshes.len() - 1
    }
    pub fn add_instance(&mut self, mesh: usize, transform: Affine3A) -> usize {
        self.instances.push(SceneInstance { mesh, transform });
        self.instances.len() - 1
    }
    pub fn triangle_count(&self) -> usize {
        self.instances.iter().map(|i| self.meshes[i.mesh].triangle_count()).sum()
    }
}

#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_y_radians: f32,
    pub near: f32,
    pub far: f32,
}

impl Camera {
    pub fn look_at(eye: Vec3, target: Vec3) -> Camera {
        Camera { eye, target, up: Vec3::Y, fov_y_radians: 60f32.to_radians(), near: 0.05, far: 100.0 }
    }

    pub fn world_to_view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up)
    }

    /// Vulkan clip space: y down, depth 0 (near) .. 1 (far).
    pub fn view_to_clip(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::vulkan::perspective(self.fov_y_radians, aspect, self.near, self.far)
    }

    pub fn sdk_camera(&self, width: u32, height: u32) -> hybrid_rt::Camera {
        hybrid_rt::Camera { world_to_view: self.world_to_view(), view_to_clip: self.view_to_clip(width as f32 / height as f32) }
    }
}

/// SplitMix64: a small, good generator for procedural scenes and the reference's sample points.
pub struct Rng(u64);
impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}
