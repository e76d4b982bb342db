//! Why a scene could not be built.

use crate::camera::CameraError;

/// A scene that cannot be built from what was added to its builder.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// No camera was set.
    #[error("the scene has no camera")]
    NoCamera,
    /// A shape names a BSDF that was not added.
    #[error("shape {shape} refers to BSDF {bsdf} but only {count} exist")]
    MissingBsdf {
        /// The shape's index.
        shape: usize,
        /// The BSDF index it names.
        bsdf: u32,
        /// How many BSDFs exist.
        count: usize,
    },
    /// A shape (or the camera) names a medium that was not added.
    #[error("shape {0} or the camera refers to a medium that does not exist")]
    MissingMedium(usize),
    /// An emitting shape has no area to emit from.
    #[error("emitting shape {0} has no area")]
    EmitterWithoutArea(u32),

    /// A moving shape that emits (pbrt-v4 refuses animated area lights too).
    #[error("shape {0} moves and emits light: moving area lights are not implemented")]
    MovingEmitter(u32),

    /// A moving shape whose transform mirrors (other than a triangle mesh, which moves
    /// whatever its transform).
    #[error("shape {0} moves under a mirroring transform, which only a triangle mesh can (motion blur)")]
    MovingShape(u32),
    /// A light's power is not finite, or is negative.
    #[error("a light's power overflows single precision or is negative (check the emitters' scales)")]
    InvalidLightPower,
    /// The camera's parameters are invalid.
    #[error(transparent)]
    Camera(#[from] CameraError),
}

impl From<crate::light::InvalidLightPower> for BuildError {
    fn from(_: crate::light::InvalidLightPower) -> BuildError {
        BuildError::InvalidLightPower
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, FovAxis};
    use crate::geometry::{Geometry, Sphere};
    use crate::material::{Bsdf, Diffuse};
    use crate::math::{Rgb, Transform, Vec3};
    use crate::scene::SceneBuilder;

    #[test]
    fn build_errors_are_typed() {
        assert_eq!(SceneBuilder::new().build().unwrap_err(), BuildError::NoCamera);
        let camera = Camera::perspective(Transform::IDENTITY, 40.0, FovAxis::X, 4, 4).unwrap();
        let mut b = SceneBuilder::new();
        b.set_camera(camera.clone());
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::Z, 1.0, false)), 3, None);
        assert_eq!(b.build().unwrap_err(), BuildError::MissingBsdf { shape: 0, bsdf: 3, count: 0 });
        let mut b = SceneBuilder::new();
        b.set_camera(camera);
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        // Radiance overflowing in the power (4π · π · 10³⁸ is not an f32) is refused; lights
        // that are off are not (the image is black, as in Mitsuba).
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::Z, 1.0, false)), m, Some(Rgb::splat(1e38)));
        assert_eq!(b.build().unwrap_err(), BuildError::InvalidLightPower);
        let mut off = SceneBuilder::new();
        off.set_camera(Camera::perspective(Transform::IDENTITY, 40.0, FovAxis::X, 4, 4).unwrap());
        let m = off.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        off.add_shape(Geometry::Sphere(Sphere::new(Vec3::Z, 1.0, false)), m, Some(Rgb::ZERO));
        assert!(off.build().is_ok());
        // A scene some 10³⁰ units wide under a constant sky: the sky's power (its flux through
        // the scene's bounding sphere, ∝ R²) overflows single precision, not double, and the
        // scene builds and renders, finite.
        let mut wide = SceneBuilder::new();
        wide.set_camera(Camera::perspective(Transform::IDENTITY, 40.0, FovAxis::X, 4, 4).unwrap());
        let m = wide.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        wide.add_shape(Geometry::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0, false)), m, None);
        wide.add_shape(Geometry::Sphere(Sphere::new(Vec3::new(1e30, 0.0, 0.0), 1.0, false)), m, None);
        wide.add_constant_environment(Rgb::ONE);
        let scene = wide.build().unwrap();
        let settings = crate::render::RenderSettings { spp: 4, ..Default::default() };
        let out = crate::render::render(&scene, &crate::integrator::PathIntegrator::default(), &settings, &Default::default());
        let (mean, _) = out.unwrap().film.mean_and_std_error();
        assert!(mean.is_finite() && mean > 0.1, "{mean}");
        let e: BuildError = Camera::perspective(Transform::IDENTITY, 200.0, FovAxis::X, 4, 4).unwrap_err().into();
        assert_eq!(e, BuildError::Camera(CameraError::FieldOfView(200.0)));
        assert!(e.to_string().contains("(0, 180)"), "{e}");
    }
}
