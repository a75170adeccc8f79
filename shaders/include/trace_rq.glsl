// hrt_trace_record with an inline ray query (compute shaders), for devices with ray queries.
#ifndef HRT_TRACE_RQ_GLSL
#define HRT_TRACE_RQ_GLSL
#include "hit_record.glsl"

// `flags` adds ray flags to Opaque (see trace_rt.glsl).
HitRecord hrt_trace_record_flags(accelerationStructureEXT tlas, uint flags, uint mask, vec3 origin, vec3 dir, float tmax) {
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, gl_RayFlagsOpaqueEXT | flags, mask, origin, 0.0, dir, tmax);
    while (rayQueryProceedEXT(q)) {}
    HitRecord h;
    h.t = -1.0;
    h.bary = vec2(0.0);
    h.instance = 0u;
    h.prim = 0u;
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        h.t = rayQueryGetIntersectionTEXT(q, true);
        h.bary = rayQueryGetIntersectionBarycentricsEXT(q, true);
        h.instance = uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, true));
        h.prim = uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true));
    }
    return h;
}

HitRecord hrt_trace_record(accelerationStructureEXT tlas, uint mask, vec3 origin, vec3 dir, float tmax) {
    return hrt_trace_record_flags(tlas, 0u, mask, origin, dir, tmax);
}
#define HRT_LAUNCH_ID gl_GlobalInvocationID.xy
#endif
