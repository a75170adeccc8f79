#version 460
#extension GL_GOOGLE_include_directive : require
// Radiance denoiser, pass 3 (repeated): one à-trous wavelet iteration (Dammertz et al. 2010,
// with SVGF's variance-guided luminance stop, Schied et al. 2017). 5x5 B3-spline taps at a
// spacing of step x scale, where scale shrinks from 1 to the minimum as the pixel's history
// grows (the temporal mean needs less help) and, for specular, with the roughness (a mirror
// is not blurred). Stops: plane distance, normal, luminance against the filtered variance,
// and roughness for specular. u_pass.x = step, u_pass.y = 1 on the last iteration.
#include "include/denoise.glsl"

// History length from which pixels beside a crease skip the wider iterations (see below).
const float CREASE_HISTORY = 8.0;

const float H[3] = float[3](0.375, 0.25, 0.0625);

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    uint count = u_d.flags.y;
    bool last = u_pass.y != 0u;
    vec3 p, n;
    HrtPixelRays rays = hrt_pixel_rays(u_d.c.clip_to_world);
    bool surface = hrt_surface_on(rays, imageLoad(u_gbuf_cur, pixel).xy, u_d.eye.xyz, pixel, p, n);
    float dist = distance(p, u_d.eye.xyz);
    float roughness = hrt_denoise_roughness(pixel);
    for (uint s = 0u; s < count; ++s) {
        uint kind = u_d.kinds[s];
        vec4 c = hrt_load_temp(s, pixel);
        if (!surface) {
            if (last) hrt_store_output(s, pixel, hrt_as_signal(kind, hrt_load_input(s, pixel)));
            else hrt_store_temp(s, pixel, c);
            continue;
        }
        // The history length, from the fast history the clamp pass kept.
        float len = hrt_load_fast_prev(s, pixel).a;
        float scale = mix(1.0, u_d.history.w, clamp((len - 1.0) / (0.25 * u_d.history.x), 0.0, 1.0));
        bool specular = kind == HRT_SIGNAL_SPECULAR;
        if (specular) scale *= clamp(roughness * 4.0, 0.0, 1.0);
        int spacing = int(float(u_pass.x) * scale + 0.5);
        if (spacing == 0) {
            if (last) hrt_store_output(s, pixel, vec4(c.rgb, 1.0));
            else hrt_store_temp(s, pixel, c);
            continue;
        }
        // Variance, 3x3 Gaussian-filtered (one noisy estimate would make the stop erratic).
        float variance = 0.0;
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                ivec2 q = clamp(pixel + ivec2(dx, dy), ivec2(u_d.c.viewport.xy), ivec2(u_d.c.viewport.xy + u_d.c.viewport.zw) - 1);
                variance += (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25) * hrt_load_temp(s, q).a;
            }
        }
        float l_c = hrt_luminance(c.rgb);
        float stop = u_d.stops.x * sqrt(max(variance, 0.0)) + 1e-4;
        float w_c = H[0] * H[0];
        vec3 sum = c.rgb * w_c;
        float wsum = w_c, vsum = w_c * w_c * c.a;
        float on_surface = 0.0, taps = 0.0;
        for (int yy = -2; yy <= 2; ++yy) {
            for (int xx = -2; xx <= 2; ++xx) {
                if (xx == 0 && yy == 0) continue;
                ivec2 q = pixel + ivec2(xx, yy) * spacing;
                if (!hrt_in_viewport(q)) continue;
                vec3 q_p, q_n;
                if (!hrt_surface_on(rays, imageLoad(u_gbuf_cur, q).xy, u_d.eye.xyz, q, q_p, q_n)) continue;
                vec4 t = hrt_load_temp(s, q);
                float lg = hrt_geometry_log2_weight(p, n, dist, q_p, q_n);
                taps += 1.0;
                on_surface += lg > -1.0 ? 1.0 : 0.0; // geometry weight > 0.5
                float lum_stop = abs(hrt_luminance(t.rgb) - l_c) / stop;
                float w = H[abs(xx)] * H[abs(yy)] * exp2(lg - lum_stop * 1.4426950409);
                if (specular) w *= exp(-abs(hrt_denoise_roughness(q) - roughness) * 10.0);
                sum += w * t.rgb;
                wsum += w;
                vsum += w * w * t.a;
            }
        }
        vec3 filtered = sum / wsum;
        // Beside a crease or an edge (15% of this iteration's footprint on another
        // surface) a pixel with history sits at an extreme of its signal — the darkest AO in
        // a corner — and every neighbour left on its own surface lies to one side: a filter
        // there only lifts it (+6% in the room's creases; +1.1% with a quarter of the
        // footprint as the bound, mean of 4 seeds; +0.7% now). Such pixels keep what the
        // earlier, smaller iterations made, once their history is long enough to need no more. AO only:
        // occlusion has its extreme in the crease by nature; GI need not (there the rule cost
        // 28% more noise for no measured bias).
        if (kind == HRT_SIGNAL_SCALAR && len >= CREASE_HISTORY && taps > 0.0 && on_surface < 0.85 * taps) filtered = c.rgb;
        if (last) hrt_store_output(s, pixel, vec4(filtered, 1.0));
        else hrt_store_temp(s, pixel, vec4(filtered, vsum / (wsum * wsum)));
    }
}
