//! Skins and animation from glTF, end to end: a strip written by the test, skinned to two
//! joints whose second bends 90 degrees and back, played by the sample. The GPU skinning
//! matches the CPU skinning of the same mesh, the SDK's rays see the bent strip where the
//! raster pass draws it (its BLAS was refit), and the file's animation is read as written.
use base64::Engine;
mod support;
use glam::{Quat, Vec3};
use hybrid_rt::DebugOutput;
use hybrid_rt_host::Host;
use hybrid_rt_samples::gltf_scene;
use hybrid_rt_samples::modes::Mode;
use hybrid_rt_samples::renderer::{Renderer, Settings};
use hybrid_rt_samples::scene::SampleScene;
use hybrid_rt_samples::skin::{Interpolation, Property};
use std::path::PathBuf;
use support::written;

/// A 2 x 0.2 strip along +X in the XY plane, four quads; vertices at x <= 1 follow joint 0
/// (the root, at the origin), the others joint 1 (at x = 1), which the animation turns about
/// Z: 0 degrees at t = 0, 90 at t = 1, 0 again at t = 2 (linear). The same mesh, unskinned,
/// on a second node that the animation moves up 2 and back (a rigid animated node).
fn write_skinned_strip(name: &str) -> PathBuf {
    let xs = [0.0f32, 0.5, 1.0, 1.5, 2.0];
    let positions: Vec<[f32; 3]> = xs.iter().flat_map(|&x| [[x, 0.0, 0.0], [x, 0.2, 0.0]]).collect();
    let joints: Vec<[u16; 4]> = xs.iter().flat_map(|&x| [[u16::from(x > 1.0), 0, 0, 0]; 2]).collect();
    let weights: Vec<[f32; 4]> = vec![[1.0, 0.0, 0.0, 0.0]; 10];
    let indices: Vec<u16> = (0..4u16).flat_map(|q| [2 * q, 2 * q + 2, 2 * q + 1, 2 * q + 1, 2 * q + 2, 2 * q + 3]).collect();
    let inverse_bind: [[f32; 16]; 2] =
        [glam::Mat4::IDENTITY.to_cols_array(), glam::Mat4::from_translation(Vec3::new(-1.0, 0.0, 0.0)).to_cols_array()];
    let times = [0.0f32, 1.0, 2.0];
    let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2).to_array();
    let rotations = [[0.0f32, 0.0, 0.0, 1.0], quarter, [0.0, 0.0, 0.0, 1.0]];
    let lifts = [[0.0f32, 0.0, 1.0], [0.0, 2.0, 1.0], [0.0, 0.0, 1.0]];
    let mut bytes: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut push = |data: Vec<u8>| {
        views.push((bytes.len(), data.len()));
        bytes.extend(data);
    };
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    push(f32s(positions.as_flattened()));
    push(joints.as_flattened().iter().flat_map(|j| j.to_le_bytes()).collect());
    push(f32s(weights.as_flattened()));
    push(indices.iter().flat_map(|i| i.to_le_bytes()).collect());
    push(f32s(inverse_bind.as_flattened()));
    push(f32s(&times));
    push(f32s(rotations.as_flattened()));
    push(f32s(lifts.as_flattened()));
    let views: Vec<String> =
        views.iter().map(|(o, l)| format!(r#"{{"buffer": 0, "byteOffset": {o}, "byteLength": {l}}}"#)).collect();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1, 3]}}],
  "nodes": [{{"mesh": 0, "skin": 0}}, {{"children": [2]}}, {{"translation": [1, 0, 0]}}, {{"mesh": 0, "translation": [0, 0, 1]}}],
  "skins": [{{"joints": [1, 2], "inverseBindMatrices": 4}}],
  "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 2, "path": "rotation"}}}},
      {{"sampler": 1, "target": {{"node": 3, "path": "translation"}}}}],
    "samplers": [{{"input": 5, "output": 6, "interpolation": "LINEAR"}}, {{"input": 5, "output": 7}}]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2}}, "indices": 3}}]}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 10, "type": "VEC3", "min": [0, 0, 0], "max": [2, 0.2, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 10, "type": "VEC4"}},
    {{"bufferView": 2, "componentType": 5126, "count": 10, "type": "VEC4"}},
    {{"bufferView": 3, "componentType": 5123, "count": 24, "type": "SCALAR"}},
    {{"bufferView": 4, "componentType": 5126, "count": 2, "type": "MAT4"}},
    {{"bufferView": 5, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0], "max": [2]}},
    {{"bufferView": 6, "componentType": 5126, "count": 3, "type": "VEC4"}},
    {{"bufferView": 7, "componentType": 5126, "count": 3, "type": "VEC3"}}],
  "bufferViews": [{views}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        views = views.join(", "),
        len = bytes.len(),
        data = base64::engine::general_purpose::STANDARD.encode(&bytes),
    );
    written(name, &json)
}

/// Renders `scene` at `time` (two frames, the SDK's random-mesh-colour view on) at `size`;
/// returns how far the GPU's skinning of `mesh` is from `reference`'s CPU skinning at worst,
/// and the `modes` of the last frame.
fn render_posed(
    host: &Host,
    scene: SampleScene,
    reference: &SampleScene,
    mesh: usize,
    time: f32,
    size: (u32, u32),
    modes: &[Mode],
) -> (f32, Vec<Vec<[f32; 4]>>) {
    let settings = Settings { width: size.0, height: size.1, ..Default::default() };
    let mut r = Renderer::new(host, scene, settings).unwrap();
    let camera = r.scene.camera_path.at(0.5);
    for _ in 0..2 {
        r.render(camera, time, &[DebugOutput::RandomMeshColor], None).unwrap();
    }
    r.finish().unwrap();
    let gpu = r.posed_vertices(mesh).unwrap().expect("the mesh is skinned");
    let cpu = &reference.at(time).meshes[mesh].positions;
    let worst = gpu.iter().zip(cpu).map(|(g, c)| (Vec3::new(g[0], g[1], g[2]) - *c).length()).fold(0.0, f32::max);
    let images = modes.iter().map(|&m| r.capture(m).unwrap().0).collect();
    r.destroy().unwrap();
    (worst, images)
}

#[test]
fn the_skin_and_its_animation_are_read() {
    let scene = gltf_scene::load(&write_skinned_strip("strip-read.gltf")).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let rig = &scene.rig;
    assert_eq!(rig.skins.len(), 1);
    assert_eq!(rig.skins[0].joints, [1, 2]);
    assert_eq!(rig.skinned.len(), 1);
    assert_eq!(rig.skinned[0].joints[9], [1, 0, 0, 0]);
    assert_eq!(rig.channels.len(), 2);
    let c = &rig.channels[0];
    assert_eq!((c.node, c.property, c.interpolation), (2, Property::Rotation, Interpolation::Linear));
    // The rigid node: its own mesh (the skinned primitive bends alone), moved by the animation.
    assert_eq!((scene.scene.meshes.len(), scene.scene.instances.len()), (2, 2));
    let rigid = (0..2).find(|&i| scene.scene.instances[i].mesh != rig.skinned[0].mesh).unwrap();
    assert_eq!(scene.motions[rigid], hybrid_rt_samples::scene::Motion::Node(3));
    let lifted = scene.transforms(1.0)[rigid].translation;
    assert!((Vec3::from(lifted) - Vec3::new(0.0, 2.0, 1.0)).length() < 1e-6, "{lifted}");
    assert!(scene.is_dynamic(rigid));
    assert_eq!(rig.duration(), 2.0);
    // The tip at three times: flat, bent up, and halfway back at 1.5 (45 degrees).
    let tip = |t: f32| scene.at(t).meshes[rig.skinned[0].mesh].positions[8];
    assert!((tip(0.0) - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-5, "{}", tip(0.0));
    assert!((tip(1.0) - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-5, "{}", tip(1.0));
    let h = std::f32::consts::FRAC_1_SQRT_2;
    assert!((tip(1.5) - Vec3::new(1.0 + h, h, 0.0)).length() < 1e-5, "{}", tip(1.5));
}

/// Rendered at the bent pose: the GPU's skinned vertices are the CPU's within 1e-4 of the
/// scene's size, and the pixels where the SDK's primary rays hit the strip (its random mesh
/// colour debug view, traced through the refit BLAS) are the pixels the raster pass drew.
#[test]
fn the_gpu_skins_and_the_sdk_traces_the_pose() {
    let host = Host::new().expect("a Vulkan device with ray tracing");
    let scene = gltf_scene::load(&write_skinned_strip("strip-render.gltf")).unwrap();
    let mesh = scene.rig.skinned[0].mesh;
    let size = {
        let (lo, hi) = scene.bounds();
        (hi - lo).length()
    };
    for time in [0.0f32, 1.0] {
        let strip = gltf_scene::load(&write_skinned_strip("strip-render.gltf")).unwrap();
        let modes = [Mode::Normals, Mode::Debug(DebugOutput::RandomMeshColor)];
        let (worst, images) = render_posed(&host, strip, &scene, mesh, time, (96, 64), &modes);
        assert!(worst <= 1e-4 * size, "t = {time}: GPU skinning {worst} from the CPU's (scene size {size})");
        let [normals, traced] = &images[..] else { unreachable!() };
        let drawn: Vec<bool> = normals.iter().map(|t| (0..3).map(|c| (2.0 * t[c] - 1.0).powi(2)).sum::<f32>() > 0.25).collect();
        let hit: Vec<bool> = traced.iter().map(|t| t[0] + t[1] + t[2] > 0.0).collect();
        let (both, either) = (
            drawn.iter().zip(&hit).filter(|(d, h)| **d && **h).count(),
            drawn.iter().zip(&hit).filter(|(d, h)| **d || **h).count(),
        );
        eprintln!(
            "t = {time}: GPU skinning within {worst:.2e}; raster {} px, SDK rays {} px, both {both}",
            drawn.iter().filter(|d| **d).count(),
            hit.iter().filter(|h| **h).count()
        );
        assert!(both > 100, "t = {time}: the strip is in view ({both} pixels)");
        assert!(both as f32 >= 0.95 * either as f32, "t = {time}: raster and SDK agree on {both} of {either} pixels");
    }
    assert_eq!(Host::validation_errors(), 0, "{:#?}", Host::validation_messages());
}

/// The built-in waving figure: every frame its vertices come from the skinning pass (the
/// CPU's skinning within 1e-4 of the scene's size at two times of the wave), its hand moves,
/// and the SDK's rays see the figure where the raster pass draws it.
#[test]
fn the_waving_figure_is_skinned_on_the_gpu_and_traced_as_drawn() {
    let host = Host::new().expect("a Vulkan device with ray tracing");
    let reference = hybrid_rt_samples::figure::waving_figure();
    let mesh = reference.rig.skinned[0].mesh;
    let size = {
        let (lo, hi) = reference.bounds();
        (hi - lo).length()
    };
    let mut hands = Vec::new();
    for time in [0.0f32, 0.5] {
        let modes = [Mode::Albedo, Mode::Debug(DebugOutput::RandomMeshColor)];
        let figure = hybrid_rt_samples::figure::waving_figure();
        let (worst, images) = render_posed(&host, figure, &reference, mesh, time, (128, 72), &modes);
        assert!(worst <= 1e-4 * size, "t = {time}: GPU skinning {worst} from the CPU's");
        let cpu = &reference.at(time).meshes[mesh].positions;
        // The right hand: the figure's vertex furthest along +X at rest.
        let rest = &reference.scene.meshes[mesh].positions;
        let hand = (0..rest.len()).max_by(|&a, &b| rest[a].x.total_cmp(&rest[b].x)).unwrap();
        hands.push(cpu[hand]);
        // The figure is orange, the floor and wall grey: its raster pixels. The SDK's view gives
        // each instance a colour: the figure's is the one most of those pixels show.
        let [albedo, traced] = &images[..] else { unreachable!() };
        let drawn: Vec<bool> = albedo.iter().map(|t| t[0] - t[2] > 0.3).collect();
        let key = |t: &[f32; 4]| t.map(|c| (c * 1000.0) as i32);
        let mut votes = std::collections::HashMap::new();
        for (t, _) in traced.iter().zip(&drawn).filter(|(_, d)| **d) {
            *votes.entry(key(t)).or_insert(0) += 1;
        }
        let figure = votes.into_iter().max_by_key(|(_, n)| *n).map(|(k, _)| k).expect("the figure is in view");
        let hit: Vec<bool> = traced.iter().map(|t| key(t) == figure).collect();
        let both = drawn.iter().zip(&hit).filter(|(d, h)| **d && **h).count();
        let either = drawn.iter().zip(&hit).filter(|(d, h)| **d || **h).count();
        eprintln!("t = {time}: GPU skinning within {worst:.2e}; the figure: raster and SDK agree on {both} of {either} pixels");
        assert!(both > 200, "t = {time}: the figure is in view ({both} pixels)");
        assert!(both as f32 >= 0.95 * either as f32, "t = {time}: raster and SDK agree on {both} of {either} pixels");
    }
    assert!((hands[0] - hands[1]).length() > 0.1, "the hand waves: {} -> {}", hands[0], hands[1]);
    assert_eq!(Host::validation_errors(), 0, "{:#?}", Host::validation_messages());
}

/// The strip of `write_skinned_strip`'s shape, unskinned, with two morph targets: the first
/// lifts each vertex by half its x (a ramp), the second pushes it along +Z by its x. The
/// node's default weights are (0, 0.5); an animation drives the first from 0 at t = 0 to 1 at
/// t = 1 (linear), the second stays at its default.
fn write_morphed_strip(name: &str) -> PathBuf {
    let xs = [0.0f32, 0.5, 1.0, 1.5, 2.0];
    let positions: Vec<[f32; 3]> = xs.iter().flat_map(|&x| [[x, 0.0, 0.0], [x, 0.2, 0.0]]).collect();
    let ramp: Vec<[f32; 3]> = xs.iter().flat_map(|&x| [[0.0, 0.5 * x, 0.0]; 2]).collect();
    let push_z: Vec<[f32; 3]> = xs.iter().flat_map(|&x| [[0.0, 0.0, x]; 2]).collect();
    let indices: Vec<u16> = (0..4u16).flat_map(|q| [2 * q, 2 * q + 2, 2 * q + 1, 2 * q + 1, 2 * q + 2, 2 * q + 3]).collect();
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let mut bytes: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    for data in [
        f32s(positions.as_flattened()),
        f32s(ramp.as_flattened()),
        f32s(push_z.as_flattened()),
        indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
        f32s(&[0.0, 1.0]),
        // Per keyframe, both targets' weights.
        f32s(&[0.0, 0.5, 1.0, 0.5]),
    ] {
        views.push(format!(r#"{{"buffer": 0, "byteOffset": {}, "byteLength": {}}}"#, bytes.len(), data.len()));
        bytes.extend(data);
    }
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "weights": [0, 0.5]}}],
  "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 0, "path": "weights"}}}}],
    "samplers": [{{"input": 4, "output": 5, "interpolation": "LINEAR"}}]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 3, "targets": [{{"POSITION": 1}}, {{"POSITION": 2}}]}}]}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 10, "type": "VEC3", "min": [0, 0, 0], "max": [2, 0.2, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 10, "type": "VEC3", "min": [0, 0, 0], "max": [0, 1, 0]}},
    {{"bufferView": 2, "componentType": 5126, "count": 10, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 2]}},
    {{"bufferView": 3, "componentType": 5123, "count": 24, "type": "SCALAR"}},
    {{"bufferView": 4, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]}},
    {{"bufferView": 5, "componentType": 5126, "count": 4, "type": "SCALAR"}}],
  "bufferViews": [{views}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}]}}"#,
        views = views.join(", "),
        len = bytes.len(),
        data = base64::engine::general_purpose::STANDARD.encode(&bytes),
    );
    written(name, &json)
}

/// Morph targets and their weight animation are read (the tip at t = 0.5: lifted by a
/// quarter of its x, pushed by half of it), the GPU's morphing matches the CPU's within 1e-4
/// of the scene's size, and the SDK's rays see the morphed strip where the raster pass draws it.
#[test]
fn morph_targets_deform_on_the_gpu_and_the_sdk_traces_them() {
    let scene = gltf_scene::load(&write_morphed_strip("morph-read.gltf")).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let m = &scene.rig.skinned[0];
    assert!(m.skin.is_none());
    let morph = m.morph.as_ref().expect("morph targets");
    assert_eq!((morph.targets.len(), morph.weights.clone()), (2, vec![0.0, 0.5]));
    assert_eq!(scene.rig.morph_weights(morph, 0.5), [0.5, 0.5]);
    assert!(!scene.is_dynamic(0), "weights deform the mesh; the node stays put");
    let tip = scene.at(0.5).meshes[m.mesh].positions[8];
    assert!((tip - Vec3::new(2.0, 0.5, 1.0)).length() < 1e-6, "{tip}");
    let size = {
        let (lo, hi) = scene.bounds();
        (hi - lo).length()
    };
    let host = Host::new().expect("a Vulkan device with ray tracing");
    for time in [0.5f32, 1.0] {
        let strip = gltf_scene::load(&write_morphed_strip("morph-render.gltf")).unwrap();
        let modes = [Mode::Normals, Mode::Debug(DebugOutput::RandomMeshColor)];
        let (worst, images) = render_posed(&host, strip, &scene, m.mesh, time, (96, 64), &modes);
        assert!(worst <= 1e-4 * size, "t = {time}: GPU morphing {worst} from the CPU's (scene size {size})");
        let [normals, traced] = &images[..] else { unreachable!() };
        let drawn: Vec<bool> = normals.iter().map(|t| (0..3).map(|c| (2.0 * t[c] - 1.0).powi(2)).sum::<f32>() > 0.25).collect();
        let hit: Vec<bool> = traced.iter().map(|t| t[0] + t[1] + t[2] > 0.0).collect();
        let both = drawn.iter().zip(&hit).filter(|(d, h)| **d && **h).count();
        let either = drawn.iter().zip(&hit).filter(|(d, h)| **d || **h).count();
        eprintln!("t = {time}: GPU morphing within {worst:.2e}; raster and SDK rays agree on {both} of {either} px");
        assert!(both > 100 && both as f32 >= 0.95 * either as f32, "t = {time}: {both} of {either} pixels");
    }
    assert_eq!(Host::validation_errors(), 0, "{:#?}", Host::validation_messages());
}

/// A skinned mesh's own motion is in the motion vectors the denoisers reproject with: the
/// strip's forearm turns 4.5 degrees between two frames seen by a still camera, and each of
/// its pixels' motion (previous - current, pixels) is where its surface point was a frame
/// earlier, within 0.05 pixels (RG16F holds a few pixels' motion to 0.002); the still part's
/// pixels do not move.
#[test]
fn skinned_motion_is_in_the_motion_vectors() {
    let host = Host::new().expect("a Vulkan device with ray tracing");
    let scene = gltf_scene::load(&write_skinned_strip("strip-motion.gltf")).unwrap();
    let (w, h) = (128u32, 96u32);
    let settings = Settings { width: w, height: h, ..Default::default() };
    let mut r = Renderer::new(&host, scene, settings).unwrap();
    let camera = r.scene.camera_path.at(0.5);
    let (t0, t1) = (0.5f32, 0.55f32);
    r.render(camera, t0, &[], None).unwrap();
    r.render(camera, t1, &[], None).unwrap();
    r.finish().unwrap();
    let motion = r.capture(Mode::Motion).unwrap().0;
    let normals = r.capture(Mode::Normals).unwrap().0;
    r.destroy().unwrap();
    // The forearm turns about Z through (1, 0, 0) by 90 degrees x t (the animation's first
    // second); the strip stays in the plane z = 0.
    let angle = |t: f32| std::f32::consts::FRAC_PI_2 * t;
    let clip = camera.view_to_clip(w as f32 / h as f32) * camera.world_to_view();
    let to_pixel = |p: Vec3| {
        let c = clip * p.extend(1.0);
        glam::Vec2::new((c.x / c.w + 1.0) * 0.5 * w as f32, (c.y / c.w + 1.0) * 0.5 * h as f32)
    };
    let inverse = clip.inverse();
    let (mut moving, mut still) = (0, 0);
    for py in 0..h {
        for px in 0..w {
            let i = (py * w + px) as usize;
            let n = &normals[i];
            if (0..3).map(|c| (2.0 * n[c] - 1.0).powi(2)).sum::<f32>() < 0.25 {
                continue;
            }
            // The pixel centre's ray meets the plane z = 0 (the skinned strip; the rigid copy
            // sits at z = 1, nearer the camera: its pixels miss this plane's strip below).
            let ndc = glam::Vec2::new((px as f32 + 0.5) / w as f32 * 2.0 - 1.0, (py as f32 + 0.5) / h as f32 * 2.0 - 1.0);
            let (a, b) = (inverse.project_point3(ndc.extend(0.0)), inverse.project_point3(ndc.extend(1.0)));
            let p = a + (b - a) * (-a.z / (b.z - a.z));
            // Where it sits on the strip at rest: the still part where it is, the forearm
            // turned back by angle(t1).
            let joint = Vec3::X;
            let rest = if p.x <= 1.0 { p } else { joint + Quat::from_rotation_z(-angle(t1)) * (p - joint) };
            let on_strip = (0.0..=2.0).contains(&rest.x) && (0.0..=0.2).contains(&rest.y);
            // Skip pixels near the strip's outline and the quad across the bend (its vertices at
            // x = 1 stay, those at 1.5 turn: it stretches), where `rest` is not where they sit.
            let inside = rest.x > 0.05 && rest.x < 1.95 && rest.y > 0.03 && rest.y < 0.17 && !(0.95..1.55).contains(&rest.x);
            if !on_strip || !inside || p.z.abs() > 1e-3 {
                continue;
            }
            let was = if rest.x > 1.5 { joint + Quat::from_rotation_z(angle(t0)) * (rest - joint) } else { p };
            let expected = to_pixel(was) - to_pixel(p);
            let got = glam::Vec2::new((motion[i][0] - 0.5) / 0.05, (motion[i][1] - 0.5) / 0.05);
            assert!((got - expected).length() < 0.05, "pixel {px},{py}: motion {got}, expected {expected}");
            if expected.length() > 0.5 {
                moving += 1;
            } else if expected.length() == 0.0 {
                still += 1;
            }
        }
    }
    eprintln!("{moving} moving and {still} still strip pixels checked");
    assert!(moving > 30 && still > 30, "{moving} moving, {still} still pixels");
}

/// No rig makes the loader panic: 300 mutants each of the skinned and the morphed strip
/// (keyframes, joints, weights, targets set to edge values, removed, emptied) load or are
/// refused, and the first two of each that load render or fail with an error.
#[test]
fn mutated_rigs_load_or_are_refused() {
    let host = Host::new().expect("a Vulkan device with ray tracing");
    for (k, file) in [write_skinned_strip("fuzz-skin.gltf"), write_morphed_strip("fuzz-morph.gltf")].iter().enumerate() {
        let (loaded, refused) = support::fuzz::fuzz_loader(file, 300, 41 + k as u64, &host, 2);
        eprintln!("{}: {loaded} mutants loaded, {refused} refused", file.display());
    }
}
