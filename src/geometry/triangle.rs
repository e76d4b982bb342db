//! Watertight ray–triangle intersection (Woop, Benthin & Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2013), with the conservative `t > 0` test and hit-point error bounds of
//! pbrt-v4 §6.5 / §6.8.
//!
//! The ray is transformed (translate to the origin, permute so its largest direction
//! component is z, shear so it points along +z); the hit test is then a 2D edge-function test
//! at the origin, which is exactly consistent between triangles sharing an edge: no ray passes
//! through the crack between two of them.

use crate::math::float::gamma;
use crate::math::{Ray, Vec3};
use glam::Vec4;
use std::ops::{Add, Mul};

/// Per-ray data of the watertight test, computed once per ray: the permutation `(kx, ky, kz)`
/// that makes the ray's largest direction component z, the shear that makes it point along
/// +z, and the permuted origin.
/// Scalar and SIMD tests evaluate the same expressions, so they agree bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct RayPrecomp {
    /// The permutation `(kx, ky, kz)` (kz: dominant direction axis).
    pub(crate) k: [usize; 3],
    /// Origin permuted: `(o[kx], o[ky], o[kz])`.
    pub(crate) op: [f32; 3],
    /// Shear `(Sx, Sy)` = `(d[kx] / d[kz], d[ky] / d[kz])` and scale `Sz = 1 / d[kz]`.
    pub(crate) s: [f32; 3],
}

impl RayPrecomp {
    /// Precomputes the permutation and shear for `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> RayPrecomp {
        let d = ray.d.to_array();
        let a = ray.d.abs();
        // kz: the dominant axis; (kx, ky) the other two in cyclic order, swapped when d[kz] < 0
        // to keep the winding of the projected triangle.
        // Branch-free (the directions of incoherent rays make these branches unpredictable):
        // x wins if it beats both, y if it beats z and x does not beat y, else z.
        let x_beats_y = a.x > a.y;
        let x_wins = x_beats_y && a.x > a.z;
        let y_wins = !x_beats_y && a.y > a.z;
        let kz = 2 - 2 * x_wins as usize - y_wins as usize;
        // (kx, ky, kz) for each kz, in cyclic order and swapped.
        const PERMUTATIONS: [[usize; 3]; 6] = [[1, 2, 0], [2, 1, 0], [2, 0, 1], [0, 2, 1], [0, 1, 2], [1, 0, 2]];
        let [kx, ky, kz] = PERMUTATIONS[2 * kz + usize::from(d[kz] < 0.0)];
        let sz = 1.0 / d[kz];
        let o = ray.o.to_array();
        let op = [o[kx], o[ky], o[kz]];
        let s = [d[kx] * sz, d[ky] * sz, sz];
        RayPrecomp { k: [kx, ky, kz], op, s }
    }

    /// Vertex `v` in the ray's frame: relative to the origin, permuted, sheared (x, y) and
    /// scaled (z).
    #[inline(always)]
    fn transform(&self, v: Vec3) -> (f32, f32, f32) {
        let v = v.to_array();
        let [kx, ky, kz] = self.k;
        let (x, y, z) = (v[kx] - self.op[0], v[ky] - self.op[1], v[kz] - self.op[2]);
        (x - self.s[0] * z, y - self.s[1] * z, self.s[2] * z)
    }
}

/// A triangle hit: ray parameter `t` and barycentrics `(b0, b1, b2)` of vertices `p0, p1, p2`,
/// the four lanes of one SIMD register. It is written and copied whole, so that a read of some
/// of its parts right after the traversal wrote it is forwarded from that one store (as four
/// fields, the compiler wrote and read them in different groupings, and a read spanning two
/// writes waits for them to reach the cache).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit(Vec4);

impl TriangleHit {
    /// The hit at ray parameter `t` with barycentrics `(b0, b1, b2)`.
    #[inline(always)]
    pub fn new(t: f32, b0: f32, b1: f32, b2: f32) -> TriangleHit {
        TriangleHit(Vec4::new(t, b0, b1, b2))
    }

    /// The hit `(t, b0, b1, b2)` as one vector (as the SIMD tests gather it from their lanes).
    #[inline(always)]
    pub fn from_vec4(v: Vec4) -> TriangleHit {
        TriangleHit(v)
    }

    /// Ray parameter.
    #[inline(always)]
    pub fn t(self) -> f32 {
        self.0.x
    }

    /// Barycentric weights `(b0, b1, b2)` of `p0, p1, p2`.
    #[inline(always)]
    pub fn barycentrics(self) -> [f32; 3] {
        [self.0.y, self.0.z, self.0.w]
    }
}

/// Intersects the precomputed ray with the triangle `p` within `(0, t_max)`.
#[inline(always)]
pub fn intersect_triangle(r: &RayPrecomp, p: &[Vec3; 3], t_max: f32) -> Option<TriangleHit> {
    let (p0x, p0y, z0) = r.transform(p[0]);
    let (p1x, p1y, z1) = r.transform(p[1]);
    let (p2x, p2y, z2) = r.transform(p[2]);
    // Edge functions.
    let mut e0 = p1x * p2y - p1y * p2x;
    let mut e1 = p2x * p0y - p2y * p0x;
    let mut e2 = p0x * p1y - p0y * p1x;
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        // Exactly on an edge in single precision: decide in double precision.
        e0 = (p1x as f64 * p2y as f64 - p1y as f64 * p2x as f64) as f32;
        e1 = (p2x as f64 * p0y as f64 - p2y as f64 * p0x as f64) as f32;
        e2 = (p0x as f64 * p1y as f64 - p0y as f64 * p1x as f64) as f32;
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    // Zero (degenerate or edge-on), or NaN (a non-finite vertex): no hit, as the SIMD tests.
    if det == 0.0 || det.is_nan() {
        return None;
    }
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // Conservative check that t is really positive (pbrt-v4 §6.8.7), and finite (an infinite
    // vertex can make it NaN or infinite: no hit, as the SIMD tests).
    let bound = t_error_bound([p0x, p1x, p2x], [p0y, p1y, p2y], [z0, z1, z2], [e0, e1, e2], inv_det);
    if !(t > bound && t < f32::INFINITY) {
        return None;
    }
    Some(TriangleHit::new(t, e0 * inv_det, e1 * inv_det, e2 * inv_det))
}

/// Arithmetic shared by one `f32` and four SIMD lanes (`Vec4`), so that the scalar and the
/// 4-wide triangle tests evaluate their error bound with one piece of code.
pub(crate) trait Lane: Copy + Add<Output = Self> + Mul<Output = Self> {
    fn abs(self) -> Self;
    fn max(self, other: Self) -> Self;
}

impl Lane for f32 {
    #[inline(always)]
    fn abs(self) -> f32 {
        f32::abs(self)
    }
    #[inline(always)]
    fn max(self, other: f32) -> f32 {
        f32::max(self, other)
    }
}

impl Lane for Vec4 {
    #[inline(always)]
    fn abs(self) -> Vec4 {
        Vec4::abs(self)
    }
    #[inline(always)]
    fn max(self, other: Vec4) -> Vec4 {
        Vec4::max(self, other)
    }
}

/// Bound `δt` on the error of the hit's `t` (pbrt-v4 §6.8.7): a hit is certain to lie in front
/// of the origin only when `t > δt`. Takes the transformed vertices' x, y and z, the edge
/// functions and `1 / det`.
#[inline(always)]
pub(crate) fn t_error_bound<T: Lane>(x: [T; 3], y: [T; 3], z: [T; 3], e: [T; 3], inv_det: T) -> T
where
    f32: Mul<T, Output = T>,
{
    t_error_scaled(x, y, z, e) * inv_det.abs()
}

/// `δt · |det|` ([`t_error_bound`] without its factor `1 / |det|`): since `t = t_scaled / det`
/// with `t_scaled` of the sign of `det`, `t > δt` is `|t_scaled| > δt · |det|`, a test that
/// needs no division (shadow rays use it).
#[inline(always)]
pub(crate) fn t_error_scaled<T: Lane>(x: [T; 3], y: [T; 3], z: [T; 3], e: [T; 3]) -> T
where
    f32: Mul<T, Output = T>,
{
    let (max_xt, max_yt, max_zt, max_e) = (max_abs3(x), max_abs3(y), max_abs3(z), max_abs3(e));
    let delta_z = gamma(3) * max_zt;
    let delta_x = gamma(5) * (max_xt + max_zt);
    let delta_y = gamma(5) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e)
}

/// The largest magnitude of three lanes, lane by lane (a function, not a closure, so that
/// it inlines into the SIMD traversals compiled for other target features).
#[inline(always)]
fn max_abs3<T: Lane>(v: [T; 3]) -> T {
    v[0].abs().max(v[1].abs()).max(v[2].abs())
}

/// Absolute error bound of the hit point `b0 p0 + b1 p1 + b2 p2` (pbrt-v4 §6.8.5).
#[inline]
pub fn triangle_point_error(p: &[Vec3; 3], h: &TriangleHit) -> Vec3 {
    let [b0, b1, b2] = h.barycentrics();
    gamma(7) * ((b0 * p[0]).abs() + (b1 * p[1]).abs() + (b2 * p[2]).abs())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    #[test]
    fn hits_inside_and_misses_outside() {
        let tri = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)];
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        let h = intersect_triangle(&RayPrecomp::new(&ray), &tri, f32::INFINITY).unwrap();
        assert!((h.t() - 2.0).abs() < 1e-6);
        let [b0, b1, b2] = h.barycentrics();
        let p = tri[0] * b0 + tri[1] * b1 + tri[2] * b2;
        assert!(p.truncate().length() < 1e-6);
        assert!(intersect_triangle(&RayPrecomp::new(&ray), &tri, 1.5).is_none(), "t_max respected");
        let back = Ray::new(Vec3::ZERO, -Vec3::Z);
        assert!(intersect_triangle(&RayPrecomp::new(&back), &tri, f32::INFINITY).is_none());
        let off = Ray::new(Vec3::new(2.0, 0.0, 0.0), Vec3::Z);
        assert!(intersect_triangle(&RayPrecomp::new(&off), &tri, f32::INFINITY).is_none());
        // Both windings hit.
        let flipped = [tri[0], tri[2], tri[1]];
        assert!(intersect_triangle(&RayPrecomp::new(&ray), &flipped, f32::INFINITY).is_some());
    }

    /// A vertex with a NaN or infinite coordinate gives no hit (never a hit at a NaN distance),
    /// for a ray through the triangle's finite part and one through its middle.
    #[test]
    fn non_finite_vertices_give_no_hit() {
        let finite = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)];
        let rays =
            [Ray::new(Vec3::ZERO, Vec3::Z), Ray::new(Vec3::new(0.1, -0.5, 0.0), Vec3::new(0.0, 0.1, 1.0).normalize())];
        for ray in rays {
            let pre = RayPrecomp::new(&ray);
            assert!(intersect_triangle(&pre, &finite, f32::INFINITY).is_some());
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                for vertex in 0..3 {
                    for axis in 0..3 {
                        let mut tri = finite;
                        tri[vertex][axis] = bad;
                        let hit = intersect_triangle(&pre, &tri, f32::INFINITY);
                        assert!(hit.is_none_or(|h| h.t().is_finite() && h.t() > 0.0), "{tri:?}: {hit:?}");
                        // The SIMD block tests (four lanes, and eight where the CPU has AVX) agree.
                        let block = crate::geometry::triangle8::Triangle8::new(&[(tri, 0)]);
                        for avx in [None, crate::math::simd::Avx::detect()] {
                            let simd = block.intersect_with(avx, &pre, f32::INFINITY).map(|(_, h)| h);
                            assert_eq!(simd, hit, "{tri:?}, AVX {}", avx.is_some());
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn shared_edges_are_watertight() {
        // A fan of triangles around a vertex (a polygon): every ray through its interior must
        // hit exactly... at least one triangle, never zero, including rays aimed at the shared
        // edges and the centre vertex.
        let n = 7;
        let c = Vec3::new(0.1, -0.2, 0.0);
        let ring: Vec<Vec3> = (0..n)
            .map(|i| {
                let a = i as f32 / n as f32 * std::f32::consts::TAU;
                c + Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let tris: Vec<[Vec3; 3]> = (0..n).map(|i| [c, ring[i], ring[(i + 1) % n]]).collect();
        let mut rng = Pcg32::new(1, 2);
        let mut targets = vec![c];
        for v in &ring {
            for k in 1..20 {
                targets.push(c + (*v - c) * (k as f32 / 20.0)); // on the shared edge
            }
        }
        for _ in 0..20_000 {
            let r = rng.next_f32() * 0.9;
            let a = rng.next_f32() * std::f32::consts::TAU;
            targets.push(c + Vec3::new(r * a.cos(), r * a.sin(), 0.0));
        }
        for target in targets {
            let o = Vec3::new(rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 4.0 - 2.0, 3.0 + rng.next_f32());
            let ray = Ray::new(o, target - o);
            let pre = RayPrecomp::new(&ray);
            let hits = tris.iter().filter(|t| intersect_triangle(&pre, t, f32::INFINITY).is_some()).count();
            assert!(hits >= 1, "ray toward {target} leaked through the mesh");
        }
    }

    #[test]
    fn error_bound_covers_true_point() {
        let mut rng = Pcg32::new(5, 5);
        for _ in 0..10_000 {
            let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 200.0 - 100.0;
            let tri = [v(), v(), v()];
            let o = v();
            let target = (tri[0] + tri[1] + tri[2]) / 3.0;
            let ray = Ray::new(o, target - o);
            if let Some(h) = intersect_triangle(&RayPrecomp::new(&ray), &tri, f32::INFINITY) {
                let [b0, b1, b2] = h.barycentrics();
                let p = tri[0] * b0 + tri[1] * b1 + tri[2] * b2;
                let err = triangle_point_error(&tri, &h);
                // Distance of p from the triangle's plane (in f64) is within the error box.
                let n = (tri[1] - tri[0]).as_dvec3().cross((tri[2] - tri[0]).as_dvec3()).normalize();
                let dist = (p.as_dvec3() - tri[0].as_dvec3()).dot(n).abs();
                assert!(dist <= err.as_dvec3().dot(n.abs()) + 1e-9, "{dist} vs {err}");
            }
        }
    }
}
