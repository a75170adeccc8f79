#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// The mesh-colors surfel layout on the GPU (sdk/src/passes/surfel_layout.rs), pass 1: each
// triangle's resolution R (as the tiles pass computes it) and its interior sample count, and
// each of its edges' slot in the list of edges owned by the edge's lower vertex (a counting
// sort: the lists' starts come from a prefix sum of the counts).
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Floats { float f[]; };
layout(push_constant) uniform Push {
    uvec2 positions;
    uvec2 indices;
    uvec2 res;         // R per triangle
    uvec2 interior;    // interior samples per triangle
    uvec2 degree;      // edges per lower vertex (zeroed by the recorder)
    uvec2 slot;        // per triangle edge: its place in its lower vertex's list
    uvec2 result;      // uvec2(samples, largest R)
    uint triangles;
    float unit;
    uint limit;
} pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.triangles) return;
    Words idx = Words(pc.indices);
    Floats pos = Floats(pc.positions);
    uint i[3] = uint[3](idx.w[3u * t], idx.w[3u * t + 1u], idx.w[3u * t + 2u]);
    vec3 p[3];
    for (uint k = 0u; k < 3u; ++k) p[k] = vec3(pos.f[3u * i[k]], pos.f[3u * i[k] + 1u], pos.f[3u * i[k] + 2u]);
    float longest = max(max(distance(p[0], p[1]), distance(p[1], p[2])), distance(p[2], p[0]));
    float q = ceil(longest / pc.unit);
    uint r = (isinf(q) || isnan(q)) ? 1u : uint(clamp(q, 1.0, 65536.0));
    r = clamp(r, 1u, max(pc.limit, 1u));
    Words(pc.res).w[t] = r;
    Words(pc.interior).w[t] = r < 3u ? 0u : (r - 1u) * (r - 2u) / 2u;
    atomicMax(Words(pc.result).w[1], r);
    for (uint k = 0u; k < 3u; ++k) {
        uint lo = min(i[k], i[(k + 1u) % 3u]);
        Words(pc.slot).w[3u * t + k] = atomicAdd(Words(pc.degree).w[lo], 1u);
    }
}
