// Every trace program's push constants (sdk/src/passes/program.rs `TracePush`): the instance
// table, the usage flags the cache budget reads (InitSettings::cache_budget_bytes), and the
// blue-noise tile.
#ifndef HRT_TRACE_PUSH_GLSL
#define HRT_TRACE_PUSH_GLSL
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(push_constant) uniform HrtTracePush {
    uvec2 instance_table;
    uvec2 usage;          // one uint per instance slot, 0 when the context has no cache budget
    uvec2 blue_noise;     // RandomNumbers::BlueNoise's 64x64 ranks (random.glsl), 0 when unused
} u_trace_push;

layout(buffer_reference, std430, buffer_reference_align = 4) buffer HrtUsage { uint used[]; };

// Instance `instance` (its slot, gl_InstanceCustomIndexEXT) was seen by a camera's injection,
// a GI or reflection ray, or a debug view this build: the budget keeps its cache, or gives it
// one again after an eviction. The flag is read before it is written, so a million hits on
// one instance cost one store.
void hrt_mark_used(uint instance) {
    if (u_trace_push.usage == uvec2(0u)) return;
    HrtUsage u = HrtUsage(u_trace_push.usage);
    if (u.used[instance] == 0u) u.used[instance] = 1u;
}
#endif
