//! pbrt-v4's `curve` shape: cubic Bézier curves swept into thin surfaces (hair, fur, grass), hit
//! as pbrt-v4 hits them (Nakamaru and Ohno's recursive subdivision in the ray's frame).
//!
//! - A curve is a cubic Bézier `c(u)`, u ∈ [0, 1], of width `w(u) = lerp(u, w₀, w₁)` (world
//!   units). pbrt's inputs — Bézier or uniform B-spline, degree 2 or 3, several segments per
//!   `Shape` — are turned into such cubics by [`CurveSet::from_control_points`].
//! - Kinds: `flat` (a ribbon always facing the ray), `cylinder` (the same ribbon, its normal
//!   turned across the width as a tube's would be: shading looks round) and `ribbon` (oriented by
//!   normals given at the ends, interpolated by slerp; its width foreshortened).
//! - Each curve is split into 2^`splitdepth` pieces (pbrt's default 3), each a primitive of the
//!   BVH, bounded by its control points' box grown by half the width.
//! - A hit: the ray's frame puts the ray on +z; the piece is subdivided to the depth its
//!   curvature needs (at most 10); at a leaf the segment between its end points is tested:
//!   the closest point of the curve to the ray's axis must lie within half the width, between
//!   the perpendiculars at both ends. `t` is the depth of that point of the curve, `u` along
//!   the curve, `v` across it (0 and 1 at the edges: the hair BSDF's `h = 2v − 1`).
//! - Surface: `∂p/∂u` the curve's tangent, `∂p/∂v` across the width in the plane facing the
//!   ray (turned by `lerp(v, −90°, 90°)` about the tangent for `cylinder`; `n × ∂p/∂u` for
//!   ribbons), the normal `∂p/∂u × ∂p/∂v` (pointing away from the viewer for flat curves, as in
//!   pbrt). The hit point is on the ray, with an error bound of the width.
//!
//! Curves have no area to sample: they cannot be area lights (as in pbrt-v4).

use crate::math::{Bounds3, Ray, Transform, Vec2, Vec3};

/// How a curve's surface is oriented.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// A flat ribbon facing the ray.
    Flat,
    /// A flat ribbon facing the ray, shaded as a tube.
    Cylinder,
    /// A ribbon oriented by the normals at its ends.
    Ribbon,
}

/// One cubic Bézier curve with its widths at u = 0 and 1 and, for ribbons, its end normals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bezier {
    /// Control points.
    pub cp: [Vec3; 4],
    /// Width at u = 0 and u = 1.
    pub width: [f32; 2],
    /// Unit normals at u = 0 and u = 1 (ribbons only).
    pub normals: Option<[Vec3; 2]>,
}

/// Curves as a scene format gives them (object space), before they are placed.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveSet {
    /// Their kind.
    pub kind: CurveKind,
    /// The cubic Bézier curves.
    pub curves: Vec<Bezier>,
    /// Each curve is split into 2^`split_depth` primitives.
    pub split_depth: u32,
}

/// Why control points do not make curves.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveError(pub String);

impl std::fmt::Display for CurveError {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

fn lerp(t: f32, a: Vec3, b: Vec3) -> Vec3 {
    a + (b - a) * t
}

impl CurveSet {
    /// pbrt-v4's curve parameters: control points `p` of `degree` 2 or 3 in the `bspline`
    /// (uniform) or `bezier` basis (segments share their end points), widths `w0`, `w1` over the
    /// whole run of segments, and for ribbons one normal per segment end.
    pub fn from_control_points(
        p: &[Vec3],
        degree: usize,
        bspline: bool,
        kind: CurveKind,
        normals: &[Vec3],
        width: [f32; 2],
        split_depth: u32,
    ) -> Result<CurveSet, CurveError> {
        if degree != 2 && degree != 3 {
            return Err(CurveError(format!("degree must be 2 or 3, got {degree}")));
        }
        let segments = if bspline {
            if p.len() < degree + 1 {
                return Err(CurveError(format!(
                    "a degree-{degree} b-spline needs at least {} control points, got {}",
                    degree + 1,
                    p.len()
                )));
            }
            p.len() - degree
        } else {
            if p.len() < degree + 1 || !(p.len() - 1).is_multiple_of(degree) {
                return Err(CurveError(format!(
                    "a degree-{degree} Bézier curve needs {} + {degree}n control points, got {}",
                    degree + 1,
                    p.len()
                )));
            }
            (p.len() - 1) / degree
        };
        match kind {
            CurveKind::Ribbon if normals.len() != segments + 1 => {
                return Err(CurveError(format!(
                    "a ribbon of {segments} segments needs {} normals \"N\", got {}",
                    segments + 1,
                    normals.len()
                )))
            }
            _ => {}
        }
        if !(width[0] >= 0.0 && width[1] >= 0.0 && width[0].is_finite() && width[1].is_finite()) {
            return Err(CurveError(format!("widths must be finite and ≥ 0, got {} and {}", width[0], width[1])));
        }
        let mut curves = Vec::with_capacity(segments);
        for s in 0..segments {
            let cp = match (bspline, degree) {
                (false, 3) => [p[3 * s], p[3 * s + 1], p[3 * s + 2], p[3 * s + 3]],
                (false, _) => elevate([p[2 * s], p[2 * s + 1], p[2 * s + 2]]),
                (true, 3) => {
                    let [p0, p1, p2, p3] = [p[s], p[s + 1], p[s + 2], p[s + 3]];
                    [
                        (p0 + p1 * 4.0 + p2) / 6.0,
                        (p1 * 2.0 + p2) / 3.0,
                        (p1 + p2 * 2.0) / 3.0,
                        (p1 + p2 * 4.0 + p3) / 6.0,
                    ]
                }
                (true, _) => {
                    let [p0, p1, p2] = [p[s], p[s + 1], p[s + 2]];
                    elevate([(p0 + p1) * 0.5, p1, (p1 + p2) * 0.5])
                }
            };
            let f = |k: usize| width[0] + (width[1] - width[0]) * (k as f32 / segments as f32);
            let normals = (kind == CurveKind::Ribbon).then(|| [normals[s].normalize(), normals[s + 1].normalize()]);
            curves.push(Bezier { cp, width: [f(s), f(s + 1)], normals });
        }
        if curves.iter().any(|c| !c.cp.iter().all(|q| q.is_finite())) {
            return Err(CurveError("control points must be finite".into()));
        }
        if curves.iter().any(|c| c.normals.is_some_and(|n| !n[0].is_finite() || !n[1].is_finite())) {
            return Err(CurveError("ribbon normals must be non-zero".into()));
        }
        Ok(CurveSet { kind, curves, split_depth: split_depth.min(10) })
    }
}

/// A quadratic Bézier as the same cubic.
fn elevate(q: [Vec3; 3]) -> [Vec3; 4] {
    [q[0], lerp(2.0 / 3.0, q[0], q[1]), lerp(1.0 / 3.0, q[1], q[2]), q[2]]
}

/// The blossom `p(u₀, u₁, u₂)` of a cubic Bézier.
fn blossom(cp: &[Vec3; 4], u0: f32, u1: f32, u2: f32) -> Vec3 {
    let (a, b, c) = (lerp(u0, cp[0], cp[1]), lerp(u0, cp[1], cp[2]), lerp(u0, cp[2], cp[3]));
    let (d, e) = (lerp(u1, a, b), lerp(u1, b, c));
    lerp(u2, d, e)
}

/// The control points of the part `[u0, u1]` of a cubic Bézier.
fn part(cp: &[Vec3; 4], u0: f32, u1: f32) -> [Vec3; 4] {
    [blossom(cp, u0, u0, u0), blossom(cp, u0, u0, u1), blossom(cp, u0, u1, u1), blossom(cp, u1, u1, u1)]
}

/// The two halves of a cubic Bézier (seven control points, the middle one shared).
fn halves(cp: &[Vec3; 4]) -> [Vec3; 7] {
    let [a, b, c, d] = *cp;
    [
        a,
        (a + b) * 0.5,
        (a + b * 2.0 + c) * 0.25,
        (a + b * 3.0 + c * 3.0 + d) * 0.125,
        (b + c * 2.0 + d) * 0.25,
        (c + d) * 0.5,
        d,
    ]
}

/// The point at `u` and the derivative there (the chord where the derivative vanishes).
fn evaluate(cp: &[Vec3; 4], u: f32) -> (Vec3, Vec3) {
    let c1 = [lerp(u, cp[0], cp[1]), lerp(u, cp[1], cp[2]), lerp(u, cp[2], cp[3])];
    let c2 = [lerp(u, c1[0], c1[1]), lerp(u, c1[1], c1[2])];
    let d = if (c2[1] - c2[0]).length_squared() > 0.0 { (c2[1] - c2[0]) * 3.0 } else { cp[3] - cp[0] };
    (lerp(u, c2[0], c2[1]), d)
}

fn bounds_of(cp: &[Vec3], grow: f32) -> Bounds3 {
    let (mut lo, mut hi) = (cp[0], cp[0]);
    for q in &cp[1..] {
        lo = lo.min(*q);
        hi = hi.max(*q);
    }
    Bounds3 { min: lo - Vec3::splat(grow), max: hi + Vec3::splat(grow) }
}

/// A placed curve (world space).
#[derive(Clone, Debug)]
struct Placed {
    cp: [Vec3; 4],
    width: [f32; 2],
    normals: [Vec3; 2],
    /// Angle between the two normals, and 1 / its sine (ribbons).
    normal_angle: f32,
    inv_sin_normal_angle: f32,
}

impl Placed {
    fn width_at(&self, u: f32) -> f32 {
        self.width[0] + (self.width[1] - self.width[0]) * u
    }

    /// A ribbon's normal at `u` (slerp of the end normals).
    fn normal_at(&self, u: f32) -> Vec3 {
        if self.normal_angle == 0.0 {
            return self.normals[0];
        }
        let s0 = ((1.0 - u) * self.normal_angle).sin() * self.inv_sin_normal_angle;
        let s1 = (u * self.normal_angle).sin() * self.inv_sin_normal_angle;
        self.normals[0] * s0 + self.normals[1] * s1
    }
}

/// One primitive: part `[u0, u1]` of curve `curve`, with that part's control points.
#[derive(Clone, Copy, Debug)]
struct Piece {
    cp: [Vec3; 4],
    curve: u32,
    u0: f32,
    u1: f32,
}

/// The ray's frame: origin at the ray's, +z along it, +y toward `up` (pbrt's `LookAt`).
struct RayFrame {
    o: Vec3,
    x: Vec3,
    y: Vec3,
    z: Vec3,
}

impl RayFrame {
    fn new(ray: &Ray, up: Vec3) -> RayFrame {
        let z = ray.d.normalize();
        // `up` need not be a unit vector: x is normalised below.
        let mut x = up.cross(z);
        if x.length_squared() == 0.0 || !x.is_finite() {
            x = crate::math::Frame::from_z(z).s;
        }
        let x = x.normalize();
        RayFrame { o: ray.o, x, y: z.cross(x), z }
    }

    fn point(&self, p: Vec3) -> Vec3 {
        let d = p - self.o;
        Vec3::new(self.x.dot(d), self.y.dot(d), self.z.dot(d))
    }

    fn vector(&self, v: Vec3) -> Vec3 {
        Vec3::new(self.x.dot(v), self.y.dot(v), self.z.dot(v))
    }

    fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }
}

/// Placed curves, split into the BVH's primitives.
#[derive(Clone, Debug)]
pub struct Curves {
    kind: CurveKind,
    curves: Vec<Placed>,
    pieces: Vec<Piece>,
    /// Turn the normal over (the transform mirrors, or the orientation is reversed).
    flip: bool,
}

/// The result of a hit: distance, and (u, v).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveHit {
    /// Ray parameter.
    pub t: f32,
    /// Along (u) and across (v) the curve.
    pub uv: Vec2,
}

/// Geometry of a curve hit.
#[derive(Clone, Copy, Debug)]
pub struct CurveSurface {
    /// The point (on the ray).
    pub p: Vec3,
    /// Its error bound (the width).
    pub p_error: Vec3,
    /// Unit normal `∂p/∂u × ∂p/∂v`.
    pub n: Vec3,
    /// Tangent along the curve.
    pub dpdu: Vec3,
    /// Across the width.
    pub dpdv: Vec3,
}

impl Curves {
    /// `set` placed by `to_world` (a similarity keeps pbrt's widths exact; widths scale by the
    /// cube root of the transform's determinant), normals turned over if `flip`.
    pub fn new(set: &CurveSet, to_world: &Transform, flip: bool) -> Curves {
        let m = to_world.matrix();
        let scale = m.determinant().abs().cbrt();
        let normal_matrix = glam::Mat3::from_mat4(*m).inverse().transpose();
        let curves: Vec<Placed> = set
            .curves
            .iter()
            .map(|c| {
                let cp = c.cp.map(|q| m.transform_point3(q));
                let normals = c.normals.map_or([Vec3::Z; 2], |n| n.map(|v| (normal_matrix * v).normalize()));
                let angle = normals[0].dot(normals[1]).clamp(-1.0, 1.0).acos();
                let inv = if angle > 0.0 { 1.0 / angle.sin() } else { 0.0 };
                Placed {
                    cp,
                    width: c.width.map(|w| w * scale),
                    normals,
                    normal_angle: angle,
                    inv_sin_normal_angle: inv,
                }
            })
            .collect();
        let n = 1u32 << set.split_depth;
        let pieces = (0..curves.len() as u32)
            .flat_map(|c| {
                let cp = curves[c as usize].cp;
                (0..n).map(move |i| {
                    let (u0, u1) = (i as f32 / n as f32, (i + 1) as f32 / n as f32);
                    Piece { cp: part(&cp, u0, u1), curve: c, u0, u1 }
                })
            })
            .collect();
        let flip = flip ^ (m.determinant() < 0.0);
        Curves { kind: set.kind, curves, pieces, flip }
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.pieces.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }

    /// Bounds of primitive `i`.
    pub fn bounds(&self, i: usize) -> Bounds3 {
        let pc = self.pieces[i];
        let c = &self.curves[pc.curve as usize];
        let w = c.width_at(pc.u0).max(c.width_at(pc.u1));
        bounds_of(&pc.cp, 0.5 * w)
    }

    /// The ray's frame for primitive `i` (pbrt orients it by the piece's chord).
    fn frame(&self, cp: &[Vec3; 4], ray: &Ray) -> RayFrame {
        RayFrame::new(ray, ray.d.cross(cp[3] - cp[0]))
    }

    /// The closest hit of primitive `i` within `(0, t_max)`.
    pub fn intersect(&self, i: usize, ray: &Ray, t_max: f32) -> Option<CurveHit> {
        // The piece's own box first: cheaper than the ray frame, and the BVH's leaf box holds
        // several pieces.
        self.bounds(i).intersect_p(ray, ray.d.recip())?;
        let pc = self.pieces[i];
        let c = &self.curves[pc.curve as usize];
        let f = self.frame(&pc.cp, ray);
        let cp = pc.cp.map(|q| f.point(q));
        let ray_length = ray.d.length();
        let z_max = ray_length * t_max;
        let max_width = c.width_at(pc.u0).max(c.width_at(pc.u1));
        if !overlaps_ray(&cp, 0.5 * max_width, z_max) {
            return None;
        }
        // Refinement depth: subdivide until the pieces are flat to 1/20 of the width.
        let mut l0 = 0.0f32;
        for k in 0..2 {
            let d = cp[k] - cp[k + 1] * 2.0 + cp[k + 2];
            l0 = l0.max(d.x.abs().max(d.y.abs()).max(d.z.abs()));
        }
        let mut depth = 0;
        if l0 > 0.0 {
            let eps = c.width[0].max(c.width[1]) * 0.05;
            let r = std::f32::consts::SQRT_2 * 6.0 * l0 / (8.0 * eps);
            if r.is_finite() && r >= 1.0 {
                depth = ((r.log2().floor() as i32) / 2).clamp(0, 10);
            }
        }
        let mut best: Option<CurveHit> = None;
        self.recurse(c, ray, ray_length, z_max, &cp, pc.u0, pc.u1, depth, &mut best);
        best
    }

    #[allow(clippy::too_many_arguments)]
    fn recurse(
        &self,
        c: &Placed,
        ray: &Ray,
        ray_length: f32,
        z_max: f32,
        cp: &[Vec3; 4],
        u0: f32,
        u1: f32,
        depth: i32,
        best: &mut Option<CurveHit>,
    ) {
        if depth > 0 {
            let split = halves(cp);
            let u = [u0, 0.5 * (u0 + u1), u1];
            for seg in 0..2 {
                let cps = [split[3 * seg], split[3 * seg + 1], split[3 * seg + 2], split[3 * seg + 3]];
                let w = c.width_at(u[seg]).max(c.width_at(u[seg + 1]));
                let z = best.map_or(z_max, |b| b.t * ray_length);
                if overlaps_ray(&cps, 0.5 * w, z) {
                    self.recurse(c, ray, ray_length, z_max, &cps, u[seg], u[seg + 1], depth - 1, best);
                }
            }
            return;
        }
        // The ray's axis must lie between the perpendiculars at both ends.
        let edge = (cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x);
        if edge < 0.0 {
            return;
        }
        let edge = (cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x);
        if edge < 0.0 {
            return;
        }
        // The segment's parameter w closest to the axis.
        let dir = Vec2::new(cp[3].x - cp[0].x, cp[3].y - cp[0].y);
        let denom = dir.length_squared();
        if denom == 0.0 {
            return;
        }
        let w = (-Vec2::new(cp[0].x, cp[0].y)).dot(dir) / denom;
        let u = (u0 + (u1 - u0) * w).clamp(u0, u1);
        let mut hit_width = c.width_at(u);
        if self.kind == CurveKind::Ribbon {
            hit_width *= c.normal_at(u).dot(ray.d).abs() / ray_length;
        }
        let (pc, dpcdw) = evaluate(cp, w.clamp(0.0, 1.0));
        let dist2 = pc.x * pc.x + pc.y * pc.y;
        if dist2 > hit_width * hit_width * 0.25 || pc.z < 0.0 || pc.z > z_max {
            return;
        }
        let t = pc.z / ray_length;
        if best.is_some_and(|b| t > b.t) || t.is_nan() || t <= 0.0 {
            return;
        }
        let dist = dist2.sqrt();
        let edge = dpcdw.x * -pc.y + pc.x * dpcdw.y;
        let across = if hit_width > 0.0 { dist / hit_width } else { 0.0 };
        let v = if edge > 0.0 { 0.5 + across } else { 0.5 - across };
        *best = Some(CurveHit { t, uv: Vec2::new(u, v.clamp(0.0, 1.0)) });
    }

    /// The surface at a hit of primitive `i` by `ray`.
    pub fn surface(&self, i: usize, ray: &Ray, hit: CurveHit) -> CurveSurface {
        let pc = self.pieces[i];
        let c = &self.curves[pc.curve as usize];
        let (u, v) = (hit.uv.x, hit.uv.y);
        let (_, dpdu) = evaluate(&c.cp, u);
        let mut hit_width = c.width_at(u);
        let dpdv = if self.kind == CurveKind::Ribbon {
            let n = c.normal_at(u);
            hit_width *= n.dot(ray.d).abs() / ray.d.length();
            n.cross(dpdu).normalize_or_zero() * hit_width
        } else {
            let f = self.frame(&pc.cp, ray);
            let du = f.vector(dpdu);
            let mut dv = Vec3::new(-du.y, du.x, 0.0).normalize_or_zero() * hit_width;
            if self.kind == CurveKind::Cylinder {
                // Turn across the width as a tube's normal turns: by −θ about the tangent.
                let theta = (-90.0 + 180.0 * v).to_radians();
                let axis = du.normalize_or_zero();
                let (s, co) = (-theta).sin_cos();
                dv = dv * co + axis.cross(dv) * s + axis * axis.dot(dv) * (1.0 - co);
            }
            f.to_world(dv)
        };
        let mut n = dpdu.cross(dpdv).normalize_or_zero();
        if n == Vec3::ZERO {
            n = -ray.d.normalize();
        }
        if self.flip {
            n = -n;
        }
        CurveSurface { p: ray.at(hit.t), p_error: Vec3::splat(hit_width), n, dpdu, dpdv }
    }
}

/// Whether the box of `cp` grown by `grow` meets the ray's segment `[0, z_max]` on the z axis.
fn overlaps_ray(cp: &[Vec3; 4], grow: f32, z_max: f32) -> bool {
    let b = bounds_of(cp, grow);
    b.min.x <= 0.0 && b.max.x >= 0.0 && b.min.y <= 0.0 && b.max.y >= 0.0 && b.min.z <= z_max && b.max.z >= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(kind: CurveKind, width: [f32; 2]) -> Curves {
        // Along x from 0 to 4, control points evenly spaced (u = x / 4).
        let p: Vec<Vec3> = (0..4).map(|i| Vec3::new(i as f32 * 4.0 / 3.0, 0.0, 0.0)).collect();
        let normals = [Vec3::Z, Vec3::Z];
        let set = CurveSet::from_control_points(&p, 3, false, kind, &normals, width, 3).unwrap();
        Curves::new(&set, &Transform::IDENTITY, false)
    }

    fn closest(c: &Curves, ray: &Ray) -> Option<(usize, CurveHit)> {
        (0..c.len())
            .filter_map(|i| c.intersect(i, ray, f32::INFINITY).map(|h| (i, h)))
            .min_by(|a, b| a.1.t.total_cmp(&b.1.t))
    }

    /// A straight flat curve of width 0.2 seen from above: hit within half the width of its
    /// axis (at the depth of the axis, u = x / 4, v across), missed beyond; its normal faces
    /// along the ray (pbrt's), ∂p/∂u along the curve, and a tapering width narrows the band.
    #[test]
    fn straight_curve_hits_within_its_width() {
        let c = straight(CurveKind::Flat, [0.2, 0.2]);
        assert_eq!(c.len(), 8);
        let ray = |x: f32, y: f32| Ray::new(Vec3::new(x, y, 5.0), -Vec3::Z);
        let (i, h) = closest(&c, &ray(1.0, 0.05)).expect("within the width");
        assert!((h.t - 5.0).abs() < 1e-4 && (h.uv.x - 0.25).abs() < 1e-3, "{h:?}");
        assert!((h.uv.y - 0.75).abs() < 1e-3 || (h.uv.y - 0.25).abs() < 1e-3, "v = 0.5 ± 0.05 / 0.2: {h:?}");
        let s = c.surface(i, &ray(1.0, 0.05), h);
        assert!(s.n.z.abs() > 0.999 && s.dpdu.normalize().x > 0.999, "{s:?}");
        assert!(closest(&c, &ray(1.0, 0.11)).is_none());
        assert!(closest(&c, &ray(4.2, 0.0)).is_none(), "beyond the end");
        let taper = straight(CurveKind::Flat, [0.4, 0.0]);
        assert!(closest(&taper, &ray(0.5, 0.15)).is_some() && closest(&taper, &ray(3.5, 0.15)).is_none());
        // A cylinder's normal turns across the width; at the middle it faces the ray.
        let cyl = straight(CurveKind::Cylinder, [0.2, 0.2]);
        let (i, h) = closest(&cyl, &ray(2.0, 0.09)).unwrap();
        let n = cyl.surface(i, &ray(2.0, 0.09), h).n;
        assert!(n.y.abs() > 0.9, "near the edge the normal lies sideways: {n}");
        let (i, h) = closest(&cyl, &ray(2.0, 0.0)).unwrap();
        assert!(cyl.surface(i, &ray(2.0, 0.0), h).n.z.abs() > 0.99);
    }

    /// A bent curve: the hit lies on it within the width, at the parameter the curve passes the
    /// ray, for rays from many directions; bounds hold every piece.
    #[test]
    fn bent_curve_hits_lie_on_the_curve() {
        let cp = [Vec3::ZERO, Vec3::new(1.0, 2.0, 0.0), Vec3::new(3.0, -1.0, 1.0), Vec3::new(4.0, 1.0, 0.5)];
        let set = CurveSet {
            kind: CurveKind::Flat,
            curves: vec![Bezier { cp, width: [0.05, 0.05], normals: None }],
            split_depth: 3,
        };
        let c = Curves::new(&set, &Transform::IDENTITY, false);
        let mut rng = crate::sampling::Pcg32::new(3, 1);
        let mut hits = 0;
        for _ in 0..2000 {
            let u = rng.next_f32();
            let (p, _) = evaluate(&cp, u);
            for i in 0..c.len() {
                let b = c.bounds(i);
                let pc = c.pieces[i];
                if u >= pc.u0 && u <= pc.u1 {
                    assert!(b.min.cmple(p).all() && b.max.cmpge(p).all(), "{p} outside piece {i}");
                }
            }
            let d = crate::sampling::sample_uniform_sphere(crate::testkit::u2(&mut rng)).value;
            let ray = Ray::new(p - d * 10.0, d);
            if let Some((_, h)) = closest(&c, &ray) {
                hits += 1;
                let q = ray.at(h.t);
                let (on, _) = evaluate(&cp, h.uv.x);
                assert!((q - on).length() < 0.06, "hit {q} vs curve {on} (u {})", h.uv.x);
            }
        }
        assert!(hits > 1900, "rays aimed at the curve hit it: {hits}");
    }

    /// pbrt's bases: a uniform cubic B-spline of collinear, evenly spaced points is a straight
    /// line (its Bézier points too); degree-2 curves are elevated; counts are checked.
    #[test]
    fn bases_and_degrees() {
        let p: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let s = CurveSet::from_control_points(&p, 3, true, CurveKind::Flat, &[], [1.0, 0.5], 2).unwrap();
        assert_eq!(s.curves.len(), 3);
        assert!((s.curves[0].cp[0] - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6);
        assert!((s.curves[2].cp[3] - Vec3::new(4.0, 0.0, 0.0)).length() < 1e-6);
        assert_eq!(s.curves[1].width, [1.0 - 0.5 / 3.0, 1.0 - 1.0 / 3.0]);
        let q = CurveSet::from_control_points(&p[..5], 2, false, CurveKind::Flat, &[], [1.0, 1.0], 0).unwrap();
        assert_eq!(q.curves.len(), 2);
        assert!((q.curves[1].cp[1] - Vec3::new(2.0 + 2.0 / 3.0, 0.0, 0.0)).length() < 1e-6);
        assert!(CurveSet::from_control_points(&p[..5], 3, false, CurveKind::Flat, &[], [1.0, 1.0], 0).is_err());
        assert!(CurveSet::from_control_points(&p[..4], 3, false, CurveKind::Ribbon, &[Vec3::Z], [1.0, 1.0], 0).is_err());
    }
}
