#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "include/transfer_hit.glsl"
layout(location = 0) rayPayloadInEXT TransferHit p_hit;
hitAttributeEXT vec2 a_bary;
void main() {
    p_hit.bary = a_bary;
    p_hit.t = gl_HitTEXT;
    p_hit.instance = gl_InstanceCustomIndexEXT;
    p_hit.prim = gl_PrimitiveID;
}
