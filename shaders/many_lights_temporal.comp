#version 460
#extension GL_EXT_ray_query : require
#extension GL_GOOGLE_include_directive : require
#include "include/common.glsl"
#include "include/trace_rq.glsl"
#include "include/many_lights.glsl"
layout(local_size_x = 8, local_size_y = 8) in;
void main() { hrt_ml_temporal_main(); }
