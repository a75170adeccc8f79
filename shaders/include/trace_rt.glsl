// hrt_trace_record through the ray-tracing pipeline (raygen shaders): closest hit and miss are
// shaders/hit_record.rchit / .rmiss.
#ifndef HRT_TRACE_RT_GLSL
#define HRT_TRACE_RT_GLSL
#include "hit_record.glsl"
layout(location = 0) rayPayloadEXT HitRecord p_hit;

// `flags`: ray flags (gl_RayFlagsTerminateOnFirstHitEXT: the record is the first hit traversal
// found, not the closest). No Opaque flag: alpha-tested geometry runs its any-hit test
// (alpha_test.rahit); opaque geometry is built opaque and never does.
HitRecord hrt_trace_record_flags(accelerationStructureEXT tlas, uint flags, uint mask, vec3 origin, vec3 dir, float tmax) {
    p_hit.t = -1.0;
    traceRayEXT(tlas, flags, mask, 0, 0, 0, origin, 0.0, dir, tmax, 0);
    return p_hit;
}

HitRecord hrt_trace_record(accelerationStructureEXT tlas, uint mask, vec3 origin, vec3 dir, float tmax) {
    return hrt_trace_record_flags(tlas, 0u, mask, origin, dir, tmax);
}
// Whether nothing blocks the segment: traversal stops at the first hit it finds and runs no
// closest-hit shader (the miss shader alone writes the payload), so a shadow ray that needs no
// occluder distance costs only the traversal it needs.
bool hrt_trace_visible(accelerationStructureEXT tlas, uint mask, vec3 origin, vec3 dir, float tmax) {
    p_hit.t = 1.0;
    traceRayEXT(tlas, gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT, mask, 0, 0, 0, origin, 0.0, dir,
                tmax, 0);
    return p_hit.t < 0.0;
}
#define HRT_LAUNCH_ID gl_LaunchIDEXT.xy
#endif
