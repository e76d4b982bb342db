//! The power distribution `p(x) = (n+1) xⁿ` on `[0, 1]` and the cosine-power lobe on the
//! hemisphere (Phong/Blinn lobes).
//!
//! Inversion: `F(x) = x^(n+1)`, so `x = ξ^(1/(n+1))`. On the hemisphere, a lobe
//! `p(ω) ∝ cosⁿ θ` per solid angle has `cos θ` distributed with density `(n+1) cosⁿθ` on
//! `[0, 1]` (because `dω = d cos θ dφ`), hence `cos θ = ξ₁^(1/(n+1))`, `φ = 2π ξ₂`, and the
//! normalized density `p(ω) = (n+1)/(2π) cosⁿ θ`. The materials layer uses it for Blinn–Phong
//! microfacet normals (`cos θ_h = ξ^(1/(n+2))` is the case `n → n+1` of the same law).

use super::Sample;
use crate::math::{safe_sqrt, spherical_phi, Vec2, Vec3, INV_2PI, ONE_MINUS_EPSILON};

/// `x = u^(1/(n+1))` on `[0, 1]` for exponent `n > -1`. Domain `u ∈ [0,1)`; pdf `(n+1) xⁿ`,
/// length measure.
#[inline]
pub fn sample_power(u: f32, n: f32) -> Sample<f32> {
    let x = u.powf(1.0 / (n + 1.0));
    Sample::length(x, power_pdf(x, n))
}

/// Density `(n+1) xⁿ` on `[0, 1]`, 0 elsewhere (length measure).
#[inline]
pub fn power_pdf(x: f32, n: f32) -> f32 {
    if (0.0..=1.0).contains(&x) {
        (n + 1.0) * x.powf(n)
    } else {
        0.0
    }
}

/// Inverse (the CDF): `u = x^(n+1)`.
#[inline]
pub fn invert_power(x: f32, n: f32) -> f32 {
    x.powf(n + 1.0)
}

/// Direction with density `(n+1)/(2π) cosⁿ θ` about +z: `cos θ = u.x^(1/(n+1))`, `φ = 2π u.y`.
/// Domain `u ∈ [0,1)²`, exponent `n ≥ 0`; solid-angle measure.
#[inline]
pub fn sample_power_cosine_hemisphere(u: Vec2, n: f32) -> Sample<Vec3> {
    let cos_theta = u.x.powf(1.0 / (n + 1.0));
    let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    let (s, c) = crate::math::sin_cos_2pi(u.y);
    let w = Vec3::new(sin_theta * c, sin_theta * s, cos_theta);
    Sample::solid_angle(w, power_cosine_hemisphere_pdf(w, n))
}

/// Density of [`sample_power_cosine_hemisphere`]: `(n+1)/(2π) cosⁿ θ` for `cos θ > 0`, else 0.
#[inline]
pub fn power_cosine_hemisphere_pdf(w: Vec3, n: f32) -> f32 {
    if w.z <= 0.0 {
        0.0
    } else {
        (n + 1.0) * INV_2PI * w.z.powf(n)
    }
}

/// Inverse of [`sample_power_cosine_hemisphere`]: `u = (cos^(n+1) θ, φ / 2π)`.
#[inline]
pub fn invert_power_cosine_hemisphere(w: Vec3, n: f32) -> Vec2 {
    Vec2::new(w.z.max(0.0).powf(n + 1.0), (spherical_phi(w) * INV_2PI).min(ONE_MINUS_EPSILON))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{
        check_inverse, chi2_1d, chi2_2d, integrate_pdf_1d, integrate_pdf_2d, ks_1d, u2, Chi2Config, HEMISPHERE,
    };

    #[test]
    fn power_chi2_ks_and_normalization() {
        for (k, &n) in [0.0f32, 1.0, 4.5, 20.0, 200.0].iter().enumerate() {
            let cfg = Chi2Config::default().with_seed(k as u64);
            let out = chi2_1d(
                (0.0, 1.0),
                50,
                500_000,
                |r| Some(sample_power(r.next_f32(), n).value as f64),
                |x| power_pdf(x as f32, n) as f64,
                &cfg,
            );
            assert!(out.passed(), "n = {n}: {out}");
            let ks = ks_1d(
                100_000,
                |r| sample_power(r.next_f32(), n).value as f64,
                |x| (x.clamp(0.0, 1.0)).powf(n as f64 + 1.0),
                &cfg,
            );
            assert!(ks.passed(), "n = {n}: {ks}");
            assert!((integrate_pdf_1d((0.0, 1.0), 200, |x| power_pdf(x as f32, n) as f64) - 1.0).abs() < 1e-4);
            for u in [0.1f32, 0.5, 0.9] {
                let s = sample_power(u, n);
                assert!((invert_power(s.value, n) - u).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn cosine_power_lobe_chi2() {
        for (k, &n) in [0.0f32, 1.0, 10.0, 100.0].iter().enumerate() {
            let cfg = Chi2Config::default().with_seed(10 + k as u64);
            let out = chi2_2d(
                &HEMISPHERE,
                [31, 15],
                1_000_000,
                |r| Some(sample_power_cosine_hemisphere(u2(r), n).value),
                |w| power_cosine_hemisphere_pdf(*w, n) as f64,
                &cfg,
            );
            assert!(out.passed(), "n = {n}: {out}");
            let total = integrate_pdf_2d(&HEMISPHERE, [256, 4], |w| power_cosine_hemisphere_pdf(*w, n) as f64);
            assert!((total - 1.0).abs() < 1e-4, "n = {n}: ∫pdf = {total}");
            let e = check_inverse(
                50_000,
                k as u64,
                1e-3,
                |u| Some(sample_power_cosine_hemisphere(u, n).value),
                |w| Some(invert_power_cosine_hemisphere(*w, n)),
            );
            assert!(e < 5e-3, "n = {n}: inverse error {e}");
        }
    }
}
