//! The built-in animated scene: a blocky figure waving on a floor before a wall, one skinned
//! mesh on five joints (hips, shoulders, elbows) whose animation turns the body and waves the
//! right arm while the left swings. The arms are tubes whose vertices blend between shoulder
//! and elbow across the elbow, so they bend smoothly: every frame the skinning pass rewrites
//! the figure's vertices and the SDK refits its BLAS — the case hybrid ray tracers worry about
//! most (characters whose acceleration structures change every frame).
use crate::lighting::Lights;
use crate::raster::Material;
use crate::scene::{CameraPath, Motion, SampleScene};
use crate::skin::{Channel, Interpolation, Node, Property, Rig, Skin, SkinnedMesh};
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};
use hybrid_rt_host::scene::{Mesh, Scene};

/// The joints: hips (the root), right shoulder and elbow, left shoulder and elbow.
const HIPS: usize = 0;
const RIGHT_SHOULDER: usize = 1;
const RIGHT_ELBOW: usize = 2;
const LEFT_SHOULDER: usize = 3;
const LEFT_ELBOW: usize = 4;
/// Upper arm and forearm lengths; the arms' radius; the half-width of the elbow's blend.
const UPPER_ARM: f32 = 0.32;
const FOREARM: f32 = 0.3;
const ARM_RADIUS: f32 = 0.065;
const ELBOW_BLEND: f32 = 0.06;

/// A mesh being built with each vertex's joints and weights.
#[derive(Default)]
struct Builder {
    positions: Vec<Vec3>,
    indices: Vec<u32>,
    joints: Vec<[u32; 4]>,
    weights: Vec<[f32; 4]>,
}

impl Builder {
    /// A box around `center`, rigid on `joint`.
    fn cuboid(&mut self, center: Vec3, half: Vec3, joint: u32) {
        let m = Mesh::cuboid(half);
        let base = self.positions.len() as u32;
        self.positions.extend(m.positions.iter().map(|p| *p + center));
        self.indices.extend(m.indices.iter().map(|i| i + base));
        self.joints.extend(std::iter::repeat_n([joint, 0, 0, 0], m.positions.len()));
        self.weights.extend(std::iter::repeat_n([1.0, 0.0, 0.0, 0.0], m.positions.len()));
    }

    /// A closed tube from `start` along `dir` (unit), upper arm on `shoulder`, forearm on
    /// `elbow`, blended across the elbow.
    fn arm(&mut self, start: Vec3, dir: Vec3, shoulder: u32, elbow: u32) {
        const SEGMENTS: u32 = 10;
        const RINGS: u32 = 24;
        let length = UPPER_ARM + FOREARM;
        let (u, v) = dir.any_orthonormal_pair();
        let base = self.positions.len() as u32;
        for r in 0..=RINGS {
            let s = length * r as f32 / RINGS as f32;
            // Weight of the forearm: 0 before the blend, 1 after it.
            let w = ((s - (UPPER_ARM - ELBOW_BLEND)) / (2.0 * ELBOW_BLEND)).clamp(0.0, 1.0);
            for k in 0..SEGMENTS {
                let a = std::f32::consts::TAU * k as f32 / SEGMENTS as f32;
                self.positions.push(start + dir * s + (u * a.cos() + v * a.sin()) * ARM_RADIUS);
                self.joints.push([shoulder, elbow, 0, 0]);
                self.weights.push([1.0 - w, w, 0.0, 0.0]);
            }
        }
        for r in 0..RINGS {
            for k in 0..SEGMENTS {
                let (a, b) = (base + r * SEGMENTS + k, base + r * SEGMENTS + (k + 1) % SEGMENTS);
                let (c, d) = (a + SEGMENTS, b + SEGMENTS);
                self.indices.extend([a, c, b, b, c, d]);
            }
        }
        // Caps: a fan at each end around its ring's first vertex.
        for (ring, flip) in [(0, true), (RINGS, false)] {
            let first = base + ring * SEGMENTS;
            for k in 1..SEGMENTS - 1 {
                let (b, c) = (first + k, first + k + 1);
                self.indices.extend(if flip { [first, c, b] } else { [first, b, c] });
            }
        }
    }
}

/// A linear channel of rotations about `axis` (radians at each time).
fn turn(node: usize, axis: Vec3, keys: &[(f32, f32)]) -> Channel {
    Channel {
        node,
        property: Property::Rotation,
        interpolation: Interpolation::Linear,
        times: keys.iter().map(|k| k.0).collect(),
        values: keys.iter().map(|k| Vec4::from(Quat::from_axis_angle(axis, k.1))).collect(),
    }
}

/// The waving figure's scene.
pub fn waving_figure() -> SampleScene {
    let mut scene = Scene::default();
    let mut materials = Vec::new();
    let matte = |albedo: [f32; 3]| Material { albedo, roughness: 0.85, ..Default::default() };
    let floor = scene.add_mesh(Mesh::grid(24.0, 24));
    scene.add_instance(floor, Affine3A::IDENTITY);
    materials.push(Material { albedo: [0.45, 0.42, 0.4], roughness: 0.3, ..Default::default() });
    let wall = scene.add_mesh(Mesh::grid(24.0, 24));
    let quarter = std::f32::consts::FRAC_PI_2;
    scene.add_instance(
        wall,
        Affine3A::from_scale_rotation_translation(
            Vec3::new(1.0, 1.0, 1.0 / 6.0),
            Quat::from_rotation_x(quarter),
            Vec3::new(0.0, 2.0, -1.5),
        ),
    );
    materials.push(matte([0.72, 0.7, 0.66]));

    // The figure in its bind pose (arms straight out), joints at their rest places.
    let hips = Vec3::new(0.0, 0.95, 0.0);
    let shoulder_offset = Vec3::new(0.3, 0.5, 0.0);
    let nodes = vec![
        Node::new(None, hips, Quat::IDENTITY),
        Node::new(Some(HIPS), shoulder_offset, Quat::IDENTITY),
        Node::new(Some(RIGHT_SHOULDER), Vec3::X * UPPER_ARM, Quat::IDENTITY),
        Node::new(Some(HIPS), shoulder_offset * Vec3::new(-1.0, 1.0, 1.0), Quat::IDENTITY),
        Node::new(Some(LEFT_SHOULDER), Vec3::NEG_X * UPPER_ARM, Quat::IDENTITY),
    ];
    let mut body = Builder::default();
    body.cuboid(hips + Vec3::new(0.0, 0.25, 0.0), Vec3::new(0.24, 0.32, 0.13), HIPS as u32);
    body.cuboid(hips + Vec3::new(0.0, 0.78, 0.0), Vec3::new(0.12, 0.14, 0.12), HIPS as u32);
    for side in [-1.0, 1.0] {
        body.cuboid(Vec3::new(0.12 * side, 0.47, 0.0), Vec3::new(0.08, 0.47, 0.09), HIPS as u32);
    }
    let right = hips + shoulder_offset;
    let left = hips + shoulder_offset * Vec3::new(-1.0, 1.0, 1.0);
    body.arm(right, Vec3::X, RIGHT_SHOULDER as u32, RIGHT_ELBOW as u32);
    body.arm(left, Vec3::NEG_X, LEFT_SHOULDER as u32, LEFT_ELBOW as u32);
    let figure = scene.add_mesh(Mesh { positions: body.positions, indices: body.indices });
    // A skinned mesh's instance stays at the identity: its joints place it.
    scene.add_instance(figure, Affine3A::IDENTITY);
    materials.push(Material { albedo: [0.85, 0.5, 0.25], roughness: 0.45, ..Default::default() });

    let mut rig = Rig { nodes, ..Default::default() };
    // Inverse bind matrices: the joints' world transforms at rest, inverted.
    let rest = rig.pose(0.0);
    rig.skins.push(Skin { joints: (0..rig.nodes.len()).collect(), inverse_bind: rest.iter().map(Mat4::inverse).collect() });
    rig.skinned.push(SkinnedMesh { mesh: figure, skin: Some(0), joints: body.joints, weights: body.weights, morph: None });
    let deg = |d: f32| d.to_radians();
    rig.channels = vec![
        // The body turns a little towards the camera path and back.
        turn(HIPS, Vec3::Y, &[(0.0, deg(-15.0)), (1.0, deg(15.0)), (2.0, deg(-15.0))]),
        // The right arm raised, its forearm waving.
        turn(RIGHT_SHOULDER, Vec3::Z, &[(0.0, deg(40.0)), (1.0, deg(50.0)), (2.0, deg(40.0))]),
        turn(RIGHT_ELBOW, Vec3::Z, &[(0.0, deg(20.0)), (0.5, deg(80.0)), (1.0, deg(20.0)), (1.5, deg(80.0)), (2.0, deg(20.0))]),
        // The left arm hangs and swings, bent a little.
        turn(LEFT_SHOULDER, Vec3::Z, &[(0.0, deg(70.0)), (1.0, deg(55.0)), (2.0, deg(70.0))]),
        turn(LEFT_ELBOW, Vec3::X, &[(0.0, deg(-10.0)), (1.0, deg(-35.0)), (2.0, deg(-10.0))]),
    ];
    let motions = vec![Motion::Static; scene.instances.len()];
    let lights = Lights {
        sun_direction: Vec3::new(0.5, 1.0, 0.45),
        sun_intensity: 2.5,
        point_position: Vec3::new(-1.2, 2.2, 1.0),
        point_intensity: 2.0,
        ambient: 0.0,
    };
    let camera_path = CameraPath {
        from: Vec3::new(-1.6, 1.6, 3.2),
        to: Vec3::new(1.6, 1.4, 3.2),
        target: Vec3::new(0.0, 1.1, 0.0),
        up: Vec3::Y,
        fov_y_radians: 55f32.to_radians(),
    };
    SampleScene {
        rig,
        lidar_eye: Vec3::new(0.0, 2.0, 1.5),
        tile_unit_length: 0.05,
        ..SampleScene::of_meshes("waving figure", scene, materials, motions, lights, camera_path)
    }
}
