#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// Mesh colors on the GPU, pass 4 (per entry) and 5 (per triangle), the layout words of
// shaders/include/cache.glsl: [v0, v1, v2, e0, e1, e2, edge_info, face_base, R]. Vertex
// samples are the vertex indices themselves (0..V), edge samples follow (V + the prefix sum
// of the representatives' counts), interiors after all edges. `mode` 0: per entry, the edge
// words and their info bits (atomicOr: three entries share a triangle's info word, zeroed by
// the recorder); 1: per triangle, the vertex, face and R words, and the sample count.
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 indices;
    uvec2 words;
    uvec2 edge;
    uvec2 rep;
    uvec2 edge_res;
    uvec2 edge_base;   // per entry: the prefix sum of the counts
    uvec2 res;
    uvec2 interior_base; // per triangle: the prefix sum of the interior counts
    uvec2 result;
    uint edges;
    uint vertices;
    uint triangles;
    uint mode;
} pc;

uint sat_add(uint a, uint b) { uint c = a + b; return c < a ? 0xffffffffu : c; }

void main() {
    uint id = gl_GlobalInvocationID.x;
    Words idx = Words(pc.indices), w = Words(pc.words);
    Words rep = Words(pc.rep), edge_res = Words(pc.edge_res), edge_base = Words(pc.edge_base);
    if (pc.mode == 0u) {
        if (id >= pc.edges) return;
        uint r = rep.w[id];
        uint e = Words(pc.edge).w[id];
        uint t = e / 3u, k = e % 3u;
        uint a = idx.w[3u * t + k], b = idx.w[3u * t + (k + 1u) % 3u];
        w.w[9u * t + 3u + k] = sat_add(pc.vertices, edge_base.w[r]);
        uint info = (edge_res.w[r] & 511u) | (a > b ? 512u : 0u);
        atomicOr(w.w[9u * t + 6u], info << (10u * k));
        return;
    }
    if (id >= pc.triangles) return;
    // All edge samples: the last entry's base plus what it owns.
    uint last = pc.edges - 1u;
    uint edge_samples = sat_add(edge_base.w[last], rep.w[last] == last ? edge_res.w[last] - 1u : 0u);
    uint faces = sat_add(pc.vertices, edge_samples);
    uint r = Words(pc.res).w[id];
    for (uint k = 0u; k < 3u; ++k) w.w[9u * id + k] = idx.w[3u * id + k];
    uint base = Words(pc.interior_base).w[id];
    w.w[9u * id + 7u] = sat_add(faces, base);
    w.w[9u * id + 8u] = r;
    if (id + 1u == pc.triangles) {
        uint interior = r < 3u ? 0u : (r - 1u) * (r - 2u) / 2u;
        Words(pc.result).w[0] = sat_add(sat_add(faces, base), interior);
    }
}
