#version 460
// G-buffer targets: world normal facing the camera + roughness, albedo (x base-colour texture)
// + metalness, and
// screen-space motion in pixels (previous - current), the SDK's MotionType::RgViewSpace.
#extension GL_GOOGLE_include_directive : require
#include "gbuffer_common.glsl"

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec4 v_clip;
layout(location = 2) in vec4 v_prev_clip;
layout(location = 3) in vec3 v_normal;
layout(location = 4) in vec2 v_uv;
// The draw's base-colour texture (sRGB, so sampled linear); a white texel when it has none.
layout(set = 0, binding = 2) uniform sampler2D u_albedo;
layout(location = 0) out vec4 o_normal_roughness;
layout(location = 1) out vec4 o_albedo_metalness;
layout(location = 2) out vec2 o_motion;

void main() {
    Instance i = u_instances.items[u_push.instance];
    // The triangle's plane, oriented towards the camera (as the reference's), orients the
    // interpolated vertex normal: meshes of either winding shade from the side they are seen.
    // A zero vertex normal (a mesh uploaded without normals) shades flat: the plane itself.
    vec3 g = normalize(cross(dFdx(v_world), dFdy(v_world)));
    if (dot(g, u_camera.eye.xyz - v_world) < 0.0) g = -g;
    float len = length(v_normal);
    vec3 n = len > 1e-12 ? v_normal / len : g;
    if (dot(n, g) < 0.0) n = -n;
    o_normal_roughness = vec4(n, i.material.w);
    vec4 base = texture(u_albedo, v_uv);
    // Alpha-tested draws (foliage): the holes the SDK's rays pass through too.
    if (base.a < i.extra.y) discard;
    o_albedo_metalness = vec4(i.material.rgb * base.rgb, i.extra.x);
    vec2 cur = v_clip.xy / v_clip.w;
    vec2 prev = v_prev_clip.xy / v_prev_clip.w;
    o_motion = (prev - cur) * 0.5 * u_camera.viewport.xy;
}
