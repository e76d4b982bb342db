//! Uniform sampling of the unit disk: polar mapping and Shirley–Chiu concentric mapping.
//!
//! Both map `[0,1)²` onto the unit disk with constant density `1/π` per unit area. The polar
//! map (`r = √ξ₁, φ = 2πξ₂`, the inversion method applied to the marginal `p(r) = 2r`) is the
//! simplest; the concentric map (Shirley & Chiu 1997) sends concentric squares to concentric
//! circles, distorting areas less, so stratified `u` stay well stratified on the disk. The
//! rejection version lives in [`super::rejection`].

use super::Sample;
use crate::math::{sin_cos_quarter, Vec2, INV_PI, PI};
use std::f32::consts::FRAC_PI_4;

/// Polar mapping: `r = √u.x`, `φ = 2π u.y`. Domain `u ∈ [0,1)²`; value: point of the unit
/// disk; pdf `1/π`, area measure.
#[inline]
pub fn sample_uniform_disk_polar(u: Vec2) -> Sample<Vec2> {
    let r = u.x.sqrt();
    let (s, c) = crate::math::sin_cos_2pi(u.y);
    Sample::area(Vec2::new(r * c, r * s), INV_PI)
}

/// Inverse of [`sample_uniform_disk_polar`]: `u = (r², φ / 2π)`.
#[inline]
pub fn invert_uniform_disk_polar(p: Vec2) -> Vec2 {
    let mut phi = p.y.atan2(p.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    Vec2::new(p.length_squared(), (phi / (2.0 * PI)).min(crate::math::ONE_MINUS_EPSILON))
}

/// Concentric mapping (Shirley–Chiu): the square `[-1,1]²` (from `2u - 1`) is split into four
/// triangular wedges, each mapped to a quarter of the disk with radius equal to the larger
/// coordinate. Domain `u ∈ [0,1)²`; pdf `1/π`, area measure.
#[inline]
pub fn sample_uniform_disk_concentric(u: Vec2) -> Sample<Vec2> {
    let a = 2.0 * u - Vec2::ONE;
    if a.x == 0.0 && a.y == 0.0 {
        return Sample::area(Vec2::ZERO, INV_PI);
    }
    // θ = π/4 · (a.y / a.x) in the wedges around ±x; θ = π/2 - π/4 · (a.x / a.y) around ±y,
    // whose sine and cosine are the cosine and sine of π/4 · (a.x / a.y).
    let (r, sin_theta, cos_theta) = if a.x.abs() > a.y.abs() {
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (a.y / a.x));
        (a.x, s, c)
    } else {
        let (s, c) = sin_cos_quarter(FRAC_PI_4 * (a.x / a.y));
        (a.y, c, s)
    };
    Sample::area(Vec2::new(r * cos_theta, r * sin_theta), INV_PI)
}

/// Inverse of [`sample_uniform_disk_concentric`].
pub fn invert_uniform_disk_concentric(p: Vec2) -> Vec2 {
    let r = p.length();
    let mut theta = p.y.atan2(p.x);
    if theta < -FRAC_PI_4 {
        theta += 2.0 * PI;
    }
    let (a, b);
    if theta < FRAC_PI_4 {
        a = r;
        b = theta * a / FRAC_PI_4;
    } else if theta < 3.0 * FRAC_PI_4 {
        b = r;
        a = -(theta - 2.0 * FRAC_PI_4) * b / FRAC_PI_4;
    } else if theta < 5.0 * FRAC_PI_4 {
        a = -r;
        b = (theta - PI) * a / FRAC_PI_4;
    } else {
        b = -r;
        a = -(theta - 6.0 * FRAC_PI_4) * b / FRAC_PI_4;
    }
    Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

/// Density of the uniform disk at `p`: `1/π` inside the unit disk, 0 outside (area measure).
#[inline]
pub fn uniform_disk_pdf(p: Vec2) -> f32 {
    if p.length_squared() <= 1.0 {
        INV_PI
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{check_inverse, chi2_2d, integrate_pdf_2d, u2, Chi2Config, Disk};

    fn pdf(p: &Vec2) -> f64 {
        uniform_disk_pdf(*p) as f64
    }

    #[test]
    fn polar_chi2() {
        let out = chi2_2d(
            &Disk,
            [15, 31],
            1_000_000,
            |r| Some(sample_uniform_disk_polar(u2(r)).value),
            pdf,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
    }

    #[test]
    fn concentric_chi2() {
        let out = chi2_2d(
            &Disk,
            [15, 31],
            1_000_000,
            |r| Some(sample_uniform_disk_concentric(u2(r)).value),
            pdf,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
    }

    #[test]
    fn pdf_integrates_to_one_and_matches_samples() {
        assert!((integrate_pdf_2d(&Disk, [32, 32], pdf) - 1.0).abs() < 1e-6);
        let mut rng = crate::sampling::Pcg32::new(1, 1);
        for _ in 0..1000 {
            let u = u2(&mut rng);
            for s in [sample_uniform_disk_polar(u), sample_uniform_disk_concentric(u)] {
                assert_eq!(s.pdf, uniform_disk_pdf(s.value));
                assert_eq!(s.measure, crate::sampling::Measure::Area);
            }
        }
    }

    #[test]
    fn inverses_round_trip() {
        let e = check_inverse(
            100_000,
            3,
            1e-4,
            |u| Some(sample_uniform_disk_polar(u).value),
            |p| Some(invert_uniform_disk_polar(*p)),
        );
        assert!(e < 1e-4, "polar inverse error {e}");
        let e = check_inverse(
            100_000,
            4,
            1e-4,
            |u| Some(sample_uniform_disk_concentric(u).value),
            |p| Some(invert_uniform_disk_concentric(*p)),
        );
        assert!(e < 1e-4, "concentric inverse error {e}");
    }

    #[test]
    fn concentric_maps_square_edges_to_circle() {
        for t in [0.0f32, 0.1, 0.5, 0.9] {
            for u in [Vec2::new(t, 0.0), Vec2::new(0.0, t), Vec2::new(t, 1.0), Vec2::new(1.0, t)] {
                let p = sample_uniform_disk_concentric(u).value;
                assert!((p.length() - 1.0).abs() < 1e-5, "{u} -> {p}");
            }
        }
        assert_eq!(sample_uniform_disk_concentric(Vec2::splat(0.5)).value, Vec2::ZERO);
    }
}
