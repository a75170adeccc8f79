#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// Shadow denoiser, pass 2: penumbra-aware blur. The blur radius is half the penumbra width
// (world) over the world size of a pixel at this depth, where the width is the geometry-
// weighted mean of the occluded samples in a 24-tap neighbourhood spanning the largest
// radius (so lit pixels beside a penumbra find it too). Contact shadows and hard lights give a
// radius under half a pixel: the visibility passes unchanged. Otherwise 8 taps of a rotated
// golden-angle disk (turned per pixel and per frame: the temporal pass after this one
// averages the turns; 16 taps measured the same penumbra error), Gaussian in the radius, with
// plane and normal stops. Workgroups with no occluded sample within the search's reach (the
// prep pass's tile map) skip the search.
#include "include/denoise.glsl"

// History length (frames) up to which the full penumbra-wide blur is kept.
const float SHADOW_BLUR_FRAMES = 1.0;

// Whether a tile within this workgroup's search reach holds an occluded sample.
shared uint s_near;

// Marks s_near from the tile map: the tiles the search of any pixel of this workgroup
// can reach (the group's 8x8 pixels, `reach` pixels around, inside the viewport). Every
// invocation of the group calls it (it has barriers).
void find_occluded_tiles(int reach) {
    if (gl_LocalInvocationIndex == 0u) s_near = 0u;
    barrier();
    ivec2 group = ivec2(gl_WorkGroupID.xy) * 8; // relative to the viewport's origin
    ivec2 lo = max(group - reach, ivec2(0)) / 8;
    ivec2 hi = min(group + 7 + reach, ivec2(u_d.c.viewport.zw) - 1) / 8;
    ivec2 span = hi - lo + 1;
    for (int i = int(gl_LocalInvocationIndex); i < span.x * span.y; i += 64) {
        if (imageLoad(u_tiles, lo + ivec2(i % span.x, i / span.x)).x != 0u) atomicOr(s_near, 1u);
    }
    barrier();
}

void main() {
    float max_radius = u_d.stops.w;
    int spacing = max(1, int(max_radius / 4.0 + 0.5));
    find_occluded_tiles(4 * spacing);
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + ivec2(u_d.c.viewport.xy);
    if (!hrt_in_viewport(pixel)) return;
    vec3 p, n;
    // z, w: the pixel's history, passed on to the temporal pass.
    vec4 c = hrt_load_temp(0u, pixel);
    if (!hrt_surface_at(imageLoad(u_gbuf_cur, pixel).xy, u_d.c.clip_to_world, u_d.eye.xyz, pixel, p, n)) {
        hrt_store_temp(0u, pixel, vec4(1.0, 0.0, c.zw));
        return;
    }
    // No occluded sample within reach: the search below would find no penumbra (radius 0),
    // and the visibility passes unchanged. In a sunlit view most tiles end here.
    if (s_near == 0u) {
        hrt_store_temp(0u, pixel, vec4(c.x, 0.0, c.zw));
        return;
    }
    float dist = distance(p, u_d.eye.xyz);
    float pixel_world = u_d.eye.w * dist;

    float pen = 0.0, pen_w = 0.0, vis_min = c.x;
    if (c.y >= 0.0) { pen = c.y; pen_w = 1.0; }
    // The search: three rings of 8 taps (3x3 without its centre) at 1, 2 and 4 spacings — 24
    // taps where a 9x9 grid at the spacing took 80, as far out, and as dense next to the pixel,
    // where the occluders that set its penumbra are. Unrolled, each tap's two fetches issued
    // before its weight is known: a loop that waited on each tap in turn took 0.43 ms at 1440p.
    HrtPixelRays rays = hrt_pixel_rays(u_d.c.clip_to_world);
    [[unroll]] for (int i = 0; i < 24; ++i) {
        int j = (i % 8) + ((i % 8) >= 4 ? 1 : 0); // 3x3 without its centre
        int k = i / 8; // rings at 1, 2 and 4 spacings
        ivec2 q = pixel + ivec2(j % 3 - 1, j / 3 - 1) * (spacing << (k == 2 ? 2 : k));
        if (!hrt_in_viewport(q)) continue;
        vec3 q_p, q_n;
        if (!hrt_surface_on(rays, imageLoad(u_gbuf_cur, q).xy, u_d.eye.xyz, q, q_p, q_n)) continue;
        // Fetched before the weight decides: the taps' fetches then overlap.
        vec4 t = hrt_load_temp(0u, q);
        float w = hrt_geometry_weight(p, n, dist, q_p, q_n);
        if (w < 0.1) continue;
        vis_min = min(vis_min, t.x);
        if (t.y >= 0.0) { pen += w * t.y; pen_w += w; }
    }
    float radius = pen_w > 0.0 ? min(0.5 * (pen / pen_w) / pixel_world, max_radius) : 0.0;
    // The temporal pass after this one averages up to max-history frames: as the pixel's
    // history grows, each frame needs less blur (the blur's own error, a flattened penumbra,
    // then stops dominating). Radius x sqrt(SHADOW_BLUR_FRAMES / length), down to a quarter.
    if (u_d.flags.z == 0u && radius >= 0.5) {
        ivec2 taps[4];
        vec4 w;
        hrt_history_taps(hrt_previous_position(pixel, p), p, n, dist, taps, w);
        float wsum = dot(w, vec4(1.0)), len = 0.0;
        for (int i = 0; i < 4; ++i) if (w[i] > 0.0) len += w[i] * hrt_load_temp(0u, taps[i]).w;
        if (wsum > 1e-3) radius *= clamp(sqrt(SHADOW_BLUR_FRAMES / max(len / wsum, 1.0)), 0.25, 1.0);
    }
    if (vis_min >= 1.0 || radius < 0.5) {
        hrt_store_temp(0u, pixel, vec4(c.x, radius, c.zw));
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
        vec3 q_p, q_n;
        if (!hrt_surface_at(imageLoad(u_gbuf_cur, q).xy, u_d.c.clip_to_world, u_d.eye.xyz, q, q_p, q_n)) continue;
        float w = exp(-2.0 * (r * r) / (radius * radius)) * hrt_geometry_weight(p, n, dist, q_p, q_n);
        sum += w * hrt_load_temp(0u, q).x;
        wsum += w;
    }
    hrt_store_temp(0u, pixel, vec4(sum / wsum, radius, c.zw));
}
