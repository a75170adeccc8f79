#ifndef HRT_DIFFUSE_GLSL
#define HRT_DIFFUSE_GLSL
// The body of the diffuse task; the includer provides hrt_trace_record and HRT_LAUNCH_ID
// (include/trace_rt.glsl or include/trace_rq.glsl).
// Diffuse GI: cosine-distributed rays from the G-buffer surface; each hit is shaded from the
// direct-lighting cache of what it hits (bilinear for mesh colors), each miss takes the miss
// radiance. Output is demodulated — the mean incoming radiance, E/pi, for the engine to
// multiply by its albedo — with the mean hit distance (misses count as the ray length) in A,
// for the denoiser.
#include "common.glsl"
#include "random.glsl"
#include "cache.glsl"
#include "trace_push.glsl"
#include "environment.glsl"

layout(set = 0, binding = 0) uniform accelerationStructureEXT u_tlas;
layout(set = 0, binding = 1) uniform sampler2D u_depth;
layout(set = 0, binding = 2) uniform sampler2D u_normals;
layout(set = 0, binding = 3) uniform writeonly image2D u_out;
layout(set = 0, binding = 4, std140) uniform DiffuseConstants {
    TraceCommon common_;
    vec4 miss;        // miss radiance rgb, ray length
    uvec4 params;     // rays per pixel, bilinear, instance table (uvec2)
    vec4 brdf;        // BRDF type (0 Lambert, 1 normalized Disney), unused...
    EnvironmentGpu environment;
} u_c;
layout(set = 0, binding = 5) uniform sampler2D u_roughness;

// Normalized Disney diffuse relative to Lambert (Burley 2012 with Frostbite's energy
// normalisation, Lagarde & de Rousiers 2014): 1 for a Lambertian surface.
float hrt_disney_factor(float ndotl, float ndotv, float ldoth, float roughness) {
    float energy_bias = mix(0.0, 0.5, roughness);
    float energy_factor = mix(1.0, 1.0 / 1.51, roughness);
    float fd90 = energy_bias + 2.0 * ldoth * ldoth * roughness;
    float light = 1.0 + (fd90 - 1.0) * pow(1.0 - ndotl, 5.0);
    float view = 1.0 + (fd90 - 1.0) * pow(1.0 - ndotv, 5.0);
    return light * view * energy_factor;
}


layout(set = 0, binding = 6) uniform sampler2D u_direct;
layout(set = 0, binding = 7) uniform sampler2D u_environment;
layout(set = 0, binding = 8) uniform sampler2D u_input_mask;
#include "screen_lighting.glsl"

void hrt_diffuse_main() {
    TraceCommon c = u_c.common_;
    uvec2 pixel;
    vec3 p, n;
    int kind = hrt_gbuffer_pixel(c, HRT_LAUNCH_ID, u_depth, u_normals, u_input_mask, pixel, p, n);
    if (kind == HRT_PIXEL_SKIP) return;
    if (kind == HRT_PIXEL_BACKGROUND) {
        imageStore(u_out, ivec2(pixel), vec4(0.0));
        return;
    }
    vec3 origin = hrt_offset_ray(c, p, n);
    mat3 basis = hrt_basis(n);
    bool disney = u_c.brdf.x != 0.0;
    float roughness = hrt_surface_roughness(c, u_roughness, ivec2(pixel));
    vec3 v = normalize(c.view_to_world[3].xyz - p);
    float ndotv = clamp(dot(n, v), 1e-4, 1.0);
    uint rays = u_c.params.x;
    bool bilinear = u_c.params.y != 0u;
    InstanceTable table = InstanceTable(u_c.params.zw);
    float ray_length = u_c.miss.w;
    // The pixel's sequence runs on across frames (see hrt_independent_frames).
    HrtSequence seq = hrt_tile_sequence(c.frame.x, c.frame.z != 0u, pixel, 0xd1ffu, rays);
    seq = hrt_with_generator(seq, c, pixel, 0xd1ffu, rays);

    vec3 sum = vec3(0.0);
    float dist = 0.0;
    for (uint i = 0u; i < rays; ++i) {
        vec3 dir = basis * hrt_cosine_hemisphere(hrt_sample(seq, i));
        float w = disney ? hrt_disney_factor(max(dot(n, dir), 0.0), ndotv, dot(dir, normalize(dir + v)), roughness) : 1.0;
        HitRecord p_hit = hrt_trace_record(u_tlas, c.frame.y & 0xffu, origin, dir, ray_length);
        if (p_hit.t < 0.0) {
            sum += hrt_miss_radiance(u_c.environment, u_environment, dir, u_c.miss.rgb) * w;
            dist += ray_length;
        } else {
            hrt_mark_used(p_hit.instance);
            sum += hrt_hit_radiance(c, origin + dir * p_hit.t, table.v[p_hit.instance], p_hit.prim, p_hit.bary, bilinear) * w;
            dist += p_hit.t;
        }
    }
    imageStore(u_out, ivec2(pixel), vec4(sum / float(rays), dist / float(rays)));
}
#endif
