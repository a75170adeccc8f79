#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// The tiles surfel layout on the GPU (sdk/src/passes/surfel_layout.rs), pass 1 of 3: each
// triangle's resolution R = clamp(ceil(longest edge / tile_unit_length), 1, limit), as
// sdk/src/cache/layout.rs `resolution` computes it, into its layout words (uvec2(first
// sample, R); the first sample comes from the prefix sum of `counts` = R x R), and the
// largest R. Reads the SDK's compact copy: 12-byte positions, u32 indices.
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Floats { float f[]; };
layout(push_constant) uniform Push {
    uvec2 positions;
    uvec2 indices;
    uvec2 words;
    uvec2 counts;
    uvec2 result;      // uvec2(samples, largest R), zeroed by the recorder
    uint triangles;
    float unit;
    uint limit;
} pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.triangles) return;
    Words idx = Words(pc.indices);
    Floats pos = Floats(pc.positions);
    vec3 p[3];
    for (uint k = 0u; k < 3u; ++k) {
        uint i = idx.w[3u * t + k];
        p[k] = vec3(pos.f[3u * i], pos.f[3u * i + 1u], pos.f[3u * i + 2u]);
    }
    float longest = max(max(distance(p[0], p[1]), distance(p[1], p[2])), distance(p[2], p[0]));
    float q = ceil(longest / pc.unit);
    uint r = (isinf(q) || isnan(q)) ? 1u : uint(clamp(q, 1.0, 65536.0));
    r = clamp(r, 1u, max(pc.limit, 1u));
    Words(pc.words).w[2u * t + 1u] = r;
    Words(pc.counts).w[t] = r * r;
    atomicMax(Words(pc.result).w[1], r);
}
