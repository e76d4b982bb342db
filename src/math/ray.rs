//! Rays `o + t d`, `t ∈ (0, t_max)`, at a time within the shutter interval (for scenes whose
//! shapes move).

use glam::Vec3;

/// A ray with origin `o`, direction `d` (not necessarily unit length) and parametric extent
/// `(0, t_max)` in units of `|d|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin (world or object space, as the holder says).
    pub o: Vec3,
    /// Direction.
    pub d: Vec3,
    /// Largest parameter considered; `f32::INFINITY` for an unbounded ray.
    pub t_max: f32,
    /// When the ray is traced (the shutter's units; 0 unless the camera samples a time): where
    /// moving shapes are ([`crate::math::AnimatedTransform`]). Rays spawned along a path keep
    /// their path's time.
    pub time: f32,
}

impl Ray {
    /// Unbounded ray.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Ray {
        Ray { o, d, t_max: f32::INFINITY, time: 0.0 }
    }

    /// Ray bounded to `(0, t_max)`.
    #[inline]
    pub fn bounded(o: Vec3, d: Vec3, t_max: f32) -> Ray {
        Ray { o, d, t_max, time: 0.0 }
    }

    /// This ray at `time`.
    #[inline]
    pub fn at_time(self, time: f32) -> Ray {
        Ray { time, ..self }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_moves_along_direction() {
        let r = Ray::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(r.at(1.5), Vec3::new(1.0, 2.0, 6.0));
        assert!(r.t_max.is_infinite());
        assert_eq!(Ray::bounded(Vec3::ZERO, Vec3::X, 4.0).t_max, 4.0);
    }
}
