#version 460
#extension GL_GOOGLE_include_directive : require
// Sets a range of cache samples to a colour with no history (a new or cleared cache).
#include "include/cache.glsl"
layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    uvec2 samples;
    uint count;
    uint pad;
    vec4 color;
} pc;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    CacheSamples c = CacheSamples(pc.samples);
    c.s[i].value = vec4(pc.color.rgb, 0.0);
    c.s[i].accum = vec4(0.0);
}
