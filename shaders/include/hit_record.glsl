// Payload of passes that only need to know what a ray hit.
#ifndef HRT_HIT_RECORD_GLSL
#define HRT_HIT_RECORD_GLSL
struct HitRecord {
    vec2 bary;      // hit attributes (weights of vertices 1 and 2)
    float t;        // hit distance, negative on a miss
    uint instance;  // gl_InstanceCustomIndexEXT
    uint prim;      // gl_PrimitiveID
};
#endif
