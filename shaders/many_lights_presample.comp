#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// TraceManyLightsTask's presampled lights, drawn every frame: `tiles` tiles of 1024 local
// lights and one of 1024 directional lights, each tile a stratified set of draws from the
// power distribution (entry j of a tile draws from [j, j + 1) / 1024 of the CDF), stored with
// the light's probability. A pixel's candidates are random entries of one tile: each entry is
// a draw from the power distribution, and a block of pixels reads one small, cached tile
// instead of searching the whole list (RTXDI's presampling).
#include "include/common.glsl"
layout(local_size_x = 256) in;
layout(push_constant) uniform Push {
    uvec2 cdf;
    uvec2 presampled;
    uint count;
    uint tiles;
    uint seed;
} pc;
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer Cdf { vec2 c[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) writeonly buffer Presampled { uvec2 s[]; };

const uint TILE = 1024u;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= (pc.tiles + 1u) * TILE) return;
    bool directional = i >= pc.tiles * TILE;
    Cdf cdf = Cdf(pc.cdf);
    float total = pc.count == 0u ? 0.0 : (directional ? cdf.c[pc.count - 1u].y : cdf.c[pc.count - 1u].x);
    if (!(total > 0.0)) {
        Presampled(pc.presampled).s[i] = uvec2(0u, floatBitsToUint(0.0));
        return;
    }
    uint j = i % TILE;
    float u = (float(j) + hrt_u01(hrt_pcg(i ^ hrt_pcg(pc.seed)))) / float(TILE) * total;
    // The first light whose inclusive prefix sum exceeds u (one with zero power never is).
    uint lo = 0u, hi = pc.count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        float v = directional ? cdf.c[mid].y : cdf.c[mid].x;
        if (v > u) hi = mid; else lo = mid + 1u;
    }
    float upper = directional ? cdf.c[lo].y : cdf.c[lo].x;
    float lower = lo == 0u ? 0.0 : (directional ? cdf.c[lo - 1u].y : cdf.c[lo - 1u].x);
    Presampled(pc.presampled).s[i] = uvec2(lo, floatBitsToUint((upper - lower) / total));
}
