#version 460
// The sample's deferred direct lighting (what an engine already has): a sun and a point light,
// each with its visibility from the SDK's (denoised) shadow output, a glTF file's lights (their
// unshadowed irradiance summed, times the one visibility the SDK's multi-light shadow task
// weighs by each light's unshadowed irradiance) and a constant ambient.
// Lambertian over the diffuse albedo (albedo x (1 - metalness): metals have no diffuse):
// lit = diffuse x (sun E x sun visibility + point E x point visibility + ambient) + emitted,
// the convention of the test kit's reference (tests/src/reference.rs, direct_lighting). The
// emission is part of the lit image the SDK injects: glowing surfaces light the scene's GI
// and show in its reflections through the cache.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D u_depth;
layout(set = 0, binding = 1) uniform sampler2D u_normal_roughness;
layout(set = 0, binding = 2) uniform sampler2D u_albedo_metalness;
layout(set = 0, binding = 3) uniform sampler2D u_sun_visibility;
layout(set = 0, binding = 4) uniform sampler2D u_point_visibility;
layout(set = 0, binding = 5) uniform sampler2D u_emissive;
layout(set = 0, binding = 6) uniform sampler2D u_file_visibility;
layout(set = 0, binding = 7, rgba16f) uniform writeonly image2D u_lit;

// A file light (lighting.rs, FileLightGpu).
struct FileLight {
    vec4 position;   // xyz, type (0 directional, 1 point, 2 spot)
    vec4 direction;  // direction the light travels, range (0: unlimited)
    vec4 radiance;   // colour x intensity, cos of the outer cone
    vec4 cone;       // cos of the inner cone
};

layout(set = 0, binding = 8, std140) uniform Lighting {
    mat4 clip_to_world;
    vec4 sun;        // direction towards the sun, intensity
    vec4 point;      // position, intensity
    vec4 ambient;    // ambient irradiance, viewport width, height, visibility channel (0 = R, 1 = G)
    uvec4 counts;    // file lights
    FileLight lights[32];
} u;

// A file light's irradiance at (p, n), unshadowed, with the falloffs the SDK documents for its
// lights (LightInfo), so the multi-light task weighs each light as it is shaded here: the
// windowed range falloff (1 - (d/range)^4)^2 and the smoothstep from the outer to the inner cone.
vec3 file_light(FileLight l, vec3 p, vec3 n) {
    uint kind = uint(l.position.w);
    if (kind == 0u) return l.radiance.rgb * max(dot(n, -normalize(l.direction.xyz)), 0.0);
    vec3 to_light = l.position.xyz - p;
    float d2 = max(dot(to_light, to_light), 1e-8);
    float d = sqrt(d2);
    vec3 dir = to_light / d;
    float reach = 1.0;
    if (l.direction.w > 0.0) {
        float r = d / l.direction.w;
        reach = clamp(1.0 - r * r * r * r, 0.0, 1.0);
        reach *= reach;
    }
    if (kind == 2u) {
        float c = dot(-dir, normalize(l.direction.xyz));
        reach *= c <= l.radiance.w ? 0.0 : smoothstep(l.radiance.w, max(l.cone.x, l.radiance.w + 1e-6), c);
    }
    return l.radiance.rgb * (reach * max(dot(n, dir), 0.0) / d2);
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x >= int(u.ambient.y) || pixel.y >= int(u.ambient.z)) return;
    float depth = texelFetch(u_depth, pixel, 0).r;
    if (depth >= 1.0) { imageStore(u_lit, pixel, vec4(0.0)); return; }
    vec2 ndc = (vec2(pixel) + 0.5) / u.ambient.yz * 2.0 - 1.0;
    vec4 h = u.clip_to_world * vec4(ndc, depth, 1.0);
    vec3 p = h.xyz / h.w;
    vec3 n = normalize(texelFetch(u_normal_roughness, pixel, 0).xyz);
    vec4 albedo_metalness = texelFetch(u_albedo_metalness, pixel, 0);
    vec3 diffuse = albedo_metalness.rgb * (1.0 - albedo_metalness.a);
    // Denoised shadows hold visibility in every channel; raw shadow traces in G.
    int channel = int(u.ambient.w);
    float sun_visibility = texelFetch(u_sun_visibility, pixel, 0)[channel];
    float point_visibility = texelFetch(u_point_visibility, pixel, 0)[channel];
    float e = max(dot(n, normalize(u.sun.xyz)), 0.0) * u.sun.w * sun_visibility;
    vec3 to_point = u.point.xyz - p;
    float d2 = max(dot(to_point, to_point), 1e-4);
    e += max(dot(n, to_point * inversesqrt(d2)), 0.0) * u.point.w / d2 * point_visibility;
    vec3 file = vec3(0.0);
    for (uint i = 0u; i < u.counts.x; ++i) file += file_light(u.lights[i], p, n);
    // The packed trace and the denoised output both hold the weighted visibility in R.
    if (u.counts.x > 0u) file *= texelFetch(u_file_visibility, pixel, 0).r;
    vec3 emitted = texelFetch(u_emissive, pixel, 0).rgb;
    imageStore(u_lit, pixel, vec4(diffuse * (e + u.ambient.x + file) + emitted, 1.0));
}
