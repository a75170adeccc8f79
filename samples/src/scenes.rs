//! Built-in scenes.
use crate::lighting::Lights;
use crate::raster::{Material, MaterialTextures, Texture};
use crate::scene::{CameraPath, Cutout, Deformer, Motion, SampleScene};
use glam::{Affine3A, Quat, Vec3};
use hybrid_rt_host::scene::{Camera, Mesh, Rng, Scene};

/// The sample's default scene: a Cornell-style room open to the sky (red left wall, green
/// right wall, white back and front walls) with a glossy floor, a mirror on the back wall, a
/// gold sphere, a box, a column and pebbles; a cube that circles the floor (instance updates)
/// and a flag that waves (a deforming mesh refit every frame). The sun shines in over the
/// back wall; a point light hangs inside. The camera stands inside, so the mirror shows the
/// room around it, and the walls the camera never sees are lit for GI by the lidar sweep.
pub fn cornell_room() -> SampleScene {
    let mut scene = Scene::default();
    let mut materials = Vec::new();
    let mut motions = Vec::new();
    let mut add = |scene: &mut Scene, mesh: usize, t: Affine3A, m: Material, motion: Motion| {
        materials.push(m);
        motions.push(motion);
        scene.add_instance(mesh, t)
    };
    let matte = |albedo: [f32; 3]| Material { albedo, roughness: 0.9, ..Default::default() };
    let white = matte([0.73, 0.71, 0.68]);
    let (half, height) = (3.0, 4.0);
    let quarter = std::f32::consts::FRAC_PI_2;
    let floor = scene.add_mesh(Mesh::grid(2.0 * half, 12));
    add(
        &mut scene,
        floor,
        Affine3A::IDENTITY,
        Material { albedo: [0.42, 0.4, 0.38], roughness: 0.22, metalness: 0.0, ..Default::default() },
        Motion::Static,
    );
    // The walls are the floor grid stood up; `height / 6` squashes the grid's edge that ends
    // up vertical (the grid's Z for walls turned about X, its X for walls turned about Z).
    let wall = scene.add_mesh(Mesh::grid(2.0 * half, 12));
    let squash = height / (2.0 * half);
    let mid = Vec3::Y * height / 2.0;
    let walls = [
        (Quat::from_rotation_x(quarter), Vec3::new(1.0, 1.0, squash), Vec3::new(0.0, 0.0, -half), white),
        (Quat::from_rotation_x(-quarter), Vec3::new(1.0, 1.0, squash), Vec3::new(0.0, 0.0, half), white),
        (Quat::from_rotation_z(-quarter), Vec3::new(squash, 1.0, 1.0), Vec3::new(-half, 0.0, 0.0), matte([0.7, 0.12, 0.1])),
        (Quat::from_rotation_z(quarter), Vec3::new(squash, 1.0, 1.0), Vec3::new(half, 0.0, 0.0), matte([0.12, 0.55, 0.15])),
    ];
    for (rotation, scale, at, m) in walls {
        add(&mut scene, wall, Affine3A::from_scale_rotation_translation(scale, rotation, at + mid), m, Motion::Static);
    }
    let mirror = scene.add_mesh(Mesh::cuboid(Vec3::new(1.3, 0.9, 0.02)));
    add(
        &mut scene,
        mirror,
        Affine3A::from_translation(Vec3::new(0.9, 2.1, -half + 0.03)),
        Material { albedo: [0.95; 3], roughness: 0.0, metalness: 1.0, ..Default::default() },
        Motion::Static,
    );
    let sphere = scene.add_mesh(Mesh::sphere(0.7, 128, 64));
    let gold = Material { albedo: [1.0, 0.78, 0.34], roughness: 0.15, metalness: 1.0, ..Default::default() };
    add(&mut scene, sphere, Affine3A::from_translation(Vec3::new(-1.4, 0.7, -1.0)), gold, Motion::Static);
    let cube = scene.add_mesh(Mesh::cuboid(Vec3::splat(0.55)));
    add(
        &mut scene,
        cube,
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(1.6, 0.55, -1.2)),
        Material { roughness: 0.6, ..white },
        Motion::Static,
    );
    let column = scene.add_mesh(Mesh::cuboid(Vec3::new(0.25, 1.2, 0.25)));
    add(
        &mut scene,
        column,
        Affine3A::from_translation(Vec3::new(-0.3, 1.2, -2.2)),
        Material { albedo: [0.2, 0.35, 0.75], roughness: 0.5, metalness: 0.0, ..Default::default() },
        Motion::Static,
    );
    let pebble = scene.add_mesh(Mesh::sphere(0.15, 24, 12));
    let mut rng = Rng::new(7);
    for k in 0..6 {
        let p = Vec3::new(-0.4 + rng.next_f32() * 1.4, 0.15, 0.2 + rng.next_f32() * 1.0);
        let hue = [[0.8, 0.3, 0.2], [0.2, 0.6, 0.8], [0.9, 0.8, 0.3]][k % 3];
        // One pebble glows (its emission the hue of its albedo): it lights the floor around
        // it through the cache, as the lit image the SDK injects carries its emission.
        let emissive = if k == 5 { hue.map(|c| 3.0 * c) } else { [0.0; 3] };
        add(
            &mut scene,
            pebble,
            Affine3A::from_translation(p),
            Material { albedo: hue, roughness: 0.35, metalness: 0.0, emissive },
            Motion::Static,
        );
    }
    let mover = scene.add_mesh(Mesh::cuboid(Vec3::splat(0.22)));
    let orbit = Motion::Orbit { center: Vec3::new(0.2, 0.22, -0.3), radius: 1.0, period: 6.0 };
    add(
        &mut scene,
        mover,
        Affine3A::IDENTITY,
        Material { albedo: [0.95, 0.45, 0.1], roughness: 0.3, metalness: 0.0, ..Default::default() },
        orbit,
    );
    // The flag: a 1.6 x 1.0 cloth in the XY plane, pinned along its left edge.
    let cloth = Mesh::grid(1.0, 16);
    let rest: Vec<Vec3> = cloth.positions.iter().map(|p| Vec3::new((p.x + 0.5) * 1.6, -p.z, 0.0)).collect();
    let flag = scene.add_mesh(Mesh { positions: rest.clone(), indices: cloth.indices });
    let flag_instance = add(
        &mut scene,
        flag,
        Affine3A::from_translation(Vec3::new(0.9, 3.0, -2.0)),
        Material { albedo: [0.8, 0.15, 0.3], roughness: 0.7, metalness: 0.0, ..Default::default() },
        Motion::Static,
    );
    let lights = Lights {
        sun_direction: Vec3::new(0.3, 1.0, -0.35),
        sun_intensity: 2.2,
        point_position: Vec3::new(0.8, 3.2, 0.6),
        point_intensity: 3.5,
        ambient: 0.0,
    };
    let camera_path = CameraPath {
        from: Vec3::new(-1.6, 2.1, 2.6),
        to: Vec3::new(1.6, 1.7, 2.6),
        target: Vec3::new(0.0, 1.2, -1.5),
        up: Vec3::Y,
        fov_y_radians: 65f32.to_radians(),
    };
    SampleScene {
        deformer: Some(Deformer { instance: flag_instance, rest, amplitude: 0.15 }),
        point_radius: 0.15,
        lidar_eye: Vec3::new(0.0, 2.0, 0.5),
        tile_unit_length: 0.08,
        ao_ray_length: 0.6,
        ..SampleScene::of_meshes("cornell room", scene, materials, motions, lights, camera_path)
    }
}

/// A room: floor, three walls and a ceiling, a sphere, a rotated box, a column and a cluster
/// of small spheres — contact shadows, corners and crevices for AO to show.
pub fn room() -> (Scene, Camera) {
    let mut s = Scene::default();
    let floor = s.add_mesh(Mesh::grid(6.0, 12));
    s.add_instance(floor, Affine3A::IDENTITY);
    let wall = s.add_mesh(Mesh::grid(6.0, 12));
    let quarter = std::f32::consts::FRAC_PI_2;
    // Back wall (facing +Z), left (facing +X), right (facing -X), ceiling (facing -Y).
    s.add_instance(wall, Affine3A::from_rotation_translation(Quat::from_rotation_x(quarter), Vec3::new(0.0, 3.0, -3.0)));
    s.add_instance(wall, Affine3A::from_rotation_translation(Quat::from_rotation_z(-quarter), Vec3::new(-3.0, 3.0, 0.0)));
    s.add_instance(wall, Affine3A::from_rotation_translation(Quat::from_rotation_z(quarter), Vec3::new(3.0, 3.0, 0.0)));
    s.add_instance(
        wall,
        Affine3A::from_rotation_translation(Quat::from_rotation_x(std::f32::consts::PI), Vec3::new(0.0, 6.0, 0.0)),
    );
    let sphere = s.add_mesh(Mesh::sphere(0.7, 48, 24));
    s.add_instance(sphere, Affine3A::from_translation(Vec3::new(-1.2, 0.7, -0.8)));
    let cube = s.add_mesh(Mesh::cuboid(Vec3::splat(0.6)));
    s.add_instance(cube, Affine3A::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::new(1.3, 0.6, -1.2)));
    let column = s.add_mesh(Mesh::cuboid(Vec3::new(0.2, 1.5, 0.2)));
    s.add_instance(column, Affine3A::from_translation(Vec3::new(0.2, 1.5, -2.5)));
    let pebble = s.add_mesh(Mesh::sphere(0.15, 16, 8));
    let mut rng = Rng::new(7);
    for _ in 0..12 {
        let p = Vec3::new(0.3 + rng.next_f32() * 1.2, 0.15, 0.4 + rng.next_f32() * 1.0);
        s.add_instance(pebble, Affine3A::from_translation(p));
    }
    let camera = Camera::look_at(Vec3::new(0.0, 2.2, 4.2), Vec3::new(0.0, 1.0, -1.0));
    (s, camera)
}

/// A synthetic benchmark field: `instances` objects (each its own geometry, so every BLAS is
/// built) of about `triangles / instances` triangles each, scattered on a ground plane.
pub fn field(triangles: usize, instances: usize) -> (Scene, Camera) {
    let mut s = Scene::default();
    let per = (triangles / instances.max(1)).max(8);
    // A sphere with segments = 2 * rings has 2 * segments * rings triangles.
    let rings = (((per / 4) as f32).sqrt().round() as u32).max(2);
    let side = (instances as f32).sqrt().ceil() as usize;
    let spacing = 1.2;
    let extent = side as f32 * spacing;
    let ground = s.add_mesh(Mesh::grid(extent * 2.0, 64));
    s.add_instance(ground, Affine3A::IDENTITY);
    let mut rng = Rng::new(11);
    for i in 0..instances.saturating_sub(1) {
        let m = s.add_mesh(Mesh::sphere(0.3 + 0.25 * rng.next_f32(), 2 * rings, rings));
        let (gx, gz) = ((i % side) as f32, (i / side) as f32);
        let p = Vec3::new((gx - side as f32 / 2.0) * spacing, 0.45, (gz - side as f32 / 2.0) * spacing);
        s.add_instance(m, Affine3A::from_translation(p + Vec3::new(rng.next_f32() * 0.3, 0.0, rng.next_f32() * 0.3)));
    }
    let camera = Camera::look_at(Vec3::new(0.0, extent * 0.35, extent * 0.55), Vec3::new(0.0, 0.0, -extent * 0.05));
    (s, camera)
}

/// What a game scene has, for scale: a rolling terrain of 1,002,528 triangles (one mesh, one
/// BLAS), 1,000 trees of thin 8 cm trunks and round canopies (2,000 instances of two shared
/// meshes; 20 canopies drift in slow circles, so the TLAS changes every frame), 500 ferns of
/// alpha-tested leaf cards (the SDK's alpha test cuts them in every ray, the raster pass in
/// the G-buffer), and a flag whose waves refit its BLAS every frame (the deformation a skinned
/// mesh brings). The sun is
/// low, so trunks cast long thin shadows; the camera flies along the forest's edge.
pub fn forest() -> SampleScene {
    const SIZE: f32 = 60.0;
    const TREES: usize = 1000;
    const FERNS: usize = 500;
    let height = |x: f32, z: f32| 0.6 * (x / 7.0).sin() * (z / 9.0).cos() + 0.25 * (x / 2.3 + z / 3.1).sin();
    let mut scene = Scene::default();
    let (mut materials, mut motions) = (Vec::new(), Vec::new());
    let mut add = |scene: &mut Scene, mesh: usize, t: Affine3A, m: Material, motion: Motion| {
        materials.push(m);
        motions.push(motion);
        scene.add_instance(mesh, t)
    };
    let mut terrain = Mesh::grid(SIZE, 708);
    for p in &mut terrain.positions {
        p.y = height(p.x, p.z);
    }
    let terrain = scene.add_mesh(terrain);
    add(
        &mut scene,
        terrain,
        Affine3A::IDENTITY,
        Material { albedo: [0.35, 0.42, 0.22], roughness: 0.95, metalness: 0.0, ..Default::default() },
        Motion::Static,
    );
    let trunk = scene.add_mesh(Mesh::cuboid(Vec3::new(0.04, 1.0, 0.04)));
    let canopy = scene.add_mesh(Mesh::sphere(0.6, 12, 6));
    let bark = Material { albedo: [0.35, 0.25, 0.15], roughness: 0.9, metalness: 0.0, ..Default::default() };
    let mut rng = Rng::new(11);
    for k in 0..TREES {
        let (x, z) = ((rng.next_f32() - 0.5) * (SIZE - 4.0), (rng.next_f32() - 0.5) * (SIZE - 4.0));
        let ground = height(x, z);
        add(&mut scene, trunk, Affine3A::from_translation(Vec3::new(x, ground + 1.0, z)), bark, Motion::Static);
        let leaves = Material {
            albedo: [0.12 + 0.1 * rng.next_f32(), 0.35 + 0.2 * rng.next_f32(), 0.1],
            roughness: 0.8,
            metalness: 0.0,
            ..Default::default()
        };
        let top = Vec3::new(x, ground + 2.3, z);
        let motion = if k % 50 == 0 { Motion::Orbit { center: top, radius: 0.3, period: 4.0 } } else { Motion::Static };
        add(&mut scene, canopy, Affine3A::from_translation(top), leaves, motion);
    }
    // Undergrowth: ferns of two crossed 1.2 m cards, cut out by a leaf texture's alpha — in
    // the raster pass and in every ray (the SDK's alpha test).
    let mut fern = Mesh::default();
    let mut fern_uvs = Vec::new();
    for (dx, dz) in [(0.6f32, 0.0f32), (0.0, 0.6)] {
        let base = fern.positions.len() as u32;
        for (u, v) in [(0.0f32, 1.0f32), (1.0, 1.0), (0.0, 0.0), (1.0, 0.0)] {
            fern.positions.push(Vec3::new((2.0 * u - 1.0) * dx, (1.0 - v) * 1.2, (2.0 * u - 1.0) * dz));
            fern_uvs.push([u, v]);
        }
        fern.indices.extend_from_slice(&[base, base + 1, base + 2, base + 2, base + 1, base + 3]);
    }
    let fern = scene.add_mesh(fern);
    let mut material_textures = vec![MaterialTextures::default(); scene.instances.len()];
    // In the stretch the camera flies past, where they are seen up close.
    for _ in 0..FERNS {
        let (x, z) = ((rng.next_f32() - 0.5) * 28.0, 14.0 + rng.next_f32() * 14.0);
        let turn = Quat::from_rotation_y(rng.next_f32() * std::f32::consts::TAU);
        let leaf = Material { albedo: [0.6, 0.8, 0.5], roughness: 0.8, metalness: 0.0, ..Default::default() };
        add(&mut scene, fern, Affine3A::from_rotation_translation(turn, Vec3::new(x, height(x, z), z)), leaf, Motion::Static);
        material_textures.push(MaterialTextures::base_color(0));
    }
    // The flag: a 1.6 x 1.0 cloth on a pole at the forest's edge.
    let cloth = Mesh::grid(1.0, 16);
    let rest: Vec<Vec3> = cloth.positions.iter().map(|p| Vec3::new((p.x + 0.5) * 1.6, -p.z, 0.0)).collect();
    let flag = scene.add_mesh(Mesh { positions: rest.clone(), indices: cloth.indices });
    let flag_at = Vec3::new(2.0, height(2.0, 26.0) + 2.5, 26.0);
    let red = Material { albedo: [0.8, 0.15, 0.3], roughness: 0.7, metalness: 0.0, ..Default::default() };
    let flag_instance = add(&mut scene, flag, Affine3A::from_translation(flag_at), red, Motion::Static);
    material_textures.push(MaterialTextures::default());
    let mut uvs = vec![Vec::new(); scene.meshes.len()];
    uvs[fern] = fern_uvs;
    let mut cutouts = vec![None; scene.meshes.len()];
    cutouts[fern] = Some(Cutout { texture: 0, cutoff: 0.5 });
    let lights = Lights {
        sun_direction: Vec3::new(0.5, 0.45, 0.3),
        sun_intensity: 2.5,
        point_position: flag_at + Vec3::new(0.0, 1.5, 1.0),
        point_intensity: 4.0,
        ambient: 0.0,
    };
    let camera_path = CameraPath {
        from: Vec3::new(-8.0, 3.0, 31.0),
        to: Vec3::new(8.0, 2.5, 31.0),
        target: Vec3::new(0.0, 1.0, 18.0),
        up: Vec3::Y,
        fov_y_radians: 60f32.to_radians(),
    };
    SampleScene {
        uvs,
        textures: vec![leaf_texture()],
        material_textures,
        cutouts,
        deformer: Some(Deformer { instance: flag_instance, rest, amplitude: 0.15 }),
        lidar_eye: Vec3::new(0.0, 4.0, 24.0),
        tile_unit_length: 0.3,
        ao_ray_length: 1.0,
        ..SampleScene::of_meshes("forest", scene, materials, motions, lights, camera_path)
    }
}

/// A 64x64 fern frond: a stem up the middle and leaflets either side, opaque green where the
/// leaf is and alpha 0 around it (the cut-out), lighter towards the tips.
fn leaf_texture() -> Texture {
    const N: u32 = 64;
    let mut rgba = Vec::with_capacity((N * N * 4) as usize);
    for y in 0..N {
        for x in 0..N {
            // v = 0 at the top (the frond's tip), 1 at its foot; u across, 0 at the stem.
            let (u, v) = ((x as f32 + 0.5) / N as f32 * 2.0 - 1.0, (y as f32 + 0.5) / N as f32);
            let width = 0.9 * (v * std::f32::consts::PI).sin();
            // Leaflets: bands slanting up from the stem, eight a side.
            let band = ((v * 8.0 + u.abs() * 1.5).fract() - 0.5).abs() < 0.32;
            let leaf = u.abs() < 0.06 || (u.abs() < width && band);
            let shade = 0.6 + 0.4 * (1.0 - v);
            let g = (200.0 * shade) as u8;
            rgba.extend_from_slice(&[(70.0 * shade) as u8, g, (60.0 * shade) as u8, if leaf { 255 } else { 0 }]);
        }
    }
    Texture { width: N, height: N, rgba, linear: false }
}
