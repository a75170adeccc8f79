#version 460
// Packs one part of a geometry into the SDK's compact copy: each vertex's position (read at
// the engine's stride from the staging copy of its buffer, transformed into geometry space)
// becomes 12 bytes, each index a 32-bit index into the geometry's vertices. A triangle with an
// index outside the part's vertices (undefined behaviour in a BLAS build, a read past the
// vertices in shading) becomes degenerate — all three corners on the part's first vertex, a
// zero-area triangle no ray hits — and is counted. One invocation per vertex and per triangle.
// Modes 1-3 pack a part's texture coordinates instead: two f32 per vertex, from R32G32_SFLOAT,
// R16G16_SFLOAT or R16G16_UNORM at the engine's stride; modes 4-7 its colours: one RGBA8
// unorm word per vertex (linear, alpha dropped), from R8G8B8A8_UNORM, R16G16B16A16_SFLOAT,
// R32G32B32_SFLOAT or R32G32B32A32_SFLOAT.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Words { uint w[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer Packed { uint w[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Counter { uint bad_triangles; };
layout(push_constant) uniform Push {
    vec4 rows[3];        // part to geometry space, row-major 3x4 (first: 16-byte aligned)
    uvec2 src_vertices;  // staging: the part's first copied vertex
    uvec2 dst_vertices;  // the copy: this part's first vertex (12 bytes each)
    uvec2 src_indices;   // staging: the part's first index (unused when index_size is 0)
    uvec2 dst_indices;   // the copy: this part's first triangle (3 x 4 bytes each)
    uvec2 counter;       // where bad triangles are counted
    uint stride_words;   // the engine's vertex stride, in 4-byte words
    uint vertex_count;   // vertices copied
    uint triangle_count;
    uint index_size;     // 0 (non-indexed), 2 or 4
    uint first_vertex;   // the first copied vertex's index in the engine's buffer
    uint vertex_base;    // the part's first vertex in the geometry
    uint first_item;     // this dispatch's first invocation (large parts take several)
    uint mode;           // 0 positions and indices; texture coordinates: 1 RG32F, 2 RG16F, 3 RG16 unorm;
                         // colours: 4 RGBA8 unorm, 5 RGBA16F, 6 RGB32F, 7 RGBA32F
} pc;

uint engine_index(uint j) {
    if (pc.index_size == 0u) return j;
    Words ix = Words(pc.src_indices);
    if (pc.index_size == 4u) return ix.w[j];
    uint word = ix.w[j >> 1];
    return (j & 1u) == 0u ? (word & 0xffffu) : (word >> 16);
}

void main() {
    uint i = gl_GlobalInvocationID.x + pc.first_item;
    if (pc.mode >= 4u) {
        if (i >= pc.vertex_count) return;
        Words src = Words(pc.src_vertices);
        uint o = i * pc.stride_words;
        vec3 c;
        if (pc.mode == 4u) c = unpackUnorm4x8(src.w[o]).rgb;
        else if (pc.mode == 5u) c = vec3(unpackHalf2x16(src.w[o]), unpackHalf2x16(src.w[o + 1u]).x);
        else c = vec3(uintBitsToFloat(src.w[o]), uintBitsToFloat(src.w[o + 1u]), uintBitsToFloat(src.w[o + 2u]));
        Packed(pc.dst_vertices).w[i] = packUnorm4x8(vec4(clamp(c, 0.0, 1.0), 1.0));
        return;
    }
    if (pc.mode != 0u) {
        if (i >= pc.vertex_count) return;
        Words src = Words(pc.src_vertices);
        uint o = i * pc.stride_words;
        vec2 uv;
        if (pc.mode == 1u) uv = vec2(uintBitsToFloat(src.w[o]), uintBitsToFloat(src.w[o + 1u]));
        else if (pc.mode == 2u) uv = unpackHalf2x16(src.w[o]);
        else uv = unpackUnorm2x16(src.w[o]);
        Packed dst = Packed(pc.dst_vertices);
        dst.w[2u * i] = floatBitsToUint(uv.x);
        dst.w[2u * i + 1u] = floatBitsToUint(uv.y);
        return;
    }
    if (i < pc.vertex_count) {
        Words src = Words(pc.src_vertices);
        uint o = i * pc.stride_words;
        vec4 p = vec4(uintBitsToFloat(src.w[o]), uintBitsToFloat(src.w[o + 1u]), uintBitsToFloat(src.w[o + 2u]), 1.0);
        Packed dst = Packed(pc.dst_vertices);
        dst.w[3u * i] = floatBitsToUint(dot(pc.rows[0], p));
        dst.w[3u * i + 1u] = floatBitsToUint(dot(pc.rows[1], p));
        dst.w[3u * i + 2u] = floatBitsToUint(dot(pc.rows[2], p));
    }
    if (i < pc.triangle_count) {
        uint local[3];
        bool bad = false;
        for (uint k = 0u; k < 3u; k++) {
            uint e = engine_index(3u * i + k);
            local[k] = e - pc.first_vertex;  // wraps for e < first_vertex: caught below
            bad = bad || e < pc.first_vertex || local[k] >= pc.vertex_count;
        }
        Packed dst = Packed(pc.dst_indices);
        for (uint k = 0u; k < 3u; k++) dst.w[3u * i + k] = pc.vertex_base + (bad ? 0u : local[k]);
        if (bad) atomicAdd(Counter(pc.counter).bad_triangles, 1u);
    }
}
