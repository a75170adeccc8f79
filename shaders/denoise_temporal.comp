#version 460
#extension GL_GOOGLE_include_directive : require
// Radiance denoiser, pass 1: temporal accumulation. Reprojects each pixel's surface (motion
// vectors or the cameras), keeps the bilinear taps of the previous frame that show the same
// surface, and blends this frame's sample into a slow history (window up to max frames; RGB +
// second luminance moment) and a fast one (a few frames; RGB + history length). Specular
// history follows the reflected point when that lands on the same plane.
#include "include/denoise.glsl"

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    uint count = u_d.flags.y;
    vec3 p, n;
    if (!hrt_engine_surface(pixel, p, n)) {
        imageStore(u_gbuf_cur, pixel, uvec4(hrt_pack_surface(vec3(0.0, 0.0, 1.0), -1.0), 0u, 0u));
        for (uint s = 0u; s < count; ++s) {
            hrt_store_temp(s, pixel, vec4(0.0));
            hrt_store_fast_cur(s, pixel, vec4(0.0));
        }
        return;
    }
    float dist = distance(p, u_d.eye.xyz);
    imageStore(u_gbuf_cur, pixel, uvec4(hrt_pack_surface(n, dist), 0u, 0u));
    bool reset = u_d.flags.z != 0u;
    ivec2 taps[4];
    vec4 weights = vec4(0.0);
    if (!reset) hrt_history_taps(hrt_previous_position(pixel, p), p, n, dist, taps, weights);
    float roughness = hrt_denoise_roughness(pixel);

    for (uint s = 0u; s < count; ++s) {
        uint kind = u_d.kinds[s];
        vec4 cur = hrt_as_signal(kind, hrt_noisy_sample(s, pixel, p, n, dist));
        bool specular = kind == HRT_SIGNAL_SPECULAR;
        // Anti-firefly: a sample brighter than all 8 neighbours is brought down to the
        // brightest of them. Mirrors keep their exact (noise-free) reflection.
        if (u_d.flags.w != 0u && kind != HRT_SIGNAL_SCALAR && !(specular && roughness < 0.05)) {
            float lmax = -1.0;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    ivec2 q = pixel + ivec2(dx, dy);
                    if ((dx == 0 && dy == 0) || !hrt_in_viewport(q) || !hrt_traced_now(q)) continue;
                    lmax = max(lmax, hrt_luminance(hrt_load_input(s, q).rgb));
                }
            }
            float l = hrt_luminance(cur.rgb);
            if (lmax >= 0.0 && l > lmax) cur.rgb *= lmax / l;
        }

        ivec2 t[4] = taps;
        vec4 w = weights;
        if (specular && !reset && roughness < 0.5) {
            // Virtual motion: the reflection moves with the reflected point, hit distance
            // behind the surface along the view ray (exact for planar reflectors).
            vec3 virtual_p = u_d.eye.xyz + (p - u_d.eye.xyz) / dist * (dist + max(cur.a, 0.0));
            vec4 clip = u_d.prev_world_to_clip * vec4(virtual_p, 1.0);
            if (clip.w > 0.0) {
                vec2 pos = (clip.xy / clip.w * 0.5 + 0.5) * u_d.c.viewport.zw + u_d.c.viewport.xy;
                ivec2 vt[4];
                vec4 vw;
                hrt_history_taps(pos, p, n, dist, vt, vw);
                if (dot(vw, vec4(1.0)) > 0.5) { t = vt; w = vw; }
            }
        }
        float wsum = dot(w, vec4(1.0));
        vec4 hist = vec4(0.0), fast = vec4(0.0);
        float len = 0.0;
        if (wsum > 1e-3) {
            for (int i = 0; i < 4; ++i) {
                if (w[i] <= 0.0) continue;
                hist += w[i] * hrt_load_hist_prev(s, t[i]);
                fast += w[i] * hrt_load_fast_prev(s, t[i]);
            }
            hist /= wsum;
            fast /= wsum;
            len = fast.a;
        }
        // Smoother specular accumulates fewer frames (its signal changes with the view); a
        // mirror keeps only this frame.
        float max_len = u_d.history.x;
        if (specular) max_len = 1.0 + (max_len - 1.0) * clamp(roughness / 0.3, 0.0, 1.0);
        len = min(floor(len + 0.5) + 1.0, max_len);
        float a = 1.0 / len;
        float a_fast = max(a, 1.0 / u_d.history.y);
        float l = hrt_luminance(cur.rgb);
        hrt_store_temp(s, pixel, vec4(mix(hist.rgb, cur.rgb, a), mix(hist.a, l * l, a)));
        hrt_store_fast_cur(s, pixel, vec4(mix(fast.rgb, cur.rgb, a_fast), len));
    }
}
