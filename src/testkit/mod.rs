//! Statistical test harness for every sampling routine, BSDF and light in neumann.
//!
//! A Monte Carlo renderer is only as correct as its samplers: a routine whose samples do not
//! follow the density its `pdf` reports biases every estimator that divides by that pdf. This
//! module checks that agreement *statistically*, with fixed seeds so that results are
//! reproducible:
//!
//! - [`chi2_2d`]: Pearson's χ² goodness-of-fit of samples on a 2D [`Domain`] (square, disk,
//!   sphere, hemisphere, spherical cap, triangle) against the claimed pdf, the pdf being
//!   *integrated* over every histogram cell by Gauss–Legendre quadrature (not evaluated at the
//!   cell centre), refined adaptively where the pdf is discontinuous inside a cell; cells with expected count below 5 are merged into one (Mitsuba 3's harness
//!   does the same).
//! - [`chi2_1d`] and [`chi2_discrete`]: the same on an interval (with an overflow cell for
//!   unbounded supports) and over a finite set of outcomes.
//! - [`chi2_two_sample_2d`]: whether two samplers draw from the same distribution.
//! - [`integrate_pdf_2d`] / [`integrate_pdf_1d`]: a pdf integrates to one over its domain.
//! - [`ks_1d`]: the Kolmogorov–Smirnov test of a 1D sampler against its CDF.
//! - [`check_inverse`]: `invert(sample(u)) ≈ u`.
//!
//! The significance level is 1 % for the whole test suite: each test runs at the Šidák-corrected
//! level `1 - (1 - 0.01)^(1/m)`, with `m` = [`Chi2Config::tests_in_run`] (the number of
//! statistical tests in one `cargo test` run, counted generously), so that a correct suite fails
//! by chance with probability at most 1 %. With fixed seeds a run is deterministic anyway; the
//! correction keeps the thresholds honest when seeds change.

mod chi2;
mod domain;
mod ks;
mod quadrature;
pub mod stats;

pub use chi2::{
    chi2_1d, chi2_2d, chi2_discrete, chi2_two_sample_2d, integrate_pdf_1d, integrate_pdf_2d, pearson, Chi2Config,
    Chi2Outcome,
};
pub use domain::{Disk, Domain, Rect, SphericalCap, Triangle, HEMISPHERE, SPHERE};
pub use ks::{ks_1d, KsOutcome};
pub use quadrature::gauss_legendre_5;

use crate::sampling::rng::Pcg32;

/// Checks `invert(sample(u)) ≈ u` for `n` uniform points `u ∈ [0,1)²` drawn with `seed`,
/// skipping points within `margin` of the square's edges (where mappings may be singular).
/// Returns the largest error found.
pub fn check_inverse<T>(
    n: usize,
    seed: u64,
    margin: f32,
    mut sample: impl FnMut(glam::Vec2) -> Option<T>,
    mut invert: impl FnMut(&T) -> Option<glam::Vec2>,
) -> f32 {
    let mut rng = Pcg32::new(seed, 0x1a7e);
    let mut worst = 0.0f32;
    for _ in 0..n {
        let u = glam::Vec2::new(rng.next_f32(), rng.next_f32());
        if u.x < margin || u.y < margin || u.x > 1.0 - margin || u.y > 1.0 - margin {
            continue;
        }
        let Some(x) = sample(u) else { continue };
        match invert(&x) {
            Some(v) => worst = worst.max((v - u).abs().max_element()),
            None => return f32::INFINITY,
        }
    }
    worst
}

/// `∫ f(ω) dω` over the unit sphere, estimated from `n` uniform directions drawn from `rng`
/// (an emitter's luminance integral, checked against its own estimate).
pub fn sphere_integral_mc(n: usize, rng: &mut Pcg32, f: impl Fn(glam::Vec3) -> f64) -> f64 {
    (0..n)
        .map(|_| {
            let s = crate::sampling::sample_uniform_sphere(u2(rng));
            f(s.value) / s.pdf as f64
        })
        .sum::<f64>()
        / n as f64
}

/// Two uniform numbers in `[0,1)` from `rng`, as a sampler's `u`.
#[inline]
pub fn u2(rng: &mut Pcg32) -> glam::Vec2 {
    glam::Vec2::new(rng.next_f32(), rng.next_f32())
}
