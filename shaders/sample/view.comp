#version 460
// Turns any image of the frame into something to look at: `linear` = swizzle x texel + bias
// (the EXR's contents), `display` = the same tone-mapped (ACES fit, exposure) when asked and
// sRGB-encoded (the PNG's, and the window's, contents). The source may be of another size
// (the lidar view): it is sampled at the pixel's relative position.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D u_source;
layout(set = 0, binding = 1, rgba32f) uniform writeonly image2D u_linear;
layout(set = 0, binding = 2, rgba8) uniform writeonly image2D u_display;
layout(set = 0, binding = 3, std140) uniform View {
    mat4 swizzle;
    vec4 bias;
    vec4 params;     // exposure, tone map (0/1), width, height
} u;

vec3 aces(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x >= int(u.params.z) || pixel.y >= int(u.params.w)) return;
    vec2 uv = (vec2(pixel) + 0.5) / u.params.zw;
    vec4 v = u.swizzle * textureLod(u_source, uv, 0.0) + u.bias;
    imageStore(u_linear, pixel, v);
    vec3 c = v.rgb * u.params.x;
    if (u.params.y > 0.5) c = aces(c);
    imageStore(u_display, pixel, vec4(srgb(c), 1.0));
}
