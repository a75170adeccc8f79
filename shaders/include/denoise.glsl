// Shared by the denoiser's compute passes (sdk/src/passes/denoise): one descriptor layout for
// all of them, the constants, G-buffer packing and reprojection helpers.
#ifndef HRT_DENOISE_GLSL
#define HRT_DENOISE_GLSL
#include "common.glsl"
#include "light_sampling.glsl"

// Signal kinds (DenoiseConstants.kinds).
#define HRT_SIGNAL_DIFFUSE 0u
#define HRT_SIGNAL_SPECULAR 1u
#define HRT_SIGNAL_SCALAR 2u
#define HRT_SIGNAL_SHADOW 3u
#define HRT_SIGNAL_MULTI_SHADOW 4u

// Motion types (DenoiseConstants.flags.x).
#define HRT_MOTION_NONE 0u
#define HRT_MOTION_VIEW 1u
#define HRT_MOTION_CLIP 2u
#define HRT_MOTION_WORLD 3u

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0) uniform sampler2D u_depth;
layout(set = 0, binding = 1) uniform sampler2D u_normals;
layout(set = 0, binding = 2) uniform sampler2D u_roughness;
layout(set = 0, binding = 3) uniform sampler2D u_motion;
// Two signals (specular and diffuse in one pass) have a binding each; one-signal tasks bind
// the same image twice. The accessors below take the signal index (a constant at every call).
layout(set = 0, binding = 4) uniform sampler2D u_input0;
layout(set = 0, binding = 5) uniform sampler2D u_input1;
layout(set = 0, binding = 6) uniform writeonly image2D u_output0;
layout(set = 0, binding = 7) uniform writeonly image2D u_output1;
layout(set = 0, binding = 8, r32ui) uniform readonly uimage2D u_gbuf_prev;
layout(set = 0, binding = 9, r32ui) uniform uimage2D u_gbuf_cur;
layout(set = 0, binding = 10, rgba16f) uniform readonly image2D u_hist_prev0;
layout(set = 0, binding = 11, rgba16f) uniform readonly image2D u_hist_prev1;
layout(set = 0, binding = 12, rgba16f) uniform image2D u_hist_cur0;
layout(set = 0, binding = 13, rgba16f) uniform image2D u_hist_cur1;
// The kept histories are single images: u_hist_prev and u_hist_cur name the same image, read
// (reprojected) by the temporal pass and overwritten in place by the first blur pass; the fast
// history goes through u_fast_cur (an intermediate: the second image of the signal's pair)
// from the temporal pass to the first blur pass, which copies it into u_fast_prev (the kept
// one) in place, where the later blur passes read its history length.
layout(set = 0, binding = 14, rgba16f) uniform image2D u_fast_prev0;
layout(set = 0, binding = 15, rgba16f) uniform image2D u_fast_prev1;
layout(set = 0, binding = 16, rgba16f) uniform image2D u_fast_cur0;
layout(set = 0, binding = 17, rgba16f) uniform image2D u_fast_cur1;
layout(set = 0, binding = 18, rgba16f) uniform readonly image2D u_temp_src0;
layout(set = 0, binding = 19, rgba16f) uniform readonly image2D u_temp_src1;
layout(set = 0, binding = 20, rgba16f) uniform writeonly image2D u_temp_dst0;
layout(set = 0, binding = 21, rgba16f) uniform writeonly image2D u_temp_dst1;
layout(set = 0, binding = 22, std140) uniform DenoiseConstants {
    TraceCommon c;           // this frame's camera and G-buffer decoding; frame.x = ticket serial
    mat4 prev_world_to_clip;
    mat4 prev_clip_to_world;
    vec4 eye;                // camera position, w = world size of a pixel at unit distance
    vec4 prev_eye;           // previous camera position, w = extra first-pass taps of fresh diffuse pixels
    uvec4 flags;             // motion type, signal count, reset history (0/1), anti-firefly (0/1)
    uvec4 kinds;             // signal kind of input 0 and 1, shadow input has a visibility channel (0/1), anti-lag (0/1)
    vec4 motion_scale;       // xyz
    vec4 jitter_delta;       // previous - current jitter in pixels
    vec4 history;            // max frames, fast frames, clamp sigma, min radius scale
    vec4 stops;              // luminance sigma, normal power, plane-distance sigma, max shadow radius (px)
    vec4 prev_viewport;      // the viewport the history was made in (x, y, w, h): dynamic resolution
    LightGpu light;          // single-light shadows
} u_d;
layout(set = 0, binding = 23) uniform sampler2D u_input_mask;
// One texel per 8x8 tile of the viewport (a workgroup of the shadow passes): the mean
// penumbra width (world units) of the tile's occluded shadow samples and their count, as two
// halves (the count negative where none of the tile's pixels sees any light); 0 where the tile
// holds no occluded sample. Written by the shadow prep pass, read by the blur (radiance passes
// bind it and ignore it).
layout(set = 0, binding = 24, r32ui) uniform uimage2D u_tiles;
// The shadow denoiser's history, kept single: (visibility, history length) as two halves. The
// prep pass copies each pixel's texel into the intermediates (their z, w), where the later
// passes read the previous frame's; the temporal pass then overwrites it in place. (Radiance
// passes bind a stand-in and ignore it.)
layout(set = 0, binding = 25, r32ui) uniform uimage2D u_shadow_history;
// AO: which 32x32 tiles of the viewport a moving object's occlusion reaches, as the number of
// the frame that found it there (a stamp: nothing to clear). Written by denoise_moving.comp
// while the scene changes, read by the temporal pass after it; other passes bind a stand-in.
layout(set = 0, binding = 26, r32ui) uniform uimage2D u_motion_tiles;

// The radiance passes' signal configuration, fixed per pipeline (one pipeline per signal type:
// specular + diffuse, specular, diffuse, AO) so the compiler drops the code and the registers
// of the signals a task does not have; DenoiseConstants.flags.y and kinds.xy hold the same.
// (The shadow passes leave them at their defaults and ignore them.)
layout(constant_id = 0) const uint HRT_SIGNALS = 2u;
layout(constant_id = 1) const uint HRT_KIND0 = HRT_SIGNAL_SPECULAR;
layout(constant_id = 2) const uint HRT_KIND1 = HRT_SIGNAL_DIFFUSE;
uint hrt_kind(uint s) { return s == 0u ? HRT_KIND0 : HRT_KIND1; }
// AO's temporal pass: whether this pipeline reads the moving-object stamps (a second pipeline,
// used while the scene changes: see denoise_moving.comp).
layout(constant_id = 3) const uint HRT_MOVING_OBJECTS = 0u;
// The blur's pipeline for DenoiserSettings::fresh_history_taps above 0 (its first pass only):
// the extra taps' loop, merely present, cost the radiance blur passes 2-4% of their time.
layout(constant_id = 4) const uint HRT_FRESH_TAPS = 0u;

layout(push_constant) uniform Pass {
    // Blur: pass index, last pass (0/1), no filtering (0/1). Temporal: this frame's stamp (AO's
    // moving objects: its guide frame, never 0). AO's moving-object pass: the stamp, 0,
    // HRT_MOVING_* flags, reach (world units, float bits).
    uvec4 u_pass;
};

// The moving-object pass's flags (u_pass.z): the camera did not move.
#define HRT_MOVING_STILL_CAMERA 4u
// Pixels per side of u_motion_tiles' tiles.
const int HRT_MOVING_STAMP_TILE = 32;
uint hrt_moving_load(ivec2 tile) { return imageLoad(u_motion_tiles, tile).x; }
void hrt_moving_store(ivec2 tile, uint stamp) { imageStore(u_motion_tiles, tile, uvec4(stamp)); }
// The history length a pixel near a moving object stores (it restarted this frame): below 1,
// so the blur passes know to keep the contact occlusion sharp.
const float HRT_MOVING_LEN = 0.5;

// The denoiser's own images are RGBA16F, and Vulkan lets a store to them round towards zero
// (lavapipe does). A running mean stored that way every frame loses half an ulp a frame on
// average — 0.6% darker after 32 frames, measured — so values are rounded to the nearest
// half-float here, and any conversion after that is exact. (Normal range: the tiny values
// where half-floats are subnormal carry no weight in a mean.)
vec4 hrt_round_half(vec4 v) {
    vec4 r;
    for (int k = 0; k < 4; ++k) {
        int e;
        float m = frexp(v[k], e);              // v = m * 2^e, |m| in [0.5, 1)
        r[k] = ldexp(round(ldexp(m, 11)), e - 11); // 11 significant bits, as a half has
    }
    return r;
}

vec4 hrt_load_input(uint s, ivec2 q) { return s == 0u ? texelFetch(u_input0, q, 0) : texelFetch(u_input1, q, 0); }
void hrt_store_output(uint s, ivec2 q, vec4 v) { if (s == 0u) imageStore(u_output0, q, v); else imageStore(u_output1, q, v); }
// A scalar signal (AO) keeps both its histories in one texel of its history image: (slow,
// variance, fast, length); the loads below spread them back to (rgb, variance) and (rgb,
// length), and hrt_keep_histories packs them.
vec4 hrt_load_hist_prev(uint s, ivec2 q) {
    vec4 v = s == 0u ? imageLoad(u_hist_prev0, q) : imageLoad(u_hist_prev1, q);
    return hrt_kind(s) == HRT_SIGNAL_SCALAR ? v.xxxy : v;
}
vec4 hrt_load_hist_cur(uint s, ivec2 q) { return s == 0u ? imageLoad(u_hist_cur0, q) : imageLoad(u_hist_cur1, q); }
void hrt_store_hist_cur(uint s, ivec2 q, vec4 v) { v = hrt_round_half(v); if (s == 0u) imageStore(u_hist_cur0, q, v); else imageStore(u_hist_cur1, q, v); }
vec4 hrt_load_fast_prev(uint s, ivec2 q) {
    if (hrt_kind(s) == HRT_SIGNAL_SCALAR) return (s == 0u ? imageLoad(u_hist_prev0, q) : imageLoad(u_hist_prev1, q)).zzzw;
    return s == 0u ? imageLoad(u_fast_prev0, q) : imageLoad(u_fast_prev1, q);
}
// Keeps this frame's slow history and fast history (`fast` as hrt_store_fast_cur rounded it)
// for the next frame, in place.
void hrt_keep_histories(uint s, ivec2 q, vec4 slow, vec4 fast) {
    if (hrt_kind(s) == HRT_SIGNAL_SCALAR) {
        hrt_store_hist_cur(s, q, vec4(slow.x, slow.a, fast.x, fast.a));
        return;
    }
    hrt_store_hist_cur(s, q, slow);
    if (s == 0u) imageStore(u_fast_prev0, q, fast); else imageStore(u_fast_prev1, q, fast);
}
vec4 hrt_load_fast_cur(uint s, ivec2 q) { return s == 0u ? imageLoad(u_fast_cur0, q) : imageLoad(u_fast_cur1, q); }
// `v` rounded by the caller (hrt_round_half): the temporal pass keeps the rounded value in
// shared memory too, and rounding twice would cost a pixel the work again.
void hrt_store_fast_cur(uint s, ivec2 q, vec4 v) { if (s == 0u) imageStore(u_fast_cur0, q, v); else imageStore(u_fast_cur1, q, v); }
vec2 hrt_load_shadow_history(ivec2 q) { return unpackHalf2x16(imageLoad(u_shadow_history, q).x); }
void hrt_store_shadow_history(ivec2 q, vec2 v) { imageStore(u_shadow_history, q, uvec4(packHalf2x16(hrt_round_half(vec4(v, 0.0, 0.0)).xy))); }
vec4 hrt_load_temp(uint s, ivec2 q) { return s == 0u ? imageLoad(u_temp_src0, q) : imageLoad(u_temp_src1, q); }
void hrt_store_temp(uint s, ivec2 q, vec4 v) { v = hrt_round_half(v); if (s == 0u) imageStore(u_temp_dst0, q, v); else imageStore(u_temp_dst1, q, v); }

float hrt_luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// The denoiser's own G-buffer (the view's guide; last frame's for the disocclusion tests), one
// 32-bit texel: the octahedral normal as two signed 8-bit values (at most ~0.5° off: a
// weight of dot^64 moves by under 0.5%) and the distance to the camera as a half (1/2048 of
// the distance: under 3% of the plane-distance stop); distance < 0 marks background. The
// second component is always 0 (the call sites take the pair the guide once was).
uvec2 hrt_pack_surface(vec3 n, float dist) {
    vec2 e = hrt_oct_encode(n);
    return uvec2((packSnorm4x8(vec4(e, 0.0, 0.0)) & 0xFFFFu) | (packHalf2x16(vec2(dist, 0.0)) << 16), 0u);
}
void hrt_unpack_surface(uvec2 v, out vec3 n, out float dist) {
    n = hrt_oct_decode(unpackSnorm4x8(v.x).xy);
    dist = unpackHalf2x16(v.x >> 16).x;
}

bool hrt_in_viewport(ivec2 q) {
    ivec2 lo = ivec2(u_d.c.viewport.xy);
    return all(greaterThanEqual(q, lo)) && all(lessThan(q, lo + ivec2(u_d.c.viewport.zw)));
}

// Inside the viewport the history was made in (with dynamic resolution, not this frame's).
bool hrt_in_prev_viewport(ivec2 q) {
    ivec2 lo = ivec2(u_d.prev_viewport.xy);
    return all(greaterThanEqual(q, lo)) && all(lessThan(q, lo + ivec2(u_d.prev_viewport.zw)));
}

// The viewport changed since the history was made (dynamic resolution).
bool hrt_viewport_changed() {
    return any(notEqual(u_d.prev_viewport, vec4(u_d.c.viewport)));
}

// World direction from the camera through a pixel centre (current or previous camera).
vec3 hrt_pixel_dir(mat4 clip_to_world, vec3 eye, vec2 pixel_pos) {
    vec2 ndc = (pixel_pos - u_d.c.viewport.xy) / u_d.c.viewport.zw * 2.0 - 1.0;
    vec4 h = clip_to_world * vec4(ndc, 0.5, 1.0);
    return normalize(h.xyz / h.w - eye);
}

// A surface of the denoiser's G-buffer as a world position and normal (false: background).
bool hrt_surface_at(uvec2 packed_surface, mat4 clip_to_world, vec3 eye, ivec2 q, out vec3 p, out vec3 n) {
    float dist;
    hrt_unpack_surface(packed_surface, n, dist);
    p = eye + hrt_pixel_dir(clip_to_world, eye, vec2(q) + 0.5) * dist;
    return dist >= 0.0;
}

// The current camera's pixel rays as an affine function of the pixel: clip_to_world x (ndc,
// 0.5, 1) is linear in ndc, and ndc in the pixel, so h(q) = h0 + q.x hx + q.y hy. A position
// then costs two vec4 multiply-adds and a divide instead of a matrix product — the à-trous
// passes reconstruct 24 neighbours per pixel per iteration.
struct HrtPixelRays {
    vec4 h0, hx, hy;
};

HrtPixelRays hrt_pixel_rays_in(mat4 clip_to_world, vec4 viewport) {
    vec2 s = 2.0 / viewport.zw;
    vec2 o = (0.5 - viewport.xy) * s - 1.0; // ndc of pixel (0, 0)'s centre
    return HrtPixelRays(clip_to_world * vec4(o, 0.5, 1.0), clip_to_world[0] * s.x, clip_to_world[1] * s.y);
}

HrtPixelRays hrt_pixel_rays(mat4 clip_to_world) {
    return hrt_pixel_rays_in(clip_to_world, vec4(u_d.c.viewport));
}

// hrt_surface_at with the rays above (the same result up to rounding).
bool hrt_surface_on(HrtPixelRays r, uvec2 packed_surface, vec3 eye, ivec2 q, out vec3 p, out vec3 n) {
    float dist;
    hrt_unpack_surface(packed_surface, n, dist);
    vec4 h = r.h0 + float(q.x) * r.hx + float(q.y) * r.hy;
    p = eye + normalize(h.xyz / h.w - eye) * dist;
    return dist >= 0.0;
}

// log2 of hrt_geometry_weight: a filter with further stops (the à-trous luminance stop) adds
// their logarithms and takes one exp2, two transcendental operations per tap instead of four.
float hrt_geometry_log2_weight(vec3 p, vec3 n, float dist, vec3 q_p, vec3 q_n) {
    float plane = abs(dot(n, q_p - p)) / (u_d.stops.z * dist);
    return u_d.stops.y * log2(max(dot(n, q_n), 1e-8)) - plane * plane * 1.4426950409;
}

// Edge-stopping weight of a neighbour surface (q_p, q_n) seen from (p, n) at distance `dist`:
// plane distance relative to the view distance, and the normal similarity.
float hrt_geometry_weight(vec3 p, vec3 n, float dist, vec3 q_p, vec3 q_n) {
    float plane = abs(dot(n, q_p - p)) / (u_d.stops.z * dist);
    return exp(-plane * plane) * pow(max(dot(n, q_n), 0.0), u_d.stops.y);
}

// Where the surface at `pixel` (world position p) was in the previous frame, in pixels
// (continuous, pixel centres at +0.5).
// Where the world point `p` was on the previous camera's screen, in pixels; false where it was
// behind that camera.
bool hrt_previous_camera_position(vec3 p, out vec2 pos) {
    vec4 clip = u_d.prev_world_to_clip * vec4(p, 1.0);
    pos = (clip.xy / clip.w * 0.5 + 0.5) * u_d.prev_viewport.zw + u_d.prev_viewport.xy;
    return clip.w > 0.0;
}

vec2 hrt_previous_position(ivec2 pixel, vec3 p) {
    uint motion = u_d.flags.x;
    vec2 here = vec2(pixel) + 0.5;
    if (motion == HRT_MOTION_VIEW || motion == HRT_MOTION_CLIP) {
        vec2 mv = texelFetch(u_motion, pixel, 0).xy * u_d.motion_scale.xy;
        if (motion == HRT_MOTION_CLIP) mv *= 0.5 * u_d.c.viewport.zw;
        vec2 was = here + mv + u_d.jitter_delta.xy;
        // Motion is in this frame's pixels; the history lies in the previous viewport.
        if (hrt_viewport_changed()) {
            vec4 vp = vec4(u_d.c.viewport);
            was = (was - vp.xy) / vp.zw * u_d.prev_viewport.zw + u_d.prev_viewport.xy;
        }
        return was;
    }
    vec3 prev_p = p;
    if (motion == HRT_MOTION_WORLD) prev_p += texelFetch(u_motion, pixel, 0).xyz * u_d.motion_scale.xyz;
    vec2 pos;
    return hrt_previous_camera_position(prev_p, pos) ? pos : vec2(-1e9);
}

// Bilinear taps of the previous frame around `prev_pos` that show the same surface as (p, n)
// seen at distance `dist`: weights are zero for taps off screen, on background, on another
// surface (off the plane) or orientation (disocclusion).
// (The four taps' positions come from the previous camera's pixel rays, one matrix product
// for all four instead of one each.)
// Also `moved`: how far the surface turned and travelled since the last frame, from the
// strongest tap — the cosine between the normals and the distance between the surface points
// (in world units; the caller scales it). (1, 0) without a tap. The cosine, not the angle:
// only moving surfaces need the angle, and the caller takes it there.
void hrt_history_taps_moved(vec2 prev_pos, vec3 p, vec3 n, float dist, out ivec2 taps[4], out vec4 weights, out vec2 moved) {
    vec2 f = prev_pos - 0.5;
    ivec2 base = ivec2(floor(f));
    vec2 t = f - vec2(base);
    taps[0] = base; taps[1] = base + ivec2(1, 0); taps[2] = base + ivec2(0, 1); taps[3] = base + ivec2(1, 1);
    vec4 bilinear = vec4((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
    HrtPixelRays rays = hrt_pixel_rays_in(u_d.prev_clip_to_world, u_d.prev_viewport);
    vec3 eye = u_d.prev_eye.xyz;
    moved = vec2(1.0, 0.0);
    float best = 0.0;
    for (int i = 0; i < 4; ++i) {
        weights[i] = 0.0;
        if (!hrt_in_prev_viewport(taps[i]) || bilinear[i] <= 0.0) continue;
        vec3 q_p, q_n;
        if (!hrt_surface_on(rays, imageLoad(u_gbuf_prev, taps[i]).xy, eye, taps[i], q_p, q_n)) continue;
        float cos_n = dot(n, q_n);
        if (abs(dot(n, q_p - p)) <= u_d.stops.z * dist && cos_n >= 0.8) {
            weights[i] = bilinear[i];
            if (bilinear[i] > best) {
                best = bilinear[i];
                moved = vec2(cos_n, distance(p, q_p));
            }
        }
    }
}

void hrt_history_taps(vec2 prev_pos, vec3 p, vec3 n, float dist, out ivec2 taps[4], out vec4 weights) {
    vec2 moved;
    hrt_history_taps_moved(prev_pos, p, n, dist, taps, weights, moved);
}

// Roughness of the specular signal at a pixel (the trace tasks' rule).
float hrt_denoise_roughness(ivec2 pixel) {
    return hrt_surface_roughness(u_d.c, u_roughness, pixel);
}

// Checkerboard: was this pixel traced by this ticket? (the trace tasks' rule in common.glsl)
bool hrt_traced_now(ivec2 pixel) {
    return hrt_traced_this_frame(u_d.c, uvec2(pixel));
}

// This frame's surface at a pixel from the engine's G-buffer (false: background, or excluded
// by the input mask: neither denoised nor used as a neighbour or as history).
bool hrt_engine_surface(ivec2 pixel, out vec3 p, out vec3 n) {
    n = vec3(0.0, 0.0, 1.0);
    p = vec3(0.0);
    if (hrt_masked(u_d.c, u_input_mask, uvec2(pixel))) return false;
    if (!hrt_world_position(u_d.c, uvec2(pixel), texelFetch(u_depth, pixel, 0), p)) return false;
    n = hrt_world_normal(u_d.c, texelFetch(u_normals, pixel, 0));
    return true;
}

// The noisy sample of a signal at a pixel; in checkerboard mode the pixels not traced this
// ticket take the geometry-weighted mean of their four traced neighbours.
vec4 hrt_noisy_sample(uint s, ivec2 pixel, vec3 p, vec3 n, float dist) {
    if (hrt_traced_now(pixel)) return hrt_load_input(s, pixel);
    const ivec2 offs[4] = ivec2[4](ivec2(1, 0), ivec2(-1, 0), ivec2(0, 1), ivec2(0, -1));
    vec4 sum = vec4(0.0);
    float wsum = 0.0;
    for (int i = 0; i < 4; ++i) {
        ivec2 q = pixel + offs[i];
        vec3 q_p, q_n;
        if (!hrt_in_viewport(q) || !hrt_engine_surface(q, q_p, q_n)) continue;
        float w = hrt_geometry_weight(p, n, dist, q_p, q_n) + 1e-4;
        sum += w * hrt_load_input(s, q);
        wsum += w;
    }
    return wsum > 0.0 ? sum / wsum : hrt_load_input(s, pixel);
}

// The signal's value as radiance: scalar signals (AO) read R into every channel.
vec4 hrt_as_signal(uint kind, vec4 v) {
    return kind == HRT_SIGNAL_SCALAR ? vec4(v.rrr, v.a) : v;
}
#endif
