//! The blue-noise tile of `RandomNumbers::BlueNoise`: a 64x64 rank matrix made by Ulichney's
//! void-and-cluster method (1993), computed once per process (a few milliseconds) instead of
//! shipped as a binary asset. Every rank 0..4096 appears once, and points of neighbouring rank
//! sit far apart, so any threshold of the tile is an evenly spread point set and a frame's
//! error is high in spatial frequency. Kickstart RT ships a 128x128x64 texture for the same
//! option; one tile, shifted per frame and per dimension in the shader, serves a comparison.
use std::sync::OnceLock;

/// The tile's side.
pub(crate) const SIDE: usize = 64;
const N: usize = SIDE * SIDE;
/// Ulichney's Gaussian energy filter width.
const SIGMA: f32 = 1.9;
/// The filter is cut off beyond this toroidal distance (its weight there is < 1e-6).
const RADIUS: i32 = 10;

/// Ranks 0..4096, row-major, one u32 each (as the shader reads them).
pub(crate) fn tile() -> &'static [u32; N] {
    static TILE: OnceLock<Box<[u32; N]>> = OnceLock::new();
    TILE.get_or_init(void_and_cluster)
}

/// The energy field of a point set: each point adds a toroidal Gaussian around it.
#[derive(Clone)]
struct Energy {
    value: Vec<f32>,
    kernel: Vec<(isize, isize, f32)>,
}

impl Energy {
    fn new() -> Energy {
        let mut kernel = Vec::new();
        for dy in -RADIUS..=RADIUS {
            for dx in -RADIUS..=RADIUS {
                let d2 = (dx * dx + dy * dy) as f32;
                kernel.push((dx as isize, dy as isize, (-d2 / (2.0 * SIGMA * SIGMA)).exp()));
            }
        }
        Energy { value: vec![0.0; N], kernel }
    }

    /// Adds (sign 1) or removes (sign -1) the point at `i`.
    fn splat(&mut self, i: usize, sign: f32) {
        let (x, y) = ((i % SIDE) as isize, (i / SIDE) as isize);
        let side = SIDE as isize;
        for &(dx, dy, w) in &self.kernel {
            let (px, py) = ((x + dx).rem_euclid(side), (y + dy).rem_euclid(side));
            self.value[(py * side + px) as usize] += sign * w;
        }
    }

    /// The tightest cluster (highest energy among the points with `set[i] == on`) when
    /// `highest`, else the largest void (lowest energy among them).
    fn extreme(&self, set: &[bool], on: bool, highest: bool) -> usize {
        let mut best = usize::MAX;
        for i in (0..N).filter(|&i| set[i] == on) {
            let better =
                best == usize::MAX || if highest { self.value[i] > self.value[best] } else { self.value[i] < self.value[best] };
            if better {
                best = i;
            }
        }
        best
    }
}

fn void_and_cluster() -> Box<[u32; N]> {
    // The initial pattern: a tenth of the cells at random (a fixed seed: the same tile every
    // run), then relaxed until moving its tightest cluster into its largest void moves nothing.
    let mut set = vec![false; N];
    let mut energy = Energy::new();
    let mut state = 0x2545_f491_u32;
    let mut ones = 0;
    while ones < N / 10 {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        let i = state as usize % N;
        if !set[i] {
            set[i] = true;
            energy.splat(i, 1.0);
            ones += 1;
        }
    }
    loop {
        let cluster = energy.extreme(&set, true, true);
        set[cluster] = false;
        energy.splat(cluster, -1.0);
        let void = energy.extreme(&set, false, false);
        if void == cluster {
            set[cluster] = true;
            energy.splat(cluster, 1.0);
            break;
        }
        set[void] = true;
        energy.splat(void, 1.0);
    }
    let mut rank = Box::new([0u32; N]);
    // Phase 1: the initial points get the ranks below `ones`, highest first, tightest cluster
    // first.
    let (mut phase1_set, mut phase1_energy) = (set.clone(), energy.clone());
    for r in (0..ones).rev() {
        let cluster = phase1_energy.extreme(&phase1_set, true, true);
        phase1_set[cluster] = false;
        phase1_energy.splat(cluster, -1.0);
        rank[cluster] = r as u32;
    }
    // Phases 2 and 3: the others fill the largest void, in order.
    for r in ones..N {
        let void = energy.extreme(&set, false, false);
        set[void] = true;
        energy.splat(void, 1.0);
        rank[void] = r as u32;
    }
    rank
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rank_once() {
        let mut seen = vec![false; N];
        for &r in tile().iter() {
            assert!(!seen[r as usize], "rank {r} twice");
            seen[r as usize] = true;
        }
    }

    /// Blue noise: the tile's low frequencies hold little of its energy. Thresholded at half,
    /// the 4x4-block means vary far less than those of white noise (a Bernoulli(0.5) cell's
    /// variance over 16: 0.25/16). A block mean moves in steps of 1/16, so one cell off in
    /// most blocks is already 1/256: a quarter of white noise's is the bound.
    #[test]
    fn thresholds_are_evenly_spread() {
        let t = tile();
        let on = |x: usize, y: usize| (t[(y % SIDE) * SIDE + x % SIDE] < (N / 2) as u32) as u32 as f32;
        let mut var = 0.0;
        for by in 0..SIDE / 4 {
            for bx in 0..SIDE / 4 {
                let mut s = 0.0;
                for y in 0..4 {
                    for x in 0..4 {
                        s += on(bx * 4 + x, by * 4 + y);
                    }
                }
                var += (s / 16.0 - 0.5f32).powi(2);
            }
        }
        var /= ((SIDE / 4) * (SIDE / 4)) as f32;
        let white = 0.25 / 16.0;
        assert!(var < white / 4.0, "4x4-block variance {var} (white noise: {white})");
    }
}
