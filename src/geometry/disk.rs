//! Disks: the unit disk in the local xy plane (normal +z), placed by a transform (Mitsuba's
//! `disk` shape), optionally partial (pbrt-v4's `innerradius` and `phimax`: an annulus, a
//! sector). Analytic intersection and uniform area sampling.

use super::sphere::SurfacePoint;
use crate::math::float::gamma;
use crate::math::{Ray, Transform, Vec2, Vec3, PI};
use crate::sampling::sample_uniform_disk_concentric;

/// A disk: the image of the unit disk `{x² + y² ≤ 1, z = 0}` under `to_world` (any affine map:
/// an ellipse in general). Its area is `π |M e_x × M e_y|`.
#[derive(Clone, Copy, Debug)]
pub struct Disk {
    to_world: Transform,
    to_object: Transform,
    n: Vec3,
    area: f32,
    /// pbrt-v4's (u, v) = (φ/2π, 1 − r) instead of Mitsuba's (r, φ/2π).
    pbrt_uv: bool,
    /// Radius of the hole (local units, `[0, 1)`).
    inner: f32,
    /// Largest azimuth `φ = atan2(y, x) ∈ [0, 2π)` kept, radians in `(0, 2π]`.
    phi_max: f32,
}

impl Disk {
    /// The unit disk placed by `to_world`; `flip` reverses the normal. `None` for a transform
    /// that flattens the disk to zero area.
    pub fn new(to_world: Transform, flip: bool) -> Option<Disk> {
        let ex = to_world.apply_vector(Vec3::X);
        let ey = to_world.apply_vector(Vec3::Y);
        let cross = ex.cross(ey);
        let area = PI * cross.length();
        if !(area > 0.0 && area.is_finite()) {
            return None;
        }
        let mut n = to_world.apply_normal(Vec3::Z).normalize();
        if flip {
            n = -n;
        }
        Some(Disk { to_world, to_object: to_world.inverse(), n, area, pbrt_uv: false, inner: 0.0, phi_max: 2.0 * PI })
    }

    /// The same disk without the points closer to the centre than `inner` (local units, the
    /// disk's radius being 1) or at an azimuth beyond `phi_max` (radians): pbrt-v4's partial
    /// disk. `None` if nothing is left.
    pub fn partial(self, inner: f32, phi_max: f32) -> Option<Disk> {
        let phi_max = phi_max.min(2.0 * PI);
        if !((0.0..1.0).contains(&inner) && phi_max > 0.0) {
            return None;
        }
        let area = self.area * (1.0 - inner * inner) * phi_max / (2.0 * PI);
        Some(Disk { inner, phi_max, area, ..self })
    }

    /// Whether pbrt-v4's `innerradius` or `phimax` cut part of the disk away.
    #[inline]
    fn is_partial(&self) -> bool {
        self.inner > 0.0 || self.phi_max < 2.0 * PI
    }

    /// The same disk with pbrt-v4's parameterization: (u, v) = (φ/2π, 1 − r).
    pub fn with_pbrt_uv(self) -> Disk {
        Disk { pbrt_uv: true, ..self }
    }

    /// Surface area.
    pub fn area(&self) -> f32 {
        self.area
    }

    /// Unit normal (front side).
    pub fn normal(&self) -> Vec3 {
        self.n
    }

    /// Intersection in `(0, t_max)`: ray parameter and local point `(x, y)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec2)> {
        let r = self.to_object.apply_ray(ray);
        if r.d.z == 0.0 {
            return None;
        }
        let t = -r.o.z / r.d.z;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let x = r.o.x + t * r.d.x;
        let y = r.o.y + t * r.d.y;
        let r2 = x * x + y * y;
        if r2 > 1.0 {
            return None;
        }
        if self.is_partial()
            && (r2 < self.inner * self.inner || crate::math::spherical_phi(Vec3::new(x, y, 0.0)) > self.phi_max)
        {
            return None;
        }
        Some((t, Vec2::new(x, y)))
    }

    /// World point, error bound and normal of the local point `q`; `uv = (r, φ / 2π)` (pbrt's:
    /// `(φ / φ_max, (1 − r) / (1 − r_inner))`, which is `(φ / 2π, 1 − r)` for a whole disk).
    #[inline]
    pub fn surface(&self, q: Vec2) -> (SurfacePoint, Vec2) {
        let local = Vec3::new(q.x, q.y, 0.0);
        let p = self.to_world.apply_point(local);
        let m = self.to_world.matrix();
        let abs_lin = m.x_axis.truncate().abs() * local.x.abs() + m.y_axis.truncate().abs() * local.y.abs();
        let p_error = gamma(6) * (abs_lin + m.w_axis.truncate().abs());
        let phi = crate::math::spherical_phi(Vec3::new(q.x, q.y, 0.0));
        let uv = if self.pbrt_uv {
            Vec2::new(phi / self.phi_max, (1.0 - q.length()) / (1.0 - self.inner))
        } else {
            Vec2::new(q.length(), phi / (2.0 * PI))
        };
        (SurfacePoint { p, n: self.n, p_error }, uv)
    }

    /// `(∂p/∂u, ∂p/∂v)` at the local point `q` for `uv = (r, φ / 2π)`, as Mitsuba gives them:
    /// the radial direction (local +x at the centre) and `2π (−y, x, 0)`, turned to world space
    /// (pbrt's parameterization: `φ_max (−y, x, 0)` and `−(1 − r_inner)` times the radial
    /// direction).
    #[inline]
    pub fn dpduv(&self, q: Vec2) -> (Vec3, Vec3) {
        let r = q.length();
        let radial = if r > 0.0 { q / r } else { Vec2::X };
        let dr = self.to_world.apply_vector(Vec3::new(radial.x, radial.y, 0.0));
        if self.pbrt_uv {
            let dphi = self.to_world.apply_vector(Vec3::new(-q.y, q.x, 0.0) * self.phi_max);
            (dphi, -(1.0 - self.inner) * dr)
        } else {
            let dphi = self.to_world.apply_vector(Vec3::new(-q.y, q.x, 0.0) * (2.0 * PI));
            (dr, dphi)
        }
    }

    /// Uniform point on the disk (concentric map); pdf `1 / area` per unit area.
    pub fn sample_area(&self, u: Vec2) -> (SurfacePoint, f32) {
        (self.surface(self.sample_local(u)).0, 1.0 / self.area)
    }

    /// A local point uniform in area: the concentric map for a whole disk; for a partial one
    /// `r = √(r_inner² + u₀ (1 − r_inner²))`, `φ = u₁ φ_max`.
    #[inline]
    pub fn sample_local(&self, u: Vec2) -> Vec2 {
        if !self.is_partial() {
            return sample_uniform_disk_concentric(u).value;
        }
        let r = (self.inner * self.inner + u.x * (1.0 - self.inner * self.inner)).sqrt();
        let (s, c) = (u.y * self.phi_max).sin_cos();
        Vec2::new(r * c, r * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disk_intersection_area_and_normal() {
        let t = Transform::translate(Vec3::new(0.0, 0.0, 2.0)) * Transform::scale(Vec3::new(2.0, 1.0, 1.0)).unwrap();
        let d = Disk::new(t, false).unwrap();
        assert!((d.area() - 2.0 * PI).abs() < 1e-5);
        assert!((d.normal() - Vec3::Z).length() < 1e-6);
        let (t_hit, q) = d.intersect(&Ray::new(Vec3::new(1.5, 0.0, 0.0), Vec3::Z), f32::INFINITY).unwrap();
        assert!((t_hit - 2.0).abs() < 1e-6 && (q.x - 0.75).abs() < 1e-6);
        assert!(d.intersect(&Ray::new(Vec3::new(0.0, 1.5, 0.0), Vec3::Z), f32::INFINITY).is_none());
        assert!(Disk::new(t, true).unwrap().normal().z < 0.0);
        let mut rng = crate::sampling::Pcg32::new(1, 1);
        for _ in 0..1000 {
            let (sp, pdf) = d.sample_area(crate::testkit::u2(&mut rng));
            assert!((sp.p.z - 2.0).abs() < 1e-6 && (sp.p.x / 2.0).powi(2) + sp.p.y.powi(2) <= 1.0 + 1e-5);
            assert!((pdf - 1.0 / (2.0 * PI)).abs() < 1e-6);
        }
    }
}
