//! Cones of directions (pbrt-v4 §3.8.4, `DirectionCone`): a unit axis `w` and the cosine of
//! the half-angle `θ` about it. They bound the normals of an emitter (the light BVH's
//! orientation bounds) and the directions a box subtends from a point.

use super::{safe_acos, Bounds3, Vec3, PI};

/// The directions within angle `acos(cos_theta)` of the unit axis `w`. `cos_theta = -1` is the
/// whole sphere; `cos_theta = +∞` is the empty cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionCone {
    /// Unit axis (world).
    pub w: Vec3,
    /// Cosine of the half-angle.
    pub cos_theta: f32,
}

/// Angle (radians) by which unions widen their result: a cone that bounds a set of directions
/// must not lose any of them to round-off (the light BVH would then give a lit point zero
/// probability: a biased estimate).
const SLACK: f32 = 1e-4;

impl DirectionCone {
    /// The empty cone (identity of [`DirectionCone::union`]).
    pub const EMPTY: DirectionCone = DirectionCone { w: Vec3::Z, cos_theta: f32::INFINITY };

    /// Every direction.
    pub const ENTIRE_SPHERE: DirectionCone = DirectionCone { w: Vec3::Z, cos_theta: -1.0 };

    /// The single direction `w` (unit).
    pub fn from_direction(w: Vec3) -> DirectionCone {
        DirectionCone { w, cos_theta: 1.0 }
    }

    /// Whether the cone holds no direction.
    pub fn is_empty(&self) -> bool {
        self.cos_theta == f32::INFINITY
    }

    /// The smallest cone of this construction holding both `a` and `b` (pbrt-v4's `Union`): the
    /// larger cone if it contains the other, else the cone whose half-angle spans both, widened
    /// by a round-off margin.
    pub fn union(a: &DirectionCone, b: &DirectionCone) -> DirectionCone {
        if a.is_empty() {
            return *b;
        }
        if b.is_empty() {
            return *a;
        }
        let (theta_a, theta_b) = (safe_acos(a.cos_theta), safe_acos(b.cos_theta));
        let theta_d = angle_between(a.w, b.w);
        if (theta_d + theta_b).min(PI) <= theta_a {
            return *a;
        }
        if (theta_d + theta_a).min(PI) <= theta_b {
            return *b;
        }
        let theta_o = (theta_a + theta_d + theta_b) / 2.0 + SLACK;
        if theta_o >= PI {
            return DirectionCone::ENTIRE_SPHERE;
        }
        // Rotate a.w toward b.w by θ_o − θ_a about their common perpendicular (Rodrigues).
        let theta_r = theta_o - SLACK - theta_a;
        let axis = a.w.cross(b.w);
        if axis.length_squared() < 1e-12 {
            return DirectionCone::ENTIRE_SPHERE;
        }
        let k = axis.normalize();
        let (s, c) = theta_r.sin_cos();
        let w = (a.w * c + k.cross(a.w) * s + k * k.dot(a.w) * (1.0 - c)).normalize();
        DirectionCone { w, cos_theta: theta_o.cos() }
    }

    /// The cone of directions from `p` toward the box `b` (pbrt-v4's
    /// `BoundSubtendedDirections`): the cone about the direction to the centre of `b`'s bounding
    /// sphere, or the whole sphere if `p` lies inside that sphere.
    pub fn subtended_by(b: &Bounds3, p: Vec3) -> DirectionCone {
        let (center, radius) = b.bounding_sphere();
        let d2 = (p - center).length_squared();
        DirectionCone { w: (center - p).normalize_or(Vec3::Z), cos_theta: cos_subtended(d2, radius * radius) }
    }

    /// Whether the unit direction `v` lies in the cone.
    pub fn contains(&self, v: Vec3) -> bool {
        !self.is_empty() && v.dot(self.w) >= self.cos_theta
    }
}

/// Cosine of the half-angle of the cone a sphere of squared radius `r2` subtends from a point at
/// squared distance `d2` from its centre; -1 (every direction) from inside.
#[inline]
pub fn cos_subtended(d2: f32, r2: f32) -> f32 {
    if d2 < r2 {
        -1.0
    } else {
        (1.0 - r2 / d2).max(0.0).sqrt()
    }
}

/// Angle between unit vectors, accurate also for nearly parallel ones.
#[inline]
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * safe_asin_half((a + b).length())
    } else {
        2.0 * safe_asin_half((b - a).length())
    }
}

/// `asin(x / 2)` with the argument clamped.
#[inline]
fn safe_asin_half(x: f32) -> f32 {
    (x / 2.0).clamp(-1.0, 1.0).asin()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, Pcg32};
    use crate::testkit::u2;

    /// The union of cones built from random directions contains every one of them, and is no
    /// wider than the whole sphere; merging with the empty cone changes nothing.
    #[test]
    fn union_contains_its_parts() {
        let mut rng = Pcg32::new(5, 1);
        for trial in 0..200 {
            // Directions clustered about an axis (tight cones) or spread (whole sphere).
            let axis = sample_uniform_sphere(u2(&mut rng)).value;
            let spread = [0.05f32, 0.5, 2.0][trial % 3];
            let mut cone = DirectionCone::EMPTY;
            let mut dirs = Vec::new();
            for _ in 0..30 {
                let r = sample_uniform_sphere(u2(&mut rng)).value;
                let d = (axis + r * spread).normalize();
                dirs.push(d);
                cone = DirectionCone::union(&cone, &DirectionCone::from_direction(d));
            }
            for d in &dirs {
                assert!(cone.contains(*d), "trial {trial}: {d} outside {cone:?}");
            }
            if spread == 0.05 {
                assert!(cone.cos_theta > 0.9, "tight cluster gives a tight cone: {cone:?}");
            }
            assert_eq!(DirectionCone::union(&cone, &DirectionCone::EMPTY), cone);
        }
        let opposite =
            DirectionCone::union(&DirectionCone::from_direction(Vec3::Z), &DirectionCone::from_direction(-Vec3::Z));
        assert_eq!(opposite.cos_theta, -1.0);
    }

    #[test]
    fn subtended_cone_holds_the_box() {
        let b = Bounds3::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 2.5, 5.0));
        let p = Vec3::new(-3.0, 0.0, 1.0);
        let cone = DirectionCone::subtended_by(&b, p);
        for i in 0..8 {
            // Corners lie on the bounding sphere: inside up to round-off.
            assert!((b.corner(i) - p).normalize().dot(cone.w) >= cone.cos_theta - 1e-6);
        }
        assert_eq!(DirectionCone::subtended_by(&b, b.centroid()).cos_theta, -1.0);
        assert!((angle_between(Vec3::X, Vec3::Y) - PI / 2.0).abs() < 1e-6);
        assert!((angle_between(Vec3::X, -Vec3::X) - PI).abs() < 1e-6);
    }
}
