#version 460
// Makes a geometry copy safe to build and shade: every triangle with an index at or past the
// vertex count (undefined behaviour in a BLAS build, and a read past the vertices in shading)
// becomes degenerate (all three indices 0: an inactive triangle), and is counted. Runs on the
// SDK's copy after vkCmdCopyBuffer, before the BLAS build and the cache's read-back.
// 16-bit indices share words with their neighbours: they are read word-wise and cleared with
// atomicAnd, so two triangles on one word never race.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Counter { uint bad_triangles; };
layout(push_constant) uniform Push {
    uvec2 indices;       // first index of the copy
    uvec2 counter;       // where bad triangles are counted
    uint triangle_count;
    uint vertex_count;
    uint index_size;     // 2 or 4
    uint pad;
} pc;

uint read_index(Words ix, uint i) {
    if (pc.index_size == 4u) return ix.w[i];
    // Atomic: a neighbouring triangle may be clearing the other half of this word.
    uint word = atomicOr(ix.w[i >> 1], 0u);
    return (i & 1u) == 0u ? (word & 0xffffu) : (word >> 16);
}

void clear_index(Words ix, uint i) {
    if (pc.index_size == 4u) {
        ix.w[i] = 0u;
    } else {
        atomicAnd(ix.w[i >> 1], (i & 1u) == 0u ? 0xffff0000u : 0x0000ffffu);
    }
}

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.triangle_count) return;
    Words ix = Words(pc.indices);
    bool bad = false;
    for (uint k = 0u; k < 3u; k++) bad = bad || read_index(ix, 3u * t + k) >= pc.vertex_count;
    if (!bad) return;
    for (uint k = 0u; k < 3u; k++) clear_index(ix, 3u * t + k);
    atomicAdd(Counter(pc.counter).bad_triangles, 1u);
}
