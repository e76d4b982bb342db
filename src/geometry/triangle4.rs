//! Four triangles intersected at once: the watertight test of [`super::triangle`] evaluated in
//! the four lanes of a SIMD vector (the layout of Embree's `Triangle4`).
//!
//! Each lane runs exactly the arithmetic of the scalar test (translate, permute and shear into
//! the ray's frame, 2D edge functions, the conservative `t > 0` check of pbrt-v4 §6.8.7), so
//! shared edges stay watertight. The rare lane whose edge function is exactly zero in single
//! precision is decided by the scalar test (which re-evaluates it in double precision).

use super::triangle::{intersect_triangle, t_error_bound, t_error_scaled, RayPrecomp, TriangleHit};
use crate::math::Vec3;
use glam::{BVec4A, Vec4};

/// Up to four triangles in structure-of-arrays form, `v[vertex][axis]` holding that
/// coordinate of the four triangles, and a caller-chosen id per lane. Blocks with fewer than
/// four triangles repeat their last triangle (and id), so every lane is a real triangle.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Triangle4 {
    v: [[Vec4; 3]; 3],
    /// Caller's id of each lane's triangle.
    pub id: [u32; 4],
}

impl Triangle4 {
    /// Packs 1 to 4 triangles with their ids.
    pub fn new(tris: &[([Vec3; 3], u32)]) -> Triangle4 {
        assert!((1..=4).contains(&tris.len()), "a Triangle4 holds 1 to 4 triangles");
        let lane = |k: usize| tris[k.min(tris.len() - 1)];
        let coord = |vertex: usize, axis: usize| Vec4::from_array(std::array::from_fn(|k| lane(k).0[vertex][axis]));
        Triangle4 {
            v: std::array::from_fn(|vertex| std::array::from_fn(|axis| coord(vertex, axis))),
            id: std::array::from_fn(|k| lane(k).1),
        }
    }

    /// The vertices of lane `k`'s triangle.
    #[inline]
    pub fn triangle(&self, k: usize) -> [Vec3; 3] {
        // `as_ref` views a lane vector as an array: one indexed load (glam's `Index` matches on
        // the lane).
        let c = |vertex: usize, axis: usize| self.v[vertex][axis].as_ref()[k];
        std::array::from_fn(|vertex| Vec3::new(c(vertex, 0), c(vertex, 1), c(vertex, 2)))
    }

    /// The closest hit among the four triangles within `(0, t_max)`: lane and hit.
    #[inline(always)]
    pub fn intersect(&self, r: &RayPrecomp, t_max: f32) -> Option<(usize, TriangleHit)> {
        let l = self.edges(
            r,
            t_max,
            |c| {
                let inv_det = c.det.recip();
                let t = c.t_scaled * inv_det;
                // Conservative check that t is really positive (pbrt-v4 §6.8.7), per lane.
                let delta_t = t_error_bound(c.x, c.y, c.z, c.e, inv_det);
                let valid = c.valid & t.cmpgt(delta_t);
                valid.any().then_some(Lanes { valid, t, inv_det, e: c.e })
            },
            |l| l,
        )?;
        let t = Vec4::select(l.valid, l.t, Vec4::INFINITY);
        let t_min = t.min_element();
        let lane = t.cmpeq(Vec4::splat(t_min)).bitmask().trailing_zeros() as usize;
        if lane >= 4 {
            // t_min is NaN (overflowing coordinates): no hit.
            return None;
        }
        let inv_det = l.inv_det.as_ref()[lane];
        Some((
            lane,
            TriangleHit {
                t: t_min,
                b0: l.e[0].as_ref()[lane] * inv_det,
                b1: l.e[1].as_ref()[lane] * inv_det,
                b2: l.e[2].as_ref()[lane] * inv_det,
            },
        ))
    }

    /// Whether any of the four triangles is hit within `(0, t_max)`: the same test without a
    /// division (the `t > δt` check as `|t_scaled| > δt · |det|`, see
    /// `t_error_scaled` in `geometry::triangle`).
    #[inline(always)]
    pub fn occludes(&self, r: &RayPrecomp, t_max: f32) -> bool {
        let finish = |c: Candidates| (c.valid & c.t_scaled.abs().cmpgt(t_error_scaled(c.x, c.y, c.z, c.e))).any();
        self.edges(r, t_max, |c| finish(c).then_some(()), |_| ()).is_some()
    }

    /// The per-lane test up to the `t > δt` check, which `finish` does on the candidate lanes;
    /// `None` when no lane hits. A lane with an edge function exactly zero sends the block
    /// through the scalar test instead, whose lanes `scalar` turns into the answer.
    #[inline(always)]
    fn edges<R>(
        &self,
        r: &RayPrecomp,
        t_max: f32,
        finish: impl FnOnce(Candidates) -> Option<R>,
        scalar: impl FnOnce(Lanes) -> R,
    ) -> Option<R> {
        let [kx, ky, kz] = r.k;
        let [ox, oy, oz] = r.op4;
        let [sx, sy, sz] = r.s4;
        // Vertices relative to the origin, permuted, sheared (x, y) and scaled (z).
        let p = |vertex: usize| {
            let v = &self.v[vertex];
            let (x, y, z) = (v[kx] - ox, v[ky] - oy, v[kz] - oz);
            (x - sx * z, y - sy * z, sz * z)
        };
        let (p0x, p0y, z0) = p(0);
        let (p1x, p1y, z1) = p(1);
        let (p2x, p2y, z2) = p(2);
        let e0 = p1x * p2y - p1y * p2x;
        let e1 = p2x * p0y - p2y * p0x;
        let e2 = p0x * p1y - p0y * p1x;
        if (e0.cmpeq(Vec4::ZERO) | e1.cmpeq(Vec4::ZERO) | e2.cmpeq(Vec4::ZERO)).any() {
            return self.scalar_lanes(r, t_max).map(scalar);
        }
        let inside = (e0.cmpge(Vec4::ZERO) & e1.cmpge(Vec4::ZERO) & e2.cmpge(Vec4::ZERO))
            | (e0.cmple(Vec4::ZERO) & e1.cmple(Vec4::ZERO) & e2.cmple(Vec4::ZERO));
        let det = e0 + e1 + e2;
        let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
        let bound = Vec4::splat(t_max) * det;
        let in_range = (det.cmpgt(Vec4::ZERO) & t_scaled.cmpgt(Vec4::ZERO) & t_scaled.cmple(bound))
            | (det.cmplt(Vec4::ZERO) & t_scaled.cmplt(Vec4::ZERO) & t_scaled.cmpge(bound));
        let valid = inside & in_range;
        if !valid.any() {
            return None;
        }
        finish(Candidates {
            valid,
            det,
            t_scaled,
            e: [e0, e1, e2],
            x: [p0x, p1x, p2x],
            y: [p0y, p1y, p2y],
            z: [z0, z1, z2],
        })
    }

    /// The lanes through the scalar test (an edge function was exactly zero).
    #[cold]
    fn scalar_lanes(&self, r: &RayPrecomp, t_max: f32) -> Option<Lanes> {
        let mut l = Lanes { valid: BVec4A::FALSE, t: Vec4::INFINITY, inv_det: Vec4::ONE, e: [Vec4::ZERO; 3] };
        let mut valid = [false; 4];
        for (k, v) in valid.iter_mut().enumerate() {
            if let Some(h) = intersect_triangle(r, &self.triangle(k), t_max) {
                *v = true;
                l.t[k] = h.t;
                (l.e[0][k], l.e[1][k], l.e[2][k]) = (h.b0, h.b1, h.b2);
            }
        }
        l.valid = BVec4A::from_array(valid);
        l.valid.any().then_some(l)
    }
}

/// The per-lane test before its last check: lanes inside their triangle with `t` in range,
/// their determinant, scaled `t`, edge functions and transformed vertices (for the error bound).
struct Candidates {
    valid: BVec4A,
    det: Vec4,
    t_scaled: Vec4,
    e: [Vec4; 3],
    x: [Vec4; 3],
    y: [Vec4; 3],
    z: [Vec4; 3],
}

/// Per-lane results: which lanes hit, their `t`, `1 / det` and edge functions (barycentrics
/// times `det`).
struct Lanes {
    valid: BVec4A,
    t: Vec4,
    inv_det: Vec4,
    e: [Vec4; 3],
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Ray;
    use crate::sampling::Pcg32;

    /// Random triangles and rays; every block answer equals the best scalar answer.
    #[test]
    fn agrees_with_the_scalar_test() {
        let mut rng = Pcg32::new(3, 4);
        let mut v = |scale: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale - scale / 2.0;
        let (mut hits, mut blocks) = (0, 0);
        for round in 0..20_000 {
            let n = 1 + round % 4;
            let c = v(2.0);
            let tris: Vec<([Vec3; 3], u32)> =
                (0..n).map(|i| ([c + v(1.0), c + v(1.0), c + v(1.0)], 10 * round as u32 + i as u32)).collect();
            let o = v(6.0);
            let ray = Ray::new(o, c + v(0.5) - o);
            let pre = RayPrecomp::new(&ray);
            let t_max = if round % 3 == 0 { 1.0 } else { f32::INFINITY };
            let block = Triangle4::new(&tris);
            let scalar = tris
                .iter()
                .filter_map(|(p, id)| intersect_triangle(&pre, p, t_max).map(|h| (h, *id)))
                .min_by(|a, b| a.0.t.total_cmp(&b.0.t));
            let simd = block.intersect(&pre, t_max).map(|(lane, h)| (h, block.id[lane]));
            assert_eq!(block.occludes(&pre, t_max), scalar.is_some());
            match (scalar, simd) {
                (None, None) => {}
                (Some((a, ida)), Some((b, idb))) => {
                    assert_eq!(a.t, b.t);
                    assert_eq!(ida, idb);
                    for (x, y) in [(a.b0, b.b0), (a.b1, b.b1), (a.b2, b.b2)] {
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
    /// occlusion test alike; farther ones are found by all three.
    #[test]
    fn hits_within_the_t_error_bound_are_refused() {
        // The plane z = x, crossed by rays going down z at x = y = 0: |z| of the vertices is 1
        // in the ray's frame, so δt is about 10⁻⁶.
        let tri = [Vec3::new(-1.0, -1.0, -1.0), Vec3::new(1.0, -1.0, 1.0), Vec3::new(0.0, 1.0, 0.0)];
        let block = Triangle4::new(&[(tri, 0)]);
        for (h, hit) in [(1e-8f32, false), (1e-7, false), (1e-4, true), (1.0, true)] {
            let pre = RayPrecomp::new(&Ray::new(Vec3::new(0.0, 0.0, h), -Vec3::Z));
            assert_eq!(intersect_triangle(&pre, &tri, f32::INFINITY).is_some(), hit, "scalar at {h}");
            assert_eq!(block.intersect(&pre, f32::INFINITY).is_some(), hit, "closest hit at {h}");
            assert_eq!(block.occludes(&pre, f32::INFINITY), hit, "occlusion at {h}");
        }
    }

    #[test]
    fn exact_edge_falls_back_and_is_watertight() {
        // Two triangles sharing the edge x = 0; a ray straight down that edge hits one of them.
        let a = [Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)];
        let b = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
        let block = Triangle4::new(&[(a, 7), (b, 8)]);
        for y in [-0.5f32, 0.0, 0.25] {
            let ray = Ray::new(Vec3::new(0.0, y, 2.0), -Vec3::Z);
            let (lane, h) = block.intersect(&RayPrecomp::new(&ray), f32::INFINITY).expect("edge ray leaked");
            assert!([7, 8].contains(&block.id[lane]));
            assert_eq!(h.t, 2.0);
        }
        assert_eq!(block.triangle(1), b);
        assert_eq!(block.triangle(3), b, "padding lanes repeat the last triangle");
    }
}
