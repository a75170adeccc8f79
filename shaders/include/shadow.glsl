#ifndef HRT_SHADOW_GLSL
#define HRT_SHADOW_GLSL
// The body of the shadow task; the includer provides hrt_trace_record and HRT_LAUNCH_ID
// (include/trace_rt.glsl or include/trace_rq.glsl).
// Shadows from one light. Each ray aims at a random point of the light's extent (a cone of
// directions for a directional light of angular size, a disk facing the surface for a point or
// spot light of radius), so penumbrae widen with the light's size and the occluder's distance
// (shared/seeds/003). Output (the integration guide's format): R = closest occluder distance,
// negative where every ray reached the light; G (if present) = the fraction of rays that did.
#include "common.glsl"
#include "random.glsl"

#include "light_sampling.glsl"

layout(set = 0, binding = 0) uniform accelerationStructureEXT u_tlas;
layout(set = 0, binding = 1) uniform sampler2D u_depth;
layout(set = 0, binding = 2) uniform sampler2D u_normals;
layout(set = 0, binding = 3) uniform writeonly image2D u_out;
layout(set = 0, binding = 4, std140) uniform ShadowConstants {
    TraceCommon common_;
    LightGpu light;
    uvec4 counts;     // rays per pixel, first-hit mode, max ray length (float bits)
} u_c;
layout(set = 0, binding = 5) uniform sampler2D u_input_mask;


void hrt_shadow_main() {
    TraceCommon c = u_c.common_;
    uvec2 pixel;
    vec3 p, n;
    int kind = hrt_gbuffer_pixel(c, HRT_LAUNCH_ID, u_depth, u_normals, u_input_mask, pixel, p, n);
    if (kind == HRT_PIXEL_SKIP) return;
    if (kind == HRT_PIXEL_BACKGROUND) {
        imageStore(u_out, ivec2(pixel), vec4(-1.0, 1.0, 0.0, 0.0));
        return;
    }
    // Beyond the range or outside the cone the light does not reach: unlit, no rays. (R = 0:
    // an occluder at the surface, so the denoiser keeps the edge hard.)
    if (hrt_light_reach(u_c.light, p) <= 0.0) {
        imageStore(u_out, ivec2(pixel), vec4(0.0));
        return;
    }
    vec3 origin = hrt_offset_ray(c, p, n);
    uint rays = u_c.counts.x;
    HrtSequence seq = hrt_sequence(c.frame.x, c.frame.z != 0u, pixel, 0x5badu, rays);
    seq = hrt_with_generator(seq, c, pixel, 0x5badu, rays);

    float closest = 1e30;
    uint visible = 0u;
    // First-hit mode: traversal stops at any occluder; its distance is kept (>= the closest).
    uint flags = u_c.counts.y != 0u ? gl_RayFlagsTerminateOnFirstHitEXT : 0u;
    for (uint i = 0u; i < rays; ++i) {
        vec3 dir;
        float tmax;
        hrt_light_ray(u_c.light, origin, hrt_sample(seq, i), dir, tmax);
        tmax = min(tmax, uintBitsToFloat(u_c.counts.z));
        // Any occluder will do for visibility; the denoiser's penumbra estimate wants the
        // closest (unless the task chose first-hit speed).
        float t = hrt_trace_record_flags(u_tlas, flags, c.frame.y & 0xffu, origin, dir, tmax).t;
        if (t < 0.0) visible += 1u;
        else closest = min(closest, t);
    }
    float fraction = float(visible) / float(rays);
    imageStore(u_out, ivec2(pixel), vec4(visible == rays ? -1.0 : closest, fraction, 0.0, 0.0));
}
#endif
