//! Comparisons of GPU images with reference images, with tolerances derived from sample
//! counts.
//!
//! AO per pixel is a mean of N samples each in [0, 1], so its variance is at most 1/(4N)
//! (Popoviciu). The difference of a GPU pixel (N rays) and a reference pixel (M rays) thus has
//! standard deviation at most sqrt(1/(4N) + 1/(4M)); a block mean of B pixels at most that over
//! sqrt(B). Tests accept block means within 4 of those deviations (a false failure has
//! probability < 1e-4 per block under the normal approximation), plus a small bias allowance
//! for the few-ULP differences between float G-buffer reconstruction on the two sides.

pub fn sample_sigma(gpu_samples: u32, reference_samples: u32) -> f32 {
    (0.25 / gpu_samples as f32 + 0.25 / reference_samples as f32).sqrt()
}

pub struct BlockReport {
    pub worst_block_error: f32,
    pub worst_block: (u32, u32),
    pub tolerance: f32,
    pub mean_abs_error: f32,
}

/// Compares means over `block`x`block` tiles.
pub fn compare_blocks(
    gpu: &[f32],
    reference: &[f32],
    width: u32,
    height: u32,
    block: u32,
    sigma_pixel: f32,
    bias: f32,
) -> BlockReport {
    let tolerance = 4.0 * sigma_pixel / ((block * block) as f32).sqrt() + bias;
    let mut worst = (0.0f32, (0, 0));
    for by in 0..height / block {
        for bx in 0..width / block {
            let mut d = 0.0;
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    let i = (y * width + x) as usize;
                    d += gpu[i] - reference[i];
                }
            }
            let e = (d / (block * block) as f32).abs();
            if e > worst.0 {
                worst = (e, (bx, by));
            }
        }
    }
    let mae = gpu.iter().zip(reference).map(|(a, b)| (a - b).abs()).sum::<f32>() / gpu.len() as f32;
    BlockReport { worst_block_error: worst.0, worst_block: worst.1, tolerance, mean_abs_error: mae }
}

pub fn mean(v: &[f32]) -> f32 {
    v.iter().sum::<f32>() / v.len() as f32
}

/// Mean over the pixels where `mask` is true.
pub fn masked_mean(v: &[f32], mask: &[bool]) -> f32 {
    let (s, n) = v.iter().zip(mask).filter(|(_, m)| **m).fold((0.0, 0usize), |(s, n), (x, _)| (s + x, n + 1));
    s / n.max(1) as f32
}

/// Relative RMSE over the masked pixels: sqrt(mean((x - r)²)) / mean(r), the usual
/// denoiser-quality measure (NRD's and SVGF's papers report it).
pub fn relative_rmse(x: &[f32], reference: &[f32], mask: &[bool]) -> f32 {
    let (mut se, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for ((a, r), m) in x.iter().zip(reference).zip(mask) {
        if *m {
            se += ((a - r) as f64).powi(2);
            sum += *r as f64;
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    ((se / n).sqrt() / (sum / n).max(1e-12)) as f32
}
