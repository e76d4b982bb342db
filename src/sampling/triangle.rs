//! Uniform sampling of a triangle.
//!
//! The seeds' formula: `u = 1 - √(1 - ξ₁)`, `v = ξ₂ √(1 - ξ₁)` are barycentric coordinates of
//! a uniform point. Derivation: the marginal density of `u` on the reference triangle
//! `{u, v ≥ 0, u + v ≤ 1}` is `2 (1 - u)`, with CDF `1 - (1 - u)²`; inverting gives
//! `u = 1 - √(1 - ξ₁)`; given `u`, `v` is uniform on `[0, 1 - u]`. The Jacobian of
//! `(ξ₁, ξ₂) ↦ (u, v)` is the constant 1/2, so the density is 2 on the reference triangle, i.e.
//! `1/A` per unit area on a triangle of area `A`.

use super::Sample;
use crate::math::{Vec2, Vec3};

/// Barycentrics `(b0, b1, b2)` of a uniform point on a triangle: `b1 = 1 - √(1 - u.x)`,
/// `b2 = u.y √(1 - u.x)`, `b0 = 1 - b1 - b2`. Domain `u ∈ [0,1)²`; pdf 2, area measure of the
/// reference triangle spanned by `(b1, b2)`.
#[inline]
pub fn sample_uniform_triangle(u: Vec2) -> Sample<Vec3> {
    let s = (1.0 - u.x).sqrt();
    let b1 = 1.0 - s;
    let b2 = u.y * s;
    Sample::area(Vec3::new((1.0 - b1 - b2).max(0.0), b1, b2), 2.0)
}

/// Inverse of [`sample_uniform_triangle`] from barycentrics `(b0, b1, b2)`:
/// `u.x = 1 - (1 - b1)²`, `u.y = b2 / (1 - b1)`.
#[inline]
pub fn invert_uniform_triangle(b: Vec3) -> Vec2 {
    let s = 1.0 - b.y;
    Vec2::new(1.0 - s * s, if s > 0.0 { (b.z / s).min(crate::math::ONE_MINUS_EPSILON) } else { 0.0 })
}

/// A uniform point on the triangle `(p0, p1, p2)`. Domain `u ∈ [0,1)²`; pdf `1 / area`
/// (`∞` for a degenerate triangle, which has no area to sample), area measure.
#[inline]
pub fn sample_triangle(p: [Vec3; 3], u: Vec2) -> Sample<Vec3> {
    let b = sample_uniform_triangle(u).value;
    let x = p[0] * b.x + p[1] * b.y + p[2] * b.z;
    Sample::area(x, 1.0 / triangle_area(p))
}

/// Area of the triangle `(p0, p1, p2)`.
#[inline]
pub fn triangle_area(p: [Vec3; 3]) -> f32 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{check_inverse, chi2_2d, integrate_pdf_2d, u2, Chi2Config, Triangle};

    #[test]
    fn triangle_chi2_on_several_shapes() {
        let shapes = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.5), Vec3::new(-1.0, -1.0, 3.0)],
            // A sliver.
            [Vec3::ZERO, Vec3::new(10.0, 0.0, 0.0), Vec3::new(5.0, 0.05, 0.0)],
        ];
        for (k, p) in shapes.into_iter().enumerate() {
            let cfg = Chi2Config::default().with_seed(k as u64);
            let area = triangle_area(p) as f64;
            let out = chi2_2d(
                &Triangle { p },
                [15, 15],
                1_000_000,
                |r| Some(sample_triangle(p, u2(r)).value),
                |_| 1.0 / area,
                &cfg,
            );
            assert!(out.passed(), "triangle {k}: {out}");
            assert!((integrate_pdf_2d(&Triangle { p }, [8, 8], |_| 1.0 / area) - 1.0).abs() < 1e-6);
            let s = sample_triangle(p, Vec2::new(0.3, 0.7));
            assert!((s.pdf as f64 - 1.0 / area).abs() < 1e-6 / area);
        }
    }

    #[test]
    fn barycentrics_are_valid_and_invert() {
        let mut rng = crate::sampling::Pcg32::new(2, 2);
        for _ in 0..10_000 {
            let b = sample_uniform_triangle(u2(&mut rng)).value;
            assert!(b.min_element() >= 0.0 && (b.x + b.y + b.z - 1.0).abs() < 1e-6);
        }
        let e = check_inverse(
            100_000,
            6,
            1e-4,
            |u| Some(sample_uniform_triangle(u).value),
            |b| Some(invert_uniform_triangle(*b)),
        );
        assert!(e < 1e-3, "{e}");
    }
}
