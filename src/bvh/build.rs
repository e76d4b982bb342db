//! Binned SAH construction (Wald 2007, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies"): at each node, primitive centroids are binned along each axis and the split
//! minimizing the surface area heuristic is taken; subtrees are built in parallel with rayon.
//! O(n log n) overall. The binary tree is then collapsed into 8-wide nodes by the SAH-optimal
//! dynamic program of Ylitie, Karras and Laine (2017).

use super::{Bvh, Node8, WIDTH};
use crate::math::{Bounds3, Vec3};
use glam::Vec4;

/// Build settings.
#[derive(Clone, Copy, Debug)]
pub struct BuildOptions {
    /// Largest leaf (primitives); larger sets are always split.
    pub max_leaf: usize,
    /// SAH bins per axis (2 to 64).
    pub bins: usize,
    /// Subtrees with more primitives than this are built in parallel.
    pub parallel_threshold: usize,
    /// Cost of a traversal step relative to one primitive intersection.
    pub traversal_cost: f32,
    /// Primitives are intersected in groups of this many at once (SIMD blocks); the SAH
    /// charges a leaf `⌈n / leaf_group⌉` intersections. 1: one at a time.
    pub leaf_group: usize,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions { max_leaf: 8, bins: 16, parallel_threshold: 4096, traversal_cost: 1.0, leaf_group: 1 }
    }
}

/// A primitive during the build: its box as two 4-lane vectors, lanes x, y, z (SSE on x86-64:
/// one instruction unites or averages all three axes), the lower corner's fourth lane holding
/// the primitive's index as bits (32 bytes; no arithmetic reads that lane: [`Item::centroid`]
/// clears it first, and the boxes' fourth lanes are never read).
#[derive(Clone, Copy)]
struct Item {
    lo: Vec4,
    hi: Vec4,
}

impl Item {
    fn new(b: &Bounds3, index: u32) -> Item {
        Item { lo: b.min.extend(f32::from_bits(index)), hi: b.max.extend(0.0) }
    }

    /// The primitive's index.
    #[inline(always)]
    fn index(&self) -> u32 {
        self.lo.w.to_bits()
    }

    /// The box's centre, `0.5 (min + max)` lane by lane as [`Bounds3::centroid`] computes it
    /// (fourth lane 0).
    #[inline(always)]
    fn centroid(&self) -> Vec4 {
        0.5 * (self.lo.with_w(0.0) + self.hi)
    }

    /// One coordinate of [`Item::centroid`] (the same bits).
    #[inline(always)]
    fn centroid_on(&self, axis: usize) -> f32 {
        0.5 * (self.lo[axis] + self.hi[axis])
    }
}

/// A box in the 4-lane form of [`Item`] (lanes x, y, z; the fourth is never read).
#[derive(Clone, Copy)]
struct Box4 {
    lo: Vec4,
    hi: Vec4,
}

impl Box4 {
    const EMPTY: Box4 = Box4 { lo: Vec4::splat(f32::INFINITY), hi: Vec4::splat(f32::NEG_INFINITY) };

    /// Grown to hold the item's box.
    #[inline(always)]
    fn grow(&mut self, it: &Item) {
        self.lo = self.lo.min(it.lo);
        self.hi = self.hi.max(it.hi);
    }

    /// Grown to hold the point `p`.
    #[inline(always)]
    fn grow_point(&mut self, p: Vec4) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    #[inline(always)]
    fn union(&self, o: &Box4) -> Box4 {
        Box4 { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    #[inline(always)]
    fn bounds(&self) -> Bounds3 {
        Bounds3 { min: self.lo.truncate(), max: self.hi.truncate() }
    }
}

/// What the SAH charges a leaf of `grouped` primitives tested in groups of `group` and others
/// of total `weight`: `⌈grouped / group⌉ + weight` group tests.
#[inline]
fn leaf_cost(grouped: u32, weight: f32, group: u32) -> f32 {
    grouped.div_ceil(group) as f32 + weight
}

/// What the binned SAH counts of a set of primitives: what a leaf of them costs.
/// Two kinds, so that a tree of triangles only bins a plain count (its build as fast as before
/// weights existed).
trait Tally: Copy + Default {
    /// The tally of one primitive; `weights` by primitive index ([`build`]'s, checked).
    fn of(it: &Item, weights: &[f32]) -> Self;
    /// The tally of two sets together.
    fn add(self, other: Self) -> Self;
    /// [`leaf_cost`] of a leaf of them.
    fn cost(self, group: u32) -> f32;
}

/// Primitives that are all tested in groups.
#[derive(Clone, Copy, Default)]
struct Grouped(u32);

impl Tally for Grouped {
    #[inline(always)]
    fn of(_: &Item, _: &[f32]) -> Self {
        Grouped(1)
    }
    #[inline(always)]
    fn add(self, other: Self) -> Self {
        Grouped(self.0 + other.0)
    }
    #[inline(always)]
    fn cost(self, group: u32) -> f32 {
        leaf_cost(self.0, 0.0, group)
    }
}

/// Primitives some of which are tested alone: how many are grouped, the others' weight.
#[derive(Clone, Copy, Default)]
struct Weighted {
    grouped: u32,
    weight: f32,
}

impl Tally for Weighted {
    #[inline(always)]
    fn of(it: &Item, weights: &[f32]) -> Self {
        let weight = weights[it.index() as usize];
        Weighted { grouped: u32::from(weight == 0.0), weight }
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Weighted { grouped: self.grouped + o.grouped, weight: self.weight + o.weight }
    }
    #[inline(always)]
    fn cost(self, group: u32) -> f32 {
        leaf_cost(self.grouped, self.weight, group)
    }
}

enum BuildNode {
    Leaf { bounds: Bounds3, first: u32, count: u32 },
    Interior { bounds: Bounds3, children: Box<[BuildNode; 2]> },
}

/// The BVH over primitives of the given bounds. `weights[i]` is what testing primitive `i` costs
/// when it is tested alone, in units of one group test (a
/// [`crate::geometry::triangle8::Triangle8`] block test), or 0 for a primitive tested in SIMD
/// groups of `leaf_group` (triangles); an empty `weights` makes every primitive grouped. The SAH charges a leaf `⌈grouped / leaf_group⌉ +
/// Σ weights`: a curve segment, whose test costs several block tests, then gets a leaf of its
/// own where a group of eight triangles would share one.
pub(super) fn build(bounds: &[Bounds3], weights: &[f32], opts: &BuildOptions) -> Bvh {
    if bounds.is_empty() {
        return Bvh::default();
    }
    // A primitive whose bounds are not finite (NaN or infinite coordinates) stands in as a point
    // at the origin: every node box stays finite, which the traversal's slab test relies on
    // (its own intersection test then finds no hit).
    let sane = |b: &Bounds3| {
        if b.is_finite() {
            *b
        } else {
            Bounds3::from_point(Vec3::ZERO)
        }
    };
    let mut items: Vec<Item> = bounds.iter().map(sane).enumerate().map(|(i, b)| Item::new(&b, i as u32)).collect();
    // Weights by primitive, each finite and positive or 0 (grouped); none (no allocation) if
    // all are grouped, as in a scene of triangles only.
    let tested_alone = |w: &f32| w.is_finite() && *w > 0.0;
    let weights: Vec<f32> = if weights.iter().any(tested_alone) {
        (0..bounds.len()).map(|i| weights.get(i).copied().filter(tested_alone).unwrap_or(0.0)).collect()
    } else {
        Vec::new()
    };
    let (root, count) = if weights.is_empty() {
        build_tree::<Grouped>(&mut items, &weights, opts)
    } else {
        build_tree::<Weighted>(&mut items, &weights, opts)
    };
    let (nodes, _) = collapse(&root, count, &items, &weights, opts);
    let bounds = match &root {
        BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
    };
    Bvh { nodes: nodes.into(), order: items.iter().map(Item::index).collect(), bounds, kernel: super::Kernel::detect() }
}

fn leaf(items: &[Item], offset: usize, bounds: Bounds3) -> (BuildNode, usize) {
    (BuildNode::Leaf { bounds, first: offset as u32, count: items.len() as u32 }, 1)
}

/// The binary tree over `items` (reordered into leaf order), and its node count.
fn build_tree<T: Tally>(items: &mut [Item], weights: &[f32], opts: &BuildOptions) -> (BuildNode, usize) {
    let extents = Extents::of(items);
    build_rec::<T>(items, extents, weights, 0, 0, opts)
}

/// The box of a set of items and the box of their centroids.
#[derive(Clone, Copy)]
struct Extents {
    boxes: Box4,
    centroids: Box4,
}

impl Extents {
    const EMPTY: Extents = Extents { boxes: Box4::EMPTY, centroids: Box4::EMPTY };

    fn of(items: &[Item]) -> Extents {
        let mut e = Extents::EMPTY;
        for it in items {
            e.grow(it);
        }
        e
    }

    #[inline(always)]
    fn grow(&mut self, it: &Item) {
        self.boxes.grow(it);
        self.centroids.grow_point(it.centroid());
    }
}

/// The subtree over `items`, whose [`Extents`] are `extents` (the parent's partition measured
/// them while moving them: each level reads the items twice, to bin and to partition).
fn build_rec<T: Tally>(
    items: &mut [Item],
    extents: Extents,
    weights: &[f32],
    offset: usize,
    depth: usize,
    opts: &BuildOptions,
) -> (BuildNode, usize) {
    let n = items.len();
    let (bounds, cbounds) = (extents.boxes.bounds(), extents.centroids.bounds());
    if n <= 1 || depth >= 60 {
        return leaf(items, offset, bounds);
    }
    let median = |items: &mut [Item], axis: usize| {
        items.select_nth_unstable_by(n / 2, |a, b| a.centroid_on(axis).total_cmp(&b.centroid_on(axis)));
        (n / 2, [Extents::of(&items[..n / 2]), Extents::of(&items[n / 2..])])
    };
    let (mid, sides) = match best_split::<T>(items, weights, &bounds, &cbounds, opts) {
        Split::Leaf if n <= opts.max_leaf => return leaf(items, offset, bounds),
        // No useful SAH split (or none at all): halve along the largest centroid extent.
        Split::Leaf | Split::Median => median(items, cbounds.max_extent()),
        Split::At { axis, bin } => {
            let (lo, extent) = (cbounds.min[axis], cbounds.diagonal()[axis]);
            let nb = bin_count(opts);
            let (mid, sides) = partition(items, |it| bin_of(it.centroid_on(axis), lo, extent, nb) < bin);
            if mid == 0 || mid == n {
                median(items, axis)
            } else {
                (mid, sides)
            }
        }
    };
    let (left, right) = items.split_at_mut(mid);
    let ((l, lc), (r, rc)) = if n > opts.parallel_threshold {
        rayon::join(
            || build_rec::<T>(left, sides[0], weights, offset, depth + 1, opts),
            || build_rec::<T>(right, sides[1], weights, offset + mid, depth + 1, opts),
        )
    } else {
        (
            build_rec::<T>(left, sides[0], weights, offset, depth + 1, opts),
            build_rec::<T>(right, sides[1], weights, offset + mid, depth + 1, opts),
        )
    };
    (BuildNode::Interior { bounds, children: Box::new([l, r]) }, 1 + lc + rc)
}

/// Most SAH bins per axis (`BuildOptions::bins` is clamped to it).
const MAX_BINS: usize = 64;

/// The number of bins actually used, the same for finding and for applying a split.
fn bin_count(opts: &BuildOptions) -> usize {
    opts.bins.clamp(2, MAX_BINS)
}

#[derive(Debug, PartialEq)]
enum Split {
    Leaf,
    Median,
    At { axis: usize, bin: usize },
}

#[inline]
fn bin_of(c: f32, lo: f32, extent: f32, nb: usize) -> usize {
    (((c - lo) / extent * nb as f32) as usize).min(nb - 1)
}

/// The SAH-best bin boundary over the three axes, or `Leaf` when no split beats a leaf.
#[inline]
fn best_split<T: Tally>(
    items: &[Item],
    weights: &[f32],
    bounds: &Bounds3,
    cbounds: &Bounds3,
    opts: &BuildOptions,
) -> Split {
    // Bin arrays on the stack, no larger than the bins in use: most nodes are small, and
    // filling 64 empty bins would cost them more than binning their few primitives.
    if bin_count(opts) <= 16 {
        best_split_in::<T, 16>(items, weights, bounds, cbounds, opts)
    } else {
        best_split_in::<T, MAX_BINS>(items, weights, bounds, cbounds, opts)
    }
}

/// [`best_split`] with at most `N` bins. The sweeps visit only the bins that hold primitives:
/// the boundaries between two of them give one partition, whose cost the first of them (the
/// one a sweep over every bin would keep) stands for, with the same sums and areas — the
/// same split, bit for bit.
fn best_split_in<T: Tally, const N: usize>(
    items: &[Item],
    weights: &[f32],
    bounds: &Bounds3,
    cbounds: &Bounds3,
    opts: &BuildOptions,
) -> Split {
    let nb = bin_count(opts).min(N);
    let n = items.len();
    let extent = cbounds.diagonal();
    if extent.max_element() <= 0.0 {
        return if n <= opts.max_leaf { Split::Leaf } else { Split::Median };
    }
    let mut counts = [[T::default(); 3]; N];
    let mut boxes = [[Box4::EMPTY; 3]; N];
    // Bit b of `filled[axis]`: bin b on that axis holds a primitive.
    let mut filled = [0u64; 3];
    let mut total = T::default();
    // `bin_of` for the three axes at once: (c − lo) / extent · nb lane by lane, the same bits.
    let (lo, scale, nbf) = (cbounds.min.extend(0.0), extent.extend(1.0), nb as f32);
    for it in items {
        let one = T::of(it, weights);
        total = total.add(one);
        let f = (it.centroid() - lo) / scale * nbf;
        for axis in 0..3 {
            if extent[axis] > 0.0 {
                let b = (f[axis] as usize).min(nb - 1);
                counts[b][axis] = counts[b][axis].add(one);
                boxes[b][axis].grow(it);
                filled[axis] |= 1 << b;
            }
        }
    }
    let group = opts.leaf_group.max(1) as u32;
    let parent_area = bounds.surface_area().max(1e-30);
    let mut best = (f32::INFINITY, 0usize, 0usize);
    let mut right_area = [0.0f32; N];
    let mut right_count = [T::default(); N];
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        // Suffix sweep: the right side from filled bin q holds bins q..nb.
        let (mut order, mut m, mut mask) = ([0usize; N], 0, filled[axis]);
        while mask != 0 {
            order[m] = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            m += 1;
        }
        let (mut b, mut c) = (Box4::EMPTY, T::default());
        for &q in order[..m].iter().rev() {
            b = b.union(&boxes[q][axis]);
            c = c.add(counts[q][axis]);
            right_area[q] = b.bounds().surface_area();
            right_count[q] = c;
        }
        // Prefix sweep: the boundary just after filled bin p, with the next filled bin q right.
        let (mut b, mut c) = (Box4::EMPTY, T::default());
        for w in order[..m].windows(2) {
            let (p, q) = (w[0], w[1]);
            b = b.union(&boxes[p][axis]);
            c = c.add(counts[p][axis]);
            let cost = opts.traversal_cost
                + (c.cost(group) * b.bounds().surface_area() + right_count[q].cost(group) * right_area[q])
                    / parent_area;
            if cost < best.0 {
                best = (cost, axis, p + 1);
            }
        }
    }
    if !best.0.is_finite() {
        return if n <= opts.max_leaf { Split::Leaf } else { Split::Median };
    }
    if best.0 >= total.cost(group) && n <= opts.max_leaf {
        return Split::Leaf;
    }
    Split::At { axis: best.1, bin: best.2 }
}

/// Moves the items satisfying `pred` to the front; returns how many there are, and the
/// [`Extents`] of the two sides.
fn partition(items: &mut [Item], pred: impl Fn(&Item) -> bool) -> (usize, [Extents; 2]) {
    let (mut left, mut right) = (Extents::EMPTY, Extents::EMPTY);
    let mut first = 0;
    for i in 0..items.len() {
        let it = items[i];
        if pred(&it) {
            left.grow(&it);
            items.swap(first, i);
            first += 1;
        } else {
            right.grow(&it);
        }
    }
    (first, [left, right])
}

/// A node of the binary tree, flattened for the collapse: its bounds, its primitive range (every
/// subtree covers a contiguous range of [`Bvh::order`]) and its children (none for a leaf).
struct Binary {
    bounds: Bounds3,
    first: u32,
    count: u32,
    /// What a leaf of the subtree's primitives would cost ([`leaf_cost`]).
    leaf_cost: f32,
    children: Option<[usize; 2]>,
}

/// Flattens the binary tree in pre-order (children after their parent); returns the index of
/// `node`. `items` in leaf order give the leaves' costs.
fn flatten(node: &BuildNode, items: &[Item], weights: &[f32], opts: &BuildOptions, out: &mut Vec<Binary>) -> usize {
    let group = opts.leaf_group.max(1) as u32;
    let index = out.len();
    // A subtree's primitives: how many are grouped, and the others' total weight.
    let tally = |first: u32, count: u32| {
        let items = &items[first as usize..(first + count) as usize];
        if weights.is_empty() {
            return (count, 0.0);
        }
        let t = items.iter().fold(Weighted::default(), |t, it| t.add(Weighted::of(it, weights)));
        (t.grouped, t.weight)
    };
    match node {
        BuildNode::Leaf { bounds, first, count } => {
            let (g, w) = tally(*first, *count);
            let leaf_cost = leaf_cost(g, w, group);
            out.push(Binary { bounds: *bounds, first: *first, count: *count, leaf_cost, children: None });
        }
        BuildNode::Interior { bounds, children } => {
            out.push(Binary { bounds: *bounds, first: 0, count: 0, leaf_cost: 0.0, children: None });
            let l = flatten(&children[0], items, weights, opts, out);
            let r = flatten(&children[1], items, weights, opts, out);
            let (first, count) = (out[l].first, out[l].count + out[r].count);
            // Only subtrees small enough to become one leaf need their leaf cost.
            let leaf_cost = if count as usize <= opts.max_leaf {
                let (g, w) = tally(first, count);
                leaf_cost(g, w, group)
            } else {
                f32::INFINITY
            };
            out[index] = Binary { bounds: *bounds, first, count, leaf_cost, children: Some([l, r]) };
        }
    }
    index
}

/// How the collapse represents a binary subtree in `i` slots of a wide node (Ylitie, Karras
/// and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs",
/// §3.1): as one child (`Root`: a leaf or a wide node of its own), as it does in `i - 1` slots
/// (`Fewer`), or split between its binary children, `k` slots to the left one (`Split(k)`).
#[derive(Clone, Copy)]
enum Slots {
    Root,
    Fewer,
    Split(u8),
}

/// The SAH-optimal collapse of the binary tree into 8-wide nodes (Ylitie et al. 2017): for every
/// binary node `n` and slot count `i`, the least cost `C(n, i)` of `n`'s subtree as at most `i`
/// children of a wide node, by dynamic programming bottom-up: `C(n, 1)` is the cheaper of a leaf
/// (area × block tests, where the subtree has at most `max_leaf` primitives) and a wide node
/// (area × node cost + `n`'s binary children spread over eight slots); `C(n, i)` is the cheaper
/// of `C(n, i - 1)` and the best split of the `i` slots between the two children. Unlike opening
/// the largest child greedily (Wald et al. 2008), it fills wide nodes where that pays (small
/// subtrees are pulled up into their parent's free slots, or merged into one leaf) instead of
/// leaving nodes of two or three children near the leaves (a 100k-triangle mesh: 2726 nodes of
/// six children on average instead of 4436 of four). Returns the wide nodes, root first, and
/// the collapse's cost `C(root, 1)`.
fn collapse(
    root: &BuildNode,
    binary_nodes: usize,
    items: &[Item],
    weights: &[f32],
    opts: &BuildOptions,
) -> (Vec<Node8>, f32) {
    let mut bin = Vec::with_capacity(binary_nodes);
    flatten(root, items, weights, opts, &mut bin);
    let node_cost = opts.traversal_cost * WIDE_NODE_STEPS;
    // cost[n][i - 1] = C(n, i); how[n][i - 1] how it is reached; leaf[n]: whether n as one child
    // is a leaf.
    let mut cost = vec![[0.0f32; WIDTH]; bin.len()];
    let mut how = vec![[Slots::Root; WIDTH]; bin.len()];
    let mut leaf = vec![true; bin.len()];
    // open[n]: slots of the left child when n's subtree becomes a wide node (of its eight).
    let mut open = vec![0u8; bin.len()];
    // Pre-order puts children after parents: a reverse sweep sees children first.
    for n in (0..bin.len()).rev() {
        let b = &bin[n];
        let area = b.bounds.surface_area();
        let Some([l, r]) = b.children else {
            cost[n] = [area * b.leaf_cost; WIDTH];
            continue;
        };
        // dist[j - 1]: the best split of j slots between l and r (one slot to the left where no
        // cost compares, as with areas that overflow: every split must give each side a slot).
        let mut dist = [(f32::INFINITY, 1u8); WIDTH];
        for j in 2..=WIDTH {
            for k in 1..j {
                let c = cost[l][k - 1] + cost[r][j - k - 1];
                if c < dist[j - 1].0 {
                    dist[j - 1] = (c, k as u8);
                }
            }
        }
        let as_node = area * node_cost + dist[WIDTH - 1].0;
        open[n] = dist[WIDTH - 1].1;
        let as_leaf = if b.count as usize <= opts.max_leaf { area * b.leaf_cost } else { f32::INFINITY };
        // Never a leaf above `max_leaf` primitives, even where costs do not compare (areas that
        // overflow to infinity or NaN).
        leaf[n] = b.count as usize <= opts.max_leaf && as_node.partial_cmp(&as_leaf) != Some(std::cmp::Ordering::Less);
        cost[n][0] = as_leaf.min(as_node);
        for i in 2..=WIDTH {
            (cost[n][i - 1], how[n][i - 1]) = if dist[i - 1].0 < cost[n][i - 2] {
                (dist[i - 1].0, Slots::Split(dist[i - 1].1))
            } else {
                (cost[n][i - 2], Slots::Fewer)
            };
        }
    }
    let mut nodes = Vec::with_capacity(bin.len() / 4 + 1);
    let plan = Plan { bin: &bin, how: &how, leaf: &leaf, open: &open };
    if leaf[0] {
        // A tree that is one leaf still needs a node to start from.
        nodes.push(Node8::empty());
        nodes[0].set(0, &bin[0].bounds, bin[0].first, bin[0].count);
    } else {
        plan.emit(0, &mut nodes);
    }
    (nodes, cost[0][0])
}

/// Wide-node cost in the collapse, in units of `BuildOptions::traversal_cost` (the cost of a
/// binary traversal step): one slab test checks the eight boxes at once, as a binary step
/// checks two. (It weighs nodes against leaves only: where no subtree could become a leaf, the
/// collapse minimizes the nodes' total area whatever this cost.)
const WIDE_NODE_STEPS: f32 = 1.0;

/// The collapse's decisions, read back top-down into wide nodes.
struct Plan<'a> {
    bin: &'a [Binary],
    how: &'a [[Slots; WIDTH]],
    leaf: &'a [bool],
    open: &'a [u8],
}

impl Plan<'_> {
    /// Writes the wide node of binary node `n` (and, depth first, those below it); returns its
    /// index.
    fn emit(&self, n: usize, out: &mut Vec<Node8>) -> u32 {
        let mut children = Vec::with_capacity(WIDTH);
        self.gather(n, WIDTH, true, &mut children);
        let index = out.len();
        out.push(Node8::empty());
        for (slot, &c) in children.iter().enumerate() {
            let b = &self.bin[c];
            if self.leaf[c] {
                out[index].set(slot, &b.bounds, b.first, b.count);
            } else {
                let child = self.emit(c, out);
                out[index].set(slot, &b.bounds, child, 0);
            }
        }
        index as u32
    }

    /// The children that binary node `n` contributes in `slots` slots (`open`: `n` is the wide
    /// node's own binary node, always split).
    fn gather(&self, n: usize, slots: usize, open: bool, out: &mut Vec<usize>) {
        let how = if open { Slots::Split(self.open[n]) } else { self.how[n][slots - 1] };
        match how {
            Slots::Root => out.push(n),
            Slots::Fewer => self.gather(n, slots - 1, false, out),
            Slots::Split(k) => {
                let [l, r] = self.bin[n].children.expect("only interior nodes split");
                self.gather(l, k as usize, false, out);
                self.gather(r, slots - k as usize, false, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    /// Random boxes of mixed sizes, clustered so that the binary tree is uneven.
    fn boxes(n: usize, seed: u64) -> Vec<Bounds3> {
        let mut rng = Pcg32::new(seed, 0);
        let mut f = || rng.next_f32();
        (0..n)
            .map(|i| {
                let cluster = Vec3::splat((i % 7) as f32 * 3.0);
                let c = cluster + Vec3::new(f(), f(), f()) * 2.0;
                let h = Vec3::new(f(), f(), f()) * if i % 13 == 0 { 1.0 } else { 0.05 };
                Bounds3::new(c - h, c + h)
            })
            .collect()
    }

    /// Whether each of the `n` primitives lies in exactly one leaf of `nodes`.
    fn each_in_one_leaf(nodes: &[Node8], n: usize) -> bool {
        let mut covered = vec![0u32; n];
        for node in nodes {
            for slot in (0..WIDTH).filter(|&s| node.valid(s) && node.count[s] > 0) {
                for k in node.child[slot]..node.child[slot] + node.count[slot] {
                    covered[k as usize] += 1;
                }
            }
        }
        covered.iter().all(|&c| c == 1)
    }

    /// Cost and node count of the greedy collapse (Wald et al. 2008: open the interior child of
    /// largest area until eight), in the dynamic program's cost model.
    fn greedy_cost(node: &BuildNode, node_cost: f32, group: u32) -> (f32, usize) {
        let area = |n: &BuildNode| match n {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => bounds.surface_area(),
        };
        let mut children: Vec<&BuildNode> = match node {
            BuildNode::Interior { children, .. } => vec![&children[0], &children[1]],
            leaf => vec![leaf],
        };
        while children.len() < WIDTH {
            let open = (0..children.len())
                .filter(|&i| matches!(children[i], BuildNode::Interior { .. }))
                .max_by(|&a, &b| area(children[a]).total_cmp(&area(children[b])));
            let Some(i) = open else { break };
            if let BuildNode::Interior { children: grand, .. } = children[i] {
                children[i] = &grand[0];
                children.insert(i + 1, &grand[1]);
            }
        }
        let (mut cost, mut nodes) = (area(node) * node_cost, 1);
        for c in children {
            match c {
                BuildNode::Leaf { bounds, count, .. } => cost += bounds.surface_area() * count.div_ceil(group) as f32,
                BuildNode::Interior { .. } => {
                    let (c, n) = greedy_cost(c, node_cost, group);
                    cost += c;
                    nodes += n;
                }
            }
        }
        (cost, nodes)
    }

    /// The wide tree written is the one the dynamic program costed: its nodes' areas times the
    /// node cost plus its leaves' areas times their block tests add up to `C(root, 1)` (a
    /// read-back that put a subtree in the wrong slots would not). Every primitive lies in one
    /// leaf; the cost is at most the greedy collapse's, with fewer nodes. In the weighted case
    /// every fifth primitive is tested alone at the cost of 2.5 group tests (a curve among
    /// triangles); the greedy collapse's cost (per group only) does not compare there.
    #[test]
    fn collapse_writes_the_costed_tree() {
        for (n, opts, weighted) in [
            (3000, BuildOptions { leaf_group: 8, ..Default::default() }, false),
            (3000, BuildOptions { traversal_cost: 0.3, leaf_group: 4, ..Default::default() }, false),
            (500, BuildOptions::default(), false),
            (3000, BuildOptions { traversal_cost: 0.3, leaf_group: 4, ..Default::default() }, true),
        ] {
            let bounds = boxes(n, n as u64);
            let weights: Vec<f32> =
                (0..n).filter(|_| weighted).map(|i| if i.is_multiple_of(5) { 2.5 } else { 0.0 }).collect();
            let weight = |i: u32| weights.get(i as usize).copied().unwrap_or(0.0);
            let mut items: Vec<Item> = bounds.iter().enumerate().map(|(i, b)| Item::new(b, i as u32)).collect();
            let (root, count) = if weighted {
                build_tree::<Weighted>(&mut items, &weights, &opts)
            } else {
                build_tree::<Grouped>(&mut items, &weights, &opts)
            };
            let (nodes, cost) = collapse(&root, count, &items, &weights, &opts);
            let group = opts.leaf_group.max(1) as u32;
            let node_cost = opts.traversal_cost * WIDE_NODE_STEPS;
            let root_bounds = match &root {
                BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
            };
            let mut total = root_bounds.surface_area() * node_cost;
            let mut children = 0;
            for node in &nodes {
                for slot in (0..WIDTH).filter(|&s| node.valid(s)) {
                    children += 1;
                    let area = node.child_bounds(slot).surface_area();
                    if node.count[slot] > 0 {
                        let (first, count) = (node.child[slot] as usize, node.count[slot] as usize);
                        let leaf = &items[first..first + count];
                        let grouped = leaf.iter().filter(|it| weight(it.index()) == 0.0).count() as u32;
                        let weight: f32 = leaf.iter().map(|it| weight(it.index())).sum();
                        total += area * leaf_cost(grouped, weight, group);
                    } else {
                        total += area * node_cost;
                    }
                }
            }
            assert!((total - cost).abs() <= 1e-4 * cost, "{n}: written {total}, costed {cost}");
            assert!(each_in_one_leaf(&nodes, n), "{n}: every primitive in exactly one leaf");
            let fill = children as f32 / nodes.len() as f32;
            if !weighted {
                let (greedy, _) = greedy_cost(&root, node_cost, group);
                assert!(cost <= greedy * (1.0 + 1e-5), "{n}: optimal {cost} above greedy {greedy}");
            }
            let (_, greedy_nodes) = greedy_cost(&root, node_cost, group);
            assert!(nodes.len() < greedy_nodes, "{n}: {} nodes, greedy {greedy_nodes}", nodes.len());
            assert!(fill > 4.0, "{n}: {fill} children per node");
        }
    }

    /// Primitives that cost more than a group test each get smaller leaves than grouped ones
    /// (their SAH charges each test): leaves of curve segments hold one or two where triangles
    /// fill blocks of eight.
    #[test]
    fn weighted_primitives_get_small_leaves() {
        let bounds = boxes(2000, 5);
        let opts = BuildOptions { traversal_cost: 1.0, leaf_group: 8, ..Default::default() };
        let mean_leaf = |weights: &[f32]| {
            let bvh = build(&bounds, weights, &opts);
            assert!(each_in_one_leaf(&bvh.nodes, bounds.len()));
            let leaves: Vec<u32> = bvh.nodes.iter().flat_map(|n| n.count).filter(|&c| c > 0).collect();
            leaves.iter().sum::<u32>() as f32 / leaves.len() as f32
        };
        let grouped = mean_leaf(&[]);
        let curves = mean_leaf(&vec![3.0; bounds.len()]);
        assert!(grouped > 3.0 && curves < 1.6, "mean leaf: grouped {grouped}, weighted {curves}");
        // Non-finite and negative weights count as grouped.
        let odd = mean_leaf(&vec![f32::NAN; bounds.len()]);
        assert_eq!(odd, grouped);
    }

    /// Trees of one, two and a few primitives (a root that is one leaf, a root whose children
    /// are all leaves) collapse into nodes that hold every primitive once.
    /// The binned SAH as a sweep over every bin boundary computes it, in scalar arithmetic:
    /// the reference [`best_split`] must agree with.
    fn full_sweep_split<T: Tally>(items: &[Item], weights: &[f32], opts: &BuildOptions) -> Split {
        let item_bounds = |it: &Item| Bounds3::new(it.lo.truncate(), it.hi.truncate());
        let bounds = items.iter().fold(Bounds3::EMPTY, |b, it| b.union(&item_bounds(it)));
        let cbounds = items.iter().fold(Bounds3::EMPTY, |b, it| b.union_point(item_bounds(it).centroid()));
        let (nb, n, extent) = (bin_count(opts), items.len(), cbounds.diagonal());
        if extent.max_element() <= 0.0 {
            return if n <= opts.max_leaf { Split::Leaf } else { Split::Median };
        }
        let mut counts = vec![[(0u32, T::default()); 3]; nb];
        let mut boxes = vec![[Bounds3::EMPTY; 3]; nb];
        for it in items {
            for axis in (0..3).filter(|&a| extent[a] > 0.0) {
                let b = bin_of(item_bounds(it).centroid()[axis], cbounds.min[axis], extent[axis], nb);
                counts[b][axis] = (counts[b][axis].0 + 1, counts[b][axis].1.add(T::of(it, weights)));
                boxes[b][axis] = boxes[b][axis].union(&item_bounds(it));
            }
        }
        let group = opts.leaf_group.max(1) as u32;
        let mut best = (f32::INFINITY, 0, 0);
        for axis in (0..3).filter(|&a| extent[a] > 0.0) {
            for k in 1..nb {
                let side = |range: std::ops::Range<usize>| {
                    range.fold((Bounds3::EMPTY, 0u32, T::default()), |(b, n, t), j| {
                        (b.union(&boxes[j][axis]), n + counts[j][axis].0, t.add(counts[j][axis].1))
                    })
                };
                let ((lb, ln, lt), (rb, rn, rt)) = (side(0..k), side(k..nb));
                if ln == 0 || rn == 0 {
                    continue;
                }
                let cost = opts.traversal_cost
                    + (lt.cost(group) * lb.surface_area() + rt.cost(group) * rb.surface_area())
                        / bounds.surface_area().max(1e-30);
                if cost < best.0 {
                    best = (cost, axis, k);
                }
            }
        }
        let total = items.iter().fold(T::default(), |t, it| t.add(T::of(it, weights)));
        if !best.0.is_finite() {
            return if n <= opts.max_leaf { Split::Leaf } else { Split::Median };
        }
        if best.0 >= total.cost(group) && n <= opts.max_leaf {
            return Split::Leaf;
        }
        Split::At { axis: best.1, bin: best.2 }
    }

    /// The split search (4-lane binning, sweeps over the filled bins only) takes the split a
    /// plain sweep over every bin boundary takes, on sets of 2 to 404 boxes (clustered, so many
    /// bins stay empty; some flat along an axis), plain and weighted, for several bin counts.
    #[test]
    fn split_search_agrees_with_a_full_sweep() {
        let mut rng = Pcg32::new(11, 3);
        let mut splits = 0;
        for trial in 0..300 {
            let n = [2, 3, 5, 9, 17, 40, 120, 400][trial as usize % 8] + (rng.next_f32() * 5.0) as usize;
            let mut bounds = boxes(n, trial);
            if trial % 5 == 0 {
                for b in &mut bounds {
                    (b.min.y, b.max.y) = (1.0, 1.0);
                }
            }
            let weights: Vec<f32> =
                if trial % 2 == 0 { Vec::new() } else { (0..n).map(|i| if i % 3 == 0 { 1.75 } else { 0.0 }).collect() };
            let bins = [16, 5, 40, 64][trial as usize / 8 % 4];
            let opts = BuildOptions { bins, leaf_group: 8, traversal_cost: 0.3, ..Default::default() };
            let items: Vec<Item> = bounds.iter().enumerate().map(|(i, b)| Item::new(b, i as u32)).collect();
            let e = Extents::of(&items);
            let (b, c) = (e.boxes.bounds(), e.centroids.bounds());
            let (fast, full) = if weights.is_empty() {
                (
                    best_split::<Grouped>(&items, &weights, &b, &c, &opts),
                    full_sweep_split::<Grouped>(&items, &weights, &opts),
                )
            } else {
                (
                    best_split::<Weighted>(&items, &weights, &b, &c, &opts),
                    full_sweep_split::<Weighted>(&items, &weights, &opts),
                )
            };
            assert_eq!(fast, full, "trial {trial}: {n} boxes, {bins} bins");
            splits += usize::from(matches!(fast, Split::At { .. }));
        }
        assert!(splits > 150, "only {splits} of the sets were split");
    }

    #[test]
    fn tiny_trees_collapse() {
        for n in [1, 2, 3, 9, 17] {
            let bvh = build(&boxes(n, 7), &[], &BuildOptions::default());
            assert!(each_in_one_leaf(&bvh.nodes, n), "{n}");
        }
    }

    /// Boxes near the largest finite coordinates, whose areas overflow to infinity or NaN (no
    /// cost compares), still collapse into a tree of nodes (not one leaf of everything) that
    /// holds every primitive once, in leaves of at most `max_leaf`.
    #[test]
    fn overflowing_areas_collapse() {
        let mut bounds = boxes(300, 3);
        for (i, b) in bounds.iter_mut().enumerate().filter(|(i, _)| i % 3 == 0) {
            let big = Vec3::new(3.0e38, if i % 2 == 0 { 0.0 } else { -3.0e38 }, 1.0);
            *b = Bounds3::new(-big, big);
        }
        let bvh = build(&bounds, &[], &BuildOptions::default());
        assert!(each_in_one_leaf(&bvh.nodes, bounds.len()));
        let largest = bvh.nodes.iter().flat_map(|n| n.count).max().unwrap();
        assert!(largest as usize <= BuildOptions::default().max_leaf, "a leaf of {largest} primitives");
        assert!(bvh.nodes.len() > 5, "{} nodes", bvh.nodes.len());
    }
}
