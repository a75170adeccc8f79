#ifndef HRT_MULTI_SHADOW_GLSL
#define HRT_MULTI_SHADOW_GLSL
// Shadows from up to 32 lights in one pass: rays_per_pixel rays towards each light that reaches
// the surface (same sampling as the single-light task; none beyond a light's range or outside
// its cone). Outputs:
//  - visibility (uint): 8 bits per light, the fraction of its rays that reached it x 255,
//    four lights per 32-bit channel (light i in channel i/4, bits 8*(i%4)); lights 16-31 in
//    visibility_high, the same way.
//  - packed (float RGBA, the multi-shadow denoiser's input): the lights' visibility weighted by
//    their unshadowed irradiance (hrt_light_weight; 1 where no light reaches), mean penumbra
//    width over the occluded rays (world units, hrt_penumbra_width; -1 if none), min occluder
//    distance (0 if none), and the surface's distance to the camera.
//  - up to 4 per-light outputs in the single-light task's format (R = closest occluder
//    distance, negative if visible; G = visible fraction), for DenoiseShadowTask.
#include "common.glsl"
#include "random.glsl"
#include "light_sampling.glsl"

#define HRT_LIGHT_OUTPUTS 4

layout(set = 0, binding = 0) uniform accelerationStructureEXT u_tlas;
layout(set = 0, binding = 1) uniform sampler2D u_depth;
layout(set = 0, binding = 2) uniform sampler2D u_normals;
layout(set = 0, binding = 3) uniform writeonly uimage2D u_visibility;
layout(set = 0, binding = 4) uniform writeonly image2D u_packed;
layout(set = 0, binding = 5, std140) uniform MultiShadowConstants {
    TraceCommon common_;
    uvec4 counts;      // rays per pixel, light count, first-hit mode, has visibility_high
    uvec4 outputs;     // light written by each per-light output (0xffffffff: none)
    vec4 limits;       // max ray length, unused x3
    LightGpu lights[HRT_MAX_LIGHTS];
} u_c;
layout(set = 0, binding = 6) uniform sampler2D u_input_mask;
layout(set = 0, binding = 7) uniform writeonly uimage2D u_visibility_high;
layout(set = 0, binding = 8) uniform writeonly image2D u_light_out0;
layout(set = 0, binding = 9) uniform writeonly image2D u_light_out1;
layout(set = 0, binding = 10) uniform writeonly image2D u_light_out2;
layout(set = 0, binding = 11) uniform writeonly image2D u_light_out3;

void hrt_store_light_output(uint slot, ivec2 pixel, vec4 v) {
    if (slot == 0u) imageStore(u_light_out0, pixel, v);
    else if (slot == 1u) imageStore(u_light_out1, pixel, v);
    else if (slot == 2u) imageStore(u_light_out2, pixel, v);
    else imageStore(u_light_out3, pixel, v);
}

// The per-light outputs that show light l get v.
void hrt_store_light_outputs(uint l, ivec2 pixel, vec4 v) {
    for (uint k = 0u; k < HRT_LIGHT_OUTPUTS; ++k) {
        if (u_c.outputs[k] == l) hrt_store_light_output(k, pixel, v);
    }
}

void hrt_store_visibility(ivec2 pixel, uvec4 low, uvec4 high) {
    imageStore(u_visibility, pixel, low);
    if (u_c.counts.w != 0u) imageStore(u_visibility_high, pixel, high);
}

void hrt_multi_shadow_main() {
    TraceCommon c = u_c.common_;
    uvec2 pixel;
    vec3 p, n;
    int kind = hrt_gbuffer_pixel(c, HRT_LAUNCH_ID, u_depth, u_normals, u_input_mask, pixel, p, n);
    if (kind == HRT_PIXEL_SKIP) return;
    uint count = u_c.counts.y;
    if (kind == HRT_PIXEL_BACKGROUND) {
        hrt_store_visibility(ivec2(pixel), uvec4(0xffffffffu), uvec4(0xffffffffu));
        imageStore(u_packed, ivec2(pixel), vec4(1.0, -1.0, 0.0, 0.0));
        for (uint l = 0u; l < count; ++l) hrt_store_light_outputs(l, ivec2(pixel), vec4(-1.0, 1.0, 0.0, 0.0));
        return;
    }
    vec3 origin = hrt_offset_ray(c, p, n);
    uint rays = u_c.counts.x;
    // The same per-pixel sequence as the single-light task, so one light gives its image.
    HrtSequence seq = hrt_sequence(c.frame.x, c.frame.z != 0u, pixel, 0x5badu, rays);
    seq = hrt_with_generator(seq, c, pixel, 0x5badu, rays);
    uvec4 words[2] = uvec4[2](uvec4(0u), uvec4(0u));
    float vis_sum = 0.0, weight_sum = 0.0, width_sum = 0.0, dist_min = 1e30;
    uint occluded = 0u;
    uint flags = u_c.counts.z != 0u ? gl_RayFlagsTerminateOnFirstHitEXT : 0u;
    for (uint l = 0u; l < count; ++l) {
        LightGpu light = u_c.lights[l];
        float reach = hrt_light_reach(light, p);
        uint visible = 0u;
        float closest = 1e30;
        if (reach > 0.0) {
            for (uint i = 0u; i < rays; ++i) {
                vec3 dir;
                float tmax;
                hrt_light_ray(light, origin, hrt_sample(seq, i), dir, tmax);
                tmax = min(tmax, u_c.limits.x);
                float t = hrt_trace_record_flags(u_tlas, flags, c.frame.y & 0xffu, origin, dir, tmax).t;
                if (t < 0.0) {
                    visible += 1u;
                } else {
                    width_sum += hrt_penumbra_width(light, p, t);
                    closest = min(closest, t);
                    occluded += 1u;
                }
            }
        }
        dist_min = min(dist_min, closest);
        float fraction = reach > 0.0 ? float(visible) / float(rays) : 0.0;
        float w = hrt_light_weight(light, p, n, reach);
        vis_sum += w * fraction;
        weight_sum += w;
        words[l >> 4][(l >> 2) & 3u] |= uint(fraction * 255.0 + 0.5) << (8u * (l & 3u));
        // Outside the reach: unlit, as the single-light task writes it.
        vec4 single = reach <= 0.0 ? vec4(0.0) : vec4(visible == rays ? -1.0 : closest, fraction, 0.0, 0.0);
        hrt_store_light_outputs(l, ivec2(pixel), single);
    }
    hrt_store_visibility(ivec2(pixel), words[0], words[1]);
    imageStore(u_packed, ivec2(pixel), vec4(weight_sum > 0.0 ? vis_sum / weight_sum : 1.0,
                                            occluded > 0u ? width_sum / float(occluded) : -1.0,
                                            occluded > 0u ? dist_min : 0.0, distance(p, c.view_to_world[3].xyz)));
}
#endif
