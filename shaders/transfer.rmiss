#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "include/transfer_hit.glsl"
layout(location = 0) rayPayloadInEXT TransferHit p_hit;
void main() { p_hit.t = -1.0; }
