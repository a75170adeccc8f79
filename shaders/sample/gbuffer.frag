#version 460
// G-buffer targets: world normal facing the camera (normal-mapped) + roughness, albedo +
// metalness, screen-space motion in pixels (previous - current: the SDK's
// MotionType::RgViewSpace), and emitted radiance. glTF's metallic-roughness material: each
// factor times its texture (white, or a flat normal, where the material has none).
#extension GL_GOOGLE_include_directive : require
#include "gbuffer_common.glsl"

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec4 v_clip;
layout(location = 2) in vec4 v_prev_clip;
layout(location = 3) in vec3 v_normal;
layout(location = 4) in vec2 v_uv;
layout(location = 5) in vec4 v_tangent;
layout(location = 6) in vec4 v_color;
// Base colour (sRGB, so sampled linear), metallic-roughness (G roughness, B metalness),
// tangent-space normal, emissive (sRGB).
layout(set = 0, binding = 2) uniform sampler2D u_textures[4];
layout(location = 0) out vec4 o_normal_roughness;
layout(location = 1) out vec4 o_albedo_metalness;
layout(location = 2) out vec2 o_motion;
layout(location = 3) out vec4 o_emissive;

// The tangent frame (tangent along +U, bitangent along glTF's "up" in the texture, -V) of the
// surface with normal n: the vertex tangent where the mesh has one, else one made from the
// screen derivatives of position and texture coordinate (Schüler, "Normal mapping without
// precomputed tangents", 2013), which follows mirrored UVs by itself.
mat3 tangent_frame(vec3 n) {
    if (dot(v_tangent.xyz, v_tangent.xyz) > 1e-12) {
        vec3 t = normalize(v_tangent.xyz - n * dot(n, v_tangent.xyz));
        return mat3(t, cross(n, t) * (v_tangent.w < 0.0 ? -1.0 : 1.0), n);
    }
    vec3 dp1 = dFdx(v_world), dp2 = dFdy(v_world);
    vec2 duv1 = dFdx(v_uv), duv2 = dFdy(v_uv);
    vec3 dp2perp = cross(dp2, n), dp1perp = cross(n, dp1);
    vec3 t = dp2perp * duv1.x + dp1perp * duv2.x;
    vec3 b = dp2perp * duv1.y + dp1perp * duv2.y;
    // Schüler's frame is for a y-up window: Vulkan's y-down screen (with n facing the eye)
    // flips both vectors. The bitangent is then flipped back to glTF's -V.
    float scale = inversesqrt(max(max(dot(t, t), dot(b, b)), 1e-30));
    return mat3(-t * scale, b * scale, n);
}

void main() {
    Instance i = u_instances.items[u_push.instance];
    vec4 base = texture(u_textures[0], v_uv);
    // Alpha-tested draws (foliage): the holes the SDK's rays pass through too.
    if (base.a < i.extra.y) discard;
    // The triangle's plane, oriented towards the camera (as the reference's), orients the
    // interpolated vertex normal: meshes of either winding shade from the side they are seen.
    // A zero vertex normal (a mesh uploaded without normals) shades flat: the plane itself.
    vec3 g = normalize(cross(dFdx(v_world), dFdy(v_world)));
    if (dot(g, u_camera.eye.xyz - v_world) < 0.0) g = -g;
    float len = length(v_normal);
    vec3 n = len > 1e-12 ? v_normal / len : g;
    if (dot(n, g) < 0.0) n = -n;
    float normal_scale = i.extra.z;
    if (normal_scale > 0.0) {
        vec3 tn = texture(u_textures[2], v_uv).xyz * 2.0 - 1.0;
        tn.xy *= normal_scale;
        vec3 mapped = tangent_frame(n) * tn;
        // A degenerate frame (no UV gradient) keeps the vertex normal.
        if (dot(mapped, mapped) > 1e-12) n = normalize(mapped);
    }
    vec4 mr = texture(u_textures[1], v_uv);
    o_normal_roughness = vec4(n, i.material.w * mr.g);
    // The vertex colour tints the base colour (its alpha is not used: the cut-out is the
    // texture's, which the SDK's rays test too).
    o_albedo_metalness = vec4(i.material.rgb * base.rgb * v_color.rgb, i.extra.x * mr.b);
    o_emissive = vec4(i.emissive.rgb * texture(u_textures[3], v_uv).rgb, 0.0);
    vec2 cur = v_clip.xy / v_clip.w;
    vec2 prev = v_prev_clip.xy / v_prev_clip.w;
    o_motion = (prev - cur) * 0.5 * u_camera.viewport.xy;
}
