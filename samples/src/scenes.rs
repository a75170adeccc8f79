//! Built-in scenes.
use glam::{Affine3A, Quat, Vec3};
use hybrid_rt_testkit::reference::{Camera, Mesh, Rng, Scene};

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
    s.add_instance(wall, Affine3A::from_rotation_translation(Quat::from_rotation_x(std::f32::consts::PI), Vec3::new(0.0, 6.0, 0.0)));
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
