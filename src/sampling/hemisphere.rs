//! Hemisphere warps: uniform, and cosine-weighted by two methods that must agree.
//!
//! Directions are in the local frame with the normal on +z. The cosine-weighted density
//! `p(ω) = cos θ / π` cancels the cosine of the rendering equation against diffuse reflection
//! (zero-variance estimator of irradiance under a uniform sky). It is obtained
//! - by **Malley's method**: sample the unit disk uniformly (concentric map) and project up,
//!   `z = √(1 - x² - y²)`; a uniform disk density `1/π` projected onto the hemisphere becomes
//!   `cos θ / π` per solid angle (the projection's Jacobian is `cos θ`);
//! - by **inversion** of the marginal CDF in θ: `p(θ) = 2 cos θ sin θ` gives `F(θ) = sin² θ`, so
//!   `θ = asin √ξ₁`, `φ = 2π ξ₂`.

use super::disk::{invert_uniform_disk_concentric, sample_uniform_disk_concentric};
use super::Sample;
use crate::math::{safe_sqrt, spherical_phi, Vec2, Vec3, INV_2PI, INV_PI, ONE_MINUS_EPSILON};

/// Uniform hemisphere: `z = cos θ = 1 - u.x`, `φ = 2π u.y`. Domain `u ∈ [0,1)²`; value: unit
/// direction with z > 0; pdf `1/(2π)`, solid-angle measure.
#[inline]
pub fn sample_uniform_hemisphere(u: Vec2) -> Sample<Vec3> {
    let z = 1.0 - u.x;
    let r = safe_sqrt(1.0 - z * z);
    let (s, c) = crate::math::sin_cos_2pi(u.y);
    Sample::solid_angle(Vec3::new(r * c, r * s, z), INV_2PI)
}

/// Density of [`sample_uniform_hemisphere`]: `1/(2π)` for `w.z ≥ 0`, else 0 (solid angle).
#[inline]
pub fn uniform_hemisphere_pdf(w: Vec3) -> f32 {
    if w.z >= 0.0 {
        INV_2PI
    } else {
        0.0
    }
}

/// Inverse of [`sample_uniform_hemisphere`]: `u = (1 - z, φ / 2π)`.
#[inline]
pub fn invert_uniform_hemisphere(w: Vec3) -> Vec2 {
    Vec2::new(1.0 - w.z, (spherical_phi(w) * INV_2PI).min(ONE_MINUS_EPSILON))
}

/// Cosine-weighted hemisphere by Malley's method: a concentric-disk sample lifted to the
/// hemisphere. Domain `u ∈ [0,1)²`; value: unit direction with z ≥ 0; pdf `cos θ / π`,
/// solid-angle measure.
#[inline]
pub fn sample_cosine_hemisphere_malley(u: Vec2) -> Sample<Vec3> {
    let d = sample_uniform_disk_concentric(u).value;
    // u.x = 0 or u.y = 0 lands exactly on the rim (z = 0, pdf 0) with probability 2⁻²³ in f32;
    // keeping z a hair above the horizon keeps such samples valid (pdf > 0).
    let z = safe_sqrt(1.0 - d.length_squared()).max(1e-7);
    Sample::solid_angle(Vec3::new(d.x, d.y, z), z * INV_PI)
}

/// Inverse of [`sample_cosine_hemisphere_malley`]: the concentric inverse of `(w.x, w.y)`.
#[inline]
pub fn invert_cosine_hemisphere_malley(w: Vec3) -> Vec2 {
    invert_uniform_disk_concentric(Vec2::new(w.x, w.y))
}

/// Cosine-weighted hemisphere by inverting the CDF of θ: `sin θ = √u.x` (θ = asin √ξ₁),
/// `φ = 2π u.y`. Domain `u ∈ [0,1)²`; pdf `cos θ / π`, solid-angle measure.
#[inline]
pub fn sample_cosine_hemisphere_inversion(u: Vec2) -> Sample<Vec3> {
    let sin_theta = u.x.sqrt();
    let cos_theta = safe_sqrt(1.0 - u.x);
    let (s, c) = crate::math::sin_cos_2pi(u.y);
    Sample::solid_angle(Vec3::new(sin_theta * c, sin_theta * s, cos_theta), cos_theta * INV_PI)
}

/// Inverse of [`sample_cosine_hemisphere_inversion`]: `u = (sin² θ, φ / 2π)`.
#[inline]
pub fn invert_cosine_hemisphere_inversion(w: Vec3) -> Vec2 {
    Vec2::new(w.x * w.x + w.y * w.y, (spherical_phi(w) * INV_2PI).min(ONE_MINUS_EPSILON))
}

/// Density of the cosine-weighted hemisphere: `max(cos θ, 0) / π` (solid angle).
#[inline]
pub fn cosine_hemisphere_pdf(w: Vec3) -> f32 {
    w.z.max(0.0) * INV_PI
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{check_inverse, chi2_2d, chi2_two_sample_2d, integrate_pdf_2d, u2, Chi2Config, HEMISPHERE};

    #[test]
    fn uniform_chi2_and_normalization() {
        let cfg = Chi2Config::default();
        let out = chi2_2d(
            &HEMISPHERE,
            [15, 31],
            1_000_000,
            |r| Some(sample_uniform_hemisphere(u2(r)).value),
            |w| uniform_hemisphere_pdf(*w) as f64,
            &cfg,
        );
        assert!(out.passed(), "{out}");
        assert!((integrate_pdf_2d(&HEMISPHERE, [16, 16], |w| uniform_hemisphere_pdf(*w) as f64) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn cosine_malley_chi2() {
        let out = chi2_2d(
            &HEMISPHERE,
            [15, 31],
            1_000_000,
            |r| Some(sample_cosine_hemisphere_malley(u2(r)).value),
            |w| cosine_hemisphere_pdf(*w) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
    }

    #[test]
    fn cosine_inversion_chi2() {
        let out = chi2_2d(
            &HEMISPHERE,
            [15, 31],
            1_000_000,
            |r| Some(sample_cosine_hemisphere_inversion(u2(r)).value),
            |w| cosine_hemisphere_pdf(*w) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        assert!((integrate_pdf_2d(&HEMISPHERE, [16, 16], |w| cosine_hemisphere_pdf(*w) as f64) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn malley_and_inversion_agree_in_distribution() {
        let out = chi2_two_sample_2d(
            &HEMISPHERE,
            [13, 27],
            1_000_000,
            |r| Some(sample_cosine_hemisphere_malley(u2(r)).value),
            |r| Some(sample_cosine_hemisphere_inversion(u2(r)).value),
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
    }

    #[test]
    fn returned_pdfs_match_pdf_functions() {
        let mut rng = crate::sampling::Pcg32::new(9, 9);
        for _ in 0..10_000 {
            let u = u2(&mut rng);
            let s = sample_uniform_hemisphere(u);
            assert_eq!(s.pdf, uniform_hemisphere_pdf(s.value));
            for s in [sample_cosine_hemisphere_malley(u), sample_cosine_hemisphere_inversion(u)] {
                assert!((s.pdf - cosine_hemisphere_pdf(s.value)).abs() < 1e-6);
                assert!((s.value.length() - 1.0).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn inverses_round_trip() {
        type Warp = (fn(Vec2) -> Sample<Vec3>, fn(Vec3) -> Vec2);
        let cases: [Warp; 3] = [
            (sample_uniform_hemisphere, invert_uniform_hemisphere),
            (sample_cosine_hemisphere_malley, invert_cosine_hemisphere_malley),
            (sample_cosine_hemisphere_inversion, invert_cosine_hemisphere_inversion),
        ];
        for (i, (s, inv)) in cases.into_iter().enumerate() {
            let e = check_inverse(100_000, i as u64, 1e-3, |u| Some(s(u).value), |w| Some(inv(*w)));
            assert!(e < 2e-3, "case {i}: inverse error {e}");
        }
    }
}
