//! Uniform sphere and spherical cap (cone of directions).
//!
//! Archimedes' hat-box theorem: `z = cos θ` of a uniform direction is uniform on `[-1, 1]`, so
//! `z = 1 - 2ξ₁`, `φ = 2πξ₂` samples the sphere, and `z` uniform on `[cos θ_max, 1]` samples a
//! cap. The cap is how a spherical light is sampled from outside: the cone it subtends.

use super::Sample;
use crate::math::{safe_sqrt, spherical_phi, Vec2, Vec3, INV_2PI, INV_4PI, ONE_MINUS_EPSILON, PI};

/// Uniform direction on the unit sphere: `z = 1 - 2u.x`, `φ = 2π u.y`. Domain `u ∈ [0,1)²`;
/// pdf `1/(4π)`, solid-angle measure.
#[inline]
pub fn sample_uniform_sphere(u: Vec2) -> Sample<Vec3> {
    let z = 1.0 - 2.0 * u.x;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = crate::math::sin_cos_2pi(u.y);
    Sample::solid_angle(Vec3::new(r * c, r * s, z), INV_4PI)
}

/// Density of [`sample_uniform_sphere`]: `1/(4π)` (solid angle).
#[inline]
pub fn uniform_sphere_pdf() -> f32 {
    INV_4PI
}

/// Inverse of [`sample_uniform_sphere`]: `u = ((1 - z)/2, φ / 2π)`.
#[inline]
pub fn invert_uniform_sphere(w: Vec3) -> Vec2 {
    Vec2::new(0.5 * (1.0 - w.z), (spherical_phi(w) * INV_2PI).min(ONE_MINUS_EPSILON))
}

/// Uniform direction in the cone of half-angle θ_max about +z (`cos_theta_max ∈ [-1, 1)`):
/// `cos θ = 1 - u.x (1 - cos θ_max)`, `φ = 2π u.y`. Domain `u ∈ [0,1)²`; pdf
/// `1 / (2π (1 - cos θ_max))`, solid-angle measure.
#[inline]
pub fn sample_uniform_cone(u: Vec2, cos_theta_max: f32) -> Sample<Vec3> {
    let cos_theta = 1.0 - u.x * (1.0 - cos_theta_max);
    let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    let (s, c) = crate::math::sin_cos_2pi(u.y);
    Sample::solid_angle(Vec3::new(sin_theta * c, sin_theta * s, cos_theta), uniform_cone_pdf_inside(cos_theta_max))
}

#[inline]
fn uniform_cone_pdf_inside(cos_theta_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_theta_max))
}

/// Density of [`sample_uniform_cone`] at `w`: `1 / (2π (1 - cos θ_max))` inside the cone, 0
/// outside (solid angle).
#[inline]
pub fn uniform_cone_pdf(w: Vec3, cos_theta_max: f32) -> f32 {
    if w.z >= cos_theta_max {
        uniform_cone_pdf_inside(cos_theta_max)
    } else {
        0.0
    }
}

/// Inverse of [`sample_uniform_cone`].
#[inline]
pub fn invert_uniform_cone(w: Vec3, cos_theta_max: f32) -> Vec2 {
    Vec2::new((1.0 - w.z) / (1.0 - cos_theta_max), (spherical_phi(w) * INV_2PI).min(ONE_MINUS_EPSILON))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{check_inverse, chi2_2d, integrate_pdf_2d, u2, Chi2Config, SphericalCap, SPHERE};

    #[test]
    fn sphere_chi2_and_normalization() {
        let out = chi2_2d(
            &SPHERE,
            [15, 31],
            1_000_000,
            |r| Some(sample_uniform_sphere(u2(r)).value),
            |_| uniform_sphere_pdf() as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        assert!((integrate_pdf_2d(&SPHERE, [8, 8], |_| uniform_sphere_pdf() as f64) - 1.0).abs() < 1e-6);
        let e = check_inverse(
            100_000,
            5,
            1e-3,
            |u| Some(sample_uniform_sphere(u).value),
            |w| Some(invert_uniform_sphere(*w)),
        );
        assert!(e < 1e-3, "{e}");
    }

    #[test]
    fn cone_chi2_for_several_apertures() {
        for (k, &cos_max) in [0.95f32, 0.5, 0.0, -0.6].iter().enumerate() {
            let cfg = Chi2Config::default().with_seed(100 + k as u64);
            // The cap domain rejects (fails on) any sample outside the cone.
            let cap = SphericalCap { z_min: cos_max as f64 };
            let out = chi2_2d(
                &cap,
                [15, 31],
                500_000,
                |r| Some(sample_uniform_cone(u2(r), cos_max).value),
                |w| uniform_cone_pdf(*w, cos_max) as f64,
                &cfg,
            );
            assert!(out.passed(), "cos θ_max = {cos_max}: {out}");
            assert!((integrate_pdf_2d(&cap, [8, 8], |w| uniform_cone_pdf(*w, cos_max) as f64) - 1.0).abs() < 1e-5);
            let e = check_inverse(
                50_000,
                k as u64,
                1e-3,
                |u| Some(sample_uniform_cone(u, cos_max).value),
                |w| Some(invert_uniform_cone(*w, cos_max)),
            );
            assert!(e < 2e-3, "cone inverse {e}");
        }
    }
}
