#version 460
// Copies a geometry's albedo texture (AlbedoTextureInput) into its compact copy, box-filtered
// down to the copy's size: each copied texel is the mean of the view's mip-level texels its
// footprint covers (RGB, linear as fetched: sRGB views decode), stored as RGBA8 sRGB-encoded
// (8 bits spend their precision where dark albedos need it). One invocation per copied texel.
// Relighting and hit lighting read it back (include/albedo.glsl).
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D u_texture;
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer Texels { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 dst;      // the copy's albedo section
    uint width;     // copied texels
    uint height;
    uint src_width; // the texture's
    uint src_height;
} pc;

vec3 srgb_encode(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (id.x >= pc.width || id.y >= pc.height) return;
    // Source texels [x0, x1) x [y0, y1): the copied texel's footprint (at least one texel).
    uint x0 = id.x * pc.src_width / pc.width, x1 = max((id.x + 1u) * pc.src_width / pc.width, x0 + 1u);
    uint y0 = id.y * pc.src_height / pc.height, y1 = max((id.y + 1u) * pc.src_height / pc.height, y0 + 1u);
    vec3 sum = vec3(0.0);
    for (uint y = y0; y < y1; ++y)
        for (uint x = x0; x < x1; ++x) sum += texelFetch(u_texture, ivec2(x, y), 0).rgb;
    vec3 mean = sum / float((x1 - x0) * (y1 - y0));
    Texels(pc.dst).w[id.y * pc.width + id.x] = packUnorm4x8(vec4(srgb_encode(mean), 1.0));
}
