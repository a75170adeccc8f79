#version 460
#extension GL_EXT_ray_query : require
#extension GL_GOOGLE_include_directive : require
#include "include/ao.glsl"
#include "include/trace_rq.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

float hrt_trace_hit_t(vec3 origin, vec3 dir, float tmax) {
    return hrt_trace_record(u_tlas, u_c.common_.frame.y & 0xffu, origin, dir, tmax).t;
}

void main() { hrt_ao_main(gl_GlobalInvocationID.xy); }
