//! Mitsuba 3's `bsplinecurve`: round tubes along uniform cubic B-splines, their radius a cubic
//! B-spline too, hit as Embree's round B-spline curves are (Mitsuba 3.9.1 measured).
//!
//! - A curve of `n ≥ 4` control points `(pᵢ, rᵢ)` (world-space centres, radii in world units:
//!   `to_world` moves the points only) has `n − 3` segments; segment `k` is the cubic B-spline
//!   of points `k .. k + 3`, `c(u)` and `r(u)` for `u ∈ [0, 1]`, and one BVH primitive.
//! - The surface is the sweep of the circle of radius `r(u)` about `c(u)` in the plane normal
//!   to the curve, `(p − c(u)) · c′(u) = 0` (on a straight piece: a cone frustum whose cross
//!   sections are those circles). Its ends are open, and only entries count (back faces are
//!   culled, as by Embree): a ray from inside a tube, or into its open end, passes.
//! - The normal is the sweep's: `(|c′|² − (p − c)·c″)(p − c) − r r′ c′`, normalised. Mitsuba's
//!   (u, v): `u` the angle of `p − c` about the tangent in [`local_frame`]'s frame over 2π,
//!   `v = (k + u_segment) / segments` along all the shape's segments; `∂p/∂u = 2π r ĉ′ × n̂ᵣ`
//!   (`n̂ᵣ` the unit radial direction), `∂p/∂v = segments · (c′ + r′ n̂ᵣ)` (as Mitsuba 3.9.1 on
//!   straight curves; on bent ones its `∂p/∂v` differs by an amount no formula we tried
//!   explains: it matters only to bump and normal maps, not to the image of other materials).
//! - A hit: the segment, converted to Bézier form, is subdivided in the ray's frame (pruned by
//!   its control points' bounds grown by the largest radius) until a piece is nearly straight;
//!   the ray is intersected with that piece's cone frustum, and Newton's method on the two
//!   equations of the sweep (in the circle's plane, on the circle) polishes `(t, u)` on the
//!   exact cubic, in double precision relative to the ray's origin.
//!
//! Curves have no area to sample: they cannot be area emitters (Mitsuba gives them no area).

use super::curve::CurveHit;
use super::roundcurve::{local_frame, place, ControlPoint, RoundCurveSurface};
use crate::math::float::gamma;
use crate::math::{Bounds3, Ray, Transform, Vec2, Vec3};
use glam::DVec3;

/// Placed B-spline round curves: control points and the segments over them.
#[derive(Clone, Debug)]
pub struct BSplineCurves {
    points: Vec<ControlPoint>,
    /// Segment `k` is the B-spline of `points[first[k] .. first[k] + 4]`.
    first: Vec<u32>,
}

/// A segment evaluated at `u`: centre, its first and second derivatives, radius and its
/// derivative.
struct Eval {
    c: DVec3,
    dc: DVec3,
    ddc: DVec3,
    r: f64,
    dr: f64,
}

/// Deepest subdivision of a segment (2^10 pieces at most along the ray's path).
const MAX_DEPTH: u32 = 10;

impl BSplineCurves {
    /// Curves given as lists of at least four control points each (object space), placed by
    /// `to_world` (points only). `Err` names the problem.
    pub fn new(curves: &[Vec<ControlPoint>], to_world: &Transform) -> Result<BSplineCurves, String> {
        let (points, first) = place(curves, to_world, 4, "a B-spline curve")?;
        Ok(BSplineCurves { points, first })
    }

    /// Number of segments (primitives).
    pub fn len(&self) -> usize {
        self.first.len()
    }

    /// Whether there are no segments (never, once built).
    pub fn is_empty(&self) -> bool {
        self.first.is_empty()
    }

    fn controls(&self, k: usize) -> &[ControlPoint] {
        let i = self.first[k] as usize;
        &self.points[i..i + 4]
    }

    /// Bounds of segment `k`: its Bézier control points grown by the largest radius (a Bézier
    /// curve lies in its control points' convex hull, about a third of the B-spline points' one
    /// along a curve; the radius is below its control points' largest). The Bézier points,
    /// computed in single precision, are grown by a further 10⁻⁶ of the B-spline points'
    /// magnitude for the rounding.
    pub fn bounds(&self, k: usize) -> Bounds3 {
        let c = self.controls(k);
        let r = c.iter().fold(0.0f32, |m, c| m.max(c.r));
        let magnitude = c.iter().fold(Vec3::ZERO, |m, c| m.max(c.p.abs()));
        let grow = Vec3::splat(r) + magnitude * 1e-6;
        bezier_points(std::array::from_fn(|i| c[i].p))
            .iter()
            .fold(Bounds3::EMPTY, |b, &p| b.union(&Bounds3 { min: p - grow, max: p + grow }))
    }

    /// Segment `k`'s control points relative to `origin`, and their radii, in double precision.
    fn segment(&self, k: usize, origin: DVec3) -> Segment {
        let c = self.controls(k);
        Segment {
            q: std::array::from_fn(|i| c[i].p.as_dvec3() - origin),
            r: std::array::from_fn(|i| f64::from(c[i].r)),
        }
    }

    /// Segment `k` at `u`, positions relative to `origin`.
    fn eval(&self, k: usize, u: f64, origin: DVec3) -> Eval {
        self.segment(k, origin).eval(u)
    }

    /// The nearest entry of `ray` into segment `k` within `(0, t_max)`: `t` and `uv.x` the
    /// segment's `u` (`uv.y` unused, 0).
    pub fn intersect(&self, k: usize, ray: &Ray, t_max: f32) -> Option<CurveHit> {
        self.intersect_with(k, ray, &BSplineRay::new(ray), t_max)
    }

    /// [`BSplineCurves::intersect`] with the ray's frames computed beforehand (once per ray
    /// for all the segments it meets: their square roots and divisions would otherwise stall
    /// every segment's test).
    #[inline]
    pub fn intersect_with(&self, k: usize, ray: &Ray, frames: &BSplineRay, t_max: f32) -> Option<CurveHit> {
        if self.misses_hull(k, ray, frames, t_max) {
            return None;
        }
        self.search(k, ray, frames, t_max)
    }

    /// [`BSplineCurves::intersect`] by the subdivision search alone.
    fn search(&self, k: usize, ray: &Ray, frames: &BSplineRay, t_max: f32) -> Option<CurveHit> {
        let BSplineFrame { len_d, d, e1, e2 } = frames.double?;
        let o = ray.o.as_dvec3();
        let to_frame = |p: DVec3| DVec3::new(p.dot(e1), p.dot(e2), p.dot(d));
        let seg = self.segment(k, o);
        let (q, r) = (seg.q, seg.r);
        // B-spline to Bézier control points, in the ray's frame.
        let bez = [
            (q[0] + 4.0 * q[1] + q[2]) / 6.0,
            (2.0 * q[1] + q[2]) / 3.0,
            (q[1] + 2.0 * q[2]) / 3.0,
            (q[1] + 4.0 * q[2] + q[3]) / 6.0,
        ]
        .map(to_frame);
        let rb = [
            (r[0] + 4.0 * r[1] + r[2]) / 6.0,
            (2.0 * r[1] + r[2]) / 3.0,
            (r[1] + 2.0 * r[2]) / 3.0,
            (r[1] + 4.0 * r[2] + r[3]) / 6.0,
        ];
        let mut search = Search { seg, d, best: f64::from(t_max) * len_d, hit: None };
        search.piece(bez, rb, 0.0, 1.0, 0);
        let (t, u) = search.hit?;
        Some(CurveHit { t: (t / len_d) as f32, uv: Vec2::new(u as f32, 0.0) })
    }

    /// Whether `ray` certainly misses segment `k` within `(0, t_max)`, by a test in single
    /// precision before the search in double: the tube lies within its largest radius of the
    /// convex hull of the segment's Bézier control points, so it is missed if the hull, so
    /// grown, lies wholly to one side of one of two planes through the ray, behind the origin
    /// or beyond `t_max` (the search's first test, in another frame). The growth carries a
    /// margin (10⁻⁴ of the points' distance) far above the rounding of either precision and the
    /// search's tolerance, so only segments the search would also miss are skipped, and the
    /// answer is the same. Segments whose axis-aligned boxes a ray enters but whose hull it
    /// passes are skipped here at a fraction of the search's setup cost (the curves scene 4 %
    /// faster with the Bézier bounds).
    #[inline]
    fn misses_hull(&self, k: usize, ray: &Ray, frames: &BSplineRay, t_max: f32) -> bool {
        let Some((d, e1, e2)) = frames.single else { return false };
        let c = self.controls(k);
        let q: [Vec3; 4] = std::array::from_fn(|i| c[i].p - ray.o);
        let scale = q.iter().fold(0.0f32, |m, q| m.max(q.abs().max_element()));
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for b in bezier_points(q) {
            let f = Vec3::new(b.dot(e1), b.dot(e2), b.dot(d));
            (lo, hi) = (lo.min(f), hi.max(f));
        }
        let r_max = c.iter().fold(0.0f32, |m, c| m.max(c.r));
        let grow = r_max + 1e-4 * (scale + r_max);
        // Comparisons false for NaN: a non-finite case is left to the search.
        lo.x > grow
            || hi.x < -grow
            || lo.y > grow
            || hi.y < -grow
            || hi.z < -grow
            || lo.z > t_max * ray.d.length() + grow
    }

    /// The surface at a hit of segment `k` by `ray`.
    pub fn surface(&self, k: usize, ray: &Ray, hit: CurveHit) -> RoundCurveSurface {
        let p = ray.at(hit.t);
        let e = self.eval(k, f64::from(hit.uv.x), DVec3::ZERO);
        let (c, dc, ddc) = (e.c.as_vec3(), e.dc.as_vec3(), e.ddc.as_vec3());
        let (r, dr) = (e.r as f32, e.dr as f32);
        let rad = p - c;
        let tangent = dc.normalize_or_zero();
        let (rot, radial_ref) = local_frame(tangent);
        let rad_n = rad.try_normalize().unwrap_or(radial_ref);
        let n = ((dc.length_squared() - rad.dot(ddc)) * rad - (dr * r) * dc).try_normalize().unwrap_or(rad_n);
        let mut u = rot.dot(rad_n).atan2(radial_ref.dot(rad_n));
        if u < 0.0 {
            u += std::f32::consts::TAU;
        }
        let segments = self.len() as f32;
        let uv = Vec2::new(u / std::f32::consts::TAU, (hit.uv.x + k as f32) / segments);
        let dpdu = tangent.cross(rad_n) * (std::f32::consts::TAU * r);
        let dpdv = (dc + rad_n * dr) * segments;
        // `o + t d` rounded, and `t` itself rounded from the double-precision solution.
        let p_error = (ray.o.abs() + (ray.d * hit.t).abs()) * gamma(5);
        RoundCurveSurface { p, p_error, n, uv, dpdu, dpdv }
    }
}

/// What the tests of B-spline segments need of a ray, computed once for it: its unit
/// direction and two unit vectors across it, in single precision (the hull test; `None` for a
/// zero direction) and in double (the search, with the direction's length; `None` for a zero
/// or non-finite length).
#[derive(Clone, Copy, Debug)]
pub struct BSplineRay {
    single: Option<(Vec3, Vec3, Vec3)>,
    double: Option<BSplineFrame>,
}

/// The ray's frame in double precision: x, y across it (`e1`, `e2`), z along it (`d`, unit),
/// and the length of the ray's own direction.
#[derive(Clone, Copy, Debug)]
struct BSplineFrame {
    len_d: f64,
    d: DVec3,
    e1: DVec3,
    e2: DVec3,
}

impl BSplineRay {
    /// The frames of `ray`.
    pub fn new(ray: &Ray) -> BSplineRay {
        let d = ray.d.normalize_or_zero();
        let single = (d != Vec3::ZERO).then(|| {
            let (e1, e2) = d.any_orthonormal_pair();
            (d, e1, e2)
        });
        let len_d = f64::from(ray.d.length());
        let double = (len_d > 0.0 && !len_d.is_nan()).then(|| {
            let d = ray.d.as_dvec3() / len_d;
            let (e1, e2) = orthonormal_pair(d);
            BSplineFrame { len_d, d, e1, e2 }
        });
        BSplineRay { single, double }
    }
}

/// A segment's four control points (relative to an origin) and radii, in double precision.
#[derive(Clone, Copy)]
struct Segment {
    q: [DVec3; 4],
    r: [f64; 4],
}

impl Segment {
    /// The segment at `u`.
    #[inline]
    fn eval(&self, u: f64) -> Eval {
        let (u2, u3) = (u * u, u * u * u);
        let w = [
            (-u3 + 3.0 * u2 - 3.0 * u + 1.0) / 6.0,
            (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0,
            (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0,
            u3 / 6.0,
        ];
        let dw = [(-u2 + 2.0 * u - 1.0) / 2.0, (3.0 * u2 - 4.0 * u) / 2.0, (-3.0 * u2 + 2.0 * u + 1.0) / 2.0, u2 / 2.0];
        let ddw = [1.0 - u, 3.0 * u - 2.0, 1.0 - 3.0 * u, u];
        let mut e = Eval { c: DVec3::ZERO, dc: DVec3::ZERO, ddc: DVec3::ZERO, r: 0.0, dr: 0.0 };
        for i in 0..4 {
            let (p, r) = (self.q[i], self.r[i]);
            e.c += w[i] * p;
            e.dc += dw[i] * p;
            e.ddc += ddw[i] * p;
            e.r += w[i] * r;
            e.dr += dw[i] * r;
        }
        e
    }
}

/// The subdivision search of one segment for one ray (unit direction `d` from the origin of
/// `seg`'s coordinates).
struct Search {
    seg: Segment,
    d: DVec3,
    /// Nearest accepted distance so far (the limit at first).
    best: f64,
    hit: Option<(f64, f64)>,
}

impl Search {
    /// The Bézier piece `bez` (ray frame) with radii `rb`, spanning `[u0, u1]` of the segment.
    fn piece(&mut self, bez: [DVec3; 4], rb: [f64; 4], u0: f64, u1: f64, depth: u32) {
        let rmax = rb.iter().fold(0.0f64, |m, &r| m.max(r));
        let lo = bez.iter().fold(DVec3::INFINITY, |m, &p| m.min(p)) - DVec3::splat(rmax);
        let hi = bez.iter().fold(DVec3::NEG_INFINITY, |m, &p| m.max(p)) + DVec3::splat(rmax);
        if lo.x > 0.0 || hi.x < 0.0 || lo.y > 0.0 || hi.y < 0.0 || hi.z < 0.0 || lo.z > self.best {
            return;
        }
        // Flat enough: the inner control points within a tenth of the smallest radius bound
        // of the chord (or as deep as allowed); compared squared (no square roots).
        let chord = bez[3] - bez[0];
        let l2 = chord.length_squared();
        let inv_l2 = if l2 > 0.0 { 1.0 / l2 } else { 0.0 };
        let off2 = |p: DVec3| {
            let v = p - bez[0];
            (v - chord * (v.dot(chord) * inv_l2)).length_squared()
        };
        let rmin = rb.iter().fold(f64::INFINITY, |m, &r| m.min(r));
        // (0.1 max(r_min, 10⁻⁶ |chord|))², with r_min ≥ 0.
        let tolerance2 = (0.01 * rmin * rmin).max(1e-14 * l2);
        if depth >= MAX_DEPTH || off2(bez[1]).max(off2(bez[2])) <= tolerance2 {
            self.leaf(&bez, &rb, u0, u1);
            return;
        }
        let (a, b) = split(bez);
        let (ra, rb2) = split_scalar(rb);
        let um = 0.5 * (u0 + u1);
        // The nearer half first (its hit prunes the farther).
        if a[0].z + a[3].z <= b[0].z + b[3].z {
            self.piece(a, ra, u0, um, depth + 1);
            self.piece(b, rb2, um, u1, depth + 1);
        } else {
            self.piece(b, rb2, um, u1, depth + 1);
            self.piece(a, ra, u0, um, depth + 1);
        }
    }

    /// A nearly straight piece: the ray against its cone frustum (extended by half its length
    /// at both ends, so that an entry near a bend, where the straight piece would be entered
    /// through its end, still gives a guess), and against the piece's axis (the ray's closest
    /// approach); each guess polished by Newton's method on the exact sweep.
    ///
    /// The piece's ends are its Bézier end points `bez[0]`, `bez[3]` with radii `rb[0]`,
    /// `rb[3]`, in the ray's frame, where the ray runs along +z from the origin: the guesses are
    /// found there (a rotation keeps distances along the ray and fractions of the axis) and
    /// polished on the segment itself.
    fn leaf(&mut self, bez: &[DVec3; 4], rb: &[f64; 4], u0: f64, u1: f64) {
        let (a, axis) = (bez[0], bez[3] - bez[0]);
        if let Some((t, s)) = frustum_entry(-a, DVec3::Z, axis, rb[0], rb[3]) {
            if self.polish(t, u0 + (u1 - u0) * s, u0, u1) {
                return;
            }
        }
        // The second guess only where the ray passes within reach of the piece's axis.
        if let Some((t, s)) = closest_approach(-a, DVec3::Z, axis) {
            if (t * DVec3::Z + a - s * axis).length() <= 1.25 * rb[0].max(rb[3]) {
                self.polish(t, u0 + (u1 - u0) * s, u0, u1);
            }
        }
    }

    /// Newton's method on F₁ = (p − c)·c′ = 0 (the circle's plane) and F₂ = |p − c|² − r² = 0
    /// from `(t, u)`; a converged front-facing root near the piece `[u0, u1]` that is nearer
    /// than the best so far becomes the hit (`true`).
    fn polish(&mut self, mut t: f64, mut u: f64, u0: f64, u1: f64) -> bool {
        let d = self.d;
        let mut converged = false;
        for _ in 0..12 {
            let e = self.seg.eval(u);
            let v = t * d - e.c;
            let (f1, f2) = (v.dot(e.dc), v.length_squared() - e.r * e.r);
            let (j11, j12) = (d.dot(e.dc), -e.dc.length_squared() + v.dot(e.ddc));
            let (j21, j22) = (2.0 * v.dot(d), -2.0 * v.dot(e.dc) - 2.0 * e.r * e.dr);
            let det = j11 * j22 - j12 * j21;
            if det == 0.0 || !det.is_finite() {
                return false;
            }
            let (dt, du) = ((f1 * j22 - f2 * j12) / det, (j11 * f2 - j21 * f1) / det);
            t -= dt;
            u -= du;
            if dt.abs() <= 1e-9 * e.r.max(1e-12) && du.abs() <= 1e-9 {
                converged = true;
                break;
            }
        }
        let slack = 0.5 * (u1 - u0);
        if !converged || !(u0 - slack..=u1 + slack).contains(&u) || !(0.0..=1.0).contains(&u) {
            return false;
        }
        if !(t > 0.0 && t < self.best) {
            return false;
        }
        // On the circle, and an entry: the sweep's outward normal faces the ray.
        let e = self.seg.eval(u);
        let v = t * d - e.c;
        let r = e.r.max(1e-9);
        if (v.length_squared() - e.r * e.r).abs() > 1e-6 * r * r + 1e-12 {
            return false;
        }
        let n = (e.dc.length_squared() - v.dot(e.ddc)) * v - (e.r * e.dr) * e.dc;
        if n.dot(d) >= 0.0 {
            return false;
        }
        self.best = t;
        self.hit = Some((t, u));
        true
    }
}

/// The ray `y + t d`'s closest approach to the segment from the origin to `axis`: `(t, s)`, `s`
/// the segment's fraction (clamped to [0, 1]).
fn closest_approach(y: DVec3, d: DVec3, axis: DVec3) -> Option<(f64, f64)> {
    let l2 = axis.length_squared();
    let b = d.dot(axis);
    let denom = l2 - b * b;
    if l2 <= 0.0 || denom <= 1e-12 * l2 {
        return None;
    }
    // Minimise |y + t d − s·axis|² over t and s (d unit).
    let (dy, ay) = (d.dot(y), axis.dot(y));
    let s = ((ay - b * dy) / denom).clamp(0.0, 1.0);
    Some((s * b - dy, s))
}

/// The Bézier control points of the uniform cubic B-spline of `q` (single precision).
#[inline(always)]
fn bezier_points(q: [Vec3; 4]) -> [Vec3; 4] {
    const SIXTH: f32 = 1.0 / 6.0;
    const THIRD: f32 = 1.0 / 3.0;
    [
        (q[0] + 4.0 * q[1] + q[2]) * SIXTH,
        (2.0 * q[1] + q[2]) * THIRD,
        (q[1] + 2.0 * q[2]) * THIRD,
        (q[1] + 4.0 * q[2] + q[3]) * SIXTH,
    ]
}

/// De Casteljau halves of a cubic Bézier.
fn split(p: [DVec3; 4]) -> ([DVec3; 4], [DVec3; 4]) {
    let (p01, p12, p23) = ((p[0] + p[1]) * 0.5, (p[1] + p[2]) * 0.5, (p[2] + p[3]) * 0.5);
    let (p012, p123) = ((p01 + p12) * 0.5, (p12 + p23) * 0.5);
    let m = (p012 + p123) * 0.5;
    ([p[0], p01, p012, m], [m, p123, p23, p[3]])
}

/// [`split`] for a scalar cubic (the radius).
fn split_scalar(p: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    let (p01, p12, p23) = ((p[0] + p[1]) * 0.5, (p[1] + p[2]) * 0.5, (p[2] + p[3]) * 0.5);
    let (p012, p123) = ((p01 + p12) * 0.5, (p12 + p23) * 0.5);
    let m = (p012 + p123) * 0.5;
    ([p[0], p01, p012, m], [m, p123, p23, p[3]])
}

/// Two unit vectors completing the unit `d` to an orthonormal frame.
fn orthonormal_pair(d: DVec3) -> (DVec3, DVec3) {
    let e1 = if d.x.abs() > d.y.abs() { DVec3::new(-d.z, 0.0, d.x) } else { DVec3::new(0.0, d.z, -d.y) }.normalize();
    (e1, d.cross(e1))
}

/// The entry `(t, s)` of the ray `y + t d` (`y` the origin relative to the frustum's first end,
/// `d` unit) into the cone along `axis` whose cross sections, perpendicular to the axis, have
/// radius `ra` at the first end and `rb` at the other, extended by half the axis beyond both
/// ends; `s ∈ [-0.5, 1.5]` the fraction of the axis there. Open ends; front faces only.
fn frustum_entry(y: DVec3, d: DVec3, axis: DVec3, ra: f64, rb: f64) -> Option<(f64, f64)> {
    let len = axis.length();
    if len <= 0.0 {
        return None;
    }
    let w = axis / len;
    let slope = (rb - ra) / len;
    let (s0, ds) = (y.dot(w), d.dot(w));
    let (yp, dp) = (y - s0 * w, d - ds * w);
    // Radius along the ray: k₀ + k₁ t; g(t) = |yp + t dp|² − (k₀ + k₁ t)², inside where < 0.
    let (k0, k1) = (ra + slope * s0, slope * ds);
    let (qa, qb, qc) = (dp.dot(dp) - k1 * k1, yp.dot(dp) - k0 * k1, yp.dot(yp) - k0 * k0);
    let disc = qb * qb - qa * qc;
    if disc < 0.0 {
        return None;
    }
    let t = if qa.abs() > 1e-12 * dp.dot(dp).max(k1 * k1) {
        (-qb - disc.sqrt()) / qa
    } else if qb < 0.0 {
        -qc / (2.0 * qb)
    } else {
        return None;
    };
    let s = s0 + t * ds;
    (k0 + k1 * t >= 0.0 && (-0.5 * len..=1.5 * len).contains(&s)).then_some((t, s / len))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cp(x: f32, y: f32, z: f32, r: f32) -> ControlPoint {
        ControlPoint { p: Vec3::new(x, y, z), r }
    }

    fn closest(c: &BSplineCurves, ray: &Ray) -> Option<(usize, CurveHit)> {
        (0..c.len())
            .filter_map(|k| c.intersect(k, ray, ray.t_max).map(|h| (k, h)))
            .min_by(|a, b| a.1.t.total_cmp(&b.1.t))
    }

    type Expect = Option<(f32, usize, [f32; 3], [f32; 2], [f32; 3], [f32; 3])>;

    fn check(c: &BSplineCurves, o: [f32; 3], d: [f32; 3], want: Expect) {
        let ray = Ray::new(Vec3::from(o), Vec3::from(d));
        match (closest(c, &ray), want) {
            (None, None) => {}
            (Some((k, h)), Some((t, seg, n, uv, dpdu, dpdv))) => {
                let s = c.surface(k, &ray, h);
                assert!((h.t - t).abs() < 2e-4, "{o:?}: t {} vs {t}", h.t);
                assert_eq!(k, seg, "{o:?}");
                assert!((s.n - Vec3::from(n)).length() < 2e-4, "{o:?}: n {} vs {n:?}", s.n);
                assert!((s.uv - Vec2::from(uv)).length() < 2e-4, "{o:?}: uv {} vs {uv:?}", s.uv);
                assert!((s.dpdu - Vec3::from(dpdu)).length() < 1e-3, "{o:?}: dpdu {} vs {dpdu:?}", s.dpdu);
                // Mitsuba 3.9.1's ∂p/∂v on bent curves follows no formula found (module docs).
                let straight =
                    c.controls(k).windows(3).all(|w| (w[1].p - w[0].p).cross(w[2].p - w[1].p).length() < 1e-6);
                if straight {
                    assert!((s.dpdv - Vec3::from(dpdv)).length() < 1e-3, "{o:?}: dpdv {} vs {dpdv:?}", s.dpdv);
                }
            }
            (g, w) => panic!("{o:?} {d:?}: got {g:?}, Mitsuba {w:?}"),
        }
    }

    /// Straight B-splines (two curves, 4 and 5 points, radii growing linearly): hits at the
    /// circle of radius r(u) (a circle sweep, not a sphere sweep), open ends, no hit from
    /// inside, and Mitsuba 3.9.1's normal, (u, v) and derivatives.
    #[test]
    fn matches_mitsuba_on_straight_curves() {
        let straight =
            |z: f32, n: usize| (0..n).map(|i| cp(-3.0 + 2.0 * i as f32, 0.0, z, 0.1 * (i + 1) as f32)).collect();
        let one = BSplineCurves::new(&[straight(0.0, 4)], &Transform::IDENTITY).unwrap();
        let down = [0.0, 0.0, -1.0];
        let n = [-0.0499376, 0.0, 0.998752];
        check(
            &one,
            [0.0, 0.0, 5.0],
            down,
            Some((4.75, 0, n, [0.25, 0.5], [0.0, -std::f32::consts::FRAC_PI_2, 0.0], [2.0, 0.0, 0.1])),
        );
        check(
            &one,
            [-0.99, 0.0, 5.0],
            down,
            Some((4.7995, 0, n, [0.25, 0.005], [0.0, -1.25978, 0.0], [2.0, 0.0, 0.1])),
        );
        check(&one, [-1.05, 0.0, 5.0], down, None);
        check(&one, [1.05, 0.0, 5.0], down, None);
        check(&one, [-3.0, 0.0, 0.0], [1.0, 0.0, 0.0], None);
        check(&one, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], None);
        let two = BSplineCurves::new(&[straight(0.0, 4), straight(2.0, 5)], &Transform::IDENTITY).unwrap();
        check(
            &two,
            [0.5, 0.0, 5.0],
            down,
            Some((2.725, 1, n, [0.25, 0.583333], [0.0, -1.72788, 0.0], [6.0, 0.0, 0.3])),
        );
        let side = [-0.0499376, 0.998752, 0.0];
        check(
            &two,
            [2.0, 5.0, 2.0],
            [0.0, -1.0, 0.0],
            Some((4.65, 2, side, [0.0, 0.833333], [0.0, 0.0, 2.19911], [6.0, 0.3, 0.0])),
        );
    }

    /// The bent curve of five points probed in Mitsuba 3.9.1.
    fn bent() -> Vec<ControlPoint> {
        vec![
            cp(-2.0, 0.0, 0.0, 0.2),
            cp(-1.0, 1.0, 0.0, 0.3),
            cp(0.0, 0.0, 0.5, 0.2),
            cp(1.0, 1.0, 1.0, 0.25),
            cp(2.0, 0.0, 1.0, 0.15),
        ]
    }

    /// The bent curve: Mitsuba 3.9.1's hits (and misses) for rays from two sides.
    #[test]
    fn matches_mitsuba_on_a_bent_curve() {
        let c = BSplineCurves::new(&[bent()], &Transform::IDENTITY).unwrap();
        let (down, back) = ([0.0, 0.0, -1.0], [0.0, -1.0, 0.0]);
        check(&c, [-1.2, 0.6, 6.0], down, None);
        check(&c, [-1.2, 6.0, 0.4], back, None);
        #[rustfmt::skip]
        let hits: [([f32; 3], [f32; 3], Expect); 7] = [
            ([-0.8, 0.6, 6.0], down, Some((5.58161, 0, [-0.312866, -0.0092753, 0.949752], [0.270414, 0.145246], [-0.553582, -1.52196, -0.197223], [2.1357, -0.123641, 0.702331]))),
            ([-0.8, 6.0, 0.4], back, Some((5.29466, 0, [-0.166942, 0.33799, 0.926225], [0.208534, 0.12585], [-0.685481, -1.43674, 0.400734], [2.22721, -0.342101, 0.526268]))),
            ([-0.3, 0.6, 6.0], down, Some((5.50946, 0, [0.0971428, 0.774057, 0.625619], [0.1149, 0.343645], [-0.804312, -0.731584, 1.03005], [2.15869, -0.484986, 0.264867]))),
            ([0.0, 0.6, 6.0], down, None),
            ([0.0, 6.0, 0.4], back, Some((5.45611, 0, [0.293045, 0.909669, -0.294324], [0.943188, 0.470943], [-0.535508, 0.559314, 1.1955], [1.45414, -0.267425, 0.621295]))),
            ([0.3, 0.6, 6.0], down, Some((5.16837, 1, [-0.563337, 0.609648, 0.557656], [0.103709, 0.712207], [-0.00575575, -0.953146, 1.0362], [1.9778, 2.85558, -1.12387]))),
            ([0.9, 0.6, 6.0], down, Some((4.88557, 1, [-0.21148, -0.283318, 0.935418], [0.29232, 0.975822], [0.223282, -1.35557, -0.360094], [1.95828, 0.313238, 0.537602]))),
        ];
        for (o, d, want) in hits {
            check(&c, o, d, want);
        }
        check(&c, [0.3, 6.0, 0.4], back, None);
        check(&c, [-0.5, 3.0, 4.0], [0.1, -0.5, -0.8], None);
    }

    /// The bounds hold the tube (points all around its circles, curves far from the origin
    /// too), and the single-precision rejection skips only segments the search misses: random
    /// rays at random curves, of which it must skip many and the search must hit many.
    #[test]
    fn bounds_hold_the_tube_and_rejections_are_misses() {
        use crate::sampling::{sample_uniform_sphere, Pcg32};
        let mut rng = Pcg32::new(11, 5);
        let (mut skipped, mut hits) = (0, 0);
        for round in 0..200 {
            let offset = if round % 4 == 0 { Vec3::new(1000.0, -300.0, 20.0) } else { Vec3::ZERO };
            let mut r = || rng.next_f32();
            let pts: Vec<ControlPoint> = (0..6)
                .map(|i| {
                    let p = Vec3::new(i as f32 + r() - 0.5, 2.0 * r() - 1.0, 2.0 * r() - 1.0);
                    ControlPoint { p: p + offset, r: 0.02 + 0.3 * r() }
                })
                .collect();
            let c = BSplineCurves::new(&[pts], &Transform::IDENTITY).unwrap();
            for k in 0..c.len() {
                let b = c.bounds(k);
                for i in 0..=16 {
                    let e = c.eval(k, i as f64 / 16.0, DVec3::ZERO);
                    let (n1, n2) = e.dc.normalize().any_orthonormal_pair();
                    for j in 0..16 {
                        let a = std::f64::consts::TAU * j as f64 / 16.0;
                        let p = (e.c + e.r * (a.cos() * n1 + a.sin() * n2)).as_vec3();
                        assert!(b.contains(p), "round {round} segment {k}: {p} outside {b:?}");
                    }
                }
            }
            let mut r = || rng.next_f32();
            for _ in 0..50 {
                let target = offset + Vec3::new(5.0 * r(), 2.0 * r() - 1.0, 2.0 * r() - 1.0);
                let dir = sample_uniform_sphere(Vec2::new(r(), r())).value;
                let ray = Ray::new(target - dir * (1.0 + 4.0 * r()), dir * (0.5 + r()));
                let t_max = if r() < 0.3 { 2.0 } else { f32::INFINITY };
                let frames = BSplineRay::new(&ray);
                for k in 0..c.len() {
                    let found = c.search(k, &ray, &frames, t_max);
                    hits += found.is_some() as u32;
                    if c.misses_hull(k, &ray, &frames, t_max) {
                        skipped += 1;
                        assert!(found.is_none(), "round {round} segment {k}: skipped a hit {found:?}");
                    }
                }
            }
        }
        assert!(skipped > 10_000 && hits > 500, "skipped {skipped}, hits {hits}: the test must exercise both");
    }

    /// Every hit lies on the sweep (in the circle's plane, on the circle) and faces the ray;
    /// the ray passes through no tube before its hit, and a ray that misses through none.
    /// Random rays at the bent curve extended to six points.
    #[test]
    fn hits_are_first_entries_of_the_sweep() {
        use crate::sampling::{sample_uniform_sphere, Pcg32};
        let mut pts = bent();
        pts.push(cp(2.5, -1.0, 0.0, 0.1));
        let c = BSplineCurves::new(&[pts], &Transform::IDENTITY).unwrap();
        // Inside: at a foot of the point on the centre line (a local minimum of the distance),
        // within the radius there.
        let inside = |x: Vec3| {
            (0..c.len()).any(|k| {
                let dist = |u: f64| {
                    let e = c.eval(k, u, DVec3::ZERO);
                    ((x.as_dvec3() - e.c).length(), e.r)
                };
                let n = 400;
                (1..n).any(|i| {
                    let (a, b, cc) =
                        (dist((i - 1) as f64 / n as f64), dist(i as f64 / n as f64), dist((i + 1) as f64 / n as f64));
                    b.0 <= a.0 && b.0 <= cc.0 && b.0 < 0.98 * b.1
                })
            })
        };
        let mut rng = Pcg32::new(3, 7);
        let mut hits = 0;
        for _ in 0..600 {
            let o =
                Vec3::new(0.0, 0.3, 0.5) + sample_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32())).value * 5.0;
            let target = Vec3::new(rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 1.6 - 0.5, rng.next_f32() * 1.2);
            let ray = Ray::new(o, (target - o).normalize());
            // Through an open end's disk a ray may pass inside without an entry.
            let through_end = [(0, 0.0), (c.len() - 1, 1.0)].iter().any(|&(k, u)| {
                let e = c.eval(k, u, ray.o.as_dvec3());
                let t = e.c.dot(e.dc) / ray.d.as_dvec3().dot(e.dc);
                t > 0.0 && (t * ray.d.as_dvec3() - e.c).length() < e.r
            });
            let Some((k, h)) = closest(&c, &ray) else {
                if through_end {
                    continue;
                }
                for i in 0..300 {
                    assert!(!inside(ray.at(10.0 * i as f32 / 300.0)), "a miss that passes through the tube: {ray:?}");
                }
                continue;
            };
            hits += 1;
            let e = c.eval(k, f64::from(h.uv.x), DVec3::ZERO);
            let v = ray.at(h.t).as_dvec3() - e.c;
            assert!(v.dot(e.dc).abs() < 1e-3 * e.dc.length(), "off the circle's plane");
            assert!((v.length() - e.r).abs() < 1e-4, "off the circle: {} vs {}", v.length(), e.r);
            assert!(c.surface(k, &ray, h).n.dot(ray.d) < 0.0, "a back face");
            for i in 0..60 {
                assert!(through_end || !inside(ray.at(h.t * i as f32 / 60.0)), "the ray was inside before its hit");
            }
        }
        assert!(hits > 100, "{hits} hits");
    }

    /// Bad curves are refused by name.
    #[test]
    fn errors() {
        let three = vec![cp(0.0, 0.0, 0.0, 0.1); 3];
        assert!(BSplineCurves::new(&[three], &Transform::IDENTITY).unwrap_err().contains("at least 4"));
        let negative = vec![cp(0.0, 0.0, 0.0, -0.1); 4];
        assert!(BSplineCurves::new(&[negative], &Transform::IDENTITY).unwrap_err().contains("≥ 0"));
    }
}
