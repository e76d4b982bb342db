//! The runtime scene: shapes with their BSDFs and emitters, the BVH over their primitives,
//! the lights with their light sampler, and the camera. Built with
//! [`SceneBuilder`]; immutable (and `Sync`) while rendering.

mod builder;
pub mod cornell;
mod motion;
mod error;

pub use builder::SceneBuilder;
pub use error::BuildError;

use crate::bvh::{prefetch, BuildOptions, Bvh, HugeArray};
use crate::camera::Camera;
use crate::geometry::bspline_curve::BSplineRay;
use crate::geometry::triangle::{intersect_triangle, triangle_point_error, RayPrecomp, TriangleHit};
use crate::geometry::triangle8::Triangle8;
use crate::geometry::{Geometry, Sphere, SurfaceInteraction};
use crate::light::{Light, LightSampleContext, LightSampler, LightSamplerKind};
use crate::material::Bsdf;
use crate::math::simd::Avx;
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

/// How large scenes build their BVH: SAH with leaves charged per block of eight triangles (the
/// [`Triangle8`] test), at most eight primitives per leaf, and a traversal cost (per binary
/// node) of one block test. Small scenes charge differently, see [`bvh_options`].
pub const BVH_OPTIONS: BuildOptions =
    BuildOptions { max_leaf: 8, bins: 16, parallel_threshold: 4096, traversal_cost: 1.0, leaf_group: 8 };

/// Scenes with at most this many primitives count as cache-resident: their triangle blocks and
/// nodes take at most about 360 bytes per primitive (a block of one triangle is 320 bytes),
/// 740 KB, within a 1 MiB L2 cache.
pub const SMALL_SCENE_PRIMITIVES: usize = 2048;

/// BVH options for a scene of `primitives` primitives. A small scene stays in cache, so a node
/// visit costs only its arithmetic, about 0.3 block tests per binary level (one 8-wide node
/// replaces about three binary levels; its slab test is about a third of a block test), and the
/// SAH separates big triangles into tight leaves (Cornell box: 11 % fewer instructions per
/// sample than with 1.0), charged per four triangles: charged per eight, leaves of big triangles
/// grow (the `textures` scene 20 % slower, `veach_mis` 16 %). A large scene is bound by memory
/// latency: every node visited is a dependent cache miss, so fewer, fuller leaves win
/// (100k-triangle mesh: 10–15 % fewer rays/s with 0.3; charged per eight triangles instead of
/// four, shadow rays +3 % at 100k and +13 % at 1M triangles, and 67 bytes per triangle instead
/// of 85).
pub fn bvh_options(primitives: usize) -> BuildOptions {
    if primitives <= SMALL_SCENE_PRIMITIVES {
        BuildOptions { traversal_cost: 0.3, leaf_group: 4, ..BVH_OPTIONS }
    } else {
        BVH_OPTIONS
    }
}

/// A closest hit whose surface interaction is computed on demand ([`Scene::intersect_deferred`]).
#[derive(Clone, Copy, Debug)]
pub struct DeferredHit<'a> {
    scene: &'a Scene,
    /// The ray (borrowed: a copy right after its maker wrote it field by field would wait for
    /// those stores to reach the cache).
    ray: &'a Ray,
    t: f32,
    /// What was hit, read where the traversal wrote it (in the caller's [`HitSlot`]).
    kind: &'a HitKind,
}

impl DeferredHit<'_> {
    /// The hit's ray parameter (distance in units of the ray direction's length).
    #[inline]
    pub fn t(&self) -> f32 {
        self.t
    }

    /// Index of the shape hit (into [`Scene::shapes`]).
    #[inline]
    pub fn shape(&self) -> u32 {
        self.scene.shape_hit(self.kind)
    }

    /// The light the shape hit carries (index into [`Scene::lights`]), if it emits.
    #[inline]
    pub fn light(&self) -> Option<u32> {
        self.scene.light_hit(self.kind)
    }

    /// The surface interaction at the hit, as [`Scene::intersect`] returns it.
    #[inline]
    pub fn interaction(&self) -> SurfaceInteraction {
        self.scene.interaction(self.ray, self.t, self.kind)
    }

    /// [`DeferredHit::interaction`] written into `out`.
    #[inline]
    pub fn interaction_into(&self, out: &mut SurfaceInteraction) {
        self.scene.interaction_to(self.ray, self.t, self.kind, out)
    }
}

/// Where a closest-hit query ([`Scene::intersect_deferred`]) leaves its hit: owned by the
/// caller, so that the hit is read where the traversal wrote it. Moved out of the traversal as
/// a whole, the record would be read by wide loads spanning the narrower stores that had just
/// written its fields, and such a load waits until those stores reach the cache (a failed
/// store-to-load forward: about 2 % of the path tracer's time, measured).
#[derive(Debug, Default)]
pub struct HitSlot(Option<(f32, HitKind)>);

/// The scene's primitive tests as the BVH traversals' leaf work, always inlined into them
/// (closures would be compiled once for both traversals and called).
struct LeafTest<'a> {
    scene: &'a Scene,
    ray: &'a Ray,
    pre: &'a RayPrecomp,
    /// The ray's frames for B-spline curve segments, computed at the first one it meets.
    bspline: Option<BSplineRay>,
    /// The closest hit so far (closest-hit queries).
    best: &'a mut Option<(f32, HitKind)>,
}

impl crate::bvh::ClosestLeaf for &mut LeafTest<'_> {
    /// The closest hit within `(0, t_max)` among the primitives of a leaf (`first`, `count` as
    /// the BVH stores them): lowers `t_max` and records it in `best`.
    #[inline(always)]
    fn visit(&mut self, first: u32, count: u32, t_max: &mut f32, avx: Option<Avx>) {
        let (scene, pre) = (self.scene, self.pre);
        if count & TRIANGLE_BLOCKS != 0 {
            for b in first..first + (count & !TRIANGLE_BLOCKS) {
                // SAFETY: leaf payloads index `blocks` (built together).
                let block = unsafe { scene.blocks.get_unchecked(b as usize) };
                if let Some((lane, h)) = block.intersect_with(avx, pre, *t_max) {
                    *t_max = h.t();
                    *self.best = Some((h.t(), HitKind::Block(h, b, lane)));
                    // The surface interaction starts from the triangle's reference: its cache
                    // miss in a large mesh overlaps the rest of the traversal.
                    prefetch(scene.refs.as_ptr().wrapping_add(block.id[lane] as usize), size_of::<PrimRef>());
                }
            }
            return;
        }
        for k in first..first + count {
            if let Some((t, kind)) = scene.intersect_prim(k, self.ray, pre, &mut self.bspline, *t_max) {
                *t_max = t;
                *self.best = Some((t, kind));
            }
        }
    }
    #[inline(always)]
    fn prefetch(&self, first: u32, count: u32) {
        self.scene.prefetch_leaf(first, count)
    }
}

impl crate::bvh::AnyLeaf for &mut LeafTest<'_> {
    #[inline(always)]
    fn hit(&mut self, first: u32, count: u32, t_max: f32, avx: Option<Avx>) -> bool {
        self.scene.occluded_in_leaf(self.ray, self.pre, &mut self.bspline, first, count, t_max, avx)
    }
    #[inline(always)]
    fn prefetch(&self, first: u32, count: u32) {
        self.scene.prefetch_leaf(first, count)
    }
}

/// Leaf payload flag: the leaf holds `count & !TRIANGLE_BLOCKS` [`Triangle8`] blocks from
/// `Scene::blocks[first]`; without it, `count` primitives from `Scene::prims[first]`.
const TRIANGLE_BLOCKS: u32 = 1 << 31;

/// A primitive of a leaf that does not hold triangles only, with its index into `Scene::refs`.
#[derive(Clone, Copy, Debug)]
struct LeafPrim {
    prim: Primitive,
    r: u32,
}

/// Primitive data of mixed leaves, compact for the traversal loop.
#[derive(Clone, Copy, Debug)]
enum Primitive {
    Triangle([Vec3; 3]),
    Sphere(Sphere),
    Disk,
    Cylinder,
    /// A voxel of an SDF grid.
    SdfVoxel,
    /// A piece of a curve.
    Curve,
    /// One of Mitsuba's ellipsoids.
    Ellipsoid,
    /// A moving shape of many primitives (a mesh, curves, an SDF grid, ellipsoids), whole
    /// (traced in its own space: [`Scene::objects`]).
    MovingObject,
    /// A moving sphere, disk or cylinder (object space: the ray is moved there at its time).
    MovingQuadric,
}

/// Identifies a primitive: shape index and primitive index within the shape.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    shape: u32,
    index: u32,
}

#[derive(Clone, Copy, Debug)]
enum HitKind {
    /// Lane `.2` of block `.1`.
    Block(TriangleHit, u32, usize),
    /// A triangle of a mixed leaf, `Scene::prims[.1]`.
    Triangle(TriangleHit, u32),
    /// The analytic shapes carry their index into `Scene::refs`.
    Sphere(u32),
    Disk(Vec2, u32),
    Cylinder(Vec3, u32),
    SdfVoxel(u32),
    /// A curve piece's (u, v).
    Curve(Vec2, u32),
    Ellipsoid(u32),
    /// A triangle of a moving mesh: the hit in the mesh's own space, the mesh's index into
    /// `Scene::refs` and the triangle's index in the mesh.
    MovingTriangle(TriangleHit, u32, u32),
    /// A piece of a moving curve, SDF grid or ellipsoid cloud: its (u, v) on a curve (zero on
    /// the others), the shape's index into `Scene::refs` and the piece's index in the shape.
    MovingPiece(Vec2, u32, u32),
}

/// A closest hit before its surface interaction is computed: what a ray-tracing kernel returns
/// (Embree's `rtcIntersect1` gives the same, plus an unnormalized geometric normal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Ray parameter of the hit (distance in units of the ray direction's length).
    pub t: f32,
    /// The primitive hit: see [`Scene::primitive`].
    pub prim: u32,
    /// Barycentrics `(b1, b2)` of vertices 1 and 2 of a triangle (`b0 = 1 - b1 - b2`); zero on
    /// analytic shapes.
    pub barycentrics: Vec2,
}

/// A scene ready to render.
#[derive(Debug)]
pub struct Scene {
    shapes: Vec<Shape>,
    geometries: Vec<Geometry>,
    bsdfs: Vec<Bsdf>,
    /// The BSDFs under pbrt-v4's path regularization (indexed like `bsdfs`), made when an
    /// integrator first asks for them.
    regularized_bsdfs: std::sync::OnceLock<Vec<Bsdf>>,
    lights: Vec<Light>,
    light_sampler: LightSampler,
    light_sampler_kind: LightSamplerKind,
    /// Lights by power, for light tracing's choice of where paths start.
    emission_distribution: Option<AliasTable>,
    infinite_lights: Vec<u32>,
    media: Vec<crate::medium::Medium>,
    camera_medium: Option<u32>,
    shape_labels: Vec<(String, Option<crate::props::Loc>)>,
    /// Each shape's texture attributes (by index; shapes past the end have none).
    texture_attributes: Vec<crate::texture::TextureAttributes>,
    bvh: Bvh,
    /// Triangles of all-triangle leaves, eight per block. This and the next two arrays, like
    /// the BVH's nodes, are [`HugeArray`]s: where large, backed by 2 MiB pages.
    blocks: HugeArray<Triangle8>,
    /// Primitives of the other leaves.
    prims: HugeArray<LeafPrim>,
    /// The shape and index of the primitive at each leaf position, in BVH order (a split
    /// triangle, [`crate::bvh::presplit`], at several).
    refs: HugeArray<PrimRef>,
    /// Primitives (each counted once, however many references it has).
    primitives: usize,
    camera: Camera,
    /// Each shape's motion (empty where nothing moves; `None` for shapes that stay put).
    motions: Vec<Option<crate::math::AnimatedTransform>>,
    /// Each moving shape of many primitives (mesh, curves, SDF grid, ellipsoids) at rest in
    /// its own space, as a scene of its one shape (its BVH and triangle blocks), which rays
    /// moved there at their time traverse (empty where no such shape moves).
    objects: Vec<Option<Box<Scene>>>,
    /// The shutter interval whose times camera rays sample, where shapes move.
    motion_shutter: Option<(f32, f32)>,
    /// Whether hits compute `∂p/∂v` (some BSDF is a bump map; zero otherwise).
    needs_dpdv: bool,
    /// Whether hits on spheres compute texture coordinates (some BSDF or emitter reads them;
    /// zero otherwise, and [`Scene::uv_at`] gives them on demand).
    needs_uv: bool,
    /// Whether hits on triangles read the mesh's cached face normals: in a cache-resident
    /// scene (at most [`SMALL_SCENE_PRIMITIVES`]); a larger one computes them from the vertices
    /// at hand, the same bits without a likely cache miss.
    cached_normals: bool,
}

impl Scene {
    /// What messages call shape `index`: its label from the scene file (type, id and position),
    /// else `shape N`.
    pub fn shape_label(&self, index: usize) -> String {
        match self.shape_labels.get(index) {
            Some((l, Some(loc))) if !l.is_empty() => format!("{l} at {}", loc.position()),
            Some((l, None)) if !l.is_empty() => l.clone(),
            _ => format!("shape {index}"),
        }
    }

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
        self.camera = camera.with_scene_bounds(self.bvh.bounds());
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

    /// The BSDFs as pbrt-v4's path regularization sees them ([`Bsdf::regularized`]; indexed
    /// like [`Scene::bsdfs`]), made on the first call.
    pub fn regularized_bsdfs(&self) -> &[Bsdf] {
        self.regularized_bsdfs.get_or_init(|| self.bsdfs.iter().map(Bsdf::regularized).collect())
    }

    /// The lights.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Whether the scene has lights but every one's power is zero (all switched off): nothing
    /// is emitted, so only black can be rendered.
    pub fn lights_are_off(&self) -> bool {
        !self.lights.is_empty() && self.emission_distribution.is_none()
    }

    /// Indices of the lights at infinity (environments), seen by rays that escape.
    pub fn infinite_lights(&self) -> &[u32] {
        &self.infinite_lights
    }

    /// The BVH over all primitives.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Traces with the BVH's compiled traversal `kernel` from now on, if this CPU supports it
    /// (see [`Bvh::set_kernel`]); the answers are the same bits, only the speed differs.
    pub fn set_bvh_kernel(&mut self, kernel: crate::bvh::Kernel) -> bool {
        self.bvh.set_kernel(kernel)
    }

    /// Bytes the ray-tracing structure takes: the BVH's nodes and order, and the leaves'
    /// primitive data (triangle blocks, mixed primitives, primitive references).
    pub fn accel_memory_bytes(&self) -> usize {
        self.bvh.memory_bytes()
            + self.blocks.len() * size_of::<Triangle8>()
            + self.prims.len() * size_of::<LeafPrim>()
            + self.refs.len() * size_of::<PrimRef>()
    }

    /// Number of primitives (triangles, spheres, disks).
    pub fn primitive_count(&self) -> usize {
        self.primitives
    }

    /// Chooses a light for next-event estimation at `ctx` with the scene's light sampler: the
    /// light index and the probability of choosing it. `None` without lights (or, with the light
    /// BVH, when no light can reach the point).
    #[inline]
    pub fn sample_light(&self, ctx: &LightSampleContext, u: f32) -> Option<(u32, f32)> {
        self.light_sampler.sample(ctx, u)
    }

    /// Probability that [`Scene::sample_light`] at `ctx` picks light `i`.
    #[inline]
    pub fn light_pmf(&self, ctx: &LightSampleContext, i: u32) -> f32 {
        self.light_sampler.pmf(ctx, i)
    }

    /// Chooses the light a light-tracing path starts from, with probability proportional to
    /// its power: the light index and its probability. `None` without lights.
    #[inline]
    pub fn sample_emitting_light(&self, u: f32) -> Option<(u32, f32)> {
        let (s, _) = self.emission_distribution.as_ref()?.sample(u);
        Some((s.value as u32, s.pdf))
    }

    /// Replaces the light sampler (default: the light BVH).
    pub fn set_light_sampler(&mut self, kind: LightSamplerKind) -> Result<(), BuildError> {
        self.light_sampler = LightSampler::new(kind, &self.lights, &self.geometries)?;
        self.light_sampler_kind = kind;
        Ok(())
    }

    /// Which light sampler next-event estimation uses.
    pub fn light_sampler_kind(&self) -> LightSamplerKind {
        self.light_sampler_kind
    }

    /// What the BSDF at the hit `si` evaluates its textures with: the texture coordinates and,
    /// for `mesh_attribute` lookups, the point on meshes that carry attributes and the shape's
    /// texture attributes.
    #[inline]
    pub fn bsdf_context<'a>(&'a self, si: &'a SurfaceInteraction) -> crate::material::BsdfContext<'a> {
        let mesh = match &self.geometries[si.shape as usize] {
            Geometry::Mesh(m) if !m.attributes.is_empty() => {
                Some(crate::geometry::mesh::MeshPoint { mesh: m, tri: si.prim, bary: si.bary })
            }
            _ => None,
        };
        let textures = self.texture_attributes.get(si.shape as usize).filter(|t| !t.is_empty());
        crate::material::BsdfContext { uv: si.uv, mesh, textures, si: Some(si), memo: None }
    }

    /// Texture coordinates of `si`, the hit [`Scene::intersect`] gave for `ray`: `si.uv`, which
    /// on spheres is zero in a scene where no BSDF or emitter reads texture coordinates (their
    /// arctangent and arc cosine are skipped there), computed here then, the same bits.
    pub fn uv_at(&self, ray: &Ray, si: &SurfaceInteraction) -> Vec2 {
        match &self.geometries[si.shape as usize] {
            Geometry::Sphere(s) if !self.needs_uv => match self.shape_motion(si.shape).and_then(|m| m.at(ray.time)) {
                // A moving sphere's (u, v) in its own space, the ray moved there.
                Some(at) => s.surface_uv(&at.inverse().apply_ray(ray), si.t),
                None => s.surface_uv(ray, si.t),
            },
            _ => si.uv,
        }
    }

    /// The closest surface hit along `ray` within `(0, ray.t_max)` (texture coordinates on
    /// spheres only where the scene reads them: see [`Scene::uv_at`]).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let mut best = None;
        let (t, kind) = self.closest(ray, &mut best)?;
        Some(self.interaction(ray, t, kind))
    }

    /// The closest surface hit along `ray` within `(0, ray.t_max)`, its surface interaction
    /// not yet computed: for callers that may need only which shape was hit (the last vertex
    /// of a path, where only an emitter matters). [`DeferredHit::interaction`] gives what
    /// [`Scene::intersect`] would have. The hit is kept in `slot` (reused from query to query).
    #[inline(always)]
    pub fn intersect_deferred<'a>(&'a self, ray: &'a Ray, slot: &'a mut HitSlot) -> Option<DeferredHit<'a>> {
        let (t, kind) = self.closest(ray, &mut slot.0)?;
        Some(DeferredHit { scene: self, ray, t, kind })
    }

    /// [`Scene::intersect_deferred`] leaving its hit in `slot` only (read it with
    /// [`Scene::deferred`]).
    #[inline(always)]
    pub fn intersect_into(&self, ray: &Ray, slot: &mut HitSlot) {
        self.closest(ray, &mut slot.0);
    }

    /// The hit [`Scene::intersect_into`] left in `slot` for `ray`, as
    /// [`Scene::intersect_deferred`] gives it.
    #[inline(always)]
    pub fn deferred<'a>(&'a self, ray: &'a Ray, slot: &'a HitSlot) -> Option<DeferredHit<'a>> {
        let (t, kind) = slot.0.as_ref()?;
        Some(DeferredHit { scene: self, ray, t: *t, kind })
    }

    /// [`Scene::intersect_deferred`] past emitting shapes: the closest hit on a shape that does
    /// not emit, each emitter in the way crossed by a ray spawned past it in the same direction,
    /// at most `max_skips` of them (`None` where the ray escapes or meets more). `ray` becomes
    /// the ray that reached the hit.
    pub fn intersect_deferred_past_emitters<'a>(
        &'a self,
        ray: &'a mut Ray,
        max_skips: u32,
        slot: &'a mut HitSlot,
    ) -> Option<DeferredHit<'a>> {
        let mut skips = 0;
        loop {
            let (t, kind) = self.closest(ray, &mut slot.0)?;
            if self.light_hit(kind).is_none() {
                break;
            }
            if skips == max_skips {
                return None;
            }
            *ray = self.interaction(ray, t, kind).spawn_ray(ray.d);
            skips += 1;
        }
        let (t, kind) = slot.0.as_ref().map(|(t, kind)| (*t, kind))?;
        Some(DeferredHit { scene: self, ray, t, kind })
    }

    /// The closest hit along `ray` within `(0, ray.t_max)` without its surface interaction
    /// (no shading normal, uv or error bounds, and no access to the shape's data): the ray
    /// query alone, as benchmarks of ray-tracing kernels time it.
    #[inline]
    pub fn intersect_hit(&self, ray: &Ray) -> Option<RayHit> {
        let mut best = None;
        let (t, kind) = self.closest(ray, &mut best)?;
        let barycentrics = match *kind {
            HitKind::Block(h, ..) | HitKind::Triangle(h, _) | HitKind::MovingTriangle(h, ..) => {
                let [_, b1, b2] = h.barycentrics();
                Vec2::new(b1, b2)
            }
            _ => Vec2::ZERO,
        };
        Some(RayHit { t, prim: self.prim_ref(kind), barycentrics })
    }

    /// The shape a hit is on (index into `shapes`).
    #[inline]
    fn shape_hit(&self, kind: &HitKind) -> u32 {
        self.refs[self.prim_ref(kind) as usize].shape
    }

    /// The light the shape a hit is on carries, if it emits.
    #[inline]
    fn light_hit(&self, kind: &HitKind) -> Option<u32> {
        self.shapes[self.shape_hit(kind) as usize].light
    }

    /// The index into `refs` of the primitive a hit names.
    #[inline]
    fn prim_ref(&self, kind: &HitKind) -> u32 {
        match *kind {
            HitKind::Block(_, b, lane) => self.blocks[b as usize].id[lane],
            HitKind::Triangle(_, k) => self.prims[k as usize].r,
            HitKind::Sphere(r)
            | HitKind::Disk(_, r)
            | HitKind::Cylinder(_, r)
            | HitKind::SdfVoxel(r)
            | HitKind::Curve(_, r)
            | HitKind::Ellipsoid(r)
            | HitKind::MovingTriangle(_, r, _)
            | HitKind::MovingPiece(_, r, _) => r,
        }
    }

    /// Shape index and, for a triangle, its index in the mesh (0 for analytic shapes and for
    /// a moving mesh, which the scene's BVH holds whole) of primitive `prim` of a [`RayHit`].
    /// Panics if `prim` is not a primitive of this scene.
    pub fn primitive(&self, prim: u32) -> (u32, u32) {
        let r = self.refs[prim as usize];
        (r.shape, r.index)
    }

    /// The closest hit along `ray` within `(0, ray.t_max)`: distance and what was hit, kept
    /// in `best` (see [`HitSlot`]).
    #[inline(always)]
    fn closest<'b>(&self, ray: &Ray, best: &'b mut Option<(f32, HitKind)>) -> Option<(f32, &'b HitKind)> {
        *best = None;
        let pre = RayPrecomp::new(ray);
        let mut leaf = LeafTest { scene: self, ray, pre: &pre, bspline: None, best: &mut *best };
        self.bvh.closest_hit_visit(ray, ray.t_max, &mut leaf);
        best.as_ref().map(|(t, kind)| (*t, kind))
    }

    /// Intersects primitive `k` of a mixed leaf (`Scene::prims[k]`) within `(0, t_max)`.
    /// Triangles and spheres are tested inline in the traversal, the other shapes by a call.
    #[inline(always)]
    fn intersect_prim(
        &self,
        k: u32,
        ray: &Ray,
        pre: &RayPrecomp,
        bspline: &mut Option<BSplineRay>,
        t_max: f32,
    ) -> Option<(f32, HitKind)> {
        // SAFETY: leaf payloads index `prims` (built together).
        let lp = unsafe { self.prims.get_unchecked(k as usize) };
        match &lp.prim {
            Primitive::Triangle(p) => intersect_triangle(pre, p, t_max).map(|h| (h.t(), HitKind::Triangle(h, k))),
            Primitive::Sphere(s) => s.intersect(ray, t_max).map(|h| (h.t, HitKind::Sphere(lp.r))),
            _ => self.intersect_other(lp, ray, bspline, t_max),
        }
    }

    /// [`Scene::intersect_prim`] for the shapes whose test is too long to inline.
    #[inline(never)]
    fn intersect_other(
        &self,
        lp: &LeafPrim,
        ray: &Ray,
        bspline: &mut Option<BSplineRay>,
        t_max: f32,
    ) -> Option<(f32, HitKind)> {
        let geometry = || &self.geometries[self.refs[lp.r as usize].shape as usize];
        match &lp.prim {
            // Tested inline by `intersect_prim`, never sent here.
            Primitive::Triangle(_) | Primitive::Sphere(_) => None,
            Primitive::Disk => match geometry() {
                Geometry::Disk(d) => d.intersect(ray, t_max).map(|(t, q)| (t, HitKind::Disk(q, lp.r))),
                _ => None,
            },
            Primitive::Cylinder => match geometry() {
                Geometry::Cylinder(c) => c.intersect(ray, t_max).map(|(t, q)| (t, HitKind::Cylinder(q, lp.r))),
                _ => None,
            },
            Primitive::SdfVoxel => match geometry() {
                Geometry::SdfGrid(g) => {
                    let voxel = self.refs[lp.r as usize].index as usize;
                    g.intersect(voxel, ray, t_max).map(|t| (t, HitKind::SdfVoxel(lp.r)))
                }
                _ => None,
            },
            Primitive::Curve => {
                let piece = self.refs[lp.r as usize].index as usize;
                let hit = match geometry() {
                    Geometry::Curves(c) => c.intersect(piece, ray, t_max),
                    Geometry::LinearCurves(c) => c.intersect(piece, ray, t_max),
                    Geometry::BSplineCurves(c) => {
                        c.intersect_with(piece, ray, bspline.get_or_insert_with(|| BSplineRay::new(ray)), t_max)
                    }
                    _ => None,
                };
                hit.map(|h| (h.t, HitKind::Curve(h.uv, lp.r)))
            }
            Primitive::Ellipsoid => match geometry() {
                Geometry::Ellipsoids(e) => {
                    let k = self.refs[lp.r as usize].index as usize;
                    e.intersect(k, ray, t_max).map(|t| (t, HitKind::Ellipsoid(lp.r)))
                }
                _ => None,
            },
            Primitive::MovingObject => {
                // The shape at rest, traversed by the ray moved to its own space at its time
                // (its direction not renormalized: the same t).
                let (object, own) = self.moving_object(lp, ray, t_max)?;
                let mut best = None;
                let (t, kind) = object.closest(&own, &mut best)?;
                // The primitive's index in the shape (the object scene holds that shape alone).
                let piece = object.refs[object.prim_ref(kind) as usize].index;
                Some((
                    t,
                    match *kind {
                        HitKind::Block(h, ..) | HitKind::Triangle(h, _) => HitKind::MovingTriangle(h, lp.r, piece),
                        HitKind::Curve(uv, _) => HitKind::MovingPiece(uv, lp.r, piece),
                        _ => HitKind::MovingPiece(Vec2::ZERO, lp.r, piece),
                    },
                ))
            }
            Primitive::MovingQuadric => {
                // The ray in the shape's own space at its time (its direction not renormalized,
                // so that distances along it keep their parameter t).
                let shape = self.refs[lp.r as usize].shape;
                let ray = self.shape_motion(shape)?.at(ray.time)?.inverse().apply_ray(ray);
                match geometry() {
                    Geometry::Sphere(s) => s.intersect(&ray, t_max).map(|h| (h.t, HitKind::Sphere(lp.r))),
                    Geometry::Disk(d) => d.intersect(&ray, t_max).map(|(t, q)| (t, HitKind::Disk(q, lp.r))),
                    Geometry::Cylinder(c) => c.intersect(&ray, t_max).map(|(t, q)| (t, HitKind::Cylinder(q, lp.r))),
                    _ => None,
                }
            }
        }
    }

    /// The vertices of triangle `triangle` of the moving mesh `shape` at `time` (world space).
    #[inline]
    fn moving_triangle(&self, shape: u32, triangle: u32, time: f32) -> Option<[Vec3; 3]> {
        let (Geometry::Mesh(m), Some(Some(motion))) = (&self.geometries[shape as usize], self.motions.get(shape as usize))
        else {
            return None;
        };
        let at = motion.matrix_at(time);
        Some(m.triangle(triangle as usize).map(|v| at.transform_point3(v)))
    }

    /// Whether shapes or the camera move (camera rays then sample a time in the shutter
    /// interval), and the interval: `Some((open, close))`.
    pub fn motion_shutter(&self) -> Option<(f32, f32)> {
        self.motion_shutter
    }

    /// Shape `shape`'s motion, if it moves.
    pub fn shape_motion(&self, shape: u32) -> Option<&crate::math::AnimatedTransform> {
        self.motions.get(shape as usize).and_then(Option::as_ref)
    }

    fn interaction(&self, ray: &Ray, t: f32, kind: &HitKind) -> SurfaceInteraction {
        self.interaction_with(ray, t, kind, self.needs_uv, self.needs_dpdv)
    }

    /// [`Scene::interaction`] written into `out` (its fields stored there directly: a record
    /// returned and then moved is copied by wide loads right after its narrow stores).
    #[inline(never)]
    fn interaction_to(&self, ray: &Ray, t: f32, kind: &HitKind, out: &mut SurfaceInteraction) {
        self.interaction_then(ray, t, kind, self.needs_uv, self.needs_dpdv, |si| *out = si)
    }

    /// The closest surface hit along `ray` within `(0, ray.t_max)` with every part of its
    /// surface interaction computed, whatever the scene's BSDFs read: texture coordinates on
    /// spheres and `∂p/∂v` everywhere (the `aov` integrator's `uv`, `dp_dv`, `duv_dx`).
    pub fn intersect_complete(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let mut best = None;
        let (t, kind) = self.closest(ray, &mut best)?;
        Some(self.interaction_with(ray, t, kind, true, true))
    }

    /// [`Scene::interaction`], texture coordinates on spheres computed where `uv` says and
    /// `∂p/∂v` where `dpdv` says.
    #[inline(always)]
    fn interaction_with(&self, ray: &Ray, t: f32, kind: &HitKind, uv: bool, dpdv: bool) -> SurfaceInteraction {
        self.interaction_then(ray, t, kind, uv, dpdv, |si| si)
    }

    /// [`Scene::interaction_with`] handed to `finish` where each kind of hit makes it: each
    /// record goes straight where `finish` puts it (one record chosen between the kinds' and
    /// then stored is assembled on the stack by narrow stores and copied by wide loads, which
    /// wait for those stores: a failed store-to-load forward, which perf put at 29 % of
    /// `interaction_to`'s cycles in the path tracer's lanes on the Cornell box).
    #[inline(always)]
    fn interaction_then<R>(
        &self,
        ray: &Ray,
        t: f32,
        kind: &HitKind,
        uv: bool,
        dpdv: bool,
        finish: impl FnOnce(SurfaceInteraction) -> R,
    ) -> R {
        // The triangle's index in its mesh where the hit is on a moving one (whose vertices are
        // placed at the ray's time).
        let mut moving = None;
        let (h, p, r) = match *kind {
            HitKind::Block(h, b, lane) => {
                let block = &self.blocks[b as usize];
                (h, block.triangle(lane), block.id[lane])
            }
            HitKind::Triangle(h, k) => match self.prims[k as usize] {
                LeafPrim { prim: Primitive::Triangle(p), r } => (h, p, r),
                _ => unreachable!("HitKind::Triangle names a triangle"),
            },
            HitKind::MovingTriangle(h, r, triangle) => {
                let shape = self.refs[r as usize].shape;
                let p = self.moving_triangle(shape, triangle, ray.time).expect("HitKind::MovingTriangle names a moving triangle");
                moving = Some(triangle);
                (h, p, r)
            }
            HitKind::Sphere(r)
            | HitKind::Disk(_, r)
            | HitKind::Cylinder(_, r)
            | HitKind::SdfVoxel(r)
            | HitKind::Curve(_, r)
            | HitKind::Ellipsoid(r) => {
                return finish(self.analytic_interaction(ray, t, *kind, self.refs[r as usize], uv, dpdv));
            }
            HitKind::MovingPiece(piece_uv, r, piece) => {
                // The piece's interaction in the shape's own space, placed where the shape is at
                // the ray's time (`analytic_interaction` moves the ray there and back).
                let shape = self.refs[r as usize].shape;
                let at_rest = match self.geometries[shape as usize] {
                    Geometry::SdfGrid(_) => HitKind::SdfVoxel(r),
                    Geometry::Ellipsoids(_) => HitKind::Ellipsoid(r),
                    _ => HitKind::Curve(piece_uv, r),
                };
                return finish(self.analytic_interaction(ray, t, at_rest, PrimRef { shape, index: piece }, uv, dpdv));
            }
        };
        let r = self.refs[r as usize];
        let Geometry::Mesh(m) = &self.geometries[r.shape as usize] else { unreachable!("triangles belong to meshes") };
        let index = moving.unwrap_or(r.index);
        let i = index as usize;
        // A small scene's cached normal is a load from cache; in a large mesh it is likely a
        // miss, and the vertices at hand (the ones it was computed from: the same bits) give it
        // by a cross product and a normalization instead.
        let ng = if self.cached_normals && matches!(kind, HitKind::Block(..) | HitKind::Triangle(..)) {
            m.face_normal(i)
        } else {
            m.normal_of(&p)
        };
        let [b0, b1, b2] = h.barycentrics();
        let crate::geometry::mesh::MeshSurface { mut ns, uv, dpdu, dpdv } = m.surface_at(i, &p, [b0, b1, b2], ng, dpdv);
        if moving.is_some() && !m.normals.is_empty() {
            // Vertex normals are the mesh's own (object space): placed as the vertices are, by
            // the mesh's transform at the ray's time (its inverse made only here, where needed).
            if let Some(t) = self.shape_motion(r.shape).and_then(|a| a.at(ray.time)) {
                ns = t.apply_normal(ns).normalize_or(ng);
            }
        }
        finish(SurfaceInteraction {
            p: p[0] * b0 + p[1] * b1 + p[2] * b2,
            p_error: triangle_point_error(&p, &h),
            t,
            ng,
            ns,
            uv,
            dpdu,
            dpdv,
            bary: crate::math::Vec2::new(b1, b2),
            shape: r.shape,
            prim: index,
            time: ray.time,
        })
    }

    /// The surface interaction of an analytic shape's hit `kind` at `t` along `ray` (a moving
    /// one's computed in its own space and placed where it is at the ray's time).
    fn analytic_interaction(
        &self,
        ray: &Ray,
        t: f32,
        kind: HitKind,
        r: PrimRef,
        needs_uv: bool,
        needs_dpdv: bool,
    ) -> SurfaceInteraction {
        if let Some(at) = self.shape_motion(r.shape).and_then(|m| m.at(ray.time)) {
            // A moving quadric: its interaction in its own space, where the ray met it (the
            // same t), placed by its transform at the ray's time.
            let own = at.inverse().apply_ray(ray);
            let si = self.analytic_interaction_at_rest(&own, t, kind, r, needs_uv, needs_dpdv);
            return motion::placed_interaction(&at, si);
        }
        self.analytic_interaction_at_rest(ray, t, kind, r, needs_uv, needs_dpdv)
    }

    /// [`Scene::analytic_interaction`] of a shape that does not move (or in a moving one's own
    /// space).
    fn analytic_interaction_at_rest(
        &self,
        ray: &Ray,
        t: f32,
        kind: HitKind,
        r: PrimRef,
        needs_uv: bool,
        needs_dpdv: bool,
    ) -> SurfaceInteraction {
        if let (HitKind::SdfVoxel(_), Geometry::SdfGrid(g)) = (kind, &self.geometries[r.shape as usize]) {
            // No parameterization: uv = 0 and a shading frame around the normal alone.
            let (p, p_error, ng, ns) = g.surface(r.index as usize, ray, t);
            let (uv, dpdu, dpdv, bary) = (Vec2::ZERO, Vec3::ZERO, Vec3::ZERO, Vec2::ZERO);
            return SurfaceInteraction { p, p_error, t, ng, ns, uv, dpdu, dpdv, shape: r.shape, prim: r.index, bary, time: ray.time };
        }
        if let (HitKind::Ellipsoid(_), Geometry::Ellipsoids(e)) = (kind, &self.geometries[r.shape as usize]) {
            // No parameterization (as in Mitsuba): uv = 0 and a shading frame around the normal.
            let sp = e.surface(r.index as usize, ray, t);
            let (uv, dpdu, dpdv, bary) = (Vec2::ZERO, Vec3::ZERO, Vec3::ZERO, Vec2::ZERO);
            let (p, p_error, ng, ns) = (sp.p, sp.p_error, sp.n, sp.n);
            return SurfaceInteraction { p, p_error, t, ng, ns, uv, dpdu, dpdv, shape: r.shape, prim: r.index, bary, time: ray.time };
        }
        if let HitKind::Curve(uv, _) = kind {
            // Mitsuba's round curves (a linear one gives no ∂p/∂u: a frame around the normal).
            let (hit, k) = (crate::geometry::curve::CurveHit { t, uv }, r.index as usize);
            let round = match &self.geometries[r.shape as usize] {
                Geometry::LinearCurves(c) => Some(c.surface(k, ray, hit)),
                Geometry::BSplineCurves(c) => Some(c.surface(k, ray, hit)),
                _ => None,
            };
            if let Some(s) = round {
                let (p, p_error, n, uv, dpdu, dpdv) = (s.p, s.p_error, s.n, s.uv, s.dpdu, s.dpdv);
                let (shape, prim, bary) = (r.shape, r.index, Vec2::ZERO);
                return SurfaceInteraction { p, p_error, t, ng: n, ns: n, uv, dpdu, dpdv, shape, prim, bary, time: ray.time };
            }
        }
        if let (HitKind::Curve(uv, _), Geometry::Curves(c)) = (kind, &self.geometries[r.shape as usize]) {
            let s = c.surface(r.index as usize, ray, crate::geometry::curve::CurveHit { t, uv });
            let (p, p_error, n, dpdu, dpdv) = (s.p, s.p_error, s.n, s.dpdu, s.dpdv);
            let bary = Vec2::ZERO;
            return SurfaceInteraction { p, p_error, t, ng: n, ns: n, uv, dpdu, dpdv, shape: r.shape, prim: r.index, bary, time: ray.time };
        }
        let ((sp, uv), (dpdu, dpdv)) = match (kind, &self.geometries[r.shape as usize]) {
            (HitKind::Sphere(_), Geometry::Sphere(s)) => {
                let surface = if needs_uv { s.surface(ray, t) } else { (s.surface_point(ray, t), Vec2::ZERO) };
                (surface, s.dpduv(surface.0.p, needs_dpdv))
            }
            (HitKind::Disk(q, _), Geometry::Disk(d)) => (d.surface(q), d.dpduv(q)),
            (HitKind::Cylinder(q, _), Geometry::Cylinder(c)) => (c.surface(q), c.dpduv(q)),
            _ => unreachable!("primitive kind and shape geometry always agree"),
        };
        let bary = crate::math::Vec2::ZERO;
        SurfaceInteraction { p: sp.p, p_error: sp.p_error, t, ng: sp.n, ns: sp.n, uv, dpdu, dpdv, shape: r.shape, prim: 0, bary, time: ray.time }
    }

    /// Whether anything blocks `ray` within `(0, ray.t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let pre = RayPrecomp::new(ray);
        // By reference: moved into the traversal, the leaf test (with its room for a curve
        // frame) was copied by wide loads right after its fields were written one by one.
        let mut leaf = LeafTest { scene: self, ray, pre: &pre, bspline: None, best: &mut None };
        self.bvh.any_hit_visit(ray, ray.t_max, &mut leaf)
    }

    /// Whether a primitive of a leaf blocks the ray within `(0, t_max)`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn occluded_in_leaf(
        &self,
        ray: &Ray,
        pre: &RayPrecomp,
        bspline: &mut Option<BSplineRay>,
        first: u32,
        count: u32,
        t_max: f32,
        avx: Option<Avx>,
    ) -> bool {
        // Plain loops: an iterator's `any` would stay a call inside the traversal.
        if count & TRIANGLE_BLOCKS != 0 {
            for b in first..first + (count & !TRIANGLE_BLOCKS) {
                // SAFETY: leaf payloads index `blocks` (built together).
                if unsafe { self.blocks.get_unchecked(b as usize) }.occludes_with(avx, pre, t_max) {
                    return true;
                }
            }
            return false;
        }
        for k in first..first + count {
            // SAFETY: leaf payloads index `prims` (built together).
            let blocked = match unsafe { &self.prims.get_unchecked(k as usize).prim } {
                Primitive::MovingObject => self.moving_object_occludes(k, ray, t_max),
                _ => self.intersect_prim(k, ray, pre, bspline, t_max).is_some(),
            };
            if blocked {
                return true;
            }
        }
        false
    }

    /// Whether the moving shape of mixed-leaf primitive `k` (a [`Primitive::MovingObject`])
    /// blocks `ray` within `(0, t_max)`: the any-hit traversal of the shape at rest by the ray
    /// moved to its own space at its time (which stops at the first primitive found, where
    /// [`Scene::intersect_prim`] looks for the closest).
    #[inline(never)]
    fn moving_object_occludes(&self, k: u32, ray: &Ray, t_max: f32) -> bool {
        self.moving_object(&self.prims[k as usize], ray, t_max).is_some_and(|(object, own)| object.occluded(&own))
    }

    /// The object scene of the moving shape of leaf primitive `lp` (a
    /// [`Primitive::MovingObject`]) and `ray` moved to its own space at the ray's time, extent
    /// `t_max` (its direction not renormalized: the same t).
    #[inline]
    fn moving_object(&self, lp: &LeafPrim, ray: &Ray, t_max: f32) -> Option<(&Scene, Ray)> {
        let shape = self.refs[lp.r as usize].shape;
        let object = self.objects.get(shape as usize)?.as_deref()?;
        let mut own = self.shape_motion(shape)?.at(ray.time)?.inverse().apply_ray(ray);
        own.t_max = t_max;
        Some((object, own))
    }

    /// Prefetches a leaf's data (at most its first two triangle blocks or primitives).
    #[inline(always)]
    fn prefetch_leaf(&self, first: u32, count: u32) {
        // Constant sizes, so that each prefetch unrolls (a leaf holds at least one item).
        #[inline(always)]
        fn first_two<T>(p: *const T, count: u32) {
            prefetch(p, size_of::<T>());
            if count > 1 {
                prefetch(p.wrapping_add(1), size_of::<T>());
            }
        }
        if count & TRIANGLE_BLOCKS != 0 {
            first_two(self.blocks.as_ptr().wrapping_add(first as usize), count & !TRIANGLE_BLOCKS);
        } else {
            first_two(self.prims.as_ptr().wrapping_add(first as usize), count);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::FovAxis;
    use crate::geometry::TriangleMesh;
    use crate::material::Diffuse;
    use crate::math::{Rgb, Transform};
    use crate::sampling::{sample_uniform_sphere, Pcg32};

    /// Shading frames follow `∂p/∂u` as Mitsuba's do (what orients anisotropic BSDFs): along
    /// the texture's u axis on a turned rectangle, around the axis on a sphere, and along the
    /// first edge `p1 − p0` on a mesh without texture coordinates (whose uv are then the
    /// barycentrics `(b1, b2)`).
    /// `∂p/∂u` and `∂p/∂v` of every shape are Mitsuba's, magnitudes included (what bump maps
    /// scale their slopes by): values Mitsuba 3.9.1 gives for the same rays.
    #[test]
    fn parameterization_derivatives_match_mitsuba() {
        use crate::geometry::{Cylinder, Disk, Sphere};
        let cases: Vec<(Geometry, Vec3, Vec3, [f32; 6])> = vec![
            (
                Geometry::Sphere(Sphere::new(Vec3::ZERO, 2.0, false)),
                Vec3::new(0.3, -5.0, 0.7),
                Vec3::Y,
                [11.6196, 1.88496, 0.0, 0.35214, -2.17074, -5.88577],
            ),
            (
                Geometry::Sphere(Sphere::new(Vec3::ZERO, 2.0, false)),
                Vec3::new(0.5, 0.2, 5.0),
                -Vec3::Z,
                [-1.25664, std::f32::consts::PI, 0.0, 5.61834, 2.24733, -1.6918],
            ),
            (
                {
                    let mut m = TriangleMesh::rectangle();
                    m.transform(&Transform::scale(Vec3::new(3.0, 2.0, 1.0)).unwrap());
                    Geometry::Mesh(m)
                },
                Vec3::new(0.5, 0.2, 5.0),
                -Vec3::Z,
                [6.0, 0.0, 0.0, 0.0, 4.0, 0.0],
            ),
            (
                Geometry::Disk(Disk::new(Transform::scale(Vec3::splat(2.0)).unwrap(), false).unwrap()),
                Vec3::new(0.5, 0.2, 5.0),
                -Vec3::Z,
                [1.85695, 0.742781, 0.0, -1.25664, std::f32::consts::PI, 0.0],
            ),
            (
                Geometry::Cylinder(Cylinder::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 3.0), 0.5, Transform::IDENTITY, false).unwrap()),
                Vec3::new(0.3, -5.0, 0.7),
                Vec3::Y,
                [2.51327, 1.88496, 0.0, 0.0, 0.0, 3.0],
            ),
        ];
        for (k, (g, o, d, expected)) in cases.into_iter().enumerate() {
            let mut b = SceneBuilder::new();
            // A bump map, so that hits compute ∂p/∂v (scenes without one skip it).
            let height = crate::texture::Texture::Bitmap {
                bitmap: crate::texture::Bitmap {
                    image: std::sync::Arc::new(crate::image::Image { width: 1, height: 1, pixels: vec![Rgb::ONE] }),
                    filter: crate::texture::Filter::Bilinear,
                    wrap: [crate::texture::Wrap::Repeat; 2],
                },
                to_uv: crate::math::Mat3::IDENTITY,
            };
            let m = b.add_bsdf(Bsdf::Perturbed(crate::material::Perturbed {
                perturbation: crate::material::Perturbation::BumpMap { height, scale: 1.0 },
                bsdf: std::sync::Arc::new(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5)))),
                flip_invalid_normals: true,
                shadowing: true,
            }));
            b.add_shape(g, m, None);
            b.set_camera(crate::camera::Camera::perspective(Transform::IDENTITY, 40.0, FovAxis::X, 4, 4).unwrap());
            let scene = b.build().unwrap();
            let si = scene.intersect(&Ray::new(o, d)).unwrap_or_else(|| panic!("case {k} misses"));
            let got = [si.dpdu.x, si.dpdu.y, si.dpdu.z, si.dpdv.x, si.dpdv.y, si.dpdv.z];
            for (g, e) in got.iter().zip(expected) {
                assert!((g - e).abs() < 1e-3 * e.abs().max(1.0), "case {k}: {got:?} vs {expected:?}");
            }
        }
    }

    /// Hits on spheres skip texture coordinates only in scenes where nothing reads them (no
    /// BSDF texture, hair or textured emitter): there `si.uv` is zero and [`Scene::uv_at`]
    /// gives, bit for bit, what a scene that reads them has in `si.uv`; a textured BSDF, a
    /// textured area light or hair makes the scene compute them.
    #[test]
    fn sphere_uv_only_where_read() {
        use crate::geometry::Sphere;
        use crate::texture::Texture;
        let checker = Texture::Bitmap {
            bitmap: crate::texture::Bitmap {
                image: std::sync::Arc::new(crate::image::Image {
                    width: 2,
                    height: 1,
                    pixels: vec![Rgb::ONE, Rgb::splat(0.2)],
                }),
                filter: crate::texture::Filter::Nearest,
                wrap: [crate::texture::Wrap::Repeat; 2],
            },
            to_uv: crate::math::Mat3::IDENTITY,
        };
        // 0: plain; 1: a textured BSDF; 2: a textured emitter on the sphere; 3: hair.
        let scene = |variant: usize| {
            let mut b = SceneBuilder::new();
            let bsdf = match variant {
                1 => Bsdf::Diffuse(Diffuse { reflectance: checker.clone() }),
                3 => Bsdf::Hair(Box::new(crate::material::Hair {
                    convention: crate::material::hair::HairConvention::Pbrt,
                    colour: crate::material::hair::HairColour::Absorption(Texture::Constant(Rgb::splat(0.5))),
                    eta: 1.55,
                    beta_m: 0.3,
                    beta_n: 0.3,
                    alpha: 2.0,
                })),
                _ => Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))),
            };
            let m = b.add_bsdf(bsdf);
            let emission = (variant == 2)
                .then(|| crate::light::ShapeEmission::Area { radiance: checker.clone(), two_sided: false });
            let sphere = Geometry::Sphere(Sphere::new(Vec3::new(0.3, -0.2, 0.1), 1.5, false));
            b.add_emitting_shape(sphere, m, emission);
            b.set_camera(Camera::perspective(Transform::IDENTITY, 40.0, FovAxis::X, 4, 4).unwrap());
            b.build().unwrap()
        };
        let mut rng = Pcg32::new(3, 1);
        let (plain, scenes) = (scene(0), [scene(1), scene(2), scene(3)]);
        assert!(!plain.needs_uv && scenes.iter().all(|s| s.needs_uv));
        for _ in 0..1000 {
            let o = 5.0 * sample_uniform_sphere(glam::Vec2::new(rng.next_f32(), rng.next_f32())).value;
            let ray = Ray::new(o, (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5 - o).normalize());
            let si = plain.intersect(&ray).expect("every ray aims inside the sphere");
            assert_eq!(si.uv, Vec2::ZERO);
            let uv = plain.uv_at(&ray, &si);
            for s in &scenes {
                let with = s.intersect(&ray).unwrap();
                assert_eq!(with.uv.to_array().map(f32::to_bits), uv.to_array().map(f32::to_bits));
                assert_eq!(s.uv_at(&ray, &with), with.uv);
                assert_eq!((with.p, with.ns, with.dpdu), (si.p, si.ns, si.dpdu));
            }
            assert!(uv.x > 0.0 || uv.y > 0.0);
        }
    }

    #[test]
    fn shading_frames_follow_the_parameterization() {
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        let mut quad = TriangleMesh::rectangle();
        let turn = Transform::rotate(Vec3::Z, 30.0).unwrap();
        quad.transform(&(Transform::translate(Vec3::new(0.0, 0.0, -3.0)) * turn));
        b.add_shape(Geometry::Mesh(quad), m, None);
        b.add_shape(Geometry::Sphere(crate::geometry::Sphere::new(Vec3::new(5.0, 0.0, 0.0), 1.0, false)), m, None);
        let mut bare = TriangleMesh::rectangle();
        bare.uvs.clear();
        bare.transform(&Transform::translate(Vec3::new(-5.0, 0.0, 0.0)));
        b.add_shape(Geometry::Mesh(bare), m, None);
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 40.0, FovAxis::X, 4, 4).unwrap());
        let scene = b.build().unwrap();
        let hit = |o: Vec3, d: Vec3| scene.intersect(&Ray::new(o, d)).unwrap();
        let si = hit(Vec3::new(0.1, 0.2, 0.0), -Vec3::Z);
        let u_axis = turn.apply_vector(Vec3::X);
        assert!((si.frame().s - u_axis).length() < 1e-5, "{} vs {u_axis}", si.frame().s);
        let si = hit(Vec3::new(5.0, -5.0, 0.0), Vec3::Y);
        assert!((si.frame().s - Vec3::X).length() < 1e-5, "around the z axis at (0, -1, 0): {}", si.frame().s);
        let si = hit(Vec3::new(-5.2, 0.3, 4.0), -Vec3::Z);
        let tri = TriangleMesh::rectangle().triangle(si.prim as usize);
        assert!((si.frame().s - (tri[1] - tri[0]).normalize()).length() < 1e-6, "{}", si.frame().s);
        assert!(si.uv.x >= 0.0 && si.uv.y >= 0.0 && si.uv.x + si.uv.y <= 1.0 + 1e-6, "{}", si.uv);
    }

    /// A triangle soup with spheres among the triangles: leaves of triangles only (SIMD blocks)
    /// and mixed leaves (primitive lists) both occur, and both answer like brute force, with the
    /// soup's slivers pre-split into several references each.
    #[test]
    fn intersect_and_occluded_match_brute_force() {
        // Below and above SMALL_SCENE_PRIMITIVES: both BVH cost models.
        for triangles in [600u32, 3000] {
            match_brute_force(triangles);
        }
    }

    fn match_brute_force(triangles: u32) {
        let mut rng = Pcg32::new(9, triangles as u64);
        let v = |rng: &mut Pcg32, s: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * s - s / 2.0;
        let size = 1.0 / (triangles as f32 / 600.0).cbrt();
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..triangles {
            let c = v(&mut rng, 8.0);
            if i % 10 == 0 {
                // A long thin sliver across the soup: pre-split into several references.
                let (d, w) = (v(&mut rng, 6.0), v(&mut rng, 0.05));
                positions.extend([c - d, c + d, c + d + w]);
            } else {
                positions.extend([c + v(&mut rng, size), c + v(&mut rng, size), c + v(&mut rng, size)]);
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let mesh = TriangleMesh::new(positions, vec![], vec![], indices).unwrap();
        let tris: Vec<[Vec3; 3]> = (0..mesh.len()).map(|i| mesh.triangle(i)).collect();
        let spheres: Vec<Sphere> = (0..40)
            .map(|_| Sphere::new(v(&mut rng, 8.0), 0.1 + 0.3 * rng.next_f32(), false))
            .collect();
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        b.add_shape(Geometry::Mesh(mesh), m, None);
        for s in &spheres {
            b.add_shape(Geometry::Sphere(*s), m, None);
        }
        b.set_camera(Camera::perspective(Transform::IDENTITY, 45.0, FovAxis::X, 1, 1).unwrap());
        let mut scene = b.build().unwrap();
        assert_eq!(scene.primitive_count() > SMALL_SCENE_PRIMITIVES, triangles > 2000);
        assert!(scene.refs.len() > scene.primitive_count() + triangles as usize / 20, "slivers are split");
        assert!(!scene.blocks.is_empty(), "no triangle-only leaves");
        assert!(scene.prims.iter().any(|p| matches!(p.prim, Primitive::Triangle(_))), "no mixed leaves");
        // The same rays through every compiled traversal this CPU runs.
        for kernel in crate::bvh::Kernel::available() {
            assert!(scene.bvh.set_kernel(kernel));
            let hits = trace_like_brute_force(&scene, &tris, &spheres, &mut rng.clone());
            assert!(hits > 1000, "{kernel:?}: {hits}");
        }
    }

    /// [`match_brute_force`]'s rays from `rng` (intersections, hit-only queries and shadow rays);
    /// returns how many hit something.
    fn trace_like_brute_force(scene: &Scene, tris: &[[Vec3; 3]], spheres: &[Sphere], rng: &mut Pcg32) -> u32 {
        let v = |rng: &mut Pcg32, s: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * s - s / 2.0;
        let mut hits = 0;
        for _ in 0..5000 {
            let ray = Ray::new(v(rng, 10.0), sample_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32())).value);
            let pre = RayPrecomp::new(&ray);
            let tri = tris
                .iter()
                .enumerate()
                .filter_map(|(i, p)| intersect_triangle(&pre, p, f32::INFINITY).map(|h| (h.t(), 0, i as u32)));
            let sph = spheres
                .iter()
                .enumerate()
                .filter_map(|(i, s)| s.intersect(&ray, f32::INFINITY).map(|h| (h.t, i as u32 + 1, 0)));
            let brute = tri.chain(sph).min_by(|a, b| a.0.total_cmp(&b.0));
            let si = scene.intersect(&ray);
            let got = si.map(|si| (si.t, si.shape, si.prim));
            assert_eq!(got, brute);
            // The hit-only query names the same primitive at the same t, and for triangles its
            // barycentrics give the interaction's point.
            let hit = scene.intersect_hit(&ray);
            assert_eq!(hit.map(|h| (h.t, scene.primitive(h.prim))), got.map(|(t, shape, prim)| (t, (shape, prim))));
            if let (Some(h), Some(si)) = (hit, si) {
                if si.shape == 0 {
                    let p = tris[si.prim as usize];
                    let b = h.barycentrics;
                    let q = p[0] * (1.0 - b.x - b.y) + p[1] * b.x + p[2] * b.y;
                    assert!((q - si.p).length() <= 1e-4, "{q} vs {}", si.p);
                } else {
                    assert_eq!(h.barycentrics, Vec2::ZERO);
                }
            }
            if let Some((t, _, _)) = brute {
                hits += 1;
                assert!(scene.occluded(&Ray::bounded(ray.o, ray.d, t * 1.001)));
                assert!(!scene.occluded(&Ray::bounded(ray.o, ray.d, t * 0.999)));
            } else {
                assert!(!scene.occluded(&ray));
            }
        }
        hits
    }

    /// Past emitters: a ray through two emitting shells finds the diffuse sphere inside them
    /// (at the distance a plain query from the last crossing ray finds), moved past both; one
    /// allowed crossing gives up; a ray that misses the sphere escapes past the shells.
    #[test]
    fn deferred_hits_past_emitters() {
        use crate::geometry::Sphere;
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(crate::material::Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), m, None);
        for r in [2.0, 3.0] {
            b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, r, false)), m, Some(Rgb::ONE));
        }
        b.set_camera(Camera::perspective(Transform::IDENTITY, 30.0, FovAxis::X, 1, 1).unwrap());
        let scene = b.build().unwrap();
        let start = Ray::new(Vec3::new(0.1, 0.2, -10.0), Vec3::Z);
        let mut ray = start;
        let mut slot = HitSlot::default();
        let hit = scene.intersect_deferred_past_emitters(&mut ray, 8, &mut slot).expect("the inner sphere");
        assert_eq!(hit.light(), None);
        let si = hit.interaction();
        assert!((si.p.length() - 1.0).abs() < 1e-5 && si.p.z < 0.0, "{:?}", si.p);
        let t = hit.t();
        // It crossed the two shells' near sides: it starts at the inner one's.
        assert!(ray.o.z > -2.0 && ray.o.z < -1.0, "{:?}", ray.o);
        assert_eq!(scene.intersect_deferred(&ray, &mut HitSlot::default()).map(|h| h.t()), Some(t));
        let mut ray = start;
        assert!(scene.intersect_deferred_past_emitters(&mut ray, 1, &mut slot).is_none());
        let mut ray = Ray::new(Vec3::new(1.5, 0.0, -10.0), Vec3::Z);
        assert!(scene.intersect_deferred_past_emitters(&mut ray, 8, &mut slot).is_none());
        assert!(ray.o.z > 0.0, "the escaping ray left past the last shell: {:?}", ray.o);
    }
}
