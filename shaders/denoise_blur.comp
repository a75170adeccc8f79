#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Radiance denoiser, pass 3 (repeated): an edge-aware blur of 8 taps on a rotated disk, as
// NRD's REBLUR blurs (its blur and post-blur), with SVGF's variance-guided luminance stop
// (Schied et al. 2017). u_pass = (pass index from 0, last pass 0/1, 0, 0).
//
// What a pass costs is its fetches per pixel: 8 taps and the centre, each one fetch of the
// view's guide and one of each signal (and, for specular, of the roughness), where four 5x5
// à-trous iterations fetched 25 taps each. Specular and diffuse share the guide's fetches and
// each tap's geometry weight. The disk's radius halves with every pass (the first reaches
// BLUR_RADIUS pixels) and shrinks as the pixel's history grows (the temporal mean needs less
// help) and, for specular, as the surface gets smoother (a mirror is not blurred). Each pass
// turns the disk by its own angle, so what one pass misses the next covers; the same for every
// pixel, so neighbouring pixels fetch neighbouring texels, and the same every frame: the blur's
// output is not accumulated, and a disk turned per frame made the image flicker (0.22% -> 0.48%
// of the mean a frame for AO, 0.45% -> 1.78% for GI; 0.20% and 0.69% with a fixed disk).
// Stops: plane distance, normal, luminance against the local variance (the taps' own, weighted
// by their geometry), and roughness for specular; weights fall off as exp(-r²/R²) over the
// disk (a steeper fall-off, exp(-2r²/R²), left GI 10% noisier after 32 frames).
#include "include/denoise.glsl"

// Radius of the first pass's disk, in pixels, for a pixel without history.
const float BLUR_RADIUS = 16.0;
const int TAPS = 8;
// History length from which pixels beside a crease keep their value (see below).
const float CREASE_HISTORY = 8.0;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    uint count = u_d.flags.y;
    bool last = u_pass.y != 0u;
    bool any_specular = u_d.kinds.x == HRT_SIGNAL_SPECULAR || (count == 2u && u_d.kinds.y == HRT_SIGNAL_SPECULAR);
    vec3 p, n;
    HrtPixelRays rays = hrt_pixel_rays(u_d.c.clip_to_world);
    bool surface = hrt_surface_on(rays, imageLoad(u_gbuf_cur, pixel).xy, u_d.eye.xyz, pixel, p, n);
    vec4 c[2];
    [[unroll]] for (uint s = 0u; s < 2u; ++s) c[s] = s < count ? hrt_load_temp(s, pixel) : vec4(0.0);
    if (!surface) {
        [[unroll]] for (uint s = 0u; s < 2u; ++s) {
            if (s >= count) break;
            if (last) hrt_store_output(s, pixel, hrt_as_signal(u_d.kinds[s], hrt_load_input(s, pixel)));
            else hrt_store_temp(s, pixel, c[s]);
        }
        return;
    }
    float dist = distance(p, u_d.eye.xyz);
    float roughness = any_specular ? hrt_denoise_roughness(pixel) : 0.0;

    // Each signal's disk radius (0: this pass leaves the signal alone).
    float radius[2], len[2];
    float pass_radius = BLUR_RADIUS * exp2(-float(u_pass.x));
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        radius[s] = 0.0;
        len[s] = 0.0;
        if (s >= count) break;
        // The history length, from the fast history the clamp pass kept.
        len[s] = hrt_load_fast_prev(s, pixel).a;
        float scale = mix(1.0, u_d.history.w, clamp((len[s] - 1.0) / (0.25 * u_d.history.x), 0.0, 1.0));
        if (u_d.kinds[s] == HRT_SIGNAL_SPECULAR) scale *= clamp(roughness * 4.0, 0.0, 1.0);
        float r = pass_radius * scale;
        radius[s] = r >= 0.5 ? r : 0.0;
    }

    // The taps of a disk: a signal's own (the two signals' disks are the same, and share their
    // fetches, when their radii are: a task of both filters each as its own task would).
    float rotation = hrt_u01(hrt_pcg(u_pass.x + 1u)) * 2.0 * HRT_PI;
    vec4 t[2][TAPS];
    float lg[TAPS], r2[TAPS], rough[TAPS];
    bool ok[TAPS];
    float taps = 0.0, on_surface = 0.0;
    bool shared_disk = count == 2u && radius[0] == radius[1];
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        if (s >= count) break;
        uint kind = u_d.kinds[s];
        vec4 filtered = c[s];
        if (radius[s] > 0.0) {
            if (s == 0u || !shared_disk) {
                taps = 0.0;
                on_surface = 0.0;
                [[unroll]] for (int i = 0; i < TAPS; ++i) {
                    ok[i] = false;
                    float r = sqrt((float(i) + 0.5) / float(TAPS)) * radius[s];
                    float a = float(i) * 2.39996323 + rotation;
                    ivec2 q = pixel + ivec2(round(r * vec2(cos(a), sin(a))));
                    vec3 q_p, q_n;
                    if (q == pixel || !hrt_in_viewport(q) || !hrt_surface_on(rays, imageLoad(u_gbuf_cur, q).xy, u_d.eye.xyz, q, q_p, q_n)) continue;
                    ok[i] = true;
                    vec2 d = vec2(q - pixel);
                    r2[i] = dot(d, d);
                    lg[i] = hrt_geometry_log2_weight(p, n, dist, q_p, q_n);
                    taps += 1.0;
                    on_surface += lg[i] > -1.0 ? 1.0 : 0.0; // geometry weight > 0.5
                    if (any_specular) rough[i] = hrt_denoise_roughness(q);
                    t[s][i] = hrt_load_temp(s, q);
                    if (shared_disk) t[1][i] = hrt_load_temp(1u, q);
                }
            }
            bool specular = kind == HRT_SIGNAL_SPECULAR;
            float inv_r2 = 1.0 / (radius[s] * radius[s]);
            // The local variance: the centre's and its same-surface taps', weighted by geometry
            // (one noisy estimate would make the stop erratic).
            float variance = c[s].a, vw = 1.0;
            [[unroll]] for (int i = 0; i < TAPS; ++i) {
                if (!ok[i]) continue;
                float g = exp2(lg[i]);
                variance += g * t[s][i].a;
                vw += g;
            }
            float l_c = hrt_luminance(c[s].rgb);
            float inv_stop = 1.0 / (u_d.stops.x * sqrt(max(variance / vw, 0.0)) + 1e-4);
            vec3 sum = c[s].rgb;
            float wsum = 1.0, vsum = c[s].a;
            [[unroll]] for (int i = 0; i < TAPS; ++i) {
                if (!ok[i]) continue;
                float lum_stop = abs(hrt_luminance(t[s][i].rgb) - l_c) * inv_stop;
                float w = exp2(lg[i] - (lum_stop + r2[i] * inv_r2) * 1.4426950409);
                if (specular) w *= exp(-abs(rough[i] - roughness) * 10.0);
                sum += w * t[s][i].rgb;
                wsum += w;
                vsum += w * w * t[s][i].a;
            }
            filtered = vec4(sum / wsum, vsum / (wsum * wsum));
            // Beside a crease or an edge (15% of the disk on another surface) a pixel with
            // history sits at an extreme of its signal — the darkest AO in a corner — and every
            // neighbour left on its own surface lies to one side: a filter there only lifts it
            // (+6% in the room's creases without this rule). Such pixels keep their value once
            // their history is long enough to need no filter. AO only: occlusion has its
            // extreme in the crease by nature; GI need not (there the rule cost 28% more noise
            // for no measured bias).
            if (kind == HRT_SIGNAL_SCALAR && len[s] >= CREASE_HISTORY && taps > 0.0 && on_surface < 0.85 * taps) filtered = c[s];
        }
        if (last) hrt_store_output(s, pixel, vec4(filtered.rgb, 1.0));
        else hrt_store_temp(s, pixel, filtered);
    }
}
