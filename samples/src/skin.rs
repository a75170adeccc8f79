//! Skeletal animation as glTF describes it: a node hierarchy with rest transforms, animations
//! whose channels drive a node's translation, rotation, scale or morph-target weights (step,
//! linear or cubic-spline keyframes, played in a loop), skins (joint nodes and inverse bind
//! matrices) that bend meshes by up to four weighted joints per vertex, and morph targets
//! (per-vertex displacements blended by weights) applied before the skin. The sample poses the
//! hierarchy on the CPU each frame (a few matrices and weights), deforms on the GPU
//! (`skinning`), and keeps a CPU deformation of the same mesh for the tests' reference renders.
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};

/// One node: its parent and its transform at rest.
#[derive(Clone, Debug)]
pub struct Node {
    pub parent: Option<usize>,
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Node {
    pub fn new(parent: Option<usize>, translation: Vec3, rotation: Quat) -> Node {
        Node { parent, translation, rotation, scale: Vec3::ONE }
    }
}

/// What a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
    /// Morph-target weights `first..first + 4` of the node's mesh (glTF's `weights` path, four
    /// targets to a channel: the values' xyzw).
    Weights {
        first: u32,
    },
}

/// How a channel's keyframes are interpolated (glTF's `interpolation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Hermite splines; each keyframe holds an in-tangent, a value and an out-tangent.
    CubicSpline,
}

/// One animated property of one node. Values are xyz(w): rotations are quaternions (x, y, z,
/// w), translations and scales leave w at 0. Cubic splines hold three values per keyframe
/// (in-tangent, value, out-tangent).
#[derive(Clone, Debug)]
pub struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    pub times: Vec<f32>,
    pub values: Vec<Vec4>,
}

impl Channel {
    /// The value at `t` seconds (clamped to the first and last keyframes).
    pub fn sample(&self, t: f32) -> Vec4 {
        let n = self.times.len();
        let per_key = if self.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
        let value = |k: usize| self.values[k * per_key + per_key / 2];
        if n == 0 || self.values.len() < n * per_key {
            return Vec4::ZERO;
        }
        if n == 1 || t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        // The keyframe at or before t.
        let k = self.times.partition_point(|&key| key <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let td = t1 - t0;
        let s = if td > 0.0 { (t - t0) / td } else { 0.0 };
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if rotation => {
                let (a, b) = (Quat::from_vec4(value(k)).normalize(), Quat::from_vec4(value(k + 1)).normalize());
                Vec4::from(a.slerp(b, s))
            }
            Interpolation::Linear => value(k).lerp(value(k + 1), s),
            Interpolation::CubicSpline => {
                let (v0, b0) = (self.values[3 * k + 1], self.values[3 * k + 2]);
                let (a1, v1) = (self.values[3 * (k + 1)], self.values[3 * (k + 1) + 1]);
                let (s2, s3) = (s * s, s * s * s);
                let p = v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + b0 * (td * (s3 - 2.0 * s2 + s))
                    + v1 * (-2.0 * s3 + 3.0 * s2)
                    + a1 * (td * (s3 - s2));
                if rotation {
                    p.normalize_or_zero()
                } else {
                    p
                }
            }
        }
    }
}

/// A skin: its joints (nodes) and each joint's inverse bind matrix.
#[derive(Clone, Debug)]
pub struct Skin {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
}

/// A mesh deformed on the GPU every frame: by morph targets, then by a skin. With a skin,
/// per vertex, four joints (indices into the skin's joint list) and their weights, and its
/// instance's transform is ignored (glTF: a skinned mesh lives where its joints put it);
/// without one (morph targets alone) its instance keeps its node's transform.
#[derive(Clone, Debug)]
pub struct SkinnedMesh {
    pub mesh: usize,
    pub skin: Option<usize>,
    pub joints: Vec<[u32; 4]>,
    pub weights: Vec<[f32; 4]>,
    pub morph: Option<Morph>,
}

/// Morph targets: displacements of every vertex, blended by weights — the node's (or mesh's)
/// defaults, which `Property::Weights` channels of `node` animate.
#[derive(Clone, Debug, Default)]
pub struct Morph {
    pub node: usize,
    pub targets: Vec<MorphTarget>,
    /// One per target.
    pub weights: Vec<f32>,
}

/// One target's displacements, one per vertex (empty: the attribute does not move).
#[derive(Clone, Debug, Default)]
pub struct MorphTarget {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub tangents: Vec<Vec3>,
}

/// The scene's nodes, what animates them and what they bend.
#[derive(Clone, Debug, Default)]
pub struct Rig {
    pub nodes: Vec<Node>,
    pub channels: Vec<Channel>,
    pub skins: Vec<Skin>,
    pub skinned: Vec<SkinnedMesh>,
}

impl Rig {
    /// The length of one loop of the animation (the last keyframe of any channel).
    pub fn duration(&self) -> f32 {
        self.channels.iter().filter_map(|c| c.times.last().copied()).fold(0.0, f32::max)
    }

    /// Every node's world transform at `time` seconds (the animation looped). Parents before
    /// children is not assumed: each node's world matrix is built from its chain.
    pub fn pose(&self, time: f32) -> Vec<Mat4> {
        let duration = self.duration();
        let t = if duration > 0.0 { time.rem_euclid(duration) } else { 0.0 };
        let mut local: Vec<(Vec3, Quat, Vec3)> = self.nodes.iter().map(|n| (n.translation, n.rotation, n.scale)).collect();
        let count = local.len();
        for c in self.channels.iter().filter(|c| c.node < count) {
            let v = c.sample(t);
            let l = &mut local[c.node];
            match c.property {
                Property::Translation => l.0 = v.truncate(),
                Property::Rotation => l.1 = Quat::from_vec4(v).normalize(),
                Property::Scale => l.2 = v.truncate(),
                Property::Weights { .. } => {}
            }
        }
        let mut world: Vec<Option<Mat4>> = vec![None; self.nodes.len()];
        for i in 0..self.nodes.len() {
            // The chain up to a node already known (hierarchies are acyclic: the loader checks).
            let mut chain = vec![i];
            while let Some(p) = self.nodes[*chain.last().unwrap()].parent.filter(|&p| world[p].is_none()) {
                if chain.len() > self.nodes.len() {
                    break;
                }
                chain.push(p);
            }
            while let Some(n) = chain.pop() {
                if world[n].is_some() {
                    continue;
                }
                let (t, r, s) = local[n];
                let m = Mat4::from_scale_rotation_translation(s, r, t);
                world[n] = Some(match self.nodes[n].parent.and_then(|p| world[p]) {
                    Some(parent) => parent * m,
                    None => m,
                });
            }
        }
        world.into_iter().map(|m| m.unwrap_or(Mat4::IDENTITY)).collect()
    }

    /// `morph`'s weights at `time` seconds (the animation looped): its defaults where no
    /// channel drives them.
    pub fn morph_weights(&self, morph: &Morph, time: f32) -> Vec<f32> {
        let duration = self.duration();
        let t = if duration > 0.0 { time.rem_euclid(duration) } else { 0.0 };
        let mut w = morph.weights.clone();
        for c in self.channels.iter().filter(|c| c.node == morph.node) {
            if let Property::Weights { first } = c.property {
                let v = c.sample(t).to_array();
                for (k, x) in v.into_iter().enumerate() {
                    if let Some(slot) = w.get_mut(first as usize + k) {
                        *slot = x;
                    }
                }
            }
        }
        w
    }

    /// `rest` displaced by `morph`'s targets at `weights`: what the GPU computes first.
    pub fn morph_positions(morph: &Morph, weights: &[f32], rest: &[Vec3]) -> Vec<Vec3> {
        let mut out = rest.to_vec();
        for (target, &w) in morph.targets.iter().zip(weights) {
            for (p, d) in out.iter_mut().zip(&target.positions) {
                *p += w * *d;
            }
        }
        out
    }

    /// Mesh `m`'s positions at `time` (`pose` the rig's nodes then): `rest` displaced by its
    /// morph targets, then bent by its skin.
    pub fn deform_positions(&self, m: &SkinnedMesh, time: f32, pose: &[Mat4], rest: &[Vec3]) -> Vec<Vec3> {
        let morphed = match &m.morph {
            Some(morph) => Rig::morph_positions(morph, &self.morph_weights(morph, time), rest),
            None => rest.to_vec(),
        };
        match m.skin {
            Some(skin) => Rig::skin_positions(m, &self.joint_matrices(skin, pose), &morphed),
            None => morphed,
        }
    }

    /// Skin `skin`'s joint matrices for the node transforms `pose`: joint world x inverse bind.
    pub fn joint_matrices(&self, skin: usize, pose: &[Mat4]) -> Vec<Mat4> {
        let s = &self.skins[skin];
        s.joints
            .iter()
            .enumerate()
            .map(|(j, &node)| {
                pose.get(node).copied().unwrap_or(Mat4::IDENTITY) * s.inverse_bind.get(j).copied().unwrap_or(Mat4::IDENTITY)
            })
            .collect()
    }

    /// `rest` (the mesh's positions) bent by `m` at `joints`: what the GPU skinning computes.
    pub fn skin_positions(m: &SkinnedMesh, joints: &[Mat4], rest: &[Vec3]) -> Vec<Vec3> {
        rest.iter()
            .enumerate()
            .map(|(v, &p)| {
                let blend = blend_matrix(
                    joints,
                    m.joints.get(v).copied().unwrap_or_default(),
                    m.weights.get(v).copied().unwrap_or([1.0, 0.0, 0.0, 0.0]),
                );
                blend.transform_point3(p)
            })
            .collect()
    }

    /// Node `n`'s world transform at `time` as an instance's.
    pub fn node_transform(&self, n: usize, time: f32) -> Affine3A {
        Affine3A::from_mat4(self.pose(time).get(n).copied().unwrap_or(Mat4::IDENTITY))
    }
}

/// The weighted sum of four joint matrices; weights are normalized (glTF asks for sums of 1,
/// files drift), and a vertex with no weight keeps its first joint.
pub fn blend_matrix(joints: &[Mat4], index: [u32; 4], weight: [f32; 4]) -> Mat4 {
    let sum: f32 = weight.iter().sum();
    let weight = if sum > 0.0 { weight.map(|w| w / sum) } else { [1.0, 0.0, 0.0, 0.0] };
    let mut m = Mat4::ZERO;
    for k in 0..4 {
        if weight[k] != 0.0 {
            m += joints.get(index[k] as usize).copied().unwrap_or(Mat4::IDENTITY) * weight[k];
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(property: Property, interpolation: Interpolation, times: &[f32], values: &[Vec4]) -> Channel {
        Channel { node: 0, property, interpolation, times: times.to_vec(), values: values.to_vec() }
    }

    /// glTF's rules at three times: before the first key, between two, after the last.
    #[test]
    fn keyframes_follow_the_gltf_interpolation_rules() {
        let v = [Vec4::new(0.0, 0.0, 0.0, 0.0), Vec4::new(2.0, 4.0, 0.0, 0.0)];
        let step = channel(Property::Translation, Interpolation::Step, &[1.0, 2.0], &v);
        assert_eq!([step.sample(0.5), step.sample(1.75), step.sample(3.0)], [v[0], v[0], v[1]]);
        let linear = channel(Property::Translation, Interpolation::Linear, &[1.0, 2.0], &v);
        assert_eq!([linear.sample(0.5), linear.sample(1.25), linear.sample(3.0)], [v[0], Vec4::new(0.5, 1.0, 0.0, 0.0), v[1]]);
        // Rotations: spherical, 90 degrees about Y halfway is 45.
        let (a, b) = (Quat::IDENTITY, Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let turn = channel(Property::Rotation, Interpolation::Linear, &[0.0, 1.0], &[Vec4::from(a), Vec4::from(b)]);
        let half = Quat::from_vec4(turn.sample(0.5));
        assert!(half.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4)) < 1e-5);
        // Cubic spline (in-tangent, value, out-tangent per key): with out-tangent 3 at the
        // first key and in-tangent 0 at the second, over td = 2: at s = 0.5,
        // p = 0.5 v0 + 2 (0.125) 3 + 0.5 v1 + 2 (-0.125) 0 = 0.5 + 0.75 + 1.5 = 2.75.
        let k = |x: f32| Vec4::new(x, 0.0, 0.0, 0.0);
        let cubic = channel(
            Property::Translation,
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[k(9.0), k(1.0), k(3.0), k(0.0), k(3.0), k(9.0)],
        );
        assert_eq!([cubic.sample(-1.0), cubic.sample(1.0), cubic.sample(5.0)], [k(1.0), k(2.75), k(3.0)]);
    }

    /// A two-joint arm bent 90 degrees at the elbow: a vertex weighted to the forearm turns
    /// with it, one weighted half and half lands between.
    #[test]
    fn skinning_follows_the_joints() {
        let rig = Rig {
            nodes: vec![
                Node::new(None, Vec3::ZERO, Quat::IDENTITY),
                Node::new(Some(0), Vec3::X, Quat::from_rotation_z(std::f32::consts::FRAC_PI_2)),
            ],
            channels: Vec::new(),
            skins: vec![Skin { joints: vec![0, 1], inverse_bind: vec![Mat4::IDENTITY, Mat4::from_translation(-Vec3::X)] }],
            skinned: Vec::new(),
        };
        let m = SkinnedMesh {
            mesh: 0,
            skin: Some(0),
            joints: vec![[1, 0, 0, 0], [0, 1, 0, 0]],
            weights: vec![[1.0, 0.0, 0.0, 0.0], [0.5, 0.5, 0.0, 0.0]],
            morph: None,
        };
        let joints = rig.joint_matrices(0, &rig.pose(0.0));
        let bent = Rig::skin_positions(&m, &joints, &[Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0)]);
        assert!((bent[0] - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-6, "{}", bent[0]);
        assert!((bent[1] - Vec3::new(1.5, 0.5, 0.0)).length() < 1e-6, "{}", bent[1]);
    }

    /// Two morph targets, the second's weight animated linearly from 0 to 1 over a second: at
    /// 0.25 s a vertex moves by the first target's default weight and a quarter of the second.
    #[test]
    fn morph_targets_blend_by_their_animated_weights() {
        let morph = Morph {
            node: 0,
            targets: vec![
                MorphTarget { positions: vec![Vec3::X], ..Default::default() },
                MorphTarget { positions: vec![Vec3::Y * 2.0], ..Default::default() },
            ],
            weights: vec![0.5, 0.0],
        };
        let rig = Rig {
            nodes: vec![Node::new(None, Vec3::ZERO, Quat::IDENTITY)],
            channels: vec![Channel {
                node: 0,
                property: Property::Weights { first: 0 },
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: vec![Vec4::new(0.5, 0.0, 0.0, 0.0), Vec4::new(0.5, 1.0, 0.0, 0.0)],
            }],
            skins: Vec::new(),
            skinned: Vec::new(),
        };
        let w = rig.morph_weights(&morph, 0.25);
        assert_eq!(w, [0.5, 0.25]);
        let p = Rig::morph_positions(&morph, &w, &[Vec3::ZERO]);
        assert!((p[0] - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6, "{}", p[0]);
    }
}
