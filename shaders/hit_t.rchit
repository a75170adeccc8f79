#version 460
#extension GL_EXT_ray_tracing : require
// Closest hit shared by passes whose payload is just the hit distance.
layout(location = 0) rayPayloadInEXT float p_hit_t;
void main() { p_hit_t = gl_HitTEXT; }
