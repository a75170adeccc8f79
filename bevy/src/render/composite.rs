//! The GI composite of a deferred camera: the denoised diffuse GI, times each pixel's diffuse
//! colour from Bevy's deferred G-buffer, added to the lit image after Bevy's lighting — as
//! Bevy adds a lightmap's light (times the diffuse colour) to a surface's emission.
//!
//! A forward camera has no per-pixel diffuse colour to multiply by, so its GI stays in the
//! application's image.
use bevy::platform::collections::HashMap;
use hybrid_rt_wgpu::wgpu;

/// Bevy's deferred G-buffer (`Rgba32Uint`): R packs the sRGB base colour (RGB, 8 bits each)
/// and the roughness, B the reflectance, metallic, diffuse occlusion and clearcoat (8 bits
/// each); unlit materials store no base colour (0), so they receive none.
const SHADER: &str = r#"
@group(0) @binding(0) var gbuffer: texture_2d<u32>;
@group(0) @binding(1) var gi: texture_2d<f32>;

@vertex
fn vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle over the whole target.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(position.xy);
    let g = textureLoad(gbuffer, pixel, 0);
    let base_color = pow(unpack4x8unorm(g.r).rgb, vec3<f32>(2.2));
    let metallic = unpack4x8unorm(g.b).g;
    let irradiance = max(textureLoad(gi, pixel, 0).rgb, vec3<f32>(0.0));
    return vec4<f32>(base_color * (1.0 - metallic) * irradiance, 0.0);
}
"#;

/// The composite's pipeline, one per target format.
pub(super) struct GiComposite {
    shader: wgpu::ShaderModule,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
}

impl GiComposite {
    pub(super) fn new(device: &wgpu::Device) -> GiComposite {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("hybrid-rt gi composite"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture { sample_type, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hybrid-rt gi composite"),
            entries: &[
                texture(0, wgpu::TextureSampleType::Uint),
                texture(1, wgpu::TextureSampleType::Float { filterable: false }),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("hybrid-rt gi composite"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        GiComposite { shader, layout, pipeline_layout, pipelines: HashMap::default() }
    }

    /// Adds `gi` times the G-buffer's diffuse colour to `target` (of `format`), in `encoder`.
    pub(super) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        (gbuffer, gi): (&wgpu::TextureView, &wgpu::TextureView),
        (target, format): (&wgpu::TextureView, wgpu::TextureFormat),
    ) {
        let (shader, pipeline_layout) = (&self.shader, &self.pipeline_layout);
        let pipeline = self.pipelines.entry(format).or_insert_with(|| {
            // Added: the lit image's colour plus the GI's; its alpha kept.
            let blend = wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
                alpha: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::Zero,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
            };
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("hybrid-rt gi composite"),
                layout: Some(pipeline_layout),
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
                    targets: &[Some(wgpu::ColorTargetState { format, blend: Some(blend), write_mask: wgpu::ColorWrites::ALL })],
                }),
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                multiview_mask: None,
                cache: None,
            })
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hybrid-rt gi composite"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(gbuffer) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(gi) },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("hybrid-rt gi composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
