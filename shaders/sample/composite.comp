#version 460
// The sample's composite: the engine's direct lighting (already shadowed by the SDK's
// shadows) plus the SDK's denoised indirect light, the issue's
//   direct x shadow + GI x albedo x AO + reflections.
// Diffuse albedo = albedo x (1 - metalness); reflections are the SDK's specular radiance
// (Smith-GGX weighted, no Fresnel) times Schlick's Fresnel with roughness, F0 = mix(0.04,
// albedo, metalness); the diffuse part keeps the energy the reflection did not take (1 - F).
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D u_depth;
layout(set = 0, binding = 1) uniform sampler2D u_normal_roughness;
layout(set = 0, binding = 2) uniform sampler2D u_albedo_metalness;
layout(set = 0, binding = 3) uniform sampler2D u_direct;
layout(set = 0, binding = 4) uniform sampler2D u_diffuse;
layout(set = 0, binding = 5) uniform sampler2D u_ao;
layout(set = 0, binding = 6) uniform sampler2D u_specular;
layout(set = 0, binding = 7, rgba16f) uniform writeonly image2D u_out;
layout(set = 0, binding = 8, std140) uniform Composite {
    mat4 clip_to_world;
    vec4 eye;        // camera position, unused
    vec4 sky;        // radiance where nothing was drawn, viewport width in w
    vec4 terms;      // weights of direct, GI, reflections; viewport height
} u;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(u.sky.w, u.terms.w);
    if (pixel.x >= size.x || pixel.y >= size.y) return;
    float depth = texelFetch(u_depth, pixel, 0).r;
    if (depth >= 1.0) { imageStore(u_out, pixel, vec4(u.sky.rgb, 1.0)); return; }
    vec2 ndc = (vec2(pixel) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec4 h = u.clip_to_world * vec4(ndc, depth, 1.0);
    vec3 p = h.xyz / h.w;
    vec4 nr = texelFetch(u_normal_roughness, pixel, 0);
    vec3 n = normalize(nr.xyz);
    vec3 v = normalize(u.eye.xyz - p);
    vec4 am = texelFetch(u_albedo_metalness, pixel, 0);
    vec3 f0 = mix(vec3(0.04), am.rgb, am.a);
    float nv = clamp(dot(n, v), 0.0, 1.0);
    vec3 fresnel = f0 + (max(vec3(1.0 - nr.w), f0) - f0) * pow(1.0 - nv, 5.0);
    vec3 diffuse_albedo = am.rgb * (1.0 - am.a) * (1.0 - fresnel);
    vec3 direct = texelFetch(u_direct, pixel, 0).rgb;
    vec3 gi = texelFetch(u_diffuse, pixel, 0).rgb * texelFetch(u_ao, pixel, 0).r;
    vec3 reflection = texelFetch(u_specular, pixel, 0).rgb * fresnel;
    vec3 c = u.terms.x * direct + u.terms.y * diffuse_albedo * gi + u.terms.z * reflection;
    imageStore(u_out, pixel, vec4(c, 1.0));
}
