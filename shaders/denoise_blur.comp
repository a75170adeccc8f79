#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Radiance denoiser, pass 2 (repeated): an edge-aware blur of 8 taps on a rotated disk, as
// NRD's REBLUR blurs (its blur and post-blur), with SVGF's variance-guided luminance stop
// (Schied et al. 2017). u_pass = (pass index from 0, last pass 0/1, no filtering 0/1, 0): a
// task without spatial passes runs the first with no filtering, for the histories' sake.
//
// The first pass also keeps the temporal pass's histories for the next frame (in place: only
// the temporal pass reads the kept images, reprojected, and it cannot write them): the slow
// history from its input pair[0] (clamped RGB; the variance times the length), the fast one
// from pair[1] (this pass's output, read at the pixel before it is written).
//
// A pass fetches 8 taps and the centre, each one fetch of the view's guide and one of each
// signal (and, for specular, of the roughness), where four 5x5 à-trous iterations fetched 25
// taps each; and it weighs each tap as it arrives, keeping none, so it needs few registers
// (48-64: more pixels in flight hide the fetches' latency). Specular and diffuse share the
// guide's fetches and each tap's geometry weight. The disk's radius halves with every pass
// (the first reaches BLUR_RADIUS pixels) and shrinks as the pixel's history grows (the
// temporal mean needs less help) and, for specular, as the surface gets smoother (a mirror is
// not blurred). Each pass turns the disk by its own angle, so what one pass misses the next
// covers; the same for every pixel, so neighbouring pixels fetch neighbouring texels, and the
// same every frame: the blur's output is not accumulated, and a disk turned per frame made the
// image flicker (0.22% -> 0.48% of the mean a frame for AO, 0.45% -> 1.78% for GI; 0.20% and
// 0.69% with a fixed disk). Stops: plane distance, normal, luminance against the local
// variance (the centre's and the taps' before each tap, weighted by geometry: the disk runs
// outwards), and roughness for specular; weights fall off as exp(-r²/R²) over the disk (a
// steeper fall-off, exp(-2r²/R²), left GI 10% noisier after 32 frames).
#include "include/denoise.glsl"

// Radius of the first pass's disk, in pixels, for a pixel without history.
const float BLUR_RADIUS = 16.0;
// Taps per disk: 6 for AO alone (its blur passes were over the frame's budget on screens of
// surfaces: 19 fetches a pixel a pass with 8 taps, 15 with 6; the quality program's AO error
// 0.044 -> 0.047 at 8 frames, 0.021 -> 0.022 at 32), 8 for radiance.
const bool AO_ONLY = HRT_SIGNALS == 1u && HRT_KIND0 == HRT_SIGNAL_SCALAR;
const int TAPS = AO_ONLY ? 6 : 8;
// Diffuse GI's disk for a pixel without history: this share of BLUR_RADIUS, shrinking as
// history grows to the quarter every signal reaches. A young pixel's variance is wide, so the
// luminance stop lets a wide disk's taps through from other lighting: the bias they brought
// outweighed the noise they took (the sample in motion's GI 0.084 -> 0.079 at 640x360, 0.093
// -> 0.083 at 320x180; a still view's first frame 0.171 -> 0.132). Half the disk did less
// well at 320x180 (0.085); every diffuse disk halved, old pixels' too, worse (0.090).
const float DIFFUSE_YOUNG_SCALE = 0.35;
// Diffuse GI's luminance stop for a pixel without history: this many times
// DenoiserSettings::luminance_sigma wide, narrowing to it by FRESH_HISTORY frames. A young
// pixel's variance is its 3x3 neighbourhood's few 1-ray samples (or a history of few frames),
// too few to tell a skewed signal's noise from a lighting edge, and the stop kept out mostly
// noise: the sample in motion's GI 0.079 -> 0.075 at 640x360 (the 64-ray run's unchanged), a
// still view's first frame 0.132 -> 0.100. Old pixels keep the plain stop: 2.5x as wide for
// every pixel did as well in the sample but blurred the lighting a moving box carries (its
// wall's error 0.33 -> 0.48 in the motion-vector test; 0.33 with this rule), and narrowing by
// 8 frames kept a revealed wall's fine lighting blurred past the fast window.
const float DIFFUSE_STOP_SCALE = 4.0;
// AO takes half the taps once its history is this share of the longest: the temporal mean then
// holds most of the noise (the quality program's AO error 0.042 -> 0.043 at 8 frames, 0.021 ->
// 0.022 at 32; the room's AO blur passes at 1440p a sixth cheaper).
const float AO_FEW_TAPS_HISTORY = 0.25;
// Diffuse pixels with less history than this (revealed by a moving camera or object, or
// restarted by anti-lag) take DenoiserSettings::fresh_history_taps more taps in the first pass,
// on a disk of their own (see below).
const float FRESH_HISTORY = 4.0;
// AO near a moving object: the share of the disk kept (see below).
const float MOVING_RADIUS_SCALE = 0.25;
// History length from which pixels beside a crease keep their value (see below).
const float CREASE_HISTORY = 8.0;

// Each signal's running sums over its taps (see below): the weighted colour, weight and
// variance, the luminance stop's geometry-weighted variance, the centre's luminance and the
// disk's fall-off.
vec3 sum[2];
float wsum[2], vsum[2], l_c[2], inv_r2[2], var_sum[2], var_w[2], stop_k[2];

// Weighs tap `v` (rgb, variance) of signal `s` as it arrives: `lg` its geometry weight (log2),
// `r2` its squared distance in pixels, `extra_w` a further factor (specular: roughness).
void take_tap(uint s, vec4 v, float lg, float r2, float extra_w) {
    // The local variance so far: the centre's and the taps' before this one (the disk runs
    // outwards), weighted by their geometry — or the tap's own where that is larger, so the
    // stop is symmetric. A skewed 1-ray signal's bright pixels have the larger variances:
    // stopped by the centre's alone, a dark pixel kept its bright neighbours out while a bright
    // one took its dark neighbours in, and the image came out dark (the sample's reflections in
    // motion by 0.9%).
    float inv_stop = 1.0 / (stop_k[s] * sqrt(max(max(var_sum[s] / var_w[s], v.a), 0.0)) + 1e-4);
    float g = exp2(lg);
    var_sum[s] += g * v.a;
    var_w[s] += g;
    float lum_stop = abs(hrt_luminance(v.rgb) - l_c[s]) * inv_stop;
    float w = exp2(lg - (lum_stop + r2 * inv_r2[s]) * 1.4426950409) * extra_w;
    sum[s] += w * v.rgb;
    wsum[s] += w;
    vsum[s] += w * w * v.a;
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    uint count = HRT_SIGNALS;
    bool last = u_pass.y != 0u;
    bool any_specular = HRT_KIND0 == HRT_SIGNAL_SPECULAR || (count == 2u && HRT_KIND1 == HRT_SIGNAL_SPECULAR);
    vec3 p, n;
    HrtPixelRays rays = hrt_pixel_rays(u_d.c.clip_to_world);
    bool surface = hrt_surface_on(rays, imageLoad(u_gbuf_cur, pixel).xy, u_d.eye.xyz, pixel, p, n);
    bool first = u_pass.x == 0u;
    vec4 c[2], fast[2];
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        c[s] = fast[s] = vec4(0.0);
        if (s >= count) break;
        c[s] = hrt_load_temp(s, pixel);
        // The history length (and, in the first pass, the fast history to keep).
        fast[s] = first ? hrt_load_fast_cur(s, pixel) : hrt_load_fast_prev(s, pixel);
        // A pixel near a moving object (AO: HRT_MOVING_LEN) keeps no variance: it restarted.
        if (first) hrt_keep_histories(s, pixel, vec4(c[s].rgb, fast[s].a >= 1.0 ? c[s].a * fast[s].a : 0.0), fast[s]);
    }
    if (!surface) {
        [[unroll]] for (uint s = 0u; s < 2u; ++s) {
            if (s >= count) break;
            if (last) hrt_store_output(s, pixel, hrt_as_signal(hrt_kind(s), hrt_load_input(s, pixel)));
            else hrt_store_temp(s, pixel, c[s]);
        }
        return;
    }
    float dist = distance(p, u_d.eye.xyz);
    float roughness = any_specular ? hrt_denoise_roughness(pixel) : 0.0;

    // Each signal's disk radius (0: this pass leaves the signal alone).
    float radius[2], len[2];
    float pass_radius = u_pass.z != 0u ? 0.0 : BLUR_RADIUS * exp2(-float(u_pass.x));
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        radius[s] = 0.0;
        len[s] = 0.0;
        if (s >= count) break;
        len[s] = fast[s].a;
        float young = hrt_kind(s) == HRT_SIGNAL_DIFFUSE ? DIFFUSE_YOUNG_SCALE : 1.0;
        float scale = mix(young, u_d.history.w, clamp((len[s] - 1.0) / (0.25 * u_d.history.x), 0.0, 1.0));
        if (hrt_kind(s) == HRT_SIGNAL_SPECULAR) scale *= clamp(roughness * 4.0, 0.0, 1.0);
        // AO: the darker the pixel, the nearer its occluders and the smaller the features its
        // occlusion has — NRD scales its blur by the hit distance, and distance-weighted AO is
        // a function of it: a quarter of the disk at 0.7 and below, so a contact shadow is not
        // spread over the open floor around it (the quality program's AO error 0.047 -> 0.043
        // at 8 frames; the sample in motion 0.032 -> 0.028).
        if (hrt_kind(s) == HRT_SIGNAL_SCALAR) scale *= mix(0.25, 1.0, smoothstep(0.7, 1.0, c[s].x));
        // AO near a moving object (the temporal pass restarted it, HRT_MOVING_LEN): a narrow
        // disk, as a wide one spreads the contact shadow — a fifth of a sliding cube's
        // change missing with the full disk, none measurable with a quarter of it.
        if (hrt_kind(s) == HRT_SIGNAL_SCALAR && len[s] < 1.0) scale *= MOVING_RADIUS_SCALE;
        float r = pass_radius * scale;
        radius[s] = r >= 0.5 ? r : 0.0;
    }

    // Each signal's luminance stop: a tap's deviation from the centre against the local noise —
    // the variances the temporal pass wrote (the history's own over its frames, or its 3x3
    // neighbourhood's while the history is short; then each pass's filtered result's) of the
    // centre and of the taps already seen. (The centre's alone left GI 10% and glossy
    // reflections 25% noisier after 8 frames.)
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        sum[s] = c[s].rgb;
        wsum[s] = 1.0;
        vsum[s] = c[s].a;
        l_c[s] = hrt_luminance(c[s].rgb);
        var_sum[s] = c[s].a;
        var_w[s] = 1.0;
        inv_r2[s] = radius[s] > 0.0 ? 1.0 / (radius[s] * radius[s]) : 0.0;
        stop_k[s] = u_d.stops.x * (hrt_kind(s) == HRT_SIGNAL_DIFFUSE ? mix(DIFFUSE_STOP_SCALE, 1.0, clamp((len[s] - 1.0) / (FRESH_HISTORY - 1.0), 0.0, 1.0)) : 1.0);
    }

    // The taps of a disk: a signal's own, or both signals' when their radii agree (they then
    // share the guide's fetches and each tap's geometry weight: a task of both filters each as
    // its own task would). Each tap is weighted as it arrives (see above).
    float rotation = hrt_u01(hrt_pcg(u_pass.x + 1u)) * 2.0 * HRT_PI;
    bool shared_disk = count == 2u && radius[0] == radius[1];
    int fresh_taps = HRT_FRESH_TAPS != 0u && u_pass.x == 0u ? int(u_d.prev_eye.w) : 0;
    bool fresh[2];
    [[unroll]] for (uint s = 0u; s < 2u; ++s) fresh[s] = s < count && fresh_taps > 0 && hrt_kind(s) == HRT_SIGNAL_DIFFUSE && len[s] < FRESH_HISTORY;
    float taps = 0.0, on_surface = 0.0;
    [[unroll]] for (uint d = 0u; d < 2u; ++d) {
        if (d >= count || (d == 1u && shared_disk)) break;
        if (radius[d] <= 0.0) continue;
        // Half the taps: the first TAPS / 2 of the unrolled loop, on a spiral of that many.
        bool few = AO_ONLY && len[d] >= AO_FEW_TAPS_HISTORY * u_d.history.x;
        float disk_taps = few ? float(TAPS / 2) : float(TAPS);
        [[unroll]] for (int i = 0; i < TAPS; ++i) {
            if (i >= TAPS / 2 && few) break;
            float r = sqrt((float(i) + 0.5) / disk_taps) * radius[d];
            float a = float(i) * 2.39996323 + rotation;
            ivec2 q = pixel + ivec2(round(r * vec2(cos(a), sin(a))));
            vec3 q_p, q_n;
            if (q == pixel || !hrt_in_viewport(q) || !hrt_surface_on(rays, imageLoad(u_gbuf_cur, q).xy, u_d.eye.xyz, q, q_p, q_n)) continue;
            vec2 dq = vec2(q - pixel);
            float r2 = dot(dq, dq);
            float lg = hrt_geometry_log2_weight(p, n, dist, q_p, q_n);
            taps += 1.0;
            on_surface += lg > -1.0 ? 1.0 : 0.0; // geometry weight > 0.5
            float rough_w = any_specular ? exp(-abs(hrt_denoise_roughness(q) - roughness) * 10.0) : 1.0;
            [[unroll]] for (uint s = 0u; s < 2u; ++s) {
                if (s >= count || (s != d && !shared_disk)) continue;
                take_tap(s, hrt_load_temp(s, q), lg, r2, hrt_kind(s) == HRT_SIGNAL_SPECULAR ? rough_w : 1.0);
            }
        }
    }
    // A fresh diffuse pixel (see FRESH_HISTORY) takes `fresh_taps` more on a disk of its own,
    // after the shared one, which stays as it is for every pixel. At one ray per pixel a
    // pixel's first frames are the noisiest of the image — the blotches of a moving view. The
    // sample in motion (640x360): GI 0.075 -> 0.073 with 16; every other figure unchanged.
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        if (HRT_FRESH_TAPS == 0u || s >= count || !fresh[s] || radius[s] <= 0.0) continue;
        float extra_rotation = rotation + 0.5 * 2.39996323;
        for (int i = 0; i < fresh_taps; ++i) {
            float r = sqrt((float(i) + 0.5) / float(fresh_taps)) * radius[s];
            float a = float(i) * 2.39996323 + extra_rotation;
            ivec2 q = pixel + ivec2(round(r * vec2(cos(a), sin(a))));
            vec3 q_p, q_n;
            if (q == pixel || !hrt_in_viewport(q) || !hrt_surface_on(rays, imageLoad(u_gbuf_cur, q).xy, u_d.eye.xyz, q, q_p, q_n)) continue;
            vec2 dq = vec2(q - pixel);
            take_tap(s, hrt_load_temp(s, q), hrt_geometry_log2_weight(p, n, dist, q_p, q_n), dot(dq, dq), 1.0);
        }
    }

    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        if (s >= count) break;
        vec4 filtered = c[s];
        if (radius[s] > 0.0) {
            filtered = vec4(sum[s] / wsum[s], vsum[s] / (wsum[s] * wsum[s]));
            // Beside a crease or an edge (15% of the disk on another surface) a pixel with
            // history sits at an extreme of its signal — the darkest AO in a corner — and every
            // neighbour left on its own surface lies to one side: a filter there only lifts it
            // (+6% in the room's creases without this rule). Such pixels keep their value once
            // their history is long enough to need no filter. AO only (a one-signal task, so
            // the counts are its disk's): occlusion has its extreme in the crease by nature; GI
            // need not (there the rule cost 28% more noise for no measured bias).
            if (hrt_kind(s) == HRT_SIGNAL_SCALAR && len[s] >= CREASE_HISTORY && taps > 0.0 && on_surface < 0.85 * taps) filtered = c[s];
        }
        if (last) hrt_store_output(s, pixel, vec4(filtered.rgb, 1.0));
        else hrt_store_temp(s, pixel, filtered);
    }
}
