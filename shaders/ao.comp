#version 460
#extension GL_EXT_ray_query : require
#extension GL_GOOGLE_include_directive : require
#include "include/ao.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

float hrt_trace_hit_t(vec3 origin, vec3 dir, float tmax) {
    rayQueryEXT q;
    rayQueryInitializeEXT(q, u_tlas, gl_RayFlagsOpaqueEXT, u_c.common_.frame.y & 0xffu,
                          origin, 0.0, dir, tmax);
    while (rayQueryProceedEXT(q)) {}
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionTriangleEXT)
        return rayQueryGetIntersectionTEXT(q, true);
    return -1.0;
}

void main() { hrt_ao_main(gl_GlobalInvocationID.xy); }
