//! glTF `KHR_lights_punctual` lights as the SDK's `LightInfo`: directional, point and spot
//! lights placed by their nodes (a light shines down its node's -Z), with the file's colour,
//! intensity (lux for directional lights, candela for the others: the sample's irradiance
//! units, so they light its lighting pass and the SDK's relighting alike), range and cones.
//!
//! Punctual lights have no size, and one-pixel-sharp shadows from every light are not what a
//! renderer with soft shadows shows: each light gets the size the sample gives its fitted
//! lights (a directional light the sun's angular diameter, a point or spot light the fitted
//! point light's radius, 2% of the scene's).
//!
//! Values the SDK refuses are brought into range with a warning: a negative intensity or
//! colour becomes 0, a range <= 0 unlimited, a cone past 90 degrees just under it.
use glam::{Mat4, Vec3};
use hybrid_rt::{LightInfo, LightType, MAX_SHADOW_LIGHTS};

/// A light of the file where its node put it (before sizes, which need the scene's bounds).
pub struct PlacedLight {
    pub kind: gltf::khr_lights_punctual::Kind,
    pub color: [f32; 3],
    pub intensity: f32,
    pub range: Option<f32>,
    pub position: Vec3,
    /// The direction the light travels: the node's -Z.
    pub direction: Vec3,
}

impl PlacedLight {
    /// The light of `light` at node transform `world`; None where the transform leaves it
    /// nowhere (not finite, or a -Z axis scaled to nothing).
    pub fn new(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Option<PlacedLight> {
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).try_normalize()?;
        position.is_finite().then_some(PlacedLight {
            kind: light.kind(),
            color: light.color(),
            intensity: light.intensity(),
            range: light.range(),
            position,
            direction,
        })
    }
}

/// The widest spot cone the SDK takes is under 90 degrees.
const WIDEST_CONE: f32 = std::f32::consts::FRAC_PI_2 - 1e-3;

/// The SDK's lights for `placed` (the first `MAX_SHADOW_LIGHTS`), directional lights
/// `angular_extent` radians wide and the others `radius` world units; `warn` hears what was
/// changed or left out.
pub fn lights(placed: &[PlacedLight], angular_extent: f32, radius: f32, warn: &mut dyn FnMut(&str)) -> Vec<LightInfo> {
    if placed.len() > MAX_SHADOW_LIGHTS {
        warn(&format!("more than {MAX_SHADOW_LIGHTS} lights (the first {MAX_SHADOW_LIGHTS} are drawn)"));
    }
    placed.iter().take(MAX_SHADOW_LIGHTS).map(|p| light(p, angular_extent, radius, warn)).collect()
}

fn light(p: &PlacedLight, angular_extent: f32, radius: f32, warn: &mut dyn FnMut(&str)) -> LightInfo {
    use gltf::khr_lights_punctual::Kind;
    let valid = |x: f32| x.is_finite() && x >= 0.0;
    if !valid(p.intensity) || !p.color.iter().all(|&c| valid(c)) {
        warn("lights with a negative intensity or colour (made 0)");
    }
    let range = match p.range {
        Some(r) if r.is_finite() && r > 0.0 => r,
        Some(_) => {
            warn("lights with a range <= 0 (made unlimited)");
            0.0
        }
        None => 0.0,
    };
    let mut l = LightInfo {
        position: p.position,
        direction: p.direction,
        intensity: if valid(p.intensity) { p.intensity } else { 0.0 },
        color: p.color.map(|c| if valid(c) { c } else { 0.0 }),
        range,
        ..Default::default()
    };
    match p.kind {
        Kind::Directional => {
            l.light_type = LightType::Directional;
            l.angular_extent = angular_extent;
            l.range = 0.0;
        }
        Kind::Point => {
            l.light_type = LightType::Point;
            l.radius = radius;
        }
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            l.light_type = LightType::Spot;
            l.radius = radius;
            let cone = |a: f32| if a.is_finite() { a.clamp(0.0, WIDEST_CONE) } else { WIDEST_CONE };
            if !(outer_cone_angle < WIDEST_CONE && (0.0..=outer_cone_angle).contains(&inner_cone_angle)) {
                warn("spot lights whose cones are not 0 <= inner <= outer < 90 degrees (clamped)");
            }
            l.outer_cone = cone(outer_cone_angle);
            l.inner_cone = cone(inner_cone_angle).min(l.outer_cone);
        }
    }
    l
}
