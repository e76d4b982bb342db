//! Transforms that move during the shutter interval (pbrt-v4's `AnimatedTransform`): a start
//! and an end transform at times `t0 < t1`, each decomposed into translation `T`, rotation `R`
//! (a unit quaternion) and the remaining scale-and-shear `S` (`M = T R S`, by polar
//! decomposition); at a time between them `T` and `S` are interpolated linearly and `R` by
//! spherical linear interpolation along the shorter arc. Before `t0` the start transform holds,
//! after `t1` the end one.

use super::{Bounds3, Transform};
use glam::{Mat3, Mat4, Quat, Vec3};

/// A transform interpolated over `[t0, t1]` (times in the shutter's units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnimatedTransform {
    start: Transform,
    end: Transform,
    t0: f32,
    t1: f32,
    /// The decompositions of `start` and `end`.
    translate: [Vec3; 2],
    rotate: [Quat; 2],
    scale: [Mat3; 2],
}

impl AnimatedTransform {
    /// `start` at time `t0`, `end` at `t1`. Errors where `t0 ≥ t1` (with the transforms
    /// differing), a transform is singular or projective, or only one of them mirrors.
    pub fn new(start: Transform, t0: f32, end: Transform, t1: f32) -> Result<AnimatedTransform, String> {
        if start != end && !(t0 < t1 && t0.is_finite() && t1.is_finite()) {
            return Err(format!("a moving transform needs a start time before its end time, got {t0} and {t1}"));
        }
        if start.swaps_handedness() != end.swaps_handedness() {
            return Err("a moving transform cannot mirror at one end only (it would pass through a flat one)".into());
        }
        let (ts, rs, ss) = decompose(start.matrix())?;
        let (te, mut re, se) = decompose(end.matrix())?;
        // Interpolate along the shorter arc.
        if rs.dot(re) < 0.0 {
            re = -re;
        }
        Ok(AnimatedTransform { start, end, t0, t1, translate: [ts, te], rotate: [rs, re], scale: [ss, se] })
    }

    /// Whether the transform changes over time.
    pub fn is_animated(&self) -> bool {
        self.start != self.end
    }

    /// The start transform (at `t0` and before).
    pub fn start(&self) -> &Transform {
        &self.start
    }

    /// The end transform (at `t1` and after).
    pub fn end(&self) -> &Transform {
        &self.end
    }

    /// The matrix at `time`.
    pub fn matrix_at(&self, time: f32) -> Mat4 {
        if !self.is_animated() || time <= self.t0 {
            return *self.start.matrix();
        }
        if time >= self.t1 {
            return *self.end.matrix();
        }
        let dt = (time - self.t0) / (self.t1 - self.t0);
        self.interpolated(dt)
    }

    /// The transform (with its inverse) at `time`; `None` where the interpolated scale is
    /// singular (a scale through zero).
    pub fn at(&self, time: f32) -> Option<Transform> {
        if !self.is_animated() || time <= self.t0 {
            return Some(self.start);
        }
        if time >= self.t1 {
            return Some(self.end);
        }
        Transform::from_matrix(self.matrix_at(time))
    }

    /// `T R S` at the fraction `dt` of the interval.
    fn interpolated(&self, dt: f32) -> Mat4 {
        let t = self.translate[0].lerp(self.translate[1], dt);
        let r = slerp(self.rotate[0], self.rotate[1], dt);
        let s = self.scale[0] * (1.0 - dt) + self.scale[1] * dt;
        Mat4::from_translation(t) * Mat4::from_mat3(Mat3::from_quat(r) * s)
    }

    /// A box holding the points `p` (in the transform's source space) wherever they move over
    /// `[t0, t1]`: the endpoints' boxes where the rotation does not change (the motion is then
    /// linear in time); otherwise the points at 33 times, widened by twice the largest distance
    /// a point can stray from them between two (the rotation's angle step times the largest
    /// scaled distance from the origin).
    pub fn motion_bounds(&self, points: &[Vec3]) -> Bounds3 {
        let at = |m: &Mat4| points.iter().fold(Bounds3::EMPTY, |b, &p| b.union_point(m.transform_point3(p)));
        let mut b = at(self.start.matrix()).union(&at(self.end.matrix()));
        let angle = 2.0 * self.rotate[0].dot(self.rotate[1]).abs().min(1.0).acos();
        if !self.is_animated() || angle == 0.0 {
            return b;
        }
        const STEPS: usize = 32;
        for k in 1..STEPS {
            b = b.union(&at(&self.interpolated(k as f32 / STEPS as f32)));
        }
        let r = points
            .iter()
            .map(|&p| (self.scale[0] * p).length().max((self.scale[1] * p).length()))
            .fold(0.0f32, f32::max);
        let pad = 2.0 * angle / STEPS as f32 * r * (1.0 + 1e-3) + 1e-6 * r;
        Bounds3 { min: b.min - Vec3::splat(pad), max: b.max + Vec3::splat(pad) }
    }
}

/// Spherical linear interpolation of unit quaternions with a non-negative dot product (pbrt's
/// `Slerp`: a normalized linear blend where they nearly coincide).
fn slerp(a: Quat, b: Quat, t: f32) -> Quat {
    let cos = a.dot(b);
    if cos > 0.9995 {
        return (a * (1.0 - t) + b * t).normalize();
    }
    let theta = cos.clamp(-1.0, 1.0).acos();
    let perp = (b - a * cos).normalize();
    a * (theta * t).cos() + perp * (theta * t).sin()
}

/// `M = T R S`: translation, rotation (a unit quaternion) and the rest (pbrt-v4's polar
/// decomposition by averaging `R` with its inverse transpose until it settles). A reflection
/// stays in `S` (`R` is made a proper rotation).
fn decompose(m: &Mat4) -> Result<(Vec3, Quat, Mat3), String> {
    if !m.is_finite() {
        return Err("a moving transform must be finite".into());
    }
    if m.row(3) != glam::Vec4::new(0.0, 0.0, 0.0, 1.0) {
        return Err("a moving transform must be affine (no projection)".into());
    }
    let t = m.w_axis.truncate();
    let upper = Mat3::from_mat4(*m);
    if upper.determinant() == 0.0 || !upper.is_finite() {
        return Err("a moving transform must not be singular".into());
    }
    let mut r = upper;
    for _ in 0..100 {
        let next = (r + r.transpose().inverse()) * 0.5;
        let diff = (next - r).abs();
        let norm = [diff.row(0), diff.row(1), diff.row(2)].iter().map(|row| row.x + row.y + row.z).fold(0.0, f32::max);
        r = next;
        if norm <= 1e-4 {
            break;
        }
    }
    if r.determinant() < 0.0 {
        r = -r;
    }
    let s = r.inverse() * upper;
    Ok((t, Quat::from_mat3(&r).normalize(), s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    fn tf(m: Mat4) -> Transform {
        Transform::from_matrix(m).unwrap()
    }

    /// Decomposition and interpolation reproduce the endpoints (both mirroring, one with a
    /// shear), a pure translation moves linearly, a rotation turns at a constant rate about
    /// its axis, and times outside the interval hold the endpoint transforms.
    #[test]
    fn interpolates_like_pbrt() {
        let a = tf(Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7)
            * Mat4::from_scale(Vec3::new(2.0, -1.0, 0.5)));
        let b = tf(Mat4::from_translation(Vec3::new(-1.0, 0.0, 3.0))
            * Mat4::from_axis_angle(Vec3::Y, -1.2)
            * Mat4::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 0.3, 1.0, 0.0, 0.0, 0.0, 0.0, -1.5, 0.0, 0.0, 0.0, 0.0, 1.0]));
        let at = AnimatedTransform::new(a, 2.0, b, 4.0).unwrap();
        for (time, expected) in [(2.0, a), (4.0, b), (1.0, a), (9.0, b)] {
            assert!(at.matrix_at(time).abs_diff_eq(*expected.matrix(), 1e-6), "{time}");
        }
        // The interpolation's own endpoints match the transforms too.
        assert!(at.interpolated(0.0).abs_diff_eq(*a.matrix(), 1e-4), "{}", at.interpolated(0.0));
        assert!(at.interpolated(1.0).abs_diff_eq(*b.matrix(), 1e-4), "{}", at.interpolated(1.0));

        let shift = AnimatedTransform::new(Transform::IDENTITY, 0.0, tf(Mat4::from_translation(Vec3::X * 4.0)), 1.0)
            .unwrap();
        assert!((shift.matrix_at(0.25).transform_point3(Vec3::ZERO) - Vec3::X).length() < 1e-6);

        let spin = AnimatedTransform::new(Transform::IDENTITY, 0.0, tf(Mat4::from_rotation_z(1.5)), 1.0).unwrap();
        let p = spin.matrix_at(0.5).transform_point3(Vec3::X);
        assert!((p - Vec3::new(0.75f32.cos(), 0.75f32.sin(), 0.0)).length() < 1e-5, "{p}");
        assert!(!AnimatedTransform::new(a, 0.0, a, 0.0).unwrap().is_animated() && at.is_animated());
        assert!(AnimatedTransform::new(a, 1.0, b, 1.0).is_err());
        assert!(AnimatedTransform::new(a, 0.0, Transform::IDENTITY, 1.0).is_err(), "mirrors at one end only");
        assert!(AnimatedTransform::new(a, 1.0, a, 1.0).is_ok());
    }

    /// Every point of a moving triangle at 2000 random times lies in its motion bounds, for
    /// random transforms with rotations up to a half turn; the bounds of a translation are
    /// exactly the union of its endpoints'.
    #[test]
    fn motion_bounds_hold_the_moving_points() {
        let mut rng = Pcg32::new(4, 2);
        let mut v = |s: f32| Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5) * s;
        for _ in 0..50 {
            let axis = v(2.0).normalize();
            let (ta, tb, sa, sb) = (v(4.0), v(4.0), v(1.0).abs() + Vec3::splat(0.2), v(1.0).abs() + Vec3::splat(0.2));
            let (angle_a, angle_b) = (v(2.0).x, v(6.0).y);
            let a = tf(Mat4::from_translation(ta) * Mat4::from_axis_angle(axis, angle_a) * Mat4::from_scale(sa));
            let b = tf(Mat4::from_translation(tb) * Mat4::from_axis_angle(axis, angle_b) * Mat4::from_scale(sb));
            let at = AnimatedTransform::new(a, 0.0, b, 1.0).unwrap();
            let tri = [v(3.0), v(3.0), v(3.0)];
            let bounds = at.motion_bounds(&tri);
            for k in 0..2000 {
                let m = at.matrix_at(k as f32 / 1999.0);
                for p in tri {
                    let q = m.transform_point3(p);
                    assert!(
                        (q.cmpge(bounds.min - Vec3::splat(1e-4)) & q.cmple(bounds.max + Vec3::splat(1e-4))).all(),
                        "{q} outside {bounds:?}"
                    );
                }
            }
        }
        let shift = AnimatedTransform::new(Transform::IDENTITY, 0.0, tf(Mat4::from_translation(Vec3::X * 4.0)), 1.0)
            .unwrap();
        let b = shift.motion_bounds(&[Vec3::ZERO, Vec3::Y]);
        assert_eq!((b.min, b.max), (Vec3::ZERO, Vec3::new(4.0, 1.0, 0.0)));
    }
}
