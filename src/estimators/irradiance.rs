//! Irradiance at a point under a sky: the first Monte Carlo estimator of the lecture material.
//!
//! `E = ∫_H L(ω) cos θ dω` (W/m² for radiance in W/(m² sr)). For a uniform sky of radiance `L`,
//! `E = L π`. Two estimators of it:
//! - **uniform hemisphere** sampling, `p(ω) = 1/(2π)`: `F = 2π L cos θ` per sample, whose
//!   variance `L² π² / 3` makes the error fall as `N^(-1/2)`;
//! - **cosine-weighted** sampling, `p(ω) = cos θ / π`: `F = π L` for every sample, an estimator
//!   with zero variance because the pdf is proportional to the integrand.

use super::Estimate;
use crate::math::{Vec2, Vec3};
use crate::sampling::{sample_cosine_hemisphere_malley, sample_uniform_hemisphere, Pcg32};

/// How directions are sampled over the hemisphere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HemisphereStrategy {
    /// `p(ω) = 1/(2π)`.
    Uniform,
    /// `p(ω) = cos θ / π` (Malley's method).
    Cosine,
}

/// Estimates `E = ∫_H L(ω) cos θ dω` with `n` directions sampled by `strategy` from `rng`.
/// `sky` gives the radiance arriving from a local direction (z = surface normal).
pub fn estimate_irradiance(
    sky: impl Fn(Vec3) -> f64,
    n: usize,
    strategy: HemisphereStrategy,
    rng: &mut Pcg32,
) -> Estimate {
    Estimate::from_values((0..n).map(|_| {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let s = match strategy {
            HemisphereStrategy::Uniform => sample_uniform_hemisphere(u),
            HemisphereStrategy::Cosine => sample_cosine_hemisphere_malley(u),
        };
        if s.pdf > 0.0 {
            sky(s.value) * s.value.z as f64 / s.pdf as f64
        } else {
            0.0
        }
    }))
}

/// Irradiance under a uniform sky of radiance `radiance`; the exact answer is `radiance · π`.
pub fn estimate_uniform_sky_irradiance(
    radiance: f64,
    n: usize,
    strategy: HemisphereStrategy,
    rng: &mut Pcg32,
) -> Estimate {
    estimate_irradiance(|_| radiance, n, strategy, rng)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::loglog_slope;
    use std::f64::consts::PI;

    #[test]
    fn both_estimators_converge_to_l_pi() {
        let l = 2.5;
        let mut rng = Pcg32::new(1, 0);
        let u = estimate_uniform_sky_irradiance(l, 1_000_000, HemisphereStrategy::Uniform, &mut rng);
        assert!((u.value - l * PI).abs() < 4.0 * u.std_error(), "uniform: {} ± {}", u.value, u.std_error());
        // The uniform estimator's variance is L²π²/3 (var of 2πL cosθ with cosθ ~ U(0,1)).
        assert!((u.sample_variance / (l * l * PI * PI / 3.0) - 1.0).abs() < 0.01);
        let c = estimate_uniform_sky_irradiance(l, 1000, HemisphereStrategy::Cosine, &mut rng);
        assert!((c.value - l * PI).abs() < 1e-5 * l * PI, "cosine: {}", c.value);
    }

    #[test]
    fn cosine_estimator_has_zero_variance() {
        let mut rng = Pcg32::new(2, 0);
        let c = estimate_uniform_sky_irradiance(1.0, 100_000, HemisphereStrategy::Cosine, &mut rng);
        // Only f32 round-off in cos θ / pdf remains.
        assert!(c.sample_variance < 1e-10, "variance {}", c.sample_variance);
        let u = estimate_uniform_sky_irradiance(1.0, 100_000, HemisphereStrategy::Uniform, &mut rng);
        assert!(u.sample_variance > 1.0);
    }

    #[test]
    fn uniform_error_falls_as_inverse_square_root() {
        // RMSE over 64 independent runs at each N, then the log-log slope, for several seeds.
        for seed in 0..4u64 {
            let mut rng = Pcg32::new(100 + seed, seed);
            let points: Vec<(f64, f64)> = [16usize, 64, 256, 1024, 4096]
                .iter()
                .map(|&n| {
                    let mse = (0..64)
                        .map(|_| {
                            let e = estimate_uniform_sky_irradiance(1.0, n, HemisphereStrategy::Uniform, &mut rng)
                                .value
                                - PI;
                            e * e
                        })
                        .sum::<f64>()
                        / 64.0;
                    (n as f64, mse.sqrt())
                })
                .collect();
            let slope = loglog_slope(&points).unwrap();
            assert!((slope + 0.5).abs() < 0.1, "seed {seed}: slope {slope}, points {points:?}");
        }
    }
}
