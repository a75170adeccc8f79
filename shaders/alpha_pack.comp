#version 460
// Copies an alpha-tested geometry's alpha texture into its compact copy: one byte per texel
// (the `channel` of the view's mip level, as unorm), four texels per u32, rows of `pitch` words.
// One invocation per word. The trace's alpha test (include/alpha_test.glsl) reads it back.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D u_texture;
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer Texels { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 dst;      // the copy's alpha section
    uint width;     // texels
    uint height;
    uint pitch;     // words per row
    uint channel;   // 0..3
} pc;

void main() {
    uvec2 id = gl_GlobalInvocationID.xy;
    if (id.x >= pc.pitch || id.y >= pc.height) return;
    uint word = 0u;
    for (uint k = 0u; k < 4u; ++k) {
        uint x = 4u * id.x + k;
        if (x >= pc.width) break;
        float a = clamp(texelFetch(u_texture, ivec2(x, id.y), 0)[pc.channel], 0.0, 1.0);
        word |= uint(a * 255.0 + 0.5) << (8u * k);
    }
    Texels(pc.dst).w[id.y * pc.pitch + id.x] = word;
}
