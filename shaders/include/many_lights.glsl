// Many shadowed lights by spatiotemporal reservoir resampling (ReSTIR DI; Bitterli et al. 2020):
// the two ray passes of TraceManyLightsTask (sdk/src/passes/many_lights.rs). The light list, its
// power CDF and this frame's presampled lights (many_lights_cdf.comp, many_lights_presample.comp)
// are reached by device address, as are the context's reservoirs and last frame's surfaces.
//
// What one pixel estimates: the sum over lights of the light's unshadowed irradiance at the
// surface (light_sampling.glsl's reach, cos and 1/d^2) times the surface's response to the
// light's centre direction (Lambert's 1/pi; GGX specular with its lobe widened by the light's
// angular radius), times the visible fraction of the light's extent (the disk the shadow tasks
// sample). A sample is (light, point of its disk); the resampling target is the unshadowed part.
#ifndef HRT_MANY_LIGHTS_GLSL
#define HRT_MANY_LIGHTS_GLSL
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#include "common.glsl"
#include "light_sampling.glsl"

// ResamplingMode (sdk/src/types/many_lights.rs)
#define HRT_ML_BIASED 0u
#define HRT_ML_UNBIASED 1u
#define HRT_ML_POWER 2u
// MotionType + 1 (0: reproject with the cameras)
#define HRT_ML_MOTION_NONE 0u
#define HRT_ML_MOTION_VIEW 1u
#define HRT_ML_MOTION_CLIP 2u
#define HRT_ML_MOTION_WORLD 3u
// Presampled lights: tiles of this many entries (sdk/src/passes/many_lights.rs PRESAMPLE_TILE).
#define HRT_ML_TILE 1024u
// The narrowest specular lobe a light is shaded with (GGX alpha): narrower lobes turn a small
// light's highlight into single-pixel fireflies.
#define HRT_ML_MIN_ALPHA 0.01
// A reservoir's light word: index + 1 (0: empty) in the low bits, and this flag when the
// sample is known to reach the light from the reservoir's own pixel.
#define HRT_ML_VISIBLE_BIT 0x80000000u
// sizes.w flags: the biased mode skips the candidates' visibility test (one ray a pixel less;
// occluded samples are then passed on and found out by the shading ray).
#define HRT_ML_NO_CANDIDATE_VISIBILITY 1u

layout(set = 0, binding = 0) uniform accelerationStructureEXT u_tlas;
layout(set = 0, binding = 1) uniform sampler2D u_depth;
layout(set = 0, binding = 2) uniform sampler2D u_normals;
layout(set = 0, binding = 3) uniform writeonly image2D u_diffuse_out;
layout(set = 0, binding = 4, std140) uniform ManyLightsConstants {
    TraceCommon common_;
    mat4 prev_world_to_clip;
    mat4 prev_clip_to_world;
    vec4 prev_eye;       // xyz: the previous camera's position; w: history valid (0/1)
    vec4 prev_viewport;  // the viewport the history was made in
    uvec4 counts;        // lights, local candidates, spatial samples, max history (M cap)
    uvec4 modes;         // resampling mode, motion type, has directional lights, has debug output
    vec4 params;         // spatial radius (pixels), motion scale xyz
    uvec4 addr0;         // lights, CDF
    uvec4 addr1;         // presampled lights, reservoirs of the temporal pass
    uvec4 addr2;         // reservoirs kept (history), surfaces (this frame's, last frame's)
    uvec4 sizes;         // buffer row pitch (pixels), presample tiles, frame, flags (HRT_ML_*)
    uvec4 changed;       // the lights written this frame: first, end
} u_c;
layout(set = 0, binding = 5) uniform sampler2D u_roughness;
layout(set = 0, binding = 6) uniform sampler2D u_motion;
layout(set = 0, binding = 7) uniform writeonly image2D u_specular_out;
layout(set = 0, binding = 8) uniform writeonly image2D u_debug_out;
layout(set = 0, binding = 9) uniform sampler2D u_input_mask;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer HrtLightList { LightGpu l[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer HrtPresampled { uvec2 s[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer HrtReservoirs { uvec4 r[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) buffer HrtSurfaces { uvec2 s[]; };

// ---------------------------------------------------------------- random numbers

uint g_rng;
void hrt_ml_seed(uvec2 pixel, uint salt) {
    g_rng = hrt_pcg(pixel.x ^ hrt_pcg(pixel.y ^ hrt_pcg(u_c.sizes.z * 0x9e3779b9u ^ salt)));
}
float hrt_ml_rand() {
    g_rng = hrt_pcg(g_rng);
    return hrt_u01(g_rng);
}

// ---------------------------------------------------------------- shading

// A surface the lights are evaluated at.
struct HrtShadePoint {
    vec3 p;
    vec3 n;
    vec3 v;      // towards the camera
    float alpha; // GGX alpha (roughness^2)
};

float hrt_ml_luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

LightGpu hrt_ml_light(uint index) { return HrtLightList(u_c.addr0.xy).l[index]; }

// Unshadowed irradiance of a light at the surface (colour), the direction to its centre and its
// distance (1e30 for a directional light).
vec3 hrt_ml_irradiance(LightGpu l, HrtShadePoint s, out vec3 wi, out float dist) {
    vec3 radiant = l.power.x * l.power.yzw;
    if (uint(l.position.w) == HRT_LIGHT_DIRECTIONAL) {
        wi = -normalize(l.direction.xyz);
        dist = 1e30;
        return radiant * max(dot(s.n, wi), 0.0);
    }
    vec3 d = l.position.xyz - s.p;
    float d2 = max(dot(d, d), 1e-8);
    dist = sqrt(d2);
    wi = d / dist;
    return radiant * (hrt_light_reach(l, s.p) * max(dot(s.n, wi), 0.0) / d2);
}

// GGX specular without Fresnel (D x height-correlated Smith visibility, Heitz 2014), for a light
// whose angular radius seen from the surface is `angle`: the lobe is widened by half of it
// (Karis 2013), so a sphere light's highlight has the light's size and keeps its energy.
float hrt_ml_specular(HrtShadePoint s, vec3 wi, float angle) {
    float nl = dot(s.n, wi), nv = dot(s.n, s.v);
    if (nl <= 0.0 || nv <= 0.0) return 0.0;
    float a = min(max(s.alpha, HRT_ML_MIN_ALPHA) + 0.5 * angle, 1.0);
    float a2 = a * a;
    float nh = max(dot(s.n, normalize(wi + s.v)), 0.0);
    float dd = nh * nh * (a2 - 1.0) + 1.0;
    float D = a2 / (HRT_PI * dd * dd);
    float lv = nl * sqrt(nv * nv * (1.0 - a2) + a2);
    float ll = nv * sqrt(nl * nl * (1.0 - a2) + a2);
    return D * 0.5 / max(lv + ll, 1e-12);
}

// The light's angular radius seen from the surface (radians, small-angle).
float hrt_ml_angle(LightGpu l, float dist) {
    return uint(l.position.w) == HRT_LIGHT_DIRECTIONAL ? l.direction.w : l.shape.x / max(dist, 1e-6);
}

// A light's unshadowed contribution: irradiance E and specular response fs (the outputs are
// E/pi and E x fs), and the resampling target, luminance(E) x (1/pi + fs).
float hrt_ml_target(uint light, HrtShadePoint s, out vec3 E, out float fs) {
    E = vec3(0.0);
    fs = 0.0;
    if (light >= u_c.counts.x) return 0.0; // removed since the reservoir was made
    LightGpu l = hrt_ml_light(light);
    vec3 wi;
    float dist;
    E = hrt_ml_irradiance(l, s, wi, dist);
    float e = hrt_ml_luminance(E);
    if (!(e > 0.0)) return 0.0;
    fs = hrt_ml_specular(s, wi, hrt_ml_angle(l, dist));
    return e * (1.0 / HRT_PI + fs);
}

float hrt_ml_target_only(uint light, HrtShadePoint s) {
    vec3 E;
    float fs;
    return hrt_ml_target(light, s, E, fs);
}

// Whether the sample (light, point `uv` of its disk) is visible from the surface; `dist` gets
// the distance to that point (hit distance for the denoiser).
bool hrt_ml_visible(uint light, vec2 uv, vec3 p, vec3 n, out float dist) {
    LightGpu l = hrt_ml_light(light);
    vec3 origin = hrt_offset_ray(u_c.common_, p, n);
    vec3 dir;
    float tmax;
    hrt_light_ray(l, origin, uv, dir, tmax);
    dist = min(tmax, 1e4);
    if (dot(dir, n) <= 0.0) return false;
    return hrt_trace_visible(u_tlas, u_c.common_.frame.y & 0xffu, origin, dir, tmax);
}

// ---------------------------------------------------------------- reservoirs

struct HrtReservoir {
    uint light;   // index + 1, 0: empty
    vec2 uv;      // the point of the light's disk
    float W;      // unbiased contribution weight
    float M;      // confidence (frames' worth of candidates)
    bool visible; // known to reach the light from its own pixel
    // While resampling:
    float wsum;
    float target;
};

HrtReservoir hrt_ml_empty() { return HrtReservoir(0u, vec2(0.0), 0.0, 0.0, false, 0.0, 0.0); }

uvec4 hrt_ml_pack(HrtReservoir r) {
    return uvec4(r.light | (r.visible ? HRT_ML_VISIBLE_BIT : 0u), packUnorm2x16(r.uv), floatBitsToUint(r.W), floatBitsToUint(r.M));
}

HrtReservoir hrt_ml_unpack(uvec4 v) {
    HrtReservoir r = hrt_ml_empty();
    r.light = v.x & ~HRT_ML_VISIBLE_BIT;
    r.visible = (v.x & HRT_ML_VISIBLE_BIT) != 0u;
    r.uv = unpackUnorm2x16(v.y);
    r.W = uintBitsToFloat(v.z);
    r.M = uintBitsToFloat(v.w);
    if (!(r.W >= 0.0 && r.W < 3.0e38)) r.W = 0.0; // never let a bad value propagate
    if (!(r.M >= 0.0 && r.M < 1.0e6)) r.M = 0.0;
    return r;
}

// Weighted reservoir sampling: takes (light, uv) with probability w / (sum of weights so far).
bool hrt_ml_stream(inout HrtReservoir r, uint light, vec2 uv, bool visible, float w, float target) {
    if (!(w > 0.0)) return false;
    r.wsum += w;
    if (hrt_ml_rand() * r.wsum < w) {
        r.light = light;
        r.uv = uv;
        r.visible = visible;
        r.target = target;
        return true;
    }
    return false;
}

uint hrt_ml_index(ivec2 q) { return uint(q.y) * u_c.sizes.x + uint(q.x); }

// ---------------------------------------------------------------- surfaces

// A pixel's surface as kept for the next frame: octahedral normal (2 x snorm16) and distance to
// the camera (< 0: nothing there).
uvec2 hrt_ml_pack_surface(vec3 n, float dist) {
    return uvec2(packSnorm2x16(hrt_oct_encode(n)), floatBitsToUint(dist));
}

bool hrt_ml_in_viewport(ivec2 q, vec4 vp) {
    return all(greaterThanEqual(q, ivec2(vp.xy))) && all(lessThan(q, ivec2(vp.xy + vp.zw)));
}

// Last frame's surface at pixel q, as a world position and normal (false: nothing there).
bool hrt_ml_prev_surface(ivec2 q, out vec3 p, out vec3 n) {
    uvec2 v = HrtSurfaces(u_c.addr2.zw).s[hrt_ml_index(q)];
    n = hrt_oct_decode(unpackSnorm2x16(v.x));
    float dist = uintBitsToFloat(v.y);
    vec2 ndc = (vec2(q) + 0.5 - u_c.prev_viewport.xy) / u_c.prev_viewport.zw * 2.0 - 1.0;
    vec4 h = u_c.prev_clip_to_world * vec4(ndc, 0.5, 1.0);
    p = u_c.prev_eye.xyz + normalize(h.xyz / h.w - u_c.prev_eye.xyz) * dist;
    return dist > 0.0;
}

// This frame's surface at pixel q from the engine's G-buffer (false: background or masked).
bool hrt_ml_surface(ivec2 q, out HrtShadePoint s) {
    TraceCommon c = u_c.common_;
    s.n = vec3(0.0, 0.0, 1.0);
    s.p = vec3(0.0);
    s.v = vec3(0.0, 0.0, 1.0);
    s.alpha = 1.0;
    if (hrt_masked(c, u_input_mask, uvec2(q))) return false;
    if (!hrt_world_position(c, uvec2(q), texelFetch(u_depth, q, 0), s.p)) return false;
    s.n = hrt_world_normal(c, texelFetch(u_normals, q, 0));
    s.v = normalize(c.view_to_world[3].xyz - s.p);
    // Lit from behind as seen: a normal facing away from the camera is turned to it.
    if (dot(s.n, s.v) < 0.0) s.n = normalize(s.n - 2.0 * dot(s.n, s.v) * s.v);
    float r = hrt_surface_roughness(c, u_roughness, q);
    s.alpha = r * r;
    return true;
}

// The same surface: on the plane of (p, n) within 5% of the view distance, normals within ~25°.
bool hrt_ml_similar(HrtShadePoint s, float dist, vec3 q_p, vec3 q_n) {
    return abs(dot(s.n, q_p - s.p)) <= 0.05 * dist && dot(s.n, q_n) >= 0.9;
}

// Where this pixel's surface was on last frame's screen (pixels, centres at +0.5).
vec2 hrt_ml_previous_position(ivec2 pixel, vec3 p) {
    uint motion = u_c.modes.y;
    vec2 here = vec2(pixel) + 0.5;
    if (motion == HRT_ML_MOTION_VIEW || motion == HRT_ML_MOTION_CLIP) {
        vec2 mv = texelFetch(u_motion, pixel, 0).xy * u_c.params.yz;
        if (motion == HRT_ML_MOTION_CLIP) mv *= 0.5 * u_c.common_.viewport.zw;
        return here + mv;
    }
    vec3 prev_p = p;
    if (motion == HRT_ML_MOTION_WORLD) prev_p += texelFetch(u_motion, pixel, 0).xyz * u_c.params.yzw;
    vec4 clip = u_c.prev_world_to_clip * vec4(prev_p, 1.0);
    if (clip.w <= 0.0) return vec2(-1e9);
    return (clip.xy / clip.w * 0.5 + 0.5) * u_c.prev_viewport.zw + u_c.prev_viewport.xy;
}

// ---------------------------------------------------------------- candidates

// A presampled light (index, probability): `tile` of the local lights, or the directional table.
uvec2 hrt_ml_presampled(uint tile, bool directional) {
    uint entry = min(uint(hrt_ml_rand() * float(HRT_ML_TILE)), HRT_ML_TILE - 1u);
    uint base = directional ? u_c.sizes.y * HRT_ML_TILE : tile * HRT_ML_TILE;
    return HrtPresampled(u_c.addr1.xy).s[base + entry];
}

// The 16x16 block's presample tile this frame (a block shares one: its candidates are coherent
// in memory; the tiles are stratified sets of the power distribution, redrawn every frame).
uint hrt_ml_tile(uvec2 pixel) {
    return hrt_pcg((pixel.x >> 4) ^ hrt_pcg((pixel.y >> 4) ^ hrt_pcg(u_c.sizes.z))) % u_c.sizes.y;
}

// Resampled importance sampling of this frame's candidates: `counts.y` local lights by power and
// one directional light (when there are any); the strategies' lights are disjoint, so each
// candidate's weight is target / (candidates of its strategy x its probability).
HrtReservoir hrt_ml_initial(uvec2 pixel, HrtShadePoint s) {
    HrtReservoir r = hrt_ml_empty();
    uint locals = u_c.counts.y;
    uint tile = hrt_ml_tile(pixel);
    for (uint i = 0u; i < locals; ++i) {
        uvec2 c = hrt_ml_presampled(tile, false);
        float pdf = uintBitsToFloat(c.y);
        vec2 uv = vec2(hrt_ml_rand(), hrt_ml_rand());
        if (!(pdf > 0.0)) continue;
        float t = hrt_ml_target_only(c.x, s);
        hrt_ml_stream(r, c.x + 1u, uv, false, t / (float(locals) * pdf), t);
    }
    if (u_c.modes.z != 0u) {
        uvec2 c = hrt_ml_presampled(0u, true);
        float pdf = uintBitsToFloat(c.y);
        vec2 uv = vec2(hrt_ml_rand(), hrt_ml_rand());
        if (pdf > 0.0) {
            float t = hrt_ml_target_only(c.x, s);
            hrt_ml_stream(r, c.x + 1u, uv, false, t / pdf, t);
        }
    }
    r.M = 1.0;
    r.W = r.light != 0u && r.target > 0.0 ? r.wsum / r.target : 0.0;
    return r;
}

// ---------------------------------------------------------------- the passes

// Pass 1: this frame's candidates, their visibility, then the pixel's reservoir of last frame
// (found along the motion vector, on the same surface) merged in.
void hrt_ml_temporal_main() {
    TraceCommon c = u_c.common_;
    uvec2 launch = HRT_LAUNCH_ID;
    if (any(greaterThanEqual(launch, uvec2(c.viewport.zw)))) return;
    ivec2 pixel = ivec2(launch + uvec2(c.viewport.xy));
    HrtReservoirs out_r = HrtReservoirs(u_c.addr1.zw);
    uint idx = hrt_ml_index(pixel);
    HrtShadePoint s;
    if (!hrt_ml_surface(pixel, s)) {
        out_r.r[idx] = hrt_ml_pack(hrt_ml_empty());
        return;
    }
    hrt_ml_seed(uvec2(pixel), 0x1u);
    HrtReservoir canonical = hrt_ml_initial(uvec2(pixel), s);
    // Visibility reuse: a candidate that cannot reach the light is not passed on (the unbiased
    // mode's weights need it).
    bool test = u_c.modes.x == HRT_ML_UNBIASED || (u_c.sizes.w & HRT_ML_NO_CANDIDATE_VISIBILITY) == 0u;
    if (test && canonical.W > 0.0) {
        float d;
        canonical.visible = hrt_ml_visible(canonical.light - 1u, canonical.uv, s.p, s.n, d);
        if (!canonical.visible) canonical.W = 0.0;
    }
    // Last frame's reservoir, on the same surface along the motion vector.
    HrtReservoir prev = hrt_ml_empty();
    HrtShadePoint prev_s = s;
    float prev_m = 0.0;
    if (u_c.prev_eye.w != 0.0) {
        ivec2 q = ivec2(floor(hrt_ml_previous_position(pixel, s.p)));
        float dist = distance(s.p, c.view_to_world[3].xyz);
        if (hrt_ml_in_viewport(q, u_c.prev_viewport) && hrt_ml_prev_surface(q, prev_s.p, prev_s.n) &&
            hrt_ml_similar(s, dist, prev_s.p, prev_s.n)) {
            prev = hrt_ml_unpack(HrtReservoirs(u_c.addr2.xy).r[hrt_ml_index(q)]);
            prev_m = min(prev.M, float(u_c.counts.w));
            prev_s.v = normalize(u_c.prev_eye.xyz - prev_s.p);
        }
    }
    // The two samples merged with the balance heuristic over the two domains' targets, weighted
    // by their confidences (generalized RIS, Lin et al. 2022): a sample is weighted by how
    // likely each domain was to produce it, so one that last frame's surface barely reached
    // and this one sees brightly takes a small weight instead of its large contribution weight
    // (the uniform 1/Z weights' fireflies). Unbiased, last frame's surface produces only
    // samples it sees: its target includes the visibility there.
    bool unbiased = u_c.modes.x == HRT_ML_UNBIASED;
    float mc = canonical.M, tc = canonical.W > 0.0 ? canonical.target : 0.0;
    // Last frame's sample, here (t) and on last frame's surface (tp).
    float t = 0.0, tp = 0.0;
    if (prev_m > 0.0 && prev.light != 0u && prev.W > 0.0) {
        t = hrt_ml_target_only(prev.light - 1u, s);
        tp = hrt_ml_target_only(prev.light - 1u, prev_s);
        // A sample of a light written this frame (moved, recoloured) that still reaches the
        // pixel: its weight was made for the light as it was, and the history's confidence,
        // kept, would let it outweigh this frame's candidates for as many frames. It counts as
        // one frame. (A light that no longer reaches the pixel contributes nothing; its history
        // keeps its confidence, which keeps the estimate unbiased while the others' weights
        // still reflect the old list.)
        uint light = prev.light - 1u;
        if (t > 0.0 && light >= u_c.changed.x && light < u_c.changed.y) prev_m = min(prev_m, 1.0);
    }
    HrtReservoir r = hrt_ml_empty();
    if (tc > 0.0) {
        float tpc = prev_m > 0.0 ? hrt_ml_target_only(canonical.light - 1u, prev_s) : 0.0;
        float d;
        if (unbiased && tpc > 0.0 && !hrt_ml_visible(canonical.light - 1u, canonical.uv, prev_s.p, prev_s.n, d)) tpc = 0.0;
        float m = mc * tc / (mc * tc + prev_m * tpc);
        hrt_ml_stream(r, canonical.light, canonical.uv, canonical.visible, m * tc * canonical.W, tc);
    }
    bool from_history = false;
    if (prev_m > 0.0 && t > 0.0) {
        float m = prev_m * tp / (prev_m * tp + mc * t);
        // Its visibility was known at its own pixel, not at this one.
        from_history = hrt_ml_stream(r, prev.light, prev.uv, false, m * t * prev.W, t);
    }
    r.M = mc + prev_m;
    r.W = r.light != 0u && r.target > 0.0 ? r.wsum / r.target : 0.0;
    if (unbiased && from_history && r.W > 0.0) {
        float d;
        r.visible = hrt_ml_visible(r.light - 1u, r.uv, s.p, s.n, d);
        if (!r.visible) r.W = 0.0;
    }
    out_r.r[idx] = hrt_ml_pack(r);
}

// A random colour per light for the debug output.
vec3 hrt_ml_light_colour(uint light) {
    uint h = hrt_pcg(light * 0x9e3779b9u + 1u);
    return vec3(float(h & 0xffu), float((h >> 8) & 0xffu), float((h >> 16) & 0xffu)) / 255.0;
}

void hrt_ml_write(ivec2 pixel, vec3 diffuse, vec3 specular, float hit, uint light, float m) {
    imageStore(u_diffuse_out, pixel, vec4(diffuse, hit));
    imageStore(u_specular_out, pixel, vec4(specular, hit));
    if (u_c.modes.w != 0u) imageStore(u_debug_out, pixel, vec4(light == 0u ? vec3(0.0) : hrt_ml_light_colour(light - 1u), m));
}

// Without resampling (ResamplingMode::PowerSampling, the baseline): `counts.y` lights by power
// and one directional light, a shadow ray each.
void hrt_ml_power_sampling(ivec2 pixel, HrtShadePoint s) {
    uint locals = u_c.counts.y;
    uint tile = hrt_ml_tile(uvec2(pixel));
    vec3 diffuse = vec3(0.0), specular = vec3(0.0);
    float hit = 1e4;
    for (uint i = 0u; i < locals + (u_c.modes.z != 0u ? 1u : 0u); ++i) {
        bool directional = i == locals;
        uvec2 c = hrt_ml_presampled(tile, directional);
        float pdf = uintBitsToFloat(c.y) * (directional ? 1.0 : float(locals));
        vec2 uv = vec2(hrt_ml_rand(), hrt_ml_rand());
        vec3 E;
        float fs;
        if (!(pdf > 0.0) || !(hrt_ml_target(c.x, s, E, fs) > 0.0)) continue;
        float d;
        if (!hrt_ml_visible(c.x, uv, s.p, s.n, d)) continue;
        diffuse += E * (1.0 / (HRT_PI * pdf));
        specular += E * (fs / pdf);
        hit = min(hit, d);
    }
    hrt_ml_write(pixel, diffuse, specular, hit, 0u, 0.0);
}

// Pass 2: neighbours' reservoirs merged in (same surface within the radius), the chosen sample
// shaded with one shadow ray, the reservoir kept for next frame, this frame's surface too.
void hrt_ml_spatial_main() {
    TraceCommon c = u_c.common_;
    uvec2 launch = HRT_LAUNCH_ID;
    if (any(greaterThanEqual(launch, uvec2(c.viewport.zw)))) return;
    ivec2 pixel = ivec2(launch + uvec2(c.viewport.xy));
    uint idx = hrt_ml_index(pixel);
    HrtReservoirs kept = HrtReservoirs(u_c.addr2.xy);
    HrtSurfaces surfaces = HrtSurfaces(u_c.addr2.zw);
    HrtShadePoint s;
    if (!hrt_ml_surface(pixel, s)) {
        kept.r[idx] = hrt_ml_pack(hrt_ml_empty());
        surfaces.s[idx] = hrt_ml_pack_surface(vec3(0.0, 0.0, 1.0), -1.0);
        hrt_ml_write(pixel, vec3(0.0), vec3(0.0), 0.0, 0u, 0.0);
        return;
    }
    float dist = distance(s.p, c.view_to_world[3].xyz);
    surfaces.s[idx] = hrt_ml_pack_surface(s.n, dist);
    hrt_ml_seed(uvec2(pixel), 0x2u);
    if (u_c.modes.x == HRT_ML_POWER) {
        kept.r[idx] = hrt_ml_pack(hrt_ml_empty());
        hrt_ml_power_sampling(pixel, s);
        return;
    }
    HrtReservoirs temporal = HrtReservoirs(u_c.addr1.zw);
    HrtReservoir own = hrt_ml_unpack(temporal.r[idx]);
    // Neighbours merged by pairwise MIS with confidences (Bitterli 2022; "A Gentle Introduction
    // to ReSTIR", Wyman et al. 2023): each neighbour i forms a pair with this pixel, whose
    // confidence Mc is shared out as Mc / k over the k neighbours drawn; within a pair the
    // balance heuristic of the confidence-weighted targets decides. Weights (before the common
    // factor 1 / (Mc + sum Mi)):
    //   neighbour i's sample y:   (Mi + Mc/k) Mi pi(y) / (Mi pi(y) + Mc/k pc(y))
    //   this pixel's sample y:    sum_i (Mi + Mc/k) (Mc/k) pc(y) / (Mi pi(y) + Mc/k pc(y))
    // which sum to one for every y, and vanish where a domain cannot produce y. A neighbour
    // rejected by the geometric test stays in the sum with Mi = 0 (its pair gives the pixel all
    // of its share), so k is known before the loop. Unbiased, a neighbour's reservoir holds only
    // samples it sees: pi includes its visibility (one ray a neighbour, for this pixel's sample).
    bool unbiased = u_c.modes.x == HRT_ML_UNBIASED;
    const uint MAX_NEIGHBOURS = 8u; // ManyLightsSettings::spatial_samples' bound
    uint samples = min(u_c.counts.z, MAX_NEIGHBOURS);
    float mc = own.M;
    float share = samples > 0u ? mc / float(samples) : mc;
    float tc = own.light != 0u && own.W > 0.0 ? hrt_ml_target_only(own.light - 1u, s) : 0.0;
    float m_own = samples > 0u ? 0.0 : mc; // this pixel's sample's weight, summed over pairs
    float m_total = mc;
    HrtReservoir r = hrt_ml_empty();
    for (uint i = 0u; i < samples; ++i) {
        vec2 d = hrt_disk(vec2(hrt_ml_rand(), hrt_ml_rand())) * u_c.params.x;
        ivec2 q = pixel + ivec2(round(d));
        HrtShadePoint qs;
        HrtReservoir nb = hrt_ml_empty();
        if (q != pixel && hrt_ml_in_viewport(q, c.viewport) && hrt_ml_surface(q, qs) && hrt_ml_similar(s, dist, qs.p, qs.n))
            nb = hrt_ml_unpack(temporal.r[hrt_ml_index(q)]);
        float mi = nb.M;
        m_total += mi;
        if (tc > 0.0) {
            float ti = mi > 0.0 ? hrt_ml_target_only(own.light - 1u, qs) : 0.0;
            float dd;
            if (unbiased && ti > 0.0 && !hrt_ml_visible(own.light - 1u, own.uv, qs.p, qs.n, dd)) ti = 0.0;
            float den = mi * ti + share * tc;
            if (den > 0.0) m_own += (mi + share) * share * tc / den;
        }
        if (mi > 0.0 && nb.light != 0u && nb.W > 0.0) {
            float t = hrt_ml_target_only(nb.light - 1u, s);
            float ti = hrt_ml_target_only(nb.light - 1u, qs);
            float den = mi * ti + share * t;
            float m = den > 0.0 ? (mi + share) * mi * ti / den : 0.0;
            hrt_ml_stream(r, nb.light, nb.uv, false, m * t * nb.W, t);
        }
    }
    bool own_sample = tc > 0.0 && hrt_ml_stream(r, own.light, own.uv, own.visible, m_own * tc * own.W, tc);
    r.M = m_total;
    r.W = r.light != 0u && r.target > 0.0 ? r.wsum / (m_total * r.target) : 0.0;
    vec3 diffuse = vec3(0.0), specular = vec3(0.0);
    float hit = 1e4;
    if (r.W > 0.0) {
        uint light = r.light - 1u;
        LightGpu l = hrt_ml_light(light);
        bool visible = own_sample && r.visible;
        float d = hit;
        if (!visible) visible = hrt_ml_visible(light, r.uv, s.p, s.n, d);
        else {
            vec3 dir;
            float tmax;
            hrt_light_ray(l, hrt_offset_ray(c, s.p, s.n), r.uv, dir, tmax);
            d = min(tmax, 1e4);
        }
        hit = d;
        if (visible) {
            vec3 E;
            float fs;
            hrt_ml_target(light, s, E, fs);
            diffuse = E * (r.W / HRT_PI);
            specular = E * (fs * r.W);
        } else {
            r.W = 0.0; // passed on only where it reaches the light
        }
        r.visible = visible;
    }
    kept.r[idx] = hrt_ml_pack(r);
    hrt_ml_write(pixel, diffuse, specular, hit, r.light, r.M);
}
#endif
