//! Bounding volume hierarchy: binned SAH build (parallel), collapsed SAH-optimally into 8-wide
//! nodes tested with one SIMD slab test per node (AVX when the CPU has it, chosen at run time;
//! two 4-wide SSE halves otherwise); closest-hit and any-hit traversal.
//!
//! Each traversal, with the caller's leaf test inlined into it, is compiled twice and picked
//! per CPU at run time ([`Kernel`]): for AVX, and portable. Both evaluate the same IEEE
//! operations in the same order, so they return the same bits; tests hold them to it. (A
//! third, compiled for x86-64-v3 — AVX2, FMA, BMI1/2, LZCNT, POPCNT — measured the same as the
//! AVX one within noise on 100k and 1M triangles, on an AMD Zen 5, and was not kept.)
//!
//! Nodes live in a [`HugeArray`] (memory advised as 2 MiB pages: incoherent rays through a
//! large tree then miss the TLB far less often).
//!
//! The BVH knows only primitive bounds; the caller intersects primitives in leaves through a
//! closure, so one BVH serves triangles, spheres and disks alike (and, later, instances). After
//! the build, [`Bvh::order`] lists primitive indices in leaf order: callers store their
//! primitive data in that order so a leaf's primitives are contiguous in memory.

mod build;
mod huge;
pub mod presplit;
mod slab;

use crate::math::simd::Avx;
use crate::math::{Bounds3, Ray, Vec3};
use slab::{Slab4x2, SlabTest};

pub use build::BuildOptions;
pub use huge::HugeArray;

/// Children per node.
pub const WIDTH: usize = 8;

/// An 8-wide node (256 bytes, four cache lines): the bounds of up to eight children in
/// structure-of-arrays form (`bounds[0..3]` = lower corners' x, y, z, `bounds[3..6]` = upper
/// corners' x, y, z, one lane per child), so one SIMD slab test checks all eight; and per child
/// either a leaf (`count > 0` primitives from `child`) or an interior node (`count == 0`, node
/// index `child`). Unused slots have `child == u32::MAX` and an empty box (min +∞, max -∞)
/// that no ray hits.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node8 {
    bounds: [[f32; WIDTH]; 6],
    child: [u32; WIDTH],
    count: [u32; WIDTH],
}

impl Node8 {
    pub(crate) fn empty() -> Node8 {
        let (inf, neg) = ([f32::INFINITY; WIDTH], [f32::NEG_INFINITY; WIDTH]);
        Node8 { bounds: [inf, inf, inf, neg, neg, neg], child: [u32::MAX; WIDTH], count: [0; WIDTH] }
    }

    pub(crate) fn set(&mut self, slot: usize, b: &Bounds3, child: u32, count: u32) {
        for axis in 0..3 {
            self.bounds[axis][slot] = b.min[axis];
            self.bounds[3 + axis][slot] = b.max[axis];
        }
        self.child[slot] = child;
        self.count[slot] = count;
    }

    fn valid(&self, slot: usize) -> bool {
        self.child[slot] != u32::MAX
    }

    fn child_bounds(&self, slot: usize) -> Bounds3 {
        let v = |c: usize| Vec3::new(self.bounds[c][slot], self.bounds[c + 1][slot], self.bounds[c + 2][slot]);
        Bounds3 { min: v(0), max: v(3) }
    }
}

/// A bounding volume hierarchy over primitives given by their bounds.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: HugeArray<Node8>,
    order: Vec<u32>,
    bounds: Bounds3,
    /// The compiled traversal this CPU runs (detected at build time).
    kernel: Kernel,
}

/// Which compiled traversal runs: the most capable one the CPU supports. Ordered from the
/// least capable.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kernel {
    /// Two 4-wide halves (SSE2 on x86-64, plain code elsewhere).
    #[default]
    Portable,
    /// The 8-wide AVX slab and triangle tests.
    Avx,
}

impl Kernel {
    /// The most capable kernel this CPU runs.
    pub fn detect() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        {
            if is_x86_feature_detected!("avx") {
                return Kernel::Avx;
            }
        }
        Kernel::Portable
    }

    /// The kernels this CPU runs, least capable first (for tests that compare them).
    pub fn available() -> Vec<Kernel> {
        [Kernel::Portable, Kernel::Avx].into_iter().filter(|&k| k <= Kernel::detect()).collect()
    }
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
    /// Builds a BVH over primitives with the given bounds, all tested in SIMD groups of
    /// `opts.leaf_group` (triangles).
    pub fn build(bounds: &[Bounds3], opts: &BuildOptions) -> Bvh {
        build::build(bounds, &[], opts)
    }

    /// [`Bvh::build`] where some primitives are tested alone: `weights[i]` is primitive `i`'s
    /// test cost in group tests (0: tested in groups). The SAH charges a leaf
    /// `⌈grouped / leaf_group⌉ + Σ weights`.
    pub fn build_weighted(bounds: &[Bounds3], weights: &[f32], opts: &BuildOptions) -> Bvh {
        build::build(bounds, weights, opts)
    }

    /// Primitive indices in leaf order: leaf primitive `k` is primitive `order()[k]`.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Bounds of everything.
    pub fn bounds(&self) -> Bounds3 {
        if self.nodes.is_empty() {
            Bounds3::EMPTY
        } else {
            self.bounds
        }
    }

    /// Re-encodes every leaf's payload: `f(first, count)` gets the leaf's primitive range (in
    /// [`Bvh::order`] positions) and returns the `(child, count)` stored in its place, which the
    /// traversal closures then receive. `count` must stay non-zero (zero marks interior nodes).
    /// Lets a caller replace primitive ranges by its own packed blocks; [`Bvh::stats`] reads the
    /// counts, so take statistics before.
    pub fn remap_leaves(&mut self, mut f: impl FnMut(u32, u32) -> (u32, u32)) {
        for node in self.nodes.iter_mut() {
            for slot in 0..WIDTH {
                if node.valid(slot) && node.count[slot] > 0 {
                    let (child, count) = f(node.child[slot], node.count[slot]);
                    assert!(count > 0, "a leaf's count must stay non-zero");
                    (node.child[slot], node.count[slot]) = (child, count);
                }
            }
        }
    }

    /// Bytes the nodes and the leaf order take.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node8>() + self.order.len() * size_of::<u32>()
    }

    /// Node count, leaf count, depth and SAH cost.
    pub fn stats(&self) -> BvhStats {
        let mut s = BvhStats { nodes: self.nodes.len(), ..Default::default() };
        if self.nodes.is_empty() {
            return s;
        }
        let root_area = self.bounds.surface_area().max(1e-30);
        s.sah_cost = 1.0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            s.max_depth = s.max_depth.max(depth);
            for slot in (0..WIDTH).filter(|&k| n.valid(k)) {
                let rel = n.child_bounds(slot).surface_area() / root_area;
                if n.count[slot] > 0 {
                    s.leaves += 1;
                    s.sah_cost += rel * n.count[slot] as f32;
                } else {
                    s.sah_cost += rel;
                    stack.push((n.child[slot] as usize, depth + 1));
                }
            }
        }
        s
    }

    /// Finds the closest hit. `leaf(first, count, t_max)` intersects leaf primitives
    /// `first .. first + count` (in [`Bvh::order`] positions) and lowers `t_max` to the closest hit
    /// found; traversal then culls everything farther. The children of a node are tested at
    /// once and visited nearest first; postponed ones are skipped when a closer hit was found
    /// meanwhile. One or two hit children (the common cases) are handled without a sort.
    /// Of the postponed children only the next one, if it is an interior node, is prefetched
    /// (the far child of two, the second nearest of more): many of the others are culled by a
    /// closer hit before their turn, and prefetching all of them measured slower. The one
    /// prefetch made incoherent rays in a 1M-triangle mesh (nodes out of cache) 10–15 % faster,
    /// and changed nothing measurable at 100k triangles.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32, leaf: impl FnMut(u32, u32, &mut f32)) {
        self.closest_hit_visit(ray, t_max, ClosestLeafFn(leaf))
    }

    /// The compiled traversal this BVH runs ([`Kernel::detect`] when built).
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Runs `kernel` from now on, if this CPU supports it (returns whether it does; a kernel it
    /// does not support is refused). For comparing the kernels' answers and speeds.
    pub fn set_kernel(&mut self, kernel: Kernel) -> bool {
        let supported = kernel <= Kernel::detect();
        if supported {
            self.kernel = kernel;
        }
        supported
    }

    /// [`Bvh::closest_hit`] with the leaf work as a [`ClosestLeaf`] (whose `visit` the
    /// traversal inlines when it is `#[inline(always)]`).
    #[inline(always)]
    pub fn closest_hit_visit(&self, ray: &Ray, t_max: f32, leaf: impl ClosestLeaf) {
        if self.nodes.is_empty() || !traceable(ray, t_max) {
            return;
        }
        match self.kernel {
            // SAFETY: `kernel` names only kernels this CPU runs (`Kernel::detect`).
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx => unsafe { self.closest_hit_avx(ray, t_max, leaf) },
            _ => self.closest_hit_with(&Slab4x2::new(ray), t_max, leaf),
        }
    }

    /// [`Bvh::closest_hit`] compiled for AVX (the slab test, and the caller's leaf code inlined
    /// into it). Safety: the CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn closest_hit_avx(&self, ray: &Ray, t_max: f32, leaf: impl ClosestLeaf) {
        self.closest_hit_with(&slab::Slab8::new(ray), t_max, leaf)
    }

    #[inline(always)]
    fn closest_hit_with(&self, r: &impl SlabTest, mut t_max: f32, mut leaf: impl ClosestLeaf) {
        // Postponed children: (node or leaf, count, entry distance). Binary depth ≤ 60 bounds the
        // wide depth by 60, with at most seven postponed children per level.
        let mut stack = [std::mem::MaybeUninit::<Entry>::uninit(); 7 * 60 + 1];
        let mut sp = 0usize;
        let (mut child, mut count) = (0u32, 0u32);
        loop {
            if count > 0 {
                leaf.visit(child, count, &mut t_max, r.avx());
            } else {
                // Interior children index `nodes` (built together), and unused slots (index
                // u32::MAX) are never entered by a traceable ray; indexing checks it anyway.
                let node = &self.nodes[child as usize];
                let (mut mask, t_near) = r.test(node, t_max);
                if mask != 0 {
                    let a = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        (child, count) = (node.child[a], node.count[a]);
                        continue;
                    }
                    let b = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        let (near, far) = if t_near[a] <= t_near[b] { (a, b) } else { (b, a) };
                        self.prefetch_closest(node.child[far], node.count[far], &leaf);
                        stack[sp].write((node.child[far], node.count[far], t_near[far]));
                        sp += 1;
                        (child, count) = (node.child[near], node.count[near]);
                        continue;
                    }
                    // Three or more: sort them farthest first by a key of the entry distance
                    // (never negative or NaN, so its bits order as integers) above the slot
                    // (reversed: among equal distances the lower slot goes deeper), push them
                    // in that order, and continue with the nearest.
                    let key = |slot: usize| u64::from(t_near[slot].to_bits()) << 32 | (7 - slot) as u64;
                    let c = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask & (mask.wrapping_sub(1)) == 0 {
                        // Three or four (the common case): a sorting network of five
                        // compare-exchanges without branches (a missing fourth key is 0, sorted
                        // last), where the insertion sort's data-dependent branches mispredicted.
                        let d = mask.trailing_zeros() as usize;
                        let n = 3 + (mask != 0) as usize;
                        let mut k = [key(a), key(b), key(c), if mask != 0 { key(d) } else { 0 }];
                        for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
                            let (hi, lo) = (k[i].max(k[j]), k[i].min(k[j]));
                            (k[i], k[j]) = (hi, lo);
                        }
                        for (e, &k) in k[..3].iter().enumerate() {
                            let slot = 7 - (k & 7) as usize;
                            stack[sp + e].write((node.child[slot], node.count[slot], t_near[slot]));
                        }
                        sp += n - 1;
                        let (nearest, next) = (7 - (k[n - 1] & 7) as usize, 7 - (k[n - 2] & 7) as usize);
                        self.prefetch_closest(node.child[next], node.count[next], &leaf);
                        (child, count) = (node.child[nearest], node.count[nearest]);
                        continue;
                    }
                    let mut keys = [0u64; WIDTH];
                    (keys[0], keys[1], keys[2]) = (key(a), key(b), key(c));
                    let mut n = 3;
                    while mask != 0 {
                        keys[n] = key(mask.trailing_zeros() as usize);
                        mask &= mask - 1;
                        n += 1;
                    }
                    for i in 1..n {
                        let k = keys[i];
                        let mut j = i;
                        while j > 0 && keys[j - 1] < k {
                            keys[j] = keys[j - 1];
                            j -= 1;
                        }
                        keys[j] = k;
                    }
                    for &k in &keys[..n - 1] {
                        let slot = 7 - (k & 7) as usize;
                        stack[sp].write((node.child[slot], node.count[slot], t_near[slot]));
                        sp += 1;
                    }
                    let (nearest, next) = (7 - (keys[n - 1] & 7) as usize, 7 - (keys[n - 2] & 7) as usize);
                    self.prefetch_closest(node.child[next], node.count[next], &leaf);
                    (child, count) = (node.child[nearest], node.count[nearest]);
                    continue;
                }
            }
            // Pop the next postponed child that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: slot `sp` was written before `sp` was incremented past it.
                let (c, n, t_entry) = unsafe { stack[sp].assume_init() };
                if t_entry <= t_max {
                    (child, count) = (c, n);
                    break;
                }
            }
        }
    }

    /// Prefetches a postponed child of the closest-hit traversal: an interior node's cache
    /// lines, or the leaf's data.
    #[inline(always)]
    fn prefetch_closest(&self, child: u32, count: u32, leaf: &impl ClosestLeaf) {
        if count == 0 {
            prefetch(self.nodes.as_ptr().wrapping_add(child as usize), size_of::<Node8>());
        } else {
            leaf.prefetch(child, count);
        }
    }

    /// Whether anything is hit within `(0, t_max)`. `leaf(first, count, t_max)` returns `true` as
    /// soon as one of the leaf's primitives is hit. Children are visited in no particular order;
    /// those waiting on the stack are prefetched when pushed (nodes here, leaf data through
    /// `prefetch_leaf(first, count)`), so that their cache misses overlap.
    #[inline]
    pub fn any_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        leaf: impl FnMut(u32, u32, f32) -> bool,
        prefetch_leaf: impl Fn(u32, u32),
    ) -> bool {
        self.any_hit_visit(ray, t_max, AnyLeafFns(leaf, prefetch_leaf))
    }

    /// [`Bvh::any_hit`] with the leaf work as an [`AnyLeaf`] (whose methods the traversal
    /// inlines when they are `#[inline(always)]`).
    #[inline]
    pub fn any_hit_visit(&self, ray: &Ray, t_max: f32, leaf: impl AnyLeaf) -> bool {
        if self.nodes.is_empty() || !traceable(ray, t_max) {
            return false;
        }
        match self.kernel {
            // SAFETY: `kernel` names only kernels this CPU runs (`Kernel::detect`).
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx => unsafe { self.any_hit_avx(ray, t_max, leaf) },
            _ => self.any_hit_with(&Slab4x2::new(ray), t_max, leaf),
        }
    }

    /// [`Bvh::any_hit_visit`] compiled for AVX. Safety: the CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn any_hit_avx(&self, ray: &Ray, t_max: f32, leaf: impl AnyLeaf) -> bool {
        self.any_hit_with(&slab::Slab8::new(ray), t_max, leaf)
    }

    #[inline(always)]
    fn any_hit_with(&self, r: &impl SlabTest, t_max: f32, mut leaf: impl AnyLeaf) -> bool {
        // At most seven children wait per level of the (≤ 60 deep) tree, plus the root.
        let mut stack = [std::mem::MaybeUninit::<(u32, u32)>::uninit(); 7 * 60 + 1];
        stack[0].write((0, 0));
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            // SAFETY: slot `sp` was written before `sp` was incremented past it.
            let (child, count) = unsafe { stack[sp].assume_init() };
            if count > 0 {
                if leaf.hit(child, count, t_max, r.avx()) {
                    return true;
                }
                continue;
            }
            // As in `closest_hit`: checked, never out of range for a traceable ray.
            let node = &self.nodes[child as usize];
            let (mut mask, _) = r.test(node, t_max);
            while mask != 0 {
                let slot = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                self.prefetch_child(node, slot, &leaf);
                stack[sp].write((node.child[slot], node.count[slot]));
                sp += 1;
            }
        }
        false
    }

    /// Prefetches child `slot` of `node`: the cache lines of an interior node, or the leaf's data.
    #[inline(always)]
    fn prefetch_child(&self, node: &Node8, slot: usize, leaf: &impl AnyLeaf) {
        if node.count[slot] == 0 {
            prefetch(self.nodes.as_ptr().wrapping_add(node.child[slot] as usize), size_of::<Node8>());
        } else {
            leaf.prefetch(node.child[slot], node.count[slot]);
        }
    }
}

/// The leaf work of [`Bvh::closest_hit`]: intersect the leaf's primitives `first .. first +
/// count` (in [`Bvh::order`] positions, or as [`Bvh::remap_leaves`] re-encoded them) and lower
/// `t_max` to the closest hit found. A renderer's own type marks `visit` `#[inline(always)]`
/// so that both compiled traversals (AVX and portable) inline it; a closure, compiled once for
/// both, stays a call.
pub trait ClosestLeaf {
    /// Intersects one leaf's primitives within `(0, t_max)`. `avx` is the AVX token where the
    /// traversal runs compiled for AVX: the leaf test can use AVX then, inlined.
    fn visit(&mut self, first: u32, count: u32, t_max: &mut f32, avx: Option<Avx>);
    /// Asks the cache for a postponed leaf's data ahead of its visit (a hint; by default none).
    #[inline(always)]
    fn prefetch(&self, first: u32, count: u32) {
        let _ = (first, count);
    }
}

/// A closure as a [`ClosestLeaf`].
pub struct ClosestLeafFn<F>(pub F);

impl<F: FnMut(u32, u32, &mut f32)> ClosestLeaf for ClosestLeafFn<F> {
    #[inline(always)]
    fn visit(&mut self, first: u32, count: u32, t_max: &mut f32, _: Option<Avx>) {
        (self.0)(first, count, t_max)
    }
}

/// The leaf work of [`Bvh::any_hit_visit`]: whether one of a leaf's primitives is hit within
/// `(0, t_max)`, and a cache hint for a leaf that waits on the stack.
pub trait AnyLeaf {
    /// Whether a primitive of the leaf `first .. first + count` is hit within `(0, t_max)`
    /// (`avx`: as in [`ClosestLeaf::visit`]).
    fn hit(&mut self, first: u32, count: u32, t_max: f32, avx: Option<Avx>) -> bool;
    /// Asks the cache for the leaf's data ahead of its visit (a hint).
    fn prefetch(&self, first: u32, count: u32);
}

/// Two closures as an [`AnyLeaf`]: the hit test and the prefetch.
pub struct AnyLeafFns<F, P>(pub F, pub P);

impl<F: FnMut(u32, u32, f32) -> bool, P: Fn(u32, u32)> AnyLeaf for AnyLeafFns<F, P> {
    #[inline(always)]
    fn hit(&mut self, first: u32, count: u32, t_max: f32, _: Option<Avx>) -> bool {
        (self.0)(first, count, t_max)
    }
    #[inline(always)]
    fn prefetch(&self, first: u32, count: u32) {
        (self.1)(first, count)
    }
}

/// Whether traversal can answer for `ray`: a finite origin and direction and a `t_max` that
/// is not NaN. Other rays hit nothing (the slab test's reasoning about empty slots and the
/// ordering of distances needs finite operands).
#[inline(always)]
fn traceable(ray: &Ray, t_max: f32) -> bool {
    ray.o.is_finite() && ray.d.is_finite() && !t_max.is_nan()
}

/// Asks the cache for the `bytes` bytes at `p` ahead of their use (a hint: it never faults,
/// whatever the address; a no-op off x86-64). Traversals use it for nodes and leaves that wait
/// on the stack, so that the misses of sibling subtrees overlap instead of following each other.
#[inline(always)]
pub fn prefetch<T>(p: *const T, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = p as *const i8;
        // A plain counted loop (an iterator's `step_by` stays a loop of ~10 instructions per
        // line; this one unrolls into the prefetches when `bytes` is a constant).
        let mut line = 0;
        while line < bytes {
            // SAFETY: prefetch instructions do not access memory architecturally and never fault.
            unsafe { _mm_prefetch(p.wrapping_add(line), _MM_HINT_T0) };
            line += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, bytes);
}

/// A traversal stack entry: node index (or first primitive), primitive count (0 for a node),
/// entry distance.
type Entry = (u32, u32, f32);

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geometry::triangle::{intersect_triangle, RayPrecomp};
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

    /// Hostile input never reads outside the nodes (it once did: a NaN ray selected unused
    /// slots): NaN and infinite primitive bounds among good ones, and rays with NaN or infinite
    /// origins, directions and limits. Finite rays still find the good primitives.
    #[test]
    fn non_finite_bounds_and_rays_are_safe() {
        let mut bounds: Vec<Bounds3> = (0..200)
            .map(|i| {
                let c = Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32);
                Bounds3::new(c, c + Vec3::splat(0.5))
            })
            .collect();
        let nan = Vec3::splat(f32::NAN);
        bounds[3] = Bounds3::new(nan, nan);
        bounds[50] = Bounds3::new(Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY));
        bounds[77] = Bounds3::new(Vec3::new(1.0, f32::NAN, 2.0), Vec3::splat(3.0));
        let bvh = Bvh::build(&bounds, &BuildOptions::default());
        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 3.4e38, -3.4e38, 0.0];
        let mut visited = 0;
        for &a in &bad {
            for &b in &bad {
                for t_max in [f32::NAN, f32::INFINITY, 1e30, 5.0] {
                    let rays = [
                        Ray::new(Vec3::new(a, 0.2, b), Vec3::new(1.0, 0.0, 0.0)),
                        Ray::new(Vec3::splat(-1.0), Vec3::new(a, b, 1.0)),
                    ];
                    for ray in rays {
                        bvh.closest_hit(&ray, t_max, |first, count, _| {
                            assert!((first + count) as usize <= bounds.len());
                            visited += 1;
                        });
                        bvh.any_hit(&ray, t_max, |first, count, _| (first + count) as usize > bounds.len(), |_, _| {});
                    }
                }
            }
        }
        assert!(visited > 0, "finite rays still reach leaves");
    }

    #[test]
    fn closest_and_any_hit_match_brute_force() {
        let tris = random_triangles(5000, 1);
        let bounds: Vec<Bounds3> =
            tris.iter().map(|t| Bounds3::from_point(t[0]).union_point(t[1]).union_point(t[2])).collect();
        let built = Bvh::build(&bounds, &BuildOptions::default());
        // Every compiled traversal this CPU runs.
        for kernel in Kernel::available() {
            check_against_brute_force(&Bvh { kernel, ..built.clone() }, &tris);
        }
    }

    fn check_against_brute_force(bvh: &Bvh, tris: &[[Vec3; 3]]) {
        let ordered: Vec<[Vec3; 3]> = bvh.order().iter().map(|&i| tris[i as usize]).collect();
        let mut sorted = bvh.order().to_vec();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..5000u32).collect::<Vec<_>>(), "order is a permutation");
        let mut rng = Pcg32::new(2, 0);
        for _ in 0..2000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 30.0 - 15.0;
            let d = crate::sampling::sample_uniform_sphere(crate::testkit::u2(&mut rng)).value;
            traces_like_brute_force(bvh, tris, &ordered, &Ray::new(o, d));
        }
        let s = bvh.stats();
        assert!(s.leaves > 5000 / 8 && s.max_depth < 64, "{s:?}");
    }

    /// Checks one ray against a BVH whose leaf position `k` holds triangle `ordered[k]` (of the
    /// soup `tris`): the closest hit is the brute-force one, no shadow ray stops short of it,
    /// and one just beyond it is blocked. Returns the hit distance (infinite for a miss).
    pub(crate) fn traces_like_brute_force(bvh: &Bvh, tris: &[[Vec3; 3]], ordered: &[[Vec3; 3]], ray: &Ray) -> f32 {
        let pre = RayPrecomp::new(ray);
        let brute = tris
            .iter()
            .filter_map(|t| intersect_triangle(&pre, t, f32::INFINITY))
            .map(|h| h.t())
            .fold(f32::INFINITY, f32::min);
        let mut best = f32::INFINITY;
        bvh.closest_hit(ray, f32::INFINITY, |first, count, t_max| {
            for k in first..first + count {
                if let Some(h) = intersect_triangle(&pre, &ordered[k as usize], *t_max) {
                    *t_max = h.t();
                    best = h.t();
                }
            }
        });
        assert_eq!(best, brute);
        let blocked = |limit: f32| {
            bvh.any_hit(
                ray,
                limit,
                |first, count, t_max| {
                    (first..first + count).any(|k| intersect_triangle(&pre, &ordered[k as usize], t_max).is_some())
                },
                |_, _| {},
            )
        };
        assert!(
            !blocked(if brute.is_finite() { brute * 0.999 } else { 1e30 }),
            "any-hit found something before the closest hit"
        );
        if brute.is_finite() {
            assert!(blocked(brute * 1.001));
        }
        brute
    }

    #[test]
    fn degenerate_inputs() {
        let empty = Bvh::build(&[], &BuildOptions::default());
        assert!(!empty.any_hit(&Ray::new(Vec3::ZERO, Vec3::X), 1.0, |_, _, _| true, |_, _| {}));
        // Many primitives with identical bounds (centroid bounds of zero size) still build.
        let same = vec![Bounds3::new(Vec3::ZERO, Vec3::ONE); 1000];
        let bvh = Bvh::build(&same, &BuildOptions::default());
        assert_eq!(bvh.order().len(), 1000);
        assert!(bvh.stats().max_depth < 64);
    }
}
