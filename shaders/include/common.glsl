// Shared helpers for every hybrid-rt pass: hashing, G-buffer decoding, ray offsets (the rays'
// sample sequences are in random.glsl).
// The constants mirrored here live in sdk/src/passes/constants.rs (a test checks the layout).
#ifndef HRT_COMMON_GLSL
#define HRT_COMMON_GLSL

#define HRT_PI 3.14159265358979323846

// DepthType (sdk::api::tasks::DepthType)
#define HRT_DEPTH_CLIP_SPACE 0u
#define HRT_DEPTH_WORLD_POSITION 1u

// NormalType (sdk::api::tasks::NormalType), the six encodings of the integration guide.
#define HRT_NORMAL_RGB_VECTOR 0u
#define HRT_NORMAL_RGB_NORMALIZED_VECTOR 1u
#define HRT_NORMAL_RG_OCTAHEDRON 2u
#define HRT_NORMAL_BA_OCTAHEDRON 3u
#define HRT_NORMAL_RG_NORMALIZED_OCTAHEDRON 4u
#define HRT_NORMAL_BA_NORMALIZED_OCTAHEDRON 5u

// RayOffset type
#define HRT_RAY_OFFSET_DISABLED 0u
#define HRT_RAY_OFFSET_WORLD_POSITION 1u
#define HRT_RAY_OFFSET_CAMERA_DISTANCE 2u

// Camera and G-buffer description shared by every trace task (std140, 384 bytes).
struct TraceCommon {
    mat4 clip_to_world;   // inverse(view_to_clip * world_to_view)
    mat4 view_to_world;
    vec4 viewport;        // x, y, width, height in pixels
    vec4 depth_range;     // viewport min depth, max depth, background depth texel, has input mask (0/1)
    uvec4 modes;          // depth type, normal type, normals need normal_to_world (0/1), ray offset type
    vec4 offset_world;    // threshold, float scale, int scale; w: RandomNumbers (random.glsl)
    vec4 offset_camera;   // constant, linear, quadratic; w: the roughness remap's multiplier (see below)
    uvec4 frame;          // random seed, TLAS instance mask, half-resolution checkerboard (0/1), has direct-lighting image (0/1)
    mat4 world_to_clip;   // view_to_clip * world_to_view
    mat4 normal_to_world; // 3x3 (in a mat4) taking decoded normals to world space when modes.z = 1
    vec4 roughness_mask;  // channel weights of the roughness image
    vec4 roughness;       // multiplier (global roughness), has image (0/1), min, max
};

// PCG hash (Jarzynski & Olano 2020): good quality, one multiply-add chain per call.
uint hrt_pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

float hrt_u01(uint bits) { return float(bits >> 8) * (1.0 / 16777216.0); }

vec3 hrt_cosine_hemisphere(vec2 u) {
    float r = sqrt(u.x);
    float phi = 2.0 * HRT_PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

// Orthonormal basis around n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").
mat3 hrt_basis(vec3 n) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    vec3 t = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    vec3 bt = vec3(b, s + n.y * n.y * a, -n.y);
    return mat3(t, bt, n);
}

// The octahedral map of a unit vector to [-1, 1]^2 (hrt_oct_decode's inverse).
vec2 hrt_oct_encode(vec3 n) {
    vec2 e = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0) e = (1.0 - abs(e.yx)) * vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
    return e;
}

vec3 hrt_oct_decode(vec2 e) {
    vec3 v = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (v.z < 0.0) {
        v.xy = (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
    }
    return normalize(v);
}

vec3 hrt_decode_normal(vec4 texel, uint normal_type) {
    switch (normal_type) {
    case HRT_NORMAL_RGB_VECTOR: return normalize(texel.xyz);
    case HRT_NORMAL_RGB_NORMALIZED_VECTOR: return normalize(texel.xyz * 2.0 - 1.0);
    case HRT_NORMAL_RG_OCTAHEDRON: return hrt_oct_decode(texel.xy);
    case HRT_NORMAL_BA_OCTAHEDRON: return hrt_oct_decode(texel.zw);
    case HRT_NORMAL_RG_NORMALIZED_OCTAHEDRON: return hrt_oct_decode(texel.xy * 2.0 - 1.0);
    default: return hrt_oct_decode(texel.zw * 2.0 - 1.0);
    }
}

// Checkerboard (half-resolution) mode, frame.z: 0 off; 1 this ticket traces the pixels where
// x + y + seed is even, the next ticket (seed + 1) the others; 2 the opposite half (inverted).
// Skipped pixels are left untouched.
bool hrt_traced_this_frame(TraceCommon c, uvec2 pixel) {
    uint phase = c.frame.z == 2u ? 1u : 0u;
    return c.frame.z == 0u || ((pixel.x + pixel.y + c.frame.x + phase) & 1u) == 0u;
}

bool hrt_checkerboard_skip(TraceCommon c, uvec2 pixel) {
    return !hrt_traced_this_frame(c, pixel);
}

// Pixel centre -> clip space for this viewport (Vulkan: y down, z in [0, 1]).
vec3 hrt_pixel_to_ndc(TraceCommon c, uvec2 pixel, float depth) {
    vec2 uv = (vec2(pixel) + 0.5 - c.viewport.xy) / c.viewport.zw;
    float z = (depth - c.depth_range.x) / max(c.depth_range.y - c.depth_range.x, 1e-20);
    return vec3(uv * 2.0 - 1.0, z);
}

// World-space position of the G-buffer sample. Returns false for background pixels (clip
// depth at the far plane of a standard or reversed projection, or a non-finite position).
bool hrt_world_position(TraceCommon c, uvec2 pixel, vec4 depth_texel, out vec3 p) {
    if (c.modes.x == HRT_DEPTH_WORLD_POSITION) {
        p = depth_texel.xyz;
        return !(any(isnan(p)) || any(isinf(p)));
    }
    // Nothing was rasterized here: the depth buffer still holds its clear value (far plane).
    if (depth_texel.x == c.depth_range.z) return false;
    vec4 h = c.clip_to_world * vec4(hrt_pixel_to_ndc(c, pixel, depth_texel.x), 1.0);
    if (abs(h.w) < 1e-30) return false;
    p = h.xyz / h.w;
    return !(any(isnan(p)) || any(isinf(p)));
}

vec3 hrt_world_normal(TraceCommon c, vec4 normal_texel) {
    vec3 n = hrt_decode_normal(normal_texel, c.modes.y);
    if (c.modes.z != 0u) n = normalize(mat3(c.normal_to_world) * n);
    return n;
}

// Surface roughness (RoughnessInput), Kickstart RT's rule: r = multiplier (global roughness) x
// dot(texel, mask), or the global roughness alone without an image; then
// clamp(r * remap multiplier + min, min, max).
float hrt_surface_roughness(TraceCommon c, sampler2D roughness, ivec2 pixel) {
    float r = c.roughness.x;
    if (c.roughness.y != 0.0) r *= dot(texelFetch(roughness, pixel, 0), c.roughness_mask);
    return clamp(r * c.offset_camera.w + c.roughness.z, c.roughness.z, c.roughness.w);
}

// The input mask (TraceCommon::input_mask): pixels whose R is >= 0.5 are excluded from every
// trace and denoise task, which treat them as background.
bool hrt_masked(TraceCommon c, sampler2D mask, uvec2 pixel) {
    return c.depth_range.w != 0.0 && texelFetch(mask, ivec2(pixel), 0).r >= 0.5;
}

// What every G-buffer trace starts with: the pixel of this launch, and the surface under it.
#define HRT_PIXEL_SKIP 0        // outside the viewport, or the other half of the checkerboard
#define HRT_PIXEL_BACKGROUND 1  // nothing was rasterized here (or the input mask excludes it): write the "nothing" value
#define HRT_PIXEL_SURFACE 2     // p and n hold the surface's world position and normal
int hrt_gbuffer_pixel(TraceCommon c, uvec2 launch, sampler2D depth, sampler2D normals, sampler2D mask,
                      out uvec2 pixel, out vec3 p, out vec3 n) {
    pixel = launch + uvec2(c.viewport.xy);
    p = vec3(0.0);
    n = vec3(0.0, 0.0, 1.0);
    if (any(greaterThanEqual(launch, uvec2(c.viewport.zw))) || hrt_checkerboard_skip(c, pixel)) return HRT_PIXEL_SKIP;
    if (hrt_masked(c, mask, pixel)) return HRT_PIXEL_BACKGROUND;
    if (!hrt_world_position(c, pixel, texelFetch(depth, ivec2(pixel), 0), p)) return HRT_PIXEL_BACKGROUND;
    n = hrt_world_normal(c, texelFetch(normals, ivec2(pixel), 0));
    return HRT_PIXEL_SURFACE;
}

// Moves a ray origin off the surface so the secondary ray does not hit the surface it starts
// from. World position: Wächter & Binder, "A Fast and Robust Method for Avoiding
// Self-Intersection" (Ray Tracing Gems ch. 6) — exact in the float's own precision.
// Camera distance: offset grows with the distance to the camera, as depth precision does.
vec3 hrt_offset_world(vec3 p, vec3 n, float threshold, float float_scale, float int_scale) {
    ivec3 of_i = ivec3(int_scale * n);
    vec3 p_i = vec3(
        intBitsToFloat(floatBitsToInt(p.x) + ((p.x < 0.0) ? -of_i.x : of_i.x)),
        intBitsToFloat(floatBitsToInt(p.y) + ((p.y < 0.0) ? -of_i.y : of_i.y)),
        intBitsToFloat(floatBitsToInt(p.z) + ((p.z < 0.0) ? -of_i.z : of_i.z)));
    return vec3(abs(p.x) < threshold ? p.x + float_scale * n.x : p_i.x,
                abs(p.y) < threshold ? p.y + float_scale * n.y : p_i.y,
                abs(p.z) < threshold ? p.z + float_scale * n.z : p_i.z);
}

vec3 hrt_offset_ray(TraceCommon c, vec3 p, vec3 n) {
    uint kind = c.modes.w;
    if (kind == HRT_RAY_OFFSET_WORLD_POSITION) {
        return hrt_offset_world(p, n, c.offset_world.x, c.offset_world.y, c.offset_world.z);
    }
    if (kind == HRT_RAY_OFFSET_CAMERA_DISTANCE) {
        float d = distance(p, c.view_to_world[3].xyz);
        float off = c.offset_camera.x + c.offset_camera.y * d + c.offset_camera.z * d * d;
        return p + n * max(off, 0.0);
    }
    return p;
}

#endif
