//! Clarberg's equal-area octahedral mapping between the unit square and the unit sphere
//! (pbrt-v4's `EqualAreaSquareToSphere` / `EqualAreaSphereToSquare`, the layout of pbrt-v4's
//! environment maps): the square `[0,1]²` folds onto an octahedron whose centre is the +z pole
//! and whose corners are −z. Every region of the square maps to a region of the sphere of 4π
//! times its area, so a uniform point of the square is a uniform direction (pdf `1/4π`).

use crate::math::{Vec2, Vec3, PI};
use crate::sampling::Sample;

/// The direction of square coordinates `p ∈ [0,1]²`, and its pdf `1/4π` for uniform `p`.
pub fn sample_equal_area_sphere(p: Vec2) -> Sample<Vec3> {
    Sample::solid_angle(equal_area_square_to_sphere(p), crate::math::INV_4PI)
}

/// The direction of square coordinates `p ∈ [0,1]²`.
#[inline]
pub fn equal_area_square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    // Signed distance from the diagonal |u| + |v| = 1 (the equator): positive inside (z > 0).
    let signed = 1.0 - (up + vp);
    let r = 1.0 - signed.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * (PI / 4.0);
    let z = (1.0 - r * r).copysign(signed);
    let cos_phi = phi.cos().copysign(u);
    let sin_phi = phi.sin().copysign(v);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi * s, sin_phi * s, z)
}

/// The square coordinates of a unit direction (inverse of [`equal_area_square_to_sphere`]).
#[inline]
pub fn equal_area_sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs().min(1.0));
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let b = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = b.atan() * (2.0 / PI);
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    Vec2::new(0.5 * (u.copysign(d.x) + 1.0), 0.5 * (v.copysign(d.y) + 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, u2, Chi2Config, SPHERE};

    #[test]
    fn round_trips_and_poles() {
        let mut rng = crate::sampling::Pcg32::new(1, 1);
        for _ in 0..10_000 {
            let p = u2(&mut rng);
            let d = equal_area_square_to_sphere(p);
            assert!((d.length() - 1.0).abs() < 1e-5, "{p} -> {d}");
            let q = equal_area_sphere_to_square(d);
            assert!((q - p).abs().max_element() < 2e-4, "{p} -> {d} -> {q}");
        }
        assert!((equal_area_square_to_sphere(Vec2::splat(0.5)) - Vec3::Z).length() < 1e-6);
        assert!((equal_area_square_to_sphere(Vec2::ZERO) + Vec3::Z).length() < 1e-6);
        assert!((equal_area_square_to_sphere(Vec2::new(1.0, 0.5)) - Vec3::X).length() < 1e-6);
        assert!((equal_area_square_to_sphere(Vec2::new(0.5, 1.0)) - Vec3::Y).length() < 1e-6);
    }

    #[test]
    fn uniform_square_is_uniform_sphere() {
        let out = chi2_2d(
            &SPHERE,
            [31, 61],
            300_000,
            |r| Some(sample_equal_area_sphere(u2(r)).value),
            |_| crate::math::INV_4PI as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
    }
}
