#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Bench only: an empty closest hit for HitRecord payloads (the bare-ray floor of the trace tasks).
#include "include/hit_record.glsl"
layout(location = 0) rayPayloadInEXT HitRecord p_hit;
void main() {}
