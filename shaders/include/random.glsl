// The rays' random numbers: per-pixel sample sequences (the default, which the denoisers are
// tuned for) and the white- and blue-noise generators of TraceCommon::random_numbers.
#ifndef HRT_RANDOM_GLSL
#define HRT_RANDOM_GLSL
#include "common.glsl"
#include "trace_push.glsl"

// RandomNumbers (sdk/src/types/inputs.rs)
#define HRT_RANDOM_DEFAULT 0u
#define HRT_RANDOM_WHITE_NOISE 1u
#define HRT_RANDOM_BLUE_NOISE 2u

// A pixel's samples across frames: one R2 sequence (Roberts 2018) per pixel, rotated by a
// hash of the pixel alone (Cranley-Patterson), whose sample `first + i` is this frame's ray i,
// first = frame x rays (frames of this pixel: half as many in checkerboard mode). Within a
// frame that is the low-discrepancy set the rays always had; across frames the denoiser's
// temporal mean of a static pixel is then a stratified estimate, not a mean of independent
// ones: a 0.2 rad sun's penumbra, 32 one-ray frames, has a raw mean 7.3% off instead of 13.6%
// and denoises to 6.6% (tests/tests/denoise.rs). Neighbouring pixels stay decorrelated by their rotations. Fixed
// point, so the sequence wraps exactly (mod 1) instead of losing float precision with time.
struct HrtSequence {
    uvec2 shift;
    uint first;
    uint generator; // HRT_RANDOM_*
    uvec2 pixel;    // white and blue noise: the pixel (not its tile)
};

HrtSequence hrt_sequence(uint frame, bool checkerboard, uvec2 pixel, uint salt, uint rays) {
    uint h = hrt_pcg(pixel.x ^ hrt_pcg(pixel.y ^ salt));
    uint pixel_frame = checkerboard ? frame >> 1u : frame;
    return HrtSequence(uvec2(h, hrt_pcg(h)), pixel_frame * rays, HRT_RANDOM_DEFAULT, pixel);
}

// Diffuse GI's and reflections' samples: hrt_sequence's, but each 8x8 tile of pixels shares
// one rotation and its pixels sit apart on a 64-point lattice (rank-1, generator (1, 10),
// visited in bit-reversed Morton order, so the tile and each aligned 2x2 and 4x4 block of it
// hold evenly spread points). A pixel's own points across frames are R2's, as before; within a
// frame a tile's pixels sample a shifted lattice, a stratified set, so a frame's error is
// higher in frequency and the spatial passes remove more of it. The quality program's static
// views, 8 / 32 frames: GI 0.034 / 0.023 -> 0.029 / 0.021 and its flicker 0.71% -> 0.42% of
// the mean a frame; glossy reflections 0.046 / 0.027 -> 0.044 / 0.025. Not AO (0.042 / 0.021
// -> 0.050 / 0.036: its frames are independent, and a fixed lattice between neighbours
// correlates their errors frame after frame) nor shadows (a 0.03 rad sun's penumbra after 32
// frames 0.083 -> 0.096).
HrtSequence hrt_tile_sequence(uint frame, bool checkerboard, uvec2 pixel, uint salt, uint rays) {
    // The tile's sequence is hrt_sequence's for the tile as if it were one pixel.
    HrtSequence seq = hrt_sequence(frame, checkerboard, pixel >> 3u, salt, rays);
    uvec2 q = pixel & 7u;
    uint morton = (q.x & 1u) | ((q.y & 1u) << 1u) | ((q.x & 2u) << 1u) | ((q.y & 2u) << 2u) | ((q.x & 4u) << 2u) | ((q.y & 4u) << 3u);
    uint k = bitfieldReverse(morton) >> 26u;
    seq.shift += uvec2(k, (k * 10u) & 63u) << 26u;
    return seq;
}

// The salt for a sequence rotated anew every frame (frame 0 of it each time): frames are then
// independent. AO keeps this: its crease rule estimates noise from frame-to-frame differences,
// which a stratified sequence makes smaller than the noise of one frame (measured: creases 1%
// too bright). Shadows, diffuse GI and reflections run their pixel's sequence on across
// frames: their anti-lag tests take one sample's variance from this frame's 5x5 neighbours
// where that is larger than the history's, and a light switched on still leaves GI within 15%
// of its new value after 4 frames (8% while neighbours' rotations were independent: a
// stratified window's mean is steadier than the test assumes, so it waits for a larger
// change). The quality program's static views, 8 / 32 frames: GI 0.057 / 0.037 -> 0.034 /
// 0.023, glossy reflections 0.060 / 0.038 -> 0.046 / 0.027.
uint hrt_independent_frames(uint frame, uint salt) {
    return hrt_pcg(frame ^ salt);
}

// The other generators of TraceCommon::random_numbers (offset_world.w), for image-quality
// comparisons: `s` becomes the task's pixel `pixel` drawing from white or blue noise, frame
// after frame; with the default it is returned as it is.
HrtSequence hrt_with_generator(HrtSequence s, TraceCommon c, uvec2 pixel, uint salt, uint rays) {
    uint generator = uint(c.offset_world.w);
    if (generator == HRT_RANDOM_DEFAULT) return s;
    s.generator = generator;
    s.pixel = pixel;
    s.first = c.frame.x * rays;
    if (generator == HRT_RANDOM_BLUE_NOISE && u_trace_push.blue_noise != uvec2(0u)) {
        // The tile's shifts are the same for every pixel: a shift keeps it blue.
        s.shift = uvec2(hrt_pcg(salt), hrt_pcg(salt ^ 0x9e3779b9u));
    } else {
        s.generator = HRT_RANDOM_WHITE_NOISE;
        uint h = hrt_pcg(pixel.x ^ hrt_pcg(pixel.y ^ salt));
        s.shift = uvec2(h, hrt_pcg(h));
    }
    return s;
}

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer HrtBlueNoise { uint rank[]; };

// Ray i's two numbers in [0, 1).
vec2 hrt_sample(HrtSequence s, uint i) {
    const uvec2 alpha = uvec2(3242174889u, 2447445413u); // (0.7548777, 0.5698403) x 2^32
    if (s.generator == HRT_RANDOM_WHITE_NOISE) {
        uint a = hrt_pcg(s.shift.x ^ hrt_pcg(s.first + i));
        return vec2(hrt_u01(a), hrt_u01(hrt_pcg(a ^ s.shift.y)));
    }
    if (s.generator == HRT_RANDOM_BLUE_NOISE) {
        // Sample n of the pixel reads the 64x64 tile at two shifts (one per dimension), the R2
        // points 2n and 2n + 1; one jitter per sample spreads the 4096 ranks over [0, 1)
        // without reordering them (Kickstart RT's blue-noise generator does the same).
        uint n = s.first + i;
        uvec2 o0 = (s.shift + alpha * (2u * n)) >> 26u;
        uvec2 o1 = (s.shift + alpha * (2u * n + 1u)) >> 26u;
        HrtBlueNoise tile = HrtBlueNoise(u_trace_push.blue_noise);
        uint r0 = tile.rank[((s.pixel.y + o0.y) & 63u) * 64u + ((s.pixel.x + o0.x) & 63u)];
        uint r1 = tile.rank[((s.pixel.y + o1.y) & 63u) * 64u + ((s.pixel.x + o1.x) & 63u)];
        float jitter = hrt_u01(hrt_pcg(n ^ s.shift.x));
        return (vec2(r0, r1) + jitter) * (1.0 / 4096.0);
    }
    uvec2 bits = s.shift + alpha * (s.first + i);
    return vec2(bits >> 8u) * (1.0 / 16777216.0);
}
#endif
