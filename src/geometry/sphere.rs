//! Spheres: analytic intersection (pbrt-v4's robust discriminant) and sampling of the cone
//! they subtend from a reference point; partial spheres (pbrt-v4's `zmin`, `zmax`, `phimax`).

use crate::math::float::gamma;
use crate::math::lanes::{FrameW, Fw, V3w};
use crate::math::{safe_sqrt, spherical_direction, Frame, Mat3, Ray, Vec2, Vec3, INV_4PI, PI};
use crate::sampling::sample_uniform_sphere;

/// A sphere in world space. `flip` turns normals inward (Mitsuba's `flip_normals`): the
/// inside becomes the front side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
    /// Whether normals point inward.
    pub flip: bool,
    /// How the object's frame, which orients the (u, v) parameterization, sits in world space.
    pub orientation: Orientation,
    /// The part of the sphere that exists ([`SphereClip::FULL`]: all of it).
    pub clip: SphereClip,
}

/// The object's frame of a sphere: `to_world` maps object directions to world ones (columns:
/// the object's axes), `to_world / radius` of the shape's transform, and `to_object` is its
/// inverse. For the similarities that Mitsuba and pbrt-v4 expect `to_world` is a rotation (a
/// reflection allowed). Mitsuba also takes a `to_world` that scales unevenly or shears (with a
/// warning): its surface is then the sphere of centre `to_world(0)` and radius `|to_world · x̂|`,
/// while the (u, v) parameterization and its derivatives keep the whole map (`stretched`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orientation {
    /// Object directions to world ones (divided by the radius).
    pub to_world: Mat3,
    /// The inverse of `to_world`.
    pub to_object: Mat3,
    /// Whether `to_world` is not a rotation (Mitsuba's uneven scales and shears).
    pub stretched: bool,
}

impl Orientation {
    /// The world axes.
    pub const IDENTITY: Orientation =
        Orientation { to_world: Mat3::IDENTITY, to_object: Mat3::IDENTITY, stretched: false };

    /// A rotation (orthonormal columns, a reflection allowed).
    pub fn rotation(r: Mat3) -> Orientation {
        Orientation { to_world: r, to_object: r.transpose(), stretched: false }
    }

    /// Any invertible linear map (Mitsuba's stretched spheres); `None` if it is singular or not
    /// finite.
    pub fn stretched(m: Mat3) -> Option<Orientation> {
        let inv = m.inverse();
        (m.determinant() != 0.0 && inv.is_finite()).then_some(Orientation {
            to_world: m,
            to_object: inv,
            stretched: true,
        })
    }
}

/// A partial sphere, in the object's frame (`orientation`) of the unit sphere: the points with
/// `z_min ≤ z ≤ z_max` and azimuth `φ = atan2(y, x) ∈ [0, 2π)` at most `phi_max` (pbrt-v4's
/// `zmin`, `zmax` divided by the radius and `phimax` in radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereClip {
    /// Lowest z, in `[-1, 1)`.
    pub z_min: f32,
    /// Highest z, in `(z_min, 1]`.
    pub z_max: f32,
    /// Largest azimuth, radians in `(0, 2π]`.
    pub phi_max: f32,
}

impl SphereClip {
    /// The whole sphere.
    pub const FULL: SphereClip = SphereClip { z_min: -1.0, z_max: 1.0, phi_max: 2.0 * PI };

    /// The clip of pbrt-v4's sphere parameters (object units, `phimax` in degrees), clamped as
    /// pbrt clamps them; `None` if nothing is left.
    pub fn from_pbrt(radius: f32, zmin: f32, zmax: f32, phimax_degrees: f32) -> Option<SphereClip> {
        let z_min = (zmin.min(zmax) / radius).clamp(-1.0, 1.0);
        let z_max = (zmin.max(zmax) / radius).clamp(-1.0, 1.0);
        let phi_max = phimax_degrees.clamp(0.0, 360.0).to_radians();
        (z_max > z_min && phi_max > 0.0).then_some(SphereClip { z_min, z_max, phi_max })
    }

    /// Whether anything is cut away.
    #[inline]
    pub fn is_partial(&self) -> bool {
        *self != SphereClip::FULL
    }

    /// Whether the unit-sphere point `local` (object frame) is kept.
    #[inline]
    fn contains(&self, local: Vec3) -> bool {
        local.z >= self.z_min
            && local.z <= self.z_max
            && (self.phi_max >= 2.0 * PI || crate::math::spherical_phi(local) <= self.phi_max)
    }
}

/// A hit on a sphere: ray parameter.
#[derive(Clone, Copy, Debug)]
pub struct SphereHit {
    /// Ray parameter.
    pub t: f32,
}

/// A point sampled on a surface with its pdf.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// Position.
    pub p: Vec3,
    /// Unit normal (front side).
    pub n: Vec3,
    /// Error bound of `p`.
    pub p_error: Vec3,
}

impl Sphere {
    /// A sphere with its parameterization aligned with the world axes.
    pub fn new(center: Vec3, radius: f32, flip: bool) -> Sphere {
        Sphere { center, radius, flip, orientation: Orientation::IDENTITY, clip: SphereClip::FULL }
    }

    /// Surface area: `4π r²`, of a partial sphere `φ_max r² (z_max − z_min)` (Archimedes).
    pub fn area(&self) -> f32 {
        self.clip.phi_max * self.radius * self.radius * (self.clip.z_max - self.clip.z_min)
    }

    /// Closest intersection in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<SphereHit> {
        // a t² + 2 h t + c = 0 with h = d·(o − centre): t = (−h ± √(h² − a c)) / a.
        let oc = ray.o - self.center;
        let a = ray.d.length_squared();
        // One division by a, beside the dot products (a, h and c do not wait for each other).
        let inv_a = 1.0 / a;
        let h = ray.d.dot(oc);
        let r2 = self.radius * self.radius;
        let c = oc.length_squared() - r2;
        // h² − a c = a (r² − |f|²), f = oc − (h / a) d the centre's offset from the ray's closest
        // approach: no cancellation between h² and a c (Haines et al., Ray Tracing Gems, ch. 7).
        let f = oc - (h * inv_a) * ray.d;
        let disc = a * (r2 - f.length_squared());
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        // q = −(h + sign(h) √disc): the root of larger magnitude, then the other as c / q.
        let q = if h < 0.0 { root - h } else { -(h + root) };
        let (mut t0, mut t1) = (q * inv_a, c / q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 >= t_max || t1 <= 0.0 {
            return None;
        }
        if self.clip.is_partial() {
            // The nearer root may lie on the part cut away: then the farther one may be kept.
            return [t0, t1]
                .into_iter()
                .find(|&t| t > 0.0 && t < t_max && self.keeps(ray.at(t)))
                .map(|t| SphereHit { t });
        }
        let t = if t0 > 0.0 { t0 } else { t1 };
        (t < t_max).then_some(SphereHit { t })
    }

    /// Whether the world point `p` (on the sphere) lies on the part that exists.
    #[inline]
    fn keeps(&self, p: Vec3) -> bool {
        self.clip.contains(self.orientation.to_object * ((p - self.center) / self.radius))
    }

    /// Reprojects the hit at `ray.at(t)` onto the sphere: point, error bound, outward-or-flipped
    /// unit normal, and (u, v) = (φ / 2π, θ / π) of the outward direction in the object's frame
    /// (Mitsuba's parameterization, turned with `to_world`; see [`Sphere::uv_of_direction`] for
    /// partial spheres).
    #[inline]
    pub fn surface(&self, ray: &Ray, t: f32) -> (SurfacePoint, Vec2) {
        let v = self.hit_direction(ray, t);
        (self.point(v), self.uv_of_direction(v))
    }

    /// [`Sphere::surface`]'s point alone (no texture coordinates: an arctangent and an arc
    /// cosine fewer).
    #[inline]
    pub fn surface_point(&self, ray: &Ray, t: f32) -> SurfacePoint {
        self.point(self.hit_direction(ray, t))
    }

    /// [`Sphere::surface`]'s texture coordinates alone, the same bits.
    #[inline]
    pub fn surface_uv(&self, ray: &Ray, t: f32) -> Vec2 {
        self.uv_of_direction(self.hit_direction(ray, t))
    }

    /// Unit direction from the centre to the hit at `ray.at(t)`.
    #[inline(always)]
    fn hit_direction(&self, ray: &Ray, t: f32) -> Vec3 {
        (ray.at(t) - self.center).normalize_or(Vec3::Z)
    }

    /// (u, v) = (φ / 2π, θ / π) of the point in unit direction `v` from the centre (world),
    /// in the object's frame. A partial sphere stretches them over what exists, as pbrt-v4 does:
    /// `u = φ / φ_max`, `v = (θ − θ(z_max)) / (θ(z_min) − θ(z_max))`. A stretched orientation
    /// maps `v` to a direction that is not a unit one: θ is then Mitsuba's `unit_angle_z` of it
    /// (`2 asin(|(x, y, |z| − 1)| / 2)`, from the pole of z's sign), as Mitsuba computes it,
    /// the arcsine's argument clamped to 1 (where Mitsuba's θ is NaN).
    #[inline]
    pub fn uv_of_direction(&self, v: Vec3) -> Vec2 {
        let local = self.orientation.to_object * v;
        let theta = if self.orientation.stretched {
            let half = (0.5 * Vec3::new(local.x, local.y, local.z.abs() - 1.0).length()).min(1.0).asin() * 2.0;
            if local.z >= 0.0 {
                half
            } else {
                PI - half
            }
        } else {
            crate::math::spherical_theta(local)
        };
        let phi = crate::math::spherical_phi(local);
        if !self.clip.is_partial() {
            return Vec2::new(phi / (2.0 * PI), theta / PI);
        }
        let (top, span) = self.theta_range();
        Vec2::new(phi / self.clip.phi_max, (theta - top) / span)
    }

    /// `θ(z_max)` and `θ(z_min) − θ(z_max)`: the polar angles the (partial) sphere spans.
    #[inline]
    fn theta_range(&self) -> (f32, f32) {
        let top = self.clip.z_max.clamp(-1.0, 1.0).acos();
        (top, self.clip.z_min.clamp(-1.0, 1.0).acos() - top)
    }

    /// `(∂p/∂u, ∂p/∂v)` at the surface point `p` for `uv = (φ / 2π, θ / π)`, as Mitsuba gives
    /// them: `2π (−y, x, 0)` and `π (z cos φ, z sin φ, −√(x² + y²))` in the object frame, turned
    /// to world space (∂p/∂u vanishes at the poles); `∂p/∂v` only `with_v` (else zero).
    #[inline]
    pub fn dpduv(&self, p: Vec3, with_v: bool) -> (Vec3, Vec3) {
        let local = self.orientation.to_object * (p - self.center);
        // ∂φ/∂u and ∂θ/∂v: 2π and π for the whole sphere.
        let (du, dv) = if self.clip.is_partial() { (self.clip.phi_max, self.theta_range().1) } else { (2.0 * PI, PI) };
        if !with_v {
            return (self.orientation.to_world * (Vec3::new(-local.y, local.x, 0.0) * du), Vec3::ZERO);
        }
        let rd = local.x.hypot(local.y);
        let (cos_phi, sin_phi) = if rd > 0.0 { (local.x / rd, local.y / rd) } else { (1.0, 0.0) };
        let dpdu = Vec3::new(-local.y, local.x, 0.0) * du;
        let dpdv = Vec3::new(local.z * cos_phi, local.z * sin_phi, -rd) * dv;
        (self.orientation.to_world * dpdu, self.orientation.to_world * dpdv)
    }

    /// The point in unit direction `v` from the centre, its normal and error bound.
    fn point(&self, v: Vec3) -> SurfacePoint {
        let p = self.center + self.radius * v;
        SurfacePoint {
            p,
            n: if self.flip { -v } else { v },
            p_error: gamma(5) * (self.radius * v).abs() + gamma(2) * p.abs(),
        }
    }

    /// Uniform point on the surface; pdf `1 / (4π r²)` per unit area (`1 / area` for a partial
    /// sphere: z uniform in `[z_min, z_max]` and φ in `[0, φ_max]`, uniform in area by
    /// Archimedes' theorem).
    pub fn sample_area(&self, u: Vec2) -> (SurfacePoint, f32) {
        if self.clip.is_partial() {
            let c = self.clip;
            let z = c.z_min + u.x * (c.z_max - c.z_min);
            let r = safe_sqrt(1.0 - z * z);
            let (s, co) = (u.y * c.phi_max).sin_cos();
            let v = self.orientation.to_world * Vec3::new(r * co, r * s, z);
            return (self.point(v), 1.0 / self.area());
        }
        let v = sample_uniform_sphere(u).value;
        (self.point(v), INV_4PI / (self.radius * self.radius))
    }

    /// A point on the sphere seen from `p_ref`, sampled uniformly in the cone of directions the
    /// sphere subtends (pbrt-v4 §6.2.4), with pdf `1 / (2π (1 - cos θ_max))` per unit solid
    /// angle at `p_ref`. From inside the sphere, falls back to uniform area sampling and returns
    /// the area pdf converted to solid angle, as does a partial sphere (whose cone holds
    /// directions to the part cut away). `None` if the conversion is degenerate.
    pub fn sample_solid_angle(&self, p_ref: Vec3, u: Vec2) -> Option<(SurfacePoint, f32)> {
        let dc2 = (p_ref - self.center).length_squared();
        let r2 = self.radius * self.radius;
        if dc2 <= r2 * (1.0 + 1e-4) || self.clip.is_partial() {
            let (sp, pdf_a) = self.sample_area(u);
            let d = sp.p - p_ref;
            let cos = sp.n.dot(-d.normalize_or_zero()).abs();
            let pdf = crate::sampling::area_to_solid_angle(pdf_a, d.length_squared(), cos);
            return (pdf > 0.0 && pdf.is_finite()).then_some((sp, pdf));
        }
        let dc = dc2.sqrt();
        let sin2_max = r2 / dc2;
        let sin_max = sin2_max.sqrt();
        let cos_max = safe_sqrt(1.0 - sin2_max);
        let mut one_minus_cos_max = 1.0 - cos_max;
        let mut cos_theta = (cos_max - 1.0) * u.x + 1.0;
        let mut sin2_theta = 1.0 - cos_theta * cos_theta;
        if sin2_max < 0.000_685_23 {
            // Small cones: use sin² (Taylor) to keep precision.
            sin2_theta = sin2_max * u.x;
            cos_theta = (1.0 - sin2_theta).sqrt();
            one_minus_cos_max = sin2_max / 2.0;
        }
        // Angle α at the centre between -(direction to p_ref) and the sampled point.
        let cos_alpha = sin2_theta / sin_max + cos_theta * safe_sqrt(1.0 - sin2_theta / sin2_max);
        let sin_alpha = safe_sqrt(1.0 - cos_alpha * cos_alpha);
        let phi = u.y * 2.0 * PI;
        let w = spherical_direction(sin_alpha, cos_alpha, phi);
        let frame = Frame::from_z((self.center - p_ref) / dc);
        let v = frame.to_world(-w);
        Some((self.point(v), 1.0 / (2.0 * PI * one_minus_cos_max)))
    }

    /// Solid-angle pdf of [`Sphere::sample_solid_angle`] for the point `p` (on the sphere, seen
    /// from `p_ref` along `wi`).
    pub fn pdf_solid_angle(&self, p_ref: Vec3, p: Vec3, n: Vec3) -> f32 {
        let dc2 = (p_ref - self.center).length_squared();
        let r2 = self.radius * self.radius;
        if dc2 <= r2 * (1.0 + 1e-4) || self.clip.is_partial() {
            let d = p - p_ref;
            let cos = n.dot(d.normalize_or_zero()).abs();
            return crate::sampling::area_to_solid_angle(1.0 / self.area(), d.length_squared(), cos);
        }
        let sin2_max = r2 / dc2;
        let cos_max = safe_sqrt(1.0 - sin2_max);
        let one_minus_cos_max = if sin2_max < 0.000_685_23 { sin2_max / 2.0 } else { 1.0 - cos_max };
        1.0 / (2.0 * PI * one_minus_cos_max)
    }
}

/// [`Sphere::sample_solid_angle`] of `W` whole spheres (centres `center`, radii `radius`) in
/// lanes, from reference points `p_ref` outside them (`|p_ref − c|² > r² (1 + 10⁻⁴)`: the
/// caller takes the others, and partial spheres, lane by lane): each lane's point on the
/// sphere, its unit direction `v` from the centre (the normal: `v`, `−v` where the sphere is
/// flipped), the point's error bound, and the density per unit solid angle seen from `p_ref`.
/// Bit for bit the scalar code's: the same operations in the same order, the azimuth's sine
/// and cosine lane by lane by the same `sin_cos`.
#[inline(always)]
pub(crate) fn sample_cone_lanes<const W: usize>(
    center: V3w<W>,
    radius: Fw<W>,
    p_ref: V3w<W>,
    ux: Fw<W>,
    uy: Fw<W>,
) -> (V3w<W>, V3w<W>, V3w<W>, Fw<W>) {
    let zero = Fw::splat(0.0);
    let dc2 = (p_ref - center).length_squared();
    let r2 = radius * radius;
    let dc = dc2.sqrt();
    let sin2_max = r2 / dc2;
    let sin_max = sin2_max.sqrt();
    let cos_max = (1.0 - sin2_max).max(zero).sqrt();
    // Small cones: sin² (Taylor) keeps the precision, as in the scalar code.
    let small = sin2_max.lt(Fw::splat(0.000_685_23));
    let cos_theta = (cos_max - 1.0) * ux + 1.0;
    let sin2_theta = Fw::select(small, sin2_max * ux, 1.0 - cos_theta * cos_theta);
    let cos_theta = Fw::select(small, (1.0 - sin2_theta).sqrt(), cos_theta);
    let one_minus_cos_max = Fw::select(small, sin2_max / 2.0, 1.0 - cos_max);
    let cos_alpha = sin2_theta / sin_max + cos_theta * (1.0 - sin2_theta / sin2_max).max(zero).sqrt();
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(zero).sqrt();
    let phi = uy * 2.0 * PI;
    let (mut sin_phi, mut cos_phi) = (zero, zero);
    for k in 0..W {
        (sin_phi.0[k], cos_phi.0[k]) = phi.0[k].sin_cos();
    }
    let (sin_alpha, cos_alpha) = (sin_alpha.clamp(-1.0, 1.0), cos_alpha.clamp(-1.0, 1.0));
    let w = V3w::new(sin_alpha * cos_phi, sin_alpha * sin_phi, cos_alpha);
    let v = FrameW::from_z((center - p_ref) / dc).to_world(-w);
    let scaled = v.scale(radius);
    let p = center + scaled;
    let p_error = scaled.abs().scale(Fw::splat(gamma(5))) + p.abs().scale(Fw::splat(gamma(2)));
    (p, v, p_error, 1.0 / (2.0 * PI * one_minus_cos_max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, u2, Chi2Config, SphericalCap};

    /// The (u, v) parameterization turns with the sphere: a sphere rotated 90° about x has its
    /// pole (v = 0) where the unrotated one has its equator facing −y.
    #[test]
    fn parameterization_follows_the_rotation() {
        let rot = Mat3::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let s = Sphere { orientation: Orientation::rotation(rot), ..Sphere::new(Vec3::ZERO, 2.0, false) };
        // The object's +z axis now points along world −y.
        let ray = Ray::new(Vec3::new(0.0, -5.0, 0.0), Vec3::Y);
        let t = s.intersect(&ray, f32::INFINITY).unwrap().t;
        let (p, uv) = s.surface(&ray, t);
        assert!((p.p - Vec3::new(0.0, -2.0, 0.0)).length() < 1e-5);
        assert!(uv.y < 1e-3, "{uv}");
        let (_, uv0) = Sphere::new(Vec3::ZERO, 2.0, false).surface(&ray, t);
        assert!((uv0.y - 0.5).abs() < 1e-5 && (uv0.x - 0.75).abs() < 1e-5, "{uv0}");
    }

    /// pbrt-v4's partial sphere: the nearer crossing on the part cut away lets the ray through
    /// to the farther one; area `φ_max r² (z_max − z_min)`; (u, v) spans [0, 1]² over what is
    /// left; area samples stay on it.
    #[test]
    fn partial_sphere_intersection_area_and_uv() {
        // Radius 2, z in [-1, 1.5] (object units), φ up to 270°.
        let clip = SphereClip::from_pbrt(2.0, -1.0, 1.5, 270.0).unwrap();
        let s = Sphere { clip, ..Sphere::new(Vec3::ZERO, 2.0, false) };
        let phi_max = 1.5 * PI;
        assert!((s.area() - phi_max * 4.0 * (0.75 + 0.5)).abs() < 1e-4, "{}", s.area());
        // From above, along −z: the cap z > 1.5 is gone, so the ray meets the inside of the
        // bottom... which is cut too (z < −1): it misses. Off-axis at x = 1.5 it hits the
        // side at z = +√(4 − 2.25) ≈ 1.32 (kept: below 1.5).
        assert!(s.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z), f32::INFINITY).is_none());
        let t = s.intersect(&Ray::new(Vec3::new(1.5, 0.0, 5.0), -Vec3::Z), f32::INFINITY).unwrap().t;
        assert!((t - (5.0 - 1.75f32.sqrt())).abs() < 1e-4, "{t}");
        // Along +y at x = 0.5 the ray enters at φ ≈ 285° (cut: beyond 270°) and leaves at
        // φ ≈ 75° (kept); from the other side the nearer crossing is that kept one.
        for (y0, dir) in [(-5.0, Vec3::Y), (5.0, -Vec3::Y)] {
            let ray = Ray::new(Vec3::new(0.5, y0, 0.0), dir);
            let t = s.intersect(&ray, f32::INFINITY).unwrap().t;
            assert!((ray.at(t).y - 3.75f32.sqrt()).abs() < 1e-4, "{}", ray.at(t));
        }
        let mut rng = crate::sampling::Pcg32::new(3, 9);
        let (mut lo, mut hi) = (Vec2::splat(1.0), Vec2::splat(0.0));
        for _ in 0..20_000 {
            let (sp, pdf) = s.sample_area(u2(&mut rng));
            let local = sp.p / 2.0;
            let phi = crate::math::spherical_phi(local);
            let kept_phi = phi <= clip.phi_max + 1e-4 || phi >= 2.0 * PI - 1e-4;
            assert!(local.z >= clip.z_min - 1e-5 && local.z <= clip.z_max + 1e-5 && kept_phi, "{local}");
            assert!((pdf - 1.0 / s.area()).abs() < 1e-7);
            let uv = s.uv_of_direction(local);
            lo = lo.min(uv);
            hi = hi.max(uv);
        }
        assert!(lo.min_element() > -1e-4 && hi.max_element() < 1.0 + 1e-4, "{lo} {hi}");
        assert!(lo.max_element() < 0.01 && hi.min_element() > 0.99, "{lo} {hi}");
    }

    /// Directions toward a partial sphere (sampled by area, converted) follow
    /// `pdf_solid_angle` summed over the kept crossings of each direction (χ² over the sphere of
    /// directions), from outside and from inside; so the pdf integrates to one.
    #[test]
    fn partial_sphere_sampling_chi2() {
        use crate::testkit::SPHERE;
        let rot = Mat3::from_rotation_x(0.4) * Mat3::from_rotation_z(0.3);
        let clip = SphereClip::from_pbrt(1.0, -0.6, 0.8, 250.0).unwrap();
        // Placed off the poles of the direction sphere's (z, φ) cells, whose slivers there a
        // cut edge could hide from the quadrature.
        let s = Sphere {
            orientation: Orientation::rotation(rot),
            clip,
            ..Sphere::new(Vec3::new(2.5, 0.3, 0.2), 1.0, false)
        };
        for (k, p_ref) in [Vec3::ZERO, Vec3::new(2.4, 0.3, 0.3)].into_iter().enumerate() {
            let pdf = |w: &Vec3| -> f64 {
                // Both crossings of the whole sphere along w, each counted where it is kept.
                let oc = (p_ref - s.center).as_dvec3();
                let wd = w.as_dvec3();
                let (b, c) = (oc.dot(wd), oc.length_squared() - 1.0);
                let disc = b * b - c;
                if disc < 0.0 {
                    return 0.0;
                }
                [-b - disc.sqrt(), -b + disc.sqrt()]
                    .into_iter()
                    .filter(|&t| t > 0.0)
                    .map(|t| (p_ref.as_dvec3() + t * wd).as_vec3())
                    .filter(|&p| s.keeps(p))
                    .map(|p| s.pdf_solid_angle(p_ref, p, (p - s.center).normalize()) as f64)
                    .sum()
            };
            let out = chi2_2d(
                &SPHERE,
                [41, 81],
                400_000,
                |r| s.sample_solid_angle(p_ref, u2(r)).map(|(sp, _)| (sp.p - p_ref).normalize()),
                pdf,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "reference point {k}: {out}");
        }
    }

    #[test]
    fn intersect_from_outside_and_inside() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0, false);
        let h = s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), f32::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-5);
        let inside = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::X);
        assert!((s.intersect(&inside, f32::INFINITY).unwrap().t - 1.0).abs() < 1e-6);
        assert!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).is_none());
        assert!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), 3.0).is_none());
    }

    /// Small spheres far away (where b² − 4ac cancels catastrophically): the distance within
    /// 10⁻⁶ of the exact `f64` root relative to the distance, and rays that pass the sphere
    /// by 1 % of its radius (beyond or within) miss or hit as they should.
    #[test]
    fn small_far_spheres_are_hit_precisely() {
        let mut rng = crate::sampling::Pcg32::new(7, 7);
        for &(radius, dist) in &[(1e-3f32, 1e4f32), (0.01, 100.0), (1.0, 1e3), (0.05, 30.0)] {
            let s = Sphere::new(Vec3::new(0.3, -0.2, dist), radius, false);
            for _ in 0..2000 {
                // Aim at the centre offset sideways by a fraction of the radius.
                let k = 1.02 * rng.next_f32();
                let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
                let target = s.center + Vec3::new(phi.cos(), phi.sin(), 0.0) * (k * radius);
                let ray = Ray::new(Vec3::ZERO, target.normalize());
                let hit = s.intersect(&ray, f32::INFINITY);
                // The exact answer in f64 for this (rounded) ray.
                let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
                let oc = o - s.center.as_dvec3();
                let (a, h, c) = (d.dot(d), d.dot(oc), oc.dot(oc) - (radius as f64).powi(2));
                let disc = h * h - a * c;
                if k < 0.99 {
                    let exact = (-h - disc.sqrt()) / a;
                    let t = hit.expect("a ray aimed inside the sphere hits it").t as f64;
                    assert!((t - exact).abs() <= 1e-6 * exact, "r {radius}, k {k}: {t} vs {exact}");
                } else if k > 1.01 {
                    assert!(hit.is_none(), "r {radius}, k {k}: a ray passing outside hit at {:?}", hit.map(|h| h.t));
                }
            }
        }
    }

    #[test]
    fn leaving_the_surface_never_hits_it_again() {
        // Rays leaving points of a sphere outward (from outside) must not re-hit it, and rays
        // going inward must hit the far side, not the start point.
        let s = Sphere::new(Vec3::new(3.0, -2.0, 1.0), 2.5, false);
        let mut rng = crate::sampling::Pcg32::new(3, 3);
        for _ in 0..20_000 {
            let (sp, _) = s.sample_area(u2(&mut rng));
            let w = sample_uniform_sphere(u2(&mut rng)).value;
            let o = crate::math::float::offset_ray_origin(sp.p, sp.p_error, sp.n, w);
            let hit = s.intersect(&Ray::new(o, w), f32::INFINITY);
            if w.dot(sp.n) > 0.0 {
                assert!(hit.is_none(), "outgoing ray re-hit its sphere at t = {:?}", hit.map(|h| h.t));
            } else if let Some(h) = hit {
                assert!(h.t > 1e-3 * s.radius * (-w.dot(sp.n)), "self-hit at t = {}", h.t);
            }
        }
    }

    /// The cone sample in lanes is the scalar one bit for bit: spheres near and far (small
    /// cones take the Taylor branch), flipped or not, at widths 4, 8 and 16.
    #[test]
    fn cone_sampling_in_lanes_is_the_scalar_one() {
        fn check<const W: usize>(rng: &mut crate::sampling::Pcg32) {
            for _ in 0..400 {
                let mut spheres = [Sphere::new(Vec3::ZERO, 1.0, false); W];
                let mut p_ref = [Vec3::ZERO; W];
                let mut u = [Vec2::ZERO; W];
                for k in 0..W {
                    let mut r = || rng.next_f32();
                    let c = Vec3::new(r() * 20.0 - 10.0, r() * 20.0 - 10.0, r() * 20.0 - 10.0);
                    let radius = 0.01 + 3.0 * r() * r();
                    // Directions of every octant, distances from just outside to a thousand radii.
                    let dir = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize();
                    let dist = radius * (1.001 + 1000.0 * r() * r() * r());
                    spheres[k] = Sphere::new(c, radius, r() < 0.5);
                    (p_ref[k], u[k]) = (c + dir * dist, Vec2::new(r(), r()));
                }
                let (p, v, err, pdf) = sample_cone_lanes(
                    V3w::<W>::from_fn(|k| spheres[k].center),
                    Fw::from_fn(|k| spheres[k].radius),
                    V3w::from_fn(|k| p_ref[k]),
                    Fw::from_fn(|k| u[k].x),
                    Fw::from_fn(|k| u[k].y),
                );
                for k in 0..W {
                    let (sp, want_pdf) = spheres[k].sample_solid_angle(p_ref[k], u[k]).unwrap();
                    let n = if spheres[k].flip { -v.lane(k) } else { v.lane(k) };
                    let bits = |a: Vec3| a.to_array().map(f32::to_bits);
                    assert_eq!(bits(p.lane(k)), bits(sp.p), "point, lane {k}");
                    assert_eq!(bits(n), bits(sp.n), "normal, lane {k}");
                    assert_eq!(bits(err.lane(k)), bits(sp.p_error), "error bound, lane {k}");
                    assert_eq!(pdf.lane(k).to_bits(), want_pdf.to_bits(), "density, lane {k}");
                }
            }
        }
        let mut rng = crate::sampling::Pcg32::new(7, 3);
        check::<4>(&mut rng);
        check::<8>(&mut rng);
        check::<16>(&mut rng);
    }

    #[test]
    fn cone_sampling_chi2_and_pdf() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, 4.0), 1.5, false);
        let p_ref = Vec3::ZERO;
        let cos_max = (1.0 - (1.5f64 / 4.0).powi(2)).sqrt();
        let out = chi2_2d(
            &SphericalCap { z_min: cos_max - 1e-6 },
            [15, 31],
            500_000,
            |r| s.sample_solid_angle(p_ref, u2(r)).map(|(sp, _)| (sp.p - p_ref).normalize()),
            |w| {
                let h = s.intersect(&Ray::new(p_ref, *w), f32::INFINITY);
                match h {
                    Some(h) => {
                        let (sp, _) = s.surface(&Ray::new(p_ref, *w), h.t);
                        s.pdf_solid_angle(p_ref, sp.p, sp.n) as f64
                    }
                    None => 0.0,
                }
            },
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        // The sampled points lie on the sphere, on the visible side.
        let mut rng = crate::sampling::Pcg32::new(1, 1);
        for _ in 0..1000 {
            let (sp, pdf) = s.sample_solid_angle(p_ref, u2(&mut rng)).unwrap();
            assert!(((sp.p - s.center).length() - 1.5).abs() < 1e-4);
            assert!(sp.n.dot(p_ref - sp.p) >= -1e-4);
            assert!((pdf - s.pdf_solid_angle(p_ref, sp.p, sp.n)).abs() < 1e-3 * pdf);
        }
    }

    /// Cone sampling stays exact for tiny cones (sin θ_max from 0.1 down to 1e-4, where f32
    /// directions cannot resolve the cone on the unit sphere): in the cone's own coordinates,
    /// computed in f64 from the sampled points, `((1 − cos θ)/(1 − cos θ_max), φ/2π)` is uniform
    /// (χ²); the pdf is `1/(2π(1 − cos θ_max))` to 1e-3; every point lies on the cap visible from
    /// the reference point, and the shadow ray toward it is not blocked by the sphere itself.
    #[test]
    fn tiny_cones_are_sampled_exactly() {
        use crate::geometry::interaction::SHADOW_EPSILON;
        use crate::math::float::offset_ray_origin;
        use crate::testkit::Rect;
        let p_ref = Vec3::new(0.3, -1.2, 2.0);
        let axis = Vec3::new(0.48, 0.6, -0.64); // unit
        for (k, sin_max) in [0.1f64, 1e-2, 1e-3, 1e-4].into_iter().enumerate() {
            let dist = 4.0f32;
            let s = Sphere::new(p_ref + axis * dist, (sin_max * dist as f64) as f32, false);
            let c = (s.center - p_ref).as_dvec3();
            let (dc, r) = (c.length(), s.radius as f64);
            let w = c / dc;
            let one_minus_cos_max = 1.0 - (1.0 - (r / dc).powi(2)).sqrt();
            let (t1, t2) = {
                let t = if w.x.abs() < 0.9 { glam::DVec3::X } else { glam::DVec3::Y };
                let t1 = w.cross(t).normalize();
                (t1, w.cross(t1))
            };
            let to_cone = |q: Vec3| -> Vec2 {
                let d = (q - p_ref).as_dvec3().normalize();
                // 1 − cos θ = 2 sin²(θ/2) = |d − w|² / 2, without cancellation.
                let u = (d - w).length_squared() / 2.0 / one_minus_cos_max;
                // Points at the silhouette may leave the cone by the f32 rounding of their
                // position (≈ 1e-7 |p| across a cone of radius r: up to a few 1e-3 of u at the
                // smallest cone); further out is an error.
                let u = if u > 1.0 && u < 1.01 { 1.0 } else { u };
                let phi = d.dot(t2).atan2(d.dot(t1));
                Vec2::new(u as f32, ((phi / std::f64::consts::TAU).rem_euclid(1.0)) as f32)
            };
            let out = chi2_2d(
                &Rect::UNIT,
                [11, 13],
                200_000,
                |rng| s.sample_solid_angle(p_ref, u2(rng)).map(|(sp, _)| to_cone(sp.p)),
                |_| 1.0,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "sin θ_max = {sin_max}: {out}");
            let want_pdf = 1.0 / (2.0 * std::f64::consts::PI * one_minus_cos_max);
            let mut rng = crate::sampling::Pcg32::new(2, k as u64);
            for _ in 0..20_000 {
                let (sp, pdf) = s.sample_solid_angle(p_ref, u2(&mut rng)).expect("a sample");
                assert!(((pdf as f64) / want_pdf - 1.0).abs() < 1e-3, "sin θ_max = {sin_max}: pdf {pdf} vs {want_pdf}");
                assert_eq!(pdf, s.pdf_solid_angle(p_ref, sp.p, sp.n));
                let to_ref = (p_ref - sp.p).normalize();
                assert!(sp.n.dot(to_ref) > -1e-3, "sin θ_max = {sin_max}: point on the far side");
                let target = offset_ray_origin(sp.p, sp.p_error, sp.n, to_ref);
                let shadow = Ray::bounded(p_ref, target - p_ref, 1.0 - SHADOW_EPSILON);
                assert!(
                    s.intersect(&shadow, shadow.t_max).is_none(),
                    "sin θ_max = {sin_max}: self-occluded shadow ray"
                );
            }
        }
    }

    /// The light-sampling estimate of irradiance from a small sphere, `L cos θ_n / p(ω)`, has
    /// the mean and variance that quadrature over the cone predicts (normal tilted 60° from the
    /// cone axis, so the cosine varies across the cone). Lost or misweighted samples would
    /// inflate the variance by orders of magnitude at these cone sizes.
    #[test]
    fn irradiance_estimate_has_the_predicted_variance() {
        let p_ref = Vec3::ZERO;
        let axis = Vec3::Z;
        let n = Vec3::new(0.75f32.sqrt(), 0.0, 0.5); // 60° from the axis
        for (k, sin_max) in [0.2f64, 0.03, 3e-3, 3e-4].into_iter().enumerate() {
            let s = Sphere::new(axis * 2.0, (2.0 * sin_max) as f32, false);
            let cos_max = (1.0 - sin_max * sin_max).sqrt();
            let omega = 2.0 * std::f64::consts::PI * (1.0 - cos_max);
            // Moments of cos θ_n over the cone by midpoint quadrature in (θ, φ).
            let (nt, np) = (400, 400);
            let theta_max = sin_max.asin();
            let (mut m1, mut m2) = (0.0f64, 0.0f64);
            for i in 0..nt {
                let th = (i as f64 + 0.5) / nt as f64 * theta_max;
                for j in 0..np {
                    let ph = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                    let d = glam::DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                    let c = d.dot(n.as_dvec3());
                    let dw = th.sin() * (theta_max / nt as f64) * (std::f64::consts::TAU / np as f64);
                    m1 += c * dw;
                    m2 += c * c * dw;
                }
            }
            // X = cos θ_n · Ω (radiance 1): E X = ∫ cos, E X² = Ω ∫ cos².
            let (mean, var) = (m1, omega * m2 - m1 * m1);
            let mut rng = crate::sampling::Pcg32::new(5, k as u64);
            let n_samples = 400_000;
            let (mut s1, mut s2) = (0.0f64, 0.0f64);
            for _ in 0..n_samples {
                let x = match s.sample_solid_angle(p_ref, u2(&mut rng)) {
                    Some((sp, pdf)) => ((sp.p - p_ref).normalize().dot(n) / pdf) as f64,
                    None => 0.0,
                };
                s1 += x;
                s2 += x * x;
            }
            let m = s1 / n_samples as f64;
            let v = s2 / n_samples as f64 - m * m;
            assert!((m / mean - 1.0).abs() < 1e-3, "sin θ_max = {sin_max}: mean {m} vs {mean}");
            assert!((v / var - 1.0).abs() < 0.05, "sin θ_max = {sin_max}: variance {v:e} vs {var:e}");
        }
    }
}
