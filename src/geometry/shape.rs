//! The closed set of shape geometries, with area and solid-angle sampling for emitters.

use super::{BSplineCurves, Curves, Cylinder, Disk, Ellipsoids, LinearCurves, SdfGrid, Sphere, TriangleMesh};
use crate::math::{Bounds3, DirectionCone, Vec2, Vec3};
use crate::sampling::area_to_solid_angle;

/// A shape's geometry (world space).
#[derive(Clone, Debug)]
pub enum Geometry {
    /// Triangle mesh (also rectangles and cubes).
    Mesh(TriangleMesh),
    /// Analytic sphere.
    Sphere(Sphere),
    /// Analytic disk.
    Disk(Disk),
    /// Analytic open cylinder.
    Cylinder(Cylinder),
    /// Signed distance field on a grid (no area: it cannot emit).
    SdfGrid(Box<SdfGrid>),
    /// pbrt-v4's curves (no area: they cannot emit).
    Curves(Box<Curves>),
    /// Mitsuba's round linear curves (no area: they cannot emit).
    LinearCurves(Box<LinearCurves>),
    /// Mitsuba's round B-spline curves (no area: they cannot emit).
    BSplineCurves(Box<BSplineCurves>),
    /// Mitsuba's analytic ellipsoids (no area: they cannot emit).
    Ellipsoids(Box<Ellipsoids>),
}

/// A point sampled on a shape as seen from a reference point.
#[derive(Clone, Copy, Debug)]
pub struct ShapeSample {
    /// Sampled point.
    pub p: Vec3,
    /// Geometric normal there (front side).
    pub ng: Vec3,
    /// Shading normal there (front side), which decides which side emits.
    pub ns: Vec3,
    /// Error bound of `p`.
    pub p_error: Vec3,
    /// Density of the direction `p - p_ref` per unit solid angle at the reference point.
    pub pdf: f32,
}

impl Geometry {
    /// Surface area.
    pub fn area(&self) -> f32 {
        match self {
            Geometry::Mesh(m) => m.area(),
            Geometry::Sphere(s) => s.area(),
            Geometry::Disk(d) => d.area(),
            Geometry::Cylinder(c) => c.area(),
            // As in Mitsuba: not sampled, so no area.
            Geometry::SdfGrid(_)
            | Geometry::Curves(_)
            | Geometry::LinearCurves(_)
            | Geometry::BSplineCurves(_)
            | Geometry::Ellipsoids(_) => 0.0,
        }
    }

    /// Whether the shape is made of many BVH primitives (a mesh's triangles, curve pieces,
    /// SDF voxels, ellipsoids), not one (a sphere, disk or cylinder).
    pub fn is_piecewise(&self) -> bool {
        !matches!(self, Geometry::Sphere(_) | Geometry::Disk(_) | Geometry::Cylinder(_))
    }

    /// Number of primitives the BVH holds for this shape.
    pub fn primitive_count(&self) -> usize {
        match self {
            Geometry::Mesh(m) => m.len(),
            Geometry::SdfGrid(g) => g.len(),
            Geometry::Curves(c) => c.len(),
            Geometry::LinearCurves(c) => c.len(),
            Geometry::BSplineCurves(c) => c.len(),
            Geometry::Ellipsoids(e) => e.len(),
            _ => 1,
        }
    }

    /// Bounds of primitive `i`.
    pub fn primitive_bounds(&self, i: usize) -> Bounds3 {
        match self {
            Geometry::Mesh(m) => {
                let p = m.triangle(i);
                Bounds3::from_point(p[0]).union_point(p[1]).union_point(p[2])
            }
            Geometry::Sphere(s) => Bounds3::new(s.center - Vec3::splat(s.radius), s.center + Vec3::splat(s.radius)),
            Geometry::Disk(d) => {
                let mut b = Bounds3::EMPTY;
                for k in 0..16 {
                    let a = k as f32 / 16.0 * std::f32::consts::TAU;
                    // The disk lies inside the polygon circumscribing it (radius 1/cos(π/16)).
                    let r = 1.0 / (std::f32::consts::PI / 16.0).cos();
                    b = b.union_point(d.surface(Vec2::new(r * a.cos(), r * a.sin())).0.p);
                }
                b
            }
            Geometry::Cylinder(c) => c.bounds(),
            Geometry::SdfGrid(g) => g.voxel_bounds(i),
            Geometry::Curves(c) => c.bounds(i),
            Geometry::LinearCurves(c) => c.bounds(i),
            Geometry::BSplineCurves(c) => c.bounds(i),
            Geometry::Ellipsoids(e) => e.bounds(i),
        }
    }

    /// What one primitive's ray test costs, in units of one eight-triangle block test
    /// ([`crate::geometry::triangle8::Triangle8`]), for the BVH's SAH (`Bvh::build_weighted`);
    /// 0 for triangles, which are tested in blocks. Measured by the render rate of scenes made
    /// of each (128², the validation scenes, a thin-LTO build): charging curve segments, SDF voxels and ellipsoids
    /// as triangles (eight to a block test) gave them leaves of up to eight primitives, each
    /// tested alone; charged 2 they get leaves of their own (`hair` +33 %, `curves` +25 %,
    /// `sdfgrid` +20 %, `ellipsoids` +15 % samples/s; any weight from 0.5 to 8 within 3 % of
    /// that). Spheres, disks and cylinders are cheap analytic tests (a half, by their
    /// arithmetic; the scenes that have them render alike from 0 to 1).
    pub fn test_cost(&self) -> f32 {
        match self {
            Geometry::Mesh(_) => 0.0,
            Geometry::Sphere(_) | Geometry::Disk(_) | Geometry::Cylinder(_) => 0.5,
            Geometry::Curves(_)
            | Geometry::LinearCurves(_)
            | Geometry::BSplineCurves(_)
            | Geometry::SdfGrid(_)
            | Geometry::Ellipsoids(_) => 2.0,
        }
    }

    /// Bounds of the whole shape (world).
    pub fn bounds(&self) -> Bounds3 {
        (0..self.primitive_count()).fold(Bounds3::EMPTY, |b, i| b.union(&self.primitive_bounds(i)))
    }

    /// A cone holding every front-side normal of the shape (geometric and, for meshes with
    /// vertex normals, shading normals, which decide the side that emits): the light BVH's
    /// orientation bound. Flat meshes and disks give a single direction; spheres and cylinders
    /// the whole sphere.
    pub fn normal_cone(&self) -> DirectionCone {
        match self {
            Geometry::Mesh(m) => m.normal_cone(),
            Geometry::Disk(d) => DirectionCone::from_direction(d.normal()),
            Geometry::Sphere(_)
            | Geometry::Cylinder(_)
            | Geometry::SdfGrid(_)
            | Geometry::Curves(_)
            | Geometry::LinearCurves(_)
            | Geometry::BSplineCurves(_)
            | Geometry::Ellipsoids(_) => DirectionCone::ENTIRE_SPHERE,
        }
    }

    /// Prepares area sampling (a triangle distribution for meshes). `false` if the shape has no
    /// area to sample.
    pub fn prepare_sampling(&mut self) -> bool {
        match self {
            Geometry::Mesh(m) => m.prepare_sampling(),
            _ => self.area() > 0.0,
        }
    }

    /// A uniformly distributed point on the surface; `pdf` is per unit **area** (`1 / area`).
    /// `None` for a mesh whose sampling was not prepared.
    #[inline]
    pub fn sample_area(&self, u: Vec2) -> Option<ShapeSample> {
        let (sp, ns, pdf) = match self {
            Geometry::Mesh(m) => m.sample_area(u)?,
            Geometry::Sphere(s) => {
                let (sp, pdf) = s.sample_area(u);
                (sp, sp.n, pdf)
            }
            Geometry::Disk(d) => {
                let (sp, pdf) = d.sample_area(u);
                (sp, sp.n, pdf)
            }
            Geometry::Cylinder(c) => {
                let (sp, pdf) = c.sample_area(u);
                (sp, sp.n, pdf)
            }
            Geometry::SdfGrid(_)
            | Geometry::Curves(_)
            | Geometry::LinearCurves(_)
            | Geometry::BSplineCurves(_)
            | Geometry::Ellipsoids(_) => {
                return None
            }
        };
        Some(ShapeSample { p: sp.p, ng: sp.n, ns, p_error: sp.p_error, pdf })
    }

    /// [`Geometry::sample_area`] that also gives the point's texture coordinates (for emitters
    /// whose radiance is a texture); the same density.
    pub fn sample_area_uv(&self, u: Vec2) -> Option<(ShapeSample, Vec2)> {
        let (sp, ns, pdf, uv) = match self {
            Geometry::Mesh(m) => m.sample_area_uv(u)?,
            Geometry::Sphere(s) => {
                let (sp, pdf) = s.sample_area(u);
                (sp, sp.n, pdf, s.uv_of_direction((sp.p - s.center) / s.radius))
            }
            Geometry::Disk(d) => {
                let (sp, uv) = d.surface(d.sample_local(u));
                (sp, sp.n, 1.0 / d.area(), uv)
            }
            Geometry::Cylinder(c) => {
                let (sp, uv) = c.surface(c.sample_local(u));
                (sp, sp.n, 1.0 / c.area(), uv)
            }
            Geometry::SdfGrid(_)
            | Geometry::Curves(_)
            | Geometry::LinearCurves(_)
            | Geometry::BSplineCurves(_)
            | Geometry::Ellipsoids(_) => {
                return None
            }
        };
        Some((ShapeSample { p: sp.p, ng: sp.n, ns, p_error: sp.p_error, pdf }, uv))
    }

    /// [`Geometry::sample_solid_angle`] that also gives the point's texture coordinates.
    pub fn sample_solid_angle_uv(&self, p_ref: Vec3, u: Vec2) -> Option<(ShapeSample, Vec3, Vec2)> {
        if let Geometry::Sphere(s) = self {
            let (ss, wi) = self.sample_solid_angle(p_ref, u)?;
            return Some((ss, wi, s.uv_of_direction((ss.p - s.center) / s.radius)));
        }
        let (area_sample, uv) = self.sample_area_uv(u)?;
        let (ss, wi) = area_to_solid_angle_sample(area_sample, p_ref)?;
        Some((ss, wi, uv))
    }

    /// A point on the shape for direct lighting at `p_ref`, with its solid-angle pdf, and the
    /// unit direction from `p_ref` to it. Spheres sample the cone they subtend; meshes and
    /// disks sample area uniformly and convert (`p_ω = p_A r² / |cos θ|`). `None` if nothing
    /// can be sampled (grazing or degenerate).
    #[inline]
    pub fn sample_solid_angle(&self, p_ref: Vec3, u: Vec2) -> Option<(ShapeSample, Vec3)> {
        if let Geometry::Sphere(s) = self {
            // Read in place: moved out of the `Option`, the sample would be copied by wide loads
            // right after the call wrote it field by field (a store-forwarding stall).
            let sampled = s.sample_solid_angle(p_ref, u);
            let (sp, pdf) = sampled.as_ref()?;
            let wi = (sp.p - p_ref).normalize_or_zero();
            // Built in the return value (`then_some` built it on the stack field by field and
            // copied it with wide loads: another stall).
            return if wi == Vec3::ZERO {
                None
            } else {
                Some((ShapeSample { p: sp.p, ng: sp.n, ns: sp.n, p_error: sp.p_error, pdf: *pdf }, wi))
            };
        }
        if let Geometry::Mesh(m) = self {
            // The mesh's own sample inlined here (a quad light's is a few multiplications): its
            // result then stays in registers, where through `Geometry::sample_area`'s return
            // it went through memory.
            let (sp, ns, pdf) = m.sample_area(u)?;
            return area_to_solid_angle_sample(ShapeSample { p: sp.p, ng: sp.n, ns, p_error: sp.p_error, pdf }, p_ref);
        }
        area_to_solid_angle_sample(self.sample_area(u)?, p_ref)
    }

    /// Solid-angle density of [`Geometry::sample_solid_angle`] from `p_ref` for the point `p` with
    /// geometric normal `ng`.
    pub fn pdf_solid_angle(&self, p_ref: Vec3, p: Vec3, ng: Vec3) -> f32 {
        if let Geometry::Sphere(s) = self {
            return s.pdf_solid_angle(p_ref, p, ng);
        }
        let d = p - p_ref;
        let dist2 = d.length_squared();
        if dist2 == 0.0 {
            return 0.0;
        }
        area_to_solid_angle(1.0 / self.area(), dist2, ng.dot(d).abs() / dist2.sqrt())
    }
}

/// An area sample (pdf per unit area) seen from `p_ref`: the same point with its density per
/// unit solid angle there, and the unit direction to it.
#[inline]
fn area_to_solid_angle_sample(s: ShapeSample, p_ref: Vec3) -> Option<(ShapeSample, Vec3)> {
    let ShapeSample { p, ng, ns, p_error, pdf: pdf_area } = s;
    let d = p - p_ref;
    let dist2 = d.length_squared();
    // p_ω = p_A r² / |cos θ| = p_A r³ / |n·d|; ω = d / r. The two divisions only wait for
    // the square root, not for each other (a shorter dependency chain than normalizing first).
    let dist = dist2.sqrt();
    let wi = d / dist;
    let pdf = pdf_area * dist2 * dist / ng.dot(d).abs();
    if pdf > 0.0 && pdf.is_finite() {
        Some((ShapeSample { p, ng, ns, p_error, pdf }, wi))
    } else {
        None
    }
}
