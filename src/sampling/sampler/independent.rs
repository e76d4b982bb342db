//! Independent uniform samples from per-pixel PCG32 streams.

use super::DIMENSIONS_PER_SAMPLE;
use crate::math::Vec2;
use crate::sampling::{hash::hash, Pcg32, Stride};

/// Independent uniform random numbers. Pixel `p` uses PCG32 stream `hash(p, seed)`; sample `i`,
/// dimension `d` is output number `i · 2¹⁶ + d` of that stream.
#[derive(Clone, Debug)]
pub struct IndependentSampler {
    spp: u32,
    seed: u64,
    rng: Pcg32,
    /// The (pixel, sample index) last started at dimension 0 and the generator there: the next
    /// sample of the same pixel is one [`SAMPLE_STRIDE`] further (the render loop's order).
    last_start: Option<([u32; 2], u32, Pcg32)>,
}

/// The jump from one sample's first dimension to the next sample's.
const SAMPLE_STRIDE: Stride = Stride::new(DIMENSIONS_PER_SAMPLE);

impl IndependentSampler {
    /// Sampler for `spp` samples per pixel and a global `seed`.
    pub fn new(spp: u32, seed: u64) -> Self {
        IndependentSampler { spp: spp.max(1), seed, rng: Pcg32::default(), last_start: None }
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.spp
    }

    /// Jumps to (pixel, sample index, dimension).
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel: [u32; 2], index: u32, dim: u32) {
        match &mut self.last_start {
            // The next sample of the same pixel: one stride on (O(1) instead of O(log n)).
            Some((p, i, start)) if *p == pixel && index > 0 && *i == index - 1 => {
                start.jump(&SAMPLE_STRIDE);
                *i = index;
                self.rng = start.clone();
            }
            _ => {
                let stream = hash(&[pixel[0] as u64 | (pixel[1] as u64) << 32, self.seed]);
                self.rng.set_sequence(stream, mix_seed(self.seed));
                self.rng.advance(index as i64 * DIMENSIONS_PER_SAMPLE);
                self.last_start = Some((pixel, index, self.rng.clone()));
            }
        }
        if dim > 0 {
            self.rng.advance(dim as i64);
        }
    }

    /// The generator the next numbers come from (the path tracer's lanes draw from it in
    /// vector instructions, [`crate::sampling::rng::Pcg32Lanes`]).
    #[inline(always)]
    pub(crate) fn rng_mut(&mut self) -> &mut Pcg32 {
        &mut self.rng
    }

    /// Next uniform number.
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        self.rng.next_f32()
    }

    /// Next two uniform numbers.
    #[inline(always)]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.rng.next_f32();
        Vec2::new(x, self.rng.next_f32())
    }
}

#[inline]
pub(crate) fn mix_seed(seed: u64) -> u64 {
    crate::sampling::hash::mix_bits(seed ^ 0x5851_f42d)
}
