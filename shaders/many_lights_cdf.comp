#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// TraceManyLightsTask's light distribution, rebuilt when the light list changes: per light its
// power (intensity x luminance of its colour x the solid angle it emits into), and the inclusive
// prefix sums over the list of the local lights' powers (x) and of the directional lights'
// (y), which the presample pass searches. One group of 1024: each thread sums a run of lights,
// the group scans the runs, each thread writes its run's prefix sums.
#include "include/common.glsl"
#include "include/light_sampling.glsl"
layout(local_size_x = 1024) in;
layout(push_constant) uniform Push {
    uvec2 lights;
    uvec2 cdf;
    uint count;
} pc;
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Lights { LightGpu l[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) writeonly buffer Cdf { vec2 c[]; };

shared vec2 s_sums[1024];

vec2 hrt_power(LightGpu l) {
    float p = l.power.x * max(dot(l.power.yzw, vec3(0.2126, 0.7152, 0.0722)), 0.0);
    if (!(p > 0.0 && p < 1e30)) return vec2(0.0);
    uint kind = uint(l.position.w);
    if (kind == HRT_LIGHT_DIRECTIONAL) return vec2(0.0, p);
    if (kind == HRT_LIGHT_SPOT) return vec2(2.0 * HRT_PI * (1.0 - l.shape.w) * p, 0.0);
    return vec2(4.0 * HRT_PI * p, 0.0);
}

void main() {
    uint t = gl_LocalInvocationID.x;
    uint per = (pc.count + 1023u) / 1024u;
    uint first = min(t * per, pc.count);
    uint end = min(first + per, pc.count);
    Lights lights = Lights(pc.lights);
    vec2 run = vec2(0.0);
    for (uint i = first; i < end; ++i) run += hrt_power(lights.l[i]);
    s_sums[t] = run;
    barrier();
    for (uint offset = 1u; offset < 1024u; offset <<= 1u) {
        vec2 v = t >= offset ? s_sums[t - offset] : vec2(0.0);
        barrier();
        s_sums[t] += v;
        barrier();
    }
    vec2 prefix = t > 0u ? s_sums[t - 1u] : vec2(0.0);
    Cdf cdf = Cdf(pc.cdf);
    for (uint i = first; i < end; ++i) {
        prefix += hrt_power(lights.l[i]);
        cdf.c[i] = prefix;
    }
}
