//! Cylinders (Mitsuba's `cylinder`): an open tube without caps, the image of the unit cylinder
//! `{x² + y² = 1, 0 ≤ z ≤ 1}` under an affine transform, intersected in the unit cylinder's
//! frame. Normals point outward (inward with `flip_normals`). A transform that scales x and y
//! uniformly (radius r) and keeps them perpendicular to the axis (length L) makes a round
//! cylinder of area `2π r L`, whose area sampling, uniform in `(φ, z)`, is uniform in area. Any
//! other makes an elliptic (or sheared) cylinder, as Mitsuba 3.9 and pbrt-v4 render it: its
//! area has no closed form (Mitsuba's `2π |to_world · x̂| |to_world · ẑ|` is kept for the
//! record) and uniform `(φ, z)` is not uniform in area, so it cannot emit
//! ([`Cylinder::is_elliptic`]). A partial cylinder (pbrt-v4's `phimax`) keeps the azimuths
//! `φ = atan2(y, x) ∈ [0, φ_max]` of the local frame.

use super::sphere::SurfacePoint;
use crate::math::float::gamma;
use crate::math::{Bounds3, Ray, Transform, Vec2, Vec3, PI};

/// A cylinder in world space.
#[derive(Clone, Copy, Debug)]
pub struct Cylinder {
    to_world: Transform,
    to_object: Transform,
    flip: bool,
    area: f32,
    /// Largest azimuth kept, radians in `(0, 2π]`.
    phi_max: f32,
    /// Whether the transform is not a similarity across the axis.
    elliptic: bool,
}

impl Cylinder {
    /// The cylinder from `p0` to `p1` of radius `radius`, then placed by `to_world` (Mitsuba's
    /// parameters; any invertible affine map). `None` if degenerate.
    pub fn new(p0: Vec3, p1: Vec3, radius: f32, to_world: Transform, flip: bool) -> Option<Cylinder> {
        let axis = p1 - p0;
        let len = axis.length();
        if !(len > 0.0 && radius > 0.0 && len.is_finite() && radius.is_finite()) {
            return None;
        }
        let frame = crate::math::Frame::from_z(axis / len);
        let basis = Transform::from_matrix(crate::math::Mat4::from_cols(
            (frame.s * radius).extend(0.0),
            (frame.t * radius).extend(0.0),
            axis.extend(0.0),
            p0.extend(1.0),
        ))?;
        let t = to_world * basis;
        let (ex, ey, ez) = (t.apply_vector(Vec3::X), t.apply_vector(Vec3::Y), t.apply_vector(Vec3::Z));
        let r = ex.length();
        let tol = 1e-4 * r;
        let elliptic = (ey.length() - r).abs() > tol
            || ex.dot(ey).abs() > tol * r
            || ex.dot(ez).abs() > tol * ez.length()
            || ey.dot(ez).abs() > tol * ez.length();
        let area = 2.0 * PI * r * ez.length();
        (area > 0.0 && area.is_finite()).then(|| Cylinder {
            to_world: t,
            to_object: t.inverse(),
            flip,
            area,
            phi_max: 2.0 * PI,
            elliptic,
        })
    }

    /// Whether the transform scales unevenly across the axis or tilts it (an elliptic or sheared
    /// cylinder, which cannot emit: see the module notes).
    pub fn is_elliptic(&self) -> bool {
        self.elliptic
    }

    /// The same cylinder keeping the azimuths up to `phi_max` radians (pbrt-v4's `phimax`; the
    /// local frame's x axis is the first vector of [`crate::math::Frame::from_z`] of the axis,
    /// which is +x for an axis along +z). `None` if nothing is left.
    pub fn partial(self, phi_max: f32) -> Option<Cylinder> {
        let phi_max = phi_max.min(2.0 * PI);
        (phi_max > 0.0).then(|| Cylinder { phi_max, area: self.area * phi_max / (2.0 * PI), ..self })
    }

    /// Surface area.
    pub fn area(&self) -> f32 {
        self.area
    }

    /// World bounds (the transformed bounds of the unit cylinder's box).
    pub fn bounds(&self) -> Bounds3 {
        self.to_world.apply_bounds(&Bounds3::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::ONE))
    }

    /// Closest intersection in `(0, t_max)`: ray parameter and the local hit point.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
        let r = self.to_object.apply_ray(ray);
        // Solve |o_xy + t d_xy|² = 1 in f64 (the quadratic loses precision at grazing angles).
        let (ox, oy, dx, dy) = (r.o.x as f64, r.o.y as f64, r.d.x as f64, r.d.y as f64);
        let a = dx * dx + dy * dy;
        if a == 0.0 {
            return None;
        }
        let b = 2.0 * (dx * ox + dy * oy);
        let c = ox * ox + oy * oy - 1.0;
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        let q = if b < 0.0 { -0.5 * (b - root) } else { -0.5 * (b + root) };
        let (mut t0, mut t1) = (q / a, if q != 0.0 { c / q } else { q / a });
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        for t in [t0, t1] {
            let t = t as f32;
            if !(t > 0.0 && t < t_max) {
                continue;
            }
            let z = r.o.z + t * r.d.z;
            if (0.0..=1.0).contains(&z) {
                let (x, y) = ((ox + t as f64 * dx) as f32, (oy + t as f64 * dy) as f32);
                if self.phi_max < 2.0 * PI && crate::math::spherical_phi(Vec3::new(x, y, 0.0)) > self.phi_max {
                    continue;
                }
                return Some((t, Vec3::new(x, y, z)));
            }
        }
        None
    }

    /// World point (reprojected onto the surface), error bound, normal and `uv = (φ/φ_max, z)`
    /// of a local point (`φ_max` = 2π but for a partial cylinder).
    #[inline]
    pub fn surface(&self, local: Vec3) -> (SurfacePoint, Vec2) {
        let rho = (local.x * local.x + local.y * local.y).sqrt().max(f32::MIN_POSITIVE);
        let q = Vec3::new(local.x / rho, local.y / rho, local.z.clamp(0.0, 1.0));
        let p = self.to_world.apply_point(q);
        let m = self.to_world.matrix();
        let abs_lin = m.x_axis.truncate().abs() * q.x.abs()
            + m.y_axis.truncate().abs() * q.y.abs()
            + m.z_axis.truncate().abs() * q.z.abs();
        let p_error = gamma(6) * (abs_lin + m.w_axis.truncate().abs());
        let mut n = self.to_world.apply_normal(Vec3::new(q.x, q.y, 0.0)).normalize();
        if self.flip {
            n = -n;
        }
        (
            SurfacePoint { p, n, p_error },
            Vec2::new(crate::math::spherical_phi(Vec3::new(q.x, q.y, 0.0)) / self.phi_max, q.z),
        )
    }

    /// `(∂p/∂u, ∂p/∂v)` at the local point `local` for `uv = (φ / φ_max, z)`, as Mitsuba gives
    /// them: `φ_max (−y, x, 0)` around the axis and the axis itself, turned to world space.
    #[inline]
    pub fn dpduv(&self, local: Vec3) -> (Vec3, Vec3) {
        let dpdu = self.to_world.apply_vector(Vec3::new(-local.y, local.x, 0.0) * self.phi_max);
        (dpdu, self.to_world.apply_vector(Vec3::Z))
    }

    /// Uniform point on the surface; pdf `1 / area` per unit area.
    pub fn sample_area(&self, u: Vec2) -> (SurfacePoint, f32) {
        (self.surface(self.sample_local(u)).0, 1.0 / self.area)
    }

    /// The local point of `u`, uniform in area: `φ = u₀ φ_max`, `z = u₁`.
    #[inline]
    pub fn sample_local(&self, u: Vec2) -> Vec3 {
        let (s, c) =
            if self.phi_max < 2.0 * PI { (u.x * self.phi_max).sin_cos() } else { crate::math::sin_cos_2pi(u.x) };
        Vec3::new(c, s, u.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tube() -> Cylinder {
        // Radius 0.5 from (1, 0, 0) to (1, 2, 0): axis along +y.
        Cylinder::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0), 0.5, Transform::IDENTITY, false).unwrap()
    }

    #[test]
    fn intersection_normal_area_and_bounds() {
        let c = tube();
        assert!((c.area() - 2.0 * PI * 0.5 * 2.0).abs() < 1e-5);
        // A ray along -z toward the axis hits the near wall at z = 0.5.
        let ray = Ray::new(Vec3::new(1.0, 1.0, 3.0), -Vec3::Z);
        let (t, local) = c.intersect(&ray, f32::INFINITY).unwrap();
        assert!((t - 2.5).abs() < 1e-5, "{t}");
        let (sp, uv) = c.surface(local);
        assert!((sp.p - Vec3::new(1.0, 1.0, 0.5)).length() < 1e-5, "{}", sp.p);
        assert!((sp.n - Vec3::Z).length() < 1e-5, "{}", sp.n);
        assert!((uv.y - 0.5).abs() < 1e-5);
        // From inside the tube the far wall is hit; beyond the ends nothing is.
        let inside = Ray::new(Vec3::new(1.0, 1.0, 0.0), Vec3::X);
        assert!((c.intersect(&inside, f32::INFINITY).unwrap().0 - 0.5).abs() < 1e-5);
        assert!(c.intersect(&Ray::new(Vec3::new(1.0, 2.5, 3.0), -Vec3::Z), f32::INFINITY).is_none());
        // Open ends: a ray along the axis passes through.
        assert!(c.intersect(&Ray::new(Vec3::new(1.0, -1.0, 0.0), Vec3::Y), f32::INFINITY).is_none());
        let b = c.bounds();
        assert!(b.min.x <= 0.5 + 1e-5 && b.max.x >= 1.5 - 1e-5 && b.min.y <= 1e-5 && b.max.y >= 2.0 - 1e-5);
        // Non-uniform scale across the axis makes an elliptic cylinder; flip turns the normal inward.
        let elliptic =
            Cylinder::new(Vec3::ZERO, Vec3::Z, 1.0, Transform::scale(Vec3::new(1.0, 2.0, 1.0)).unwrap(), false)
                .unwrap();
        assert!(elliptic.is_elliptic() && !c.is_elliptic());
        // pbrt-v4's phimax: along +z, φ = 0 is +x; a quarter tube keeps only x, y ≥ 0.
        let quarter =
            Cylinder::new(Vec3::ZERO, Vec3::Z, 1.0, Transform::IDENTITY, false).unwrap().partial(PI / 2.0).unwrap();
        let down =
            |x: f32, y: f32| Ray::new(Vec3::new(x, y, 0.5) * 3.0 - Vec3::new(0.0, 0.0, 1.0), -Vec3::new(x, y, 0.0));
        assert!(quarter.intersect(&down(0.6, 0.8), f32::INFINITY).is_some());
        // From (−0.6, 0.8)·3 toward the axis: the near wall (φ ≈ 127°) is cut, the far one too.
        assert!(quarter.intersect(&down(-0.6, 0.8), f32::INFINITY).is_none());
        // From (0.6, −0.8)·3: near wall cut (φ ≈ 307°), far wall at φ ≈ 127°: cut.
        assert!(quarter.intersect(&down(0.6, -0.8), f32::INFINITY).is_none());
        // From (−0.6, −0.8)·3: the far wall is at φ ≈ 53°, kept.
        let (_, q) = quarter.intersect(&down(-0.6, -0.8), f32::INFINITY).unwrap();
        assert!((q.x - 0.6).abs() < 1e-4 && (q.y - 0.8).abs() < 1e-4, "{q}");
        assert!((quarter.surface(q).1.x - 0.8f32.atan2(0.6) / (PI / 2.0)).abs() < 1e-5);
        let flipped = Cylinder::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0), 0.5, Transform::IDENTITY, true);
        assert!((flipped.unwrap().surface(local).0.n + Vec3::Z).length() < 1e-5);
    }

    /// Area sampling is uniform: χ² of the sampled points' (φ/2π, z) against the uniform
    /// density, after a rotation and uniform scale.
    #[test]
    fn area_sampling_is_uniform_chi2() {
        use crate::testkit::{chi2_2d, u2, Chi2Config, Rect};
        let t =
            Transform::rotate(Vec3::new(1.0, 2.0, 0.5), 35.0).unwrap() * Transform::scale(Vec3::splat(1.7)).unwrap();
        let c = Cylinder::new(Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.4, -0.2, 1.5), 0.6, t, false).unwrap();
        let out = chi2_2d(
            &Rect::UNIT,
            [20, 20],
            200_000,
            |r| {
                let (sp, _) = c.sample_area(u2(r));
                let local = c.to_object.apply_point(sp.p);
                Some(c.surface(local).1)
            },
            |_| 1.0,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        // pbrt-v4's partial cylinder: (u, v) still uniform over [0, 1]², points at φ ≤ φ_max.
        let part = c.partial(2.0).unwrap();
        assert!((part.area() - c.area() * 2.0 / (2.0 * PI)).abs() < 1e-4 * c.area());
        let out = chi2_2d(
            &Rect::UNIT,
            [20, 20],
            200_000,
            |r| {
                let local = part.to_object.apply_point(part.sample_area(u2(r)).0.p);
                assert!(crate::math::spherical_phi(Vec3::new(local.x, local.y, 0.0)) <= 2.0 + 1e-4);
                Some(part.surface(local).1)
            },
            |_| 1.0,
            &Chi2Config::default().with_seed(1),
        );
        assert!(out.passed(), "{out}");
        // Area of the transformed tube: 2π (0.6·1.7) (|p1 - p0|·1.7).
        let len = (Vec3::new(0.4, -0.2, 1.5) - Vec3::new(0.1, 0.2, 0.3)).length();
        assert!((c.area() - 2.0 * PI * 0.6 * 1.7 * len * 1.7).abs() < 1e-4 * c.area());
    }

    #[test]
    fn area_samples_lie_on_the_surface_with_constant_density() {
        let c = tube();
        let mut rng = crate::sampling::Pcg32::new(5, 5);
        let mut mean_y = 0.0;
        for _ in 0..10_000 {
            let (sp, pdf) = c.sample_area(crate::testkit::u2(&mut rng));
            let radial = Vec3::new(sp.p.x - 1.0, 0.0, sp.p.z);
            assert!((radial.length() - 0.5).abs() < 1e-5 && (-1e-5..=2.0 + 1e-5).contains(&sp.p.y));
            assert!((sp.n - radial / 0.5).length() < 1e-4);
            assert!((pdf - 1.0 / c.area()).abs() < 1e-7);
            mean_y += sp.p.y as f64 / 10_000.0;
        }
        assert!((mean_y - 1.0).abs() < 0.03, "{mean_y}");
    }
}
