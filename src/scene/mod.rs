//! The runtime scene: shapes with their BSDFs and emitters, the BVH over their primitives,
//! the lights with a power-proportional selection distribution, and the camera. Built with
//! [`SceneBuilder`]; immutable (and `Sync`) while rendering.

mod builder;
pub mod cornell;
pub mod xml;

pub use builder::SceneBuilder;

use crate::bvh::Bvh;
use crate::camera::Camera;
use crate::geometry::triangle::{intersect_triangle, triangle_point_error, RayPrecomp, TriangleHit};
use crate::geometry::{Geometry, Sphere, SurfaceInteraction};
use crate::light::Light;
use crate::material::Bsdf;
use crate::math::{Ray, Vec2, Vec3};
use crate::sampling::AliasTable;

/// What a shape is made of: its BSDF and optional emitter (its geometry is
/// [`Scene::geometries`] at the same index).
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    /// Index into [`Scene::bsdfs`].
    pub bsdf: u32,
    /// Index into [`Scene::lights`] if the shape emits.
    pub light: Option<u32>,
    /// Medium inside the shape (behind its front face), index into [`Scene::media`].
    pub interior: Option<u32>,
    /// Medium outside the shape (in front of its front face).
    pub exterior: Option<u32>,
}

/// Primitive data in BVH leaf order, compact for the traversal loop.
#[derive(Clone, Copy, Debug)]
enum Primitive {
    Triangle([Vec3; 3]),
    Sphere(Sphere),
    Disk,
    Cylinder,
}

/// Identifies a primitive: shape index and primitive index within the shape.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    shape: u32,
    index: u32,
}

#[derive(Clone, Copy, Debug)]
enum HitKind {
    Triangle(TriangleHit),
    Sphere,
    Disk(Vec2),
    Cylinder(Vec3),
}

/// A scene ready to render.
#[derive(Debug)]
pub struct Scene {
    shapes: Vec<Shape>,
    geometries: Vec<Geometry>,
    bsdfs: Vec<Bsdf>,
    lights: Vec<Light>,
    light_distribution: Option<AliasTable>,
    infinite_lights: Vec<u32>,
    media: Vec<crate::medium::Medium>,
    camera_medium: Option<u32>,
    bvh: Bvh,
    prims: Vec<Primitive>,
    refs: Vec<PrimRef>,
    camera: Camera,
}

impl Scene {
    /// The participating media.
    pub fn media(&self) -> &[crate::medium::Medium] {
        &self.media
    }

    /// The medium the camera sits in (Mitsuba's sensor medium), if any.
    pub fn camera_medium(&self) -> Option<u32> {
        self.camera_medium
    }

    /// Whether any participating medium is present.
    pub fn has_media(&self) -> bool {
        !self.media.is_empty()
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Replaces the camera (e.g. to change the resolution).
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
    }

    /// The shapes.
    pub fn shapes(&self) -> &[Shape] {
        &self.shapes
    }

    /// The geometry of every shape (indexed like [`Scene::shapes`]).
    pub fn geometries(&self) -> &[Geometry] {
        &self.geometries
    }

    /// The BSDFs.
    pub fn bsdfs(&self) -> &[Bsdf] {
        &self.bsdfs
    }

    /// The lights.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Indices of the lights at infinity (environments), seen by rays that escape.
    pub fn infinite_lights(&self) -> &[u32] {
        &self.infinite_lights
    }

    /// The BVH over all primitives.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Number of primitives (triangles, spheres, disks).
    pub fn primitive_count(&self) -> usize {
        self.prims.len()
    }

    /// Chooses a light with probability proportional to its power: the light index and its
    /// probability. `None` without lights.
    #[inline]
    pub fn sample_light(&self, u: f32) -> Option<(u32, f32)> {
        let (s, _) = self.light_distribution.as_ref()?.sample(u);
        Some((s.value as u32, s.pdf))
    }

    /// Probability that [`Scene::sample_light`] picks light `i`.
    #[inline]
    pub fn light_pmf(&self, i: u32) -> f32 {
        self.light_distribution.as_ref().map_or(0.0, |d| d.pmf(i as usize))
    }

    /// The closest surface hit along `ray` within `(0, ray.t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let pre = RayPrecomp::new(ray);
        let mut best: Option<(u32, f32, HitKind)> = None;
        self.bvh.closest_hit(ray, ray.t_max, |first, count, t_max| {
            for k in first..first + count {
                match unsafe { self.prims.get_unchecked(k as usize) } {
                    Primitive::Triangle(p) => {
                        if let Some(h) = intersect_triangle(&pre, p, *t_max) {
                            *t_max = h.t;
                            best = Some((k, h.t, HitKind::Triangle(h)));
                        }
                    }
                    Primitive::Sphere(s) => {
                        if let Some(h) = s.intersect(ray, *t_max) {
                            *t_max = h.t;
                            best = Some((k, h.t, HitKind::Sphere));
                        }
                    }
                    Primitive::Disk => {
                        let r = self.refs[k as usize];
                        if let Geometry::Disk(d) = &self.geometries[r.shape as usize] {
                            if let Some((t, q)) = d.intersect(ray, *t_max) {
                                *t_max = t;
                                best = Some((k, t, HitKind::Disk(q)));
                            }
                        }
                    }
                    Primitive::Cylinder => {
                        let r = self.refs[k as usize];
                        if let Geometry::Cylinder(c) = &self.geometries[r.shape as usize] {
                            if let Some((t, q)) = c.intersect(ray, *t_max) {
                                *t_max = t;
                                best = Some((k, t, HitKind::Cylinder(q)));
                            }
                        }
                    }
                }
            }
        });
        let (k, t, kind) = best?;
        Some(self.interaction(ray, k, t, kind))
    }

    fn interaction(&self, ray: &Ray, k: u32, t: f32, kind: HitKind) -> SurfaceInteraction {
        let r = self.refs[k as usize];
        let geometry = &self.geometries[r.shape as usize];
        match (kind, geometry) {
            (HitKind::Triangle(h), Geometry::Mesh(m)) => {
                let i = r.index as usize;
                let p = m.triangle(i);
                let ng = m.normal_of(&p);
                let (ns, uv) = m.shading(i, [h.b0, h.b1, h.b2], ng);
                SurfaceInteraction {
                    p: p[0] * h.b0 + p[1] * h.b1 + p[2] * h.b2,
                    p_error: triangle_point_error(&p, &h),
                    t,
                    ng,
                    ns,
                    uv,
                    shape: r.shape,
                    prim: r.index,
                }
            }
            (HitKind::Sphere, Geometry::Sphere(s)) => {
                let (sp, uv) = s.surface(ray, t);
                SurfaceInteraction { p: sp.p, p_error: sp.p_error, t, ng: sp.n, ns: sp.n, uv, shape: r.shape, prim: 0 }
            }
            (HitKind::Disk(q), Geometry::Disk(d)) => {
                let (sp, uv) = d.surface(q);
                SurfaceInteraction { p: sp.p, p_error: sp.p_error, t, ng: sp.n, ns: sp.n, uv, shape: r.shape, prim: 0 }
            }
            (HitKind::Cylinder(q), Geometry::Cylinder(c)) => {
                let (sp, uv) = c.surface(q);
                SurfaceInteraction { p: sp.p, p_error: sp.p_error, t, ng: sp.n, ns: sp.n, uv, shape: r.shape, prim: 0 }
            }
            _ => unreachable!("primitive kind and shape geometry always agree"),
        }
    }

    /// Whether anything blocks `ray` within `(0, ray.t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let pre = RayPrecomp::new(ray);
        self.bvh.any_hit(ray, ray.t_max, |first, count, t_max| {
            (first..first + count).any(|k| match unsafe { self.prims.get_unchecked(k as usize) } {
                Primitive::Triangle(p) => intersect_triangle(&pre, p, t_max).is_some(),
                Primitive::Sphere(s) => s.intersect(ray, t_max).is_some(),
                Primitive::Disk => match &self.geometries[self.refs[k as usize].shape as usize] {
                    Geometry::Disk(d) => d.intersect(ray, t_max).is_some(),
                    _ => false,
                },
                Primitive::Cylinder => match &self.geometries[self.refs[k as usize].shape as usize] {
                    Geometry::Cylinder(c) => c.intersect(ray, t_max).is_some(),
                    _ => false,
                },
            })
        })
    }
}
