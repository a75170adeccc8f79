// Direct light from the engine's lights at a point of the scene, with shadow rays: what
// RelightCacheTask writes into the caches and what the specular task's hit lighting shades
// mirror hits with. The includer provides hrt_trace_record_flags (trace_rt.glsl or
// trace_rq.glsl), the instance table (cache.glsl), and defines HRT_LIGHTS as its array of
// LightGpu (a uniform block's: passing it as an argument would copy it per invocation).
#ifndef HRT_DIRECT_LIGHT_GLSL
#define HRT_DIRECT_LIGHT_GLSL
#include "light_sampling.glsl"

// A point of triangle `prim` at barycentrics b (weights of its vertices 0, 1, 2): world
// position and front-face normal (counter-clockwise in object space; a mirroring transform
// reverses the winding of the world-space corners). False for a degenerate triangle.
bool hrt_surface_point(InstanceGpu inst, uint prim, vec3 b, out vec3 p, out vec3 n) {
    vec3 v0 = hrt_to_world(inst, hrt_vertex(inst, hrt_index(inst, prim * 3u)));
    vec3 v1 = hrt_to_world(inst, hrt_vertex(inst, hrt_index(inst, prim * 3u + 1u)));
    vec3 v2 = hrt_to_world(inst, hrt_vertex(inst, hrt_index(inst, prim * 3u + 2u)));
    p = b.x * v0 + b.y * v1 + b.z * v2;
    n = cross(v1 - v0, v2 - v0);
    if (dot(n, n) <= 0.0) return false;
    mat3 m = mat3(inst.object_to_world[0].xyz, inst.object_to_world[1].xyz, inst.object_to_world[2].xyz);
    n = normalize(determinant(m) < 0.0 ? -n : n);
    return true;
}

// Sum over the first `count` of HRT_LIGHTS of colour x intensity x irradiance x visibility
// at (p, n): one shadow ray per light (rays masked by `mask`) from `origin` towards a random
// point of its extent, so sized lights give soft shadows over frames. `h` is the caller's
// random state.
vec3 hrt_direct_light(accelerationStructureEXT tlas, uint count, uint mask, vec3 p, vec3 n, vec3 origin, inout uint h) {
    vec3 e = vec3(0.0);
    for (uint l = 0u; l < count; ++l) {
        LightGpu light = HRT_LIGHTS[l];
        float irradiance = hrt_light_weight(light, p, n, hrt_light_reach(light, p));
        if (irradiance <= 0.0) continue;
        h = hrt_pcg(h + l);
        vec2 u = vec2(hrt_u01(h), hrt_u01(hrt_pcg(h ^ 0x9e3779b9u)));
        vec3 dir;
        float tmax;
        hrt_light_ray(light, origin, u, dir, tmax);
        if (dot(dir, n) <= 0.0) continue;
        HitRecord hit = hrt_trace_record_flags(tlas, gl_RayFlagsTerminateOnFirstHitEXT, mask, origin, dir, tmax);
        if (hit.t < 0.0) e += light.power.yzw * irradiance;
    }
    return e;
}

// One cosine-distributed ray from `origin` around n (masked by `mask`) reading the cache
// sample it lands on: true with that sample's radiance (nothing while it is unlit), false
// when the ray leaves the scene (the caller's sky). Its mean over frames is the gathered
// radiance's cosine-weighted mean, TraceDiffuseTask's convention.
bool hrt_gather_cache(accelerationStructureEXT tlas, InstanceTable table, uint mask, vec3 origin, vec3 n, inout uint h,
                      out vec3 radiance, out vec3 dir) {
    h = hrt_pcg(h ^ 0x68bc21ebu);
    vec2 u = vec2(hrt_u01(h), hrt_u01(hrt_pcg(h)));
    dir = hrt_basis(n) * hrt_cosine_hemisphere(u);
    HitRecord hit = hrt_trace_record(tlas, mask, origin, dir, 1e30);
    radiance = vec3(0.0);
    if (hit.t < 0.0) return false;
    InstanceGpu other = table.v[hit.instance];
    if (hrt_has_cache(other)) {
        vec4 s = hrt_sample(CacheSamples(other.cache_addr), hrt_cache_sample_index(other, hit.prim, hit.bary));
        radiance = s.w > 0.0 ? s.rgb : vec3(0.0);
    }
    return true;
}
#endif
