// The sum of one vec3 per invocation over an 8x8 workgroup, for every invocation: 8 rows of 8
// summed by 8 invocations, then each invocation adds the 8 row sums itself — two barriers,
// where a six-level tree in shared memory took seven. Every invocation must call it (it has
// barriers); the includer's workgroup is 64 invocations.
#ifndef HRT_GROUP_SUM_GLSL
#define HRT_GROUP_SUM_GLSL
shared vec3 s_group_values[64];
shared vec3 s_group_rows[8];

vec3 hrt_group_sum(vec3 v) {
    uint me = gl_LocalInvocationIndex;
    s_group_values[me] = v;
    barrier();
    if (me < 8u) {
        vec3 row = vec3(0.0);
        for (uint i = 0u; i < 8u; ++i) row += s_group_values[me * 8u + i];
        s_group_rows[me] = row;
    }
    barrier();
    vec3 total = vec3(0.0);
    for (uint i = 0u; i < 8u; ++i) total += s_group_rows[i];
    return total;
}
#endif
