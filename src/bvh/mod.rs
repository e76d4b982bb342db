//! Bounding volume hierarchy: binned SAH build (parallel), flattened depth-first nodes of 32
//! bytes, closest-hit and any-hit traversal.
//!
//! The BVH knows only primitive bounds; the caller intersects primitives in leaves through a
//! closure, so one BVH serves triangles, spheres and disks alike (and, later, instances). After
//! the build, [`Bvh::order`] lists primitive indices in leaf order: callers store their
//! primitive data in that order so a leaf's primitives are contiguous in memory.

mod build;

use crate::math::float::gamma;
use crate::math::{Bounds3, Ray};
use glam::{Vec3A, Vec4};

pub use build::BuildOptions;

/// A flattened node (32 bytes): bounds, and either a leaf (primitives `offset .. offset +
/// count`) or an interior node whose first child follows it and whose second child is at
/// `offset`. The integer fields ride in the `w` lanes of the bounds so that one aligned SIMD load
/// fetches each corner.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Node {
    /// Lower corner; `w` holds the bits of `offset`.
    min: Vec4,
    /// Upper corner; `w` holds the bits of `meta`: leaf primitive count (> 0), or
    /// `INTERIOR | split axis`.
    max: Vec4,
}

const INTERIOR: u32 = 0x8000_0000;

impl Node {
    pub(crate) fn new(bounds: &Bounds3, offset: u32, meta: u32) -> Node {
        Node { min: bounds.min.extend(f32::from_bits(offset)), max: bounds.max.extend(f32::from_bits(meta)) }
    }
    #[inline(always)]
    fn offset(&self) -> u32 {
        self.min.w.to_bits()
    }
    #[inline(always)]
    fn meta(&self) -> u32 {
        self.max.w.to_bits()
    }
    pub(crate) fn set_offset(&mut self, offset: u32) {
        self.min.w = f32::from_bits(offset);
    }
    /// Node bounds.
    pub fn bounds(&self) -> Bounds3 {
        Bounds3 { min: self.min.truncate(), max: self.max.truncate() }
    }
    /// Whether the node is a leaf.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.meta() & INTERIOR == 0
    }
}

/// A bounding volume hierarchy over primitives given by their bounds.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

/// Statistics of a built BVH.
#[derive(Clone, Copy, Debug, Default)]
pub struct BvhStats {
    /// Total nodes.
    pub nodes: usize,
    /// Leaf nodes.
    pub leaves: usize,
    /// Deepest leaf.
    pub max_depth: usize,
    /// SAH cost (traversal cost 1, intersection cost 1) relative to the root's area.
    pub sah_cost: f32,
}

impl Bvh {
    /// Builds a BVH over primitives with the given bounds.
    pub fn build(bounds: &[Bounds3], opts: &BuildOptions) -> Bvh {
        build::build(bounds, opts)
    }

    /// Primitive indices in leaf order: leaf primitive `k` is primitive `order()[k]`.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// The flattened nodes (root first).
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Bounds of everything.
    pub fn bounds(&self) -> Bounds3 {
        self.nodes.first().map_or(Bounds3::EMPTY, |n| n.bounds())
    }

    /// Node count, leaf count, depth and SAH cost.
    pub fn stats(&self) -> BvhStats {
        let mut s = BvhStats { nodes: self.nodes.len(), ..Default::default() };
        if self.nodes.is_empty() {
            return s;
        }
        let root_area = self.nodes[0].bounds().surface_area().max(1e-30);
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            let rel = n.bounds().surface_area() / root_area;
            s.max_depth = s.max_depth.max(depth);
            if n.is_leaf() {
                s.leaves += 1;
                s.sah_cost += rel * n.meta() as f32;
            } else {
                s.sah_cost += rel;
                stack.push((i + 1, depth + 1));
                stack.push((n.offset() as usize, depth + 1));
            }
        }
        s
    }

    /// Finds the closest hit. `leaf(first, count, t_max)` intersects leaf primitives
    /// `first .. first + count` (in [`Bvh::order`] positions) and lowers `t_max` to the closest hit
    /// found; traversal then culls everything farther. Children are visited nearest first, and
    /// postponed nodes whose entry distance is beyond the current `t_max` are skipped.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, mut t_max: f32, mut leaf: impl FnMut(u32, u32, &mut f32)) {
        let Some(root) = self.nodes.first() else { return };
        let r = SlabRay::new(ray);
        if r.entry(root, t_max).is_none() {
            return;
        }
        // Uninitialized: only slots below `sp` are ever read (saves a 512-byte memset per ray).
        let mut stack = [std::mem::MaybeUninit::<(u32, f32)>::uninit(); 64];
        let mut sp = 0usize;
        let mut idx = 0u32;
        loop {
            let node = unsafe { self.nodes.get_unchecked(idx as usize) };
            if node.is_leaf() {
                leaf(node.offset(), node.meta(), &mut t_max);
            } else {
                let (a, b) = (idx + 1, node.offset());
                let ta = r.entry(unsafe { self.nodes.get_unchecked(a as usize) }, t_max);
                let tb = r.entry(unsafe { self.nodes.get_unchecked(b as usize) }, t_max);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far, t_far) = if ta <= tb { (a, b, tb) } else { (b, a, ta) };
                        stack[sp].write((far, t_far));
                        sp += 1;
                        idx = near;
                        continue;
                    }
                    (Some(_), None) => {
                        idx = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        idx = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next postponed node that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: slot `sp` was written before `sp` was incremented past it.
                let (next, t_entry) = unsafe { stack[sp].assume_init() };
                if t_entry <= t_max {
                    idx = next;
                    break;
                }
            }
        }
    }

    /// Whether anything is hit within `(0, t_max)`. `leaf(first, count, t_max)` returns `true` as
    /// soon as one of the leaf's primitives is hit.
    #[inline]
    pub fn any_hit(&self, ray: &Ray, t_max: f32, mut leaf: impl FnMut(u32, u32, f32) -> bool) -> bool {
        let Some(root) = self.nodes.first() else { return false };
        let r = SlabRay::new(ray);
        if r.entry(root, t_max).is_none() {
            return false;
        }
        let mut stack = [std::mem::MaybeUninit::<u32>::uninit(); 64];
        let mut sp = 0usize;
        let mut idx = 0u32;
        loop {
            let node = unsafe { self.nodes.get_unchecked(idx as usize) };
            if node.is_leaf() {
                if leaf(node.offset(), node.meta(), t_max) {
                    return true;
                }
            } else {
                let (a, b) = (idx + 1, node.offset());
                let ha = r.entry(unsafe { self.nodes.get_unchecked(a as usize) }, t_max).is_some();
                let hb = r.entry(unsafe { self.nodes.get_unchecked(b as usize) }, t_max).is_some();
                if ha && hb {
                    stack[sp].write(b);
                    sp += 1;
                    idx = a;
                    continue;
                } else if ha {
                    idx = a;
                    continue;
                } else if hb {
                    idx = b;
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            // SAFETY: slot `sp` was written before `sp` was incremented past it.
            idx = unsafe { stack[sp].assume_init() };
        }
    }
}

/// A ray prepared for SIMD slab tests.
struct SlabRay {
    o: Vec3A,
    inv_d: Vec3A,
}

impl SlabRay {
    #[inline(always)]
    fn new(ray: &Ray) -> SlabRay {
        SlabRay { o: Vec3A::from(ray.o), inv_d: Vec3A::from(ray.d.recip()) }
    }

    /// Entry distance of the ray into the node's box within `(0, t_max)`, or `None`. The far
    /// distance is enlarged by `1 + 2γ₃` so that round-off never culls a box the ray enters.
    #[inline(always)]
    fn entry(&self, node: &Node, t_max: f32) -> Option<f32> {
        let t0 = (Vec3A::from_vec4(node.min) - self.o) * self.inv_d;
        let t1 = (Vec3A::from_vec4(node.max) - self.o) * self.inv_d;
        let t_near = t0.min(t1).max_element().max(0.0);
        let t_far = (t0.max(t1).min_element() * (1.0 + 2.0 * gamma(3))).min(t_max);
        (t_near <= t_far).then_some(t_near)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::{intersect_triangle, RayPrecomp};
    use crate::math::Vec3;
    use crate::sampling::Pcg32;

    fn random_triangles(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut rng = Pcg32::new(seed, 0);
        (0..n)
            .map(|_| {
                let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0 - 10.0;
                let mut v = || c + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
                [v(), v(), v()]
            })
            .collect()
    }

    #[test]
    fn closest_and_any_hit_match_brute_force() {
        let tris = random_triangles(5000, 1);
        let bounds: Vec<Bounds3> =
            tris.iter().map(|t| Bounds3::from_point(t[0]).union_point(t[1]).union_point(t[2])).collect();
        let bvh = Bvh::build(&bounds, &BuildOptions::default());
        let ordered: Vec<[Vec3; 3]> = bvh.order().iter().map(|&i| tris[i as usize]).collect();
        let mut sorted = bvh.order().to_vec();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..5000u32).collect::<Vec<_>>(), "order is a permutation");
        let mut rng = Pcg32::new(2, 0);
        for _ in 0..2000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 30.0 - 15.0;
            let d = crate::sampling::sample_uniform_sphere(crate::testkit::u2(&mut rng)).value;
            let ray = Ray::new(o, d);
            let pre = RayPrecomp::new(&ray);
            let brute = tris
                .iter()
                .filter_map(|t| intersect_triangle(&pre, t, f32::INFINITY))
                .map(|h| h.t)
                .fold(f32::INFINITY, f32::min);
            let mut best = f32::INFINITY;
            bvh.closest_hit(&ray, f32::INFINITY, |first, count, t_max| {
                for k in first..first + count {
                    if let Some(h) = intersect_triangle(&pre, &ordered[k as usize], *t_max) {
                        *t_max = h.t;
                        best = h.t;
                    }
                }
            });
            assert_eq!(best, brute);
            let limit = if brute.is_finite() { brute * 0.999 } else { 1e30 };
            let any = bvh.any_hit(&ray, limit, |first, count, t_max| {
                (first..first + count).any(|k| intersect_triangle(&pre, &ordered[k as usize], t_max).is_some())
            });
            assert!(!any, "any-hit found something before the closest hit");
            if brute.is_finite() {
                assert!(bvh.any_hit(&ray, brute * 1.001, |first, count, t_max| {
                    (first..first + count).any(|k| intersect_triangle(&pre, &ordered[k as usize], t_max).is_some())
                }));
            }
        }
        let s = bvh.stats();
        assert!(s.leaves > 5000 / 8 && s.max_depth < 64, "{s:?}");
    }

    #[test]
    fn degenerate_inputs() {
        let empty = Bvh::build(&[], &BuildOptions::default());
        assert!(!empty.any_hit(&Ray::new(Vec3::ZERO, Vec3::X), 1.0, |_, _, _| true));
        // Many primitives with identical bounds (centroid bounds of zero size) still build.
        let same = vec![Bounds3::new(Vec3::ZERO, Vec3::ONE); 1000];
        let bvh = Bvh::build(&same, &BuildOptions::default());
        assert_eq!(bvh.order().len(), 1000);
        assert!(bvh.stats().max_depth < 64);
    }
}
