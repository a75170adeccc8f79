#version 460
#extension GL_GOOGLE_include_directive : require
// Shadow denoiser, pass 3: temporal stabilisation. The reprojected history (visibility,
// length) is clamped to the 3x3 range of this frame's blurred visibility, so a moving
// shadow does not smear, then blended with weight 1 / length.
#include "include/denoise.glsl"

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    vec3 p, n;
    if (!hrt_surface_at(imageLoad(u_gbuf_cur, pixel).xy, u_d.c.clip_to_world, u_d.eye.xyz, pixel, p, n)) {
        hrt_store_hist_cur(0u, pixel, vec4(0.0));
        hrt_store_output(0u, pixel, vec4(1.0));
        return;
    }
    float dist = distance(p, u_d.eye.xyz);
    float v = hrt_load_temp(0u, pixel).x;
    float lo = v, hi = v;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 q = pixel + ivec2(dx, dy);
            if (!hrt_in_viewport(q)) continue;
            float t = hrt_load_temp(0u, q).x;
            lo = min(lo, t);
            hi = max(hi, t);
        }
    }
    vec2 hist = vec2(0.0);
    if (u_d.flags.z == 0u) {
        ivec2 taps[4];
        vec4 w;
        hrt_history_taps(hrt_previous_position(pixel, p), p, n, dist, taps, w);
        float wsum = dot(w, vec4(1.0));
        if (wsum > 1e-3) {
            for (int i = 0; i < 4; ++i) if (w[i] > 0.0) hist += w[i] * hrt_load_hist_prev(0u, taps[i]).xy;
            hist /= wsum;
        }
    }
    float len = min(floor(hist.y + 0.5) + 1.0, u_d.history.x);
    // A small margin keeps the clamp from chasing each frame's blur noise on a static
    // scene; it bounds a moving shadow's trail to that margin.
    float result = mix(clamp(hist.x, lo - 0.05, hi + 0.05), v, 1.0 / len);
    hrt_store_hist_cur(0u, pixel, vec4(result, len, 0.0, 0.0));
    hrt_store_output(0u, pixel, vec4(result, result, result, 1.0));
}
