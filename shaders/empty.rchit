#version 460
#extension GL_EXT_ray_tracing : require
// Bench only: an empty closest-hit shader, for the bare-ray floor the AO pass is compared to.
layout(location = 0) rayPayloadInEXT float p_hit_t;
void main() {}
