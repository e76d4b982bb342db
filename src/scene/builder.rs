//! Assembles a [`Scene`]: collects shapes, BSDFs and emitters, then builds the BVH and the
//! light distribution.

use super::BuildError;
use super::{LeafPrim, PrimRef, Primitive, Scene, Shape, TRIANGLE_BLOCKS};
use crate::bvh::{Bvh, HugeArray};
use crate::camera::Camera;
use crate::geometry::triangle8::{Triangle8, LANES};
use crate::geometry::Geometry;
use crate::light::{Light, LightSampler, LightSamplerKind, ShapeEmission};
use crate::material::Bsdf;
use crate::math::{Rgb, Vec3};
use crate::sampling::AliasTable;
use crate::texture::{Texture, TextureAttributes};

/// Extra BVH references for split triangles, relative to the primitive count
/// ([`crate::bvh::presplit`]): Karras and Aila's 30 %.
pub const PRESPLIT_BUDGET: f32 = 0.3;

/// Collects the parts of a scene.
#[derive(Debug, Default)]
pub struct SceneBuilder {
    shapes: Vec<Shape>,
    geometries: Vec<Geometry>,
    bsdfs: Vec<Bsdf>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    media: Vec<crate::medium::Medium>,
    camera_medium: Option<u32>,
    /// What messages call each shape (by index; missing ones are called `shape N`): a
    /// description and where the shape was written, formatted only when a message needs it
    /// (finding a line and column in a large file for every shape would cost more than loading).
    shape_labels: Vec<(String, Option<crate::props::Loc>)>,
    /// Each shape's texture attributes (by index; missing ones have none).
    texture_attributes: Vec<TextureAttributes>,
    /// Each shape's motion (by index; missing ones stay put).
    motions: Vec<Option<crate::math::AnimatedTransform>>,
    /// The camera's shutter interval (0, 0 unless set).
    shutter: (f32, f32),
}

impl SceneBuilder {
    /// Makes shape `index` move: its geometry (a triangle mesh, given in its own space) is
    /// placed by `motion` at each ray's time (motion blur). Building the scene fails where the
    /// shape is not a triangle mesh or emits light.
    pub fn set_shape_motion(&mut self, index: u32, motion: crate::math::AnimatedTransform) {
        let i = index as usize;
        if self.motions.len() <= i {
            self.motions.resize(i + 1, None);
        }
        self.motions[i] = Some(motion);
    }

    /// The camera's shutter interval, whose times camera rays sample where shapes move (the
    /// default, (0, 0), renders every moving shape where it is at time 0).
    pub fn set_shutter(&mut self, open: f32, close: f32) {
        self.shutter = (open, close);
    }

    /// Gives shape `index` its texture attributes (Mitsuba's textures nested in a `<shape>`),
    /// which the `mesh_attribute` textures of its BSDF read after its mesh's own attributes.
    pub fn set_shape_textures(&mut self, index: u32, textures: TextureAttributes) {
        let i = index as usize;
        if self.texture_attributes.len() <= i {
            self.texture_attributes.resize(i + 1, TextureAttributes::default());
        }
        self.texture_attributes[i] = textures;
    }

    /// Names shape `index` for messages, e.g. `the obj shape 'floor'` written at `loc`
    /// (messages say `the obj shape 'floor' at scene.xml:12:5`).
    pub fn set_shape_label(&mut self, index: u32, label: String, loc: Option<crate::props::Loc>) {
        let i = index as usize;
        if self.shape_labels.len() <= i {
            self.shape_labels.resize(i + 1, (String::new(), None));
        }
        self.shape_labels[i] = (label, loc);
    }

    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// The BSDF of index `i` (from [`SceneBuilder::add_bsdf`]).
    pub fn bsdf(&self, i: u32) -> &Bsdf {
        &self.bsdfs[i as usize]
    }

    /// Adds a BSDF and returns its index.
    pub fn add_bsdf(&mut self, bsdf: Bsdf) -> u32 {
        self.bsdfs.push(bsdf);
        self.bsdfs.len() as u32 - 1
    }

    /// Adds a shape with BSDF `bsdf`; with `Some(radiance)` it is also an area emitter (front
    /// side). Returns the shape index.
    pub fn add_shape(&mut self, geometry: Geometry, bsdf: u32, emission: Option<Rgb>) -> u32 {
        let emission = emission.map(|c| ShapeEmission::Area { radiance: Texture::Constant(c), two_sided: false });
        self.add_emitting_shape(geometry, bsdf, emission)
    }

    /// [`SceneBuilder::add_shape`] with any emission a shape can carry (a radiance texture over
    /// the shape's (u, v), two-sided, or along the normal only).
    pub fn add_emitting_shape(&mut self, geometry: Geometry, bsdf: u32, emission: Option<ShapeEmission>) -> u32 {
        let index = self.shapes.len() as u32;
        let light = emission.map(|e| {
            self.lights.push(e.light(index));
            self.lights.len() as u32 - 1
        });
        self.shapes.push(Shape { bsdf, light, interior: None, exterior: None });
        self.geometries.push(geometry);
        index
    }

    /// Adds a participating medium and returns its index.
    pub fn add_medium(&mut self, medium: crate::medium::Medium) -> u32 {
        self.media.push(medium);
        self.media.len() as u32 - 1
    }

    /// Sets the media inside and outside shape `shape` (indices from [`SceneBuilder::add_medium`]).
    pub fn set_shape_media(&mut self, shape: u32, interior: Option<u32>, exterior: Option<u32>) {
        let s = &mut self.shapes[shape as usize];
        s.interior = interior;
        s.exterior = exterior;
    }

    /// Sets the medium the camera sits in.
    pub fn set_camera_medium(&mut self, medium: Option<u32>) {
        self.camera_medium = medium;
    }

    /// Adds a constant environment (Mitsuba's `constant` emitter) of radiance `radiance`.
    pub fn add_constant_environment(&mut self, radiance: Rgb) {
        self.lights.push(Light::Constant { radiance, center: Vec3::ZERO, radius: 0.0 });
    }

    /// Adds any emitter that is not attached to a shape (point, spot, directional, environment).
    pub fn add_light(&mut self, light: Light) {
        self.lights.push(light);
    }

    /// Adds an isotropic point light of radiant intensity `intensity` (W/sr) at `position`.
    pub fn add_point_light(&mut self, position: Vec3, intensity: Rgb) {
        self.lights.push(Light::Point { position, intensity });
    }

    /// Sets the camera.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = Some(camera);
    }

    /// Builds the scene: BVH, primitive arrays in leaf order, the light sampler (the light BVH;
    /// see [`Scene::set_light_sampler`]) and the power-proportional distribution that light
    /// tracing starts paths from. Errors name what is missing or inconsistent.
    pub fn build(mut self) -> Result<Scene, BuildError> {
        let camera = self.camera.take().ok_or(BuildError::NoCamera)?;
        // The shutter where shapes move, else the moving camera's own.
        let motion_shutter = match self.motions.iter().any(Option::is_some) {
            true => Some(self.shutter),
            false => camera.motion_shutter(),
        };
        for (i, s) in self.shapes.iter().enumerate() {
            if s.bsdf as usize >= self.bsdfs.len() {
                return Err(BuildError::MissingBsdf { shape: i, bsdf: s.bsdf, count: self.bsdfs.len() });
            }
        }
        let n_media = self.media.len() as u32;
        for (i, s) in self.shapes.iter().enumerate() {
            if s.interior.iter().chain(&s.exterior).chain(&self.camera_medium).any(|&m| m >= n_media) {
                return Err(BuildError::MissingMedium(i));
            }
        }
        for l in &self.lights {
            if let Light::Area { shape, .. } | Light::DirectionalArea { shape, .. } = l {
                if !self.geometries[*shape as usize].prepare_sampling() {
                    return Err(BuildError::EmitterWithoutArea(*shape));
                }
            }
        }
        // Moving shapes: triangle meshes that do not emit, wound as a static mesh placed by the
        // start transform would be (`TriangleMesh::transform` swaps two vertices of each
        // triangle under a mirroring transform).
        self.motions.resize(if self.motions.iter().any(Option::is_some) { self.shapes.len() } else { 0 }, None);
        for (i, motion) in self.motions.iter().enumerate() {
            let Some(motion) = motion else { continue };
            if self.shapes[i].light.is_some() {
                return Err(BuildError::MovingEmitter(i as u32));
            }
            match &mut self.geometries[i] {
                Geometry::Mesh(m) => {
                    if motion.start().swaps_handedness() {
                        for tri in &mut m.indices {
                            tri.swap(1, 2);
                        }
                    }
                }
                // Every other shape is tested in its own space, the ray moved there at its time
                // (where a mirroring transform would turn its frames).
                _ if !motion.start().swaps_handedness() => {}
                _ => return Err(BuildError::MovingShape(i as u32)),
            }
        }
        // A moving shape of many primitives (a mesh's triangles, curve pieces, SDF voxels,
        // ellipsoids) is traced in its own space (pbrt-v4's animated primitives, Embree's
        // motion-blurred instances): the ray moved there at its time traverses a BVH of the
        // shape at rest, built here as a scene of its own; the scene's BVH holds the shape as
        // one primitive bounded over its whole motion.
        let mut objects: Vec<Option<Box<Scene>>> = Vec::new();
        for (i, motion) in self.motions.iter().enumerate() {
            let (Some(_), g) = (motion, &self.geometries[i]) else { continue };
            if !g.is_piecewise() {
                continue;
            }
            let mut b = SceneBuilder::new();
            let bsdf = b.add_bsdf(crate::material::Bsdf::Diffuse(crate::material::Diffuse::new(Rgb::ZERO)));
            b.add_shape(g.clone(), bsdf, None);
            b.set_camera(Camera::perspective(crate::math::Transform::IDENTITY, 90.0, crate::camera::FovAxis::X, 1, 1)?);
            objects.resize_with(self.shapes.len(), || None);
            objects[i] = Some(Box::new(b.build()?));
        }
        let motions = &self.motions;
        let moving = |shape: u32| motions.get(shape as usize).and_then(Option::as_ref);
        // Hits in a small scene read the triangles' normals from this cache (no cross product,
        // square root and division on the path's critical chain; see `Scene::interaction`).
        for g in &mut self.geometries {
            if let Geometry::Mesh(m) = g {
                m.prepare_normals();
            }
        }
        // Primitives and their bounds.
        // (The vectors below are sized exactly and dropped as soon as they are used: a scene of
        // millions of triangles peaks at what its BVH build holds.)
        // (A moving shape of many primitives is one.)
        let count = |s: usize, g: &Geometry| match moving(s as u32) {
            Some(_) if g.is_piecewise() => usize::from(g.primitive_count() > 0),
            _ => g.primitive_count(),
        };
        let total: usize = self.geometries.iter().enumerate().map(|(s, g)| count(s, g)).sum();
        let mut refs = Vec::with_capacity(total);
        let mut bounds = Vec::with_capacity(total);
        for (s, g) in self.geometries.iter().enumerate() {
            for i in 0..count(s, g) {
                refs.push(PrimRef { shape: s as u32, index: i as u32 });
                bounds.push(match (g, moving(s as u32)) {
                    (Geometry::Mesh(m), Some(motion)) => motion.motion_bounds(&m.positions),
                    // Any other shape (one primitive) within its own-space box: the box's
                    // corners wherever they move.
                    (_, Some(motion)) => {
                        let b = g.bounds();
                        motion.motion_bounds(&std::array::from_fn::<Vec3, 8, _>(|k| b.corner(k)))
                    }
                    _ => g.primitive_bounds(i),
                });
            }
        }
        let geometries = &self.geometries;
        let triangle = |k: usize| {
            let r = refs[k];
            match &geometries[r.shape as usize] {
                Geometry::Mesh(m) if moving(r.shape).is_none() => Some(m.triangle(r.index as usize)),
                _ => None,
            }
        };
        let pieces = crate::bvh::presplit::presplit(&bounds, triangle, PRESPLIT_BUDGET);
        drop(bounds);
        let (piece_bounds, piece_prims): (Vec<_>, Vec<_>) = pieces.iter().map(|p| (p.bounds, p.prim)).unzip();
        drop(pieces);
        let costs: Vec<f32> = self.geometries.iter().map(Geometry::test_cost).collect();
        // (None where every shape is a mesh: all triangles are tested in blocks.)
        let weights: Vec<f32> = if costs.iter().any(|&c| c > 0.0) {
            piece_prims.iter().map(|&p| costs[refs[p as usize].shape as usize]).collect()
        } else {
            Vec::new()
        };
        let mut bvh = Bvh::build_weighted(&piece_bounds, &weights, &super::bvh_options(total));
        drop((piece_bounds, weights));
        let refs: Vec<PrimRef> = bvh.order().iter().map(|&k| refs[piece_prims[k as usize] as usize]).collect();
        drop(piece_prims);
        // Leaves of triangles only become blocks of eight, written after the leaves are
        // numbered (their count known, straight into their array); the others keep a primitive
        // list.
        let (mut block_leaves, mut block_count, mut prims) = (Vec::new(), 0usize, Vec::new());
        let primitive = |k: u32| {
            let r = refs[k as usize];
            match &geometries[r.shape as usize] {
                g if moving(r.shape).is_some() && g.is_piecewise() => Primitive::MovingObject,
                _ if moving(r.shape).is_some() => Primitive::MovingQuadric,
                Geometry::Mesh(m) => Primitive::Triangle(m.triangle(r.index as usize)),
                Geometry::Sphere(s) => Primitive::Sphere(*s),
                Geometry::Disk(_) => Primitive::Disk,
                Geometry::Cylinder(_) => Primitive::Cylinder,
                Geometry::SdfGrid(_) => Primitive::SdfVoxel,
                Geometry::Curves(_) | Geometry::LinearCurves(_) | Geometry::BSplineCurves(_) => Primitive::Curve,
                Geometry::Ellipsoids(_) => Primitive::Ellipsoid,
            }
        };
        let is_triangle = |k: u32| {
            let shape = refs[k as usize].shape;
            matches!(geometries[shape as usize], Geometry::Mesh(_)) && moving(shape).is_none()
        };
        bvh.remap_leaves(|first, count| {
            if (first..first + count).all(is_triangle) {
                let (start, n) = (block_count as u32, count.div_ceil(LANES as u32));
                block_leaves.push((first, count));
                block_count += n as usize;
                return (start, n | TRIANGLE_BLOCKS);
            }
            let start = prims.len() as u32;
            prims.extend((first..first + count).map(|k| LeafPrim { prim: primitive(k), r: k }));
            (start, count)
        });
        let blocks = HugeArray::from_exact_iter(
            block_count,
            block_leaves.iter().flat_map(|&(first, count)| {
                let tris: Vec<([Vec3; 3], u32)> = (first..first + count)
                    .filter_map(|k| match primitive(k) {
                        Primitive::Triangle(p) => Some((p, k)),
                        _ => None,
                    })
                    .collect();
                tris.chunks(LANES).map(Triangle8::new).collect::<Vec<_>>()
            }),
        );
        drop(block_leaves);
        // Infinite lights need the scene's extent.
        let (center, radius) = bvh.bounds().bounding_sphere();
        for l in &mut self.lights {
            if let Light::Constant { center: c, radius: r, .. }
            | Light::Directional { center: c, radius: r, .. }
            | Light::EnvMap { center: c, radius: r, .. }
            | Light::SunSky { center: c, radius: r, .. } = l
            {
                *c = center;
                *r = radius.max(1e-3);
            }
        }
        let infinite_lights =
            (0..self.lights.len() as u32).filter(|&i| self.lights[i as usize].is_infinite()).collect();
        let light_sampler = LightSampler::new(LightSamplerKind::default(), &self.lights, &self.geometries)?;
        let powers = crate::light::selection_powers(&self.lights, &self.geometries).unwrap_or_default();
        let emission_distribution = if powers.is_empty() { None } else { AliasTable::new(&powers) };
        // ∂p/∂v is computed at hits only where a bump map reads it.
        let needs_dpdv = self.bsdfs.iter().any(Bsdf::perturbs_with_height);
        // Texture coordinates on spheres only where a BSDF or an emitter reads them.
        let needs_uv = self.bsdfs.iter().any(Bsdf::reads_uv) || self.lights.iter().any(Light::reads_uv);
        // A distant sensor aims at the scene's bounding sphere.
        let camera = camera.with_scene_bounds(bvh.bounds());
        Ok(Scene {
            needs_dpdv,
            needs_uv,
            cached_normals: total <= super::SMALL_SCENE_PRIMITIVES,
            shapes: self.shapes,
            geometries: self.geometries,
            bsdfs: self.bsdfs,
            regularized_bsdfs: std::sync::OnceLock::new(),
            lights: self.lights,
            light_sampler,
            light_sampler_kind: LightSamplerKind::default(),
            emission_distribution,
            infinite_lights,
            media: self.media,
            camera_medium: self.camera_medium,
            shape_labels: self.shape_labels,
            texture_attributes: self.texture_attributes,
            bvh,
            blocks,
            prims: prims.into(),
            refs: refs.into(),
            primitives: total,
            camera,
            motion_shutter,
            motions: self.motions,
            objects,
        })
    }
}
