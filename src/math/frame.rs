//! Orthonormal frames: the local shading frame has the normal on +z.
//!
//! The basis is built with the branch-free construction of Duff et al., "Building an Orthonormal
//! Basis, Revisited" (JCGT 2017), which is continuous everywhere except across the plane n.z = 0
//! where the sign flips, and exact for unit input.

use glam::Vec3;

/// A right-handed orthonormal basis `(s, t, n)`. `to_local` maps world vectors into the frame
/// (n becomes +z); `to_world` is its inverse. Vectors only: a frame has no origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent (local +x).
    pub s: Vec3,
    /// Second tangent (local +y), `n × s`.
    pub t: Vec3,
    /// Normal (local +z).
    pub n: Vec3,
}

impl Frame {
    /// Frame whose +z is the unit vector `n`.
    #[inline]
    pub fn from_z(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// Frame with normal `n` and first tangent as close as possible to `s` (Gram–Schmidt).
    /// Falls back to [`Frame::from_z`] when `s` is zero or parallel to `n` (or not finite).
    #[inline]
    pub fn from_zx(n: Vec3, s: Vec3) -> Frame {
        let s2 = s.length_squared();
        let s = s - n * n.dot(s);
        let len2 = s.length_squared();
        if s2 == 0.0 || len2.is_nan() || len2 <= 1e-12 * s2 || !s2.is_finite() {
            return Frame::from_z(n);
        }
        let s = s / len2.sqrt();
        Frame { s, t: n.cross(s), n }
    }

    /// World vector → local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local coordinates → world vector.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        let mut rng = Pcg32::new(7, 0);
        let mut dirs: Vec<Vec3> = vec![Vec3::Z, -Vec3::Z, Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, -0.999_999_9)];
        for _ in 0..10_000 {
            let v = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5);
            if v.length() > 1e-3 {
                dirs.push(v.normalize());
            }
        }
        for n in dirs {
            let f = Frame::from_z(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5, "{n}");
            assert!((f.t.length() - 1.0).abs() < 1e-5, "{n}");
            assert!(f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5, "{n}");
            assert!((f.s.cross(f.t) - n).length() < 1e-5, "not right-handed for {n}");
            let v = Vec3::new(0.3, -0.2, 0.9);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
            assert!((f.to_local(n) - Vec3::Z).length() < 1e-5);
        }
    }

    #[test]
    fn from_zx_keeps_tangent_direction() {
        let n = Vec3::new(0.0, 1.0, 0.0);
        let f = Frame::from_zx(n, Vec3::new(1.0, 0.5, 0.0));
        assert!((f.s - Vec3::X).length() < 1e-6);
        assert!((f.s.cross(f.t) - n).length() < 1e-6);
        let g = Frame::from_zx(n, n);
        assert!(g.s.dot(n).abs() < 1e-6);
    }
}
