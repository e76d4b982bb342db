//! 2D domains on which samples are histogrammed, each with a rectangular parameterization.
//!
//! A domain maps its points to parameters `(s, t)` in a rectangle and back, and reports the
//! Jacobian `dμ / ds dt` of its natural measure μ (area for planar domains, solid angle for
//! directions). The density of samples in parameter space is then `pdf(x) · jacobian`, which the
//! harness integrates over each histogram cell. Parameterizations are chosen so that densities
//! stay smooth (no cell straddles the support's edge): the disk is parameterized by (r, φ),
//! directions by (cos θ, φ), a triangle by a collapsed square.

use glam::{Vec2, Vec3};
use std::f64::consts::PI;

/// A 2D sampling domain with a rectangular parameterization.
pub trait Domain {
    /// The sampled point type (`Vec2` for planar domains, `Vec3` for directions and 3D points).
    type Point;
    /// Parameter rectangle `[[s0, t0], [s1, t1]]`.
    fn bounds(&self) -> [[f64; 2]; 2];
    /// Parameters of `x`, or `None` if `x` is not on the domain (outside it, or a direction
    /// that is not unit length): the harness treats that as a failure.
    fn to_param(&self, x: &Self::Point) -> Option<[f64; 2]>;
    /// The point at parameters `p` and the Jacobian `dμ/(ds dt)` there.
    fn param_to_point(&self, p: [f64; 2]) -> (Self::Point, f64);
    /// Short name used in reports.
    fn name(&self) -> String;
}

const UNIT_TOL: f32 = 1e-3;

/// An axis-aligned rectangle of the plane, area measure, identity parameterization.
#[derive(Clone, Copy, Debug)]
pub struct Rect {
    /// Lower corner.
    pub min: [f64; 2],
    /// Upper corner.
    pub max: [f64; 2],
}

impl Rect {
    /// The unit square `[0, 1]²`.
    pub const UNIT: Rect = Rect { min: [0.0, 0.0], max: [1.0, 1.0] };
}

impl Domain for Rect {
    type Point = Vec2;
    fn bounds(&self) -> [[f64; 2]; 2] {
        [self.min, self.max]
    }
    fn to_param(&self, x: &Vec2) -> Option<[f64; 2]> {
        let p = [x.x as f64, x.y as f64];
        let inside = (0..2).all(|i| p[i] >= self.min[i] && p[i] <= self.max[i]);
        inside.then_some(p)
    }
    fn param_to_point(&self, p: [f64; 2]) -> (Vec2, f64) {
        (Vec2::new(p[0] as f32, p[1] as f32), 1.0)
    }
    fn name(&self) -> String {
        format!("rect {:?}-{:?}", self.min, self.max)
    }
}

/// The unit disk in the plane, area measure, parameterized by (r, φ) ∈ \[0, 1\] × \[0, 2π) with
/// Jacobian r.
#[derive(Clone, Copy, Debug)]
pub struct Disk;

impl Domain for Disk {
    type Point = Vec2;
    fn bounds(&self) -> [[f64; 2]; 2] {
        [[0.0, 0.0], [1.0, 2.0 * PI]]
    }
    fn to_param(&self, x: &Vec2) -> Option<[f64; 2]> {
        let r = (x.x as f64).hypot(x.y as f64);
        if r > 1.0 + 1e-6 {
            return None;
        }
        Some([r.min(1.0), phi(x.x as f64, x.y as f64)])
    }
    fn param_to_point(&self, p: [f64; 2]) -> (Vec2, f64) {
        let (s, c) = p[1].sin_cos();
        (Vec2::new((p[0] * c) as f32, (p[0] * s) as f32), p[0])
    }
    fn name(&self) -> String {
        "unit disk".into()
    }
}

/// Unit directions with `cos θ ∈ [z_min, 1]` (a spherical cap about +z), solid-angle measure,
/// parameterized by (cos θ, φ) with Jacobian 1 (dω = d cos θ dφ).
#[derive(Clone, Copy, Debug)]
pub struct SphericalCap {
    /// Smallest cos θ on the cap: -1 for the sphere, 0 for the hemisphere.
    pub z_min: f64,
}

/// All unit directions (a cap with `z_min = -1`).
pub const SPHERE: SphericalCap = SphericalCap { z_min: -1.0 };
/// Unit directions of the upper hemisphere (z ≥ 0).
pub const HEMISPHERE: SphericalCap = SphericalCap { z_min: 0.0 };

impl Domain for SphericalCap {
    type Point = Vec3;
    fn bounds(&self) -> [[f64; 2]; 2] {
        [[self.z_min, 0.0], [1.0, 2.0 * PI]]
    }
    fn to_param(&self, w: &Vec3) -> Option<[f64; 2]> {
        if (w.length() - 1.0).abs() > UNIT_TOL || !w.is_finite() {
            return None;
        }
        let z = w.z as f64;
        if z < self.z_min - 1e-6 {
            return None;
        }
        Some([z.clamp(self.z_min, 1.0), phi(w.x as f64, w.y as f64)])
    }
    fn param_to_point(&self, p: [f64; 2]) -> (Vec3, f64) {
        let z = p[0];
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (s, c) = p[1].sin_cos();
        (Vec3::new((r * c) as f32, (r * s) as f32, z as f32), 1.0)
    }
    fn name(&self) -> String {
        if self.z_min == -1.0 {
            "sphere".into()
        } else if self.z_min == 0.0 {
            "hemisphere".into()
        } else {
            format!("spherical cap cos θ ≥ {}", self.z_min)
        }
    }
}

/// A triangle in 3D, area measure. Parameters (a, b) ∈ \[0, 1\]² map to the barycentrics
/// `b1 = a (1 - b)`, `b2 = a b`, i.e. the point `p0 + b1 (p1 - p0) + b2 (p2 - p0)`: the unit
/// square collapsed onto the triangle at `p0`, with Jacobian `2 A a` (A = triangle area).
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    /// Vertices.
    pub p: [Vec3; 3],
}

impl Triangle {
    fn area(&self) -> f64 {
        let e1 = (self.p[1] - self.p[0]).as_dvec3();
        let e2 = (self.p[2] - self.p[0]).as_dvec3();
        0.5 * e1.cross(e2).length()
    }
}

impl Domain for Triangle {
    type Point = Vec3;
    fn bounds(&self) -> [[f64; 2]; 2] {
        [[0.0, 0.0], [1.0, 1.0]]
    }
    fn to_param(&self, x: &Vec3) -> Option<[f64; 2]> {
        // Barycentrics by least squares in double precision.
        let e1 = (self.p[1] - self.p[0]).as_dvec3();
        let e2 = (self.p[2] - self.p[0]).as_dvec3();
        let d = x.as_dvec3() - self.p[0].as_dvec3();
        let (a11, a12, a22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (r1, r2) = (e1.dot(d), e2.dot(d));
        let det = a11 * a22 - a12 * a12;
        let b1 = (a22 * r1 - a12 * r2) / det;
        let b2 = (a11 * r2 - a12 * r1) / det;
        let off_plane = (d - e1 * b1 - e2 * b2).length();
        let scale = e1.length().max(e2.length());
        let tol = 1e-5;
        if off_plane > tol * scale || b1 < -tol || b2 < -tol || b1 + b2 > 1.0 + tol {
            return None;
        }
        let a = (b1 + b2).clamp(0.0, 1.0);
        let b = if a > 0.0 { (b2 / a).clamp(0.0, 1.0) } else { 0.0 };
        Some([a, b])
    }
    fn param_to_point(&self, p: [f64; 2]) -> (Vec3, f64) {
        let (a, b) = (p[0], p[1]);
        let b1 = a * (1.0 - b);
        let b2 = a * b;
        let x = self.p[0].as_dvec3() * (1.0 - b1 - b2) + self.p[1].as_dvec3() * b1 + self.p[2].as_dvec3() * b2;
        (x.as_vec3(), 2.0 * self.area() * a)
    }
    fn name(&self) -> String {
        format!("triangle {:?}", self.p)
    }
}

fn phi(x: f64, y: f64) -> f64 {
    let p = y.atan2(x);
    if p < 0.0 {
        (p + 2.0 * PI).min(2.0 * PI)
    } else {
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip<D: Domain>(d: &D) {
        let [lo, hi] = d.bounds();
        for i in 1..10 {
            for j in 1..10 {
                let p = [lo[0] + (hi[0] - lo[0]) * i as f64 / 10.0, lo[1] + (hi[1] - lo[1]) * j as f64 / 10.0];
                let (x, jac) = d.param_to_point(p);
                assert!(jac >= 0.0);
                let q = d.to_param(&x).unwrap_or_else(|| panic!("{} rejects its own point", d.name()));
                assert!((q[0] - p[0]).abs() < 1e-4 && (q[1] - p[1]).abs() < 1e-4, "{}: {p:?} -> {q:?}", d.name());
            }
        }
    }

    #[test]
    fn parameterizations_round_trip() {
        round_trip(&Rect::UNIT);
        round_trip(&Disk);
        round_trip(&SPHERE);
        round_trip(&HEMISPHERE);
        round_trip(&SphericalCap { z_min: 0.7 });
        round_trip(&Triangle { p: [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.5), Vec3::new(-1.0, -1.0, 3.0)] });
    }

    #[test]
    fn points_off_the_domain_are_rejected() {
        assert!(Disk.to_param(&Vec2::new(0.9, 0.9)).is_none());
        assert!(HEMISPHERE.to_param(&Vec3::new(0.0, 0.0, -1.0)).is_none());
        assert!(SPHERE.to_param(&Vec3::new(0.0, 0.0, 0.5)).is_none(), "non-unit direction");
        assert!(Rect::UNIT.to_param(&Vec2::new(1.5, 0.0)).is_none());
        let t = Triangle { p: [Vec3::ZERO, Vec3::X, Vec3::Y] };
        assert!(t.to_param(&Vec3::new(0.8, 0.8, 0.0)).is_none());
        assert!(t.to_param(&Vec3::new(0.2, 0.2, 0.1)).is_none());
    }

    #[test]
    fn jacobians_integrate_to_the_domain_measure() {
        fn measure<D: Domain>(d: &D) -> f64 {
            let [lo, hi] = d.bounds();
            let n = 64;
            let (hs, ht) = ((hi[0] - lo[0]) / n as f64, (hi[1] - lo[1]) / n as f64);
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    sum += crate::testkit::quadrature::gauss_legendre_5x5(
                        lo[0] + i as f64 * hs,
                        lo[0] + (i + 1) as f64 * hs,
                        lo[1] + j as f64 * ht,
                        lo[1] + (j + 1) as f64 * ht,
                        |s, t| d.param_to_point([s, t]).1,
                    );
                }
            }
            sum
        }
        assert!((measure(&Disk) - PI).abs() < 1e-9);
        assert!((measure(&SPHERE) - 4.0 * PI).abs() < 1e-9);
        assert!((measure(&HEMISPHERE) - 2.0 * PI).abs() < 1e-9);
        let t = Triangle { p: [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)] };
        assert!((measure(&t) - 3.0).abs() < 1e-9);
    }
}
