//! Jittered stratified sampling.

use super::independent::mix_seed;
use super::DIMENSIONS_PER_SAMPLE;
use crate::math::{Vec2, ONE_MINUS_EPSILON};
use crate::sampling::hash::{hash, permutation_element};
use crate::sampling::Pcg32;

/// Jittered stratified sampling: the unit interval (1D) or square (2D) is split into `spp`
/// strata (`nx × ny` with `nx ≈ √spp` for 2D), and sample `i` of a pixel lands in stratum
/// `π(i)` of a permutation `π` private to (pixel, dimension), at a uniform position inside it
/// (or its centre when `jitter` is off). Indices beyond `spp` start a new round of strata with a
/// new permutation.
#[derive(Clone, Debug)]
pub struct StratifiedSampler {
    nx: u32,
    ny: u32,
    jitter: bool,
    seed: u64,
    pixel: [u32; 2],
    index: u32,
    dim: u32,
    rng: Pcg32,
}

impl StratifiedSampler {
    /// Sampler with `spp` samples per pixel as `nx × ny` strata, `nx · ny = spp`, the most nearly
    /// square factor pair (`nx ≥ ny`; a prime `spp` gives `spp × 1`).
    pub fn new(spp: u32, jitter: bool, seed: u64) -> Self {
        let spp = spp.max(1);
        let mut nx = (spp as f64).sqrt() as u32;
        while nx > 1 && !spp.is_multiple_of(nx) {
            nx -= 1;
        }
        let ny = spp / nx;
        StratifiedSampler { nx: ny, ny: nx, jitter, seed, pixel: [0, 0], index: 0, dim: 0, rng: Pcg32::default() }
    }

    /// Sampler with explicit `nx × ny` strata.
    pub fn with_strata(nx: u32, ny: u32, jitter: bool, seed: u64) -> Self {
        StratifiedSampler {
            nx: nx.max(1),
            ny: ny.max(1),
            jitter,
            seed,
            pixel: [0, 0],
            index: 0,
            dim: 0,
            rng: Pcg32::default(),
        }
    }

    /// Samples per pixel (`nx · ny`).
    pub fn samples_per_pixel(&self) -> u32 {
        self.nx * self.ny
    }

    /// Jumps to (pixel, sample index, dimension).
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel: [u32; 2], index: u32, dim: u32) {
        self.pixel = pixel;
        self.index = index;
        self.dim = dim;
        let stream = hash(&[pixel[0] as u64 | (pixel[1] as u64) << 32, self.seed]);
        self.rng.set_sequence(stream, mix_seed(self.seed));
        self.rng.advance(index as i64 * DIMENSIONS_PER_SAMPLE + dim as i64);
    }

    /// Stratum of the current sample for the current dimension, among `n`.
    #[inline]
    fn stratum(&self, n: u32) -> u32 {
        let round = self.index / n;
        let h = hash(&[self.pixel[0] as u64 | (self.pixel[1] as u64) << 32, self.dim as u64, self.seed, round as u64]);
        permutation_element(self.index % n, n, h as u32)
    }

    #[inline]
    fn offset(&mut self) -> f32 {
        if self.jitter {
            self.rng.next_f32()
        } else {
            self.rng.next_f32();
            0.5
        }
    }

    /// Next dimension: stratum among `spp` intervals.
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let n = self.samples_per_pixel();
        let s = self.stratum(n);
        self.dim += 1;
        ((s as f32 + self.offset()) / n as f32).min(ONE_MINUS_EPSILON)
    }

    /// Next two dimensions: stratum among the `nx × ny` cells.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let n = self.samples_per_pixel();
        let s = self.stratum(n);
        self.dim += 2;
        let (x, y) = (s % self.nx, s / self.nx);
        let (dx, dy) = (self.offset(), self.offset());
        Vec2::new(
            ((x as f32 + dx) / self.nx as f32).min(ONE_MINUS_EPSILON),
            ((y as f32 + dy) / self.ny as f32).min(ONE_MINUS_EPSILON),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_stratum_gets_exactly_one_sample() {
        for spp in [1u32, 4, 12, 16, 17] {
            let mut s = StratifiedSampler::new(spp, true, 3);
            let (nx, ny) = (s.nx, s.ny);
            assert_eq!(nx * ny, spp);
            let mut cells_2d = vec![0u32; spp as usize];
            let mut cells_1d = vec![0u32; spp as usize];
            for i in 0..spp {
                s.start_pixel_sample([9, 4], i, 0);
                let p = s.next_2d();
                let q = s.next_1d();
                cells_2d[((p.y * ny as f32) as u32 * nx + (p.x * nx as f32) as u32) as usize] += 1;
                cells_1d[(q * spp as f32) as usize] += 1;
            }
            assert!(cells_2d.iter().all(|&c| c == 1), "spp {spp}: {cells_2d:?}");
            assert!(cells_1d.iter().all(|&c| c == 1), "spp {spp}: {cells_1d:?}");
        }
    }

    #[test]
    fn without_jitter_samples_sit_at_stratum_centres() {
        let mut s = StratifiedSampler::with_strata(4, 2, false, 1);
        s.start_pixel_sample([0, 0], 3, 0);
        let p = s.next_2d();
        assert!(((p.x * 4.0).fract() - 0.5).abs() < 1e-6 && ((p.y * 2.0).fract() - 0.5).abs() < 1e-6);
    }
}
