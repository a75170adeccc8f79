//! The CPU reference renderer: triangle scenes, a BVH, G-buffer generation by primary rays,
//! and reference ambient occlusion. Written for clarity and for exactly the conventions the
//! SDK documents (Vulkan clip space, cosine-weighted visibility, distance-weighted hits), not
//! for speed; tests keep images small. The scenes themselves (meshes, instances, the camera)
//! are the host's (`hybrid_rt_host::scene`), shared with the sample.
use glam::{Affine3A, Mat4, Vec3, Vec4};
pub use hybrid_rt_host::scene::{Camera, Mesh, Rng, Scene, SceneInstance};

// ---------------------------------------------------------------- BVH

#[derive(Clone, Copy)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// Leaf: first triangle, count > 0. Inner: left child index, count == 0 (right = left + 1).
    start: u32,
    count: u32,
}

#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    /// Geometric normal (unit), as wound.
    pub normal: Vec3,
    pub triangle: u32,
    /// Weights of the triangle's vertices 1 and 2 (Vulkan's hit attributes).
    pub bary: [f32; 2],
    /// Index of the scene instance hit.
    pub instance: u32,
}

/// World-space triangles of a scene with a BVH over them.
pub struct Tracer {
    tris: Vec<[Vec3; 3]>,
    /// Scene instance of each triangle (kept in step with `tris` through the BVH sort).
    instance_of: Vec<u32>,
    nodes: Vec<Node>,
}

impl Tracer {
    pub fn new(scene: &Scene) -> Tracer {
        Self::with_instances(scene, |_| true)
    }

    /// Only the instances `keep` accepts (e.g. those whose BLAS the SDK has built).
    pub fn with_instances(scene: &Scene, keep: impl Fn(usize) -> bool) -> Tracer {
        let mut tris = Vec::new();
        let mut instance_of = Vec::new();
        for (i, inst) in scene.instances.iter().enumerate() {
            if !keep(i) {
                continue;
            }
            let m = &scene.meshes[inst.mesh];
            for t in m.indices.chunks_exact(3) {
                tris.push([0, 1, 2].map(|k| inst.transform.transform_point3(m.positions[t[k] as usize])));
                instance_of.push(i as u32);
            }
        }
        let mut tracer = Tracer { tris, instance_of, nodes: Vec::new() };
        tracer.build();
        tracer
    }

    fn build(&mut self) {
        self.nodes.clear();
        if self.tris.is_empty() {
            return;
        }
        self.nodes.push(Node { min: Vec3::ZERO, max: Vec3::ZERO, start: 0, count: self.tris.len() as u32 });
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let (start, count) = (self.nodes[ni].start as usize, self.nodes[ni].count as usize);
            let tris = &self.tris[start..start + count];
            let (mut min, mut max) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            let (mut cmin, mut cmax) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            for t in tris {
                for p in t {
                    min = min.min(*p);
                    max = max.max(*p);
                }
                let c = (t[0] + t[1] + t[2]) / 3.0;
                cmin = cmin.min(c);
                cmax = cmax.max(c);
            }
            self.nodes[ni].min = min;
            self.nodes[ni].max = max;
            if count <= 4 {
                continue;
            }
            let ext = cmax - cmin;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let key = |t: &[Vec3; 3]| (t[0][axis] + t[1][axis] + t[2][axis]) / 3.0;
            let mut order: Vec<usize> = (start..start + count).collect();
            order.sort_by(|&a, &b| key(&self.tris[a]).total_cmp(&key(&self.tris[b])));
            let tris: Vec<[Vec3; 3]> = order.iter().map(|&i| self.tris[i]).collect();
            let inst: Vec<u32> = order.iter().map(|&i| self.instance_of[i]).collect();
            self.tris[start..start + count].copy_from_slice(&tris);
            self.instance_of[start..start + count].copy_from_slice(&inst);
            let half = count / 2;
            let left = self.nodes.len();
            self.nodes.push(Node { min, max, start: start as u32, count: half as u32 });
            self.nodes.push(Node { min, max, start: (start + half) as u32, count: (count - half) as u32 });
            self.nodes[ni].start = left as u32;
            self.nodes[ni].count = 0;
            stack.push(left);
            stack.push(left + 1);
        }
    }

    /// Closest hit in (tmin, tmax), both faces.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let inv = dir.recip();
        let mut best: Option<Hit> = None;
        let mut t_best = tmax;
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = self.nodes[stack[sp] as usize];
            let t0 = (n.min - origin) * inv;
            let t1 = (n.max - origin) * inv;
            let tnear = t0.min(t1).max_element().max(tmin);
            let tfar = t0.max(t1).min_element().min(t_best);
            if tnear > tfar {
                continue;
            }
            if n.count > 0 {
                for i in n.start..n.start + n.count {
                    let tri = &self.tris[i as usize];
                    if let Some((t, u, v)) = intersect(origin, dir, tri) {
                        if t > tmin && t < t_best {
                            t_best = t;
                            let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
                            best = Some(Hit { t, normal, triangle: i, bary: [u, v], instance: self.instance_of[i as usize] });
                        }
                    }
                }
            } else {
                stack[sp] = n.start;
                stack[sp + 1] = n.start + 1;
                sp += 2;
            }
        }
        best
    }
}

/// Möller–Trumbore: (t, weight of vertex 1, weight of vertex 2).
fn intersect(o: Vec3, d: Vec3, tri: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - tri[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv, u, v))
}

// ---------------------------------------------------------------- G-buffer

/// What a rasterizer would have produced, by casting one primary ray per pixel centre.
#[derive(Clone, Debug)]
pub struct GBuffer {
    pub width: u32,
    pub height: u32,
    /// Hardware depth (clip z / w), 1.0 where nothing was hit.
    pub depth: Vec<f32>,
    /// World-space unit normal facing the camera; zero where nothing was hit.
    pub normal: Vec<Vec3>,
    pub position: Vec<Vec3>,
    pub hit: Vec<bool>,
    /// Scene instance under each pixel (0 on background).
    pub instance: Vec<u32>,
}

impl GBuffer {
    pub fn render(tracer: &Tracer, camera: &Camera, width: u32, height: u32) -> GBuffer {
        GBuffer::render_with(tracer, camera, camera.view_to_clip(width as f32 / height as f32), width, height)
    }

    /// The camera's projection shifted so the image content moves by `jitter` pixels (a TAA
    /// jitter), and that projection (what the engine passes as `Camera::view_to_clip`).
    pub fn render_jittered(tracer: &Tracer, camera: &Camera, width: u32, height: u32, jitter: [f32; 2]) -> (GBuffer, Mat4) {
        let shift = Mat4::from_translation(Vec3::new(2.0 * jitter[0] / width as f32, 2.0 * jitter[1] / height as f32, 0.0));
        let view_to_clip = shift * camera.view_to_clip(width as f32 / height as f32);
        (GBuffer::render_with(tracer, camera, view_to_clip, width, height), view_to_clip)
    }

    /// One primary ray per pixel centre through `view_to_clip` from `camera`'s pose.
    pub fn render_with(tracer: &Tracer, camera: &Camera, view_to_clip: Mat4, width: u32, height: u32) -> GBuffer {
        let world_to_clip = view_to_clip * camera.world_to_view();
        let clip_to_world = world_to_clip.inverse();
        let n = (width * height) as usize;
        let mut g = GBuffer {
            width,
            height,
            depth: vec![1.0; n],
            normal: vec![Vec3::ZERO; n],
            position: vec![Vec3::ZERO; n],
            hit: vec![false; n],
            instance: vec![0; n],
        };
        // Rows in parallel: the bench renders 1080p G-buffers of million-triangle scenes.
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(32);
        let rows_per = (height as usize).div_ceil(threads).max(1);
        let px = width as usize;
        std::thread::scope(|s| {
            let chunks = g
                .depth
                .chunks_mut(rows_per * px)
                .zip(g.normal.chunks_mut(rows_per * px))
                .zip(g.position.chunks_mut(rows_per * px).zip(g.hit.chunks_mut(rows_per * px)))
                .zip(g.instance.chunks_mut(rows_per * px));
            for (c, (((depth, normal), (position, hit)), instance)) in chunks.enumerate() {
                s.spawn(move || {
                    for (k, d) in depth.iter_mut().enumerate() {
                        let i = c * rows_per * px + k;
                        let (x, y) = ((i % px) as f32, (i / px) as f32);
                        let ndc = Vec3::new((x + 0.5) / width as f32 * 2.0 - 1.0, (y + 0.5) / height as f32 * 2.0 - 1.0, 0.5);
                        let p = clip_to_world * ndc.extend(1.0);
                        let dir = (p.truncate() / p.w - camera.eye).normalize();
                        if let Some(h) = tracer.closest_hit(camera.eye, dir, 0.0, f32::MAX) {
                            let pos = camera.eye + dir * h.t;
                            let c: Vec4 = world_to_clip * pos.extend(1.0);
                            *d = c.z / c.w;
                            normal[k] = if h.normal.dot(dir) > 0.0 { -h.normal } else { h.normal };
                            position[k] = pos;
                            hit[k] = true;
                            instance[k] = h.instance;
                        }
                    }
                });
            }
        });
        g
    }

    /// Depth texels as R32_SFLOAT bytes.
    pub fn depth_bytes(&self) -> Vec<u8> {
        bytemuck::cast_slice(&self.depth).to_vec()
    }

    /// Normals as R32G32B32A32_SFLOAT bytes (NormalType::RgbVector).
    pub fn normal_bytes_rgba32f(&self) -> Vec<u8> {
        let v: Vec<[f32; 4]> = self.normal.iter().map(|n| [n.x, n.y, n.z, 0.0]).collect();
        bytemuck::cast_slice(&v).to_vec()
    }

    /// World positions as R32G32B32A32_SFLOAT bytes (DepthType::WorldPosition); background
    /// pixels hold NaN.
    pub fn position_bytes_rgba32f(&self) -> Vec<u8> {
        let v: Vec<[f32; 4]> =
            self.position.iter().zip(&self.hit).map(|(p, h)| if *h { [p.x, p.y, p.z, 1.0] } else { [f32::NAN; 4] }).collect();
        bytemuck::cast_slice(&v).to_vec()
    }
}

// ---------------------------------------------------------------- AO

/// Reference parameters, matching `hybrid_rt::TraceAmbientOcclusionTask`.
#[derive(Clone, Copy, Debug)]
pub struct AoParams {
    pub ray_length: f32,
    pub falloff_power: f32,
    pub ray_offset: hybrid_rt::RayOffset,
}

pub fn offset_origin(p: Vec3, n: Vec3, eye: Vec3, o: &hybrid_rt::RayOffset) -> Vec3 {
    match o.offset_type {
        hybrid_rt::RayOffsetType::CameraDistance => {
            let d = p.distance(eye);
            p + n * (o.cam_constant + o.cam_linear * d + o.cam_quadratic * d * d).max(0.0)
        }
        // Ray Tracing Gems ch. 6, as shaders/include/common.glsl applies it: a few ULPs along
        // n in each coordinate's own precision, a fixed step near the origin.
        hybrid_rt::RayOffsetType::WorldPosition => {
            let step = |p: f32, n: f32| {
                let of = (o.world_int_scale * n) as i32;
                let bits = p.to_bits() as i32;
                let moved = f32::from_bits(bits.wrapping_add(if p < 0.0 { -of } else { of }) as u32);
                if p.abs() < o.world_threshold {
                    p + o.world_float_scale * n
                } else {
                    moved
                }
            };
            Vec3::new(step(p.x, n.x), step(p.y, n.y), step(p.z, n.z))
        }
        hybrid_rt::RayOffsetType::Disabled => p,
    }
}

/// Orthonormal basis around n (any rotation about n is as good for a reference).
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let t = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    let t = (t - n * n.dot(t)).normalize();
    (t, n.cross(t))
}

/// Reference AO at one surface point with `strata`² stratified cosine samples.
pub fn ao_at(tracer: &Tracer, p: Vec3, n: Vec3, eye: Vec3, params: &AoParams, strata: u32, rng: &mut Rng) -> f32 {
    let origin = offset_origin(p, n, eye, &params.ray_offset);
    let (t, b) = basis(n);
    let mut sum = 0.0;
    for sy in 0..strata {
        for sx in 0..strata {
            let u1 = (sx as f32 + rng.next_f32()) / strata as f32;
            let u2 = (sy as f32 + rng.next_f32()) / strata as f32;
            let r = u1.sqrt();
            let phi = 2.0 * std::f32::consts::PI * u2;
            let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
            let dir = (t * local.x + b * local.y + n * local.z).normalize();
            sum += match tracer.closest_hit(origin, dir, 0.0, params.ray_length) {
                None => 1.0,
                Some(h) => (h.t / params.ray_length).clamp(0.0, 1.0).powf(params.falloff_power),
            };
        }
    }
    sum / (strata * strata) as f32
}

/// Reference AO image (1.0 on background pixels).
pub fn reference_ao(tracer: &Tracer, g: &GBuffer, eye: Vec3, params: &AoParams, strata: u32) -> Vec<f32> {
    let mut rng = Rng::new(0x5eed);
    (0..g.depth.len())
        .map(|i| if g.hit[i] { ao_at(tracer, g.position[i], g.normal[i], eye, params, strata, &mut rng) } else { 1.0 })
        .collect()
}

// ---------------------------------------------------------------- direct lighting

/// A sun: direction towards the light and its radiance scale.
#[derive(Clone, Copy, Debug)]
pub struct Sun {
    pub to_light: Vec3,
    pub intensity: f32,
}

/// What the engine's rasterizer would have lit: Lambertian albedo under a sun with ray-traced
/// shadows plus a small ambient term, RGBA32F texels (A = 1 on surfaces, 0 on background).
/// `albedo` gives each scene instance its colour.
pub fn direct_lighting(tracer: &Tracer, g: &GBuffer, sun: Sun, albedo: impl Fn(u32) -> [f32; 3]) -> Vec<[f32; 4]> {
    let l = sun.to_light.normalize();
    (0..g.depth.len())
        .map(|i| {
            if !g.hit[i] {
                return [0.0; 4];
            }
            let (p, n) = (g.position[i], g.normal[i]);
            let a = albedo(g.instance[i]);
            let lit = n.dot(l).max(0.0) * sun.intensity;
            let shadowed = lit > 0.0 && tracer.closest_hit(p + n * 1e-3, l, 0.0, f32::MAX).is_some();
            let e = if shadowed { 0.0 } else { lit } + 0.08;
            [a[0] * e, a[1] * e, a[2] * e, 1.0]
        })
        .collect()
}

// ---------------------------------------------------------------- shadows

/// A point of the unit disk (concentric map), as the SDK samples a light's extent.
pub fn concentric_disk(u: f32, v: f32) -> (f32, f32) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (b / a))
    } else {
        (b, std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / b))
    };
    (r * phi.cos(), r * phi.sin())
}

/// Fraction of the light's extent visible from surface point `p` (normal `n`), with
/// `strata`² stratified samples of the same disk of directions / positions the SDK samples,
/// and the closest occluder distance over them (None if all reach the light).
// One argument per input of the SDK's shadow trace that it mirrors.
#[allow(clippy::too_many_arguments)]
pub fn shadow_visibility(
    tracer: &Tracer,
    p: Vec3,
    n: Vec3,
    eye: Vec3,
    light: &hybrid_rt::LightInfo,
    offset: &hybrid_rt::RayOffset,
    strata: u32,
    rng: &mut Rng,
) -> (f32, Option<f32>) {
    let origin = offset_origin(p, n, eye, offset);
    let mut visible = 0;
    let mut closest: Option<f32> = None;
    for sy in 0..strata {
        for sx in 0..strata {
            let (u, v) = ((sx as f32 + rng.next_f32()) / strata as f32, (sy as f32 + rng.next_f32()) / strata as f32);
            let (dir, tmax) = light_ray(light, origin, u, v);
            match tracer.closest_hit(origin, dir, 0.0, tmax) {
                None => visible += 1,
                Some(h) => closest = Some(closest.map_or(h.t, |c: f32| c.min(h.t))),
            }
        }
    }
    (visible as f32 / (strata * strata) as f32, closest)
}

/// The ray from `origin` to the point of the light's extent at (u, v) in the unit square, as
/// the SDK samples it (`hrt_light_ray`): a disk of directions for a directional light of angular
/// size, a disk facing the origin for a sphere light. Returns the direction and the distance
/// to stop short of the light.
pub fn light_ray(light: &hybrid_rt::LightInfo, origin: Vec3, u: f32, v: f32) -> (Vec3, f32) {
    let (dx, dy) = concentric_disk(u, v);
    if light.light_type == hybrid_rt::LightType::Directional {
        let to_light = -light.direction.normalize();
        let (t, b) = basis(to_light);
        ((to_light + (t * dx + b * dy) * (light.angular_extent * 0.5).tan()).normalize(), f32::MAX)
    } else {
        let to_centre = (light.position - origin).normalize();
        let (t, b) = basis(to_centre);
        let target = light.position + (t * dx + b * dy) * light.radius;
        let v = target - origin;
        (v.normalize(), v.length() * 0.9999)
    }
}

// ---------------------------------------------------------------- test scenes

/// A unit-diameter sphere resting on an 8 m plane, and a camera above and in front: contact
/// occlusion and a shadow on open ground.
pub fn sphere_on_plane() -> (Scene, Camera) {
    let mut scene = Scene::default();
    let plane = scene.add_mesh(Mesh::grid(8.0, 8));
    let sphere = scene.add_mesh(Mesh::sphere(0.5, 24, 12));
    scene.add_instance(plane, Affine3A::IDENTITY);
    scene.add_instance(sphere, Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)));
    (scene, Camera::look_at(Vec3::new(0.0, 1.6, 2.2), Vec3::new(0.0, 0.2, 0.0)))
}

/// A 4 m room: a grey floor and red (left), green (right) and blue (back) walls, each carrying
/// its colour as a known cache radiance; `with_ceiling` adds a grey ceiling. The front is open.
/// Returns the scene, each instance's colour, and a camera looking into the room.
pub fn coloured_room(with_ceiling: bool) -> (Scene, Vec<[f32; 3]>, Camera) {
    use glam::Quat;
    let mut s = Scene::default();
    let quad = s.add_mesh(Mesh::grid(4.0, 2));
    let q = std::f32::consts::FRAC_PI_2;
    let mut placements = vec![
        (Affine3A::IDENTITY, [0.3, 0.3, 0.3]),
        (Affine3A::from_rotation_translation(Quat::from_rotation_z(-q), Vec3::new(-2.0, 2.0, 0.0)), [0.9, 0.1, 0.1]),
        (Affine3A::from_rotation_translation(Quat::from_rotation_z(q), Vec3::new(2.0, 2.0, 0.0)), [0.1, 0.9, 0.1]),
        (Affine3A::from_rotation_translation(Quat::from_rotation_x(q), Vec3::new(0.0, 2.0, -2.0)), [0.1, 0.1, 0.9]),
    ];
    if with_ceiling {
        placements.push((
            Affine3A::from_rotation_translation(Quat::from_rotation_x(2.0 * q), Vec3::new(0.0, 4.0, 0.0)),
            [0.5, 0.5, 0.5],
        ));
    }
    let mut colours = Vec::new();
    for (t, c) in placements {
        s.add_instance(quad, t);
        colours.push(c);
    }
    (s, colours, Camera::look_at(Vec3::new(0.0, 1.8, 1.9), Vec3::new(0.0, 0.6, -1.0)))
}

// ---------------------------------------------------------------- diffuse GI

/// Reference mean incoming radiance over the cosine-weighted hemisphere (E/pi, what
/// `TraceDiffuseTask` estimates): a hit takes its instance's radiance from `colours`, a miss
/// `sky`; each sample is weighted by `weight(n, dir, v)` (the BRDF relative to Lambert: 1 for
/// Lambertian); `strata`² stratified samples per pixel.
#[allow(clippy::too_many_arguments)]
pub fn diffuse_reference(
    tracer: &Tracer,
    g: &GBuffer,
    eye: Vec3,
    colours: &[[f32; 3]],
    sky: [f32; 3],
    ray_length: f32,
    strata: u32,
    weight: impl Fn(Vec3, Vec3, Vec3) -> f32,
) -> Vec<[f32; 3]> {
    diffuse_reference_with(
        tracer,
        g,
        eye,
        |hit| hit.map_or(sky, |(_, instance)| colours[instance as usize]),
        ray_length,
        strata,
        weight,
    )
}

/// `diffuse_reference` with each sample's radiance from `radiance(hit)`: the hit point and
/// instance, or None for a miss.
pub fn diffuse_reference_with(
    tracer: &Tracer,
    g: &GBuffer,
    eye: Vec3,
    radiance: impl Fn(Option<(Vec3, u32)>) -> [f32; 3],
    ray_length: f32,
    strata: u32,
    weight: impl Fn(Vec3, Vec3, Vec3) -> f32,
) -> Vec<[f32; 3]> {
    let offset = hybrid_rt::RayOffset::default();
    let mut rng = Rng::new(3);
    (0..g.depth.len())
        .map(|i| {
            if !g.hit[i] {
                return [0.0; 3];
            }
            let (p, n) = (g.position[i], g.normal[i]);
            let origin = offset_origin(p, n, eye, &offset);
            let (t, b) = basis(n);
            let mut sum = [0.0f32; 3];
            for sy in 0..strata {
                for sx in 0..strata {
                    let u1 = (sx as f32 + rng.next_f32()) / strata as f32;
                    let u2 = (sy as f32 + rng.next_f32()) / strata as f32;
                    let (r, phi) = (u1.sqrt(), 2.0 * std::f32::consts::PI * u2);
                    let dir = (t * r * phi.cos() + b * r * phi.sin() + n * (1.0 - u1).max(0.0).sqrt()).normalize();
                    let c = radiance(tracer.closest_hit(origin, dir, 0.0, ray_length).map(|h| (origin + dir * h.t, h.instance)));
                    let w = weight(n, dir, (eye - p).normalize());
                    for k in 0..3 {
                        sum[k] += c[k] * w / (strata * strata) as f32;
                    }
                }
            }
            sum
        })
        .collect()
}

/// A light's weight in the multi-light mean, as `LightInfo` documents it: its unshadowed
/// irradiance at (p, n) up to a constant.
pub fn light_weight(l: &hybrid_rt::LightInfo, p: Vec3, n: Vec3) -> f32 {
    if l.light_type == hybrid_rt::LightType::Directional {
        return l.intensity * n.dot(-l.direction.normalize()).max(0.0);
    }
    let v = p - l.position;
    let d = v.length();
    let mut reach = 1.0;
    if l.range > 0.0 {
        reach = (1.0 - (d / l.range).powi(4)).clamp(0.0, 1.0).powi(2);
    }
    if l.light_type == hybrid_rt::LightType::Spot {
        let c = (v / d).dot(l.direction.normalize());
        let (lo, hi) = (l.outer_cone.cos(), l.inner_cone.cos());
        let t = ((c - lo) / (hi - lo)).clamp(0.0, 1.0);
        reach *= if c <= lo { 0.0 } else { t * t * (3.0 - 2.0 * t) };
    }
    l.intensity * reach * n.dot(-v / d).max(0.0) / (d * d)
}

// ---------------------------------------------------------------- many lights

/// What `TraceManyLightsTask` estimates at a surface, by brute force: every light's unshadowed
/// irradiance times the surface's response to the light's centre direction (Lambert's 1/pi;
/// GGX specular, lobe widened by half the light's angular radius) times the visible fraction
/// of the light's extent, with `strata`² stratified shadow rays per light (one for a point of
/// no size). Returns per pixel (diffuse = E/pi, specular = E x GGX), summed over the lights;
/// background pixels get zeros. `roughness` is the surface's everywhere.
#[allow(clippy::too_many_arguments)]
pub fn many_lights_reference(
    tracer: &Tracer,
    g: &GBuffer,
    eye: Vec3,
    lights: &[hybrid_rt::LightInfo],
    roughness: f32,
    offset: &hybrid_rt::RayOffset,
    strata: u32,
    rng: &mut Rng,
) -> Vec<([f32; 3], [f32; 3])> {
    (0..g.depth.len())
        .map(|i| {
            if !g.hit[i] {
                return ([0.0; 3], [0.0; 3]);
            }
            let p = g.position[i];
            let v = (eye - p).normalize();
            let mut n = g.normal[i];
            if n.dot(v) < 0.0 {
                n = (n - 2.0 * n.dot(v) * v).normalize();
            }
            let (mut diffuse, mut specular) = (Vec3::ZERO, Vec3::ZERO);
            for l in lights {
                let (e, wi, dist) = many_lights_irradiance(l, p, n);
                if luminance(e) <= 0.0 {
                    continue;
                }
                let angle = if l.light_type == hybrid_rt::LightType::Directional {
                    (l.angular_extent * 0.5).tan()
                } else {
                    l.radius / dist.max(1e-6)
                };
                let fs = ggx_direct(n, v, wi, roughness * roughness, angle);
                let sized =
                    if l.light_type == hybrid_rt::LightType::Directional { l.angular_extent > 0.0 } else { l.radius > 0.0 };
                let s = if sized { strata } else { 1 };
                let vis = light_visible_fraction(tracer, p, n, eye, l, offset, s, rng);
                diffuse += e * (vis / std::f32::consts::PI);
                specular += e * (fs * vis);
            }
            (diffuse.to_array(), specular.to_array())
        })
        .collect()
}

/// Rec. 709 luminance.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// A light's unshadowed irradiance at (p, n) (colour), the direction to its centre and its
/// distance: `hrt_ml_irradiance` in shaders/include/many_lights.glsl.
pub fn many_lights_irradiance(l: &hybrid_rt::LightInfo, p: Vec3, n: Vec3) -> (Vec3, Vec3, f32) {
    let radiant = Vec3::from_array(l.color) * l.intensity;
    if l.light_type == hybrid_rt::LightType::Directional {
        let wi = -l.direction.normalize();
        return (radiant * n.dot(wi).max(0.0), wi, 1e30);
    }
    let d = l.position - p;
    let d2 = d.length_squared().max(1e-8);
    let dist = d2.sqrt();
    let wi = d / dist;
    let mut reach = 1.0;
    if l.range > 0.0 {
        reach = (1.0 - (dist / l.range).powi(4)).clamp(0.0, 1.0).powi(2);
    }
    if l.light_type == hybrid_rt::LightType::Spot {
        let c = (-wi).dot(l.direction.normalize());
        let (lo, hi) = (l.outer_cone.cos(), l.inner_cone.cos().max(l.outer_cone.cos() + 1e-6));
        let t = ((c - lo) / (hi - lo)).clamp(0.0, 1.0);
        reach *= if c <= lo { 0.0 } else { t * t * (3.0 - 2.0 * t) };
    }
    (radiant * (reach * n.dot(wi).max(0.0) / d2), wi, dist)
}

/// GGX specular without Fresnel for a light of angular radius `angle`: `hrt_ml_specular`.
pub fn ggx_direct(n: Vec3, v: Vec3, wi: Vec3, alpha: f32, angle: f32) -> f32 {
    let (nl, nv) = (n.dot(wi), n.dot(v));
    if nl <= 0.0 || nv <= 0.0 {
        return 0.0;
    }
    let a = (alpha.max(0.01) + 0.5 * angle).min(1.0);
    let a2 = a * a;
    let nh = n.dot((wi + v).normalize()).max(0.0);
    let dd = nh * nh * (a2 - 1.0) + 1.0;
    let d = a2 / (std::f32::consts::PI * dd * dd);
    let lv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
    let ll = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
    d * 0.5 / (lv + ll).max(1e-12)
}

/// The visible fraction of a light's extent from (p, n): `strata`² stratified samples of the
/// disk the SDK samples (`hrt_light_ray`), a sample below the surface's horizon unseen.
#[allow(clippy::too_many_arguments)]
pub fn light_visible_fraction(
    tracer: &Tracer,
    p: Vec3,
    n: Vec3,
    eye: Vec3,
    light: &hybrid_rt::LightInfo,
    offset: &hybrid_rt::RayOffset,
    strata: u32,
    rng: &mut Rng,
) -> f32 {
    let origin = offset_origin(p, n, eye, offset);
    let mut visible = 0;
    for sy in 0..strata {
        for sx in 0..strata {
            let (u, v) = ((sx as f32 + rng.next_f32()) / strata as f32, (sy as f32 + rng.next_f32()) / strata as f32);
            let (dir, tmax) = light_ray(light, origin, u, v);
            if dir.dot(n) > 0.0 && tracer.closest_hit(origin, dir, 0.0, tmax).is_none() {
                visible += 1;
            }
        }
    }
    visible as f32 / (strata * strata) as f32
}
