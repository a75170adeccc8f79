// The lit image as a direct-lighting source for secondary hits (the integration guide's
// "Direct Lighting Input"): a hit that lands inside the task's viewport, where the depth
// buffer shows that very surface, takes the engine's lit pixel — sharper and fully dynamic —
// and any other hit takes the direct-lighting cache. The includer declares u_depth and
// u_direct (the lit image).
#ifndef HRT_SCREEN_LIGHTING_GLSL
#define HRT_SCREEN_LIGHTING_GLSL

bool hrt_screen_radiance(TraceCommon c, vec3 hit, out vec3 radiance) {
    if (c.frame.w == 0u) return false;
    vec4 h = c.world_to_clip * vec4(hit, 1.0);
    if (h.w <= 0.0) return false;
    vec3 ndc = h.xyz / h.w;
    if (any(greaterThan(abs(ndc.xy), vec2(1.0)))) return false;
    vec2 px = (ndc.xy * 0.5 + 0.5) * c.viewport.zw + c.viewport.xy;
    uvec2 pixel = uvec2(min(px, c.viewport.xy + c.viewport.zw - 1.0));
    vec3 q;
    if (!hrt_world_position(c, pixel, texelFetch(u_depth, ivec2(pixel), 0), q)) return false;
    // The same surface: within 1% of its distance to the camera (depth precision, pixel size).
    float d = distance(hit, c.view_to_world[3].xyz);
    if (distance(q, hit) > 0.01 * d + 1e-3) return false;
    radiance = texelFetch(u_direct, ivec2(pixel), 0).rgb;
    return true;
}

// A secondary hit's incoming radiance: the lit pixel where the screen shows that surface,
// the instance's cache elsewhere (the includer has included cache.glsl).
vec3 hrt_hit_radiance(TraceCommon c, vec3 hit, InstanceGpu inst, uint prim, vec2 bary, bool bilinear) {
    vec3 r;
    if (hrt_screen_radiance(c, hit, r)) return r;
    return hrt_cache_radiance(inst, prim, bary, bilinear);
}
#endif
