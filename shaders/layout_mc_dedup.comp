#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// Mesh colors on the GPU, pass 3: the edges of one lower vertex that share a higher vertex are
// one mesh edge. Each entry finds the first entry of its list with its key (its edge's
// representative) and the edge's resolution (the finest of the triangles sharing it); the
// representative owns R - 1 edge samples. A vertex with more than MAX_SHARED entries (a huge
// fan) keeps its edges unshared rather than scan its list once per entry.
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 start;
    uvec2 key;
    uvec2 edge;
    uvec2 lower;
    uvec2 res;         // per triangle
    uvec2 rep;         // per entry: its representative entry
    uvec2 edge_res;    // per entry: its edge's resolution
    uvec2 count;       // per entry: edge samples it owns (R - 1 for representatives, else 0)
    uint edges;
    uint vertices;
} pc;

const uint MAX_SHARED = 4096u;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.edges) return;
    Words start = Words(pc.start), key = Words(pc.key), edge = Words(pc.edge), res = Words(pc.res);
    uint lo = Words(pc.lower).w[i];
    uint first = start.w[lo];
    uint end = lo + 1u < pc.vertices ? start.w[lo + 1u] : pc.edges;
    uint k = key.w[i];
    uint rep = i, r = res.w[edge.w[i] / 3u];
    if (end - first <= MAX_SHARED) {
        for (uint j = first; j < end; ++j) {
            if (key.w[j] != k) continue;
            rep = min(rep, j);
            r = max(r, res.w[edge.w[j] / 3u]);
        }
    }
    Words(pc.rep).w[i] = rep;
    Words(pc.edge_res).w[i] = r;
    Words(pc.count).w[i] = rep == i ? r - 1u : 0u;
}
