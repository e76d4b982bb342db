//! A moving camera (motion blur; pbrt-v4's animated camera transform).
//!
//! The camera's `to_world` is interpolated over `[t0, t1]` as pbrt-v4 interpolates its
//! world-from-camera transform ([`AnimatedTransform`]: translation and scale linearly, the
//! rotation by slerp), and each camera ray is generated at a time uniform over the shutter.
//! Every projection computes its ray in camera space and places it by `to_world`; a moving
//! camera makes the ray at its start placement and then moves it by the world-to-world map
//! `to_world(t) · to_world(t0)⁻¹` ([`CameraMotion::moved_by`]), which is the same ray as the
//! camera placed by `to_world(t)` would make (up to rounding). Light tracing connects a scene
//! point to the camera where it is at the light path's time by the inverse map
//! ([`super::Camera::sample_wi_at`]).

use crate::math::{AnimatedTransform, Mat4, Ray, Transform};

/// A camera's placement over the shutter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMotion {
    /// `to_world` over time (start: the camera's own `to_world`).
    to_world: AnimatedTransform,
    /// `to_world(t0)⁻¹`, world to the start's camera space.
    from_start: Mat4,
    /// The shutter interval `[open, close]` camera rays draw their time from.
    shutter: (f32, f32),
    /// The motion's start time: up to it the camera is at its start placement.
    t0: f32,
}

impl CameraMotion {
    /// The motion from `start` at time `t0` to `end` at `t1`, seen over `shutter`; `None` where
    /// the camera does not move (`start == end`). Errors as [`AnimatedTransform::new`]'s.
    pub fn new(start: Transform, t0: f32, end: Transform, t1: f32, shutter: (f32, f32)) -> Result<Option<CameraMotion>, String> {
        if !(shutter.0.is_finite() && shutter.1.is_finite() && shutter.0 <= shutter.1) {
            return Err(format!("the shutter must be an interval of finite times, got [{}, {}]", shutter.0, shutter.1));
        }
        let to_world = AnimatedTransform::new(start, t0, end, t1)?;
        Ok(to_world.is_animated().then(|| CameraMotion { to_world, from_start: *start.inverse_matrix(), shutter, t0 }))
    }

    /// The shutter interval `[open, close]`.
    pub fn shutter(&self) -> (f32, f32) {
        self.shutter
    }

    /// The world-to-world map taking where the camera is at its start to where it is at
    /// `time`: `to_world(time) · to_world(t0)⁻¹`, with its inverse. `None` if the interpolated
    /// transform is singular (not for the transforms [`CameraMotion::new`] accepts), and up to
    /// the motion's start time, where the camera is at its start placement (its rays then are
    /// the static camera's, bit for bit).
    pub fn moved_by(&self, time: f32) -> Option<Transform> {
        if time <= self.t0 {
            return None;
        }
        let now = self.to_world.at(time)?;
        let start_inverse = Transform::from_matrix_and_inverse(self.from_start, *self.to_world.start().matrix());
        Some(now * start_inverse)
    }
}

/// `ray` moved by the world-to-world map `m`: origin and direction mapped, the direction
/// renormalized and the extent rescaled so that the same segment is covered.
pub fn moved_ray(m: &Transform, ray: &Ray) -> Ray {
    let d = m.apply_vector(ray.d);
    let len = d.length();
    let scale = len / ray.d.length();
    let t_max = if ray.t_max.is_finite() { ray.t_max * scale } else { ray.t_max };
    Ray { o: m.apply_point(ray.o), d: d / len, t_max, time: ray.time }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, FovAxis, Projection, SphericalMapping};
    use crate::math::{Vec2, Vec3};

    /// A camera that moves generates at each time the rays the camera placed by the
    /// interpolated transform generates (pinhole, thin lens, orthographic, spherical), at the
    /// start the static camera's rays exactly, and at rest (the same transform at both ends) no
    /// motion at all.
    #[test]
    fn moving_camera_rays_are_the_interpolated_cameras_rays() {
        let start = Transform::look_at(Vec3::new(0.0, 1.0, -5.0), Vec3::ZERO, Vec3::Y).unwrap();
        let end = Transform::look_at(Vec3::new(3.0, 2.0, -4.0), Vec3::new(0.5, 0.0, 0.0), Vec3::Y).unwrap();
        let motion = AnimatedTransform::new(start, 0.0, end, 1.0).unwrap();
        let cameras = |to_world: Transform| {
            let p = Camera::perspective(to_world, 50.0, FovAxis::X, 32, 24).unwrap();
            vec![
                p.clone(),
                p.clone().with_thin_lens(0.2, 4.0).unwrap(),
                Camera::orthographic(to_world, 32, 24).unwrap(),
                Camera { projection: Projection::Spherical(SphericalMapping::Equirectangular), ..p },
            ]
        };
        for (k, camera) in cameras(start).into_iter().enumerate() {
            let moving = camera.clone().with_motion(end, 0.0, 1.0, (0.0, 1.0)).unwrap();
            assert!(moving.motion_shutter() == Some((0.0, 1.0)));
            for time in [0.0f32, 0.3, 0.71, 1.0] {
                let at = cameras(motion.at(time).unwrap()).swap_remove(k);
                for (i, film) in [Vec2::new(3.5, 7.25), Vec2::new(30.1, 1.9), Vec2::new(16.0, 12.0)].into_iter().enumerate() {
                    let u_lens = Vec2::new(0.1 + 0.3 * i as f32, 0.8 - 0.2 * i as f32);
                    let (want, _) = at.sample_ray(film, u_lens);
                    let (got, _) = moving.sample_ray_at(film, u_lens, time);
                    assert!((got.o - want.o).length() < 1e-4, "camera {k} t {time}: origin {} vs {}", got.o, want.o);
                    assert!((got.d - want.d).length() < 1e-5, "camera {k} t {time}: direction {} vs {}", got.d, want.d);
                    assert!((got.t_max - want.t_max).abs() <= 1e-4 * want.t_max, "camera {k}: {} vs {}", got.t_max, want.t_max);
                    assert_eq!(got.time, time);
                    if time == 0.0 {
                        assert_eq!((got.o, got.d), (want.o, want.d), "at the start the ray is the static camera's");
                    }
                }
            }
        }
        let p = Camera::perspective(start, 50.0, FovAxis::X, 32, 24).unwrap();
        assert!(p.with_motion(start, 0.0, 1.0, (0.0, 1.0)).unwrap().motion_shutter().is_none());
    }

    /// Light tracing's connection to a moving camera: at each time, what the camera placed by
    /// the interpolated transform answers (film position, lens point, direction, distance and
    /// importance), for a pinhole and a thin lens.
    #[test]
    fn connections_reach_the_camera_where_it_is() {
        let start = Transform::look_at(Vec3::new(0.0, 1.0, -5.0), Vec3::ZERO, Vec3::Y).unwrap();
        let end = Transform::look_at(Vec3::new(1.0, 1.5, -4.5), Vec3::new(0.2, 0.1, 0.0), Vec3::Y).unwrap();
        let motion = AnimatedTransform::new(start, 0.0, end, 1.0).unwrap();
        for lens in [0.0f32, 0.1] {
            let make = |t: Transform| {
                let c = Camera::perspective(t, 45.0, FovAxis::X, 40, 30).unwrap();
                if lens > 0.0 {
                    c.with_thin_lens(lens, 5.0).unwrap()
                } else {
                    c
                }
            };
            let moving = make(start).with_motion(end, 0.0, 1.0, (0.0, 1.0)).unwrap();
            let mut seen = 0;
            for time in [0.0f32, 0.4, 0.9] {
                let at = make(motion.at(time).unwrap());
                for p in [Vec3::new(0.3, 0.2, 0.5), Vec3::new(-0.6, 0.8, 1.0), Vec3::new(0.1, -0.3, -1.0)] {
                    let u = Vec2::new(0.3, 0.6);
                    match (at.sample_wi(p, u), moving.sample_wi_at(p, u, time)) {
                        (Some(a), Some(b)) => {
                            seen += 1;
                            assert!((a.film - b.film).length() < 2e-3, "film {} vs {}", a.film, b.film);
                            assert!((a.p_lens - b.p_lens).length() < 1e-4 && (a.wi - b.wi).length() < 1e-5);
                            assert!((a.dist - b.dist).abs() < 1e-4 && (a.weight - b.weight).abs() < 1e-4 * a.weight);
                        }
                        (None, None) => {}
                        (a, b) => panic!("t {time} {p}: {a:?} vs {b:?}"),
                    }
                }
            }
            assert!(seen >= 6, "too few connections checked: {seen}");
        }
    }

    /// Cameras that cannot move say so; a mirroring end or an empty shutter is an error.
    #[test]
    fn what_cannot_move_is_an_error() {
        let start = Transform::look_at(Vec3::new(0.0, 1.0, -5.0), Vec3::ZERO, Vec3::Y).unwrap();
        let end = Transform::translate(Vec3::X) * start;
        let meter = Camera::radiancemeter(start);
        assert!(meter.with_motion(end, 0.0, 1.0, (0.0, 1.0)).unwrap_err().to_string().contains("radiancemeter"));
        let p = Camera::perspective(start, 50.0, FovAxis::X, 8, 8).unwrap();
        let mirrored = Transform::scale(Vec3::new(-1.0, 1.0, 1.0)).unwrap() * start;
        assert!(p.clone().with_motion(mirrored, 0.0, 1.0, (0.0, 1.0)).is_err());
        assert!(p.with_motion(end, 0.0, 1.0, (1.0, 0.5)).is_err());
    }
}
