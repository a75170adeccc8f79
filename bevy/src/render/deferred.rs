//! Passes over Bevy's deferred G-buffer: the decode that gives the SDK's specular trace its
//! roughness (and the pixels it should leave out), and the composite that brings the traced
//! effects into the lit image after Bevy's lighting — the GI times each pixel's diffuse colour
//! (as Bevy adds a lightmap's light), the reflections times its environment BRDF (as Bevy
//! weighs its environment map's specular light), and a sun's ray-traced shadow, by taking out
//! the part of the sun's light (lit unshadowed by Bevy: its shadow maps off) that the shadow
//! says is occluded — the sun's light computed as Bevy's lighting computes it.
//!
//! A forward camera has no per-pixel material in any texture, so its GI and shadow stay in
//! the application's images and it traces no reflections.
use super::{HybridRt, Warnings};
use bevy::core_pipeline::prepass::ViewPrepassTextures;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::texture::GpuImage;
use bevy::render::view::{ExtractedView, ViewTarget};
use hybrid_rt::glam::Mat4;
use hybrid_rt::{LightInfo, LightType};
use hybrid_rt_wgpu::wgpu;
use hybrid_rt_wgpu::wgpu::util::DeviceExt;

/// Bevy's deferred G-buffer (`Rgba32Uint`), as its deferred lighting reads it: R packs the sRGB
/// base colour (RGB, 8 bits each) and the perceptual roughness, B the reflectance, metallic,
/// diffuse occlusion and clearcoat (8 bits each), A the octahedral normal (24 bits) and flags
/// (bit 0: unlit; unlit materials store no base colour).
const GBUFFER: &str = r#"
@group(0) @binding(0) var gbuffer: texture_2d<u32>;

struct Material {
    base_color: vec3<f32>,
    perceptual_roughness: f32,
    reflectance: f32,
    metallic: f32,
    unlit: bool,
    shadow_receiver: bool,
    normal: vec3<f32>,
}

fn material(pixel: vec2<i32>) -> Material {
    let g = textureLoad(gbuffer, pixel, 0);
    let base_rough = unpack4x8unorm(g.r);
    let props = unpack4x8unorm(g.b);
    let flags = (g.a >> 24u) & 0xffu;
    // Bevy's octahedral normal, 12 bits a coordinate.
    let oct = vec2<f32>(f32(g.a & 0xfffu), f32((g.a >> 12u) & 0xfffu)) / 4095.0 * 2.0 - 1.0;
    var n = vec3<f32>(oct, 1.0 - abs(oct.x) - abs(oct.y));
    let t = saturate(-n.z);
    n = vec3<f32>(n.xy + select(vec2<f32>(t), vec2<f32>(-t), n.xy >= vec2<f32>(0.0)), n.z);
    let base_color = pow(base_rough.rgb, vec3<f32>(2.2));
    return Material(base_color, base_rough.a, props.r, props.g, (flags & 1u) != 0u, (flags & 4u) != 0u, normalize(n));
}

@vertex
fn vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle over the whole target.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}
"#;

/// The decode: R = left out of the specular trace (unlit, rougher than the limit, or no
/// surface), G = perceptual roughness.
const DECODE: &str = r#"
@group(0) @binding(1) var<uniform> max_roughness: vec4<f32>;

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let m = material(vec2<i32>(position.xy));
    let g = textureLoad(gbuffer, vec2<i32>(position.xy), 0);
    let skip = m.unlit || m.perceptual_roughness > max_roughness.x || all(g == vec4<u32>(0u));
    return vec4<f32>(select(0.0, 1.0, skip), m.perceptual_roughness, 0.0, 0.0);
}
"#;

/// The composite. `terms`: x > 0 adds the GI, y > 0 the reflections, z > 0 takes a light's
/// occluded part out (z = 1: directional, 2: point, 3: spot; its visible fraction in the
/// shadow image's R, or G where w > 0).
const COMPOSITE: &str = r#"
const PI: f32 = 3.141592653589793;

@group(0) @binding(1) var gi: texture_2d<f32>;
@group(0) @binding(2) var reflections: texture_2d<f32>;
@group(0) @binding(3) var shadow: texture_2d<f32>;
struct Composite {
    world_from_clip: mat4x4<f32>,
    terms: vec4<f32>,
    // Directional: the direction to the light; point and spot: the light's position.
    light_vector: vec4<f32>,
    // Its colour x brightness x the camera's exposure, as Bevy lights with it; w: 1 / range².
    light_radiance: vec4<f32>,
    // Point and spot: radius; spot: Bevy's cone scale and offset.
    light_shape: vec4<f32>,
    // Spot: the direction it shines.
    light_forward: vec4<f32>,
}
@group(0) @binding(4) var<uniform> u: Composite;
@group(0) @binding(5) var depth: texture_depth_2d;

fn schlick(f0: f32, f90: f32, x: f32) -> f32 {
    return f0 + (f90 - f0) * pow(1.0 - x, 5.0);
}

// Bevy's lighting terms (Filament's): Burley diffuse; GGX with height-correlated Smith
// visibility, Schlick Fresnel with Bevy's f90, and the multiple-scattering compensation.
fn burley(m: Material, roughness: f32, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, n_dot_v: f32) -> vec3<f32> {
    let h = normalize(l + v);
    let l_dot_h = saturate(dot(l, h));
    let f90 = 0.5 + 2.0 * roughness * l_dot_h * l_dot_h;
    let n_dot_l = saturate(dot(n, l));
    return m.base_color * (1.0 - m.metallic) * schlick(1.0, f90, n_dot_l) * schlick(1.0, f90, n_dot_v) / PI;
}

fn ggx(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, roughness: f32, intensity: f32, f0: vec3<f32>, ab: vec2<f32>, n_dot_v: f32) -> vec3<f32> {
    let h = normalize(l + v);
    let n_dot_l = saturate(dot(n, l));
    let n_dot_h = saturate(dot(n, h));
    let l_dot_h = saturate(dot(l, h));
    let a = n_dot_h * roughness;
    let k = roughness / (1.0 - n_dot_h * n_dot_h + a * a);
    let d = k * k / PI;
    let a2 = roughness * roughness;
    let lambda_v = n_dot_l * sqrt((n_dot_v - a2 * n_dot_v) * n_dot_v + a2);
    let lambda_l = n_dot_v * sqrt((n_dot_l - a2 * n_dot_l) * n_dot_l + a2);
    let visibility = 0.5 / (lambda_v + lambda_l);
    let spec_f90 = saturate(dot(f0, vec3<f32>(50.0 * 0.33)));
    let fresnel = f0 + (spec_f90 - f0) * pow(1.0 - l_dot_h, 5.0);
    return intensity * d * visibility * fresnel * (1.0 + f0 * (1.0 / (ab.x + ab.y) - 1.0));
}

// The light's contribution to the pixel at `p`, as Bevy's PBR lighting computes it, before
// its shadow: a directional light; a point light (Karis' representative point for its
// radius, Bevy's windowed inverse-square falloff); a spot light (the point light x Bevy's
// cone).
fn light_contribution(m: Material, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, n_dot_v: f32, f0: vec3<f32>, ab: vec2<f32>) -> vec3<f32> {
    let clamped = clamp(m.perceptual_roughness, 0.089, 1.0);
    let roughness = clamped * clamped;
    if (u.terms.z < 1.5) {
        let l = u.light_vector.xyz;
        let lobes = burley(m, roughness, n, v, l, n_dot_v) + ggx(n, v, l, roughness, 1.0, f0, ab, n_dot_v);
        return lobes * saturate(dot(n, l)) * u.light_radiance.rgb;
    }
    let to_light = u.light_vector.xyz - p;
    let l = normalize(to_light);
    let d2 = dot(to_light, to_light);
    let d = sqrt(d2);
    let window = saturate(1.0 - d2 * u.light_radiance.w * d2 * u.light_radiance.w);
    let falloff = window * window / max(d2, 0.0001);
    let radius = u.light_shape.x;
    let r = reflect(-v, n);
    let center_to_ray = max(0.0001, dot(to_light, r)) * r - to_light;
    let closest = to_light + center_to_ray * saturate(radius * inverseSqrt(dot(center_to_ray, center_to_ray)));
    let l_spec = closest * inverseSqrt(dot(closest, closest));
    let a_prime = saturate(roughness + radius / (2.0 * d));
    let normalization = roughness / a_prime;
    let inv = (1.0 - roughness) * (1.0 - roughness);
    let brdf_roughness = mix(roughness, a_prime, 1.0 - inv * inv);
    var specular = ggx(n, v, l_spec, brdf_roughness, normalization * normalization, f0, ab, n_dot_v);
    let n_dot_l_spec = saturate(dot(n, l_spec));
    if (radius > 0.0) {
        specular *= saturate(n_dot_l_spec / max(n_dot_l_spec + radius * radius / d2, 1e-4));
    }
    let lit = burley(m, roughness, n, v, l, n_dot_v) * saturate(dot(n, l)) + specular * n_dot_l_spec;
    var cone = 1.0;
    if (u.terms.z > 2.5) {
        let c = saturate(dot(u.light_forward.xyz, -l) * u.light_shape.y + u.light_shape.z);
        cone = c * c;
    }
    return lit * u.light_radiance.rgb * falloff * cone;
}

// Bevy's split-sum environment BRDF terms without its lookup table (Karis' fit, as Bevy's
// F_AB): the specular colour's scale and bias.
fn f_ab(perceptual_roughness: f32, n_dot_v: f32) -> vec2<f32> {
    let c0 = vec4<f32>(-1.0, -0.0275, -0.572, 0.022);
    let c1 = vec4<f32>(1.0, 0.0425, 1.04, -0.04);
    let r = perceptual_roughness * c0 + c1;
    let a004 = min(r.x * r.x, exp2(-9.28 * n_dot_v)) * r.x + r.y;
    return max(vec2<f32>(-1.04, 1.04) * a004 + r.zw, vec2<f32>(0.00005));
}

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let m = material(pixel);
    if (m.unlit) {
        return vec4<f32>(0.0);
    }
    // The direction to the eye from two points of the pixel's ray (perspective or
    // orthographic; reversed-Z keeps both finite).
    let size = vec2<f32>(textureDimensions(gbuffer));
    let uv = position.xy / size;
    let ndc = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let near = u.world_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    let far = u.world_from_clip * vec4<f32>(ndc, 0.5, 1.0);
    let v = normalize(near.xyz / near.w - far.xyz / far.w);
    let at = u.world_from_clip * vec4<f32>(ndc, textureLoad(depth, pixel, 0), 1.0);
    let p = at.xyz / at.w;
    let n = m.normal;
    let n_dot_v = max(dot(n, v), 0.0001);
    let ab = f_ab(m.perceptual_roughness, n_dot_v);
    let f0 = mix(vec3<f32>(0.16 * m.reflectance * m.reflectance), m.base_color, m.metallic);
    var c = vec3<f32>(0.0);
    if (u.terms.x > 0.0) {
        c += m.base_color * (1.0 - m.metallic) * max(textureLoad(gi, pixel, 0).rgb, vec3<f32>(0.0));
    }
    if (u.terms.y > 0.0) {
        // The trace weighs by the lobe's shadowing and masking (its albedo without Fresnel,
        // A + B): Fresnel is the environment BRDF over that.
        let fresnel = (f0 * ab.x + ab.y) / (ab.x + ab.y);
        c += fresnel * max(textureLoad(reflections, pixel, 0).rgb, vec3<f32>(0.0));
    }
    if (u.terms.z > 0.0 && m.shadow_receiver) {
        let texel = textureLoad(shadow, pixel, 0);
        let visible = saturate(select(texel.r, texel.g, u.terms.w > 0.0));
        c -= (1.0 - visible) * light_contribution(m, p, n, v, n_dot_v, f0, ab);
    }
    // Signed: the blend adds it to the float lit image.
    return vec4<f32>(c, 0.0);
}
"#;

/// The decode's output format: R = left out, G = roughness.
pub(super) const DECODED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg8Unorm;

/// What a camera's traces left this frame for the composite to bring into its lit image
/// (views of the application's images).
#[derive(Default)]
pub(super) struct CompositeRequest {
    pub(super) gi: Option<wgpu::TextureView>,
    pub(super) reflections: Option<wgpu::TextureView>,
    pub(super) shadow: Option<LightShadow>,
}

/// A light's ray-traced shadow, for the composite to take the occluded part of the light out
/// of the lit image.
pub(super) struct LightShadow {
    pub(super) visible: wgpu::TextureView,
    /// The visible fraction is in G (the raw trace), not R (denoised).
    pub(super) in_green: bool,
    /// The light: its kind, place, direction, radius, range and cone, as the SDK took it.
    pub(super) light: LightInfo,
    /// Its colour x brightness x the camera's exposure, as Bevy lights with it (a directional
    /// light's illuminance, a point or spot light's lumens / 4 pi).
    pub(super) radiance: [f32; 3],
}

impl LightShadow {
    /// The composite's light terms: its kind (`terms.z`), then `light_vector`,
    /// `light_radiance`, `light_shape` and `light_forward`.
    fn uniform(&self) -> (f32, [f32; 16]) {
        let l = &self.light;
        let forward = l.direction.normalize_or_zero();
        let kind = match l.light_type {
            LightType::Directional => 1.0,
            LightType::Point => 2.0,
            LightType::Spot => 3.0,
            _ => 0.0,
        };
        let vector = match l.light_type {
            LightType::Directional => -forward,
            _ => l.position,
        };
        let inverse_range_squared = if l.range > 0.0 { 1.0 / (l.range * l.range) } else { 0.0 };
        // Bevy's cone: saturate(cos x scale + offset)², full inside the inner cone.
        let cos_outer = l.outer_cone.cos();
        let scale = 1.0 / (l.inner_cone.cos() - cos_outer).max(1e-4);
        let [r, g, b] = self.radiance;
        #[rustfmt::skip]
        let terms = [
            vector.x, vector.y, vector.z, 0.0,
            r, g, b, inverse_range_squared,
            l.radius, scale, -cos_outer * scale, 0.0,
            forward.x, forward.y, forward.z, 0.0,
        ];
        (kind, terms)
    }
}

/// The decode's and the composite's pipelines (the composite's one per target format), made
/// when a deferred camera first needs them.
pub(super) struct DeferredPasses {
    decode_layout: wgpu::BindGroupLayout,
    decode: wgpu::RenderPipeline,
    composite_shader: wgpu::ShaderModule,
    composite_layout: wgpu::BindGroupLayout,
    composite_pipeline_layout: wgpu::PipelineLayout,
    composites: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    /// Bound for the effects the composite does not bring.
    blank: wgpu::TextureView,
}

fn texture_entry(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture { sample_type, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// A full-screen triangle's pipeline into one target of `format`.
fn fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    (shader, layout): (&wgpu::ShaderModule, &wgpu::PipelineLayout),
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: shader,
            entry_point: Some("vertex"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: shader,
            entry_point: Some("fragment"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState { format, blend, write_mask: wgpu::ColorWrites::ALL })],
        }),
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// Draws the full-screen triangle into `target`, loading (`clear`: false) or clearing it.
fn fullscreen_pass(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    target: &wgpu::TextureView,
    clear: bool,
    (pipeline, bind_group): (&wgpu::RenderPipeline, &wgpu::BindGroup),
) {
    let load = if clear { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) } else { wgpu::LoadOp::Load };
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.draw(0..3, 0..1);
}

impl DeferredPasses {
    pub(super) fn new(device: &wgpu::Device) -> DeferredPasses {
        let module = |label, body: &str| {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(format!("{GBUFFER}{body}").into()),
            })
        };
        let layout = |label, entries: &[wgpu::BindGroupLayoutEntry]| {
            let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries });
            let pipeline = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(&group)],
                immediate_size: 0,
            });
            (group, pipeline)
        };
        let gbuffer = texture_entry(0, wgpu::TextureSampleType::Uint);
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let (decode_layout, decode_pipeline_layout) = layout("hybrid-rt g-buffer decode", &[gbuffer, uniform_entry(1)]);
        let decode_shader = module("hybrid-rt g-buffer decode", DECODE);
        let decode = fullscreen_pipeline(
            device,
            "hybrid-rt g-buffer decode",
            (&decode_shader, &decode_pipeline_layout),
            DECODED_FORMAT,
            None,
        );
        let (composite_layout, composite_pipeline_layout) = layout(
            "hybrid-rt composite",
            &[
                gbuffer,
                texture_entry(1, float),
                texture_entry(2, float),
                texture_entry(3, float),
                uniform_entry(4),
                texture_entry(5, wgpu::TextureSampleType::Depth),
            ],
        );
        let blank = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("hybrid-rt composite blank"),
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        DeferredPasses {
            decode_layout,
            decode,
            composite_shader: module("hybrid-rt composite", COMPOSITE),
            composite_layout,
            composite_pipeline_layout,
            composites: HashMap::default(),
            blank: blank.create_view(&Default::default()),
        }
    }

    /// Decodes the G-buffer into `target` (`DECODED_FORMAT`, the G-buffer's size) for the
    /// specular trace: pixels rougher than `max_roughness` are left out.
    pub(super) fn decode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer: &wgpu::TextureView,
        max_roughness: f32,
        target: &wgpu::TextureView,
    ) {
        let limit = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hybrid-rt g-buffer decode"),
            contents: &uniform_bytes(&[max_roughness, 0.0, 0.0, 0.0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hybrid-rt g-buffer decode"),
            layout: &self.decode_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(gbuffer) },
                wgpu::BindGroupEntry { binding: 1, resource: limit.as_entire_binding() },
            ],
        });
        fullscreen_pass(encoder, "hybrid-rt g-buffer decode", target, true, (&self.decode, &bind_group));
    }

    /// Brings `request` into `target` (of `format`), in `encoder`, for a camera whose clip
    /// space (wgpu's) maps to world space by `world_from_clip`.
    pub(super) fn composite(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        (gbuffer, depth, request, world_from_clip): (&wgpu::TextureView, &wgpu::TextureView, &CompositeRequest, [f32; 16]),
        (target, format): (&wgpu::TextureView, wgpu::TextureFormat),
    ) {
        let (shader, pipeline_layout) = (&self.composite_shader, &self.composite_pipeline_layout);
        let pipeline = self.composites.entry(format).or_insert_with(|| {
            // Added: the lit image's colour plus the composite's; its alpha kept.
            let add = |src_factor| wgpu::BlendComponent {
                src_factor,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            };
            let blend = wgpu::BlendState { color: add(wgpu::BlendFactor::One), alpha: add(wgpu::BlendFactor::Zero) };
            fullscreen_pipeline(device, "hybrid-rt composite", (shader, pipeline_layout), format, Some(blend))
        });
        let on = |o: bool| if o { 1.0 } else { 0.0 };
        let shadow = request.shadow.as_ref();
        let (kind, light) = shadow.map_or((0.0, [0.0; 16]), LightShadow::uniform);
        let mut uniform = world_from_clip.to_vec();
        uniform.extend([
            on(request.gi.is_some()),
            on(request.reflections.is_some()),
            kind,
            on(shadow.is_some_and(|s| s.in_green)),
        ]);
        uniform.extend(light);
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hybrid-rt composite"),
            contents: &uniform_bytes(&uniform),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let view = |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hybrid-rt composite"),
            layout: &self.composite_layout,
            entries: &[
                view(0, gbuffer),
                view(1, request.gi.as_ref().unwrap_or(&self.blank)),
                view(2, request.reflections.as_ref().unwrap_or(&self.blank)),
                view(3, shadow.map_or(&self.blank, |s| &s.visible)),
                wgpu::BindGroupEntry { binding: 4, resource: uniform.as_entire_binding() },
                view(5, depth),
            ],
        });
        fullscreen_pass(encoder, "hybrid-rt composite", target, false, (pipeline, &bind_group));
    }
}

/// The bytes of a uniform's floats (little-endian, as the GPU reads them).
fn uniform_bytes(floats: &[f32]) -> Vec<u8> {
    floats.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// The view of an effect's output the composite reads, where it is on (None: off, or the image
/// cannot be read by a shader, warned once).
pub(super) fn composited(image: &GpuImage, on: bool, component: &str, warned: &mut Warnings) -> Option<wgpu::TextureView> {
    if !on {
        return None;
    }
    if !image.texture.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        warned.once(format!("{component}.output needs TEXTURE_BINDING usage for the composite of a deferred camera"));
        return None;
    }
    Some((*image.texture_view).clone())
}

/// Per deferred camera, after its traces and before transparent surfaces: what they left for
/// the lit image, in one full-screen pass.
pub(super) fn composite(
    view: ViewQuery<(&ExtractedView, &ExtractedCamera, &ViewPrepassTextures, &ViewTarget)>,
    mut state: ResMut<HybridRt>,
    mut ctx: RenderContext,
) {
    let (view, camera, prepass, target) = view.into_inner();
    let state = &mut *state;
    let Some(mut request) = state.composites.remove(&view.retained_view_entity) else { return };
    // Without HDR Bevy's lit image is tonemapped already: no light can be taken out of it.
    if !camera.hdr && request.shadow.take().is_some() {
        state.warned.once("RayTracedShadow's composite needs an Hdr camera: the shadow stays in its image");
    }
    let (Some(rt), Some(gbuffer), Some(depth)) = (state.rt.as_ref(), prepass.deferred.as_ref(), prepass.depth_only_view()) else {
        return;
    };
    let world_from_view = Mat4::from_cols_array(&view.world_from_view.to_matrix().to_cols_array());
    let clip_from_view = Mat4::from_cols_array(&view.clip_from_view.to_cols_array());
    let world_from_clip = (world_from_view * clip_from_view.inverse()).to_cols_array();
    let passes = state.deferred.get_or_insert_with(|| DeferredPasses::new(&rt.device));
    let (lit, format) = (target.main_texture_view(), target.main_texture_format());
    passes.composite(
        &rt.device,
        ctx.command_encoder(),
        (&gbuffer.texture.default_view, depth, &request, world_from_clip),
        (lit, format),
    );
}
