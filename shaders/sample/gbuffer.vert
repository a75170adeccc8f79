#version 460
// The sample's rasterized G-buffer (what an engine already has): world position, shading
// normal and tangent, current and previous clip positions (for motion vectors) of each vertex:
// the previous one from last frame's camera, transform and vertex position, so a skinned or
// morphed mesh's own motion is in its motion vectors too.
#extension GL_GOOGLE_include_directive : require
#include "gbuffer_common.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in vec4 a_tangent;   // xyz, bitangent sign (glTF); zero: none
layout(location = 4) in vec4 a_color;     // linear, times the base colour (glTF COLOR_0)
layout(location = 5) in vec3 a_prev_position; // last frame's (a deforming mesh's moved)
layout(location = 0) out vec3 v_world;
layout(location = 1) out vec4 v_clip;
layout(location = 2) out vec4 v_prev_clip;
layout(location = 3) out vec3 v_normal;
layout(location = 4) out vec2 v_uv;
layout(location = 5) out vec4 v_tangent;
layout(location = 6) out vec4 v_color;

void main() {
    Instance i = u_instances.items[u_push.instance];
    vec4 world = i.model * vec4(a_position, 1.0);
    v_world = world.xyz;
    v_uv = a_uv;
    v_color = a_color;
    // Normals transform with the inverse transpose (instances may scale unevenly); tangents,
    // lying in the surface, with the model matrix itself.
    v_normal = transpose(inverse(mat3(i.model))) * a_normal;
    v_tangent = vec4(mat3(i.model) * a_tangent.xyz, a_tangent.w);
    v_clip = u_camera.view_proj * world;
    v_prev_clip = u_camera.prev_view_proj * (i.prev_model * vec4(a_prev_position, 1.0));
    gl_Position = v_clip;
}
