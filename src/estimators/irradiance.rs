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

/// How the irradiance from a spherical light is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphereLightStrategy {
    /// Uniform hemisphere directions, counted when they hit the light.
    Uniform,
    /// Cosine-weighted hemisphere directions, counted when they hit the light.
    Cosine,
    /// Points uniform on the light's whole surface (`p_A = 1/(4π r²)`), converted to solid
    /// angle; points on the far side are hidden by the sphere itself and contribute 0.
    Area,
    /// Directions uniform in the cone the light subtends (`p = 1/(2π(1 - cos θ_max))`).
    Cone,
}

/// Irradiance at the origin (normal +z) from a sphere of radiance `radiance`, radius `r`, centre
/// at height `h > r` on the normal: exactly `E = π L (r/h)²`. Each strategy is unbiased; their
/// variances differ by orders of magnitude (the point of the demo).
pub fn estimate_sphere_light_irradiance(
    radiance: f64,
    r: f64,
    h: f64,
    n: usize,
    strategy: SphereLightStrategy,
    rng: &mut Pcg32,
) -> Estimate {
    let c = Vec3::new(0.0, 0.0, h as f32);
    let (r32, h32) = (r as f32, h as f32);
    // Radiance along direction w (unit) from the origin: L if it meets the sphere.
    let hits = |w: Vec3| {
        let b = w.dot(c);
        b > 0.0 && b * b - (h32 * h32 - r32 * r32) >= 0.0
    };
    Estimate::from_values((0..n).map(|_| {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        match strategy {
            SphereLightStrategy::Uniform | SphereLightStrategy::Cosine => {
                let s = if strategy == SphereLightStrategy::Uniform {
                    sample_uniform_hemisphere(u)
                } else {
                    sample_cosine_hemisphere_malley(u)
                };
                if s.pdf > 0.0 && hits(s.value) {
                    radiance * s.value.z as f64 / s.pdf as f64
                } else {
                    0.0
                }
            }
            SphereLightStrategy::Area => {
                let n_s = crate::sampling::sample_uniform_sphere(u).value.as_dvec3();
                let p = c.as_dvec3() + r * n_s;
                let d2 = p.length_squared();
                let w = p / d2.sqrt();
                // Visible from the origin iff the light's normal faces it.
                let cos_light = -n_s.dot(w);
                if cos_light <= 0.0 {
                    return 0.0;
                }
                let pdf_w = d2 / (4.0 * std::f64::consts::PI * r * r * cos_light);
                radiance * w.z / pdf_w
            }
            SphereLightStrategy::Cone => {
                let cos_max = (1.0 - (r / h) * (r / h)).sqrt();
                let s = crate::sampling::sample_uniform_cone(u, cos_max as f32);
                radiance * s.value.z as f64 / s.pdf as f64
            }
        }
    }))
}

/// Irradiance under a uniform sky by uniform hemisphere sampling with `k × k` jittered strata
/// of the unit square (`N = k²` samples): the same integrand as the independent estimator, a
/// smaller variance (the error falls faster than `N^(-1/2)` for this smooth integrand).
pub fn estimate_uniform_sky_irradiance_stratified(radiance: f64, k: usize, rng: &mut Pcg32) -> Estimate {
    Estimate::from_values((0..k * k).map(|i| {
        let (a, b) = ((i % k) as f32, (i / k) as f32);
        let u = Vec2::new((a + rng.next_f32()) / k as f32, (b + rng.next_f32()) / k as f32);
        let s = sample_uniform_hemisphere(u.min(Vec2::splat(crate::math::ONE_MINUS_EPSILON)));
        radiance * s.value.z as f64 / s.pdf as f64
    }))
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

    /// All four sphere-light estimators converge to `π L (r/h)²`; cone sampling has the lowest
    /// variance, uniform hemisphere sampling the highest.
    #[test]
    fn sphere_light_estimators_agree_and_rank() {
        let (l, r, h) = (3.0, 0.5, 2.0);
        let exact = PI * l * (r / h) * (r / h);
        let mut var = Vec::new();
        for (k, s) in [
            SphereLightStrategy::Cone,
            SphereLightStrategy::Area,
            SphereLightStrategy::Cosine,
            SphereLightStrategy::Uniform,
        ]
        .into_iter()
        .enumerate()
        {
            let mut rng = Pcg32::new(10 + k as u64, 0);
            let e = estimate_sphere_light_irradiance(l, r, h, 400_000, s, &mut rng);
            assert!((e.value - exact).abs() < 4.0 * e.std_error() + 1e-4 * exact, "{s:?}: {} vs {exact}", e.value);
            var.push(e.sample_variance);
        }
        assert!(var[0] < var[1] && var[1] < var[2] && var[2] < var[3], "variances {var:?}");
    }

    /// Stratification lowers the error of the same uniform-hemisphere estimator.
    #[test]
    fn stratified_beats_independent() {
        let (runs, k) = (200, 16);
        let mse = |strat: bool| {
            let mut rng = Pcg32::new(99, strat as u64);
            (0..runs)
                .map(|_| {
                    let e = if strat {
                        estimate_uniform_sky_irradiance_stratified(1.0, k, &mut rng)
                    } else {
                        estimate_uniform_sky_irradiance(1.0, k * k, HemisphereStrategy::Uniform, &mut rng)
                    };
                    (e.value - PI).powi(2)
                })
                .sum::<f64>()
                / runs as f64
        };
        let (independent, stratified) = (mse(false), mse(true));
        assert!(stratified * 10.0 < independent, "stratified {stratified} vs independent {independent}");
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
