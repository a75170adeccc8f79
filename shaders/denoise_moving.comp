#version 460
#extension GL_GOOGLE_include_directive : require
// AO's denoiser, before its temporal pass while the scene changes: where objects moved.
//
// A moving object changes the occlusion of the static surfaces around it (its contact shadow
// slides over the floor), and nothing in the floor's own history or neighbourhood says so: its
// pixels reproject onto themselves, and a contact band changing by 0.2-0.5 stands out of 25
// 1-ray samples by about one deviation, which no anti-lag test can tell from noise within a
// frame. So the denoiser looks for the objects instead. This pass samples one pixel of each
// 4x4 block (another one each frame): a surface moved where its motion vector is more than a pixel off the camera's
// motion (TAA's jitter moves a static surface's reprojection by less), or, without motion
// vectors under a still camera, where the last frame showed another surface at that pixel.
// A workgroup (32x32 pixels) that sees a moving surface stamps this frame's number on every
// 32x32 tile within the surface's reach on screen (the task's reach at its distance); the
// temporal pass (its pipeline for moving objects) starts the stamped tiles' pixels over from
// this frame's sample and the blur passes filter them narrowly, so a moving contact shadow is
// this frame's, noisy but in place. (One frame of history already leaves a quarter of a 2.6
// px/frame slide's change behind; the full blur a fifth.) The search is a pass of its own
// because inside the temporal pass its code alone, run or not, slowed it by 15% (its
// registers).
// u_pass: this frame's stamp (never 0), 0, HRT_MOVING_* flags, reach (world units, float bits).
#include "include/denoise.glsl"

// A motion vector this many pixels off the camera's motion marks a moving surface.
const float MOVING_MIN_PIXELS = 1.0;
// The farthest reach stamped, in pixels.
const float MOVING_MAX_REACH = 128.0;
// Pixels per side of the block one invocation samples, and of a workgroup's.
const int STRIDE = 4;
const int BLOCK = 8 * STRIDE;
shared uint s_reach;

// Whether the surface at `pixel` moved since the last frame (see above).
bool surface_moved(ivec2 pixel, vec3 p, vec3 n, float dist) {
    if (u_d.flags.x != HRT_MOTION_NONE) {
        vec2 camera;
        bool in_front = hrt_previous_camera_position(p, camera);
        return in_front && distance(camera + u_d.jitter_delta.xy, hrt_previous_position(pixel, p)) > MOVING_MIN_PIXELS;
    }
    // A still camera whose viewport changed (dynamic resolution) sees the same point at
    // another pixel: the test below does not apply.
    if ((u_pass.z & HRT_MOVING_STILL_CAMERA) == 0u || hrt_viewport_changed()) return false;
    // A still camera sees the same point at the same pixel: another surface there moved.
    vec3 q_p, q_n;
    if (!hrt_surface_at(imageLoad(u_gbuf_prev, pixel).xy, u_d.prev_clip_to_world, u_d.prev_eye.xyz, pixel, q_p, q_n)) return true;
    return abs(dot(n, q_p - p)) > u_d.stops.z * dist || dot(n, q_n) < 0.8;
}

void main() {
    if (gl_LocalInvocationIndex == 0u) s_reach = 0u;
    barrier();
    ivec2 offset = ivec2(u_pass.x % uint(STRIDE), (u_pass.x / uint(STRIDE)) % uint(STRIDE));
    ivec2 pixel = STRIDE * ivec2(gl_GlobalInvocationID.xy) + offset + ivec2(u_d.c.viewport.xy);
    vec3 p, n;
    if (hrt_in_viewport(pixel) && hrt_engine_surface(pixel, p, n)) {
        float dist = distance(p, u_d.eye.xyz);
        if (surface_moved(pixel, p, n, dist)) {
            float reach = uintBitsToFloat(u_pass.w) / (dist * u_d.eye.w);
            atomicMax(s_reach, uint(clamp(reach, 1.0, MOVING_MAX_REACH)));
        }
    }
    barrier();
    int r = int(s_reach);
    if (r == 0) return;
    // Every 32x32 tile within reach of this workgroup's block.
    const int S = HRT_MOVING_STAMP_TILE;
    ivec2 lo = ivec2(gl_WorkGroupID.xy) * BLOCK;
    ivec2 first = max((lo - r) / S, ivec2(0));
    ivec2 last = min((lo + BLOCK - 1 + r) / S, (ivec2(u_d.c.viewport.zw) + S - 1) / S - 1);
    ivec2 count = last - first + 1;
    for (int i = int(gl_LocalInvocationIndex); i < count.x * count.y; i += 64) {
        ivec2 t = first + ivec2(i % count.x, i / count.x);
        vec2 gap = vec2(max(max(t * S - (lo + BLOCK), lo - (t + 1) * S), ivec2(0)));
        if (length(gap) <= float(r)) hrt_moving_store(t, u_pass.x);
    }
}
