// Rays towards a sized light, shared by the single- and multi-light shadow tasks.
#ifndef HRT_LIGHT_SAMPLING_GLSL
#define HRT_LIGHT_SAMPLING_GLSL
#define HRT_LIGHT_DIRECTIONAL 0u
#define HRT_LIGHT_POINT 1u
#define HRT_LIGHT_SPOT 2u
// Lights one task takes at most (MAX_SHADOW_LIGHTS).
#define HRT_MAX_LIGHTS 32

// A light as shaders see it (std140, 64 bytes).
struct LightGpu {
    vec4 position;   // xyz, light type (as float)
    vec4 direction;  // direction the light travels, tan of half the angular extent
    vec4 shape;      // radius, range (0: unlimited), cos inner cone, cos outer cone
    vec4 power;      // intensity, colour (RelightCacheTask)
};

// How much of a point or spot light reaches p, before shadowing: 0 beyond the range or outside
// the outer cone (no rays are traced there), the spot's smoothstep from the outer to the inner
// cone, and the windowed range falloff (1 - (d/range)^4)^2 (Karis 2013) that reaches 0 at the
// range. 1 for a directional light.
float hrt_light_reach(LightGpu l, vec3 p) {
    uint kind = uint(l.position.w);
    if (kind == HRT_LIGHT_DIRECTIONAL) return 1.0;
    vec3 v = p - l.position.xyz;
    float d = length(v);
    float reach = 1.0;
    if (l.shape.y > 0.0) {
        float r = d / l.shape.y;
        reach = clamp(1.0 - r * r * r * r, 0.0, 1.0);
        reach *= reach;
    }
    if (kind == HRT_LIGHT_SPOT) {
        float cos_angle = dot(v / max(d, 1e-20), normalize(l.direction.xyz));
        reach *= cos_angle <= l.shape.w ? 0.0 : smoothstep(l.shape.w, max(l.shape.z, l.shape.w + 1e-6), cos_angle);
    }
    return reach;
}

// The weight of a light in the multi-light mean: its unshadowed irradiance at (p, n) up to a
// constant — intensity x reach x cos(theta), and 1/d^2 for point and spot lights.
float hrt_light_weight(LightGpu l, vec3 p, vec3 n, float reach) {
    if (reach <= 0.0) return 0.0;
    if (uint(l.position.w) == HRT_LIGHT_DIRECTIONAL) return l.power.x * max(dot(n, -normalize(l.direction.xyz)), 0.0);
    vec3 v = l.position.xyz - p;
    float d2 = max(dot(v, v), 1e-8);
    return l.power.x * reach * max(dot(n, v * inversesqrt(d2)), 0.0) / d2;
}

// A uniform point in the unit disk (concentric map, Shirley & Chiu 1997).
vec2 hrt_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    float r, phi;
    if (abs(o.x) > abs(o.y)) { r = o.x; phi = (HRT_PI / 4.0) * (o.y / o.x); }
    else { r = o.y; phi = (HRT_PI / 2.0) - (HRT_PI / 4.0) * (o.x / o.y); }
    return r * vec2(cos(phi), sin(phi));
}

// A ray from `origin` to a point of the light's extent picked by `u`: a cone of directions for
// a directional light of angular size, a disk facing the origin for a point or spot light.
void hrt_light_ray(LightGpu l, vec3 origin, vec2 u, out vec3 dir, out float tmax) {
    vec2 d = hrt_disk(u);
    if (uint(l.position.w) == HRT_LIGHT_DIRECTIONAL) {
        vec3 to_light = -normalize(l.direction.xyz);
        mat3 b = hrt_basis(to_light);
        dir = normalize(to_light + (b[0] * d.x + b[1] * d.y) * l.direction.w);
        tmax = 1e30;
    } else {
        vec3 to_centre = l.position.xyz - origin;
        mat3 b = hrt_basis(normalize(to_centre));
        vec3 target = l.position.xyz + (b[0] * d.x + b[1] * d.y) * l.shape.x;
        vec3 v = target - origin;
        float len = length(v);
        dir = v / max(len, 1e-20);
        tmax = len * 0.9999;
    }
}

// Width (world units) of the penumbra that an occluder `t` away along the shadow ray casts
// on the surface at p: the light's angular diameter seen from p times t (similar triangles
// through the occluder's edge). The shadow denoisers blur by it.
float hrt_penumbra_width(LightGpu l, vec3 p, float t) {
    if (uint(l.position.w) == HRT_LIGHT_DIRECTIONAL) return 2.0 * l.direction.w * t;
    float d = distance(l.position.xyz, p);
    return 2.0 * l.shape.x * t / max(d - t, 1e-3 * d);
}
#endif
