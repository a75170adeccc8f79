#version 460
#extension GL_GOOGLE_include_directive : require
// Radiance denoiser, pass 2: history clamping and variance. The slow history is clamped to the
// box mean ± sigma x std of the fast history's 3x3 neighbourhood (widened to hold the pixel's
// own fast value), so lighting and objects that move are followed within the fast window
// instead of ghosting. The clamped history is kept for the next frame. Variance (for the
// spatial filter's luminance stop): the temporal moments divided by the history length (the
// noise left in the mean), blended from the neighbourhood's while history is short.
// Both histories are kept in place here (the temporal pass has read the previous frame's), and
// the intermediate is filtered in place (the fast history's image is then free for à-trous).
// u_pass.y = 1: no spatial passes follow, write the output. AO near a moving object (while the
// scene changes, a second pipeline: HRT_MOVING_OBJECTS) starts over from this frame's sample
// (denoise_moving.comp found the objects; u_pass.x is this frame's stamp).
#include "include/denoise.glsl"

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    uint count = HRT_SIGNALS;
    bool last = u_pass.y != 0u;
    vec3 n;
    float dist;
    uvec2 surface = imageLoad(u_gbuf_cur, pixel).xy;
    hrt_unpack_surface(surface, n, dist);
    // A constant condition but in AO's pipeline for moving objects.
    bool near_moving = HRT_SIGNALS == 1u && HRT_KIND0 == HRT_SIGNAL_SCALAR && HRT_MOVING_OBJECTS != 0u && dist >= 0.0 &&
                       hrt_moving_load(ivec2(gl_GlobalInvocationID.xy) / HRT_MOVING_STAMP_TILE) == u_pass.x;
    for (uint s = 0u; s < count; ++s) {
        if (dist < 0.0) {
            hrt_keep_histories(s, pixel, vec4(0.0), hrt_load_fast_cur(s, pixel));
            if (last) hrt_store_output(s, pixel, hrt_as_signal(hrt_kind(s), hrt_load_input(s, pixel)));
            else hrt_store_temp(s, pixel, vec4(0.0));
            continue;
        }
        if (near_moving) {
            // This frame's sample alone: the history and the fast window behind the clamp both
            // lag a contact shadow that slides (the blur passes then keep it narrow). Nothing
            // to clamp, so no neighbourhood to read; its variance is the largest one
            // visibility sample can have (the luminance stop then leaves the narrow disk
            // alone, as a neighbourhood's spread of one sample would).
            vec3 p, n_again;
            hrt_surface_at(surface, u_d.c.clip_to_world, u_d.eye.xyz, pixel, p, n_again);
            vec4 cur = hrt_as_signal(hrt_kind(s), hrt_noisy_sample(s, pixel, p, n, dist));
            float l = hrt_luminance(cur.rgb);
            hrt_keep_histories(s, pixel, vec4(cur.rgb, l * l), vec4(cur.rgb, HRT_MOVING_LEN));
            if (last) hrt_store_output(s, pixel, vec4(cur.rgb, 1.0));
            else hrt_store_temp(s, pixel, vec4(cur.rgb, 0.25));
            continue;
        }
        vec4 fast_c = hrt_load_fast_cur(s, pixel);
        vec4 slow = hrt_load_temp(s, pixel);
        float len = max(fast_c.a, 1.0);
        vec3 m1 = vec3(0.0), m2 = vec3(0.0);
        float l1 = 0.0, l2 = 0.0, k = 0.0;
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                ivec2 q = pixel + ivec2(dx, dy);
                if (!hrt_in_viewport(q)) continue;
                vec4 f = hrt_load_fast_cur(s, q);
                if (f.a <= 0.0) continue;  // background
                float l = hrt_luminance(f.rgb);
                m1 += f.rgb; m2 += f.rgb * f.rgb; l1 += l; l2 += l * l; k += 1.0;
            }
        }
        m1 /= k; m2 /= k; l1 /= k; l2 /= k;
        vec3 sigma = sqrt(max(m2 - m1 * m1, vec3(0.0)));
        vec3 lo = min(m1 - u_d.history.z * sigma, fast_c.rgb);
        vec3 hi = max(m1 + u_d.history.z * sigma, fast_c.rgb);
        vec3 clamped = clamp(slow.rgb, lo, hi);
        float l_slow = hrt_luminance(slow.rgb);
        float var_temporal = max(slow.a - l_slow * l_slow, 0.0) / len;
        float var_spatial = max(l2 - l1 * l1, 0.0);
        float variance = mix(var_spatial, var_temporal, clamp((len - 1.0) / 7.0, 0.0, 1.0));
        hrt_keep_histories(s, pixel, vec4(clamped, slow.a), fast_c);
        if (last) hrt_store_output(s, pixel, vec4(clamped, 1.0));
        else hrt_store_temp(s, pixel, vec4(clamped, variance));
    }
}
