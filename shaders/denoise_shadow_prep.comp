#version 460
#extension GL_GOOGLE_include_directive : require
// Shadow denoiser, pass 1: decode the trace output into (visibility, penumbra width in world
// units or -1 where no ray was occluded) and write the denoiser's G-buffer. Single light: the
// width comes from the occluder distance and the light's size; multi-light: the trace task
// computed it (packed G). Checkerboard: untraced pixels take their traced neighbours' mean.
// Each 8x8 workgroup also summarises its tile for the blur: the mean penumbra width of its
// occluded samples, how many it holds (0: none, so the blur skips tiles out of reach), and
// whether any of its pixels sees some of the light (none: the blur skips umbra interiors).
#include "include/denoise.glsl"
#include "include/group_sum.glsl"

// (visibility, penumbra width or -1) of a traced texel at surface point p.
vec2 decode_shadow(ivec2 q, vec3 p) {
    vec4 v = hrt_load_input(0u, q);
    if (u_d.kinds.x == HRT_SIGNAL_MULTI_SHADOW) return vec2(v.r, v.g > 0.0 ? v.g : -1.0);
    float vis = u_d.kinds.z != 0u ? v.g : (v.r < 0.0 ? 1.0 : 0.0);
    return vec2(vis, v.r >= 0.0 ? hrt_penumbra_width(u_d.light, p, v.r) : -1.0);
}


// Decodes one pixel into the intermediate (with the pixel's history texel in z, w); returns
// (visibility, penumbra width or -1 where it holds no occluded sample).
vec2 prep(ivec2 pixel) {
    vec3 p, n;
    vec2 history = hrt_load_shadow_history(pixel);
    if (!hrt_engine_surface(pixel, p, n)) {
        imageStore(u_gbuf_cur, pixel, uvec4(hrt_pack_surface(vec3(0.0, 0.0, 1.0), -1.0), 0u, 0u));
        hrt_store_temp(0u, pixel, vec4(1.0, -1.0, history));
        return vec2(1.0, -1.0);
    }
    float dist = distance(p, u_d.eye.xyz);
    imageStore(u_gbuf_cur, pixel, uvec4(hrt_pack_surface(n, dist), 0u, 0u));
    vec2 result;
    if (hrt_traced_now(pixel)) {
        result = decode_shadow(pixel, p);
    } else {
        const ivec2 offs[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
        float vis = 0.0, vw = 0.0, pen = 0.0, pw = 0.0;
        for (int i = 0; i < 4; ++i) {
            ivec2 q = pixel + offs[i];
            vec3 q_p, q_n;
            if (!hrt_in_viewport(q) || !hrt_engine_surface(q, q_p, q_n)) continue;
            float w = hrt_geometry_weight(p, n, dist, q_p, q_n) + 1e-4;
            vec2 d = decode_shadow(q, q_p);
            vis += w * d.x; vw += w;
            if (d.y >= 0.0) { pen += w * d.y; pw += w; }
        }
        result = vec2(vw > 0.0 ? vis / vw : 1.0, pw > 0.0 ? pen / pw : -1.0);
    }
    hrt_store_temp(0u, pixel, vec4(result, history));
    return result;
}

void main() {
    uint me = gl_LocalInvocationIndex;
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    vec2 v = hrt_in_viewport(pixel) ? prep(pixel) : vec2(1.0, -1.0);
    // Per invocation (penumbra width, 1, 0) where its pixel holds an occluded sample, z = 1
    // where it sees some of the light; summed over the workgroup (no float atomics needed).
    vec3 sum = hrt_group_sum(vec3(v.y >= 0.0 ? vec2(min(v.y, 60000.0), 1.0) : vec2(0.0), v.x > 0.0 ? 1.0 : 0.0));
    // (mean width, count) as halves, the count negative where no pixel sees any light (pixels
    // outside the viewport count as lit); 0 where the tile holds no occluded sample.
    if (me == 0u) {
        uint texel = sum.y > 0.0 ? packHalf2x16(vec2(sum.x / sum.y, sum.z > 0.0 ? sum.y : -sum.y)) : 0u;
        imageStore(u_tiles, ivec2(gl_WorkGroupID.xy), uvec4(texel));
    }
}
