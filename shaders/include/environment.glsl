// The environment map of rays that miss (EnvironmentInput, sdk/src/types/trace.rs): lat-long,
// bilinear by texel fetches (wrapping in u, clamped in v), so any sampled format works without
// a filtering sampler. The includer declares the map's sampler and passes it in.
#ifndef HRT_ENVIRONMENT_GLSL
#define HRT_ENVIRONMENT_GLSL

// Constants of a task's environment (std140, 80 bytes).
struct EnvironmentGpu {
    mat4 world_to_env;  // 3x3 in a mat4: rotation^T
    vec4 params;        // intensity, has map (0/1), unused...
};

vec3 hrt_environment(EnvironmentGpu e, sampler2D map, vec3 dir) {
    vec3 d = normalize(mat3(e.world_to_env) * dir);
    vec2 uv = vec2(0.5 + atan(d.x, -d.z) * (0.5 / HRT_PI), acos(clamp(d.y, -1.0, 1.0)) * (1.0 / HRT_PI));
    ivec2 size = textureSize(map, 0);
    vec2 x = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(x));
    vec2 f = x - vec2(i0);
    int u0 = ((i0.x % size.x) + size.x) % size.x, u1 = (u0 + 1) % size.x;
    int v0 = clamp(i0.y, 0, size.y - 1), v1 = clamp(i0.y + 1, 0, size.y - 1);
    vec3 top = mix(texelFetch(map, ivec2(u0, v0), 0).rgb, texelFetch(map, ivec2(u1, v0), 0).rgb, f.x);
    vec3 bottom = mix(texelFetch(map, ivec2(u0, v1), 0).rgb, texelFetch(map, ivec2(u1, v1), 0).rgb, f.x);
    return e.params.x * mix(top, bottom, f.y);
}

// Radiance of a ray that missed: the map, or the task's constant miss radiance.
vec3 hrt_miss_radiance(EnvironmentGpu e, sampler2D map, vec3 dir, vec3 constant_radiance) {
    return e.params.y != 0.0 ? hrt_environment(e, map, dir) : constant_radiance;
}
#endif
