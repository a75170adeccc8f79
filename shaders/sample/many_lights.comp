#version 460
// Adds the SDK's resampled many-light direct lighting (denoised, demodulated) to the sample's
// lit image, the way an engine composes it: diffuse albedo x the diffuse output (irradiance /
// pi) plus the specular colour (F0: 0.04 for dielectrics, the albedo for metals) x the
// specular output. The lit image is then what the SDK injects into its cache next frame, so
// the many lights reach GI and reflections too.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D u_albedo_metalness;
layout(set = 0, binding = 1) uniform sampler2D u_diffuse;
layout(set = 0, binding = 2) uniform sampler2D u_specular;
layout(set = 0, binding = 3, rgba16f) uniform image2D u_lit;
layout(set = 0, binding = 4, std140) uniform Size {
    vec4 size; // width, height
} u;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x >= int(u.size.x) || pixel.y >= int(u.size.y)) return;
    vec4 am = texelFetch(u_albedo_metalness, pixel, 0);
    vec3 diffuse_albedo = am.rgb * (1.0 - am.a);
    vec3 f0 = mix(vec3(0.04), am.rgb, am.a);
    vec4 lit = imageLoad(u_lit, pixel);
    lit.rgb += diffuse_albedo * texelFetch(u_diffuse, pixel, 0).rgb + f0 * texelFetch(u_specular, pixel, 0).rgb;
    imageStore(u_lit, pixel, lit);
}
