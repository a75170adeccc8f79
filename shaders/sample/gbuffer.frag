#version 460
// G-buffer targets: world normal facing the camera + roughness, albedo + metalness, and
// screen-space motion in pixels (previous - current), the SDK's MotionType::RgViewSpace.
#extension GL_GOOGLE_include_directive : require
#include "gbuffer_common.glsl"

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec4 v_clip;
layout(location = 2) in vec4 v_prev_clip;
layout(location = 0) out vec4 o_normal_roughness;
layout(location = 1) out vec4 o_albedo_metalness;
layout(location = 2) out vec2 o_motion;

void main() {
    Instance i = u_instances.items[u_push.instance];
    // Flat shading: the triangle's plane, oriented towards the camera (as the reference's).
    vec3 n = normalize(cross(dFdx(v_world), dFdy(v_world)));
    if (dot(n, u_camera.eye.xyz - v_world) < 0.0) n = -n;
    o_normal_roughness = vec4(n, i.material.w);
    o_albedo_metalness = vec4(i.material.rgb, i.extra.x);
    vec2 cur = v_clip.xy / v_clip.w;
    vec2 prev = v_prev_clip.xy / v_prev_clip.w;
    o_motion = (prev - cur) * 0.5 * u_camera.viewport.xy;
}
