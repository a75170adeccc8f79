#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Shadow denoiser, pass 2: penumbra-aware blur, shaped like SIGMA's. The blur radius is half
// the penumbra width (world) over the world size of a pixel at this depth. The width comes
// from what is already at hand rather than from a search: the pixel's own occluded sample and
// its 3x3 neighbours (geometry-weighted, from a 12x12 tile the workgroup loads into shared
// memory once, four and a half fetches a pixel), and the prep pass's tile summaries within the
// largest radius (each 8x8 tile's mean width and count, summed once per workgroup), so lit
// pixels beside a penumbra find it too. (The 24-tap search this replaces fetched 48 texels a
// pixel and set the pass's time.) While the view moves, penumbrae under EDGE_PENUMBRA pixels
// are blurred along their edge instead (`along_edge`). Still views: contact shadows and hard
// lights give a radius under half a pixel, and the visibility passes unchanged; otherwise 8
// taps of a rotated golden-angle disk (turned per pixel and per frame: the temporal pass
// after this one averages the turns), Gaussian in the radius, with plane and normal stops.
// Workgroups with no occluded sample within reach, and those deep in an umbra (no pixel
// within reach sees any light), do nothing but copy.
#include "include/denoise.glsl"
#include "include/group_sum.glsl"

// History length (frames) up to which the full penumbra-wide blur is kept.
const float SHADOW_BLUR_FRAMES = 1.0;
// Weight of the tiles' estimate beside the 3x3's occluded samples (each weighs up to 1):
// where the 3x3 holds occluded samples they decide the width; where it holds none (a lit
// pixel beside a penumbra) the tiles do.
const float TILE_WEIGHT = 0.5;

// Narrow penumbrae while the view moves (see `along_edge`): the kernel's deviations across
// and along the edge (pixels; docs/benchmarks.md has the values tried).
const float EDGE_ACROSS = 0.3;
const float EDGE_ALONG = 1.5;
// Whether this pipeline has the edge-aligned blur: the SDK records the one without it when
// neither the view nor the scene moved and history was not reset (no pixel then has the short
// history the blur is for). Merely present, its code cost the pass time where it never ran
// (docs/benchmarks.md has the figures).
layout(constant_id = 5) const uint HRT_EDGE_BLUR = 1u;
// The history length (frames) up to which, and the penumbra half-width (pixels) under which,
// the edge-aligned blur replaces the disk.
const float SHORT_HISTORY = 2.5;
const float EDGE_PENUMBRA = 3.0;

// The intermediate and the denoiser's G-buffer around the workgroup (two texels of border:
// the edge-aligned blur reaches two pixels, its direction's differences one beyond the 3x3).
const int BORDER = 2;
const int APRON = 8 + 2 * BORDER;
shared vec4 s_temp[APRON * APRON];
shared uint s_gbuf[APRON * APRON];

// The tile summaries within `reach` pixels of this workgroup's 8x8 pixels, summed. Every
// invocation calls it (it has barriers).
vec3 sum_tiles(int reach) {
    uint me = gl_LocalInvocationIndex;
    ivec2 group = ivec2(gl_WorkGroupID.xy) * 8; // relative to the viewport's origin
    ivec2 lo = max(group - reach, ivec2(0)) / 8;
    ivec2 hi = min(group + 7 + reach, ivec2(u_d.c.viewport.zw) - 1) / 8;
    ivec2 span = hi - lo + 1;
    vec3 sum = vec3(0.0);
    for (int i = int(me); i < span.x * span.y; i += 64) {
        vec2 t = unpackHalf2x16(imageLoad(u_tiles, lo + ivec2(i % span.x, i / span.x)).x);
        float count = abs(t.y);
        sum += vec3(t.x * count, count, t.y >= 0.0 ? 1.0 : 0.0);
    }
    // Per invocation, then summed: (sum of count x mean width, count, tiles where some pixel
    // sees light) over the tiles in reach.
    return hrt_group_sum(sum);
}

// Fills the apron: texels outside the viewport read as background.
void load_apron(ivec2 origin) {
    for (int i = int(gl_LocalInvocationIndex); i < APRON * APRON; i += 64) {
        ivec2 q = origin + ivec2(i % APRON, i / APRON);
        bool inside = hrt_in_viewport(q);
        s_gbuf[i] = inside ? imageLoad(u_gbuf_cur, q).x : hrt_pack_surface(vec3(0.0, 0.0, 1.0), -1.0).x;
        s_temp[i] = inside ? hrt_load_temp(0u, q) : vec4(1.0, -1.0, 0.0, 0.0);
    }
    barrier();
}

// Index of pixel q in the apron, or -1 outside it.
int apron_index(ivec2 q, ivec2 origin) {
    ivec2 l = q - origin;
    return all(greaterThanEqual(l, ivec2(0))) && all(lessThan(l, ivec2(APRON))) ? l.y * APRON + l.x : -1;
}

// A narrow penumbra while the view moves. The history, resampled between texels, softens a
// sharp edge, so the temporal pass keeps at most two frames there; a disk blur as wide as
// the penumbra would soften it as much; one frame's samples alone are as noisy as the raw
// trace. But along the edge the visibility changes slowly (the edge's offset from the pixel
// centres drifts by a fraction of a pixel per pixel), so a kernel narrow across the edge and
// long along it averages samples of nearly one value. The edge's direction: the structure
// tensor of this frame's visibility over the 3x3. Taps come in point-symmetric pairs, so a
// tap's offset across the edge is cancelled by its partner's (the visibility's slope across
// the edge drops out; only its curvature is left). Its loops stay rolled: unrolled, their
// 24 decoded neighbours widened the whole pass's register footprint, and every pixel paid for
// it in occupancy (rolled, the pass costs nearly what it costs without the edge blur:
// docs/benchmarks.md).
float along_edge(ivec2 pixel, int centre, HrtPixelRays rays, vec3 p, vec3 n, float dist) {
    float v = s_temp[centre].x;
    vec3 tensor = vec3(0.0);
    float lo = v, hi = v;
    [[dont_unroll]] for (int j = 0; j < 9; ++j) {
        int k = centre + (j / 3 - 1) * APRON + (j % 3 - 1);
        float gx = s_temp[k + 1].x - s_temp[k - 1].x;
        float gy = s_temp[k + APRON].x - s_temp[k - APRON].x;
        tensor += vec3(gx * gx, gx * gy, gy * gy);
        lo = min(lo, s_temp[k].x);
        hi = max(hi, s_temp[k].x);
    }
    // No edge through the 3x3: nothing to align with (and nothing a blur would change much).
    if (hi - lo < 0.5) return v;
    float angle = 0.5 * atan(2.0 * tensor.y, tensor.x - tensor.z);
    vec2 across = vec2(cos(angle), sin(angle));
    // One of each point-symmetric pair in a 5x5 (the other is its negation).
    const ivec2 PAIRS[12] = ivec2[12](ivec2(1, 0), ivec2(2, 0), ivec2(-2, 1), ivec2(-1, 1), ivec2(0, 1), ivec2(1, 1),
        ivec2(2, 1), ivec2(-2, 2), ivec2(-1, 2), ivec2(0, 2), ivec2(1, 2), ivec2(2, 2));
    float sum = v, wsum = 1.0;
    [[dont_unroll]] for (int i = 0; i < 12; ++i) {
        vec2 o = vec2(PAIRS[i]);
        float x = dot(o, across), y = dot(o, vec2(-across.y, across.x));
        float w = exp(-(x * x) / (EDGE_ACROSS * EDGE_ACROSS) - (y * y) / (2.0 * EDGE_ALONG * EDGE_ALONG));
        if (w < 0.01) continue;
        int offset = PAIRS[i].y * APRON + PAIRS[i].x;
        vec3 a_p, a_n, b_p, b_n;
        if (!hrt_surface_on(rays, uvec2(s_gbuf[centre + offset], 0u), u_d.eye.xyz, pixel + PAIRS[i], a_p, a_n)) continue;
        if (!hrt_surface_on(rays, uvec2(s_gbuf[centre - offset], 0u), u_d.eye.xyz, pixel - PAIRS[i], b_p, b_n)) continue;
        w *= min(hrt_geometry_weight(p, n, dist, a_p, a_n), hrt_geometry_weight(p, n, dist, b_p, b_n));
        float a = s_temp[centre + offset].x, b = s_temp[centre - offset].x;
        sum += w * (a + b);
        wsum += 2.0 * w;
    }
    return sum / wsum;
}

void main() {
    float max_radius = u_d.stops.w;
    vec3 tiles = sum_tiles(int(ceil(max_radius)));
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    // No occluded sample within reach: the width would be unknown (radius 0) and the
    // visibility passes unchanged. In a sunlit view most tiles end here. No pixel within reach
    // sees any light: every tap would read 0, and so does the pixel — an umbra's interior.
    if (tiles.y <= 0.0 || tiles.z <= 0.0) {
        if (!hrt_in_viewport(pixel)) return;
        vec4 c = hrt_load_temp(0u, pixel);
        hrt_store_temp(0u, pixel, vec4(c.x, 0.0, c.zw));
        return;
    }
    ivec2 origin = ivec2(gl_WorkGroupID.xy) * 8 + ivec2(u_d.c.viewport.xy) - BORDER;
    load_apron(origin);
    if (!hrt_in_viewport(pixel)) return;
    int centre = apron_index(pixel, origin);
    // z, w: the pixel's history, passed on to the temporal pass.
    vec4 c = s_temp[centre];
    HrtPixelRays rays = hrt_pixel_rays(u_d.c.clip_to_world);
    vec3 p, n;
    if (!hrt_surface_on(rays, uvec2(s_gbuf[centre], 0u), u_d.eye.xyz, pixel, p, n)) {
        hrt_store_temp(0u, pixel, vec4(1.0, 0.0, c.zw));
        return;
    }
    float dist = distance(p, u_d.eye.xyz);
    float pixel_world = u_d.eye.w * dist;

    float pen = 0.0, pen_w = 0.0;
    if (c.y >= 0.0) { pen = c.y; pen_w = 1.0; }
    [[unroll]] for (int j = 0; j < 9; ++j) {
        if (j == 4) continue;
        ivec2 q = pixel + ivec2(j % 3 - 1, j / 3 - 1);
        int k = centre + (j / 3 - 1) * APRON + (j % 3 - 1);
        vec3 q_p, q_n;
        if (!hrt_surface_on(rays, uvec2(s_gbuf[k], 0u), u_d.eye.xyz, q, q_p, q_n)) continue;
        float t = s_temp[k].y;
        float w = hrt_geometry_weight(p, n, dist, q_p, q_n);
        if (w >= 0.1 && t >= 0.0) { pen += w * t; pen_w += w; }
    }
    float width = (pen + TILE_WEIGHT * tiles.x / tiles.y) / (pen_w + TILE_WEIGHT);
    float radius = min(0.5 * width / pixel_world, max_radius);
    // Stored in y for the temporal pass: the penumbra's half-width in pixels, before the
    // history shrinks the blur (under half a pixel the shadow's edge is sharp).
    float penumbra = radius;
    // The temporal pass after this one averages up to max-history frames: as the pixel's
    // history grows, each frame needs less blur (the blur's own error, a flattened penumbra,
    // then stops dominating). Radius x sqrt(SHADOW_BLUR_FRAMES / length), down to a quarter.
    // The length is the kept history's at this pixel (the prep pass's copy, already in the
    // apron): while the view moves it is a neighbour's, a frame or two off at most, and
    // reprojecting it cost the pass three fetches a pixel (motion, last frame's guide, the
    // texel) for no measured difference.
    if (u_d.flags.z == 0u && radius >= 0.5) radius *= clamp(sqrt(SHADOW_BLUR_FRAMES / max(c.w, 1.0)), 0.25, 1.0);
    // While the view moves (the temporal pass keeps a short history there: see
    // SHARP_EDGE_RADIUS in it) a narrow penumbra is blurred along its edge, not across it.
    // Where the history is long it averages the pixel's own samples instead, and any spatial
    // blur would only bias it where the edge curves within the kernel.
    bool short_history = u_d.flags.z != 0u || c.w <= SHORT_HISTORY;
    if (HRT_EDGE_BLUR != 0u && penumbra < EDGE_PENUMBRA && short_history) {
        hrt_store_temp(0u, pixel, vec4(along_edge(pixel, centre, rays, p, n, dist), penumbra, c.zw));
        return;
    }
    if (radius < 0.5) {
        hrt_store_temp(0u, pixel, vec4(c.x, penumbra, c.zw));
        return;
    }
    float rotation = hrt_u01(hrt_pcg(uint(pixel.x) ^ hrt_pcg(uint(pixel.y) ^ hrt_pcg(u_d.c.frame.x)))) * 2.0 * HRT_PI;
    float sum = c.x, wsum = 1.0;
    const int TAPS = 8;
    [[unroll]] for (int i = 0; i < TAPS; ++i) {
        float r = sqrt((float(i) + 0.5) / float(TAPS)) * radius;
        float a = float(i) * 2.39996323 + rotation;
        ivec2 q = pixel + ivec2(round(r * vec2(cos(a), sin(a))));
        if (q == pixel || !hrt_in_viewport(q)) continue;
        int k = apron_index(q, origin);
        vec3 q_p, q_n;
        uint g = k >= 0 ? s_gbuf[k] : imageLoad(u_gbuf_cur, q).x;
        if (!hrt_surface_on(rays, uvec2(g, 0u), u_d.eye.xyz, q, q_p, q_n)) continue;
        float w = exp(-2.0 * (r * r) / (radius * radius)) * hrt_geometry_weight(p, n, dist, q_p, q_n);
        sum += w * (k >= 0 ? s_temp[k].x : hrt_load_temp(0u, q).x);
        wsum += w;
    }
    hrt_store_temp(0u, pixel, vec4(sum / wsum, penumbra, c.zw));
}
