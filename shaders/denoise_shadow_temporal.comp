#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Shadow denoiser, pass 3: temporal stabilisation. The reprojected history (visibility,
// length; the previous frame's, copied into the intermediate's z, w by the prep pass, so the
// kept history is overwritten in place here) is clamped to the 3x3 range of this frame's blurred visibility, so a moving
// shadow does not smear, then blended with weight 1 / length.
#include "include/denoise.glsl"

// Anti-lag thresholds (deviations) and the history kept past the soft one (frames).
const float ANTILAG_SIGMA = 4.0;
const float ANTILAG_SOFT = 3.0;
const float SOFT_FRAMES = 4.0;
// Mean change of the 3x3's visibility past which more than a column of it changed (see below).
const float WHOLE_CHANGE = 0.4;
// Penumbrae narrower than this half-width in pixels keep at most two frames while the view
// moves (see below). Sample in motion, 320x180: sun shadow error 0.082 with 0.5 pixels, 0.074
// with 1, 0.072 with 2 and wider (point light 0.042, 0.041, 0.040; at 640x360 with 0.5 pixels
// 0.065 and 0.037 on the H200, from 0.097 and 0.042 without the rule); one frame instead of two
// gave 0.075 / 0.063, four 0.104 / 0.043 (at 0.5 pixels).
const float SHARP_EDGE_RADIUS = 2.0;
// While the view moves, a pixel keeps at most 1 + EDGE_FRAMES r² frames, r the penumbra's
// half-width in pixels: where the blur found no penumbra (r under a sixth of a pixel: a hard
// edge, or a lit or umbra pixel beside one) the frame's own visibility is right and every
// resampled history only softens it. (Smaller factors also shorten real penumbrae's
// histories and make them noisier; docs/benchmarks.md has the measurements.)
const float EDGE_FRAMES = 36.0;

// The previous frame's history texel at q: the prep pass copied it into the intermediate for
// this frame's viewport; outside it (`resized`: the viewport shrank, dynamic resolution) the
// kept image still holds it, since this pass overwrites only the viewport's texels.
vec2 history_at(ivec2 q, bool resized) {
    return resized && !hrt_in_viewport(q) ? hrt_load_shadow_history(q) : hrt_load_temp(0u, q).zw;
}

// The pass for one pixel; `resized`: the viewport changed since the history was made.
void temporal(ivec2 pixel, bool resized) {
    vec3 p, n;
    if (!hrt_surface_at(imageLoad(u_gbuf_cur, pixel).xy, u_d.c.clip_to_world, u_d.eye.xyz, pixel, p, n)) {
        hrt_store_shadow_history(pixel, vec2(0.0));
        hrt_store_output(0u, pixel, vec4(1.0));
        return;
    }
    float dist = distance(p, u_d.eye.xyz);
    vec2 hist = vec2(0.0);
    vec2 previous = hrt_previous_position(pixel, p);
    bool resampled = false;
    if (u_d.flags.z == 0u) {
        ivec2 taps[4];
        vec4 w;
        hrt_history_taps(previous, p, n, dist, taps, w);
        float wsum = dot(w, vec4(1.0));
        // Whether the history is interpolated between texels (the view moved by part of a
        // pixel) rather than read from one.
        resampled = max(max(w.x, w.y), max(w.z, w.w)) < 0.99 * wsum;
        if (wsum > 1e-3) {
            for (int i = 0; i < 4; ++i) if (w[i] > 0.0) hist += w[i] * history_at(taps[i], resized);
            hist /= wsum;
        }
    }
    // This frame's 3x3 (its range for the clamp, its mean for anti-lag) and the history's
    // 3x3 about where the pixel was (nearest texels: the test compares means, not pixels).
    // (The pixel's own visibility comes out of it: one fetch fewer.)
    float v = 0.0, lo = 1e30, hi = -1e30, sum = 0.0, hsum = 0.0, hvar = 0.0, k = 0.0, radius_here = 0.0;
    float t[9];
    [[unroll]] for (int i = 0; i < 9; ++i) {
        ivec2 q = pixel + ivec2(i % 3 - 1, i / 3 - 1);
        t[i] = -1.0;
        if (!hrt_in_viewport(q)) continue;
        vec2 tt = hrt_load_temp(0u, q).xy;
        t[i] = tt.x;
        if (i == 4) { v = tt.x; radius_here = tt.y; }
        lo = min(lo, tt.x);
        hi = max(hi, tt.x);
    }
    // Where this frame's 3x3 is all one value (lit, or umbra) and the history agrees at the
    // pixel, the test cannot change the result: the clamp below holds the history within the
    // margin of that value either way. Most of a sunlit view is such pixels, and the history's
    // 3x3 is the pass's largest share of fetches.
    // One pixel of this frame spans `step` pixels of the history's viewport (dynamic
    // resolution; 1 otherwise): the history's 3x3 covers the same part of the scene.
    vec2 step = u_d.prev_viewport.zw / vec2(u_d.c.viewport.zw);
    ivec2 was = ivec2(floor(previous));
    bool settled = hi - lo < 1e-3 && abs(hist.x - v) < 1e-3;
    if (u_d.flags.z == 0u && hist.y > 0.0 && !settled) {
        [[unroll]] for (int i = 0; i < 9; ++i) {
            ivec2 d = ivec2(i % 3 - 1, i / 3 - 1);
            ivec2 r = resized ? ivec2(floor(previous + vec2(d) * step)) : was + d;
            if (t[i] < 0.0 || !(resized ? hrt_in_prev_viewport(r) : hrt_in_viewport(r))) continue;
            vec2 hq = history_at(r, resized);
            if (hq.y <= 0.0) continue;
            float hv = clamp(hq.x, 0.0, 1.0);
            sum += t[i];
            hsum += hv;
            hvar += hv * (1.0 - hv);
            k += 1.0;
        }
    }
    float h = clamp(hist.x, 0.0, 1.0);
    float prior = floor(hist.y + 0.5);
    // Anti-lag: were the history right, this frame's 3x3 would be k one-ray samples of the
    // visibilities the history holds there: their means agree within sqrt(sum h(1 - h)) / k
    // (less after the blur; both footprints have the same gradient, so a penumbra's slope
    // cancels). Past ANTILAG_SIGMA of that the shadow moved: the pixel keeps two frames of
    // history, or none where much of the 3x3 changed (a surface that went from lit to umbra
    // or back: an occluder or a sun patch that moved on, an object that entered the scene);
    // past ANTILAG_SOFT, at most SOFT_FRAMES. (A hard edge's 3x3 about where the pixel was
    // differs from this frame's by a column whenever the view moves by part of a pixel:
    // restarting on any change made a 0.03 rad sun's penumbrae 3x noisier. Two frames kept
    // everywhere left a tenth of the old light for a dozen frames, 10x its 1-ray noise, in
    // the sample's umbrae. A penumbra that moved away leaves mid-range histories the clamp
    // below cannot catch: its box must be wide there.)
    if (k >= 3.0) {
        float change = abs(sum - hsum);
        float z = change / k / (sqrt(hvar) / k + 0.02);
        if (z > ANTILAG_SIGMA) prior = change > WHOLE_CHANGE * k ? 0.0 : min(prior, 2.0);
        else if (z > ANTILAG_SOFT) prior = min(prior, SOFT_FRAMES);
    }
    float len = min(prior + 1.0, u_d.history.x);
    // A penumbra under SHARP_EDGE_RADIUS pixels (the blur's y: its half-width) is a sharp
    // edge, which one raw frame gets right but for the edge's own pixels. A history
    // interpolated between texels softens such an edge a little more every frame the view
    // moves, and the 3x3 box spans both sides of it, so nothing clamps that away: there the
    // pixel keeps at most two frames (one frame's softening; the blur pass averages such
    // pixels along their edge, which takes most of the one-ray noise). Still views read
    // single texels and keep everything.
    if (radius_here < SHARP_EDGE_RADIUS && resampled) len = min(len, 2.0);
    if (resampled) len = min(len, 1.0 + EDGE_FRAMES * radius_here * radius_here);
    // The box is widened by the noise a 3x3 of one-ray visibilities has where the history
    // says the visibility is h: 3 deviations of a mean of 9 Bernoulli samples. Without it a
    // penumbra pixel at 0.93 whose 9 neighbours all happened to be lit this frame (half the
    // frames) is pulled up to 0.95 every time: penumbrae biased towards their ends (0.2 rad
    // sun, 32 frames: 11.9% relative error instead of 7.5%). Where the history is lit or
    // umbra (h(1 - h) = 0) the box stays tight, so a shadow that moved away leaves at once.
    // The small fixed margin keeps the clamp from chasing each frame's blur noise.
    float margin = 0.05 + 3.0 * sqrt(h * (1.0 - h) / 9.0);
    float kept = clamp(hist.x, lo - margin, hi + margin);
    float result = mix(kept, v, 1.0 / len);
    // Checkerboard: a pixel not traced this frame holds its neighbours' mean, not a sample of
    // its own; folding that in every other frame blurred edges into the history (3x the
    // full-resolution error after 32 frames). With a history, it keeps it (clamped) instead.
    if (!hrt_traced_now(pixel) && prior >= 1.0) {
        len = prior;
        result = kept;
    }
    hrt_store_shadow_history(pixel, vec2(result, len));
    hrt_store_output(0u, pixel, vec4(result, result, result, 1.0));
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    // Two copies of the pass, chosen per dispatch (a uniform branch): the one for an unchanged
    // viewport, every frame but a resolution change, reads the history from the intermediate
    // alone and keeps the unscaled 3x3.
    if (hrt_viewport_changed()) {
        temporal(pixel, true);
    } else {
        temporal(pixel, false);
    }
}
