// Payload of the cache transfer: like HitRecord, plus the one instance the ray may hit.
#ifndef HRT_TRANSFER_HIT_GLSL
#define HRT_TRANSFER_HIT_GLSL
struct TransferHit {
    vec2 bary;
    float t;
    uint instance;
    uint prim;
    uint want;  // the source instance's custom index
};
#endif
