//! The built-in Cornell box: the same geometry, camera and colours as
//! `shared/scenes/cbox.xml` (Mitsuba 3's `mi.cornell_box()`: the published Cornell box data
//! rescaled to `[-1, 1]³`, open front, camera at z = 3.9). Rectangles are `[-1, 1]²` with normal
//! +z and cubes `[-1, 1]³`, placed by scale, then rotate, then translate.

use super::{BuildError, Scene, SceneBuilder};
use crate::camera::{Camera, FovAxis};
use crate::geometry::{Geometry, TriangleMesh};
use crate::material::{Bsdf, Diffuse};
use crate::math::{Rgb, Transform, Vec3};

/// Default film size (square), samples per pixel and path depth, as in `cbox.xml`.
pub const DEFAULT_RES: u32 = 256;
/// Default samples per pixel of `cbox.xml`.
pub const DEFAULT_SPP: u32 = 64;
/// Default `max_depth` of `cbox.xml`.
pub const DEFAULT_MAX_DEPTH: i32 = 65;

fn placed(mut mesh: TriangleMesh, scale: Vec3, axis: Vec3, angle: f32, translate: Vec3) -> Geometry {
    let t = Transform::translate(translate)
        * Transform::rotate(axis, angle).expect("non-zero axis")
        * Transform::scale(scale).expect("non-zero scale");
    mesh.transform(&t);
    Geometry::Mesh(mesh)
}

/// The Cornell box rendered on a `width × height` film.
pub fn cornell_box(width: u32, height: u32) -> Result<Scene, BuildError> {
    let mut b = SceneBuilder::new();
    let white = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::new(0.885809, 0.698859, 0.666422))));
    let green = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::new(0.105421, 0.37798, 0.076425))));
    let red = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::new(0.570068, 0.0430135, 0.0443706))));
    let rect = TriangleMesh::rectangle;
    let one = Vec3::ONE;
    // Area light: 0.46 × 0.38, facing down, just below the ceiling.
    b.add_shape(
        placed(rect(), Vec3::new(0.23, 0.19, 0.19), Vec3::X, 90.0, Vec3::new(0.0, 0.99, 0.01)),
        white,
        Some(Rgb::new(18.387, 13.9873, 6.75357)),
    );
    b.add_shape(placed(rect(), one, Vec3::X, -90.0, Vec3::new(0.0, -1.0, 0.0)), white, None); // floor
    b.add_shape(placed(rect(), one, Vec3::X, 90.0, Vec3::new(0.0, 1.0, 0.0)), white, None); // ceiling
    b.add_shape(placed(rect(), one, Vec3::X, 0.0, Vec3::new(0.0, 0.0, -1.0)), white, None); // back
    b.add_shape(placed(rect(), one, Vec3::Y, -90.0, Vec3::new(1.0, 0.0, 0.0)), green, None); // right
    b.add_shape(placed(rect(), one, Vec3::Y, 90.0, Vec3::new(-1.0, 0.0, 0.0)), red, None); // left
    b.add_shape(
        placed(TriangleMesh::cube(), Vec3::splat(0.3), Vec3::Y, -17.0, Vec3::new(0.335, -0.7, 0.38)),
        white,
        None,
    );
    b.add_shape(
        placed(TriangleMesh::cube(), Vec3::new(0.3, 0.61, 0.3), Vec3::Y, 18.25, Vec3::new(-0.33, -0.4, -0.28)),
        white,
        None,
    );
    let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, Vec3::Y).expect("valid look-at");
    b.set_camera(Camera::perspective(to_world, 39.3077, FovAxis::Smaller, width, height)?.with_clip(0.001, 100.0)?);
    b.build()
}
