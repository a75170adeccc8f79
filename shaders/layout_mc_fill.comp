#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// Mesh colors on the GPU, pass 2: every triangle edge goes into its lower vertex's list (at
// the list's start, from the prefix sum of the degrees, plus its slot): the higher vertex
// (the key), the triangle edge it came from, and the lower vertex.
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 indices;
    uvec2 start;       // per vertex: its list's first entry
    uvec2 slot;
    uvec2 key;         // per entry: the higher vertex
    uvec2 edge;        // per entry: 3 x triangle + edge
    uvec2 lower;       // per entry: the lower vertex
    uint edges;        // 3 x triangles
} pc;

void main() {
    uint e = gl_GlobalInvocationID.x;
    if (e >= pc.edges) return;
    Words idx = Words(pc.indices);
    uint t = e / 3u, k = e % 3u;
    uint a = idx.w[3u * t + k], b = idx.w[3u * t + (k + 1u) % 3u];
    uint lo = min(a, b);
    uint at = Words(pc.start).w[lo] + Words(pc.slot).w[e];
    Words(pc.key).w[at] = max(a, b);
    Words(pc.edge).w[at] = e;
    Words(pc.lower).w[at] = lo;
}
