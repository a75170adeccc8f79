//! A glTF file's node hierarchy, animation and skins as the sample's `Rig`: every node with
//! its parent and rest transform, the channels of the file's first animation (translation,
//! rotation, scale and morph-target weights; step, linear or cubic spline), and every skin's
//! joints and inverse bind matrices. Skinned and morphed meshes are added by the scene loader
//! as it meets them.
use crate::skin::{Channel, Interpolation, Node, Property, Rig, Skin};
use glam::{Mat4, Quat, Vec3, Vec4};

/// The rig of `doc` (empty when it has no animation and no skin). Names what it skips in
/// `warn`.
pub(crate) fn rig(doc: &gltf::Document, data: &[Vec<u8>], warn: &mut dyn FnMut(&str)) -> Result<Rig, String> {
    let animations = doc.animations().count();
    let morphs = doc.meshes().any(|m| m.primitives().any(|p| p.morph_targets().next().is_some()));
    if animations == 0 && doc.skins().next().is_none() && !morphs {
        return Ok(Rig::default());
    }
    let mut nodes: Vec<Node> = doc
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            Node { parent: None, translation: Vec3::from(t), rotation: Quat::from_array(r), scale: Vec3::from(s) }
        })
        .collect();
    for n in doc.nodes() {
        for child in n.children() {
            nodes[child.index()].parent = Some(n.index());
        }
    }
    let read = |b: gltf::Buffer| data.get(b.index()).map(|d| d.as_slice());
    let mut channels = Vec::new();
    if animations > 1 {
        warn("more than one animation (the first is played)");
    }
    if let Some(animation) = doc.animations().next() {
        for c in animation.channels() {
            let at = || format!("animation {} channel {}", animation.index(), c.index());
            let reader = c.reader(read);
            let times: Vec<f32> = reader.read_inputs().ok_or_else(|| format!("{}: no keyframe times", at()))?.collect();
            use gltf::animation::util::ReadOutputs;
            let interpolation = match c.sampler().interpolation() {
                gltf::animation::Interpolation::Step => Interpolation::Step,
                gltf::animation::Interpolation::Linear => Interpolation::Linear,
                gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
            let node = c.target().node().index();
            let (property, values): (Property, Vec<Vec4>) = match reader.read_outputs() {
                Some(ReadOutputs::Translations(v)) => (Property::Translation, v.map(|t| Vec3::from(t).extend(0.0)).collect()),
                Some(ReadOutputs::Rotations(r)) => (Property::Rotation, r.into_f32().map(Vec4::from).collect()),
                Some(ReadOutputs::Scales(v)) => (Property::Scale, v.map(|s| Vec3::from(s).extend(0.0)).collect()),
                Some(ReadOutputs::MorphTargetWeights(w)) => {
                    let w: Vec<f32> = w.into_f32().collect();
                    channels
                        .extend(weight_channels(node, interpolation, &times, &w, per_key).map_err(|e| format!("{}: {e}", at()))?);
                    continue;
                }
                None => return Err(format!("{}: no keyframe values", at())),
            };
            if values.len() != times.len() * per_key {
                return Err(format!("{}: {} keyframe times but {} values", at(), times.len(), values.len()));
            }
            if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
                return Err(format!("{}: keyframe times are not increasing", at()));
            }
            channels.push(Channel { node, property, interpolation, times, values });
        }
    }
    let skins = doc
        .skins()
        .map(|s| {
            let joints: Vec<usize> = s.joints().map(|j| j.index()).collect();
            let inverse_bind: Vec<Mat4> = match s.reader(read).read_inverse_bind_matrices() {
                Some(m) => m.map(|m| Mat4::from_cols_array_2d(&m)).collect(),
                None => vec![Mat4::IDENTITY; joints.len()],
            };
            if inverse_bind.len() < joints.len() {
                return Err(format!(
                    "skin {}: {} inverse bind matrices for {} joints",
                    s.index(),
                    inverse_bind.len(),
                    joints.len()
                ));
            }
            Ok(Skin { joints, inverse_bind })
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Rig { nodes, channels, skins, skinned: Vec::new() })
}

/// A `weights` channel of `node` as channels of four targets each: `w` holds every target's
/// weight per keyframe (three values per target for cubic splines: in-tangent, value,
/// out-tangent, each a run over the targets).
fn weight_channels(
    node: usize,
    interpolation: Interpolation,
    times: &[f32],
    w: &[f32],
    per_key: usize,
) -> Result<Vec<Channel>, String> {
    let slots = times.len() * per_key;
    if slots == 0 || w.is_empty() || !w.len().is_multiple_of(slots) {
        return Err(format!("{} keyframe times but {} weights", times.len(), w.len()));
    }
    if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|p| p[1] < p[0]) {
        return Err("keyframe times are not increasing".into());
    }
    let targets = w.len() / slots;
    Ok((0..targets.div_ceil(4))
        .map(|g| Channel {
            node,
            property: Property::Weights { first: 4 * g as u32 },
            interpolation,
            times: times.to_vec(),
            values: (0..slots)
                .map(|s| {
                    Vec4::from_array(std::array::from_fn(|k| {
                        w.get(s * targets + 4 * g + k).copied().filter(|_| 4 * g + k < targets).unwrap_or(0.0)
                    }))
                })
                .collect(),
        })
        .collect())
}

/// Per node, whether an animation moves it (it or an ancestor is animated).
pub(crate) fn animated_nodes(rig: &Rig) -> Vec<bool> {
    let mut moved = vec![false; rig.nodes.len()];
    // (Morph-target weights deform a mesh; they do not move its node.)
    for c in rig.channels.iter().filter(|c| !matches!(c.property, Property::Weights { .. })) {
        if let Some(m) = moved.get_mut(c.node) {
            *m = true;
        }
    }
    (0..rig.nodes.len())
        .map(|n| {
            let mut at = Some(n);
            // Bounded: the loader refused hierarchies with cycles before this runs.
            for _ in 0..=rig.nodes.len() {
                match at {
                    Some(k) if moved[k] => return true,
                    Some(k) => at = rig.nodes[k].parent,
                    None => return false,
                }
            }
            false
        })
        .collect()
}
