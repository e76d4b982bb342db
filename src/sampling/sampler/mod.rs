//! Samplers: the sources of the uniform numbers `u` that every warp consumes.
//!
//! A sampler is a deterministic function of (seed, pixel, sample index, dimension): the render
//! driver calls [`Sampler::start_pixel_sample`] before each camera sample and then draws
//! dimensions in a fixed order with [`Sampler::next_1d`] / [`Sampler::next_2d`]. Nothing depends
//! on which thread renders which pixel or in which order, so images are reproducible for a
//! given `--seed` regardless of thread count.
//!
//! - [`IndependentSampler`]: plain PCG32 streams (unbiased, `O(N^-1/2)` error).
//! - [`StratifiedSampler`]: jittered strata, each (pixel, dimension) with its own random
//!   permutation of strata (so dimensions are not correlated with each other).
//! - [`SobolSampler`]: Owen-scrambled 2D Sobol points, padded across dimension pairs with
//!   independent index shuffles (pbrt-v4's padded Sobol); scrambled nets for any sample count,
//!   best for powers of two.

mod independent;
mod sobol;
mod stratified;

pub use independent::IndependentSampler;
pub use sobol::{sobol_2d, SobolSampler};
pub use stratified::StratifiedSampler;

use crate::math::Vec2;
use crate::props::{Obj, Result as PropResult};

/// How far apart in a PCG32 stream consecutive sample indices start: room for this many
/// dimensions per sample.
pub(crate) const DIMENSIONS_PER_SAMPLE: i64 = 1 << 16;

/// Which sampler feeds the integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Independent uniform numbers.
    #[default]
    Independent,
    /// Jittered strata.
    Stratified,
    /// Padded Owen-scrambled Sobol.
    Sobol,
}

impl SamplerKind {
    /// The sampler for `spp` samples per pixel and `seed`.
    pub fn make(self, spp: u32, seed: u64) -> Sampler {
        match self {
            SamplerKind::Independent => Sampler::Independent(IndependentSampler::new(spp, seed)),
            SamplerKind::Stratified => Sampler::Stratified(StratifiedSampler::new(spp, true, seed)),
            SamplerKind::Sobol => Sampler::Sobol(SobolSampler::new(spp, seed)),
        }
    }
}

crate::choices!(SamplerKind, "sampler", {
    SamplerKind::Independent => "independent", "independent uniform numbers (PCG32 streams)";
    SamplerKind::Stratified => "stratified", "jittered strata, randomly permuted per dimension";
    SamplerKind::Sobol => "sobol", "Owen-scrambled Sobol points, padded across dimension pairs";
});

/// What a sampler plugin asks for: the kind, samples per pixel and seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplerSettings {
    /// Which sampler.
    pub kind: SamplerKind,
    /// Samples per pixel (`sample_count`).
    pub spp: u32,
    /// Seed.
    pub seed: u64,
}

impl Default for SamplerSettings {
    /// Mitsuba's default: independent, 4 samples per pixel, seed 0.
    fn default() -> Self {
        SamplerSettings { kind: SamplerKind::Independent, spp: 4, seed: 0 }
    }
}

/// Every sampler plugin name neumann reads (Mitsuba's; `multijitter` and `orthogonal` are
/// stratified here, `ldsampler` Owen-scrambled Sobol).
pub const SAMPLER_PLUGINS: &[&str] = &["independent", "stratified", "multijitter", "orthogonal", "ldsampler"];

impl SamplerSettings {
    /// Mitsuba's sampler plugins: `sample_count` (4, up to 2²⁴), `seed` (0); the stratified
    /// ones read `jitter`.
    pub fn from_props(s: &Obj) -> PropResult<SamplerSettings> {
        s.built.set(true);
        let kind = match s.ty.as_str() {
            "independent" => SamplerKind::Independent,
            "stratified" | "multijitter" | "orthogonal" => {
                s.bool("jitter", true)?;
                if s.ty == "orthogonal" {
                    s.int("strength", 2)?;
                }
                SamplerKind::Stratified
            }
            "ldsampler" => SamplerKind::Sobol,
            _ => return Err(s.unknown_plugin(SAMPLER_PLUGINS)),
        };
        let n = s.int("sample_count", 4)?;
        if !(1..=1 << 24).contains(&n) {
            return Err(s.error_at("sample_count", format!("sample_count must be between 1 and 2^24, got {n}")));
        }
        Ok(SamplerSettings { kind, spp: n as u32, seed: s.int("seed", 0)? as u64 })
    }
}

/// The samplers (a closed set, dispatched by `match`).
#[derive(Clone, Debug)]
pub enum Sampler {
    /// Independent uniform random numbers.
    Independent(IndependentSampler),
    /// Jittered stratified sampling.
    Stratified(StratifiedSampler),
    /// Padded Owen-scrambled Sobol.
    Sobol(SobolSampler),
}

impl Sampler {
    /// Samples per pixel this sampler was set up for (strata count, Sobol net size).
    pub fn samples_per_pixel(&self) -> u32 {
        match self {
            Sampler::Independent(s) => s.samples_per_pixel(),
            Sampler::Stratified(s) => s.samples_per_pixel(),
            Sampler::Sobol(s) => s.samples_per_pixel(),
        }
    }

    /// Name as used on the command line and in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            Sampler::Independent(_) => "independent",
            Sampler::Stratified(_) => "stratified",
            Sampler::Sobol(_) => "sobol",
        }
    }

    /// Positions the sampler at sample `index` of `pixel`, dimension `dim` (usually 0).
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel: [u32; 2], index: u32, dim: u32) {
        match self {
            Sampler::Independent(s) => s.start_pixel_sample(pixel, index, dim),
            Sampler::Stratified(s) => s.start_pixel_sample(pixel, index, dim),
            Sampler::Sobol(s) => s.start_pixel_sample(pixel, index, dim),
        }
    }

    /// The next dimension, a uniform number in `[0, 1)`.
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        match self {
            Sampler::Independent(s) => s.next_1d(),
            Sampler::Stratified(s) => s.next_1d(),
            Sampler::Sobol(s) => s.next_1d(),
        }
    }

    /// The next two dimensions, a uniform point of `[0, 1)²` (stratified jointly where the
    /// sampler stratifies).
    #[inline(always)]
    pub fn next_2d(&mut self) -> Vec2 {
        match self {
            Sampler::Independent(s) => s.next_2d(),
            Sampler::Stratified(s) => s.next_2d(),
            Sampler::Sobol(s) => s.next_2d(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, Chi2Config, Rect};

    fn all(spp: u32, seed: u64) -> Vec<Sampler> {
        vec![
            Sampler::Independent(IndependentSampler::new(spp, seed)),
            Sampler::Stratified(StratifiedSampler::new(spp, true, seed)),
            Sampler::Sobol(SobolSampler::new(spp, seed)),
        ]
    }

    /// Draws sample `index` of `pixel`: four 2D points and two 1D values.
    fn draw(s: &mut Sampler, pixel: [u32; 2], index: u32) -> Vec<f32> {
        s.start_pixel_sample(pixel, index, 0);
        let mut v = Vec::new();
        for _ in 0..2 {
            let p = s.next_2d();
            v.extend([p.x, p.y]);
        }
        v.push(s.next_1d());
        let p = s.next_2d();
        v.extend([p.x, p.y, s.next_1d()]);
        v
    }

    #[test]
    fn deterministic_in_seed_pixel_index_dimension() {
        for mut s in all(16, 42) {
            let a = draw(&mut s, [3, 5], 7);
            // Other work in between must not change the values.
            let _ = draw(&mut s, [100, 2], 1);
            let _ = draw(&mut s, [3, 5], 8);
            let b = draw(&mut s, [3, 5], 7);
            assert_eq!(a, b, "{} not deterministic", s.name());
            // A fresh sampler with the same seed agrees; another seed or pixel differs.
            let mut fresh = all(16, 42).into_iter().find(|t| t.name() == s.name()).unwrap();
            assert_eq!(draw(&mut fresh, [3, 5], 7), a);
            let mut other = all(16, 43).into_iter().find(|t| t.name() == s.name()).unwrap();
            assert_ne!(draw(&mut other, [3, 5], 7), a, "{}: seed ignored", s.name());
            assert_ne!(draw(&mut s, [4, 5], 7), a, "{}: pixel ignored", s.name());
            // Starting at dimension d gives the same values as drawing up to d.
            s.start_pixel_sample([3, 5], 7, 4);
            assert_eq!(s.next_1d(), a[4], "{}: start dimension", s.name());
        }
    }

    #[test]
    fn consecutive_samples_equal_random_access() {
        // The render loop starts samples 0, 1, 2, ... of a pixel in turn (the independent sampler
        // then jumps by a precomputed stride); any other order must give the same values.
        for mut s in all(16, 5) {
            let sequential: Vec<Vec<f32>> = (0..40).map(|i| draw(&mut s, [9, 4], i)).collect();
            for i in (0..40).rev() {
                let _ = draw(&mut s, [i, 1], i);
                assert_eq!(draw(&mut s, [9, 4], i), sequential[i as usize], "{} sample {i}", s.name());
            }
        }
    }

    #[test]
    fn every_sampler_is_uniform_in_each_pair_and_across_pairs() {
        // χ² on the unit square, over 4096 pixels × 64 samples: dimensions (0,1), (2,3) and the
        // cross pair (0, 2) that would reveal correlation between dimensions.
        for s in all(64, 7) {
            for (k, pair) in [(0usize, 1usize), (2, 3), (0, 2), (4, 6)].into_iter().enumerate() {
                let mut sampler = s.clone();
                let (mut pixel, mut index) = (0u32, 0u32);
                let out = chi2_2d(
                    &Rect::UNIT,
                    [16, 16],
                    4096 * 64,
                    |_| {
                        let v = draw(&mut sampler, [pixel % 64, pixel / 64], index);
                        index += 1;
                        if index == 64 {
                            index = 0;
                            pixel += 1;
                        }
                        Some(Vec2::new(v[pair.0], v[pair.1]))
                    },
                    |_| 1.0,
                    &Chi2Config::default().with_seed(k as u64),
                );
                assert!(out.passed(), "{} dims {pair:?}: {out}", s.name());
            }
        }
    }

    #[test]
    fn sample_indices_beyond_spp_stay_uniform() {
        // Progressive rendering past the planned sample count (time budgets) keeps drawing
        // valid, uniform points.
        for s in all(16, 9) {
            let mut sampler = s.clone();
            let mut i = 0u32;
            let out = chi2_2d(
                &Rect::UNIT,
                [8, 8],
                64 * 256,
                |_| {
                    let v = draw(&mut sampler, [1 + i / 256, 2], 16 + i % 256);
                    i += 1;
                    Some(Vec2::new(v[0], v[1]))
                },
                |_| 1.0,
                &Chi2Config::default(),
            );
            assert!(out.passed(), "{}: {out}", s.name());
        }
    }
}
