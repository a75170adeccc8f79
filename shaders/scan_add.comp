#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// Second half of the two-level prefix sum (scan_block.comp): every element of block k gets
// the scanned total of the blocks before it.
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 data;
    uvec2 sums;
    uint count;
} pc;

uint sat_add(uint a, uint b) { uint c = a + b; return c < a ? 0xffffffffu : c; }

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    Words d = Words(pc.data);
    d.w[i] = sat_add(d.w[i], Words(pc.sums).w[i / 512u]);
}
