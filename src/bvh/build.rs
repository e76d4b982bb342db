//! Binned SAH construction (Wald 2007, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies"): at each node, primitive centroids are binned along each axis and the split
//! minimizing the surface area heuristic is taken; subtrees are built in parallel with rayon.
//! O(n log n) overall. The binary tree is then collapsed into 8-wide nodes.

use super::{Bvh, Node8, WIDTH};
use crate::math::{Bounds3, Vec3};

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

#[derive(Clone, Copy)]
struct Item {
    bounds: Bounds3,
    centroid: Vec3,
    index: u32,
}

enum BuildNode {
    Leaf { bounds: Bounds3, first: u32, count: u32 },
    Interior { bounds: Bounds3, children: Box<[BuildNode; 2]> },
}

pub(super) fn build(bounds: &[Bounds3], opts: &BuildOptions) -> Bvh {
    if bounds.is_empty() {
        return Bvh::default();
    }
    // A primitive whose bounds are not finite (NaN or infinite coordinates) stands in as a point
    // at the origin: every node box stays finite, which the traversal's slab test relies on
    // (its own intersection test then finds no hit).
    let sane = |b: &Bounds3| {
        if b.min.is_finite() && b.max.is_finite() {
            *b
        } else {
            Bounds3::from_point(Vec3::ZERO)
        }
    };
    let mut items: Vec<Item> = bounds
        .iter()
        .map(sane)
        .enumerate()
        .map(|(i, b)| Item { bounds: b, centroid: b.centroid(), index: i as u32 })
        .collect();
    let (root, count) = build_rec(&mut items, 0, 0, opts);
    let mut nodes = Vec::with_capacity(count / 2 + 1);
    collapse(&root, &mut nodes);
    let bounds = match &root {
        BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
    };
    Bvh { nodes: nodes.into(), order: items.iter().map(|it| it.index).collect(), bounds, avx: avx_detected() }
}

/// Whether this CPU runs the AVX slab test.
fn avx_detected() -> bool {
    #[cfg(target_arch = "x86_64")]
    return is_x86_feature_detected!("avx");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

fn leaf(items: &[Item], offset: usize, bounds: Bounds3) -> (BuildNode, usize) {
    (BuildNode::Leaf { bounds, first: offset as u32, count: items.len() as u32 }, 1)
}

fn build_rec(items: &mut [Item], offset: usize, depth: usize, opts: &BuildOptions) -> (BuildNode, usize) {
    let n = items.len();
    let mut bounds = Bounds3::EMPTY;
    let mut cbounds = Bounds3::EMPTY;
    for it in items.iter() {
        bounds = bounds.union(&it.bounds);
        cbounds = cbounds.union_point(it.centroid);
    }
    if n <= 1 || depth >= 60 {
        return leaf(items, offset, bounds);
    }
    let median = |items: &mut [Item], axis: usize| {
        items.select_nth_unstable_by(n / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        (n / 2, axis)
    };
    let (mid, _axis) = match best_split(items, &bounds, &cbounds, opts) {
        Split::Leaf if n <= opts.max_leaf => return leaf(items, offset, bounds),
        // No useful SAH split (or none at all): halve along the largest centroid extent.
        Split::Leaf | Split::Median => median(items, cbounds.max_extent()),
        Split::At { axis, bin } => {
            let (lo, extent) = (cbounds.min[axis], cbounds.diagonal()[axis]);
            let nb = bin_count(opts);
            let mid = partition(items, |it| bin_of(it.centroid[axis], lo, extent, nb) < bin);
            if mid == 0 || mid == n {
                median(items, axis)
            } else {
                (mid, axis)
            }
        }
    };
    let (left, right) = items.split_at_mut(mid);
    let ((l, lc), (r, rc)) = if n > opts.parallel_threshold {
        rayon::join(|| build_rec(left, offset, depth + 1, opts), || build_rec(right, offset + mid, depth + 1, opts))
    } else {
        (build_rec(left, offset, depth + 1, opts), build_rec(right, offset + mid, depth + 1, opts))
    };
    (BuildNode::Interior { bounds, children: Box::new([l, r]) }, 1 + lc + rc)
}

/// Most SAH bins per axis (`BuildOptions::bins` is clamped to it).
const MAX_BINS: usize = 64;

/// The number of bins actually used, the same for finding and for applying a split.
fn bin_count(opts: &BuildOptions) -> usize {
    opts.bins.clamp(2, MAX_BINS)
}

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
fn best_split(items: &[Item], bounds: &Bounds3, cbounds: &Bounds3, opts: &BuildOptions) -> Split {
    let nb = bin_count(opts);
    let n = items.len();
    let extent = cbounds.diagonal();
    if extent.max_element() <= 0.0 {
        return if n <= opts.max_leaf { Split::Leaf } else { Split::Median };
    }
    // Fixed-size bin arrays on the stack: no allocation per node.
    let mut counts = [[0u32; 3]; MAX_BINS];
    let mut boxes = [[Bounds3::EMPTY; 3]; MAX_BINS];
    for it in items {
        for axis in 0..3 {
            if extent[axis] > 0.0 {
                let b = bin_of(it.centroid[axis], cbounds.min[axis], extent[axis], nb);
                counts[b][axis] += 1;
                boxes[b][axis] = boxes[b][axis].union(&it.bounds);
            }
        }
    }
    let group = opts.leaf_group.max(1) as u32;
    let groups = |n: u32| n.div_ceil(group) as f32;
    let parent_area = bounds.surface_area().max(1e-30);
    let mut best = (f32::INFINITY, 0usize, 0usize);
    let mut right_area = [0.0f32; MAX_BINS];
    let mut right_count = [0u32; MAX_BINS];
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        // Suffix sweep: right side of boundary k holds bins k..nb.
        let (mut b, mut c) = (Bounds3::EMPTY, 0u32);
        for k in (1..nb).rev() {
            b = b.union(&boxes[k][axis]);
            c += counts[k][axis];
            right_area[k] = b.surface_area();
            right_count[k] = c;
        }
        let (mut b, mut c) = (Bounds3::EMPTY, 0u32);
        for k in 1..nb {
            b = b.union(&boxes[k - 1][axis]);
            c += counts[k - 1][axis];
            if c == 0 || right_count[k] == 0 {
                continue;
            }
            let cost = opts.traversal_cost
                + (groups(c) * b.surface_area() + groups(right_count[k]) * right_area[k]) / parent_area;
            if cost < best.0 {
                best = (cost, axis, k);
            }
        }
    }
    if !best.0.is_finite() {
        return if n <= opts.max_leaf { Split::Leaf } else { Split::Median };
    }
    if best.0 >= groups(n as u32) && n <= opts.max_leaf {
        return Split::Leaf;
    }
    Split::At { axis: best.1, bin: best.2 }
}

/// Moves the items satisfying `pred` to the front; returns how many there are.
fn partition(items: &mut [Item], pred: impl Fn(&Item) -> bool) -> usize {
    let mut first = 0;
    for i in 0..items.len() {
        if pred(&items[i]) {
            items.swap(first, i);
            first += 1;
        }
    }
    first
}

/// Collapses the binary tree below `node` into 8-wide nodes (Wald et al. 2008, "Getting rid of
/// packets"): each wide node takes its binary node's two children and repeatedly opens the
/// interior child of largest surface area until it holds eight. Returns the wide node's index.
fn collapse(node: &BuildNode, out: &mut Vec<Node8>) -> u32 {
    let mut children: Vec<&BuildNode> = match node {
        BuildNode::Interior { children, .. } => vec![&children[0], &children[1]],
        leaf @ BuildNode::Leaf { .. } => vec![leaf],
    };
    while children.len() < WIDTH {
        let best = children
            .iter()
            .enumerate()
            .filter(|(_, c)| matches!(c, BuildNode::Interior { .. }))
            .max_by(|a, b| area(a.1).total_cmp(&area(b.1)))
            .map(|(i, _)| i);
        let Some(i) = best else { break };
        if let BuildNode::Interior { children: grand, .. } = children[i] {
            children[i] = &grand[0];
            children.insert(i + 1, &grand[1]);
        }
    }
    let index = out.len() as u32;
    out.push(Node8::empty());
    for (slot, child) in children.into_iter().enumerate() {
        match child {
            BuildNode::Leaf { bounds, first, count } => out[index as usize].set(slot, bounds, *first, *count),
            BuildNode::Interior { bounds, .. } => {
                let c = collapse(child, out);
                out[index as usize].set(slot, bounds, c, 0);
            }
        }
    }
    index
}

fn area(n: &BuildNode) -> f32 {
    match n {
        BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => bounds.surface_area(),
    }
}
