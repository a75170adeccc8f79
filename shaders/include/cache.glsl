// The surfel direct-lighting cache as shaders see it: the instance table (one record per TLAS
// instance, indexed by gl_InstanceCustomIndexEXT), each geometry's surfel layout, and each
// instance's cache samples — all reached through buffer device addresses, so there is no
// descriptor per instance and no limit but memory.
//
// Layouts (built on the CPU by sdk/src/cache/layout.rs; keep in sync):
//   Tiles: per triangle uvec2(first sample, R). The triangle maps to an R x R square through
//     the warped barycentrics s = b1 + b2, t = b2 / (b1 + b2); one sample per cell.
//   MeshColors (Yuksel et al. 2010): samples on the barycentric lattice of resolution R —
//     vertex samples shared by every triangle at a vertex, edge samples shared by the two
//     triangles at an edge, interior samples per triangle — so interpolation is continuous
//     across edges. Per triangle 9 words:
//     [v0, v1, v2, e0, e1, e2, edge_info, face_base, R]. Edge k runs from vertex k to vertex
//     (k+1)%3; e_k is its first inner sample; edge_info packs, per edge, 9 bits of the edge's
//     resolution and 1 bit "stored in the opposite direction".
// Sample = 32 bytes: vec4(cached rgb, history length) then vec4(accumulated rgb, count). The
// history length counts injected frames (> 0); a sample only relit from the engine's lights
// (shaders/relight.rgen) holds minus its relit frames (< 0); 0: its initial colour.
#ifndef HRT_CACHE_GLSL
#define HRT_CACHE_GLSL
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#define HRT_SURFEL_MESH_COLORS 0u
#define HRT_SURFEL_TILES 1u
#define HRT_INSTANCE_HAS_CACHE 1u

struct InstanceGpu {
    uvec2 layout_addr;   // surfel layout of the geometry (0 when not ready)
    uvec2 cache_addr;    // first sample of this instance's cache (0 when none)
    vec4 initial_color;  // rgb, unused
    uint surfel_type;
    uint triangle_count;
    uint flags;
    uint sample_count;
    vec4 object_to_world[3]; // rows of the 3x4 transform
    uvec2 vertex_addr;   // the SDK's copy of the positions (stride below)
    uvec2 index_addr;    // indices (index_size bytes each; 0 = non-indexed)
    uint vertex_stride;
    uint index_size;
    uint max_resolution; // largest per-triangle resolution of the layout
    uint pad;
    uvec2 uv_addr;       // alpha-tested geometry: two f32 per vertex (0: opaque)
    uvec2 alpha_addr;    // its alpha texture, one byte per texel, rows of alpha_pitch words
    uint alpha_width;
    uint alpha_height;
    uint alpha_pitch;
    float alpha_cutoff;
    vec4 albedo;         // diffuse albedo for relighting and hit lighting (rgb, unused)
    vec4 emission;       // emitted radiance for relighting and hit lighting (rgb, unused)
    uvec2 color_addr;    // vertex colours, one RGBA8 word per vertex (0: none)
    uvec2 albedo_addr;   // albedo texture, RGBA8 sRGB, rows of albedo_width texels (0: none)
    uint albedo_width;
    uint albedo_height;
    uint pad2[2];
};

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer InstanceTable { InstanceGpu v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer LayoutWords { uint w[]; };
struct CacheSample { vec4 value; vec4 accum; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer CacheSamples { CacheSample s[]; };

bool hrt_has_cache(InstanceGpu inst) { return (inst.flags & HRT_INSTANCE_HAS_CACHE) != 0u; }

uint hrt_index(InstanceGpu inst, uint i) {
    if (inst.index_size == 0u) return i;
    LayoutWords w = LayoutWords(inst.index_addr);
    if (inst.index_size == 4u) return w.w[i];
    uint word = w.w[i >> 1];
    return (i & 1u) == 0u ? (word & 0xffffu) : (word >> 16);
}

vec3 hrt_vertex(InstanceGpu inst, uint v) {
    LayoutWords w = LayoutWords(inst.vertex_addr);
    uint o = v * (inst.vertex_stride / 4u);
    return vec3(uintBitsToFloat(w.w[o]), uintBitsToFloat(w.w[o + 1u]), uintBitsToFloat(w.w[o + 2u]));
}

vec3 hrt_to_world(InstanceGpu inst, vec3 p) {
    vec4 h = vec4(p, 1.0);
    return vec3(dot(inst.object_to_world[0], h), dot(inst.object_to_world[1], h), dot(inst.object_to_world[2], h));
}

// ---- Tiles
uint hrt_tile_sample(InstanceGpu inst, uint prim, vec2 bary) {
    LayoutWords l = LayoutWords(inst.layout_addr);
    uint base = l.w[prim * 2u], r = l.w[prim * 2u + 1u];
    float s = clamp(bary.x + bary.y, 0.0, 1.0);
    float t = s > 0.0 ? clamp(bary.y / s, 0.0, 1.0) : 0.0;
    uvec2 cell = min(uvec2(vec2(s, t) * float(r)), uvec2(r - 1u));
    return base + cell.y * r + cell.x;
}

// ---- Mesh colors
struct MeshColorTri {
    uint v[3];
    uint e[3];
    uint einfo;
    uint face;
    uint r;
};

MeshColorTri hrt_mc_tri(InstanceGpu inst, uint prim) {
    LayoutWords l = LayoutWords(inst.layout_addr);
    uint o = prim * 9u;
    MeshColorTri t;
    t.v[0] = l.w[o]; t.v[1] = l.w[o + 1u]; t.v[2] = l.w[o + 2u];
    t.e[0] = l.w[o + 3u]; t.e[1] = l.w[o + 4u]; t.e[2] = l.w[o + 5u];
    t.einfo = l.w[o + 6u]; t.face = l.w[o + 7u]; t.r = l.w[o + 8u];
    return t;
}

// A sample as (rgb, lit): lit = 1 once injection, a relight or a transfer has written it, 0
// while it still holds its initial colour.
vec4 hrt_sample(CacheSamples c, uint i) {
    vec4 v = c.s[i].value;
    return vec4(v.rgb, v.w != 0.0 ? 1.0 : 0.0);
}

// Interpolates (rgb, lit) values by weight, over lit ones only; all unlit -> the plain mix
// (their initial colour), so never-lit surfaces still show it.
vec4 hrt_lit_mix(vec4 a, vec4 b, vec4 c, vec3 w) {
    vec3 lw = w * vec3(a.w, b.w, c.w);
    float s = lw.x + lw.y + lw.z;
    if (s > 0.0) return vec4((a.rgb * lw.x + b.rgb * lw.y + c.rgb * lw.z) / s, 1.0);
    float ws = max(w.x + w.y + w.z, 1e-6);
    return vec4((a.rgb * w.x + b.rgb * w.y + c.rgb * w.z) / ws, 0.0);
}

// Value of lattice point (i, j, k), i + j + k = R, weights of vertices 0, 1, 2. Points on an
// edge whose stored resolution differs from R are interpolated along the edge's own samples.
vec4 hrt_mc_point(CacheSamples c, MeshColorTri t, ivec3 ijk) {
    int r = int(t.r);
    if (ijk.x == r) return hrt_sample(c, t.v[0]);
    if (ijk.y == r) return hrt_sample(c, t.v[1]);
    if (ijk.z == r) return hrt_sample(c, t.v[2]);
    int zero = ijk.x == 0 ? 0 : (ijk.y == 0 ? 1 : (ijk.z == 0 ? 2 : -1));
    if (zero < 0) {
        // Interior: rows of the (R-3)-triangle over i' = i - 1, j' = j - 1.
        int n = r - 3, i = ijk.x - 1, j = ijk.y - 1;
        uint idx = uint(i * (n + 1) - (i * (i - 1)) / 2 + j);
        return hrt_sample(c, t.face + idx);
    }
    // On the edge opposite vertex `zero`: edge k runs from vertex k to vertex k+1.
    int k = (zero + 1) % 3;           // edge from vertex k to k+1 excludes vertex `zero`
    int a = k, b = (k + 1) % 3;
    float x = float(ijk[b]) / float(r); // 0 at vertex a, 1 at vertex b
    uint info = (t.einfo >> (10u * uint(k))) & 0x3ffu;
    uint re = info & 0x1ffu;
    if ((info & 0x200u) != 0u) x = 1.0 - x;
    vec4 va = hrt_sample(c, t.v[(info & 0x200u) != 0u ? b : a]);
    vec4 vb = hrt_sample(c, t.v[(info & 0x200u) != 0u ? a : b]);
    float p = x * float(re);
    int m0 = int(floor(p)), m1 = min(m0 + 1, int(re));
    float f = p - float(m0);
    vec4 s0 = m0 == 0 ? va : (m0 == int(re) ? vb : hrt_sample(c, t.e[k] + uint(m0 - 1)));
    vec4 s1 = m1 == 0 ? va : (m1 == int(re) ? vb : hrt_sample(c, t.e[k] + uint(m1 - 1)));
    return hrt_lit_mix(s0, s1, s1, vec3(1.0 - f, f, 0.0));
}

// Nearest sample of a mesh-colors triangle (for injection).
uint hrt_mc_nearest(MeshColorTri t, vec3 b) {
    int r = int(t.r);
    vec3 p = b * float(r);
    ivec3 q = ivec3(floor(p + 0.5));
    // Make the rounded point sum to R: fix the coordinate with the largest rounding error.
    int excess = q.x + q.y + q.z - r;
    if (excess != 0) {
        vec3 err = vec3(q) - p;
        int m = excess > 0 ? (err.x > err.y ? (err.x > err.z ? 0 : 2) : (err.y > err.z ? 1 : 2))
                           : (err.x < err.y ? (err.x < err.z ? 0 : 2) : (err.y < err.z ? 1 : 2));
        q[m] -= excess;
    }
    q = clamp(q, ivec3(0), ivec3(r));
    if (q.x == r) return t.v[0];
    if (q.y == r) return t.v[1];
    if (q.z == r) return t.v[2];
    int zero = q.x == 0 ? 0 : (q.y == 0 ? 1 : (q.z == 0 ? 2 : -1));
    if (zero < 0) {
        int n = r - 3, i = q.x - 1, j = q.y - 1;
        return t.face + uint(i * (n + 1) - (i * (i - 1)) / 2 + j);
    }
    int k = (zero + 1) % 3, b2 = (k + 1) % 3;
    float x = float(q[b2]) / float(r);
    uint info = (t.einfo >> (10u * uint(k))) & 0x3ffu;
    uint re = info & 0x1ffu;
    if ((info & 0x200u) != 0u) x = 1.0 - x;
    int m = int(floor(x * float(re) + 0.5));
    if (m <= 0) return t.v[(info & 0x200u) != 0u ? b2 : k];
    if (m >= int(re)) return t.v[(info & 0x200u) != 0u ? k : b2];
    return t.e[k] + uint(m - 1);
}

// Sample `local` of triangle `tri` of the instance's layout, as the passes that visit every
// sample enumerate them (cache transfer, relight): its barycentrics and index; false past the
// triangle's samples. Tiles: cell `local` of the R x R square; mesh colors: lattice point
// `local`, rows of decreasing length R + 1, R, ..., 1 (shared points come out once per
// triangle, with the same index).
bool hrt_layout_sample(InstanceGpu inst, uint tri, uint local, out vec3 b, out uint sample_index) {
    b = vec3(1.0 / 3.0);
    sample_index = 0u;
    if (inst.surfel_type == HRT_SURFEL_TILES) {
        LayoutWords l = LayoutWords(inst.layout_addr);
        uint base = l.w[tri * 2u], r = l.w[tri * 2u + 1u];
        if (local >= r * r) return false;
        vec2 st = (vec2(local % r, local / r) + 0.5) / float(r);
        b = vec3(1.0 - st.x, st.x * (1.0 - st.y), st.x * st.y);
        sample_index = base + local;
        return true;
    }
    MeshColorTri t = hrt_mc_tri(inst, tri);
    uint r = t.r, n = (r + 1u) * (r + 2u) / 2u;
    if (local >= n) return false;
    uint i = 0u, row = r + 1u, rest = local;
    while (rest >= row) { rest -= row; row -= 1u; i += 1u; }
    b = vec3(float(i), float(rest), float(r - i - rest)) / float(r);
    sample_index = hrt_mc_nearest(t, b);
    return true;
}

// Barycentrics of hit attributes (b1, b2) -> (b0, b1, b2).
vec3 hrt_bary3(vec2 b) { return vec3(1.0 - b.x - b.y, b.x, b.y); }

// Texture coordinates at barycentrics w of triangle `prim` (geometry with uv_addr).
vec2 hrt_uv(InstanceGpu inst, uint prim, vec3 w) {
    LayoutWords uv = LayoutWords(inst.uv_addr);
    vec2 t = vec2(0.0);
    for (uint k = 0u; k < 3u; ++k) {
        uint v = hrt_index(inst, 3u * prim + k);
        t += w[k] * vec2(uintBitsToFloat(uv.w[2u * v]), uintBitsToFloat(uv.w[2u * v + 1u]));
    }
    return t;
}

// The diffuse albedo relighting and hit lighting use at barycentrics w of triangle `prim`:
// the instance's albedo x the geometry's vertex colour x its albedo texture (nearest texel,
// wrapping; stored sRGB-encoded), each where present (AlbedoTextureInput).
vec3 hrt_albedo(InstanceGpu inst, uint prim, vec3 w) {
    vec3 a = inst.albedo.rgb;
    if (inst.color_addr != uvec2(0u)) {
        LayoutWords colors = LayoutWords(inst.color_addr);
        vec3 c = vec3(0.0);
        for (uint k = 0u; k < 3u; ++k) c += w[k] * unpackUnorm4x8(colors.w[hrt_index(inst, 3u * prim + k)]).rgb;
        a *= c;
    }
    if (inst.albedo_addr != uvec2(0u) && inst.uv_addr != uvec2(0u)) {
        vec2 size = vec2(inst.albedo_width, inst.albedo_height);
        uvec2 texel = min(uvec2(fract(hrt_uv(inst, prim, w)) * size), uvec2(inst.albedo_width - 1u, inst.albedo_height - 1u));
        vec3 e = unpackUnorm4x8(LayoutWords(inst.albedo_addr).w[texel.y * inst.albedo_width + texel.x]).rgb;
        a *= mix(e / 12.92, pow((e + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), e));
    }
    return a;
}

// The sample a hit lands on (nearest), as an index into the instance's cache.
uint hrt_cache_sample_index(InstanceGpu inst, uint prim, vec2 bary) {
    if (inst.surfel_type == HRT_SURFEL_TILES) return hrt_tile_sample(inst, prim, bary);
    return hrt_mc_nearest(hrt_mc_tri(inst, prim), hrt_bary3(bary));
}

// The sample a hit lands on (nearest), and where that sample sits on the triangle: the tile
// cell's centre, or the mesh-colors lattice point (a point of an edge stored at another
// resolution: approximately).
uint hrt_cache_sample_point(InstanceGpu inst, uint prim, vec2 bary, out vec3 b) {
    if (inst.surfel_type == HRT_SURFEL_TILES) {
        LayoutWords l = LayoutWords(inst.layout_addr);
        uint r = l.w[prim * 2u + 1u];
        float s = clamp(bary.x + bary.y, 0.0, 1.0);
        float t = s > 0.0 ? clamp(bary.y / s, 0.0, 1.0) : 0.0;
        vec2 st = (vec2(min(uvec2(vec2(s, t) * float(r)), uvec2(r - 1u))) + 0.5) / float(r);
        b = vec3(1.0 - st.x, st.x * (1.0 - st.y), st.x * st.y);
        return hrt_tile_sample(inst, prim, bary);
    }
    MeshColorTri t = hrt_mc_tri(inst, prim);
    b = clamp(floor(hrt_bary3(bary) * float(t.r) + 0.5) / float(t.r), vec3(0.0), vec3(1.0));
    b /= max(b.x + b.y + b.z, 1e-6);
    return hrt_mc_nearest(t, hrt_bary3(bary));
}

// Cached radiance at a hit. Mesh colors interpolate linearly over the lattice triangle that
// holds the point (continuous across edges) when `bilinear`, over lit samples only, so a
// sample no injected pixel landed on (skinny triangles, grazing views) does not show through;
// tiles are piecewise constant.
vec3 hrt_cache_radiance(InstanceGpu inst, uint prim, vec2 bary, bool bilinear) {
    if (!hrt_has_cache(inst)) return inst.initial_color.rgb;
    CacheSamples c = CacheSamples(inst.cache_addr);
    if (inst.surfel_type == HRT_SURFEL_TILES || !bilinear)
        return c.s[hrt_cache_sample_index(inst, prim, bary)].value.rgb;
    MeshColorTri t = hrt_mc_tri(inst, prim);
    vec3 p = hrt_bary3(bary) * float(t.r);
    ivec3 f = ivec3(floor(p));
    vec3 w = p - vec3(f);
    // The lattice cell is an "upward" triangle when the fractional parts sum to 2, else
    // "downward"; interpolate its three corners.
    int rem = int(t.r) - (f.x + f.y + f.z);
    if (rem == 2) {
        ivec3 c0 = f + ivec3(0, 1, 1), c1 = f + ivec3(1, 0, 1), c2 = f + ivec3(1, 1, 0);
        vec3 wt = vec3(1.0) - w; // weights: distance from the opposite corner
        return hrt_lit_mix(hrt_mc_point(c, t, c0), hrt_mc_point(c, t, c1), hrt_mc_point(c, t, c2), wt).rgb;
    }
    if (rem <= 0) return hrt_mc_point(c, t, clamp(f, ivec3(0), ivec3(int(t.r)))).rgb;
    ivec3 c0 = f + ivec3(1, 0, 0), c1 = f + ivec3(0, 1, 0), c2 = f + ivec3(0, 0, 1);
    return hrt_lit_mix(hrt_mc_point(c, t, c0), hrt_mc_point(c, t, c1), hrt_mc_point(c, t, c2), w).rgb;
}
#endif
