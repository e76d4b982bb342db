//! Triangle pre-splitting (Karras and Aila 2013, "Fast Parallel Construction of High-Quality
//! Bounding Volume Hierarchies", §4): before the build, a large triangle whose bounding box is
//! mostly empty space (a long diagonal sliver, a tilted wall) is entered as several references,
//! each bounding the part of the triangle on one side of a spatial split plane. The build sees
//! tight boxes, and a ray near such a triangle no longer enters every node it overlaps.
//!
//! The budget of extra references (a fraction of the triangle count) goes to the triangles with
//! the most empty box area: the box's surface area minus the least total area its pieces could
//! reach (`2 A (|nₓ| + |n_y| + |n_z|)` for a triangle of area `A` and unit normal `n`, the sum of
//! its three axis projections, both sides), weighted by how coarse a plane of the global grid
//! crosses the triangle (a triangle across one of the scene's main planes is split first: the
//! build's upper levels split there too). Each triangle is split recursively along its box's
//! longest axis at the coarsest grid plane inside the box, the piece (a convex polygon) clipped
//! on each side and bounded, widened by the round-off of its clipped vertices; the remaining
//! splits go to the sides in proportion to their boxes' lengths.

use crate::math::{Bounds3, Vec3};

/// A reference to primitive `prim` with bounds covering part of it (all of it, unless split).
#[derive(Clone, Copy, Debug)]
pub struct Reference {
    /// Bounds of the part of the primitive this reference stands for.
    pub bounds: Bounds3,
    /// The primitive.
    pub prim: u32,
}

/// References for primitives with the given `bounds`, where `triangle(i)` gives primitive `i`'s
/// vertices if it is a triangle (other primitives are never split): every primitive once, plus
/// up to `budget · n` extra references for the triangles whose boxes waste the most area. Each
/// primitive's references cover it (their union contains every point of it).
pub fn presplit(bounds: &[Bounds3], triangle: impl Fn(usize) -> Option<[Vec3; 3]>, budget: f32) -> Vec<Reference> {
    let whole = |i: usize| Reference { bounds: bounds[i], prim: i as u32 };
    let scene = bounds.iter().filter(|b| b.is_finite()).fold(Bounds3::EMPTY, |a, b| a.union(b));
    let scene_area = scene.surface_area();
    let extra = (budget.max(0.0) * bounds.len() as f32) as usize;
    // (A scene whose box area overflows is left whole too: the priorities would not compare.)
    if extra == 0 || !scene_area.is_finite() || scene_area <= 0.0 {
        return (0..bounds.len()).map(whole).collect();
    }
    let grid = Grid { lo: scene.min, inv: scene.diagonal().recip() };
    let threshold = MIN_WASTE * scene_area;
    // Priority of each triangle: (2^-level · wasted area)^(1/3), Karras and Aila's eq. 1.
    let priority: Vec<f32> = (0..bounds.len())
        .map(|i| {
            let (Some(p), b) = (triangle(i), bounds[i]) else { return 0.0 };
            if !b.is_finite() {
                return 0.0;
            }
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let ideal = n.abs().element_sum();
            let wasted = (b.surface_area() - ideal).max(0.0);
            if wasted < threshold {
                return 0.0;
            }
            let level = grid.plane(&b, b.max_extent()).map_or(24, |(_, level)| level);
            // Finite within a finite scene box; checked all the same (an infinite priority would
            // stall the bisection below).
            let p = (wasted * (-(level as f32)).exp2()).cbrt();
            if p.is_finite() {
                p
            } else {
                0.0
            }
        })
        .collect();
    let total: f64 = priority.iter().map(|&p| f64::from(p)).sum();
    if total.is_nan() || total <= 0.0 {
        return (0..bounds.len()).map(whole).collect();
    }
    // The largest scale D whose splits ⌊D pᵢ⌋ stay within the budget (bisection, as Karras and
    // Aila do: with D = budget / Σp most triangles would round down to no split at all).
    // Where every candidate can take `MAX_SPLITS` within the budget (a few large triangles among
    // many small ones), each is given them.
    let used = |d: f64| priority.iter().map(|&p| ((f64::from(p) * d) as u64).min(u64::from(MAX_SPLITS))).sum::<u64>();
    let candidates = priority.iter().filter(|&&p| p > 0.0).count() as u64;
    let scale = if candidates * u64::from(MAX_SPLITS) <= extra as u64 {
        f64::MAX
    } else {
        // used(lo) ≤ extra (⌊D pᵢ⌋ ≤ D pᵢ, summing to the budget); doubling reaches a scale
        // beyond it (the caps alone exceed the budget).
        let (mut lo, mut hi) = (extra as f64 / total, extra as f64 / total);
        // (At most 2000 doublings: f64's whole range, whatever the priorities.)
        for _ in 0..2000 {
            if used(hi) > extra as u64 {
                break;
            }
            hi *= 2.0;
        }
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if used(mid) <= extra as u64 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    };
    let mut out = Vec::with_capacity(bounds.len() + extra);
    for (i, &p) in priority.iter().enumerate() {
        // (Only a candidate, p > 0, has splits: the others' vertices are not fetched again.)
        let splits = (f64::from(p) * scale) as u32;
        let tri = if splits > 0 { triangle(i) } else { None };
        match tri {
            Some(tri) => split(&tri, bounds[i], 0.0, splits.min(MAX_SPLITS), &grid, i as u32, &mut out),
            None => out.push(whole(i)),
        }
    }
    out
}

/// The least wasted box area, relative to the surface area of the scene's bounds, for which a
/// triangle is split. Smaller ones are left whole: a finely tessellated mesh (each triangle's
/// box a ten-thousandth of the scene's) then builds as before, where splitting a third of its
/// triangles measured 5–15 % fewer rays/s (more references and leaves for no tighter tree);
/// the slivers and tilted walls that do waste area still are split (a floor of 1500 tilted
/// sticks, 7–13 % faster; `caustics`, 11 % fewer instructions).
const MIN_WASTE: f32 = 1e-3;

/// Most splits of one triangle (references beyond one).
const MAX_SPLITS: u32 = 255;

/// The global grid of split planes: the scene's bounds, halved recursively along each axis.
struct Grid {
    lo: Vec3,
    inv: Vec3,
}

impl Grid {
    /// The coarsest grid plane strictly inside `b` along `axis`: its coordinate and its level
    /// (1: the scene's midplane, 2: the quarter planes, …); `None` if none within 24 levels.
    fn plane(&self, b: &Bounds3, axis: usize) -> Option<(f32, u32)> {
        let (lo, inv) = (self.lo[axis], self.inv[axis]);
        if !inv.is_finite() {
            return None;
        }
        let (a, c) = ((b.min[axis] - lo) * inv, (b.max[axis] - lo) * inv);
        for level in 1..=24u32 {
            let cells = (1u32 << level) as f32;
            let k = (c * cells).floor();
            if k > a * cells && k < c * cells {
                let pos = lo + k / cells / inv;
                if pos > b.min[axis] && pos < b.max[axis] {
                    return Some((pos, level));
                }
            }
        }
        None
    }
}

/// Splits the piece `poly` of a triangle (a convex polygon, its vertices within `err` of the
/// exact piece's, which lies in the box `b`) `splits` times, pushing one reference per piece.
fn split(poly: &[Vec3], b: Bounds3, err: f32, splits: u32, grid: &Grid, prim: u32, out: &mut Vec<Reference>) {
    let axis = b.max_extent();
    let Some((pos, _)) = grid.plane(&b, axis).filter(|_| splits > 0) else {
        out.push(Reference { bounds: b, prim });
        return;
    };
    // Crossing points are rounded once more: their error grows by a few ulps of the triangle.
    let err = err + err_step(poly);
    let (below, above) = clip(poly, axis, pos);
    let bound = |piece: &[Vec3]| {
        let pad = Vec3::splat(err);
        let tight = piece.iter().fold(Bounds3::EMPTY, |acc, &v| acc.union(&Bounds3::new(v - pad, v + pad)));
        tight.intersection(&b)
    };
    let (left, right) = (bound(&below), bound(&above));
    let nonempty = |x: &Bounds3| x.min.cmple(x.max).all();
    if !below.is_empty() && !above.is_empty() && nonempty(&left) && nonempty(&right) {
        let rest = splits - 1;
        let (wl, wr) = (left.diagonal().max_element(), right.diagonal().max_element());
        let to_left = if wl + wr > 0.0 { ((rest as f32 * wl / (wl + wr)).round() as u32).min(rest) } else { 0 };
        split(&below, left, err, to_left, grid, prim, out);
        split(&above, right, err, rest - to_left, grid, prim, out);
    } else {
        // The plane missed the piece (within round-off): it stays whole.
        out.push(Reference { bounds: b, prim });
    }
}

/// A bound on the error one clipping adds to a crossing point of the polygon's edges: four
/// ulps of its largest coordinate.
fn err_step(poly: &[Vec3]) -> f32 {
    poly.iter().fold(0.0f32, |m, v| m.max(v.abs().max_element())) * (4.0 * f32::EPSILON)
}

/// The parts of the convex polygon `poly` below and above the plane `x[axis] = pos`
/// (Sutherland–Hodgman): vertices on the plane and the edges' crossing points (at exactly
/// `pos` along `axis`, rounded in the other coordinates) belong to both. A part is empty where
/// the polygon lies entirely on the other side.
fn clip(poly: &[Vec3], axis: usize, pos: f32) -> (Vec<Vec3>, Vec<Vec3>) {
    let (mut below, mut above) = (Vec::with_capacity(poly.len() + 1), Vec::with_capacity(poly.len() + 1));
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (da, db) = (a[axis] - pos, b[axis] - pos);
        if da <= 0.0 {
            below.push(a);
        }
        if da >= 0.0 {
            above.push(a);
        }
        if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
            let mut x = a + (b - a) * (da / (da - db));
            x[axis] = pos;
            below.push(x);
            above.push(x);
        }
    }
    (below, above)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{BuildOptions, Bvh};
    use crate::math::Ray;
    use crate::sampling::Pcg32;

    fn bounds_of(t: &[Vec3; 3]) -> Bounds3 {
        Bounds3::from_point(t[0]).union_point(t[1]).union_point(t[2])
    }

    /// Long thin triangles at random angles (the halves of tilted sticks), with small ones among
    /// them: the case splitting is for.
    fn slivers(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut rng = Pcg32::new(seed, 0);
        let mut v = |s: f32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * s - s / 2.0;
        (0..n)
            .map(|i| {
                let c = v(4.0);
                if i % 3 == 0 {
                    [c, c + v(0.1), c + v(0.1)]
                } else {
                    let d = v(2.0);
                    let w = v(0.02);
                    [c - d, c + d, c + d + w]
                }
            })
            .collect()
    }

    /// Every reference lies within its primitive's box, no primitive is lost, the budget holds,
    /// slivers are split, and every point of every triangle (vertices, edge points, interior
    /// points) lies in one of its references' boxes.
    #[test]
    fn references_cover_their_triangles() {
        let tris = slivers(600, 1);
        let bounds: Vec<Bounds3> = tris.iter().map(bounds_of).collect();
        let refs = presplit(&bounds, |i| Some(tris[i]), 0.3);
        assert!(refs.len() > tris.len() + 100, "slivers are split: {} references", refs.len());
        assert!(refs.len() <= tris.len() + (0.3 * tris.len() as f32) as usize, "{} references", refs.len());
        let mut of: Vec<Vec<Bounds3>> = vec![Vec::new(); tris.len()];
        for r in &refs {
            let whole = bounds[r.prim as usize];
            assert!(r.bounds.min.cmpge(whole.min).all() && r.bounds.max.cmple(whole.max).all());
            of[r.prim as usize].push(r.bounds);
        }
        let mut rng = Pcg32::new(2, 0);
        for (t, boxes) in tris.iter().zip(&of) {
            assert!(!boxes.is_empty());
            // Within the round-off of computing `p` from the vertices (a few of their ulps).
            let e = t[0].abs().max(t[1].abs()).max(t[2].abs()) * (4.0 * f32::EPSILON);
            let inside = |p: Vec3| boxes.iter().any(|b| (p + e).cmpge(b.min).all() && (p - e).cmple(b.max).all());
            for k in 0..200 {
                let (a, b) = (rng.next_f32(), rng.next_f32());
                let (a, b) = if k < 3 {
                    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)][k]
                } else if k < 60 {
                    (a, 0.0)
                } else if a + b > 1.0 {
                    (1.0 - a, 1.0 - b)
                } else {
                    (a, b)
                };
                let p = t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b;
                assert!(inside(p), "{p} of {t:?} is in none of {boxes:?}");
            }
        }
    }

    /// One sliver among many small triangles: it takes (nearly) the most splits, the budget
    /// allowing them all, and nothing else is split.
    #[test]
    fn few_large_triangles_take_the_most_splits() {
        let mut tris = slivers(3000, 5);
        for t in tris.iter_mut().skip(2) {
            // All but the first two (a small one and a sliver) shrink.
            *t = [t[0], t[0] + (t[1] - t[0]) * 0.001, t[0] + (t[2] - t[0]) * 0.001];
        }
        let bounds: Vec<Bounds3> = tris.iter().map(bounds_of).collect();
        let refs = presplit(&bounds, |i| Some(tris[i]), 0.3);
        let of_sliver = refs.iter().filter(|r| r.prim == 1).count();
        // (A few pieces end early: planes that only cut a piece's round-off margin.)
        assert!(of_sliver > MAX_SPLITS as usize * 9 / 10, "{of_sliver} pieces");
        assert_eq!(refs.len(), tris.len() + of_sliver - 1);
    }

    /// Hostile coordinates (a scene box whose area overflows, NaN and infinite vertices,
    /// degenerate triangles) neither hang nor panic, and every primitive keeps a reference.
    #[test]
    fn hostile_triangles_are_safe() {
        let (nan, inf) = (f32::NAN, f32::INFINITY);
        let huge = 1e30;
        let soups: [Vec<[Vec3; 3]>; 3] = [
            vec![
                [Vec3::ZERO, Vec3::splat(huge), Vec3::new(huge, 0.0, 1.0)],
                // Collinear: no area, a box whose area overflows.
                [Vec3::ZERO, Vec3::splat(1e20), Vec3::splat(2e20)],
                // Nearly collinear: a finite area in a box whose area overflows (an infinite
                // priority, which stalled the bisection before it was guarded).
                [Vec3::ZERO, Vec3::splat(1e19), Vec3::new(1e19, 1e19, 1.0001e19)],
                [Vec3::ZERO, Vec3::X, Vec3::Y],
                [Vec3::splat(-huge), Vec3::ZERO, Vec3::new(0.0, huge, 0.0)],
            ],
            vec![
                [Vec3::ZERO, Vec3::splat(nan), Vec3::X],
                [Vec3::ZERO, Vec3::new(inf, 0.0, 0.0), Vec3::Y],
                [Vec3::ZERO, Vec3::new(4.0, 3.0, 2.0), Vec3::new(0.01, 0.0, 0.0)],
            ],
            // Collinear and repeated vertices, long and tilted.
            vec![
                [Vec3::ZERO, Vec3::splat(5.0), Vec3::splat(10.0)],
                [Vec3::splat(3.0); 3],
                [Vec3::new(-5.0, 0.0, 1.0), Vec3::new(5.0, 7.0, -3.0), Vec3::new(5.0, 7.01, -3.0)],
            ],
        ];
        for tris in soups {
            let bounds: Vec<Bounds3> = tris.iter().map(bounds_of).collect();
            for budget in [10.0, 100.0] {
                let refs = presplit(&bounds, |i| Some(tris[i]), budget);
                for i in 0..tris.len() {
                    assert!(refs.iter().any(|r| r.prim == i as u32), "primitive {i} lost");
                }
            }
        }
    }

    /// A finely tessellated surface wastes no box area worth splitting: it is left as it is.
    #[test]
    fn fine_meshes_stay_whole() {
        let mut tris = Vec::new();
        let n = 60;
        for i in 0..n {
            for j in 0..n {
                let p = |a: usize, b: usize| {
                    let (u, v) = (a as f32 / n as f32 * std::f32::consts::TAU, 0.05 + b as f32 / n as f32 * 3.0);
                    Vec3::new(v.sin() * u.cos(), v.cos(), v.sin() * u.sin())
                };
                tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        let bounds: Vec<Bounds3> = tris.iter().map(bounds_of).collect();
        assert_eq!(presplit(&bounds, |i| Some(tris[i]), 0.3).len(), tris.len());
    }

    /// A BVH over the references of slivers has a lower SAH cost than over whole triangles,
    /// and finds the same closest hits as a brute-force search (and no hit before them).
    #[test]
    fn split_trees_are_tighter_and_trace_alike() {
        let tris = slivers(2000, 3);
        let bounds: Vec<Bounds3> = tris.iter().map(bounds_of).collect();
        let refs = presplit(&bounds, |i| Some(tris[i]), 0.3);
        let ref_bounds: Vec<Bounds3> = refs.iter().map(|r| r.bounds).collect();
        let opts = BuildOptions::default();
        let (whole, split) = (Bvh::build(&bounds, &opts), Bvh::build(&ref_bounds, &opts));
        let (c0, c1) = (whole.stats().sah_cost, split.stats().sah_cost);
        assert!(c1 < 0.8 * c0, "SAH cost {c0} unsplit, {c1} split");
        let ordered: Vec<[Vec3; 3]> = split.order().iter().map(|&k| tris[refs[k as usize].prim as usize]).collect();
        let mut rng = Pcg32::new(4, 0);
        let mut hits = 0;
        for _ in 0..3000 {
            // From anywhere toward a point on a random triangle (most rays hit something).
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 8.0 - 4.0;
            let t = tris[(rng.next_f32() * tris.len() as f32) as usize % tris.len()];
            let (a, b) = (rng.next_f32() * 0.5, rng.next_f32() * 0.5);
            let ray = Ray::new(o, (t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b - o).normalize());
            hits += usize::from(crate::bvh::tests::traces_like_brute_force(&split, &tris, &ordered, &ray).is_finite());
        }
        assert!(hits > 2000, "{hits} rays hit");
    }
}
