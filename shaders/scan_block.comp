#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// Exclusive prefix sum of u32s, one block of 512 per workgroup (sdk/src/passes/surfel_layout.rs):
// each block is scanned in place and its total written to `sums[block]`; a second level
// scans the sums and scan_add.comp adds them back. Sums saturate at 2^32 - 1 (a layout that
// large is refused by its caller, never wrapped).
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 data;
    uvec2 sums;
    uint count;
} pc;
shared uint s_partial[256];

uint sat_add(uint a, uint b) { uint c = a + b; return c < a ? 0xffffffffu : c; }

void main() {
    uint lid = gl_LocalInvocationID.x;
    uint i = gl_WorkGroupID.x * 512u + 2u * lid;
    Words d = Words(pc.data);
    uint a = i < pc.count ? d.w[i] : 0u;
    uint b = i + 1u < pc.count ? d.w[i + 1u] : 0u;
    s_partial[lid] = sat_add(a, b);
    barrier();
    for (uint off = 1u; off < 256u; off <<= 1u) {
        uint v = lid >= off ? s_partial[lid - off] : 0u;
        barrier();
        s_partial[lid] = sat_add(s_partial[lid], v);
        barrier();
    }
    uint before = lid > 0u ? s_partial[lid - 1u] : 0u;
    if (i < pc.count) d.w[i] = before;
    if (i + 1u < pc.count) d.w[i + 1u] = sat_add(before, a);
    if (lid == 255u) Words(pc.sums).w[gl_WorkGroupID.x] = s_partial[255];
}
