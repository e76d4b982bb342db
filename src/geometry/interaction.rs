//! Surface interactions: what the renderer knows about a ray–surface hit.

use crate::math::float::offset_ray_origin;
use crate::math::{Frame, Ray, Vec2, Vec3};

/// A point on a surface where a ray hit (world space).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    /// Hit point.
    pub p: Vec3,
    /// Conservative absolute error bound of each coordinate of `p`.
    pub p_error: Vec3,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Unit geometric normal, on the shape's front side (triangle winding, or outward for
    /// spheres; flipped by `flip_normals`).
    pub ng: Vec3,
    /// Unit shading normal (interpolated vertex normal, else `ng`). The shading frame is built
    /// around it; BSDFs and one-sided emitters use it to tell front from back (as Mitsuba 3).
    pub ns: Vec3,
    /// Surface parameterization (texture coordinates).
    pub uv: Vec2,
    /// `∂p/∂u` (world space, not normalized; zero where the parameterization is degenerate):
    /// the shading frame's first tangent is this made perpendicular to `ns`, as in Mitsuba, which
    /// orients anisotropic BSDFs.
    pub dpdu: Vec3,
    /// `∂p/∂v` (world space, not normalized): with `dpdu`, what bump maps perturb. Computed only
    /// in scenes that have a bump map (zero elsewhere, and where the parameterization is
    /// degenerate), as no other part of the renderer reads it.
    pub dpdv: Vec3,
    /// Index of the shape in the scene.
    pub shape: u32,
    /// Index of the primitive (triangle) within the shape.
    pub prim: u32,
    /// Barycentric coordinates (b1, b2) of the hit in its triangle (zero on analytic shapes).
    pub bary: Vec2,
    /// The time of the ray that found it ([`Ray::time`]), which the rays spawned here keep.
    pub time: f32,
}

impl SurfaceInteraction {
    /// The shading frame: z = `ns`, x along `dpdu` made perpendicular to it (Gram–Schmidt, as
    /// Mitsuba builds `sh_frame`); where `dpdu` is zero or along `ns`, Duff et al.'s basis.
    #[inline]
    pub fn frame(&self) -> Frame {
        Frame::from_zx(self.ns, self.dpdu)
    }

    /// Origin for a ray leaving this point toward `w`, offset past the error bounds.
    #[inline]
    pub fn offset_origin(&self, w: Vec3) -> Vec3 {
        offset_ray_origin(self.p, self.p_error, self.ng, w)
    }

    /// Unbounded ray leaving the surface in direction `d`.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3) -> Ray {
        Ray::new(self.offset_origin(d), d).at_time(self.time)
    }

    /// Shadow ray from this point to the point `p_to` (with error bound `err_to` and normal
    /// `n_to`, zero for points not on a surface), covering `t ∈ (0, 1 - ε)` so that neither
    /// endpoint's own surface is hit.
    #[inline]
    pub fn spawn_ray_to(&self, p_to: Vec3, n_to: Vec3, err_to: Vec3) -> Ray {
        let o = self.offset_origin(p_to - self.p);
        let target = if n_to == Vec3::ZERO { p_to } else { offset_ray_origin(p_to, err_to, n_to, o - p_to) };
        Ray::bounded(o, target - o, 1.0 - SHADOW_EPSILON).at_time(self.time)
    }
}

/// Relative shortening of shadow rays (pbrt's ShadowEpsilon).
pub const SHADOW_EPSILON: f32 = 1e-4;
