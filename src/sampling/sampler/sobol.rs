//! Owen-scrambled Sobol points, padded across dimension pairs.
//!
//! The first two dimensions of the Sobol sequence form a (0, 2)-sequence in base 2: every
//! aligned block of `2^m` consecutive points is a (0, m, 2)-net, i.e. each elementary interval
//! of area `2^-m` holds exactly one point. Dimension 0 is the van der Corput radical inverse
//! (bit reversal); dimension 1 uses the generator matrix of Pascal's triangle mod 2. Each pair
//! of dimensions gets its own Owen scrambling and its own shuffle of the sample index (the
//! "padding" of pbrt-v4's PaddedSobolSampler), so pairs are decorrelated from each other while
//! every pair keeps the net property. Error falls close to `O(N^-1)` for smooth integrands.

use crate::math::{Vec2, ONE_MINUS_EPSILON};
use crate::sampling::hash::{hash, owen_scramble, permutation_element};

/// Sobol point `i` in dimensions 0 and 1, as 32-bit binary fractions.
#[inline]
pub fn sobol_2d(i: u32) -> (u32, u32) {
    let x = i.reverse_bits();
    let mut y = 0u32;
    let mut v = 1u32 << 31;
    let mut i = i;
    while i != 0 {
        if i & 1 != 0 {
            y ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    (x, y)
}

#[inline]
fn to_unit(v: u32) -> f32 {
    ((v >> 8) as f32 * (1.0 / 16_777_216.0)).min(ONE_MINUS_EPSILON)
}

/// Padded, Owen-scrambled Sobol sampler. For (pixel, dimension pair, seed) the sample index is
/// permuted within each round of `spp` indices, then mapped to the 2D Sobol point and scrambled.
/// A power-of-two `spp` makes each pixel's points a scrambled (0, m, 2)-net in every pair.
#[derive(Clone, Debug)]
pub struct SobolSampler {
    spp: u32,
    seed: u64,
    pixel: [u32; 2],
    index: u32,
    dim: u32,
}

impl SobolSampler {
    /// Sampler for `spp` samples per pixel (best a power of two) and a global `seed`.
    pub fn new(spp: u32, seed: u64) -> Self {
        SobolSampler { spp: spp.max(1), seed, pixel: [0, 0], index: 0, dim: 0 }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.spp
    }

    /// Jumps to (pixel, sample index, dimension).
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel: [u32; 2], index: u32, dim: u32) {
        self.pixel = pixel;
        self.index = index;
        self.dim = dim;
    }

    /// Hash of (pixel, dimension, seed) and the shuffled Sobol index for the current sample.
    #[inline]
    fn point_index(&self) -> (u64, u32) {
        let h = hash(&[self.pixel[0] as u64 | (self.pixel[1] as u64) << 32, self.dim as u64, self.seed]);
        let round = self.index / self.spp;
        let shuffled = permutation_element(self.index % self.spp, self.spp, h as u32);
        (h, round.wrapping_mul(self.spp).wrapping_add(shuffled))
    }

    /// Next dimension: scrambled van der Corput.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let (h, i) = self.point_index();
        self.dim += 1;
        to_unit(owen_scramble(sobol_2d(i).0, (h >> 32) as u32))
    }

    /// Next two dimensions: a scrambled 2D Sobol point.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let (h, i) = self.point_index();
        self.dim += 2;
        let (x, y) = sobol_2d(i);
        let h2 = crate::sampling::hash::mix_bits(h);
        Vec2::new(to_unit(owen_scramble(x, (h >> 32) as u32)), to_unit(owen_scramble(y, h2 as u32)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `pts` (2^m points) form a (0, m, 2)-net: every elementary interval
    /// `2^-a × 2^-(m-a)` holds exactly one point.
    fn is_net(pts: &[(f32, f32)], m: u32) -> bool {
        for a in 0..=m {
            let (nx, ny) = (1u32 << a, 1u32 << (m - a));
            let mut count = vec![0u32; pts.len()];
            for &(x, y) in pts {
                let c = (y * ny as f32) as u32 * nx + (x * nx as f32) as u32;
                count[c as usize] += 1;
            }
            if count.iter().any(|&c| c != 1) {
                return false;
            }
        }
        true
    }

    #[test]
    fn unscrambled_points_are_sobol() {
        // Sobol dimension 2 has direction numbers v = 1/2, 3/4, 5/8, …; point i is the XOR of
        // the v_k of the bits set in i.
        let ys: Vec<f64> = (0..8).map(|i| sobol_2d(i).1 as f64 / 4_294_967_296.0).collect();
        assert_eq!(ys, vec![0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875]);
        let xs: Vec<f64> = (0..4).map(|i| sobol_2d(i).0 as f64 / 4_294_967_296.0).collect();
        assert_eq!(xs, vec![0.0, 0.5, 0.25, 0.75]);
        let pts: Vec<(f32, f32)> = (0..256).map(sobol_2d).map(|(x, y)| (to_unit(x), to_unit(y))).collect();
        assert!(is_net(&pts, 8));
    }

    #[test]
    fn every_pixel_and_pair_is_a_scrambled_net() {
        for m in [0u32, 2, 5, 8] {
            let spp = 1u32 << m;
            let mut s = SobolSampler::new(spp, 11);
            for pixel in [[0u32, 0u32], [17, 3], [640, 480]] {
                for pair in 0..4u32 {
                    let pts: Vec<(f32, f32)> = (0..spp)
                        .map(|i| {
                            s.start_pixel_sample(pixel, i, 2 * pair);
                            let p = s.next_2d();
                            (p.x, p.y)
                        })
                        .collect();
                    assert!(is_net(&pts, m), "spp {spp}, pixel {pixel:?}, pair {pair}");
                    // 1D projections are stratified too.
                    let mut seen = vec![false; spp as usize];
                    for i in 0..spp {
                        s.start_pixel_sample(pixel, i, 2 * pair);
                        let k = (s.next_1d() * spp as f32) as usize;
                        assert!(!seen[k]);
                        seen[k] = true;
                    }
                }
            }
        }
    }

    #[test]
    fn a_second_round_is_a_net_too() {
        let mut s = SobolSampler::new(16, 5);
        let pts: Vec<(f32, f32)> = (16..32)
            .map(|i| {
                s.start_pixel_sample([2, 2], i, 0);
                let p = s.next_2d();
                (p.x, p.y)
            })
            .collect();
        assert!(is_net(&pts, 4));
    }
}
