//! Affine and projective transforms of points, vectors, normals, rays and bounds.
//!
//! A [`Transform`] stores its 4×4 matrix and the inverse, so inverting is free and normals
//! (which transform by the inverse transpose) cost no inversion. Composition follows matrix
//! order: `a * b` applies `b` first, then `a`. Angles are in degrees, as in Mitsuba 3 and pbrt
//! scene files.

use super::{Bounds3, Ray};
use glam::{Mat3, Mat4, Vec3, Vec4};
use std::ops::Mul;

/// An invertible transform with its cached inverse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    m: Mat4,
    inv: Mat4,
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform { m: Mat4::IDENTITY, inv: Mat4::IDENTITY };

    /// Transform from a matrix (column-vector convention, `p' = M p`). `None` when the matrix is
    /// singular or not finite.
    pub fn from_matrix(m: Mat4) -> Option<Transform> {
        let det = m.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return None;
        }
        let inv = m.inverse();
        if !inv.is_finite() {
            return None;
        }
        Some(Transform { m, inv })
    }

    /// Transform from a matrix and its known inverse (not checked).
    pub fn from_matrix_and_inverse(m: Mat4, inv: Mat4) -> Transform {
        Transform { m, inv }
    }

    /// Translation by `d`.
    pub fn translate(d: Vec3) -> Transform {
        Transform { m: Mat4::from_translation(d), inv: Mat4::from_translation(-d) }
    }

    /// Non-uniform scale by `s`; `None` if a factor is zero.
    pub fn scale(s: Vec3) -> Option<Transform> {
        if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 || !s.is_finite() {
            return None;
        }
        Some(Transform { m: Mat4::from_scale(s), inv: Mat4::from_scale(s.recip()) })
    }

    /// Rotation by `angle_deg` degrees counter-clockwise about `axis` (right-hand rule).
    /// `None` for a zero axis.
    pub fn rotate(axis: Vec3, angle_deg: f32) -> Option<Transform> {
        let len = axis.length();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let m = Mat4::from_axis_angle(axis / len, angle_deg.to_radians());
        Some(Transform { m, inv: m.transpose() })
    }

    /// Mitsuba 3's rotation: the Rodrigues matrix `cos θ I + (1 − cos θ) a aᵀ + sin θ [a]×` of
    /// the axis `a` as given, not normalized — for a non-unit axis it scales and shears too, as
    /// Mitsuba 3 (3.9.1) builds `<rotate x="1" y="1" …>`. A unit axis gives [`Transform::rotate`].
    /// `None` if the matrix is singular or not finite.
    pub fn rotate_unnormalized(axis: Vec3, angle_deg: f32) -> Option<Transform> {
        if (axis.length_squared() - 1.0).abs() <= 1e-6 {
            return Transform::rotate(axis, angle_deg);
        }
        let (s, c) = angle_deg.to_radians().sin_cos();
        let a = axis;
        let skew = Mat3::from_cols(Vec3::new(0.0, a.z, -a.y), Vec3::new(-a.z, 0.0, a.x), Vec3::new(a.y, -a.x, 0.0));
        let outer = Mat3::from_cols(a * a.x, a * a.y, a * a.z);
        let m = Mat3::from_diagonal(Vec3::splat(c)) + outer * (1.0 - c) + skew * s;
        Transform::from_matrix(Mat4::from_mat3(m))
    }

    /// Camera-to-world transform of a camera at `origin` looking at `target` (Mitsuba 3's
    /// `lookat`): local +z points to the target, +y is as close to `up` as possible and +x is
    /// `up × dir` (the camera's left). `None` if `up` is parallel to the view direction or the
    /// points coincide.
    pub fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Option<Transform> {
        let dir = (target - origin).normalize_or_zero();
        let left = up.normalize_or_zero().cross(dir);
        if dir == Vec3::ZERO || left.length_squared() < 1e-12 {
            return None;
        }
        let left = left.normalize();
        let new_up = dir.cross(left);
        let m = Mat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0));
        Transform::from_matrix(m)
    }

    /// Perspective projection of camera space (looking down +z) onto the plane z = 1 with depth
    /// mapped to [0, 1] between `near` and `far`; `fov_deg` is the full field of view in degrees
    /// that maps to [-1, 1]. Used by cameras to build raster transforms.
    pub fn perspective(fov_deg: f32, near: f32, far: f32) -> Option<Transform> {
        if !(near > 0.0 && far > near && fov_deg > 0.0 && fov_deg < 180.0) {
            return None;
        }
        let inv_tan = 1.0 / (0.5 * fov_deg.to_radians()).tan();
        let m = Mat4::from_cols(
            Vec4::new(inv_tan, 0.0, 0.0, 0.0),
            Vec4::new(0.0, inv_tan, 0.0, 0.0),
            Vec4::new(0.0, 0.0, far / (far - near), 1.0),
            Vec4::new(0.0, 0.0, -far * near / (far - near), 0.0),
        );
        Transform::from_matrix(m)
    }

    /// The matrix.
    pub fn matrix(&self) -> &Mat4 {
        &self.m
    }

    /// The inverse matrix.
    pub fn inverse_matrix(&self) -> &Mat4 {
        &self.inv
    }

    /// The inverse transform (free: the inverse is stored).
    pub fn inverse(&self) -> Transform {
        Transform { m: self.inv, inv: self.m }
    }

    /// Whether this is exactly the identity.
    pub fn is_identity(&self) -> bool {
        self.m == Mat4::IDENTITY
    }

    /// Transforms a point (w = 1), dividing by the homogeneous coordinate when it is not 1.
    #[inline]
    pub fn apply_point(&self, p: Vec3) -> Vec3 {
        let r = self.m * p.extend(1.0);
        if r.w == 1.0 {
            r.truncate()
        } else {
            r.truncate() / r.w
        }
    }

    /// Transforms a direction (w = 0): no translation, no normalization.
    #[inline]
    pub fn apply_vector(&self, v: Vec3) -> Vec3 {
        self.m.transform_vector3(v)
    }

    /// Transforms a surface normal by the inverse transpose so that it stays perpendicular to
    /// transformed tangents. Not normalized.
    #[inline]
    pub fn apply_normal(&self, n: Vec3) -> Vec3 {
        // (M^-1)^T n, written out to avoid forming the transpose.
        let i = &self.inv;
        Vec3::new(
            i.x_axis.x * n.x + i.x_axis.y * n.y + i.x_axis.z * n.z,
            i.y_axis.x * n.x + i.y_axis.y * n.y + i.y_axis.z * n.z,
            i.z_axis.x * n.x + i.z_axis.y * n.y + i.z_axis.z * n.z,
        )
    }

    /// Transforms a ray's origin and direction (the direction is not renormalized, so ray
    /// parameters `t` stay valid across the transform).
    #[inline]
    pub fn apply_ray(&self, r: &Ray) -> Ray {
        Ray { o: self.apply_point(r.o), d: self.apply_vector(r.d), t_max: r.t_max, time: r.time }
    }

    /// Axis-aligned bounds of the transformed box (all eight corners).
    pub fn apply_bounds(&self, b: &Bounds3) -> Bounds3 {
        let mut out = Bounds3::EMPTY;
        if b.is_empty() {
            return out;
        }
        for i in 0..8 {
            out = out.union_point(self.apply_point(b.corner(i)));
        }
        out
    }

    /// Whether the transform flips orientation (negative determinant of the linear part).
    pub fn swaps_handedness(&self) -> bool {
        glam::Mat3::from_mat4(self.m).determinant() < 0.0
    }
}

impl Mul for Transform {
    type Output = Transform;
    /// `a * b` applies `b` first.
    fn mul(self, rhs: Transform) -> Transform {
        Transform { m: self.m * rhs.m, inv: rhs.inv * self.inv }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).length() <= tol * (1.0 + b.length())
    }

    fn sample_transform() -> Transform {
        Transform::translate(Vec3::new(1.0, -2.0, 3.0))
            * Transform::rotate(Vec3::new(1.0, 1.0, 0.3), 37.0).unwrap()
            * Transform::scale(Vec3::new(2.0, 0.5, -1.5)).unwrap()
    }

    #[test]
    fn inverse_round_trips() {
        let t = sample_transform();
        let p = Vec3::new(0.3, -0.7, 2.0);
        assert!(close(t.inverse().apply_point(t.apply_point(p)), p, 1e-5));
        assert!(close(t.inverse().apply_vector(t.apply_vector(p)), p, 1e-5));
        let m = *(t * t.inverse()).matrix();
        assert!(m.abs_diff_eq(Mat4::IDENTITY, 1e-5));
        let t2 = Transform::from_matrix(*t.matrix()).unwrap();
        assert!(t2.inverse_matrix().abs_diff_eq(*t.inverse_matrix(), 1e-4));
    }

    #[test]
    fn composition_order_applies_right_first() {
        let t = Transform::translate(Vec3::X);
        let s = Transform::scale(Vec3::splat(2.0)).unwrap();
        // scale then translate: (1,0,0) -> (2,0,0) -> (3,0,0)
        assert!(close((t * s).apply_point(Vec3::X), Vec3::new(3.0, 0.0, 0.0), 1e-6));
        assert!(close((s * t).apply_point(Vec3::X), Vec3::new(4.0, 0.0, 0.0), 1e-6));
    }

    #[test]
    fn vectors_ignore_translation_and_rotation_is_right_handed() {
        let t = Transform::translate(Vec3::new(5.0, 5.0, 5.0));
        assert_eq!(t.apply_vector(Vec3::X), Vec3::X);
        let r = Transform::rotate(Vec3::Z, 90.0).unwrap();
        assert!(close(r.apply_vector(Vec3::X), Vec3::Y, 1e-6));
    }

    #[test]
    fn normals_stay_perpendicular_to_tangents() {
        let t = sample_transform();
        let n = Vec3::new(0.2, 0.9, -0.4).normalize();
        let tangent = n.cross(Vec3::new(0.3, 0.1, 0.8)).normalize();
        let n2 = t.apply_normal(n);
        let t2 = t.apply_vector(tangent);
        assert!(n2.normalize().dot(t2.normalize()).abs() < 1e-5);
        assert!(t.swaps_handedness());
        assert!(!Transform::rotate(Vec3::Y, 10.0).unwrap().swaps_handedness());
    }

    #[test]
    fn look_at_follows_mitsuba_convention() {
        let eye = Vec3::new(0.0, 0.0, 3.9);
        let t = Transform::look_at(eye, Vec3::ZERO, Vec3::Y).unwrap();
        assert!(close(t.apply_point(Vec3::ZERO), eye, 1e-6));
        assert!(close(t.apply_vector(Vec3::Z), -Vec3::Z, 1e-6));
        assert!(close(t.apply_vector(Vec3::Y), Vec3::Y, 1e-6));
        // +x is the camera's left: up × dir = y × (-z) = -x.
        assert!(close(t.apply_vector(Vec3::X), -Vec3::X, 1e-6));
        assert!(Transform::look_at(eye, Vec3::ZERO, Vec3::Z).is_none());
        assert!(Transform::look_at(eye, eye, Vec3::Y).is_none());
    }

    #[test]
    fn degenerate_inputs_are_rejected() {
        assert!(Transform::scale(Vec3::new(1.0, 0.0, 1.0)).is_none());
        assert!(Transform::rotate(Vec3::ZERO, 10.0).is_none());
        assert!(Transform::from_matrix(Mat4::ZERO).is_none());
        assert!(Transform::perspective(45.0, 0.0, 1.0).is_none());
    }

    #[test]
    fn perspective_maps_frustum_edges() {
        let p = Transform::perspective(90.0, 1.0, 10.0).unwrap();
        // at 45° half-angle, x = z maps to x' = 1
        assert!(close(p.apply_point(Vec3::new(2.0, 0.0, 2.0)), Vec3::new(1.0, 0.0, 5.0 / 9.0), 1e-5));
        assert!((p.apply_point(Vec3::new(0.0, 0.0, 1.0)).z - 0.0).abs() < 1e-6);
        assert!((p.apply_point(Vec3::new(0.0, 0.0, 10.0)).z - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bounds_transform_covers_corners() {
        let b = Bounds3::new(Vec3::ZERO, Vec3::ONE);
        let r = Transform::rotate(Vec3::Z, 45.0).unwrap();
        let rb = r.apply_bounds(&b);
        let s = std::f32::consts::FRAC_1_SQRT_2;
        assert!(close(rb.min, Vec3::new(-s, 0.0, 0.0), 1e-5));
        assert!(close(rb.max, Vec3::new(s, 2.0 * s, 1.0), 1e-5));
    }
}
