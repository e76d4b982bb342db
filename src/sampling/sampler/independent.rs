//! Independent uniform samples from per-pixel PCG32 streams.

use super::DIMENSIONS_PER_SAMPLE;
use crate::math::Vec2;
use crate::sampling::{hash::hash, Pcg32};

/// Independent uniform random numbers. Pixel `p` uses PCG32 stream `hash(p, seed)`; sample `i`,
/// dimension `d` is output number `i · 2¹⁶ + d` of that stream.
#[derive(Clone, Debug)]
pub struct IndependentSampler {
    spp: u32,
    seed: u64,
    rng: Pcg32,
}

impl IndependentSampler {
    /// Sampler for `spp` samples per pixel and a global `seed`.
    pub fn new(spp: u32, seed: u64) -> Self {
        IndependentSampler { spp: spp.max(1), seed, rng: Pcg32::default() }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.spp
    }

    /// Jumps to (pixel, sample index, dimension).
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel: [u32; 2], index: u32, dim: u32) {
        let stream = hash(&[pixel[0] as u64 | (pixel[1] as u64) << 32, self.seed]);
        self.rng.set_sequence(stream, mix_seed(self.seed));
        self.rng.advance(index as i64 * DIMENSIONS_PER_SAMPLE + dim as i64);
    }

    /// Next uniform number.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        self.rng.next_f32()
    }

    /// Next two uniform numbers.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.rng.next_f32();
        Vec2::new(x, self.rng.next_f32())
    }
}

#[inline]
pub(crate) fn mix_seed(seed: u64) -> u64 {
    crate::sampling::hash::mix_bits(seed ^ 0x5851_f42d)
}
