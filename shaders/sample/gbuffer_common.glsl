// Bindings of the sample's G-buffer pass (samples/src/raster.rs mirrors them).
struct Instance {
    mat4 model;
    mat4 prev_model;
    vec4 material;   // albedo rgb, roughness
    vec4 extra;      // metalness, alpha cutoff (0: opaque), normal-map scale (0: no normal map), unused
    vec4 emissive;   // emitted radiance rgb (factor x strength), unused
};
layout(set = 0, binding = 0, std140) uniform Camera {
    mat4 view_proj;
    mat4 prev_view_proj;
    vec4 eye;        // camera position
    vec4 viewport;   // width, height in pixels
} u_camera;
layout(set = 0, binding = 1, std430) readonly buffer Instances { Instance items[]; } u_instances;
layout(push_constant) uniform Push { uint instance; } u_push;
