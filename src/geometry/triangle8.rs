//! Eight triangles intersected at once: the watertight test of [`super::triangle`] evaluated in
//! SIMD lanes, one triangle per lane (the layout of Embree's `Triangle4`, twice as wide). Where
//! the CPU has AVX the BVH's AVX traversal tests all eight in one register
//! ([`Triangle8::intersect_avx`]); elsewhere two SSE halves of four do ([`Triangle8::intersect`]).
//! Both evaluate the same operations in the same order and give the same bits.
//!
//! Each lane runs exactly the arithmetic of the scalar test (translate, permute and shear into
//! the ray's frame, 2D edge functions, the conservative `t > 0` check of pbrt-v4 §6.8.7), so
//! shared edges stay watertight. The rare block with an edge function exactly zero in single
//! precision is decided by the scalar test (which re-evaluates it in double precision).

use super::triangle::{intersect_triangle, t_error_bound, t_error_scaled, Lane, RayPrecomp, TriangleHit};
use crate::math::simd::Avx;
use crate::math::Vec3;
use glam::Vec4;
use std::ops::{BitAnd, BitOr, Mul, Sub};

/// Triangles per block.
pub const LANES: usize = 8;

/// A block's coordinates, `[vertex][axis][lane]`.
type Rows = [[[f32; LANES]; 3]; 3];

/// Up to eight triangles in structure-of-arrays form, `v[vertex][axis][lane]` holding that
/// coordinate of the lane's triangle, and a caller-chosen id per lane, distinct within the
/// block. Blocks with fewer than eight triangles repeat their last triangle (and id), so every
/// lane is a real triangle, and a repeated id marks the padding.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Triangle8 {
    v: Rows,
    /// Caller's id of each lane's triangle.
    pub id: [u32; LANES],
}

impl Triangle8 {
    /// Packs 1 to 8 triangles with their ids (distinct: the tests skip padding by its id).
    pub fn new(tris: &[([Vec3; 3], u32)]) -> Triangle8 {
        assert!((1..=LANES).contains(&tris.len()), "a Triangle8 holds 1 to 8 triangles");
        assert!(
            tris.iter().enumerate().all(|(i, a)| tris[..i].iter().all(|b| b.1 != a.1)),
            "the triangles of a Triangle8 need distinct ids"
        );
        let lane = |k: usize| tris[k.min(tris.len() - 1)];
        Triangle8 {
            v: std::array::from_fn(|vertex| {
                std::array::from_fn(|axis| std::array::from_fn(|k| lane(k).0[vertex][axis]))
            }),
            id: std::array::from_fn(|k| lane(k).1),
        }
    }

    /// The vertices of lane `k`'s triangle.
    #[inline]
    pub fn triangle(&self, k: usize) -> [Vec3; 3] {
        std::array::from_fn(|vertex| {
            let v = &self.v[vertex];
            Vec3::new(v[0][k], v[1][k], v[2][k])
        })
    }

    /// Whether lanes 4–7 repeat lane 3 (a block of at most four triangles): the SSE test then
    /// skips its second half, which could only find lane 3's hit again.
    #[inline(always)]
    fn upper_half_padding(&self) -> bool {
        self.id[4] == self.id[3]
    }

    /// [`Triangle8::intersect_avx`] where the caller holds the AVX token (the BVH's AVX
    /// traversal), else [`Triangle8::intersect`].
    #[inline(always)]
    pub fn intersect_with(&self, avx: Option<Avx>, r: &RayPrecomp, t_max: f32) -> Option<(usize, TriangleHit)> {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = avx {
            return self.intersect_avx(avx, r, t_max);
        }
        let _ = avx;
        self.intersect(r, t_max)
    }

    /// [`Triangle8::occludes_avx`] where the caller holds the AVX token, else
    /// [`Triangle8::occludes`].
    #[inline(always)]
    pub fn occludes_with(&self, avx: Option<Avx>, r: &RayPrecomp, t_max: f32) -> bool {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = avx {
            return self.occludes_avx(avx, r, t_max);
        }
        let _ = avx;
        self.occludes(r, t_max)
    }

    /// The closest hit among the eight triangles within `(0, t_max)`: lane and hit. Two SSE
    /// halves of four lanes.
    #[inline(always)]
    pub fn intersect(&self, r: &RayPrecomp, t_max: f32) -> Option<(usize, TriangleHit)> {
        let low = self.half_closest(0, r, t_max);
        if self.upper_half_padding() {
            return low;
        }
        match (low, self.half_closest(1, r, t_max)) {
            (Some(a), Some(b)) => Some(if b.1.t() < a.1.t() { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// The closest hit among lanes `4 · half ..= 4 · half + 3` (SSE).
    #[inline(always)]
    fn half_closest(&self, half: usize, r: &RayPrecomp, t_max: f32) -> Option<(usize, TriangleHit)> {
        match closest::<Vec4>((), &self.v, half, r, t_max) {
            Outcome::Scalar => self.scalar_closest(4 * half..4 * half + 4, r, t_max),
            Outcome::Miss => None,
            Outcome::Hit((lane, hit)) => Some((lane + 4 * half, hit)),
        }
    }

    /// [`Triangle8::intersect`] in one AVX register (the same answer, bit for bit).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn intersect_avx(&self, avx: Avx, r: &RayPrecomp, t_max: f32) -> Option<(usize, TriangleHit)> {
        if self.upper_half_padding() {
            // Four triangles or fewer: one SSE half is cheaper (its reduction is shorter).
            return self.half_closest(0, r, t_max);
        }
        match closest::<crate::math::simd::F32x8>(avx, &self.v, 0, r, t_max) {
            Outcome::Scalar => self.scalar_closest(0..LANES, r, t_max),
            Outcome::Miss => None,
            Outcome::Hit(hit) => Some(hit),
        }
    }

    /// Whether any of the eight triangles is hit within `(0, t_max)`: the same test without a
    /// division (the `t > δt` check as `|t_scaled| > δt · |det|`, see `t_error_scaled` in
    /// `geometry::triangle`). Two SSE halves.
    #[inline(always)]
    pub fn occludes(&self, r: &RayPrecomp, t_max: f32) -> bool {
        self.half_occludes(0, r, t_max) || (!self.upper_half_padding() && self.half_occludes(1, r, t_max))
    }

    /// Whether one of lanes `4 · half ..= 4 · half + 3` is hit (SSE).
    #[inline(always)]
    fn half_occludes(&self, half: usize, r: &RayPrecomp, t_max: f32) -> bool {
        match occluded::<Vec4>((), &self.v, half, r, t_max) {
            Outcome::Scalar => self.scalar_closest(4 * half..4 * half + 4, r, t_max).is_some(),
            Outcome::Miss => false,
            Outcome::Hit(()) => true,
        }
    }

    /// [`Triangle8::occludes`] in one AVX register.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn occludes_avx(&self, avx: Avx, r: &RayPrecomp, t_max: f32) -> bool {
        if self.upper_half_padding() {
            return self.half_occludes(0, r, t_max);
        }
        match occluded::<crate::math::simd::F32x8>(avx, &self.v, 0, r, t_max) {
            Outcome::Scalar => self.scalar_closest(0..LANES, r, t_max).is_some(),
            Outcome::Miss => false,
            Outcome::Hit(()) => true,
        }
    }

    /// The closest hit among `lanes` by the scalar test (an edge function was exactly zero);
    /// the lowest lane among equal distances, as the SIMD reduction picks.
    #[cold]
    fn scalar_closest(
        &self,
        lanes: std::ops::Range<usize>,
        r: &RayPrecomp,
        t_max: f32,
    ) -> Option<(usize, TriangleHit)> {
        let mut best: Option<(usize, TriangleHit)> = None;
        for k in lanes {
            if let Some(h) = intersect_triangle(r, &self.triangle(k), t_max) {
                if best.is_none_or(|(_, b)| h.t() < b.t()) {
                    best = Some((k, h));
                }
            }
        }
        best
    }
}

/// The lane operations of the test, for SSE's four lanes ([`Vec4`]) and AVX's eight
/// ([`crate::math::simd::F32x8`]); `Isa` is what it takes to make lanes (nothing, or the
/// [`Avx`] token).
pub(crate) trait Lanes: Lane + Sub<Output = Self> {
    /// A lane mask.
    type Mask: Copy + BitAnd<Output = Self::Mask> + BitOr<Output = Self::Mask>;
    /// The proof that the instructions exist.
    type Isa: Copy;
    /// Lanes.
    const N: usize;
    fn splat(isa: Self::Isa, x: f32) -> Self;
    /// Lanes `N · part ..` of `row`.
    fn load(isa: Self::Isa, row: &[f32; LANES], part: usize) -> Self;
    fn cmpeq(self, o: Self) -> Self::Mask;
    fn cmpge(self, o: Self) -> Self::Mask;
    fn cmple(self, o: Self) -> Self::Mask;
    fn cmpgt(self, o: Self) -> Self::Mask;
    fn cmplt(self, o: Self) -> Self::Mask;
    fn cmpne(self, o: Self) -> Self::Mask;
    fn min(self, o: Self) -> Self;
    fn any(m: Self::Mask) -> bool;
    fn bitmask(m: Self::Mask) -> u32;
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    fn recip(self) -> Self;
    fn min_element(self) -> f32;
    /// Lane `k` of each of `v`, gathered into one vector.
    fn gather(v: [Self; 4], k: usize) -> Vec4;
}

/// The comparisons of [`Lanes`], forwarded to the lane type's own.
macro_rules! forward_compare {
    ($ty:ty, $mask:ty, $($name:ident),*) => {$(
        #[inline(always)]
        fn $name(self, o: $ty) -> $mask {
            <$ty>::$name(self, o)
        }
    )*};
}

/// [`Lanes`] for a lane type whose methods have the trait's names, with the few that differ
/// given as closures or functions.
macro_rules! forward_lanes {
    ($ty:ty, $mask:ty, $isa:ty, $n:expr, $splat:expr, $load:expr, $gather:expr) => {
        impl Lanes for $ty {
            type Mask = $mask;
            type Isa = $isa;
            const N: usize = $n;
            #[inline(always)]
            fn splat(isa: $isa, x: f32) -> $ty {
                $splat(isa, x)
            }
            #[inline(always)]
            fn load(isa: $isa, row: &[f32; LANES], part: usize) -> $ty {
                $load(isa, row, part)
            }
            forward_compare!($ty, $mask, cmpeq, cmpge, cmple, cmpgt, cmplt, cmpne);
            #[inline(always)]
            fn min(self, o: $ty) -> $ty {
                <$ty>::min(self, o)
            }
            #[inline(always)]
            fn any(m: $mask) -> bool {
                m.any()
            }
            #[inline(always)]
            fn bitmask(m: $mask) -> u32 {
                m.bitmask()
            }
            #[inline(always)]
            fn select(m: $mask, a: $ty, b: $ty) -> $ty {
                <$ty>::select(m, a, b)
            }
            #[inline(always)]
            fn recip(self) -> $ty {
                <$ty>::recip(self)
            }
            #[inline(always)]
            fn min_element(self) -> f32 {
                <$ty>::min_element(self)
            }
            #[inline(always)]
            fn gather(v: [$ty; 4], k: usize) -> Vec4 {
                $gather(v, k)
            }
        }
    };
}

forward_lanes!(
    Vec4,
    glam::BVec4A,
    (),
    4,
    |_, x| Vec4::splat(x),
    |_, row: &[f32; LANES], part: usize| Vec4::from_slice(&row[4 * part..4 * part + 4]),
    crate::math::simd::gather_lane4
);

#[cfg(target_arch = "x86_64")]
forward_lanes!(
    crate::math::simd::F32x8,
    crate::math::simd::M8,
    Avx,
    8,
    crate::math::simd::F32x8::splat,
    |avx, row: &[f32; LANES], _| crate::math::simd::F32x8::load(avx, row),
    crate::math::simd::F32x8::gather_lane
);

#[cfg(target_arch = "x86_64")]
impl Lane for crate::math::simd::F32x8 {
    #[inline(always)]
    fn abs(self) -> Self {
        crate::math::simd::F32x8::abs(self)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        crate::math::simd::F32x8::max(self, other)
    }
}

/// What the lanes found: no hit, a hit (the caller's `finish` answer), or an edge function
/// exactly zero somewhere (the scalar test decides the block).
enum Outcome<R> {
    Miss,
    Hit(R),
    Scalar,
}

/// The per-lane test before its last check: lanes inside their triangle with `t` in range,
/// their determinant, scaled `t`, edge functions and transformed vertices (for the error bound).
struct Candidates<L: Lanes> {
    valid: L::Mask,
    det: L,
    t_scaled: L,
    e: [L; 3],
    x: [L; 3],
    y: [L; 3],
    z: [L; 3],
}

/// Vertex `vertex` of the lanes in the ray's frame: relative to the origin `o`, permuted by
/// `k`, sheared (x, y) and scaled (z) by `s`.
#[inline(always)]
fn to_ray_frame<L: Lanes>(
    isa: L::Isa,
    v: &Rows,
    part: usize,
    vertex: usize,
    k: [usize; 3],
    o: [L; 3],
    s: [L; 3],
) -> (L, L, L) {
    let v = &v[vertex];
    let (x, y, z) =
        (L::load(isa, &v[k[0]], part) - o[0], L::load(isa, &v[k[1]], part) - o[1], L::load(isa, &v[k[2]], part) - o[2]);
    (x - s[0] * z, y - s[1] * z, s[2] * z)
}

/// The per-lane test up to the `t > δt` check, which `finish` does on the candidate lanes;
/// `v[vertex][axis]` holds the coordinates, `part` says which `L::N` lanes of them.
#[inline(always)]
fn edges<L: Lanes, R>(
    isa: L::Isa,
    v: &Rows,
    part: usize,
    r: &RayPrecomp,
    t_max: f32,
    finish: impl Finish<L, R>,
) -> Outcome<R> {
    let o = [L::splat(isa, r.op[0]), L::splat(isa, r.op[1]), L::splat(isa, r.op[2])];
    let s = [L::splat(isa, r.s[0]), L::splat(isa, r.s[1]), L::splat(isa, r.s[2])];
    let (p0x, p0y, z0) = to_ray_frame(isa, v, part, 0, r.k, o, s);
    let (p1x, p1y, z1) = to_ray_frame(isa, v, part, 1, r.k, o, s);
    let (p2x, p2y, z2) = to_ray_frame(isa, v, part, 2, r.k, o, s);
    let e0 = p1x * p2y - p1y * p2x;
    let e1 = p2x * p0y - p2y * p0x;
    let e2 = p0x * p1y - p0y * p1x;
    let zero = L::splat(isa, 0.0);
    if L::any(e0.cmpeq(zero) | e1.cmpeq(zero) | e2.cmpeq(zero)) {
        return Outcome::Scalar;
    }
    // No edge function is zero here, so the scalar test's "all ≥ 0 or all ≤ 0" is "the
    // smallest > 0 or the largest < 0".
    let inside = e0.min(e1).min(e2).cmpgt(zero) | Lane::max(Lane::max(e0, e1), e2).cmplt(zero);
    let det = e0 + e1 + e2;
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    // The scalar test's `0 < t_scaled ≤ t_max · det` for det > 0 and `t_max · det ≤ t_scaled <
    // 0` for det < 0, in one: `t_scaled` between 0 and `t_max · det` and not 0. (An inside lane
    // has det ≠ 0: three nonzero edge functions of one sign; a negative `t_max`, which would
    // swap the bounds, is taken as 0.)
    let bound = L::splat(isa, t_max.max(0.0)) * det;
    let in_range = t_scaled.cmpge(bound.min(zero)) & t_scaled.cmple(Lane::max(bound, zero)) & t_scaled.cmpne(zero);
    let valid = inside & in_range;
    if !L::any(valid) {
        return Outcome::Miss;
    }
    let c =
        Candidates { valid, det, t_scaled, e: [e0, e1, e2], x: [p0x, p1x, p2x], y: [p0y, p1y, p2y], z: [z0, z1, z2] };
    match finish.finish(isa, c) {
        Some(found) => Outcome::Hit(found),
        None => Outcome::Miss,
    }
}

/// The last step of [`edges`] on its candidate lanes: the closest hit, or whether any is hit.
/// A trait with an always-inlined method rather than a closure: a closure is a function of
/// its own, compiled without the caller's target features and inlined only at the optimizer's
/// discretion; a traversal compiled for x86-64-v3 (tried) called it, and every AVX intrinsic
/// in it, where the one compiled for AVX happened to inline it.
trait Finish<L: Lanes, R> {
    fn finish(self, isa: L::Isa, c: Candidates<L>) -> Option<R>;
}

/// [`Finish`] of the closest-hit test: lane and hit (the lowest lane among equal distances).
struct ClosestLane;

impl<L: Lanes> Finish<L, (usize, TriangleHit)> for ClosestLane
where
    f32: Mul<L, Output = L>,
{
    #[inline(always)]
    fn finish(self, isa: L::Isa, c: Candidates<L>) -> Option<(usize, TriangleHit)> {
        let inv_det = c.det.recip();
        let t = c.t_scaled * inv_det;
        // Conservative check that t is really positive (pbrt-v4 §6.8.7), per lane.
        let delta_t = t_error_bound(c.x, c.y, c.z, c.e, inv_det);
        let valid = c.valid & t.cmpgt(delta_t);
        if !L::any(valid) {
            return None;
        }
        let t = L::select(valid, t, L::splat(isa, f32::INFINITY));
        let t_min = t.min_element();
        let lane = L::bitmask(t.cmpeq(L::splat(isa, t_min))).trailing_zeros() as usize;
        if lane >= L::N {
            // t_min is NaN (overflowing coordinates): no hit.
            return None;
        }
        // The barycentrics `e / det` of every lane (the scalar test's products), then the
        // closest lane's `(t, b0, b1, b2)` gathered in registers.
        let b = c.e.map(|e| e * inv_det);
        Some((lane, TriangleHit::from_vec4(L::gather([t, b[0], b[1], b[2]], lane))))
    }
}

/// [`Finish`] of the any-hit test: whether a candidate lane passes the `t > δt` check.
struct AnyLane;

impl<L: Lanes> Finish<L, ()> for AnyLane
where
    f32: Mul<L, Output = L>,
{
    #[inline(always)]
    fn finish(self, _: L::Isa, c: Candidates<L>) -> Option<()> {
        L::any(c.valid & c.t_scaled.abs().cmpgt(t_error_scaled(c.x, c.y, c.z, c.e))).then_some(())
    }
}

/// The closest hit among the lanes: lane and hit (the lowest lane among equal distances).
#[inline(always)]
fn closest<L: Lanes>(isa: L::Isa, v: &Rows, part: usize, r: &RayPrecomp, t_max: f32) -> Outcome<(usize, TriangleHit)>
where
    f32: Mul<L, Output = L>,
{
    edges(isa, v, part, r, t_max, ClosestLane)
}

/// Whether any lane is hit.
#[inline(always)]
fn occluded<L: Lanes>(isa: L::Isa, v: &Rows, part: usize, r: &RayPrecomp, t_max: f32) -> Outcome<()>
where
    f32: Mul<L, Output = L>,
{
    edges(isa, v, part, r, t_max, AnyLane)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Ray;
    use crate::sampling::Pcg32;

    /// Random blocks of 1 to 8 triangles and rays: every block answer (both widths) equals the
    /// best scalar answer, and the AVX answer equals the SSE one bit for bit.
    #[test]
    fn agrees_with_the_scalar_test() {
        let mut rng = Pcg32::new(3, 4);
        let mut v = |scale: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale - scale / 2.0;
        let (mut hits, mut blocks) = (0, 0);
        for round in 0..20_000 {
            let n = 1 + round % LANES;
            let c = v(2.0);
            let tris: Vec<([Vec3; 3], u32)> =
                (0..n).map(|i| ([c + v(1.0), c + v(1.0), c + v(1.0)], 10 * round as u32 + i as u32)).collect();
            let o = v(6.0);
            let ray = Ray::new(o, c + v(0.5) - o);
            let pre = RayPrecomp::new(&ray);
            let t_max = if round % 3 == 0 { 1.0 } else { f32::INFINITY };
            let block = Triangle8::new(&tris);
            let scalar = tris
                .iter()
                .filter_map(|(p, id)| intersect_triangle(&pre, p, t_max).map(|h| (h, *id)))
                .min_by(|a, b| a.0.t().total_cmp(&b.0.t()));
            let simd = block.intersect(&pre, t_max);
            assert_eq!(block.occludes(&pre, t_max), scalar.is_some());
            #[cfg(target_arch = "x86_64")]
            if let Some(avx) = Avx::detect() {
                assert_eq!(block.intersect_avx(avx, &pre, t_max), simd, "round {round}");
                assert_eq!(block.occludes_avx(avx, &pre, t_max), scalar.is_some());
            }
            match (scalar, simd.map(|(lane, h)| (h, block.id[lane]))) {
                (None, None) => {}
                (Some((a, ida)), Some((b, idb))) => {
                    assert_eq!(a.t(), b.t());
                    assert_eq!(ida, idb);
                    for (x, y) in a.barycentrics().into_iter().zip(b.barycentrics()) {
                        assert!((x - y).abs() <= 1e-6, "{a:?} vs {b:?}");
                    }
                    hits += 1;
                }
                (a, b) => panic!("scalar {a:?} vs block {b:?}"),
            }
            blocks += 1;
        }
        assert!(hits > blocks / 4, "{hits} of {blocks}: the test must exercise hits");
    }

    /// Hits closer to the origin than the error bound of `t` (pbrt-v4's conservative check)
    /// are refused by the scalar test, by the block's closest hit and by its division-free
    /// occlusion test alike (both widths); farther ones are found by all.
    #[test]
    fn hits_within_the_t_error_bound_are_refused() {
        // The plane z = x, crossed by rays going down z at x = y = 0: |z| of the vertices is 1
        // in the ray's frame, so δt is about 10⁻⁶.
        let tri = [Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, -1.0, 1.0), Vec3::new(0.0, 1.0, 0.0)];
        let far = [tri[0] + Vec3::X * 50.0, tri[1] + Vec3::X * 50.0, tri[2] + Vec3::X * 50.0];
        // The triangle alone, and in the upper half of a full block.
        for block in [Triangle8::new(&[(tri, 0)]), Triangle8::new(&[(far, 1), (far, 2), (far, 3), (far, 4), (tri, 5)])]
        {
            for (h, hit) in [(1e-8f32, false), (1e-7, false), (1e-4, true), (1.0, true)] {
                let pre = RayPrecomp::new(&Ray::new(Vec3::new(0.0, 0.0, h), -Vec3::Z));
                assert_eq!(intersect_triangle(&pre, &tri, f32::INFINITY).is_some(), hit, "scalar at {h}");
                assert_eq!(block.intersect(&pre, f32::INFINITY).is_some(), hit, "closest hit at {h}");
                assert_eq!(block.occludes(&pre, f32::INFINITY), hit, "occlusion at {h}");
                #[cfg(target_arch = "x86_64")]
                if let Some(avx) = Avx::detect() {
                    assert_eq!(block.intersect_avx(avx, &pre, f32::INFINITY).is_some(), hit);
                    assert_eq!(block.occludes_avx(avx, &pre, f32::INFINITY), hit);
                }
            }
        }
    }

    #[test]
    fn exact_edge_falls_back_and_is_watertight() {
        // Two triangles sharing the edge x = 0; a ray straight down that edge hits one of them.
        let a = [Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)];
        let b = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        let away = [Vec3::new(5.0, 5.0, 0.0), Vec3::new(6.0, 5.0, 0.0), Vec3::new(5.0, 6.0, 0.0)];
        // The pair in the lower half, and in the upper half behind four that the ray misses.
        let blocks = [
            Triangle8::new(&[(a, 7), (b, 8)]),
            Triangle8::new(&[(away, 1), (away, 2), (away, 3), (away, 4), (a, 7), (b, 8)]),
        ];
        for block in blocks {
            for y in [-0.5f32, 0.0, 0.25] {
                let ray = Ray::new(Vec3::new(0.0, y, 2.0), -Vec3::Z);
                let pre = RayPrecomp::new(&ray);
                let (lane, h) = block.intersect(&pre, f32::INFINITY).expect("edge ray leaked");
                assert!([7, 8].contains(&block.id[lane]));
                assert_eq!(h.t(), 2.0);
                assert!(block.occludes(&pre, f32::INFINITY));
                #[cfg(target_arch = "x86_64")]
                if let Some(avx) = Avx::detect() {
                    assert_eq!(block.intersect_avx(avx, &pre, f32::INFINITY), Some((lane, h)));
                    assert!(block.occludes_avx(avx, &pre, f32::INFINITY));
                }
            }
        }
        let block = Triangle8::new(&[(a, 7), (b, 8)]);
        assert_eq!(block.triangle(1), b);
        assert_eq!(block.triangle(7), b, "padding lanes repeat the last triangle");
        assert!(block.upper_half_padding());
    }
}
