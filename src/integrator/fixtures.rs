//! Scenes and helpers the integrators' tests share.

use super::{Integrator, RadianceSample};
use crate::camera::{Camera, FovAxis};
use crate::geometry::{Geometry, Sphere, TriangleMesh};
use crate::material::{Bsdf, Diffuse};
use crate::math::{Ray, Rgb, Transform, Vec3};
use crate::sampling::sampler::SamplerKind;
use crate::scene::{Scene, SceneBuilder};

/// Where [`null_sphere_before_a_wall`]'s camera stands.
pub const EYE: Vec3 = Vec3::new(0.0, 0.0, 4.0);

/// A `null` sphere (radius 1, at the origin) in front of a diffuse wall (ρ 0.5, 0.8 × 0.8,
/// facing +z at z = −2) under a white sky, seen from [`EYE`]: a ray from the eye toward the
/// wall, or toward the sky just above it, crosses the sphere twice.
pub fn null_sphere_before_a_wall() -> Scene {
    let mut b = SceneBuilder::new();
    let null = b.add_bsdf(Bsdf::Null);
    b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), null, None);
    let wall = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
    let mut plane = TriangleMesh::rectangle();
    let place = Transform::translate(Vec3::new(0.0, 0.0, -2.0)) * Transform::scale(Vec3::splat(0.4)).unwrap();
    plane.transform(&place);
    b.add_shape(Geometry::Mesh(plane), wall, None);
    b.add_constant_environment(Rgb::ONE);
    let to_world = Transform::look_at(EYE, Vec3::ZERO, Vec3::Y).unwrap();
    b.set_camera(Camera::perspective(to_world, 12.0, FovAxis::X, 2, 1).unwrap());
    b.build().unwrap()
}

/// One sample of `integrator` along the ray from [`EYE`] through `target` (independent
/// sampler, the first sample of its first pixel).
pub fn sample_toward(scene: &Scene, integrator: &impl Integrator, target: Vec3) -> RadianceSample {
    let mut sampler = SamplerKind::Independent.make(64, 0);
    sampler.start_pixel_sample([0, 0], 0, 0);
    integrator.sample(scene, &Ray::new(EYE, (target - EYE).normalize()), &mut sampler, &mut [])
}
