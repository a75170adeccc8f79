#version 460
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// The tiles surfel layout on the GPU, pass 3 of 3: each triangle's first sample (the prefix
// sum of R x R) into its layout words, and the layout's sample count (the last triangle's
// first sample + its R x R, saturating) into the result the host reads.
layout(local_size_x = 256) in;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
layout(push_constant) uniform Push {
    uvec2 words;
    uvec2 counts;
    uvec2 result;
    uint triangles;
} pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.triangles) return;
    Words w = Words(pc.words);
    uint first = Words(pc.counts).w[t];
    w.w[2u * t] = first;
    if (t + 1u == pc.triangles) {
        uint r = w.w[2u * t + 1u];
        uint end = first + r * r;
        Words(pc.result).w[0] = end < first ? 0xffffffffu : end;
    }
}
