// Ambient occlusion, shared by the ray-tracing pipeline (ao.rgen) and the inline ray-query
// variant (ao.comp). The includer defines `float hrt_trace_hit_t(vec3 o, vec3 d, float tmax)`
// returning the closest hit distance or a negative value on a miss, and then calls hrt_ao_main.
#ifndef HRT_AO_GLSL
#define HRT_AO_GLSL
#include "common.glsl"
#include "random.glsl"

layout(set = 0, binding = 0) uniform accelerationStructureEXT u_tlas;
layout(set = 0, binding = 1) uniform sampler2D u_depth;
layout(set = 0, binding = 2) uniform sampler2D u_normals;
layout(set = 0, binding = 3) uniform writeonly image2D u_out;
layout(set = 0, binding = 4, std140) uniform AoConstants {
    TraceCommon common_;
    vec4 ao_params;   // ray length, falloff power, unused, unused
    uvec4 ao_counts;  // rays per pixel, unused...
} u_c;
layout(set = 0, binding = 5) uniform sampler2D u_input_mask;

float hrt_trace_hit_t(vec3 origin, vec3 dir, float tmax);

// Visibility in [0, 1] (1 = open). A miss counts 1; a hit at distance t counts
// (t / ray_length)^falloff_power, so near occluders darken more than far ones (distance-
// weighted AO). Directions are cosine-distributed, so the plain mean estimates the
// cosine-weighted visibility integral (1/pi) * integral V(w) cos(theta) dw.
void hrt_ao_main(uvec2 local) {
    TraceCommon c = u_c.common_;
    uvec2 pixel;
    vec3 p, n;
    int kind = hrt_gbuffer_pixel(c, local, u_depth, u_normals, u_input_mask, pixel, p, n);
    if (kind == HRT_PIXEL_SKIP) return;
    if (kind == HRT_PIXEL_BACKGROUND) {
        imageStore(u_out, ivec2(pixel), vec4(1.0));
        return;
    }
    vec3 origin = hrt_offset_ray(c, p, n);
    mat3 basis = hrt_basis(n);

    float ray_length = u_c.ao_params.x;
    float power = u_c.ao_params.y;
    uint rays = u_c.ao_counts.x;
    // A new rotation every frame (see hrt_independent_frames).
    HrtSequence seq = hrt_sequence(0u, false, pixel, hrt_independent_frames(c.frame.x, 0xa0u), rays);
    seq = hrt_with_generator(seq, c, pixel, 0xa0u, rays);

    float visibility = 0.0;
    for (uint i = 0u; i < rays; ++i) {
        vec3 dir = basis * hrt_cosine_hemisphere(hrt_sample(seq, i));
        float t = hrt_trace_hit_t(origin, dir, ray_length);
        visibility += t < 0.0 ? 1.0 : pow(clamp(t / ray_length, 0.0, 1.0), power);
    }
    float ao = visibility / float(rays);
    imageStore(u_out, ivec2(pixel), vec4(ao, ao, ao, 1.0));
}
#endif
