// The alpha test of alpha-tested geometry (AlphaTestInput, sdk/src/types/scene.rs), shared by
// the any-hit shader (alpha_test.rahit) and the inline ray-query loop (trace_rq.glsl): the
// hit's texture coordinates from the SDK's copy, the alpha texel there (nearest, repeat).
#ifndef HRT_ALPHA_TEST_GLSL
#define HRT_ALPHA_TEST_GLSL
#include "cache.glsl"
#include "trace_push.glsl"

// Whether the ray stops at this hit: opaque geometry always (its BLAS is built opaque, so no
// test runs for it at all), alpha-tested geometry where alpha >= cutoff.
bool hrt_alpha_opaque(uint instance, uint prim, vec2 bary) {
    InstanceGpu inst = InstanceTable(u_trace_push.instance_table).v[instance];
    if (inst.alpha_addr == uvec2(0u)) return true;
    vec2 t = hrt_uv(inst, prim, hrt_bary3(bary));
    vec2 size = vec2(inst.alpha_width, inst.alpha_height);
    uvec2 texel = min(uvec2(fract(t) * size), uvec2(inst.alpha_width - 1u, inst.alpha_height - 1u));
    uint word = LayoutWords(inst.alpha_addr).w[texel.y * inst.alpha_pitch + (texel.x >> 2)];
    float alpha = float((word >> (8u * (texel.x & 3u))) & 0xffu) * (1.0 / 255.0);
    return alpha >= inst.alpha_cutoff;
}
#endif
