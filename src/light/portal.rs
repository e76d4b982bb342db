//! pbrt-v4's portal for an environment light: a rectangle (a window, an opening) through which
//! the environment shines into an interior. The environment's radiance arrives only along rays
//! that cross the portal from its back to its front (pbrt-v4's `PortalImageInfiniteLight::Le`),
//! so a portal changes the image, not only how it is sampled; and light sampling picks a point
//! of the portal uniformly by area, so every sample can arrive.
//!
//! Frame (pbrt-v4's): for corners `p0 … p3`, the portal's x axis is `p3 − p0`, its y axis
//! `p1 − p0` and its normal `n = x × y`; a ray in unit direction `d` from `o` sees the
//! environment through the portal when `d · n > 0` and it meets the rectangle at some `t > 0`.

use crate::math::{Vec2, Vec3};

/// A portal rectangle (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    /// Corner `p0`.
    p0: Vec3,
    /// Edge `p3 − p0` (the portal's x).
    ex: Vec3,
    /// Edge `p1 − p0` (the portal's y).
    ey: Vec3,
    /// Unit normal `ex × ey`: rays crossing toward it see the environment.
    n: Vec3,
    /// Area (m²).
    area: f32,
}

/// Why four points make no portal.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PortalError {
    /// Not a rectangle (pbrt-v4 requires opposite edges parallel and sides perpendicular).
    #[error(
        "the portal's four points must make a rectangle p0, p1, p2, p3 (opposite edges parallel, sides perpendicular)"
    )]
    NotARectangle,
}

impl Portal {
    /// The portal with corners `p` in pbrt-v4's order (`p0 → p1 → p2 → p3` around the
    /// rectangle), checked as pbrt checks it (unit edge directions within 0.001).
    pub fn new(p: [Vec3; 4]) -> Result<Portal, PortalError> {
        let unit = |a: Vec3, b: Vec3| (b - a).try_normalize().ok_or(PortalError::NotARectangle);
        let (p01, p12, p32, p03) = (unit(p[0], p[1])?, unit(p[1], p[2])?, unit(p[3], p[2])?, unit(p[0], p[3])?);
        let parallel = (p01.dot(p32) - 1.0).abs() <= 1e-3 && (p12.dot(p03) - 1.0).abs() <= 1e-3;
        let square = [p01.dot(p12), p12.dot(p32), p32.dot(p03), p03.dot(p01)].iter().all(|c| c.abs() <= 1e-3);
        if !(parallel && square) {
            return Err(PortalError::NotARectangle);
        }
        let (ex, ey) = (p[3] - p[0], p[1] - p[0]);
        let cross = ex.cross(ey);
        let area = cross.length();
        if !(area > 0.0 && area.is_finite()) {
            return Err(PortalError::NotARectangle);
        }
        Ok(Portal { p0: p[0], ex, ey, n: cross / area, area })
    }

    /// Unit normal: the environment is seen along directions with a positive component on it.
    pub fn normal(&self) -> Vec3 {
        self.n
    }

    /// Area (m²).
    pub fn area(&self) -> f32 {
        self.area
    }

    /// The point at `u ∈ [0, 1]²` (uniform in area).
    #[inline]
    pub fn point(&self, u: Vec2) -> Vec3 {
        self.p0 + u.x * self.ex + u.y * self.ey
    }

    /// Distance from `o` along unit `d` to where the ray crosses the portal toward its front;
    /// `None` if it does not.
    #[inline]
    pub fn crossing(&self, o: Vec3, d: Vec3) -> Option<f32> {
        let dn = d.dot(self.n);
        if dn <= 0.0 {
            return None;
        }
        let t = (self.p0 - o).dot(self.n) / dn;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        let q = o + t * d - self.p0;
        let (s, r) = (q.dot(self.ex) / self.ex.length_squared(), q.dot(self.ey) / self.ey.length_squared());
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)).then_some(t)
    }

    /// A unit direction from `p_ref` through a uniformly chosen point of the portal, with its
    /// density per unit solid angle (`dist² / (area · cos θ)`); `None` from in front of it.
    #[inline]
    pub fn sample(&self, p_ref: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
        let d = self.point(u) - p_ref;
        let dist2 = d.length_squared();
        let wi = d / dist2.sqrt();
        let cos = wi.dot(self.n);
        let pdf = dist2 / (self.area * cos);
        (cos > 0.0 && pdf.is_finite()).then_some((wi, pdf))
    }

    /// Density of [`Portal::sample`] from `p_ref` for the unit direction `wi` (0 unless it
    /// crosses the portal).
    #[inline]
    pub fn pdf(&self, p_ref: Vec3, wi: Vec3) -> f32 {
        match self.crossing(p_ref, wi) {
            Some(t) => t * t / (self.area * wi.dot(self.n)),
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, u2, Chi2Config, SPHERE};

    /// A 2 × 1 window in the plane x = 1 facing +x (corners in pbrt's order).
    fn window() -> Portal {
        let p =
            [Vec3::new(1.0, -1.0, 0.2), Vec3::new(1.0, -1.0, 1.2), Vec3::new(1.0, 1.0, 1.2), Vec3::new(1.0, 1.0, 0.2)];
        Portal::new(p).unwrap()
    }

    #[test]
    fn frame_crossing_and_checks() {
        let w = window();
        // x = p3 − p0 = +y·2, y = p1 − p0 = +z: n = y × z = +x.
        assert!((w.normal() - Vec3::X).length() < 1e-6 && (w.area() - 2.0).abs() < 1e-6);
        let o = Vec3::new(-1.0, 0.0, 0.5);
        assert!((w.crossing(o, Vec3::X).unwrap() - 2.0).abs() < 1e-6);
        assert!(w.crossing(o, -Vec3::X).is_none(), "away from the portal");
        assert!(w.crossing(Vec3::new(2.0, 0.0, 0.5), -Vec3::X).is_none(), "from in front, toward its back");
        assert!(w.crossing(o, Vec3::new(1.0, 0.0, 1.0).normalize()).is_none(), "above the window");
        let skew = [Vec3::ZERO, Vec3::Y, Vec3::new(1.0, 1.5, 0.0), Vec3::X];
        assert_eq!(Portal::new(skew), Err(PortalError::NotARectangle));
    }

    /// Directions sampled from a point behind the portal follow `pdf` (χ² over the sphere of
    /// directions), which is zero outside the window: it integrates to one.
    #[test]
    fn sampling_matches_pdf_chi2() {
        let w = window();
        let p_ref = Vec3::new(-0.3, 0.4, 0.1);
        let out = chi2_2d(
            &SPHERE,
            [41, 81],
            300_000,
            |r| w.sample(p_ref, u2(r)).map(|(wi, _)| wi),
            |d| w.pdf(p_ref, *d) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        // From in front of the portal nothing is sampled.
        assert!(w.sample(Vec3::new(3.0, 0.0, 0.5), Vec2::splat(0.5)).is_none());
    }
}
