#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Radiance denoiser, pass 1: temporal accumulation and history clamping. Reprojects each
// pixel's surface (motion vectors or the cameras), keeps the bilinear taps of the previous frame
// that show the same surface, and blends this frame's sample into a slow history (window up to
// max frames; RGB + one sample's luminance variance) and a fast one (a few frames; RGB + history
// length). Specular history follows the reflected point when that lands on the same plane.
// The slow history is then clamped to the fast one's neighbourhood (see CLAMP below), and the
// variance the spatial passes stop on is made. Writes pair[0] (clamped slow RGB, variance) and
// pair[1] (fast RGB, length); the first blur pass keeps both for the next frame (the kept
// images are read here, reprojected, so they cannot be overwritten here). AO near a moving
// object (while the scene changes, a second pipeline: HRT_MOVING_OBJECTS) starts over from
// this frame's sample (denoise_moving.comp found the objects; u_pass.x is this frame's stamp).
#include "include/denoise.glsl"

// Anti-firefly threshold in standard deviations of the pixel's history (see below). A
// two-valued signal (a bright surface seen by a fraction p of the rays, dark elsewhere) has
// its bright samples (1 - p) / sqrt(p (1 - p)) deviations above its mean: 10 passes every
// such signal down to p = 1% — a small window, a lamp, a sun patch seen from afar — and cuts
// rarer ones. (4 cut everything under p = 6% and, the cut feeding the history it is measured
// against, darkened such light by ~17%.)
const float FIREFLY_SIGMA = 10.0;
// Anti-lag threshold, in standard deviations of the noise of the footprint's mean against the
// fast history (see below).
const float ANTILAG_SIGMA = 2.5;
const float ANTILAG_SOFT = 2.0;
// Reflections' thresholds sit this many deviations higher: their 1-ray samples are
// heavier-tailed (a glint, the sky through a gap). Measured on a glossy floor (quality program):
// 0 restarted chance pixels (error after 32 frames 0.042 instead of 0.038, flicker 0.62%
// instead of 0.39%); 1 left 5% of a moved object's reflection after 4 frames (1% with 0, 6%
// with 1.5; 96% without the test). Reflections no longer lose their glints to the firefly cut,
// so more chance deviations stay in their history: 0.5 keeps a moved object's trail at 5%
// (7% with 1) for a flicker of 0.42%.
const float SPECULAR_EXTRA = 0.5;
// A glossy reflection keeps at most this many frames per lobe width (GGX alpha, roughness²)
// that the view direction to its surface turned by since the last frame: its lobe moves with
// the view, and an older history shows what the lobe saw before (a lag no anti-lag test sees
// in 1-ray samples; NRD limits its specular accumulation by parallax likewise). The sample in
// motion (lavapipe, 320x180): reflections' error against the 64-ray trace 0.237 -> 0.201,
// the 64-ray run's own 0.191 -> 0.126; of the bias's -4.9%, 1.5 points go (0.25: 0.196 and 1.2
// points less; 0.18: 0.205 and 1.6). A still view keeps its history.
const float PARALLAX_LOBE_FRAMES = 0.2;
// The anti-lag test's footprint: (2r+1)^2 pixels (25 samples: a change of a quarter of the
// signal's range stands out of 1-ray noise).
const int ANTILAG_RADIUS = 2;
// A moving surface's diffuse lighting changes as it turns and travels: what lit it a few
// frames ago lit another place or orientation (an orbiting box's faces, a waving flag). Its
// diffuse history keeps at most this many frames per radian it turned since the last frame
// (the normal's turn, plus the distance it travelled over the distance to what its rays hit;
// hrt_history_taps_moved), and never fewer than the fast window. A still surface, or one moving
// through lighting that comes from far away, keeps its history. NRD limits accumulation by
// parallax likewise, for specular; this is the diffuse lobe's counterpart, only for surfaces
// that move in the world.
const float MOVING_TURN_FRAMES = 0.5;
// A surface moves when its motion vector lands more than this many pixels from where the
// cameras alone put it.
const float MOVING_PIXELS = 1.0;
// Without history: a sample this many times its brightest neighbour is a firefly (none is
// where every neighbour is black: a sparse signal's first hits look just like that).
const float FIREFLY_NEIGHBOUR_FACTOR = 8.0;

// The anti-lag test's tile: this group's 8x8 pixels, each with this frame's luminance of each
// signal and its fast history's (where that signal's history is read), stored by each pixel.
// A pixel's footprint is the 5x5 window of the tile nearest to it (centred where the group
// allows, shifted inwards at its border): the same 25 samples as a centred window, up to 2
// pixels off centre, for none of the 80 border texels a centred window needs from outside the
// group. An 8x8 tile has only 16 such windows: their sums are made once per group, separably
// (rows of 5, then columns of 5), and each pixel reads its window's — 25 taps a pixel with a
// geometry test each cost a quarter of the pass. The window holds every surface pixel in it,
// not only the pixel's own surface: both means the test compares cover the same pixels, so
// another surface in the window changes neither unless its signal changed too (then the
// pixel restarts with it — at a moving object's border, where its contact shadow changes).
const int TILE = 8;
const int SIDE = 2 * ANTILAG_RADIUS + 1;
const int WINDOWS = TILE - SIDE + 1; // window corners per axis
// Per signal: this frame's luminance and its fast history's (where that signal's history is
// read: for reflections the reflected point, or the surface where that is off screen).
shared float s_cur[HRT_SIGNALS][TILE * TILE];
shared float s_fast[HRT_SIGNALS][TILE * TILE];
shared float s_ok[TILE * TILE];   // 1 on a surface traced this frame whose history is on screen
// Per signal: (sum, sum of squares, fast sum, pixels) of each row's 5-wide windows, then of
// each 5x5 window.
shared vec4 s_row_win[HRT_SIGNALS][TILE * WINDOWS];
shared vec4 s_win[HRT_SIGNALS][WINDOWS * WINDOWS];
// Diffuse GI's group-wide test (see below): per tile row, (sum, sum of squares, fast sum,
// pixels) of the diffuse signal.
shared vec4 s_rows[TILE];
// The clamp's neighbourhood: each pixel's new fast history (RGB, length; 0 off a surface) per
// signal, as two pairs of halves (the values stored are halves already). A pixel's 3x3 box is
// the one of the tile nearest to it (shifted inwards at the tile's border, as the anti-lag
// windows are): the neighbours' fast histories are made by this pass, and a centred box would
// need another group's.
// (The arrays are sized by the signal count: the group's shared memory bounds how many groups
// a multiprocessor holds, and with them the pass's speed — 1 KB more slowed it by 8%.)
shared uvec2 s_box[HRT_SIGNALS][TILE * TILE];

void store_box_texel(uint s, uint e, vec4 v) { s_box[s][e] = uvec2(packHalf2x16(v.rg), packHalf2x16(v.ba)); }
vec4 box_texel(uint s, int e) { uvec2 v = s_box[s][e]; return vec4(unpackHalf2x16(v.x), unpackHalf2x16(v.y)); }

// Whether the task has a diffuse signal, and which. (Functions of the specialization
// constants: a driver folds them; glslang cannot make a short-circuit constant of them.)
bool has_diffuse() { return HRT_KIND0 == HRT_SIGNAL_DIFFUSE || (HRT_SIGNALS == 2u && HRT_KIND1 == HRT_SIGNAL_DIFFUSE); }
uint diffuse_signal() { return HRT_KIND0 == HRT_SIGNAL_DIFFUSE ? 0u : 1u; }

// Virtual motion: where the reflected point of the surface q_p (at distance q_dist, the
// reflection's hit distance behind it along the view ray: exact for planar reflectors) was in
// the previous frame, in pixels; false where it was behind the camera.
bool reflected_point_position(vec3 q_p, float q_dist, float hit_dist, out vec2 pos) {
    vec3 virtual_p = u_d.eye.xyz + (q_p - u_d.eye.xyz) / q_dist * (q_dist + max(hit_dist, 0.0));
    return hrt_previous_camera_position(virtual_p, pos);
}

// This pixel's texel of the anti-lag tile: this frame's sample (luminance) of each signal and
// its fast history's, where the pixel is a surface traced this frame with a history (`ok`).
void store_antilag_texel(bool ok, float cur[2], float fast[2]) {
    uint e = gl_LocalInvocationIndex;
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        if (s >= HRT_SIGNALS) break;
        s_cur[s][e] = ok ? cur[s] : 0.0;
        s_fast[s][e] = ok ? fast[s] : 0.0;
    }
    s_ok[e] = ok ? 1.0 : 0.0;
}

// Sums the 5x5 windows of the tile into s_win (every invocation calls it: it has barriers).
void sum_antilag_windows() {
    uint me = gl_LocalInvocationIndex;
    if (me < uint(TILE * WINDOWS)) {
        int row = int(me) / WINDOWS, x0 = int(me) % WINDOWS;
        [[unroll]] for (uint s = 0u; s < 2u; ++s) {
            if (s >= HRT_SIGNALS) break;
            vec4 sum = vec4(0.0);
            [[unroll]] for (int dx = 0; dx < SIDE; ++dx) {
                int e = row * TILE + x0 + dx;
                float lq = s_cur[s][e];
                sum += s_ok[e] * vec4(lq, lq * lq, s_fast[s][e], 1.0);
            }
            s_row_win[s][me] = sum;
        }
    }
    barrier();
    if (me < uint(WINDOWS * WINDOWS)) {
        int y0 = int(me) / WINDOWS, x0 = int(me) % WINDOWS;
        [[unroll]] for (uint s = 0u; s < 2u; ++s) {
            if (s >= HRT_SIGNALS) break;
            vec4 sum = vec4(0.0);
            [[unroll]] for (int dy = 0; dy < SIDE; ++dy) sum += s_row_win[s][(y0 + dy) * WINDOWS + x0];
            s_win[s][me] = sum;
        }
    }
    barrier();
}

void main() {
    // DenoiserSettings::anti_lag (kinds.w); the history is reset anyway when flags.z is set.
    // Uniform over the dispatch, so every invocation reaches the barrier before any returns.
    bool antilag = u_d.kinds.w != 0u && u_d.flags.z == 0u;
    bool reset = u_d.flags.z != 0u;
    uint count = HRT_SIGNALS;
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    bool inside = hrt_in_viewport(pixel);
    vec3 p = vec3(0.0), n = vec3(0.0, 0.0, 1.0);
    bool surface = inside && hrt_engine_surface(pixel, p, n);
    float dist = distance(p, u_d.eye.xyz);
    float roughness = surface ? hrt_denoise_roughness(pixel) : 1.0;

    // Each signal's sample and its reprojected histories, read before the anti-lag tile's
    // barrier: the tile holds their luminances (a pixel's history where the pixel reads it),
    // and their fetches' latency hides behind the barrier.
    vec4 cur[2], hist[2], fast[2];
    bool moving = false;
    vec2 moved = vec2(1.0, 0.0); // the surface's turn (cosine) and travel (world units): hrt_history_taps_moved
    ivec2 taps[4];
    vec4 weights = vec4(0.0);
    float lum_cur[2], lum_fast[2];
    bool found[2];
    if (surface) {
        vec2 was = hrt_previous_position(pixel, p);
        if (!reset) hrt_history_taps_moved(was, p, n, dist, taps, weights, moved);
        vec2 still;
        moving = u_d.flags.x != HRT_MOTION_NONE && hrt_previous_camera_position(p, still) && distance(was, still) > MOVING_PIXELS;
        [[unroll]] for (uint s = 0u; s < 2u; ++s) {
            cur[s] = hist[s] = fast[s] = vec4(0.0);
            lum_cur[s] = lum_fast[s] = 0.0;
            found[s] = false;
            if (s >= count) break;
            uint kind = hrt_kind(s);
            cur[s] = hrt_as_signal(kind, hrt_noisy_sample(s, pixel, p, n, dist));
            ivec2 t[4] = taps;
            vec4 w = weights;
            if (kind == HRT_SIGNAL_SPECULAR && !reset && roughness < 0.5) {
                // Virtual motion: the reflection moves with the reflected point.
                vec2 pos;
                if (reflected_point_position(p, dist, cur[s].a, pos)) {
                    ivec2 vt[4];
                    vec4 vw;
                    hrt_history_taps(pos, p, n, dist, vt, vw);
                    if (dot(vw, vec4(1.0)) > 0.5) { t = vt; w = vw; }
                }
            }
            float wsum = dot(w, vec4(1.0));
            if (wsum > 1e-3) {
                for (int i = 0; i < 4; ++i) {
                    if (w[i] <= 0.0) continue;
                    hist[s] += w[i] * hrt_load_hist_prev(s, t[i]);
                    fast[s] += w[i] * hrt_load_fast_prev(s, t[i]);
                }
                hist[s] /= wsum;
                fast[s] /= wsum;
                found[s] = true;
            }
            lum_cur[s] = hrt_luminance(cur[s].rgb);
            lum_fast[s] = hrt_luminance(fast[s].rgb);
        }
    } else {
        [[unroll]] for (uint s = 0u; s < 2u; ++s) {
            cur[s] = hist[s] = fast[s] = vec4(0.0);
            lum_cur[s] = lum_fast[s] = 0.0;
            found[s] = false;
        }
    }

    vec4 group = vec4(0.0);
    if (antilag) {
        store_antilag_texel(surface && hrt_traced_now(pixel) && found[0] && (count < 2u || found[1]), lum_cur, lum_fast);
        barrier();
        sum_antilag_windows();
        // Diffuse GI also compares the whole group's mean with its fast history's: a light
        // switched on changes GI by less than its 1-ray noise over 25 pixels, but not over 64
        // (the group's surfaces differ, which only widens the spread the test allows). The
        // quality program's light switch: 46% of the old lighting left after 4 frames with the
        // 25-pixel test alone, 12% with this one; static GI's error unchanged.
        if (has_diffuse()) {
            uint row = gl_LocalInvocationIndex;
            if (row < uint(TILE)) {
                vec4 r = vec4(0.0);
                for (int x = 0; x < TILE; ++x) {
                    int e = int(row) * TILE + x;
                    float lq = s_cur[diffuse_signal()][e];
                    r += s_ok[e] * vec4(lq, lq * lq, s_fast[diffuse_signal()][e], 1.0);
                }
                s_rows[row] = r;
            }
            barrier();
            for (int i = 0; i < TILE; ++i) group += s_rows[i];
        }
    }
    // AO near a moving object (a constant condition but in AO's pipeline for moving objects):
    // this frame's sample alone. The history and the fast window behind the clamp both lag a
    // contact shadow that slides (the blur passes then keep it narrow).
    bool near_moving = HRT_SIGNALS == 1u && HRT_KIND0 == HRT_SIGNAL_SCALAR && HRT_MOVING_OBJECTS != 0u && surface &&
                       hrt_moving_load(ivec2(gl_GlobalInvocationID.xy) / HRT_MOVING_STAMP_TILE) == u_pass.x;

    // Every store but the clamped slow history's is made before the clamp's barrier, so only
    // that history lives across it (what lives across a barrier holds registers).
    if (inside) imageStore(u_gbuf_cur, pixel, uvec4(surface ? hrt_pack_surface(n, dist) : hrt_pack_surface(vec3(0.0, 0.0, 1.0), -1.0), 0u, 0u));
    // Each signal's new slow history (RGB, one sample's luminance variance), kept in registers
    // for the clamp; the new fast history (RGB, length) goes to the image and to s_box.
    vec4 slow_new[2];
    // The anti-lag test's footprint (see below): this pixel's 5x5 window of the tile, whose
    // sums (sum, sum of squares, fast sum, pixels) were made once per group.
    ivec2 corner = clamp(ivec2(gl_LocalInvocationID.xy) - ANTILAG_RADIUS, ivec2(0), ivec2(WINDOWS - 1));
    int win = corner.y * WINDOWS + corner.x;
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        slow_new[s] = vec4(0.0);
        if (s >= count) break;
        store_box_texel(s, gl_LocalInvocationIndex, vec4(0.0));
        if (!inside) continue;
        if (!surface) {
            hrt_store_temp(s, pixel, vec4(0.0));
            hrt_store_fast_cur(s, pixel, vec4(0.0));
            continue;
        }
        if (near_moving) {
            // Nothing to clamp, so no neighbourhood to read; its variance is the largest one
            // visibility sample can have (the luminance stop then leaves the narrow disk
            // alone, as a neighbourhood's spread of one sample would).
            hrt_store_temp(s, pixel, vec4(cur[s].rgb, 0.25));
            hrt_store_fast_cur(s, pixel, hrt_round_half(vec4(cur[s].rgb, HRT_MOVING_LEN)));
            continue;
        }
        uint kind = hrt_kind(s);
        bool specular = kind == HRT_SIGNAL_SPECULAR;
        float len = found[s] ? fast[s].a : 0.0;
        // One sample's variance over the history (the slow history keeps it, as an exponential
        // moving variance: the same as its second moment less its mean's square, without the
        // cancellation).
        float hist_var = max(hist[s].a, 0.0);
        // Anti-lag (history confidence): this frame's samples in the 5x5 window and their
        // fast histories estimate the same thing while the signal holds still. When their
        // means differ by more than ANTILAG_SIGMA of their combined noise, the signal changed
        // under a history that the geometry tests kept (a moved object's contact AO, a light
        // switched on, an object that left a reflection): the pixel starts over from this
        // frame, and the spatial passes, seeing a short history, filter it wide.
        // Every signal, each against its own history where it reads it (reflections: where the
        // reflected point was). (A 3x3 test with this frame's spread alone biased 1-ray GI by
        // 1.4% — chance dark neighbourhoods restarted pixels dark; 25 samples and the history's
        // own variance keep it unbiased: +0.1..-0.3%.)
        if (len >= 2.0 && antilag) {
            vec4 f = s_win[s][win];
            float sum = f.x, sum2 = f.y, fsum = f.z, k = f.w;
            if (k >= 3.0) {
                float m = sum / k, mf = fsum / k;
                // One sample's variance: this frame's spread in the window, or the pixel's own
                // over its history when larger — nine 1-ray samples of a two-valued signal
                // (miss or hit) are often all alike, and a spread of 0 would call any
                // difference a change.
                float var = max(max(sum2 / k - m * m, 0.0), hist_var);
                // Both means cover the same k pixels: this frame's (k samples) and the fast
                // history's (k x its frames).
                float sigma = sqrt(var / k * (1.0 + 1.0 / min(len, u_d.history.y))) + 0.02 * max(m, mf) + 1e-3;
                // A deviation past ANTILAG_SIGMA restarts the pixel; one past ANTILAG_SOFT keeps
                // at most the fast window (a chance deviation costs little, a real change is
                // gone within a frame or two).
                float z = abs(m - mf) / sigma - (specular ? SPECULAR_EXTRA : 0.0);
                if (has_diffuse() && s == diffuse_signal() && group.w >= 16.0) {
                    float gm = group.x / group.w, gf = group.z / group.w;
                    float gvar = max(max(group.y / group.w - gm * gm, 0.0), hist_var);
                    float gsigma = sqrt(gvar / group.w * (1.0 + 1.0 / min(len, u_d.history.y))) + 0.02 * max(gm, gf) + 1e-3;
                    z = max(z, abs(gm - gf) / gsigma);
                }
                if (z > ANTILAG_SIGMA) len = 0.0;
                else if (z > ANTILAG_SOFT) len = min(len, u_d.history.y);
            }
        }
        // Anti-firefly, diffuse GI only. With a history of 4 frames or more, a sample is a
        // firefly when its luminance is more than FIREFLY_SIGMA deviations above this pixel's
        // history mean: a 1-ray distribution gets there only for light reaching fewer than 1%
        // of the rays, so the mean stays unbiased, while a 1-in-1000 path to a bright emitter
        // is cut down. With less history the 8 neighbours stand in, loosely (8x their
        // brightest, and no cut where all of them are black), as fresh pixels have no
        // statistics yet. (Clamping every sample to its brightest neighbour, as the first
        // generation did, darkened GI and glossy reflections by 2-6%.) Not reflections: a glint
        // of a lamp or a sun patch is their signal, and in a moving view their history (few
        // frames, another lobe) is no measure of it — the cut darkened the sample's reflections
        // in motion by 0.8% for no less error.
        if (u_d.flags.w != 0u && kind == HRT_SIGNAL_DIFFUSE) {
            float limit;
            if (len >= 4.0) {
                float m1 = hrt_luminance(hist[s].rgb);
                // A few frames' variance is often near 0 for a signal of a few discrete values
                // (sky or wall): the deviation never counts below the mean itself, so a
                // sample must also be (1 + FIREFLY_SIGMA) times the mean to be cut.
                limit = m1 + FIREFLY_SIGMA * max(sqrt(hist_var), m1) + 1e-4;
            } else {
                float lmax = -1.0;
                for (int dy = -1; dy <= 1; ++dy) {
                    for (int dx = -1; dx <= 1; ++dx) {
                        ivec2 q = pixel + ivec2(dx, dy);
                        if ((dx == 0 && dy == 0) || !hrt_in_viewport(q) || !hrt_traced_now(q)) continue;
                        lmax = max(lmax, hrt_luminance(hrt_load_input(s, q).rgb));
                    }
                }
                limit = lmax > 0.0 ? FIREFLY_NEIGHBOUR_FACTOR * lmax : 1e30;
            }
            float l = hrt_luminance(cur[s].rgb);
            if (l > limit) cur[s].rgb *= limit / l;
        }
        // Smoother specular accumulates fewer frames (its signal changes with the view); a
        // mirror keeps only this frame.
        float max_len = u_d.history.x;
        if (specular) {
            max_len = 1.0 + (max_len - 1.0) * clamp(roughness / 0.3, 0.0, 1.0);
            vec3 v = normalize(p - u_d.eye.xyz), v_prev = normalize(p - u_d.prev_eye.xyz);
            float turned = acos(clamp(dot(v, v_prev), -1.0, 1.0));
            max_len = min(max_len, max(1.0, PARALLAX_LOBE_FRAMES * roughness * roughness / max(turned, 1e-6)));
        }
        if (kind == HRT_SIGNAL_DIFFUSE && moving && found[s]) {
            float turned = acos(min(moved.x, 1.0)) + moved.y / max(cur[s].a, 1e-3);
            max_len = min(max_len, max(u_d.history.y, MOVING_TURN_FRAMES / max(turned, 1e-6)));
        }
        len = min(floor(len + 0.5) + 1.0, max_len);
        float a = 1.0 / len;
        float a_fast = max(a, 1.0 / u_d.history.y);
        // The moving variance: (1 - a)(var + a (l - mean)^2) is the second moment's blend less
        // the new mean's square, exactly.
        float dl = hrt_luminance(cur[s].rgb) - hrt_luminance(hist[s].rgb);
        slow_new[s] = vec4(mix(hist[s].rgb, cur[s].rgb, a), (1.0 - a) * (hist_var + a * dl * dl));
        vec4 fast_new = hrt_round_half(vec4(mix(fast[s].rgb, cur[s].rgb, a_fast), len));
        hrt_store_fast_cur(s, pixel, fast_new);
        store_box_texel(s, gl_LocalInvocationIndex, fast_new);
    }

    barrier();
    if (!inside || !surface || near_moving) return;
    ivec2 box = clamp(ivec2(gl_LocalInvocationID.xy) - 1, ivec2(0), ivec2(TILE - 3));
    [[unroll]] for (uint s = 0u; s < 2u; ++s) {
        if (s >= count) break;
        // CLAMP: the slow history is clamped to the box mean ± sigma x std of the fast
        // history's 3x3 neighbourhood (widened to hold the pixel's own fast value), so lighting
        // and objects that move are followed within the fast window instead of ghosting.
        // (A box texel's w: the length, above 0 on a surface.)
        vec3 m1 = vec3(0.0), m2 = vec3(0.0);
        float l1 = 0.0, l2 = 0.0, k = 0.0;
        [[unroll]] for (int dy = 0; dy < 3; ++dy) {
            [[unroll]] for (int dx = 0; dx < 3; ++dx) {
                vec4 f = box_texel(s, (box.y + dy) * TILE + box.x + dx);
                float l = hrt_luminance(f.rgb);
                m1 += f.rgb; m2 += f.rgb * f.rgb; l1 += l; l2 += l * l; k += f.a > 0.0 ? 1.0 : 0.0;
            }
        }
        // k >= 1: the pixel's own texel is in its box.
        m1 /= k; m2 /= k; l1 /= k; l2 /= k;
        vec4 own = box_texel(s, int(gl_LocalInvocationIndex));
        vec3 sigma = sqrt(max(m2 - m1 * m1, vec3(0.0)));
        // The box is never narrower than the noise of its own mean: k fast histories of up to
        // the fast window's samples each, a sample's variance the slow history's. At 1 ray per
        // pixel, light reaching few of the rays leaves most 3x3 fast windows without a hit — a
        // box of spread 0 at 0 — and clamping the slow mean into it darkened such light by
        // ~18%. A smooth signal's sample variance is small, so its box stays as tight.
        float box_samples = k * clamp(own.a, 1.0, u_d.history.y);
        float mean_noise = sqrt(max(slow_new[s].a, 0.0) / box_samples);
        sigma = max(sigma, mean_noise * slow_new[s].rgb / max(hrt_luminance(slow_new[s].rgb), 1e-4));
        vec3 lo = min(m1 - u_d.history.z * sigma, own.rgb);
        vec3 hi = max(m1 + u_d.history.z * sigma, own.rgb);
        vec3 clamped = clamp(slow_new[s].rgb, lo, hi);
        // Variance (for the spatial filter's luminance stop): the history's divided by its
        // length (the noise left in the mean), blended from the neighbourhood's while history
        // is short. The first blur pass keeps it, times the length, as the slow history's
        // variance: a short history's few samples are no measure of it.
        float len = own.a;
        float var_spatial = max(l2 - l1 * l1, 0.0);
        float variance = mix(var_spatial, slow_new[s].a / len, clamp((len - 1.0) / 7.0, 0.0, 1.0));
        hrt_store_temp(s, pixel, vec4(clamped, variance));
    }
}
