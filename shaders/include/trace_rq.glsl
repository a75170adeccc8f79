// hrt_trace_record with an inline ray query (compute shaders), for devices with ray queries.
#ifndef HRT_TRACE_RQ_GLSL
#define HRT_TRACE_RQ_GLSL
#include "hit_record.glsl"
#include "alpha_test.glsl"

// `flags`: ray flags (see trace_rt.glsl). Candidates are the hits of alpha-tested geometry
// (opaque geometry commits without one): confirmed where the alpha test passes.
HitRecord hrt_trace_record_flags(accelerationStructureEXT tlas, uint flags, uint mask, vec3 origin, vec3 dir, float tmax) {
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, flags, mask, origin, 0.0, dir, tmax);
    while (rayQueryProceedEXT(q)) {
        if (rayQueryGetIntersectionTypeEXT(q, false) == gl_RayQueryCandidateIntersectionTriangleEXT
            && hrt_alpha_opaque(uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, false)),
                                uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, false)),
                                rayQueryGetIntersectionBarycentricsEXT(q, false))) {
            rayQueryConfirmIntersectionEXT(q);
        }
    }
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
// Whether nothing blocks the segment (see trace_rt.glsl): the first hit found ends it (a ray
// query runs no shaders, so the record's reads are all the difference).
bool hrt_trace_visible(accelerationStructureEXT tlas, uint mask, vec3 origin, vec3 dir, float tmax) {
    return hrt_trace_record_flags(tlas, gl_RayFlagsTerminateOnFirstHitEXT, mask, origin, dir, tmax).t < 0.0;
}
#define HRT_LAUNCH_ID gl_GlobalInvocationID.xy
#endif
