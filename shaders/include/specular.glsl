#ifndef HRT_SPECULAR_GLSL
#define HRT_SPECULAR_GLSL
// The body of the specular task; the includer provides hrt_trace_record and HRT_LAUNCH_ID
// (include/trace_rt.glsl or include/trace_rq.glsl).
// Specular reflections shaded from the direct-lighting cache. Roughness 0 traces the exact
// mirror direction (no noise, seeds/000); otherwise GGX visible normals are sampled (Heitz
// 2018) and each sample weighs G1(L), the VNDF estimator of the Smith-GGX lobe with F = 1:
// the output is demodulated by Fresnel — the engine multiplies by its F (or split-sum
// specular albedo). RGB = mean weighted radiance, A = hit distance of the first ray (misses:
// the ray length). An optional firefly clamp limits each sample's luminance (seeds/003).
// With hit lighting, hits of pixels up to a roughness are lit from the engine's lights.
#include "common.glsl"
#include "random.glsl"
#include "cache.glsl"
#include "trace_push.glsl"
#include "environment.glsl"
#include "light_sampling.glsl"

layout(set = 0, binding = 0) uniform accelerationStructureEXT u_tlas;
layout(set = 0, binding = 1) uniform sampler2D u_depth;
layout(set = 0, binding = 2) uniform sampler2D u_normals;
layout(set = 0, binding = 3) uniform sampler2D u_roughness;
layout(set = 0, binding = 4) uniform writeonly image2D u_out;
layout(set = 0, binding = 5, std140) uniform SpecularConstants {
    TraceCommon common_;
    vec4 params;           // ray length, firefly clamp (0 = off), unused, unused
    vec4 miss;             // miss radiance rgb, unused
    uvec4 counts;          // rays per pixel, bilinear, instance table (uvec2)
    vec4 specular;         // global metalness, has specular image, has demodulated output, unused
    EnvironmentGpu environment;
    uvec4 hit_lighting;    // light count (0: off), shadow-ray mask, gather rays, gather-ray mask
    vec4 hit_params;       // largest roughness hit-lit, indirect mode (HRT_HIT_INDIRECT_*), unused x2
    LightGpu lights[HRT_MAX_LIGHTS];
} u_c;
#define HRT_LIGHTS u_c.lights


// GGX visible normal in the local frame (z = normal), Heitz 2018, isotropic alpha.
vec3 hrt_ggx_vndf(vec3 v, float alpha, vec2 u) {
    vec3 vh = normalize(vec3(alpha * v.x, alpha * v.y, v.z));
    float lensq = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = lensq > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(lensq) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * HRT_PI * u.y;
    float s = 0.5 * (1.0 + vh.z);
    float p1 = r * cos(phi);
    float p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * r * sin(phi);
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(0.0, nh.z)));
}

float hrt_smith_g1(float ndotx, float alpha) {
    float a2 = alpha * alpha;
    return 2.0 * ndotx / (ndotx + sqrt(a2 + (1.0 - a2) * ndotx * ndotx));
}

layout(set = 0, binding = 6) uniform sampler2D u_direct;
layout(set = 0, binding = 7) uniform sampler2D u_specular;
layout(set = 0, binding = 8) uniform writeonly image2D u_demodulated;
layout(set = 0, binding = 9) uniform sampler2D u_input_mask;
layout(set = 0, binding = 10) uniform sampler2D u_environment;
#include "screen_lighting.glsl"
#include "direct_light.glsl"

// Hit lighting (TraceSpecularTask::hit_lighting, Lumen's name for it): the hit is shaded from
// the engine's lights with shadow rays — albedo x direct light + emission, exact where the
// cache is a tile wide — plus the indirect part (HitIndirect): the cache sample's radiance
// less the direct light and emission the same lights give at that sample (what the relight
// stored beyond them: its bounce), or `gather` cosine rays reading the caches at their own
// hits, or nothing. Both faces are lit: the one the ray sees.
#define HRT_HIT_INDIRECT_CACHE 0u
#define HRT_HIT_INDIRECT_GATHER 1u
#define HRT_HIT_INDIRECT_NONE 2u
vec3 hrt_hit_lighting(InstanceTable table, HitRecord hit, vec3 dir, inout uint h) {
    InstanceGpu inst = table.v[hit.instance];
    vec3 p, n;
    if (!hrt_surface_point(inst, hit.prim, hrt_bary3(hit.bary), p, n)) return inst.emission.rgb;
    if (dot(n, dir) > 0.0) n = -n;
    // The paper's constants (RayOffset's defaults): relative to the float's own precision.
    vec3 origin = hrt_offset_world(p, n, 1.0 / 32.0, 1.0 / 65536.0, 256.0);
    uint count = u_c.hit_lighting.x, shadow_mask = u_c.hit_lighting.y;
    vec3 albedo = hrt_albedo(inst, hit.prim, hrt_bary3(hit.bary));
    vec3 lit = albedo * hrt_direct_light(u_tlas, count, shadow_mask, p, n, origin, h) + inst.emission.rgb;
    uint mode = uint(u_c.hit_params.y);
    if (mode == HRT_HIT_INDIRECT_CACHE && hrt_has_cache(inst)) {
        // The relight lit the front face a hair inside the triangle; light the sample there.
        vec3 bs;
        uint index = hrt_cache_sample_point(inst, hit.prim, hit.bary, bs);
        vec4 cached = hrt_sample(CacheSamples(inst.cache_addr), index);
        vec3 q, nq;
        bs = mix(bs, vec3(1.0 / 3.0), 1e-3);
        if (cached.w > 0.0 && hrt_surface_point(inst, hit.prim, bs, q, nq)) {
            vec3 oq = hrt_offset_world(q, nq, 1.0 / 32.0, 1.0 / 65536.0, 256.0);
            vec3 e = hrt_direct_light(u_tlas, count, shadow_mask, q, nq, oq, h);
            vec3 at_sample = hrt_albedo(inst, hit.prim, bs) * e + inst.emission.rgb;
            lit += max(cached.rgb - at_sample, vec3(0.0));
        }
    } else if (mode == HRT_HIT_INDIRECT_GATHER) {
        uint gathers = max(u_c.hit_lighting.z, 1u);
        vec3 sum = vec3(0.0);
        for (uint i = 0u; i < gathers; ++i) {
            vec3 r, d;
            bool landed = hrt_gather_cache(u_tlas, table, u_c.hit_lighting.w, origin, n, h, r, d);
            sum += landed ? r : hrt_miss_radiance(u_c.environment, u_environment, d, u_c.miss.rgb);
        }
        lit += albedo * sum / float(gathers);
    }
    return lit;
}

void hrt_specular_main() {
    TraceCommon c = u_c.common_;
    uvec2 pixel;
    vec3 p, n;
    int kind = hrt_gbuffer_pixel(c, HRT_LAUNCH_ID, u_depth, u_normals, u_input_mask, pixel, p, n);
    if (kind == HRT_PIXEL_SKIP) return;
    if (kind == HRT_PIXEL_BACKGROUND) {
        imageStore(u_out, ivec2(pixel), vec4(0.0));
        if (u_c.specular.z != 0.0) imageStore(u_demodulated, ivec2(pixel), vec4(0.0));
        return;
    }
    vec3 eye = c.view_to_world[3].xyz;
    vec3 v = normalize(eye - p);
    if (dot(v, n) <= 0.0) n = normalize(n + v * (1e-3 - dot(v, n))); // back-facing normal map
    float roughness = hrt_surface_roughness(c, u_roughness, ivec2(pixel));
    float alpha = roughness * roughness;
    vec3 origin = hrt_offset_ray(c, p, n);
    mat3 basis = hrt_basis(n);
    vec3 v_local = transpose(basis) * v;
    uint rays = alpha < 1e-4 ? 1u : u_c.counts.x;
    bool bilinear = u_c.counts.y != 0u;
    InstanceTable table = InstanceTable(u_c.counts.zw);
    float ray_length = u_c.params.x;
    float clamp_lum = u_c.params.y;
    // The pixel's sequence runs on across frames (see hrt_independent_frames).
    HrtSequence seq = hrt_tile_sequence(c.frame.x, c.frame.z != 0u, pixel, 0x5bec7u, rays);
    seq = hrt_with_generator(seq, c, pixel, 0x5bec7u, rays);
    bool hit_lit = u_c.hit_lighting.x > 0u && roughness <= u_c.hit_params.x;
    uint h = hrt_pcg(pixel.x ^ hrt_pcg(pixel.y ^ hrt_pcg(c.frame.x ^ 0x4c1u)));

    vec3 sum = vec3(0.0);
    float first_t = ray_length;
    for (uint i = 0u; i < rays; ++i) {
        vec3 dir;
        float weight = 1.0;
        if (alpha < 1e-4) {
            dir = reflect(-v, n);
        } else {
            vec3 h = basis * hrt_ggx_vndf(v_local, alpha, hrt_sample(seq, i));
            dir = reflect(-v, h);
            float ndotl = dot(n, dir);
            if (ndotl <= 0.0) continue; // reflected below the surface: no light
            weight = hrt_smith_g1(ndotl, alpha);
        }
        HitRecord p_hit = hrt_trace_record(u_tlas, c.frame.y & 0xffu, origin, dir, ray_length);
        if (p_hit.t >= 0.0) hrt_mark_used(p_hit.instance);
        vec3 radiance;
        if (p_hit.t < 0.0) radiance = hrt_miss_radiance(u_c.environment, u_environment, dir, u_c.miss.rgb);
        else if (hit_lit) radiance = hrt_hit_lighting(table, p_hit, dir, h);
        else radiance = hrt_hit_radiance(c, origin + dir * p_hit.t, table.v[p_hit.instance], p_hit.prim, p_hit.bary, bilinear);
        if (clamp_lum > 0.0) {
            float lum = dot(radiance, vec3(0.2126, 0.7152, 0.0722));
            if (lum > clamp_lum) radiance *= clamp_lum / lum;
        }
        sum += radiance * weight;
        if (i == 0u && p_hit.t >= 0.0) first_t = p_hit.t;
    }
    vec3 demodulated = sum / float(rays);
    vec3 spec = vec3(u_c.specular.x);
    if (u_c.specular.y != 0.0) spec *= texelFetch(u_specular, ivec2(pixel), 0).rgb;
    imageStore(u_out, ivec2(pixel), vec4(demodulated * spec, first_t));
    if (u_c.specular.z != 0.0) imageStore(u_demodulated, ivec2(pixel), vec4(demodulated, first_t));
}
#endif
