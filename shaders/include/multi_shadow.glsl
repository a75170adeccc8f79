#ifndef HRT_MULTI_SHADOW_GLSL
#define HRT_MULTI_SHADOW_GLSL
// Shadows from up to 16 lights in one pass: rays_per_pixel rays towards each light (same
// sampling as the single-light task). Two outputs:
//  - visibility (uint): 8 bits per light, the fraction of its rays that reached it x 255,
//    four lights per 32-bit channel (light i in channel i/4, bits 8*(i%4)).
//  - packed (float RGBA, the multi-shadow denoiser's input): mean visibility over the
//    lights, mean penumbra width over the occluded rays (world units, hrt_penumbra_width;
//    -1 if none), min occluder distance (0 if none), and the surface's distance to the camera.
#include "common.glsl"
#include "light_sampling.glsl"

layout(set = 0, binding = 0) uniform accelerationStructureEXT u_tlas;
layout(set = 0, binding = 1) uniform sampler2D u_depth;
layout(set = 0, binding = 2) uniform sampler2D u_normals;
layout(set = 0, binding = 3) uniform writeonly uimage2D u_visibility;
layout(set = 0, binding = 4) uniform writeonly image2D u_packed;
layout(set = 0, binding = 5, std140) uniform MultiShadowConstants {
    TraceCommon common_;
    uvec4 counts;      // rays per pixel, light count, first-hit mode
    LightGpu lights[16];
} u_c;
layout(set = 0, binding = 6) uniform sampler2D u_input_mask;

void hrt_multi_shadow_main() {
    TraceCommon c = u_c.common_;
    uvec2 pixel;
    vec3 p, n;
    int kind = hrt_gbuffer_pixel(c, HRT_LAUNCH_ID, u_depth, u_normals, u_input_mask, pixel, p, n);
    if (kind == HRT_PIXEL_SKIP) return;
    if (kind == HRT_PIXEL_BACKGROUND) {
        imageStore(u_visibility, ivec2(pixel), uvec4(0xffffffffu));
        imageStore(u_packed, ivec2(pixel), vec4(1.0, -1.0, 0.0, 0.0));
        return;
    }
    vec3 origin = hrt_offset_ray(c, p, n);
    uint rays = u_c.counts.x, count = u_c.counts.y;
    // The same per-pixel sequence as the single-light task, so one light gives its image.
    uint seed = hrt_pcg(pixel.x ^ hrt_pcg(pixel.y ^ hrt_pcg(c.frame.x ^ 0x5badu)));
    vec2 shift = vec2(hrt_u01(seed), hrt_u01(hrt_pcg(seed)));
    uvec4 words = uvec4(0u);
    float vis_sum = 0.0, width_sum = 0.0, dist_min = 1e30;
    uint occluded = 0u;
    uint flags = u_c.counts.z != 0u ? gl_RayFlagsTerminateOnFirstHitEXT : 0u;
    for (uint l = 0u; l < count; ++l) {
        uint visible = 0u;
        for (uint i = 0u; i < rays; ++i) {
            vec3 dir;
            float tmax;
            hrt_light_ray(u_c.lights[l], origin, hrt_r2(i, shift), dir, tmax);
            float t = hrt_trace_record_flags(u_tlas, flags, c.frame.y & 0xffu, origin, dir, tmax).t;
            if (t < 0.0) {
                visible += 1u;
            } else {
                width_sum += hrt_penumbra_width(u_c.lights[l], p, t);
                dist_min = min(dist_min, t);
                occluded += 1u;
            }
        }
        float fraction = float(visible) / float(rays);
        vis_sum += fraction;
        words[l >> 2] |= uint(fraction * 255.0 + 0.5) << (8u * (l & 3u));
    }
    imageStore(u_visibility, ivec2(pixel), words);
    imageStore(u_packed, ivec2(pixel), vec4(vis_sum / float(count), occluded > 0u ? width_sum / float(occluded) : -1.0,
                                            occluded > 0u ? dist_min : 0.0, distance(p, c.view_to_world[3].xyz)));
}
#endif
