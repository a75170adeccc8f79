#version 460
#extension GL_EXT_ray_tracing : require
// Miss shader for hit-distance payloads: negative means "nothing hit".
layout(location = 0) rayPayloadInEXT float p_hit_t;
void main() { p_hit_t = -1.0; }
