//! Geometry: shapes (triangle meshes, spheres, disks, cylinders, SDF grids, curves (pbrt-v4's flat
//! ones, Mitsuba's round linear and B-spline ones), Mitsuba's ellipsoids; rectangles and cubes as meshes;
//! Loop subdivision surfaces as meshes), their
//! ray intersection with floating-point error bounds, and area / solid-angle sampling.
//!
//! All geometry is stored in world space (transforms are applied when a shape is built), so
//! the BVH intersects world-space rays directly.

pub mod curve;
pub mod cylinder;
pub mod disk;
pub mod ellipsoids;
pub mod interaction;
pub mod mesh;
mod registry;
pub mod roundcurve;
pub mod bspline_curve;
pub mod sdfgrid;
pub mod shape;
pub mod sphere;
pub mod subdivision;
pub mod triangle;
pub mod triangle8;

pub use curve::{CurveSet, Curves};
pub use cylinder::Cylinder;
pub use disk::Disk;
pub use ellipsoids::Ellipsoids;
pub use interaction::SurfaceInteraction;
pub use mesh::TriangleMesh;
pub use bspline_curve::BSplineCurves;
pub use roundcurve::LinearCurves;
pub use registry::{is_similarity, shape_plugin, MeshFile, MeshSource, ShapePlugin, SHAPE_PLUGINS};
pub use mesh::MeshError;
pub use sdfgrid::{SdfGrid, SdfGridError};
pub use shape::{Geometry, ShapeSample};
pub use sphere::{Orientation, Sphere, SphereClip};
