#version 460
// Morph targets and linear-blend skinning (samples/src/skinning.rs): each vertex of a
// deforming mesh, displaced by its weighted morph targets, then bent by up to four weighted
// joint matrices, written where the raster pass draws it and the SDK refits its BLAS from. Vertices are the sample's interleaved 16 floats (position, normal, texture
// coordinate, tangent with its bitangent sign, colour).
layout(local_size_x = 64) in;

struct Influence {
    uvec4 joints;
    vec4 weights;
};

layout(std430, binding = 0) readonly buffer Rest { float rest[]; };
layout(std430, binding = 1) readonly buffer Influences { Influence influences[]; };
layout(std430, binding = 2) readonly buffer Joints { mat4 joints[]; };
layout(std430, binding = 3) writeonly buffer Posed { float posed[]; };
// Per target, per vertex: position, normal and tangent displacements (xyz).
layout(std430, binding = 4) readonly buffer Displacements { vec4 displacements[]; };
layout(std430, binding = 5) readonly buffer Weights { float weights[]; };

layout(push_constant) uniform Push {
    uint vertex_count;
    uint joint_offset; // the mesh's first joint in `joints`
    uint joint_count;  // 0: no skin (every joint is the identity)
    uint target_count; // morph targets
    uint weight_offset; // the mesh's first weight in `weights`
} u;

mat4 joint(uint j) {
    return j < u.joint_count ? joints[u.joint_offset + j] : mat4(1.0);
}

// A direction bent by the blend's 3x3, unit length again; a zero vector (no normal, no
// tangent) stays zero.
vec3 bend(mat3 m, vec3 v) {
    vec3 b = m * v;
    float len2 = dot(b, b);
    return len2 > 0.0 ? b * inversesqrt(len2) : vec3(0.0);
}

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= u.vertex_count) return;
    Influence inf = influences[v];
    // Weights normalized as the CPU skinning does (files drift from a sum of 1).
    float sum = dot(inf.weights, vec4(1.0));
    vec4 w = sum > 0.0 ? inf.weights / sum : vec4(1.0, 0.0, 0.0, 0.0);
    mat4 m = w.x * joint(inf.joints.x) + w.y * joint(inf.joints.y) + w.z * joint(inf.joints.z) + w.w * joint(inf.joints.w);
    uint b = 16u * v;
    vec3 p = vec3(rest[b], rest[b + 1u], rest[b + 2u]);
    vec3 n = vec3(rest[b + 3u], rest[b + 4u], rest[b + 5u]);
    vec3 t = vec3(rest[b + 8u], rest[b + 9u], rest[b + 10u]);
    for (uint k = 0u; k < u.target_count; ++k) {
        float w = weights[u.weight_offset + k];
        if (w == 0.0) continue;
        uint d = 3u * (k * u.vertex_count + v);
        p += w * displacements[d].xyz;
        n += w * displacements[d + 1u].xyz;
        // A zero tangent (none) stays zero.
        if (dot(t, t) > 0.0) t += w * displacements[d + 2u].xyz;
    }
    p = (m * vec4(p, 1.0)).xyz;
    n = bend(mat3(m), n);
    t = bend(mat3(m), t);
    posed[b] = p.x;
    posed[b + 1u] = p.y;
    posed[b + 2u] = p.z;
    posed[b + 3u] = n.x;
    posed[b + 4u] = n.y;
    posed[b + 5u] = n.z;
    posed[b + 6u] = rest[b + 6u];
    posed[b + 7u] = rest[b + 7u];
    posed[b + 8u] = t.x;
    posed[b + 9u] = t.y;
    posed[b + 10u] = t.z;
    posed[b + 11u] = rest[b + 11u];
    for (uint c = 12u; c < 16u; ++c) posed[b + c] = rest[b + c];
}
