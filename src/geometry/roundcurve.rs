//! Mitsuba 3's `linearcurve`: round tubes along polylines, their radius varying linearly along
//! each segment (hair, fur, wires), hit as Embree's round linear curves are.
//!
//! - A curve is a list of control points `(pᵢ, rᵢ)` (world-space centre, radius in world
//!   units: `to_world` moves the points and leaves the radii alone, as in Mitsuba). Segment
//!   `k` joins two consecutive points of a curve; each segment is one primitive of the BVH.
//! - A segment's solid is the sweep of the sphere of centre `c(v) = lerp(v, p₀, p₁)` and radius
//!   `r(v) = lerp(v, r₀, r₁)`, `v ∈ [0, 1]`: the convex hull of its two end spheres, bounded by
//!   the cone tangent to both and by the spheres' outer caps. Consecutive segments share their
//!   joint's sphere, so a curve is smooth at its joints and ends in round caps.
//! - Only entries count (Embree and Mitsuba cull back faces): a ray that starts inside a tube
//!   does not hit it.
//! - A hit's `v` is the parameter of the swept sphere that touches the surface there (0 or 1 on
//!   the caps), so that the normal is `(p − c(v)) / r(v)`. Mitsuba's (u, v): `u` the angle
//!   about the segment's axis in the frame [`local_frame`] builds (its reference direction
//!   toward +z) over 2π, `v = (k + v_segment) / segments` along all the shape's segments.
//!   Mitsuba 3.9.1 gives no `∂p/∂u`, `∂p/∂v` on curves: the shading frame is built around the
//!   normal alone, as here.
//! - The ray is solved in double precision relative to the segment's first point (thin tubes
//!   far from the origin stay exact); the hit point is on the ray, as in Mitsuba.
//!
//! Curves have no area to sample: they cannot be area emitters (Mitsuba gives them no area).

use super::curve::CurveHit;
use crate::math::float::gamma;
use crate::math::{Bounds3, Ray, Transform, Vec2, Vec3};
use glam::DVec3;

/// A control point: centre and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlPoint {
    /// Centre (world space once placed).
    pub p: Vec3,
    /// Radius (world units; not scaled by `to_world`).
    pub r: f32,
}

/// Placed linear round curves: control points and the segments joining them.
#[derive(Clone, Debug)]
pub struct LinearCurves {
    points: Vec<ControlPoint>,
    /// Segment `k` joins `points[first[k]]` and `points[first[k] + 1]`.
    first: Vec<u32>,
}

/// Geometry of a hit on a round curve (linear or B-spline).
#[derive(Clone, Copy, Debug)]
pub struct RoundCurveSurface {
    /// The point (on the ray).
    pub p: Vec3,
    /// Its error bound.
    pub p_error: Vec3,
    /// Unit outward normal.
    pub n: Vec3,
    /// Mitsuba's (u, v): around the curve, along all segments.
    pub uv: Vec2,
    /// `∂p/∂u` (around; zero on linear curves, as Mitsuba 3.9.1).
    pub dpdu: Vec3,
    /// `∂p/∂v` (along; zero on linear curves).
    pub dpdv: Vec3,
}

impl LinearCurves {
    /// Curves given as lists of at least two control points each (object space), placed by
    /// `to_world` (points only). `Err` names the problem: a curve of fewer than two points, a
    /// negative radius, or no curve at all.
    pub fn new(curves: &[Vec<ControlPoint>], to_world: &Transform) -> Result<LinearCurves, String> {
        let (points, first) = place(curves, to_world, 2, "a curve")?;
        Ok(LinearCurves { points, first })
    }

    /// Number of segments (primitives).
    pub fn len(&self) -> usize {
        self.first.len()
    }

    /// Whether there are no segments (never, once built).
    pub fn is_empty(&self) -> bool {
        self.first.is_empty()
    }

    /// The two control points of segment `k`.
    fn segment(&self, k: usize) -> (ControlPoint, ControlPoint) {
        let i = self.first[k] as usize;
        (self.points[i], self.points[i + 1])
    }

    /// Bounds of segment `k`: both end spheres.
    pub fn bounds(&self, k: usize) -> Bounds3 {
        let (a, b) = self.segment(k);
        let sphere = |c: ControlPoint| Bounds3 { min: c.p - Vec3::splat(c.r), max: c.p + Vec3::splat(c.r) };
        sphere(a).union(&sphere(b))
    }

    /// The entry of `ray` into segment `k` within `(0, t_max)`: `t` and `uv.x` the swept
    /// sphere's `v` (`uv.y` unused, 0).
    pub fn intersect(&self, k: usize, ray: &Ray, t_max: f32) -> Option<CurveHit> {
        let (a, b) = self.segment(k);
        let len_d = f64::from(ray.d.length());
        if len_d <= 0.0 || len_d.is_nan() {
            return None;
        }
        let d = ray.d.as_dvec3() / len_d;
        let (t, v) = segment_entry(ray.o.as_dvec3() - a.p.as_dvec3(), d, a, b)?;
        let t = (t / len_d) as f32;
        (t > 0.0 && t < t_max).then(|| CurveHit { t, uv: Vec2::new(v as f32, 0.0) })
    }

    /// The surface at a hit of segment `k` by `ray` (normal `(p − c(v)) / r(v)`; no ∂p/∂u, ∂p/∂v).
    pub fn surface(&self, k: usize, ray: &Ray, hit: CurveHit) -> RoundCurveSurface {
        let (a, b) = self.segment(k);
        let v = hit.uv.x;
        let p = ray.at(hit.t);
        let c = a.p * (1.0 - v) + b.p * v;
        let axis = (b.p - a.p).normalize_or_zero();
        let n = (p - c).try_normalize().unwrap_or_else(|| local_frame(axis).1);
        let (rot, rad) = local_frame(axis);
        let mut u = n.dot(rot).atan2(n.dot(rad));
        if u < 0.0 {
            u += std::f32::consts::TAU;
        }
        let uv = Vec2::new(u / std::f32::consts::TAU, (v + k as f32) / self.len() as f32);
        // `o + t d` rounded, and `t` itself rounded from the double-precision solution.
        let p_error = (ray.o.abs() + (ray.d * hit.t).abs()) * gamma(5);
        RoundCurveSurface { p, p_error, n, uv, dpdu: Vec3::ZERO, dpdv: Vec3::ZERO }
    }
}

/// Curves of control points placed by `to_world` (points only; radii kept), each with at least
/// `order` points and `len − order + 1` segments, a segment starting at each of its first
/// points: all points, and each segment's first point. `Err` names the problem (`what`, such as
/// "a curve", needs at least `order` points; a negative radius; no curve at all).
pub fn place(
    curves: &[Vec<ControlPoint>],
    to_world: &Transform,
    order: usize,
    what: &str,
) -> Result<(Vec<ControlPoint>, Vec<u32>), String> {
    if curves.is_empty() {
        return Err(format!("no curves: {what} needs at least {order} control points"));
    }
    let (mut points, mut first) = (Vec::new(), Vec::new());
    for (i, curve) in curves.iter().enumerate() {
        if curve.len() < order {
            let n = curve.len();
            return Err(format!("curve {} has {n} control point(s); {what} needs at least {order}", i + 1));
        }
        if let Some(c) = curve.iter().find(|c| c.r.is_nan() || c.r < 0.0) {
            return Err(format!("curve {} has a control point of radius {}: radii must be ≥ 0", i + 1, c.r));
        }
        let start = points.len() as u32;
        first.extend((0..(curve.len() - order + 1) as u32).map(|k| start + k));
        points.extend(curve.iter().map(|c| ControlPoint { p: to_world.apply_point(c.p), r: c.r }));
    }
    Ok((points, first))
}

/// Mitsuba's frame about a segment's unit axis: the rotation axis (+z made perpendicular to
/// the axis; +y where the axis is ±z) and the radial reference direction, `rot × axis`.
pub fn local_frame(axis: Vec3) -> (Vec3, Vec3) {
    let guide = Vec3::Z;
    let rot = if guide.dot(axis).abs() == 1.0 { Vec3::Y } else { (guide - axis * axis.dot(guide)).normalize_or_zero() };
    (rot, rot.cross(axis))
}

/// The entry `(t, v)` of the ray `y + t d` (`y` the origin relative to `a`'s centre, `d` unit)
/// into the hull of the spheres `a` and `b`: the nearest front-facing point of its boundary
/// (the tangent cone between the spheres, or a sphere's outer cap), `t` in units of `d`.
fn segment_entry(y: DVec3, d: DVec3, a: ControlPoint, b: ControlPoint) -> Option<(f64, f64)> {
    let axis = b.p.as_dvec3() - a.p.as_dvec3();
    let (r0, r1) = (f64::from(a.r), f64::from(b.r));
    let len = axis.length();
    // The cone's normal in the (along, across) plane is (ns, nr): ns = (r₀ − r₁) / L.
    let ns = if len > 0.0 { (r0 - r1) / len } else { f64::INFINITY };
    if ns.is_nan() || ns.abs() >= 1.0 {
        // One sphere holds the other (or they coincide): the hull is the larger sphere.
        return if r0 >= r1 {
            sphere_entry(y, d, r0).map(|t| (t, 0.0))
        } else {
            sphere_entry(y - axis, d, r1).map(|t| (t, 1.0))
        };
    }
    let w = axis / len;
    let nr = (1.0 - ns * ns).sqrt();
    // Along-axis coordinates where the cone touches the spheres: the caps lie beyond them.
    let (s_lo, s_hi) = (r0 * ns, len + r1 * ns);
    // The cone: distance to the axis ρ(t) = (r₀ − ns·s(t)) / nr, s the along-axis coordinate.
    let (s0, ds) = (y.dot(w), d.dot(w));
    let (yp, dp) = (y - s0 * w, d - ds * w);
    let (k0, k1) = ((r0 - ns * s0) / nr, -ns * ds / nr);
    // g(t) = ρ(t)² − (k₀ + k₁t)² = qa t² + 2 qb t + qc: inside the cone where g < 0.
    let (qa, qb, qc) = (dp.dot(dp) - k1 * k1, yp.dot(dp) - k0 * k1, yp.dot(yp) - k0 * k0);
    let disc = qb * qb - qa * qc;
    if disc < 0.0 && qa > 0.0 {
        // Never inside the cone, nor then in the spheres it holds.
        return None;
    }
    if disc >= 0.0 {
        // The entering root (g falling through zero) is (−qb − √disc) / qa for either sign of
        // qa; a ray parallel to the cone's slope (qa = 0) enters at −qc / 2qb if qb < 0.
        let t = if qa.abs() > 1e-12 * dp.dot(dp).max(k1 * k1) {
            Some((-qb - disc.sqrt()) / qa)
        } else {
            (qb < 0.0).then(|| -qc / (2.0 * qb))
        };
        if let Some(t) = t {
            let s = s0 + t * ds;
            if k0 + k1 * t >= 0.0 && (s_lo..=s_hi).contains(&s) {
                // The hull's one entry (it is convex): before the origin, no hit.
                return (t > 0.0).then(|| (t, ((s - s_lo) / (len * nr * nr)).clamp(0.0, 1.0)));
            }
        }
    }
    // Not through the cone: through a cap, if at all.
    let cap0 = sphere_entry(y, d, r0).filter(|&t| t > 0.0 && (y + t * d).dot(w) <= s_lo).map(|t| (t, 0.0));
    let cap1 = sphere_entry(y - axis, d, r1).filter(|&t| t > 0.0 && (y + t * d).dot(w) >= s_hi).map(|t| (t, 1.0));
    match (cap0, cap1) {
        (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
        (a, b) => a.or(b),
    }
}

/// Entry distance of the ray `y + t d` (`y` relative to the centre, `d` unit) into the sphere
/// of radius `r`, if the line meets it (negative when the origin is inside or past it).
fn sphere_entry(y: DVec3, d: DVec3, r: f64) -> Option<f64> {
    let tc = -y.dot(d);
    let q = y + tc * d;
    let h2 = r * r - q.length_squared();
    (h2 >= 0.0).then(|| tc - h2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, Pcg32};

    fn cp(x: f32, y: f32, z: f32, r: f32) -> ControlPoint {
        ControlPoint { p: Vec3::new(x, y, z), r }
    }

    /// The two curves of the probe file that checked these semantics against Mitsuba 3.9.1:
    /// a two-point curve along x with a growing radius, and a three-point bent one.
    fn probe() -> LinearCurves {
        let curves = vec![
            vec![cp(-1.0, 0.0, 0.0, 0.2), cp(1.0, 0.0, 0.0, 0.4)],
            vec![cp(0.0, -1.0, 2.0, 0.1), cp(0.5, 0.0, 2.0, 0.15), cp(0.0, 1.0, 2.5, 0.1)],
        ];
        LinearCurves::new(&curves, &Transform::IDENTITY).unwrap()
    }

    fn closest(c: &LinearCurves, ray: &Ray) -> Option<(usize, CurveHit)> {
        (0..c.len())
            .filter_map(|k| c.intersect(k, ray, ray.t_max).map(|h| (k, h)))
            .min_by(|a, b| a.1.t.total_cmp(&b.1.t))
    }

    /// Hits, normals and (u, v) as Mitsuba 3.9.1 (`llvm_ad_rgb`, Embree) reported them for the
    /// same curves and rays: the cone, a cap, a joint's neighbourhood, and a ray from inside.
    #[test]
    fn matches_mitsuba_on_the_probe() {
        let c = probe();
        // (origin, direction, Some((t, segment, normal, uv)) or None)
        type Case = ([f32; 3], [f32; 3], Option<(f32, usize, [f32; 3], [f32; 2])>);
        let cases: [Case; 7] = [
            ([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], Some((4.69849, 0, [-0.1, 0.0, 0.994987], [0.25, 0.171717]))),
            (
                [-1.1, 0.1, 5.0],
                [0.0, 0.0, -1.0],
                Some((4.85858, 0, [-0.5, 0.5, std::f32::consts::FRAC_1_SQRT_2], [0.152043, 0.0])),
            ),
            ([0.9, 0.3, 5.0], [0.0, 0.0, -1.0], Some((4.74774, 0, [-0.1, 0.761538, 0.640359], [0.111277, 0.323232]))),
            ([0.5, 0.0, 5.0], [0.0, 0.0, -1.0], Some((2.8385, 2, [0.165755, -0.331511, 0.928777], [0.25, 0.682972]))),
            (
                [0.3, -0.5, 5.0],
                [0.0, 0.0, -1.0],
                Some((2.88207, 1, [0.296826, -0.198413, 0.934092], [0.307687, 0.50835])),
            ),
            ([0.0, -5.0, 0.1], [0.0, 1.0, 0.0], Some((4.71555, 0, [-0.1, -0.938669, 0.33], [0.446195, 0.171717]))),
            ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], None),
        ];
        for (o, d, want) in cases {
            let ray = Ray::new(Vec3::from(o), Vec3::from(d));
            let got = closest(&c, &ray);
            match (got, want) {
                (None, None) => {}
                (Some((k, h)), Some((t, seg, n, uv))) => {
                    let s = c.surface(k, &ray, h);
                    assert!((h.t - t).abs() < 1e-4, "{o:?}: t {} vs {t}", h.t);
                    assert_eq!(k, seg, "{o:?}");
                    assert!((s.n - Vec3::from(n)).length() < 1e-4, "{o:?}: n {} vs {n:?}", s.n);
                    assert!((s.uv - Vec2::from(uv)).length() < 1e-4, "{o:?}: uv {} vs {uv:?}", s.uv);
                }
                (g, w) => panic!("{o:?}: got {g:?}, Mitsuba {w:?}"),
            }
        }
    }

    /// Every hit lies on the swept surface: `|p − c(v)| = r(v)`, the normal `(p − c(v)) / r(v)`
    /// faces the ray, and no point of the ray before the hit is inside any swept sphere (the
    /// entry is the first); a ray that misses passes through no tube. Random rays from a sphere
    /// around the curves toward them.
    #[test]
    fn hits_are_first_entries_of_the_sweep() {
        let c = probe();
        let mut rng = Pcg32::new(5, 9);
        let inside = |x: Vec3| {
            (0..c.len()).any(|k| {
                let (a, b) = c.segment(k);
                (0..=200).any(|i| {
                    let v = i as f32 / 200.0;
                    (x - (a.p * (1.0 - v) + b.p * v)).length() < (a.r * (1.0 - v) + b.r * v) * 0.999
                })
            })
        };
        let mut hits = 0;
        for _ in 0..1000 {
            let o =
                Vec3::new(0.0, 0.0, 1.0) + sample_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32())).value * 4.0;
            let target = Vec3::new(rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.5);
            let ray = Ray::new(o, (target - o).normalize());
            let Some((k, h)) = closest(&c, &ray) else {
                // A miss: no point of the ray (to beyond the curves) is inside a tube.
                for i in 0..400 {
                    assert!(!inside(ray.at(9.0 * i as f32 / 400.0)), "a miss that passes through a tube: {ray:?}");
                }
                continue;
            };
            hits += 1;
            let (a, b) = c.segment(k);
            let v = h.uv.x;
            let (centre, r) = (a.p * (1.0 - v) + b.p * v, a.r * (1.0 - v) + b.r * v);
            let p = ray.at(h.t);
            assert!(((p - centre).length() - r).abs() < 1e-4, "off the sweep: {} vs {r}", (p - centre).length());
            assert!(c.surface(k, &ray, h).n.dot(ray.d) < 0.0, "a back face");
            for i in 0..50 {
                assert!(!inside(ray.at(h.t * i as f32 / 50.0)), "the ray was inside before its hit");
            }
        }
        assert!(hits > 150, "{hits} hits");
    }

    /// `to_world` moves the points and keeps the radii; bad curves are refused by name.
    #[test]
    fn placement_and_errors() {
        let t = Transform::scale(Vec3::splat(2.0)).unwrap();
        let c = LinearCurves::new(&[vec![cp(0.0, 0.0, 0.0, 0.5), cp(1.0, 0.0, 0.0, 0.5)]], &t).unwrap();
        let b = c.bounds(0);
        assert_eq!((b.min, b.max), (Vec3::new(-0.5, -0.5, -0.5), Vec3::new(2.5, 0.5, 0.5)));
        let e = LinearCurves::new(&[vec![cp(0.0, 0.0, 0.0, 0.5)]], &t).unwrap_err();
        assert!(e.contains("at least 2"), "{e}");
        let e = LinearCurves::new(&[vec![cp(0.0, 0.0, 0.0, -0.5), cp(1.0, 0.0, 0.0, 0.5)]], &t).unwrap_err();
        assert!(e.contains("≥ 0"), "{e}");
        assert!(LinearCurves::new(&[], &t).is_err());
    }
}
