//! The light BVH: chooses a light for next-event estimation with probability proportional to a
//! bound on its contribution at the shading point (pbrt-v4's `BVHLightSampler`, after Conty
//! Estevez and Kulla, "Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018).
//!
//! Each node bounds its lights by [`LightBounds`]: a box, their total power `φ`, a cone `(w, θ_o)`
//! holding their normals and the spread `θ_e` of emission about each normal (π/2 for diffuse
//! emitters). The importance of a node at point `p` with normal `n` is
//! `φ cos θ' / d² · cos θ'_i`, where `θ'` is the smallest angle between the emission cone and
//! the direction to `p` (zero importance beyond `θ_o + θ_e`), `θ'_i` the smallest angle between
//! `n` and the directions to the box, and `d²` the squared distance to the box centre clamped
//! below by half the box diagonal. Sampling walks from the root choosing a child with
//! probability proportional to its importance; the pmf of a light is the product of the choices
//! on its path (recorded as a bit trail, so [`LightBvh::pmf`] retraces it for MIS).
//!
//! The binary tree the build makes is walked two levels at a time: each node of the walked tree
//! holds a binary node's two children and their (up to four) children, and evaluates the six
//! importances at once (one AVX evaluation of eight lanes where the CPU has AVX, chosen at run
//! time; two SSE evaluations side by side otherwise) before making the two binary choices, so
//! that the second level's square roots and divisions do not wait for the first choice. The
//! probabilities are the binary walk's to the last bit (tested against it), and both
//! evaluations give the same bits.
//!
//! Lights at infinity (environments, directional light) have no bounds: they are chosen apart,
//! each with probability `1 / (n_infinite + 1)`, and the BVH gets the remaining `1 / (n + 1)`
//! (as in pbrt-v4). Lights of zero power are never chosen.
//!
//! The tree is built top-down with pbrt-v4's surface-area-orientation heuristic: 12 buckets per
//! axis, cost `φ M_Ω K_r A` per side (`M_Ω` the orientation cone's measure, `K_r` the box's
//! aspect along the split axis, `A` its surface area).

use super::Light;
use crate::geometry::Geometry;
use crate::math::simd::Avx;
use crate::math::{safe_acos, safe_sqrt, Bounds3, DirectionCone, Vec3, Vec4, PI};

/// Spatial and directional bounds of a set of emitters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Box holding the emitters (world).
    pub bounds: Bounds3,
    /// Total emitted power (luminance of the flux, W), as [`Light::power`].
    pub phi: f32,
    /// Axis of the normal cone.
    pub w: Vec3,
    /// Cosine of the normal cone's half-angle `θ_o` (-1: every direction).
    pub cos_theta_o: f32,
    /// Cosine of the spread `θ_e` of emission about each normal (0 for diffuse emitters).
    pub cos_theta_e: f32,
}

impl LightBounds {
    /// The bounds of `light`, or `None` for lights at infinity, lights without power and lights
    /// that next-event estimation cannot reach (a directional area light).
    pub fn of(light: &Light, shapes: &[Geometry]) -> Option<LightBounds> {
        let phi = light.power(shapes);
        if !(phi > 0.0 && phi.is_finite()) {
            return None;
        }
        match light {
            Light::Area { shape, two_sided, .. } => {
                let g = &shapes[*shape as usize];
                let cone = g.normal_cone();
                // A two-sided emitter's normals point both ways: the whole sphere of directions.
                let cos_theta_o = if *two_sided { -1.0 } else { cone.cos_theta };
                Some(LightBounds { bounds: g.bounds(), phi, w: cone.w, cos_theta_o, cos_theta_e: 0.0 })
            }
            Light::Point { position, .. } => Some(LightBounds {
                bounds: Bounds3::from_point(*position),
                phi,
                w: Vec3::Z,
                cos_theta_o: -1.0,
                cos_theta_e: 0.0,
            }),
            Light::Spot { position, frame, cutoff, beam, .. } => Some(LightBounds {
                bounds: Bounds3::from_point(*position),
                phi,
                w: frame.to_world(Vec3::Z),
                // Full strength within the beam, falling to zero at the cutoff (pbrt-v4's bound).
                cos_theta_o: beam.cos(),
                cos_theta_e: (cutoff - beam).cos(),
            }),
            Light::Projector(p) => {
                let (w, cos_theta_o) = p.cone();
                // Nothing beyond the image's frustum (pbrt-v4's projection light bound).
                Some(LightBounds { bounds: Bounds3::from_point(p.position()), phi, w, cos_theta_o, cos_theta_e: 1.0 })
            }
            // Bounded as an isotropic point, as pbrt-v4 bounds it.
            Light::Goniometric(g) => Some(LightBounds {
                bounds: Bounds3::from_point(g.position()),
                phi,
                w: Vec3::Z,
                cos_theta_o: -1.0,
                cos_theta_e: 0.0,
            }),
            Light::Constant { .. }
            | Light::EnvMap { .. }
            | Light::SunSky { .. }
            | Light::Directional { .. }
            | Light::DirectionalArea { .. } => None,
        }
    }

    /// Bounds of the union of two sets of emitters.
    pub fn union(a: &LightBounds, b: &LightBounds) -> LightBounds {
        let cone = DirectionCone::union(
            &DirectionCone { w: a.w, cos_theta: a.cos_theta_o },
            &DirectionCone { w: b.w, cos_theta: b.cos_theta_o },
        );
        LightBounds {
            bounds: a.bounds.union(&b.bounds),
            phi: a.phi + b.phi,
            w: cone.w,
            cos_theta_o: cone.cos_theta,
            cos_theta_e: a.cos_theta_e.min(b.cos_theta_e),
        }
    }

    /// Conservative importance of these emitters at point `p` with unit normal `n` (zero for a
    /// point in a medium): pbrt-v4's `LightBounds::Importance` (module docs). Zero only where
    /// no emitter of the set can send light to `p` (or reach `n`'s hemisphere pair).
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        NodeBounds::new(self).importance(p, n)
    }

    /// pbrt-v4's split cost of a node with these bounds inside `parent` split along `axis`.
    fn cost(&self, parent: &Bounds3, axis: usize) -> f32 {
        let theta_o = safe_acos(self.cos_theta_o);
        let theta_e = safe_acos(self.cos_theta_e);
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = safe_sqrt(1.0 - self.cos_theta_o * self.cos_theta_o);
        let m_omega = 2.0 * PI * (1.0 - self.cos_theta_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + self.cos_theta_o);
        let d = parent.diagonal();
        let kr = if d[axis] > 0.0 { d.max_element() / d[axis] } else { 1.0 };
        self.phi * m_omega * kr * self.bounds.surface_area()
    }
}

/// [`LightBounds`] as the traversal reads them: the box reduced to its bounding sphere, and the
/// sine of the normal cone's angle, precomputed.
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    /// Centre of the box (and of its bounding sphere).
    center: Vec3,
    /// Radius of the bounding sphere (half the box diagonal).
    radius: f32,
    w: Vec3,
    phi: f32,
    cos_theta_o: f32,
    sin_theta_o: f32,
    cos_theta_e: f32,
}

impl NodeBounds {
    fn new(b: &LightBounds) -> NodeBounds {
        let (center, radius) = b.bounds.bounding_sphere();
        NodeBounds {
            center,
            radius,
            w: b.w,
            phi: b.phi,
            cos_theta_o: b.cos_theta_o,
            sin_theta_o: safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o),
            cos_theta_e: b.cos_theta_e,
        }
    }

    /// See [`LightBounds::importance`]; [`WideBounds::importance`] is the same for eight at once.
    #[inline]
    fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        // cos(a − b) and sin(a − b), clamped to the angle 0 when a < b.
        #[inline(always)]
        fn cos_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
            if cos_a > cos_b {
                1.0
            } else {
                cos_a * cos_b + sin_a * sin_b
            }
        }
        #[inline(always)]
        fn sin_sub(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
            if cos_a > cos_b {
                0.0
            } else {
                sin_a * cos_b - cos_a * sin_b
            }
        }
        let d = p - self.center;
        let dist2 = d.length_squared();
        // pbrt-v4 clamps d² below by half the box diagonal (a length: its units as written).
        let d2 = dist2.max(self.radius);
        // One square root and one division give the unit direction and the cone below (this
        // runs twice per level of the tree for every light sample: its chain of square roots and
        // divisions is the light choice's latency).
        let inv_dist = if dist2 > 0.0 { 1.0 / dist2.sqrt() } else { 0.0 };
        let wi = d * inv_dist;
        let cos_w = self.w.dot(wi);
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        // The cone of directions from p to the bounding sphere, sin θb = r / d (the whole sphere
        // from inside: cos θb = −1).
        let (sin_b, cos_b) = if dist2 <= self.radius * self.radius {
            (0.0, -1.0)
        } else {
            let sin_b = (self.radius * inv_dist).min(1.0);
            (sin_b, safe_sqrt(1.0 - sin_b * sin_b))
        };
        let cos_x = cos_sub(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
        let sin_x = sin_sub(sin_w, cos_w, self.sin_theta_o, self.cos_theta_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        // Nothing beyond θo + θe. Strictly beyond: a light that stops sharply at its cone (θe = 0,
        // a spot whose beam width is its cutoff, a projector) still lights the inside.
        if cos_p < self.cos_theta_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if n != Vec3::ZERO {
            let cos_i = wi.dot(n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            importance *= cos_sub(sin_i, cos_i, sin_b, cos_b);
        }
        importance.max(0.0)
    }
}

/// Lanes of one SSE evaluation of importances.
const WIDTH: usize = 4;

/// Lanes of a [`WideBounds`]: two SSE evaluations, or one AVX evaluation.
const LANES: usize = 2 * WIDTH;

/// The [`NodeBounds`] of up to eight nodes, lane `k` for node `k`, so that SIMD evaluations give
/// all their importances at once: two SSE evaluations of four lanes, or one AVX evaluation of
/// eight where the CPU has AVX (the same operations in the same order as
/// [`NodeBounds::importance`], lane by lane: the same bits either way). Unused lanes have
/// importance 0.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct WideBounds {
    center: [[f32; LANES]; 3],
    radius: [f32; LANES],
    w: [[f32; LANES]; 3],
    phi: [f32; LANES],
    cos_theta_o: [f32; LANES],
    sin_theta_o: [f32; LANES],
    cos_theta_e: [f32; LANES],
}

/// Lane-wise square root (exact, as the scalar one).
#[inline(always)]
fn sqrt4(x: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE is part of x86_64.
        Vec4::from(unsafe { std::arch::x86_64::_mm_sqrt_ps(x.into()) })
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec4::new(x.x.sqrt(), x.y.sqrt(), x.z.sqrt(), x.w.sqrt())
    }
}

/// `safe_sqrt` lane by lane (`max` returns its second operand for a NaN lane, as `f32::max`
/// returns the number).
#[inline(always)]
fn safe_sqrt4(x: Vec4) -> Vec4 {
    sqrt4(x.max(Vec4::ZERO))
}

impl WideBounds {
    /// Lanes for `nodes` (at most [`LANES`]); lanes of `None` or beyond can never be chosen
    /// (their emission spread `cos θ_e = 2` puts every point outside it).
    fn new(nodes: &[Option<NodeBounds>]) -> WideBounds {
        assert!(nodes.len() <= LANES, "a wide bound holds at most {LANES} lanes");
        let lane = |f: &dyn Fn(&NodeBounds) -> f32, unused: f32| {
            std::array::from_fn(|k| nodes.get(k).copied().flatten().as_ref().map_or(unused, f))
        };
        WideBounds {
            center: [lane(&|b| b.center.x, 0.0), lane(&|b| b.center.y, 0.0), lane(&|b| b.center.z, 0.0)],
            radius: lane(&|b| b.radius, 1.0),
            w: [lane(&|b| b.w.x, 0.0), lane(&|b| b.w.y, 0.0), lane(&|b| b.w.z, 1.0)],
            phi: lane(&|b| b.phi, 0.0),
            cos_theta_o: lane(&|b| b.cos_theta_o, 1.0),
            sin_theta_o: lane(&|b| b.sin_theta_o, 0.0),
            cos_theta_e: lane(&|b| b.cos_theta_e, 2.0),
        }
    }

    /// [`NodeBounds::importance`] of every lane at `p` with unit normal `n` (zero in a medium),
    /// in one AVX evaluation where `avx` is given, else in two SSE evaluations.
    #[inline(always)]
    fn importance(&self, p: Vec3, n: Vec3, avx: Option<Avx>) -> [f32; LANES] {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = avx {
            return self.importance_avx(avx, p, n);
        }
        let _ = avx;
        let mut out = [0.0; LANES];
        out[..WIDTH].copy_from_slice(&self.importance4(0, p, n));
        out[WIDTH..].copy_from_slice(&self.importance4(WIDTH, p, n));
        out
    }

    /// Lanes `first .. first + 4` of [`WideBounds::importance`] in one SSE evaluation.
    #[inline(always)]
    fn importance4(&self, first: usize, p: Vec3, n: Vec3) -> [f32; WIDTH] {
        // cos(a − b) and sin(a − b), clamped to the angle 0 when a < b.
        #[inline(always)]
        fn cos_sub(sin_a: Vec4, cos_a: Vec4, sin_b: Vec4, cos_b: Vec4) -> Vec4 {
            Vec4::select(cos_a.cmpgt(cos_b), Vec4::ONE, cos_a * cos_b + sin_a * sin_b)
        }
        #[inline(always)]
        fn sin_sub(sin_a: Vec4, cos_a: Vec4, sin_b: Vec4, cos_b: Vec4) -> Vec4 {
            Vec4::select(cos_a.cmpgt(cos_b), Vec4::ZERO, sin_a * cos_b - cos_a * sin_b)
        }
        let v = |x: &[f32; LANES]| Vec4::from_slice(&x[first..first + WIDTH]);
        let (radius, w) = (v(&self.radius), self.w.each_ref().map(v));
        let (sin_theta_o, cos_theta_o) = (v(&self.sin_theta_o), v(&self.cos_theta_o));
        let d = [
            Vec4::splat(p.x) - v(&self.center[0]),
            Vec4::splat(p.y) - v(&self.center[1]),
            Vec4::splat(p.z) - v(&self.center[2]),
        ];
        let dist2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let d2 = dist2.max(radius);
        let inv_dist = Vec4::select(dist2.cmpgt(Vec4::ZERO), Vec4::ONE / sqrt4(dist2), Vec4::ZERO);
        let wi = [d[0] * inv_dist, d[1] * inv_dist, d[2] * inv_dist];
        let cos_w = w[0] * wi[0] + w[1] * wi[1] + w[2] * wi[2];
        let sin_w = safe_sqrt4(Vec4::ONE - cos_w * cos_w);
        let inside = dist2.cmple(radius * radius);
        let sin_b_out = (radius * inv_dist).min(Vec4::ONE);
        let sin_b = Vec4::select(inside, Vec4::ZERO, sin_b_out);
        let cos_b = Vec4::select(inside, Vec4::NEG_ONE, safe_sqrt4(Vec4::ONE - sin_b_out * sin_b_out));
        let cos_x = cos_sub(sin_w, cos_w, sin_theta_o, cos_theta_o);
        let sin_x = sin_sub(sin_w, cos_w, sin_theta_o, cos_theta_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        let mut importance = v(&self.phi) * cos_p / d2;
        if n != Vec3::ZERO {
            let cos_i = (wi[0] * n.x + wi[1] * n.y + wi[2] * n.z).abs();
            let sin_i = safe_sqrt4(Vec4::ONE - cos_i * cos_i);
            importance *= cos_sub(sin_i, cos_i, sin_b, cos_b);
        }
        Vec4::select(cos_p.cmplt(v(&self.cos_theta_e)), Vec4::ZERO, importance.max(Vec4::ZERO)).to_array()
    }

    /// [`WideBounds::importance`] in one AVX evaluation: [`WideBounds::importance4`]'s
    /// operations on eight lanes (`maxps`/`minps` with the same operand order, comparisons that
    /// are false for NaN alike, blends for its selects).
    #[cfg(target_arch = "x86_64")]
    #[inline]
    fn importance_avx(&self, _: Avx, p: Vec3, n: Vec3) -> [f32; LANES] {
        // SAFETY: the token proves the CPU has AVX.
        unsafe { self.importance_avx_unchecked(p, n) }
    }

    /// Safety: the CPU must have AVX. (Its loads are aligned ones: `WideBounds` is aligned to
    /// 32 bytes and each of its rows is 32 bytes long.)
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn importance_avx_unchecked(&self, p: Vec3, n: Vec3) -> [f32; LANES] {
        use std::arch::x86_64::*;
        let v = |x: &[f32; LANES]| _mm256_load_ps(x.as_ptr());
        let (one, zero, splat) = (_mm256_set1_ps(1.0), _mm256_setzero_ps(), |x: f32| _mm256_set1_ps(x));
        let (add, sub, mul) = (|a, b| _mm256_add_ps(a, b), |a, b| _mm256_sub_ps(a, b), |a, b| _mm256_mul_ps(a, b));
        // Vec4::select(mask, a, b): a where the mask is set.
        let select = |mask, a, b| _mm256_blendv_ps(b, a, mask);
        let gt = |a, b| _mm256_cmp_ps::<_CMP_GT_OS>(a, b);
        let safe_sqrt = |x| _mm256_sqrt_ps(_mm256_max_ps(x, zero));
        let cos_sub =
            |sin_a, cos_a, sin_b, cos_b| select(gt(cos_a, cos_b), one, add(mul(cos_a, cos_b), mul(sin_a, sin_b)));
        let sin_sub =
            |sin_a, cos_a, sin_b, cos_b| select(gt(cos_a, cos_b), zero, sub(mul(sin_a, cos_b), mul(cos_a, sin_b)));
        let radius = v(&self.radius);
        let w = self.w.each_ref().map(v);
        let (sin_theta_o, cos_theta_o) = (v(&self.sin_theta_o), v(&self.cos_theta_o));
        let d = [
            sub(splat(p.x), v(&self.center[0])),
            sub(splat(p.y), v(&self.center[1])),
            sub(splat(p.z), v(&self.center[2])),
        ];
        let dist2 = add(add(mul(d[0], d[0]), mul(d[1], d[1])), mul(d[2], d[2]));
        let d2 = _mm256_max_ps(dist2, radius);
        let inv_dist = select(gt(dist2, zero), _mm256_div_ps(one, _mm256_sqrt_ps(dist2)), zero);
        let wi = [mul(d[0], inv_dist), mul(d[1], inv_dist), mul(d[2], inv_dist)];
        let cos_w = add(add(mul(w[0], wi[0]), mul(w[1], wi[1])), mul(w[2], wi[2]));
        let sin_w = safe_sqrt(sub(one, mul(cos_w, cos_w)));
        let inside = _mm256_cmp_ps::<_CMP_LE_OS>(dist2, mul(radius, radius));
        let sin_b_out = _mm256_min_ps(mul(radius, inv_dist), one);
        let sin_b = select(inside, zero, sin_b_out);
        let cos_b = select(inside, splat(-1.0), safe_sqrt(sub(one, mul(sin_b_out, sin_b_out))));
        let cos_x = cos_sub(sin_w, cos_w, sin_theta_o, cos_theta_o);
        let sin_x = sin_sub(sin_w, cos_w, sin_theta_o, cos_theta_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        let mut importance = _mm256_div_ps(mul(v(&self.phi), cos_p), d2);
        if n != Vec3::ZERO {
            let dot = add(add(mul(wi[0], splat(n.x)), mul(wi[1], splat(n.y))), mul(wi[2], splat(n.z)));
            let cos_i = _mm256_andnot_ps(splat(-0.0), dot);
            let sin_i = safe_sqrt(sub(one, mul(cos_i, cos_i)));
            importance = mul(importance, cos_sub(sin_i, cos_i, sin_b, cos_b));
        }
        let beyond = _mm256_cmp_ps::<_CMP_LT_OS>(cos_p, v(&self.cos_theta_e));
        let out = select(beyond, zero, _mm256_max_ps(importance, zero));
        let mut lanes = [0.0f32; LANES];
        _mm256_storeu_ps(lanes.as_mut_ptr(), out);
        lanes
    }
}

/// Buckets per axis of the light BVH's split search.
const BUCKETS: usize = 12;

/// The split bucket of `b`'s centroid along `axis`, whose centroids span `[lo, hi]`.
#[inline]
fn bucket(b: &LightBounds, axis: usize, lo: f32, hi: f32) -> usize {
    (((b.bounds.centroid()[axis] - lo) / (hi - lo) * BUCKETS as f32) as usize).min(BUCKETS - 1)
}

/// A node of the binary tree the build makes (then collapsed into [`WideNode`]s): its bounds,
/// and either its second child (the first follows it) or its light.
#[derive(Clone, Copy, Debug)]
struct BinaryNode {
    bounds: LightBounds,
    /// Second child's index (interior) or the light's index (leaf).
    child_or_light: u32,
    leaf: bool,
}

/// Two levels of the binary tree as sampling walks them: a binary node's two children (lanes 0
/// and 1 of `bounds`) and, for each child that is not a light, its two children (lanes `4 + 2k`
/// and `5 + 2k` for child `k`). All six importances are evaluated at once (one AVX evaluation, or
/// two SSE evaluations side by side), then the two binary choices are made from them as the
/// binary walk makes them, so that the walk is half as deep and gives the binary tree's
/// probabilities to the last bit.
#[derive(Clone, Copy, Debug)]
struct WideNode {
    bounds: WideBounds,
    /// Child `k`'s light, where bit `k` of `lights` is set (else its children are below).
    child: [u32; 2],
    /// Grandchild `j`: a node's index, or a light's index where bit `2 + j` of `lights` is set.
    grandchild: [u32; 4],
    /// Which children (bits 0, 1) and grandchildren (bits 2 to 5) are lights.
    lights: u8,
}

/// The light BVH over a scene's bounded lights, with the scene's lights at infinity beside it.
#[derive(Clone, Debug)]
pub struct LightBvh {
    /// The tree (root first); empty when it holds fewer than two lights.
    nodes: Vec<WideNode>,
    /// The one bounded light, when there is exactly one (no tree to walk).
    lone: Option<u32>,
    /// Per light: its path from the root of the binary tree (bit k set: the second child at
    /// depth k), or `NOT_IN_TREE`.
    trails: Vec<u64>,
    /// Lights at infinity, chosen apart.
    infinite: Vec<u32>,
    /// Whether each light is at infinity.
    is_infinite: Vec<bool>,
    /// Probability of choosing among the lights at infinity, `n_inf / (n_inf + 1)` (or 1 without
    /// a tree).
    p_infinite: f32,
    /// The AVX token where this CPU has AVX (one evaluation per node instead of two).
    avx: Option<Avx>,
}

/// Trail of a light that the tree does not hold.
const NOT_IN_TREE: u64 = u64::MAX;

/// Deepest leaf a trail can record (one bit per level): the build keeps every leaf at most this
/// deep (see [`build`]).
const MAX_DEPTH: u32 = 64;

impl LightBvh {
    /// Builds the tree over `lights` (on `shapes`).
    pub fn new(lights: &[Light], shapes: &[Geometry]) -> LightBvh {
        let mut items: Vec<(u32, LightBounds)> = Vec::new();
        let mut infinite = Vec::new();
        let mut is_infinite = vec![false; lights.len()];
        for (i, l) in lights.iter().enumerate() {
            if l.is_infinite() || matches!(l, Light::Directional { .. }) {
                // Zero-power lights at infinity are still never chosen: skip them too.
                if l.power(shapes) > 0.0 {
                    infinite.push(i as u32);
                    is_infinite[i] = true;
                }
            } else if let Some(b) = LightBounds::of(l, shapes) {
                items.push((i as u32, b));
            }
        }
        let mut bvh = LightBvh {
            nodes: Vec::new(),
            lone: None,
            trails: vec![NOT_IN_TREE; lights.len()],
            infinite,
            is_infinite,
            p_infinite: 0.0,
            avx: Avx::detect(),
        };
        match items.len() {
            0 => {}
            1 => {
                bvh.lone = Some(items[0].0);
                bvh.trails[items[0].0 as usize] = 0;
            }
            n => {
                let mut binary = Vec::with_capacity(2 * n - 1);
                build(&mut binary, &mut items, 0, n, 0, MAX_DEPTH);
                bvh.collapse(&binary, 0, 0, 0);
            }
        }
        let (n_inf, tree) = (bvh.infinite.len() as u32, u32::from(!bvh.nodes.is_empty() || bvh.lone.is_some()));
        bvh.p_infinite = if n_inf + tree == 0 { 0.0 } else { n_inf as f32 / (n_inf + tree) as f32 };
        bvh
    }

    /// Whether light `i` can be chosen at all (some point gives it a positive probability): a
    /// light at infinity, or one in the tree (bounded, of positive power, reachable by
    /// next-event estimation).
    pub fn selectable(&self, i: u32) -> bool {
        self.is_infinite[i as usize] || self.trails[i as usize] != NOT_IN_TREE
    }

    /// Writes the wide node of binary interior node `b` (and its subtree) at binary depth
    /// `depth` with path `trail` (bit `k` set: the second child at depth `k`); returns its index.
    fn collapse(&mut self, binary: &[BinaryNode], b: usize, trail: u64, depth: u32) -> u32 {
        let second = |c: usize| binary[c].child_or_light as usize;
        let children = [b + 1, second(b)];
        let mut grandchildren = [None; 4];
        for (k, &c) in children.iter().enumerate() {
            if !binary[c].leaf {
                (grandchildren[2 * k], grandchildren[2 * k + 1]) = (Some(c + 1), Some(second(c)));
            }
        }
        // Lanes 0 and 1 the children, 4 to 7 the grandchildren.
        let lanes: Vec<Option<NodeBounds>> = [Some(children[0]), Some(children[1]), None, None]
            .iter()
            .chain(&grandchildren)
            .map(|c| c.map(|c| NodeBounds::new(&binary[c].bounds)))
            .collect();
        let index = self.nodes.len();
        self.nodes.push(WideNode { bounds: WideBounds::new(&lanes), child: [0; 2], grandchild: [0; 4], lights: 0 });
        for (k, &c) in children.iter().enumerate() {
            let trail = trail | (k as u64) << depth;
            if binary[c].leaf {
                let light = binary[c].child_or_light;
                self.trails[light as usize] = trail;
                self.nodes[index].child[k] = light;
                self.nodes[index].lights |= 1 << k;
                continue;
            }
            for (j, g) in [c + 1, second(c)].into_iter().enumerate() {
                let trail = trail | (j as u64) << (depth + 1);
                let reference = if binary[g].leaf {
                    self.nodes[index].lights |= 1 << (2 + 2 * k + j);
                    self.trails[binary[g].child_or_light as usize] = trail;
                    binary[g].child_or_light
                } else {
                    self.collapse(binary, g, trail, depth + 2)
                };
                self.nodes[index].grandchild[2 * k + j] = reference;
            }
        }
        index as u32
    }

    /// Number of (wide) tree nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Chooses a light for shading point `p` with unit normal `n` (zero in a medium): the
    /// light's index and the probability of choosing it. `None` if no light can reach `p`.
    #[inline]
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(u32, f32)> {
        let p_inf = self.p_infinite;
        if u < p_inf {
            let k = ((u / p_inf * self.infinite.len() as f32) as usize).min(self.infinite.len() - 1);
            return Some((self.infinite[k], p_inf / self.infinite.len() as f32));
        }
        if let Some(light) = self.lone {
            // A lone light is returned without testing it: its pmf is the same everywhere, and
            // where it cannot reach, its sample_li or the BSDF gives nothing.
            return Some((light, 1.0 - p_inf));
        }
        if self.nodes.is_empty() {
            return None;
        }
        // u walks down the tree as the interval [lo, hi) of [0, 1) that the node covers (the
        // first child the first p0 of it): the choice at a node compares u with the children's
        // importances by multiplication, so the divisions that give p0 and the interval run
        // beside the next node's importances instead of before them (u is not rescaled, which
        // would put two divisions per level on the chain of dependent operations).
        let mut walk = Walk { lo: p_inf, hi: 1.0, pmf: 1.0 - p_inf };
        let mut index = 0usize;
        loop {
            let node = &self.nodes[index];
            // Both levels' importances at once: the second does not wait for the first choice.
            let i = node.bounds.importance(p, n, self.avx);
            let (ic, ig) = (&i[..WIDTH], &i[WIDTH..]);
            let k = walk.choose(u, ic[0], ic[1])?;
            if node.lights >> k & 1 == 1 {
                return Some((node.child[k], walk.pmf));
            }
            let g = 2 * k + walk.choose(u, ig[2 * k], ig[2 * k + 1])?;
            if node.lights >> (2 + g) & 1 == 1 {
                return Some((node.grandchild[g], walk.pmf));
            }
            index = node.grandchild[g] as usize;
        }
    }

    /// Probability that [`LightBvh::sample`] at `(p, n)` chooses light `light`.
    #[inline]
    pub fn pmf(&self, p: Vec3, n: Vec3, light: u32) -> f32 {
        let p_inf = self.p_infinite;
        if self.is_infinite.get(light as usize).copied().unwrap_or(false) {
            return p_inf / self.infinite.len() as f32;
        }
        let Some(&trail) = self.trails.get(light as usize) else { return 0.0 };
        if trail == NOT_IN_TREE {
            return 0.0;
        }
        if self.lone.is_some() {
            return 1.0 - p_inf;
        }
        let mut trail = trail;
        let mut pmf = 1.0 - p_inf;
        let mut index = 0usize;
        loop {
            let node = &self.nodes[index];
            let i = node.bounds.importance(p, n, self.avx);
            let (ic, ig) = (&i[..WIDTH], &i[WIDTH..]);
            let Some(k) = follow(&mut pmf, &mut trail, ic[0], ic[1]) else { return 0.0 };
            if node.lights >> k & 1 == 1 {
                return pmf;
            }
            let Some(j) = follow(&mut pmf, &mut trail, ig[2 * k], ig[2 * k + 1]) else { return 0.0 };
            let g = 2 * k + j;
            if node.lights >> (2 + g) & 1 == 1 {
                return pmf;
            }
            index = node.grandchild[g] as usize;
        }
    }
}

/// The state of [`LightBvh::sample`]'s walk: the interval `[lo, hi)` of `[0, 1)` that the
/// node reached covers, and the probability of reaching it.
struct Walk {
    lo: f32,
    hi: f32,
    pmf: f32,
}

impl Walk {
    /// One binary choice between importances `i0` and `i1` for `u`: 1 if the second is taken,
    /// `None` where neither can be.
    #[inline(always)]
    fn choose(&mut self, u: f32, i0: f32, i1: f32) -> Option<usize> {
        if i0 == 0.0 && i1 == 0.0 {
            return None;
        }
        let total = i0 + i1;
        // The same p0 as `pmf` computes, so that the two agree to the last bit.
        let p0 = i0 / total;
        let split = self.lo + (self.hi - self.lo) * p0;
        // First child: u in the first i0 / total of [lo, hi); a zero-importance child is never
        // chosen.
        if i1 == 0.0 || (i0 > 0.0 && (u - self.lo) * total < (self.hi - self.lo) * i0) {
            self.hi = split.max(self.lo);
            self.pmf *= p0;
            Some(0)
        } else {
            self.lo = split.min(self.hi);
            self.pmf *= 1.0 - p0;
            Some(1)
        }
    }
}

/// [`Walk::choose`] retraced for [`LightBvh::pmf`]: the child that bit 0 of `trail` names
/// (shifted out), its probability multiplied into `pmf`; `None` where neither can be chosen.
#[inline(always)]
fn follow(pmf: &mut f32, trail: &mut u64, i0: f32, i1: f32) -> Option<usize> {
    if i0 == 0.0 && i1 == 0.0 {
        return None;
    }
    // The same arithmetic as `sample`, so that the two agree to the last bit.
    let p0 = i0 / (i0 + i1);
    let second = (*trail & 1) as usize;
    *pmf *= if second == 1 { 1.0 - p0 } else { p0 };
    *trail >>= 1;
    Some(second)
}

/// Builds the binary subtree of `items[start..end]` at `depth` into `nodes` (its root first, each
/// interior node's first child after it); returns its bounds. No leaf is deeper than
/// `max_depth` (given `depth + ⌈log₂ count⌉ ≤ max_depth`, true at the root for any count up to
/// 2⁶⁴): the SAH may split off as little as one light, so it splits a node only where a child of
/// all but one of its lights could still be halved down to single lights within the bound; below
/// that, median splits halve the count at each level.
fn build(
    nodes: &mut Vec<BinaryNode>,
    items: &mut [(u32, LightBounds)],
    start: usize,
    end: usize,
    depth: u32,
    max_depth: u32,
) -> LightBounds {
    if end - start == 1 {
        let (light, bounds) = items[start];
        nodes.push(BinaryNode { bounds, child_or_light: light, leaf: true });
        return bounds;
    }
    let mut bounds = Bounds3::EMPTY;
    let mut centroids = Bounds3::EMPTY;
    for (_, b) in &items[start..end] {
        bounds = bounds.union(&b.bounds);
        centroids = centroids.union_point(b.bounds.centroid());
    }
    // ⌈log₂ x⌉ for x ≥ 1.
    let ceil_log2 = |x: usize| usize::BITS - (x - 1).leading_zeros();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, last bucket of side 0)
    if depth + 1 + ceil_log2(end - start - 1) <= max_depth {
        for axis in 0..3 {
            let (lo, hi) = (centroids.min[axis], centroids.max[axis]);
            if hi <= lo {
                continue;
            }
            let bucket_of = |b: &LightBounds| bucket(b, axis, lo, hi);
            let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
            for (_, b) in &items[start..end] {
                let k = bucket_of(b);
                buckets[k] = Some(match buckets[k] {
                    Some(acc) => LightBounds::union(&acc, b),
                    None => *b,
                });
            }
            let merge = |range: &[Option<LightBounds>]| {
                range
                    .iter()
                    .flatten()
                    .fold(None, |acc: Option<LightBounds>, b| Some(acc.map_or(*b, |a| LightBounds::union(&a, b))))
            };
            for split in 0..BUCKETS - 1 {
                let (Some(b0), Some(b1)) = (merge(&buckets[..=split]), merge(&buckets[split + 1..])) else {
                    continue;
                };
                let cost = b0.cost(&bounds, axis) + b1.cost(&bounds, axis);
                if cost.is_finite() && best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, split));
                }
            }
        }
    }
    let mut mid = (start + end) / 2;
    if let Some((_, axis, split)) = best {
        let (lo, hi) = (centroids.min[axis], centroids.max[axis]);
        let slice = &mut items[start..end];
        let mut k = 0;
        for i in 0..slice.len() {
            let b = bucket(&slice[i].1, axis, lo, hi);
            if b <= split {
                slice.swap(i, k);
                k += 1;
            }
        }
        if k > 0 && k < slice.len() {
            mid = start + k;
        }
    }
    let index = nodes.len();
    // Placeholder; filled in once both children are built.
    nodes.push(BinaryNode { bounds: items[start].1, child_or_light: 0, leaf: false });
    let b0 = build(nodes, items, start, mid, depth + 1, max_depth);
    let second = nodes.len() as u32;
    let b1 = build(nodes, items, mid, end, depth + 1, max_depth);
    let bounds = LightBounds::union(&b0, &b1);
    nodes[index] = BinaryNode { bounds, child_or_light: second, leaf: false };
    bounds
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Disk, Sphere, TriangleMesh};
    use crate::math::{Frame, Rgb, Transform};
    use crate::sampling::{sample_uniform_sphere, Pcg32};
    use crate::testkit::{chi2_discrete, u2, Chi2Config};

    /// A scene of varied bounded lights (spheres, oriented quads, a disk, points, a spot) and an
    /// environment, with their shapes.
    pub(crate) fn many_lights(seed: u64) -> (Vec<Light>, Vec<Geometry>) {
        let mut rng = Pcg32::new(seed, 7);
        let mut shapes = Vec::new();
        let mut lights = Vec::new();
        let mut r = || rng.next_f32();
        for k in 0..40 {
            let c = Vec3::new(8.0 * r() - 4.0, 3.0 * r(), 8.0 * r() - 4.0);
            let radiance = Rgb::new(r(), r(), r()) * (10.0 * r() + 0.1);
            let mut g = if k % 3 == 0 {
                let mut m = TriangleMesh::rectangle();
                let axis = sample_uniform_sphere(glam::Vec2::new(r(), r())).value;
                let t = Transform::translate(c)
                    * Transform::rotate(axis, 360.0 * r()).unwrap()
                    * Transform::scale(Vec3::splat(0.05 + 0.3 * r())).unwrap();
                m.transform(&t);
                Geometry::Mesh(m)
            } else if k % 7 == 1 {
                Geometry::Disk(
                    Disk::new(Transform::translate(c) * Transform::rotate(Vec3::X, 90.0).unwrap(), false).unwrap(),
                )
            } else {
                Geometry::Sphere(Sphere::new(c, 0.01 + 0.3 * r(), false))
            };
            assert!(g.prepare_sampling());
            if let Geometry::Mesh(m) = &mut g {
                m.prepare_normals();
            }
            shapes.push(g);
            lights.push(Light::Area { shape: k, radiance: radiance.into(), two_sided: k == 1 });
        }
        lights.push(Light::Point { position: Vec3::new(1.0, 2.0, -1.0), intensity: Rgb::splat(3.0) });
        lights.push(Light::Point { position: Vec3::new(-3.0, 0.5, 2.0), intensity: Rgb::new(0.1, 0.5, 0.2) });
        lights.push(Light::Spot {
            position: Vec3::new(0.0, 4.0, 0.0),
            frame: Frame::from_z(-Vec3::Y),
            intensity: Rgb::splat(20.0),
            cutoff: 0.5,
            beam: 0.3,
            texture: None,
            falloff: crate::light::SpotFalloff::SmoothStep,
        });
        // Lights that stop sharply at their cone: a spot whose beam is its cutoff, a projector.
        lights.push(Light::Spot {
            position: Vec3::new(2.0, 3.0, 1.0),
            frame: Frame::from_z(Vec3::new(-0.2, -1.0, 0.1).normalize()),
            intensity: Rgb::splat(5.0),
            cutoff: 0.4,
            beam: 0.4,
            texture: None,
            falloff: crate::light::SpotFalloff::Linear,
        });
        let to_world =
            crate::math::Transform::look_at(Vec3::new(-2.0, 3.0, 0.0), Vec3::new(-1.0, 0.0, 0.5), Vec3::Y).unwrap();
        lights.push(Light::Projector(Box::new(crate::light::Projector::new(
            to_world,
            30.0,
            crate::props::fov::FovAxis::X,
            crate::texture::Texture::Constant(Rgb::splat(2.0)),
            1.0,
        ))));
        lights.push(Light::Constant { radiance: Rgb::splat(0.2), center: Vec3::ZERO, radius: 6.0 });
        (lights, shapes)
    }

    /// The reference: pbrt-v4's walk of the binary tree that [`LightBvh::new`] builds, one
    /// scalar importance at a time. Returns the binary tree's nodes and, per light, the pmf at
    /// `(p, n)` computed root to leaf with the same arithmetic as the walk.
    fn binary_reference(lights: &[Light], shapes: &[Geometry]) -> (Vec<BinaryNode>, f32) {
        let bvh = LightBvh::new(lights, shapes);
        let mut items: Vec<(u32, LightBounds)> = (0..lights.len() as u32)
            .filter(|&i| !bvh.is_infinite[i as usize])
            .filter_map(|i| Some((i, LightBounds::of(&lights[i as usize], shapes)?)))
            .collect();
        let mut nodes = Vec::new();
        let n = items.len();
        build(&mut nodes, &mut items, 0, n, 0, MAX_DEPTH);
        (nodes, bvh.p_infinite)
    }

    /// [`LightBvh::sample`] by the reference's binary walk.
    fn sample_binary(nodes: &[BinaryNode], p_inf: f32, p: Vec3, n: Vec3, u: f32) -> Option<(u32, f32)> {
        let mut walk = Walk { lo: p_inf, hi: 1.0, pmf: 1.0 - p_inf };
        let mut index = 0;
        while !nodes[index].leaf {
            let (c0, c1) = (index + 1, nodes[index].child_or_light as usize);
            let second = walk.choose(u, nodes[c0].bounds.importance(p, n), nodes[c1].bounds.importance(p, n))?;
            index = if second == 1 { c1 } else { c0 };
        }
        Some((nodes[index].child_or_light, walk.pmf))
    }

    /// [`LightBvh::pmf`] of every light by the reference's binary walk (0 for lights it does
    /// not hold).
    fn pmf_binary(nodes: &[BinaryNode], p_inf: f32, p: Vec3, n: Vec3, count: usize) -> Vec<f32> {
        let mut out = vec![0.0; count];
        let mut stack = vec![(0usize, 1.0 - p_inf)];
        while let Some((index, pmf)) = stack.pop() {
            if nodes[index].leaf {
                out[nodes[index].child_or_light as usize] = pmf;
                continue;
            }
            let (c0, c1) = (index + 1, nodes[index].child_or_light as usize);
            let (i0, i1) = (nodes[c0].bounds.importance(p, n), nodes[c1].bounds.importance(p, n));
            if i0 == 0.0 && i1 == 0.0 {
                continue;
            }
            let p0 = i0 / (i0 + i1);
            stack.extend([(c0, pmf * p0), (c1, pmf * (1.0 - p0))]);
        }
        out
    }

    /// The wide walk is the binary walk: the same light and probability for every `u`, and the
    /// same pmf for every light, bit for bit, at points near and far, with and without a normal,
    /// for trees of two to fifty lights (odd and even levels end in lights).
    #[test]
    fn wide_walk_is_the_binary_walk() {
        let (all, shapes) = many_lights(4);
        let mut rng = Pcg32::new(11, 5);
        let mut chosen = 0;
        for count in [2, 3, 4, 5, 7, 12, all.len()] {
            let lights = &all[all.len() - count..];
            let bvh = LightBvh::new(lights, &shapes);
            let (nodes, p_inf) = binary_reference(lights, &shapes);
            let mut contexts = contexts();
            contexts.extend((0..20).map(|_| {
                let p = Vec3::new(12.0 * rng.next_f32() - 6.0, 6.0 * rng.next_f32() - 1.0, 12.0 * rng.next_f32() - 6.0);
                (p, if rng.next_f32() < 0.2 { Vec3::ZERO } else { sample_uniform_sphere(u2(&mut rng)).value })
            }));
            for (p, n) in contexts {
                let pmf = pmf_binary(&nodes, p_inf, p, n, lights.len());
                for (i, &expected) in pmf.iter().enumerate() {
                    if !bvh.is_infinite[i] {
                        assert_eq!(bvh.pmf(p, n, i as u32).to_bits(), expected.to_bits(), "{count} lights: light {i}");
                    }
                }
                for k in 0..200 {
                    let u = p_inf + (1.0 - p_inf) * (k as f32 + rng.next_f32()) / 200.0;
                    let got = bvh.sample(p, n, u.min(1.0 - f32::EPSILON / 2.0));
                    let expected = sample_binary(&nodes, p_inf, p, n, u.min(1.0 - f32::EPSILON / 2.0));
                    assert_eq!(
                        got.map(|(i, q)| (i, q.to_bits())),
                        expected.map(|(i, q)| (i, q.to_bits())),
                        "{count} lights"
                    );
                    chosen += usize::from(got.is_some());
                }
            }
        }
        assert!(chosen > 20_000, "{chosen} lights chosen");
    }

    fn contexts() -> Vec<(Vec3, Vec3)> {
        let mut rng = Pcg32::new(3, 3);
        let mut out = vec![(Vec3::new(0.3, -0.2, 0.1), Vec3::Y), (Vec3::new(2.0, 1.0, 0.5), Vec3::ZERO)];
        for _ in 0..4 {
            let p = Vec3::new(8.0 * rng.next_f32() - 4.0, 3.0 * rng.next_f32(), 8.0 * rng.next_f32() - 4.0);
            out.push((p, sample_uniform_sphere(u2(&mut rng)).value));
        }
        out
    }

    /// The lights chosen at a shading point follow `pmf` (χ²), the pmf sums to at most one over
    /// the lights, and `sample` reports exactly the probability that `pmf` computes (MIS needs both
    /// to agree to the last bit).
    #[test]
    fn selection_follows_the_pmf() {
        let (lights, shapes) = many_lights(1);
        let bvh = LightBvh::new(&lights, &shapes);
        for (k, &(p, n)) in contexts().iter().enumerate() {
            // Below 1 where a node's bound is positive but both children's are zero: then no
            // light is chosen (pbrt-v4 likewise), which the χ² test's extra cell checks.
            let total: f64 = (0..lights.len() as u32).map(|i| bvh.pmf(p, n, i) as f64).sum();
            assert!(total <= 1.0 + 1e-5 && total > 0.5, "context {k}: Σ pmf = {total}");
            let out = chi2_discrete(
                lights.len(),
                300_000,
                |rng| {
                    let (i, pmf) = bvh.sample(p, n, rng.next_f32())?;
                    assert_eq!(pmf.to_bits(), bvh.pmf(p, n, i).to_bits(), "light {i}: sample and pmf disagree");
                    Some(i as usize)
                },
                |i| bvh.pmf(p, n, i as u32) as f64,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "context {k}: {out}");
        }
    }

    /// Eight importances at once are the scalar ones, bit for bit, in two SSE evaluations and
    /// in one AVX evaluation (where the CPU has it), at points far, near and inside the bounds,
    /// with and without a normal, including a point at a bound's centre (distance 0) and NaN
    /// points; unused lanes are zero.
    #[test]
    fn wide_importance_is_the_scalar_one() {
        let (lights, shapes) = many_lights(3);
        let bounds: Vec<LightBounds> = lights.iter().filter_map(|l| LightBounds::of(l, &shapes)).collect();
        let mut rng = Pcg32::new(5, 2);
        let mut positive = 0;
        let implementations = [None, Avx::detect()];
        for (c, chunk) in bounds.chunks(7).enumerate() {
            let wide = WideBounds::new(&chunk.iter().map(|b| Some(NodeBounds::new(b))).collect::<Vec<_>>());
            for t in 0..2000 {
                let scale = [0.1, 1.0, 10.0][rng.next_u32() as usize % 3];
                let mut p = chunk[0].bounds.centroid() + scale * sample_uniform_sphere(u2(&mut rng)).value;
                if t == 0 {
                    p = NodeBounds::new(&chunk[c % chunk.len()]).center;
                } else if t == 1 {
                    p = Vec3::new(f32::NAN, 0.0, 1.0);
                }
                let n = if rng.next_f32() < 0.2 { Vec3::ZERO } else { sample_uniform_sphere(u2(&mut rng)).value };
                for avx in implementations {
                    let got = wide.importance(p, n, avx);
                    for (k, b) in chunk.iter().enumerate() {
                        let expected = b.importance(p, n).to_bits();
                        assert_eq!(got[k].to_bits(), expected, "lane {k} at {p}, n {n}, AVX {}", avx.is_some());
                        positive += usize::from(got[k] > 0.0);
                    }
                    assert!(got[chunk.len()..].iter().all(|&i| i == 0.0));
                }
            }
        }
        assert!(positive > 10_000, "{positive} positive importances");
    }

    /// The build keeps every leaf within the depth bound (a trail has one bit per level), where
    /// the SAH alone would go deeper: 45 lights under bounds from ⌈log₂ 45⌉ = 6 up; the tree
    /// still holds each light once.
    #[test]
    fn builds_keep_leaves_within_the_depth_bound() {
        let (lights, shapes) = many_lights(6);
        let items: Vec<(u32, LightBounds)> = (0..lights.len() as u32)
            .filter_map(|i| Some((i, LightBounds::of(&lights[i as usize], &shapes)?)))
            .collect();
        let n = items.len();
        let depths = |max_depth: u32| {
            let mut nodes = Vec::new();
            build(&mut nodes, &mut items.clone(), 0, n, 0, max_depth);
            let mut depth = vec![0u32; nodes.len()];
            let mut leaves = Vec::new();
            for i in 0..nodes.len() {
                if nodes[i].leaf {
                    leaves.push((nodes[i].child_or_light, depth[i]));
                } else {
                    depth[i + 1] = depth[i] + 1;
                    depth[nodes[i].child_or_light as usize] = depth[i] + 1;
                }
            }
            leaves.sort();
            leaves
        };
        let unbounded = depths(MAX_DEPTH);
        let deepest = unbounded.iter().map(|l| l.1).max().unwrap();
        assert!(deepest > 7, "the SAH tree is {deepest} deep: no test of the bound");
        for max_depth in 6..deepest {
            let leaves = depths(max_depth);
            assert!(leaves.iter().all(|l| l.1 <= max_depth), "bound {max_depth}: {leaves:?}");
            assert_eq!(
                leaves.iter().map(|l| l.0).collect::<Vec<_>>(),
                unbounded.iter().map(|l| l.0).collect::<Vec<_>>()
            );
        }
    }

    /// With two lights the tree is one split, and the pmf is the ratio of importances, computed
    /// here from the definition: for point lights `φ |cos θ_i| / d²`; the environment gets half.
    #[test]
    fn two_point_lights_by_exact_importance() {
        let a = Vec3::new(1.0, 2.0, 0.0);
        let b = Vec3::new(-2.0, 1.0, 3.0);
        let lights = vec![
            Light::Point { position: a, intensity: Rgb::splat(2.0) },
            Light::Point { position: b, intensity: Rgb::new(1.0, 5.0, 0.5) },
            Light::Constant { radiance: Rgb::ONE, center: Vec3::ZERO, radius: 5.0 },
        ];
        let bvh = LightBvh::new(&lights, &[]);
        let p = Vec3::new(0.2, 0.0, 0.4);
        let n = Vec3::new(0.3, 1.0, -0.2).normalize();
        let imp = |c: Vec3, l: &Light| {
            let d = c - p;
            l.power(&[]) as f64 * (d.normalize().dot(n).abs() as f64) / d.length_squared() as f64
        };
        let (ia, ib) = (imp(a, &lights[0]), imp(b, &lights[1]));
        assert!((bvh.pmf(p, n, 0) as f64 - 0.5 * ia / (ia + ib)).abs() < 1e-5);
        assert!((bvh.pmf(p, n, 1) as f64 - 0.5 * ib / (ia + ib)).abs() < 1e-5);
        assert_eq!(bvh.pmf(p, n, 2), 0.5);
        // In a medium (no normal) the cosine drops out.
        let imp0 = |c: Vec3, l: &Light| l.power(&[]) as f64 / (c - p).length_squared() as f64;
        let (ia, ib) = (imp0(a, &lights[0]), imp0(b, &lights[1]));
        assert!((bvh.pmf(p, Vec3::ZERO, 0) as f64 - 0.5 * ia / (ia + ib)).abs() < 1e-5);
    }

    /// The importance bound is conservative: wherever a light can send light to a point (a light
    /// sample from there arrives from the light's front, off the point's tangent plane), the
    /// light's pmf is positive, so the estimator stays unbiased. A one-sided quad seen from
    /// behind gets nothing.
    #[test]
    fn every_light_that_can_contribute_can_be_chosen() {
        let (lights, shapes) = many_lights(2);
        let bvh = LightBvh::new(&lights, &shapes);
        let mut rng = Pcg32::new(9, 1);
        let mut checked = 0;
        for _ in 0..300 {
            let p = Vec3::new(10.0 * rng.next_f32() - 5.0, 4.0 * rng.next_f32() - 0.5, 10.0 * rng.next_f32() - 5.0);
            let n = sample_uniform_sphere(u2(&mut rng)).value;
            for (i, light) in lights.iter().enumerate() {
                for _ in 0..8 {
                    let Some(ls) = light.sample_li(&shapes, p, u2(&mut rng)) else { continue };
                    if ls.li.max_element() > 0.0 && ls.wi.dot(n).abs() > 1e-3 {
                        checked += 1;
                        assert!(bvh.pmf(p, n, i as u32) > 0.0, "light {i} reaches {p} but has pmf 0");
                    }
                }
            }
        }
        assert!(checked > 10_000, "{checked} contributions checked");
        let mut quad = TriangleMesh::rectangle(); // faces +z
        quad.prepare_normals();
        let shapes = [Geometry::Mesh(quad)];
        let lights = [Light::Area { shape: 0, radiance: Rgb::ONE.into(), two_sided: false }];
        let bvh = LightBvh::new(&lights, &shapes);
        // Behind it, outside its bounding sphere (radius √2), nothing can arrive: the bound
        // says so. (A lone light is still chosen there: its pmf is one everywhere.)
        let bounds = LightBounds::of(&lights[0], &shapes).unwrap();
        assert_eq!(bounds.importance(Vec3::new(0.0, 0.0, -3.0), Vec3::Z), 0.0, "behind a one-sided light");
        assert!(bounds.importance(Vec3::new(0.0, 0.0, 3.0), Vec3::Z) > 0.0);
        assert_eq!(bvh.pmf(Vec3::new(0.3, 0.2, -3.0), Vec3::Z, 0), 1.0);
    }

    /// Lights without power are never chosen, and lights at infinity share their half evenly.
    #[test]
    fn zero_power_and_infinite_lights() {
        let lights = vec![
            Light::Point { position: Vec3::ZERO, intensity: Rgb::ZERO },
            Light::Point { position: Vec3::X, intensity: Rgb::ONE },
            Light::Constant { radiance: Rgb::ONE, center: Vec3::ZERO, radius: 5.0 },
            Light::Directional { direction: -Vec3::Y, irradiance: Rgb::ONE, center: Vec3::ZERO, radius: 5.0 },
        ];
        let bvh = LightBvh::new(&lights, &[]);
        let (p, n) = (Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
        assert_eq!(bvh.pmf(p, n, 0), 0.0);
        assert!((bvh.pmf(p, n, 1) - 1.0 / 3.0).abs() < 1e-6);
        assert!((bvh.pmf(p, n, 2) - 1.0 / 3.0).abs() < 1e-6 && (bvh.pmf(p, n, 3) - 1.0 / 3.0).abs() < 1e-6);
        for k in 0..1000 {
            let (i, _) = bvh.sample(p, n, k as f32 / 1000.0).unwrap();
            assert_ne!(i, 0);
        }
    }
}
