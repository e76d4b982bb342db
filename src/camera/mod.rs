//! Cameras: Mitsuba's `perspective` (pinhole), `thinlens`, `orthographic`, `radiancemeter`
//! (one ray: the radiance arriving at a point from a direction) and `irradiancemeter` (the
//! irradiance on a shape's surface, averaged over it); neumann's `spherical` (pbrt-v4's: every
//! direction around a point, in an equirectangular or an equal-area image); Mitsuba's `batch`
//! (several cameras side by side on one film) and `distant` (the radiance leaving the scene
//! in one direction, averaged over a target); pbrt-v4's `realistic` (a lens system traced ray
//! by ray, [`realistic`]).
//!
//! Camera space looks down +z with +y up and +x to the *left* (Mitsuba's `lookat`
//! convention); film coordinates run from (0, 0) at the top-left pixel corner to
//! (width, height) at the bottom-right. The field of view applies to the axis given by
//! [`FovAxis`].

use crate::geometry::Geometry;
use crate::math::float::offset_ray_origin;
use crate::math::{Bounds3, Frame, Ray, Transform, Vec2, Vec3, ONE_MINUS_EPSILON, PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::{sample_cosine_hemisphere_malley, sample_uniform_disk_concentric};
use std::sync::Arc;

pub mod motion;
pub mod realistic;

pub use crate::props::fov::FovAxis;
pub use motion::CameraMotion;
pub use realistic::LensSystem;

/// A camera that cannot be built from its parameters.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// The field of view is outside (0°, 180°).
    #[error("field of view must be in (0, 180) degrees, got {0}")]
    FieldOfView(f32),
    /// A film side is zero.
    #[error("film size must be positive, got {0}x{1}")]
    FilmSize(u32, u32),
    /// The clip range is empty or negative.
    #[error("need 0 < near_clip < far_clip, got {0} and {1}")]
    Clip(f32, f32),
    /// The thin lens's aperture or focus distance is invalid.
    #[error("need aperture_radius ≥ 0 and focus_distance > 0, got {0}, {1}")]
    Lens(f32, f32),
    /// A radiance or irradiance meter's film is not 1 × 1.
    #[error("a radiancemeter or irradiancemeter measures one value: its film must be 1x1, got {0}x{1}")]
    MeterFilm(u32, u32),
    /// A batch's film width is not a multiple of its camera count (or it has none).
    #[error("a batch sensor's film width ({0}) must be a positive multiple of the number of nested sensors ({1})")]
    BatchWidth(u32, usize),
    /// An irradiance meter's shape has no area to sample.
    #[error("an irradiancemeter needs a shape with an area (a mesh, rectangle, disk, sphere or cylinder)")]
    MeterShape,
    /// The camera cannot move as asked (motion blur).
    #[error("{0}")]
    Motion(String),
}

/// How camera space maps to rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// Rays from the centre of projection (or the lens) through the plane z = 1.
    Perspective,
    /// Parallel rays along +z from the near-clip plane; the film spans x ∈ [-1, 1] and
    /// y ∈ [-1/aspect, 1/aspect] of camera space (Mitsuba's `orthographic`; `to_world` scales it).
    Orthographic,
    /// Rays in every direction from the centre (pbrt-v4's `spherical`), laid out on the film
    /// by a [`SphericalMapping`] of its (u, v) = (x / width, y / height).
    Spherical(SphericalMapping),
    /// Every ray starts at the origin and runs along +z (Mitsuba's `radiancemeter`): the 1 × 1
    /// film measures the radiance arriving at that point from that direction (W m⁻² sr⁻¹),
    /// whatever the film position.
    Radiancemeter,
    /// Mitsuba's `irradiancemeter`: each ray starts at a point uniform on a shape's surface
    /// (from the film position, uniform over the 1 × 1 film) in a cosine-distributed direction
    /// about its normal (from the lens sample), and carries the weight π: the film measures the
    /// irradiance `E = ∫ L cos θ dω` (W m⁻²) averaged over the surface.
    Irradiancemeter,
    /// Mitsuba's `distant`: parallel rays along `to_world`'s +z from outside the scene's
    /// bounding sphere toward a [`DistantTarget`] (the lens sample picks the target point);
    /// the 1 × 1 film measures the radiance leaving the scene in the opposite direction,
    /// averaged over the target.
    Distant,
    /// Mitsuba's `batch`: the film is split into as many columns of equal width as there are
    /// cameras, column k rendered by camera k on a film of that column's size.
    Batch,
    /// pbrt-v4's `realistic`: rays traced from the film through a [`LensSystem`], each with
    /// its own weight (none where the lens stops it).
    Realistic,
}

/// The rays one pixel to the right (`x`) and one pixel down (`y`) of a camera ray (Mitsuba's
/// ray differentials): their origins and directions, world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayDifferentials {
    /// Origin of the ray one pixel to the right.
    pub o_x: Vec3,
    /// Origin of the ray one pixel down.
    pub o_y: Vec3,
    /// Direction of the ray one pixel to the right.
    pub d_x: Vec3,
    /// Direction of the ray one pixel down.
    pub d_y: Vec3,
}

impl RayDifferentials {
    /// The differentials moved by the world-to-world map `m` (a moving camera's, at its ray's
    /// time): those of the camera placed where it then is.
    pub fn moved(self, m: &Transform) -> RayDifferentials {
        RayDifferentials {
            o_x: m.apply_point(self.o_x),
            o_y: m.apply_point(self.o_y),
            d_x: m.apply_vector(self.d_x),
            d_y: m.apply_vector(self.d_y),
        }
    }

    /// Mitsuba's `scale_differential`: the offset rays moved toward `ray` to the fraction `s`
    /// of their offset (a render of N samples per pixel uses `s = 1/√N`, the spacing of its
    /// samples).
    pub fn scaled(self, ray: &Ray, s: f32) -> RayDifferentials {
        RayDifferentials {
            o_x: ray.o + (self.o_x - ray.o) * s,
            o_y: ray.o + (self.o_y - ray.o) * s,
            d_x: ray.d + (self.d_x - ray.d) * s,
            d_y: ray.d + (self.d_y - ray.d) * s,
        }
    }
}

/// How a spherical camera lays the sphere of directions out on the film. With (u, v) the film
/// position over its size (v down the image), θ, φ and the equal-area square are pbrt-v4's,
/// about the camera's +y (up) axis: the direction is `(−sin θ cos φ, cos θ, sin θ sin φ)` in
/// camera space (+x left, +y up, +z ahead): the image's centre (u = ½, φ = π) looks along
/// camera +x, to the left of the view direction, and u = ¼ straight ahead, as in pbrt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphericalMapping {
    /// θ = π v from up, φ = 2π u: latitude–longitude.
    Equirectangular,
    /// pbrt-v4's equal-area octahedral square (Clarberg), its z axis turned to camera +y: every
    /// pixel covers the same solid angle.
    EqualArea,
}

/// Where a distant sensor's rays go (Mitsuba's `target`).
#[derive(Clone, Debug)]
pub enum DistantTarget {
    /// Uniformly over the cross-section of the scene's bounding sphere (no `target`).
    Scene,
    /// Every ray through this world point.
    Point(Vec3),
    /// Uniformly over this surface (world space; not part of the scene), area sampling
    /// prepared.
    Shape(Arc<Geometry>),
}

/// A perspective camera, optionally with a thin lens, or an orthographic one.
#[derive(Clone, Debug)]
pub struct Camera {
    projection: Projection,
    to_world: Transform,
    fov_deg: f32,
    fov_axis: FovAxis,
    /// tan of half the horizontal / vertical field of view.
    tan_half: Vec2,
    /// Film position (pixels) to the camera-space plane z = 1: `xy = film · plane_scale +
    /// plane_origin` (the NDC mapping and the field of view folded into one multiply-add).
    plane_scale: Vec2,
    /// The plane point of film position (0, 0): `tan_half`, moved by the principal point offset.
    plane_origin: Vec2,
    /// Mitsuba's `principal_point_offset_x/y`: the film is shifted by this fraction of its width
    /// and height (the image's centre no longer on the view axis; 0 for a centred film).
    principal_offset: Vec2,
    width: u32,
    height: u32,
    near_clip: f32,
    far_clip: f32,
    lens_radius: f32,
    focus_distance: f32,
    /// The surface an irradiance meter measures (its area sampling prepared).
    meter_shape: Option<Arc<Geometry>>,
    /// A batch's cameras, left to right, each on its column's film.
    batch: Vec<Camera>,
    /// A distant sensor's target.
    distant: Option<DistantTarget>,
    /// The scene's bounding sphere (centre, radius), which a distant sensor aims at.
    scene_sphere: (Vec3, f32),
    /// A realistic camera's lens.
    lens: Option<Arc<LensSystem>>,
    /// Where the camera moves over the shutter (motion blur; `None`: it stays at `to_world`).
    motion: Option<CameraMotion>,
}

impl Camera {
    /// Pinhole camera placed by `to_world` (e.g. [`Transform::look_at`]) with a full field of
    /// view `fov_deg` along `fov_axis`, for a `width × height` film.
    pub fn perspective(
        to_world: Transform,
        fov_deg: f32,
        fov_axis: FovAxis,
        width: u32,
        height: u32,
    ) -> Result<Camera, CameraError> {
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(CameraError::FieldOfView(fov_deg));
        }
        if width == 0 || height == 0 {
            return Err(CameraError::FilmSize(width, height));
        }
        let tan_half = crate::props::fov::tan_half(fov_deg, fov_axis, width as f32 / height as f32);
        // x_plane = -(2 x / width - 1) tan_x (camera +x is left, film x grows right); likewise y.
        let plane_scale = Vec2::new(-2.0 * tan_half.x / width as f32, -2.0 * tan_half.y / height as f32);
        Ok(Camera {
            projection: Projection::Perspective,
            to_world,
            fov_deg,
            fov_axis,
            tan_half,
            plane_scale,
            plane_origin: tan_half,
            principal_offset: Vec2::ZERO,
            width,
            height,
            near_clip: 1e-2,
            far_clip: 1e4,
            lens_radius: 0.0,
            focus_distance: 1.0,
            meter_shape: None,
            batch: Vec::new(),
            distant: None,
            scene_sphere: (Vec3::ZERO, 1.0),
            lens: None,
            motion: None,
        })
    }

    /// Mitsuba's orthographic camera placed (and scaled) by `to_world` for a `width × height`
    /// film: camera-space x ∈ [-1, 1] spans the film's width, y ∈ [-1/aspect, 1/aspect] its
    /// height; rays are parallel to +z.
    pub fn orthographic(to_world: Transform, width: u32, height: u32) -> Result<Camera, CameraError> {
        // The same film-to-plane mapping as a perspective camera whose half-extents at z = 1
        // are (1, 1/aspect), i.e. a 90° horizontal field of view.
        let c = Camera::perspective(to_world, 90.0, FovAxis::X, width, height)?;
        Ok(Camera { projection: Projection::Orthographic, ..c })
    }

    /// Mitsuba's radiance meter placed by `to_world`: every ray starts at its origin along its
    /// +z, unbounded; the film is 1 × 1.
    pub fn radiancemeter(to_world: Transform) -> Camera {
        let c = Camera::perspective(to_world, 90.0, FovAxis::X, 1, 1).expect("a valid 90° 1x1 camera");
        Camera { projection: Projection::Radiancemeter, ..c }
    }

    /// Mitsuba's irradiance meter on the surface `shape` (world space; front side as its
    /// normals face); the film is 1 × 1. An error for a shape without area (an SDF grid,
    /// curves).
    pub fn irradiancemeter(shape: &Geometry) -> Result<Camera, CameraError> {
        let c = Camera::radiancemeter(Transform::IDENTITY);
        Ok(Camera { projection: Projection::Irradiancemeter, meter_shape: Some(sampled_shape(shape)?), ..c })
    }

    /// Mitsuba's distant sensor looking along `to_world`'s +z at `target`; the film is 1 × 1.
    /// Its rays need the scene's bounds ([`Camera::with_scene_bounds`], which building a scene
    /// applies). An error for a target shape without area.
    pub fn distant(to_world: Transform, target: DistantTarget) -> Result<Camera, CameraError> {
        let target = match target {
            DistantTarget::Shape(shape) => DistantTarget::Shape(sampled_shape(&shape)?),
            t => t,
        };
        let c = Camera::radiancemeter(to_world);
        Ok(Camera { projection: Projection::Distant, distant: Some(target), ..c })
    }

    /// pbrt-v4's realistic camera placed by `to_world` (camera space as this module's: +x
    /// left), its rays traced through `lens` for a `width × height` film.
    pub fn realistic(to_world: Transform, lens: LensSystem, width: u32, height: u32) -> Result<Camera, CameraError> {
        let c = Camera::perspective(to_world, 90.0, FovAxis::X, width, height)?;
        Ok(Camera { projection: Projection::Realistic, lens: Some(Arc::new(lens)), ..c })
    }

    /// The camera for a scene whose shapes lie in `bounds`: a distant sensor aims at their
    /// bounding sphere (Mitsuba's, its radius enlarged by a relative 10⁻⁴ and at least 10⁻⁴);
    /// other cameras are unchanged.
    pub fn with_scene_bounds(mut self, bounds: Bounds3) -> Camera {
        if bounds.is_finite() && !bounds.is_empty() {
            let (centre, radius) = bounds.bounding_sphere();
            self.scene_sphere = (centre, (radius * (1.0 + 1e-4)).max(1e-4));
        }
        self
    }

    /// The width of each of a batch's `n` columns on a film `width` wide: an error unless
    /// `width` is a positive multiple of `n`.
    pub fn batch_column_width(width: u32, n: usize) -> Result<u32, CameraError> {
        match u32::try_from(n) {
            Ok(n) if n > 0 && width > 0 && width.is_multiple_of(n) => Ok(width / n),
            _ => Err(CameraError::BatchWidth(width, n)),
        }
    }

    /// Mitsuba's batch sensor: `cameras` side by side on a `width × height` film, each on a
    /// `width / n × height` column (their own film sizes are replaced). `width` must be a
    /// multiple of their number `n`.
    pub fn batch(cameras: Vec<Camera>, width: u32, height: u32) -> Result<Camera, CameraError> {
        let column = Camera::batch_column_width(width, cameras.len())?;
        let columns =
            cameras.iter().map(|c| c.with_resolution(column, height)).collect::<Result<Vec<Camera>, CameraError>>()?;
        let first = columns[0].clone();
        Ok(Camera { projection: Projection::Batch, width, height, batch: columns, ..first })
    }

    /// The weight every camera ray's radiance carries: π for an irradiance meter (cosine
    /// sampling of the irradiance integral), 1 otherwise.
    #[inline]
    pub fn ray_weight(&self) -> f32 {
        if self.projection == Projection::Irradiancemeter {
            PI
        } else {
            1.0
        }
    }

    /// The projection.
    pub fn projection(&self) -> Projection {
        self.projection
    }

    /// The same camera on a `width × height` film: the field of view along its axis is kept, the
    /// other follows the new aspect ratio (orthographic: the width keeps its extent).
    pub fn with_resolution(&self, width: u32, height: u32) -> Result<Camera, CameraError> {
        if self.projection == Projection::Batch {
            return Camera::batch(self.batch.clone(), width, height);
        }
        let meter =
            matches!(self.projection, Projection::Radiancemeter | Projection::Irradiancemeter | Projection::Distant);
        if meter && (width, height) != (1, 1) {
            return Err(CameraError::MeterFilm(width, height));
        }
        let c = Camera::perspective(self.to_world, self.fov_deg, self.fov_axis, width, height)?;
        let c = Camera { tan_half: c.tan_half, plane_scale: c.plane_scale, width, height, ..self.clone() };
        Ok(c.with_principal_point(self.principal_offset))
    }

    /// Shifts the film of a perspective camera by `offset` times its width and height
    /// (Mitsuba's `principal_point_offset_x/y`): film position `p` sees what film position
    /// `p + offset · (width, height)` of the centred camera sees, as in Mitsuba, whose sample
    /// position moves by the offset over the film (crop windows included).
    pub fn with_principal_point(mut self, offset: Vec2) -> Camera {
        self.principal_offset = offset;
        self.plane_origin = self.tan_half * (Vec2::ONE - 2.0 * offset);
        self
    }

    /// Sets the near and far clip distances (along the view axis).
    pub fn with_clip(mut self, near: f32, far: f32) -> Result<Camera, CameraError> {
        if !(near > 0.0 && far > near) {
            return Err(CameraError::Clip(near, far));
        }
        self.near_clip = near;
        self.far_clip = far;
        Ok(self)
    }

    /// Makes it a thin-lens camera (Mitsuba's `thinlens`): `aperture_radius` and
    /// `focus_distance` in world units.
    pub fn with_thin_lens(mut self, aperture_radius: f32, focus_distance: f32) -> Result<Camera, CameraError> {
        if !(aperture_radius >= 0.0 && focus_distance > 0.0) {
            return Err(CameraError::Lens(aperture_radius, focus_distance));
        }
        self.lens_radius = aperture_radius;
        self.focus_distance = focus_distance;
        Ok(self)
    }

    /// Film width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Film height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The camera moving from its `to_world` at time `t0` to `end` at `t1` (motion blur: pbrt-v4's
    /// animated camera transform), its rays drawing their time uniformly over `shutter`. The
    /// same camera where `end` is its `to_world`. Perspective, thin-lens, orthographic,
    /// spherical and realistic cameras move; meters, distant sensors and batches are an error,
    /// as are the transforms [`crate::math::AnimatedTransform::new`] refuses.
    pub fn with_motion(mut self, end: Transform, t0: f32, t1: f32, shutter: (f32, f32)) -> Result<Camera, CameraError> {
        let name = match self.projection {
            Projection::Perspective | Projection::Orthographic | Projection::Spherical(_) | Projection::Realistic => None,
            Projection::Radiancemeter => Some("radiancemeter"),
            Projection::Irradiancemeter => Some("irradiancemeter"),
            Projection::Distant => Some("distant sensor"),
            Projection::Batch => Some("batch sensor"),
        };
        if let Some(name) = name {
            return Err(CameraError::Motion(format!("a {name} cannot move (motion blur moves perspective, thin-lens, orthographic, spherical and realistic cameras)")));
        }
        self.motion = CameraMotion::new(self.to_world, t0, end, t1, shutter).map_err(CameraError::Motion)?;
        Ok(self)
    }

    /// The shutter interval camera rays draw their time from where the camera moves; `None`
    /// for a camera at rest.
    pub fn motion_shutter(&self) -> Option<(f32, f32)> {
        self.motion.as_ref().map(CameraMotion::shutter)
    }

    /// The world-to-world map from the camera's start placement to where it is at `time`
    /// (`None` for a camera at rest).
    #[inline]
    pub fn moved_by(&self, time: f32) -> Option<Transform> {
        self.motion.as_ref().and_then(|m| m.moved_by(time))
    }

    /// A ray made at the camera's start placement (by [`Camera::sample_ray`] or
    /// [`Camera::generate_ray`]) moved to where the camera is at `time`, carrying `time`; with
    /// the start-to-`time` map that moved it (`None` at rest or at the start), for the ray's
    /// differentials.
    #[inline]
    pub fn ray_at_time(&self, ray: &Ray, time: f32) -> (Ray, Option<Transform>) {
        match self.moved_by(time) {
            Some(m) => (motion::moved_ray(&m, ray).at_time(time), Some(m)),
            None => (ray.at_time(time), None),
        }
    }

    /// [`Camera::sample_ray`] at `time`: the ray of the camera where it is then, carrying
    /// `time`.
    #[inline]
    pub fn sample_ray_at(&self, film: Vec2, u_lens: Vec2, time: f32) -> (Ray, f32) {
        let (ray, weight) = self.sample_ray(film, u_lens);
        (self.ray_at_time(&ray, time).0, weight)
    }

    /// [`Camera::sample_wi`] for the camera where it is at `time` (light tracing's
    /// connections from a light path of that time).
    pub fn sample_wi_at(&self, p: Vec3, u_lens: Vec2, time: f32) -> Option<CameraSample> {
        let Some(m) = self.moved_by(time) else { return self.sample_wi(p, u_lens) };
        // The point where it is relative to the camera's start placement, connected there,
        // and the lens point moved back to where the camera is.
        let cs = self.sample_wi(m.inverse().apply_point(p), u_lens)?;
        let p_lens = m.apply_point(cs.p_lens);
        let w = p_lens - p;
        let dist = w.length();
        if dist <= 0.0 || dist.is_nan() {
            return None;
        }
        // The importance's 1/r² at the moved distance (the same where the motion is rigid).
        let weight = cs.weight * (cs.dist / dist) * (cs.dist / dist);
        weight.is_finite().then_some(CameraSample { film: cs.film, p_lens, wi: w / dist, dist, weight })
    }

    /// Centre of projection (world).
    pub fn position(&self) -> Vec3 {
        self.to_world.apply_point(Vec3::ZERO)
    }

    /// World-space ray through film position `film` (pixels, continuous) and lens sample
    /// `u_lens ∈ [0,1)²` (ignored by a pinhole). The direction is unit length; the ray spans the
    /// clip range.
    #[inline]
    pub fn generate_ray(&self, film: Vec2, u_lens: Vec2) -> Ray {
        match self.projection {
            Projection::Perspective => self.perspective_ray(film, u_lens),
            Projection::Orthographic => {
                // Mitsuba: the origin on the near plane, through to_world (which may scale it);
                // the direction is to_world's +z, normalized; the ray spans far − near.
                let xy = self.plane_point(film);
                let o = self.to_world.apply_point(Vec3::new(xy.x, xy.y, self.near_clip));
                let d = self.to_world.apply_vector(Vec3::Z).normalize();
                Ray::bounded(o, d, self.far_clip - self.near_clip)
            }
            Projection::Spherical(mapping) => {
                let uv = Vec2::new(film.x / self.width as f32, film.y / self.height as f32);
                let d = self.to_world.apply_vector(spherical_direction(mapping, uv)).normalize();
                let o = self.to_world.apply_point(Vec3::ZERO);
                Ray::bounded(o + d * self.near_clip, d, self.far_clip - self.near_clip)
            }
            Projection::Radiancemeter => {
                let o = self.to_world.apply_point(Vec3::ZERO);
                Ray::new(o, self.to_world.apply_vector(Vec3::Z).normalize())
            }
            Projection::Irradiancemeter => self.irradiance_meter_ray(film, u_lens),
            Projection::Distant => self.distant_ray(u_lens),
            Projection::Batch => {
                let column = (self.width as usize / self.batch.len()) as f32;
                let k = ((film.x / column) as usize).min(self.batch.len() - 1);
                self.batch[k].generate_ray(Vec2::new(film.x - k as f32 * column, film.y), u_lens)
            }
            Projection::Realistic => self.realistic_ray(film, u_lens).map_or_else(|| self.stopped_ray(), |(r, _)| r),
        }
    }

    /// [`Camera::generate_ray`] with the weight the radiance along it carries: π for an
    /// irradiance meter, a realistic camera's lens weight, 1 otherwise; 0 (and a ray of no
    /// length) where a realistic camera's lens stops the ray.
    #[inline]
    pub fn sample_ray(&self, film: Vec2, u_lens: Vec2) -> (Ray, f32) {
        if self.projection == Projection::Realistic {
            return self.realistic_ray(film, u_lens).unwrap_or_else(|| (self.stopped_ray(), 0.0));
        }
        (self.generate_ray(film, u_lens), self.ray_weight())
    }

    /// A realistic camera's ray through the lens and its weight, or `None` where the lens stops
    /// it (camera space turned from pbrt's, +x right, to this module's, +x left).
    fn realistic_ray(&self, film: Vec2, u_lens: Vec2) -> Option<(Ray, f32)> {
        let lens = self.lens.as_ref()?;
        let size = Vec2::new(self.width as f32, self.height as f32);
        let (o, d, weight) = lens.ray(film, size, u_lens)?;
        let flip = |v: Vec3| Vec3::new(-v.x, v.y, v.z);
        let d = self.to_world.apply_vector(flip(d)).normalize();
        Some((Ray::new(self.to_world.apply_point(flip(o)), d), weight))
    }

    /// The ray of a camera sample the lens stops: no length, from the camera's position.
    fn stopped_ray(&self) -> Ray {
        Ray::bounded(self.position(), self.to_world.apply_vector(Vec3::Z).normalize(), 0.0)
    }

    /// The ray differentials of the camera ray `ray` that [`Camera::generate_ray`] made from
    /// `film` and `u_lens`, as Mitsuba 3.9.1's `sample_ray_differential` gives them: the rays
    /// through the film position one pixel to the right and one pixel down. A pinhole's start
    /// at `ray`'s origin (Mitsuba's perspective sensor); every other projection's are its own
    /// rays from those film positions with the same lens sample (Mitsuba's generic sensor
    /// rule, which its thin lens and orthographic sensors follow; a batch asks the camera of
    /// the column). Where the film position does not choose the ray (radiance meter, distant
    /// sensor) they are `ray` itself; an irradiance meter's wrap around its one pixel, where
    /// Mitsuba extrapolates the shape's sampling beyond it.
    pub fn ray_differentials(&self, film: Vec2, u_lens: Vec2, ray: &Ray) -> RayDifferentials {
        match self.projection {
            Projection::Perspective if self.lens_radius == 0.0 => {
                let xy = self.plane_point(film);
                let near = Vec3::new(xy.x, xy.y, 1.0);
                let direction = |step: Vec3| self.to_world.apply_vector((near + step).normalize());
                RayDifferentials {
                    o_x: ray.o,
                    o_y: ray.o,
                    d_x: direction(Vec3::new(self.plane_scale.x, 0.0, 0.0)),
                    d_y: direction(Vec3::new(0.0, self.plane_scale.y, 0.0)),
                }
            }
            Projection::Batch => {
                let column = (self.width as usize / self.batch.len()) as f32;
                let k = ((film.x / column) as usize).min(self.batch.len() - 1);
                self.batch[k].ray_differentials(Vec2::new(film.x - k as f32 * column, film.y), u_lens, ray)
            }
            _ => {
                // (A realistic camera's offset ray the lens stops: the ray itself.)
                let at = |f: Vec2| Some(self.generate_ray(f, u_lens)).filter(|r| r.t_max > 0.0).unwrap_or(*ray);
                let (x, y) = (at(film + Vec2::X), at(film + Vec2::Y));
                RayDifferentials { o_x: x.o, o_y: y.o, d_x: x.d, d_y: y.d }
            }
        }
    }

    /// The camera-space point on the plane z = 1 (perspective) or of the film (orthographic)
    /// that film position `film` maps to. +x is left and +y is up in camera space; film x grows
    /// right and y grows down.
    #[inline]
    fn plane_point(&self, film: Vec2) -> Vec2 {
        film * self.plane_scale + self.plane_origin
    }

    /// A pinhole or thin-lens ray through `film`.
    #[inline]
    fn perspective_ray(&self, film: Vec2, u_lens: Vec2) -> Ray {
        let xy = self.plane_point(film);
        let d = Vec3::new(xy.x, xy.y, 1.0);
        let (o, d) = if self.lens_radius > 0.0 {
            let lens = sample_uniform_disk_concentric(u_lens).value * self.lens_radius;
            let focus = d * self.focus_distance;
            let o = Vec3::new(lens.x, lens.y, 0.0);
            (o, focus - o)
        } else {
            (Vec3::ZERO, d)
        };
        let inv_z = 1.0 / d.z;
        let o_clip = o + d * (self.near_clip * inv_z);
        let len = d.length();
        let t_max = (self.far_clip - self.near_clip) * inv_z * len;
        let d_world = self.to_world.apply_vector(d).normalize();
        Ray::bounded(self.to_world.apply_point(o_clip), d_world, t_max)
    }

    /// An irradiance meter's ray: the film position within the one pixel picks the point on
    /// the shape, the lens sample the cosine-distributed direction (as Mitsuba's
    /// `irradiancemeter` does).
    fn irradiance_meter_ray(&self, film: Vec2, u_lens: Vec2) -> Ray {
        let u = (film - film.floor()).clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON));
        let Some(ps) = self.meter_shape.as_ref().and_then(|shape| shape.sample_area(u)) else {
            return Ray::bounded(Vec3::ZERO, Vec3::Z, 0.0);
        };
        let d = Frame::from_z(ps.ns).to_world(sample_cosine_hemisphere_malley(u_lens).value);
        Ray::new(offset_ray_origin(ps.p, ps.p_error, ps.ng, d), d)
    }

    /// A distant sensor's ray toward the target point the lens sample picks, from outside the
    /// scene's bounding sphere.
    fn distant_ray(&self, u_lens: Vec2) -> Ray {
        let d = self.to_world.apply_vector(Vec3::Z).normalize();
        let (centre, radius) = self.scene_sphere;
        let o = match &self.distant {
            Some(DistantTarget::Point(p)) => *p - d * (2.0 * radius),
            Some(DistantTarget::Shape(shape)) => match shape.sample_area(u_lens) {
                Some(ps) => ps.p - d * (2.0 * radius),
                None => return Ray::bounded(Vec3::ZERO, Vec3::Z, 0.0),
            },
            Some(DistantTarget::Scene) | None => {
                let offset = sample_uniform_disk_concentric(u_lens).value * radius;
                centre + Frame::from_z(d).to_world(Vec3::new(offset.x, offset.y, 0.0)) - d * radius
            }
        };
        Ray::new(o, d)
    }
}

/// A connection from a scene point to the camera ([`Camera::sample_wi`]).
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// Film position (pixels, continuous) the connection lands on.
    pub film: Vec2,
    /// Point on the lens (world; the centre of projection for a pinhole).
    pub p_lens: Vec3,
    /// Unit direction from the scene point toward `p_lens`.
    pub wi: Vec3,
    /// Distance from the scene point to `p_lens`.
    pub dist: f32,
    /// `Wₑ cos θ_c / (r² p_lens)`: the camera's importance for this connection times the
    /// geometry at the camera end, divided by the lens-position pdf, normalised so that a
    /// pixel's value is the sum of its splats over all light paths divided by the
    /// number of paths per pixel. Equals `1 / (A cos³θ_c r²)` with `A` the film's area on the
    /// plane at unit distance, `θ_c` the angle to the view axis and `r` the distance. The
    /// surface cosine at the scene point is not included.
    pub weight: f32,
}

impl Camera {
    /// Connects the world point `p` to the camera (light tracing): a lens position (uniform
    /// on the aperture disk from `u_lens`; the centre for a pinhole), the film position whose
    /// camera ray through that lens point passes through `p`, and the importance weight.
    /// `None` if `p` is behind the camera, outside the clip range, or projects off the film.
    ///
    /// Derivation: a pixel's value is `(1/A_pix)(1/A_lens) ∫∫ L dA_film dA_lens` with the film
    /// on the plane at unit distance; the camera ray's solid angle is `dω = cos³θ dA_film`, and
    /// from the scene point's side `dω = |cos θ_y| dA_y / r²`.
    pub fn sample_wi(&self, p: Vec3, u_lens: Vec2) -> Option<CameraSample> {
        if self.projection != Projection::Perspective {
            // A parallel projection has no point to connect to (Mitsuba's orthographic sensor
            // cannot be sampled by direction either); the light tracer refuses it up front.
            return None;
        }
        let local = self.to_world.inverse().apply_point(p);
        if !(local.z >= self.near_clip && local.z <= self.far_clip) {
            return None;
        }
        let lens = if self.lens_radius > 0.0 {
            let q = sample_uniform_disk_concentric(u_lens).value * self.lens_radius;
            Vec3::new(q.x, q.y, 0.0)
        } else {
            Vec3::ZERO
        };
        // Direction (plane z = 1) of the pinhole ray that meets the lens ray in the focal plane.
        let to_p = local - lens;
        let d = if self.lens_radius > 0.0 {
            let focus = lens + to_p * (self.focus_distance / to_p.z);
            focus / self.focus_distance
        } else {
            to_p / to_p.z
        };
        let ndc = Vec2::new(-d.x / self.tan_half.x, -d.y / self.tan_half.y);
        let size = Vec2::new(self.width as f32, self.height as f32);
        let film = (ndc + Vec2::ONE) * 0.5 * size - self.principal_offset * size;
        if !(film.x >= 0.0 && film.x < self.width as f32 && film.y >= 0.0 && film.y < self.height as f32) {
            return None;
        }
        let p_lens = self.to_world.apply_point(lens);
        let w = p_lens - p;
        let dist = w.length();
        if dist <= 0.0 || dist.is_nan() {
            return None;
        }
        let cos = to_p.z / to_p.length();
        let area = 4.0 * self.tan_half.x * self.tan_half.y;
        let weight = 1.0 / (area * cos * cos * cos * dist * dist);
        weight.is_finite().then_some(CameraSample { film, p_lens, wi: w / dist, dist, weight })
    }
}

/// The camera-space direction of film position `uv` (over the film's size) of a spherical
/// camera (see [`SphericalMapping`]).
pub fn spherical_direction(mapping: SphericalMapping, uv: Vec2) -> Vec3 {
    // pbrt-v4's direction about its z axis, then its y and z swapped (z up → y up), then its
    // camera's +x (right) turned to neumann's (+x left).
    let d = match mapping {
        SphericalMapping::Equirectangular => {
            let (theta, phi) = (std::f32::consts::PI * uv.y, 2.0 * std::f32::consts::PI * uv.x);
            Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
        }
        SphericalMapping::EqualArea => {
            let wrap = |x: f32| x.clamp(0.0, 1.0);
            crate::sampling::equal_area::equal_area_square_to_sphere(Vec2::new(wrap(uv.x), wrap(uv.y)))
        }
    };
    Vec3::new(-d.x, d.z, d.y)
}

/// Camera plugins by their (Mitsuba) names.
pub const CAMERA_PLUGINS: &[&str] = &[
    "perspective",
    "thinlens",
    "orthographic",
    "radiancemeter",
    "irradiancemeter",
    "distant",
    "batch",
    "spherical",
    "realistic",
];

impl Camera {
    /// Mitsuba's `perspective` and `thinlens` sensors for a `width × height` film: `to_world`,
    /// `fov` + `fov_axis` (`x` default, `y`, `diagonal`, `smaller`, `larger`) or `focal_length`
    /// (default `50mm`: the diagonal field of view of a 36 × 24 mm frame), `near_clip` (0.01),
    /// `far_clip` (10⁴), `focus_distance` (default `far_clip`: every projective camera of
    /// Mitsuba reads it; only the thin lens focuses); perspective: `principal_point_offset_x/y`
    /// (0; the film shifted by that fraction of its size, see [`Camera::with_principal_point`]);
    /// thin lens: `aperture_radius` (required).
    /// `orthographic`: `to_world` (its scale sets the extent: camera-space x ∈ [-1, 1] spans the
    /// film's width), `near_clip`, `far_clip`, `focus_distance`. `radiancemeter`: `to_world`
    /// (rays from its origin along its +z), or else `origin` and `direction` (both; default the
    /// world origin and +z), a 1 × 1 film.
    pub fn from_props(o: &Obj, width: u32, height: u32) -> PropResult<Camera> {
        if !CAMERA_PLUGINS.contains(&o.ty.as_str()) {
            return Err(o.unknown_plugin(CAMERA_PLUGINS));
        }
        if o.ty == "radiancemeter" {
            return Camera::radiancemeter_from_props(o, width, height);
        }
        if o.ty == "distant" {
            // (The loader builds it, with its target shape, by `Camera::distant`.)
            return Err(o.error("a distant sensor cannot be part of a batch"));
        }
        if o.ty == "batch" {
            // (The loader builds it from the nested sensors with `Camera::batch`.)
            return Err(o.error("a batch sensor cannot be nested in another"));
        }
        if o.ty == "realistic" {
            // (The loader builds it, with its lens file, by `Camera::realistic`.)
            return Err(o.error("a realistic sensor cannot be part of a batch"));
        }
        if o.ty == "irradiancemeter" {
            // (The loader builds one nested in a shape with `Camera::irradiancemeter`.)
            return Err(o.error("an irradiancemeter must be nested in the <shape> whose irradiance it measures"));
        }
        let to_world = o.transform("to_world")?;
        check_shutter(o)?;
        let (near, far) = (o.float("near_clip", 0.01)?, o.float("far_clip", 10000.0)?);
        let focus = o.float_checked("focus_distance", far, |d| d > 0.0 && d.is_finite(), "positive")?;
        if o.ty == "spherical" {
            let mapping = match o.choice("mapping", &["equirectangular", "equal_area"])?.as_str() {
                "equirectangular" => SphericalMapping::Equirectangular,
                _ => SphericalMapping::EqualArea,
            };
            let camera = Camera::perspective(to_world, 90.0, FovAxis::X, width, height)
                .map_err(|e| o.error(e.to_string()))?
                .with_clip(near, far)
                .map_err(|e| o.error_at("near_clip", e.to_string()))?;
            return Ok(Camera { projection: Projection::Spherical(mapping), ..camera });
        }
        if o.ty == "orthographic" {
            let camera = Camera::orthographic(to_world, width, height).map_err(|e| o.error(e.to_string()))?;
            return camera.with_clip(near, far).map_err(|e| o.error_at("near_clip", e.to_string()));
        }
        let (fov, axis) = crate::props::fov::fov_from_props(o)?;
        let mut camera =
            Camera::perspective(to_world, fov, axis, width, height).map_err(|e| o.error_at("fov", e.to_string()))?;
        camera = camera.with_clip(near, far).map_err(|e| o.error_at("near_clip", e.to_string()))?;
        if o.ty == "perspective" {
            // (Mitsuba's thin lens does not take the offset.)
            // (Bounded so that the film's plane coordinates stay finite.)
            let ok = |v: f32| v.abs() <= 1e6;
            let what = "a finite fraction of the film, at most 10⁶ in size";
            let x = o.float_checked("principal_point_offset_x", 0.0, ok, what)?;
            let y = o.float_checked("principal_point_offset_y", 0.0, ok, what)?;
            camera = camera.with_principal_point(Vec2::new(x, y));
        }
        if o.ty == "thinlens" {
            let r = o.float_opt("aperture_radius")?.ok_or_else(|| o.error("'aperture_radius' is required"))?;
            camera = camera.with_thin_lens(r, focus).map_err(|e| o.error_at("aperture_radius", e.to_string()))?;
        }
        Ok(camera)
    }
}

impl Camera {
    /// Mitsuba's `radiancemeter` (see [`Camera::from_props`]): a `to_world` wins over `origin`
    /// and `direction`, as in Mitsuba (which reads and ignores them then).
    fn radiancemeter_from_props(o: &Obj, width: u32, height: u32) -> PropResult<Camera> {
        require_one_pixel(o, width, height)?;
        let (origin, direction) = (o.point_opt("origin")?, o.point_opt("direction")?);
        if o.get("to_world").is_some() {
            return Ok(Camera::radiancemeter(o.transform("to_world")?));
        }
        let to_world = match (origin, direction) {
            (None, None) => Transform::IDENTITY,
            (Some(p), Some(d)) => look_along(o, p, d)?,
            _ => return Err(o.error("give both 'origin' and 'direction' (or a 'to_world')")),
        };
        Ok(Camera::radiancemeter(to_world))
    }
}

/// Reads and checks a sensor's `shutter_open` and `shutter_close` (0 each; open ≤ close). The
/// interval only matters for animated transforms, which neumann does not have.
pub(crate) fn check_shutter(o: &Obj) -> PropResult<()> {
    let (open, close) = (o.float("shutter_open", 0.0)?, o.float("shutter_close", 0.0)?);
    if !(open.is_finite() && close.is_finite() && close >= open) {
        return Err(o.error_at("shutter_close", format!("need shutter_open ≤ shutter_close, got {open} and {close}")));
    }
    Ok(())
}

/// A copy of `shape` ready to be sampled by area (a meter's or a distant sensor's target); an
/// error for a shape without area.
fn sampled_shape(shape: &Geometry) -> Result<Arc<Geometry>, CameraError> {
    let mut shape = shape.clone();
    if !shape.prepare_sampling() {
        return Err(CameraError::MeterShape);
    }
    Ok(Arc::new(shape))
}

/// The error unless a meter's film (`width × height`, sensor `o`) is 1 × 1, as Mitsuba's
/// radiance, irradiance and distant meters require.
pub(crate) fn require_one_pixel(o: &Obj, width: u32, height: u32) -> PropResult<()> {
    if (width, height) != (1, 1) {
        return Err(o.error(CameraError::MeterFilm(width, height).to_string()));
    }
    Ok(())
}

/// A sensor's `to_world` from its `direction` parameter `d` (and a position `p`): looking along
/// `d` from `p`, with any up vector not parallel to it; an error at `direction` for a zero or
/// non-finite one.
pub(crate) fn look_along(o: &Obj, p: Vec3, d: Vec3) -> PropResult<Transform> {
    let up = if d.normalize_or_zero().y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    Transform::look_at(p, p + d, up)
        .ok_or_else(|| o.error_at("direction", format!("the direction must be a non-zero finite vector, got {d}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(axis: FovAxis, w: u32, h: u32) -> Camera {
        let t = Transform::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y).unwrap();
        Camera::perspective(t, 90.0, axis, w, h).unwrap()
    }

    /// The spherical camera's layouts: the equirectangular one at known points, the equal-area
    /// one covering the sphere evenly (pixel centres uniform in cos θ about every axis).
    #[test]
    fn spherical_camera_directions() {
        let t = Transform::translate(Vec3::new(1.0, 2.0, 3.0));
        let base = Camera::perspective(t, 90.0, FovAxis::X, 64, 32).unwrap();
        let eq = Camera { projection: Projection::Spherical(SphericalMapping::Equirectangular), ..base.clone() };
        let dir = |c: &Camera, x: f32, y: f32| c.generate_ray(Vec2::new(x, y), Vec2::ZERO);
        let r = dir(&eq, 16.0, 16.0);
        assert!((r.d - Vec3::Z).length() < 1e-5, "u = ¼ looks ahead: {}", r.d);
        assert!((r.o - Vec3::new(1.0, 2.0, 3.0 + 0.01)).length() < 1e-5, "from the near clip: {}", r.o);
        assert!((dir(&eq, 32.0, 16.0).d - Vec3::X).length() < 1e-5, "u = ½: camera +x (left)");
        assert!((dir(&eq, 10.0, 0.0).d - Vec3::Y).length() < 1e-5, "top row: up");
        assert!((dir(&eq, 10.0, 32.0).d + Vec3::Y).length() < 1e-5, "bottom row: down");
        let ea = Camera { projection: Projection::Spherical(SphericalMapping::EqualArea), ..base.with_resolution(64, 64).unwrap() };
        let mut bins = [[0u32; 8]; 3];
        // Roberts' R2 points over the film (a grid would put whole rows on the octahedron's
        // edges, which map to the great circles between the bins).
        let n = 256;
        let (a1, a2) = (0.754_877_7f64, 0.569_840_3f64);
        for i in 0..n * n {
            let (u, v) = (((i as f64 + 0.5) * a1).fract(), ((i as f64 + 0.5) * a2).fract());
            let d = dir(&ea, u as f32 * 64.0, v as f32 * 64.0).d;
            assert!((d.length() - 1.0).abs() < 1e-5);
            for (axis, b) in bins.iter_mut().enumerate() {
                b[(((d[axis] + 1.0) * 4.0) as usize).min(7)] += 1;
            }
        }
        for b in bins {
            assert!(b.iter().all(|&c| (c as f32 / (n * n / 8) as f32 - 1.0).abs() < 0.02), "{b:?}");
        }
    }

    #[test]
    fn centre_ray_looks_at_target_and_image_is_not_mirrored() {
        let c = cam(FovAxis::X, 200, 100);
        let r = c.generate_ray(Vec2::new(100.0, 50.0), Vec2::ZERO);
        assert!((r.d - (-Vec3::Z)).length() < 1e-6);
        // Looking down -z from +z with y up: the right of the image is world +x, the top +y.
        let right = c.generate_ray(Vec2::new(200.0, 50.0), Vec2::ZERO);
        assert!(right.d.x > 0.0 && (right.d.x / -right.d.z - 1.0).abs() < 1e-5, "{}", right.d);
        let top = c.generate_ray(Vec2::new(100.0, 0.0), Vec2::ZERO);
        assert!(top.d.y > 0.0 && (top.d.y / -top.d.z - 0.5).abs() < 1e-5, "{}", top.d);
    }

    /// Mitsuba's orthographic sensor: parallel rays along the view axis, starting on the
    /// near plane; camera-space x ∈ [-1, 1] spans the width (scaled by `to_world`), y the height
    /// at the same scale, and the image is not mirrored.
    #[test]
    fn orthographic_rays_are_parallel_and_span_the_scaled_film() {
        let look = Transform::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y).unwrap();
        let t = look * Transform::scale(Vec3::new(2.0, 2.0, 1.0)).unwrap();
        let c = Camera::orthographic(t, 200, 100).unwrap().with_clip(0.5, 100.0).unwrap();
        assert_eq!(c.projection(), Projection::Orthographic);
        let centre = c.generate_ray(Vec2::new(100.0, 50.0), Vec2::ZERO);
        assert!((centre.o - Vec3::new(0.0, 0.0, 4.5)).length() < 1e-5, "{}", centre.o);
        assert!((centre.d + Vec3::Z).length() < 1e-6);
        assert!((centre.t_max - 99.5).abs() < 1e-3);
        let right = c.generate_ray(Vec2::new(200.0, 50.0), Vec2::ZERO);
        assert!((right.o.x - 2.0).abs() < 1e-5 && (right.d - centre.d).length() < 1e-6, "{}", right.o);
        let top = c.generate_ray(Vec2::new(100.0, 0.0), Vec2::ZERO);
        assert!((top.o.y - 1.0).abs() < 1e-5, "{}", top.o);
        assert!(c.sample_wi(Vec3::ZERO, Vec2::ZERO).is_none());
    }

    #[test]
    fn fov_axis_variants() {
        let edge = |c: &Camera, film: Vec2| {
            let d = c.generate_ray(film, Vec2::ZERO).d;
            (d.x / -d.z, d.y / -d.z)
        };
        // Wide image: `smaller` means vertical.
        let c = cam(FovAxis::Smaller, 200, 100);
        assert!((edge(&c, Vec2::new(100.0, 0.0)).1 - 1.0).abs() < 1e-5);
        let c = cam(FovAxis::Larger, 200, 100);
        assert!((edge(&c, Vec2::new(200.0, 50.0)).0 - 1.0).abs() < 1e-5);
        let c = cam(FovAxis::Diagonal, 200, 100);
        let (x, y) = edge(&c, Vec2::new(200.0, 0.0));
        assert!(((x * x + y * y).sqrt() - 1.0).abs() < 1e-5);
        assert!(Camera::perspective(Transform::IDENTITY, 180.0, FovAxis::X, 1, 1).is_err());
    }

    /// Mitsuba 3.9.1's `perspective` with `principal_point_offset_x/y` = (0.1, −0.2), a 64 × 48
    /// film cropped to 32 × 40 at (8, 4): `sensor.sample_ray` at crop positions (0, 0), (½, ½),
    /// (¼, 0.9), (1, 1), i.e. film positions below; the offset moves the film, not the crop.
    /// The light tracer's connection lands back on the same film position.
    #[test]
    fn principal_point_offset_matches_mitsuba() {
        let t = Transform::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y).unwrap();
        let c = Camera::perspective(t, 40.0, FovAxis::X, 64, 48).unwrap().with_principal_point(Vec2::new(0.1, -0.2));
        let rows = [
            ((8.0, 4.0), Vec3::new(-0.478671, -0.232764, -0.846579)),
            ((24.0, 24.0), Vec3::new(-0.301143, -0.439554, -0.84623)),
            ((16.0, 40.0), Vec3::new(-0.355496, -0.590978, -0.724132)),
            ((40.0, 44.0), Vec3::new(-0.090065, -0.62193, -0.777876)),
        ];
        for ((x, y), d) in rows {
            let film = Vec2::new(x, y);
            let r = c.generate_ray(film, Vec2::ZERO);
            assert!((r.d - d).length() < 2e-6, "{film}: {} vs Mitsuba {d}", r.d);
            let s = c.sample_wi(r.at(3.0), Vec2::ZERO);
            if x < 64.0 && y < 48.0 {
                let s = s.expect("on the film");
                assert!((s.film - film).length() < 1e-3, "{} vs {film}", s.film);
            }
        }
        // A new resolution keeps the offset as a fraction of the film.
        let half = c.with_resolution(32, 24).unwrap();
        assert!((half.generate_ray(Vec2::new(12.0, 12.0), Vec2::ZERO).d - rows[1].1).length() < 2e-6);
    }

    #[test]
    fn thin_lens_rays_converge_on_the_focal_plane() {
        let c = cam(FovAxis::X, 100, 100).with_thin_lens(0.5, 3.0).unwrap();
        let film = Vec2::new(30.0, 70.0);
        let pin = cam(FovAxis::X, 100, 100).generate_ray(film, Vec2::ZERO);
        let target = Vec3::new(0.0, 0.0, 5.0) + pin.d * (3.0 / -pin.d.z);
        for u in [Vec2::new(0.1, 0.9), Vec2::new(0.7, 0.2), Vec2::new(0.5, 0.5)] {
            let r = c.generate_ray(film, u);
            let t = (r.o.z - 2.0) / -r.d.z; // plane z = 5 - 3
            assert!((r.at(t) - target).length() < 1e-4, "{} vs {}", r.at(t), target);
        }
    }
}
