#version 460
#extension GL_GOOGLE_include_directive : require
// Folds each sample's accumulated injection into its running average and clears the
// accumulator: value += (mean - value) / n with n = min(history + 1, average_window). A
// relit sample's history (negative) does not count: camera light replaces it at once.
#include "include/cache.glsl"
layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    uvec2 samples;     // address of the first sample of the range
    uint count;
    float average_window;
} pc;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    CacheSamples c = CacheSamples(pc.samples);
    vec4 acc = c.s[i].accum;
    if (acc.w <= 0.0) return;
    vec4 v = c.s[i].value;
    float n = min(max(v.w, 0.0) + 1.0, pc.average_window);
    c.s[i].value = vec4(v.rgb + (acc.rgb / acc.w - v.rgb) / n, n);
    c.s[i].accum = vec4(0.0);
}
