//! Mitsuba's `envmap`: radiance from every direction given by a latitude-longitude image,
//! importance-sampled with a piecewise-constant 2D (marginal/conditional) distribution.
//!
//! Mapping (Mitsuba 3, local frame with +y up): a direction `d` has image coordinates
//! `u = atan2(d.x, -d.z) / 2π` (wrapped to [0, 1)) and `v = acos(d.y) / π`, so row 0 is the
//! zenith. The radiance is Mitsuba's continuous interpolant of the W × H image: texel (i, j)
//! sits at `u = (i + ½)/W` (periodic in u) and `v = j/(H - 1)` (the first and last rows lie on
//! the poles), and radiance between these points is bilinear. The sampling distribution is
//! piecewise constant over the same bilinear cells, each cell weighted by the largest luminance
//! of its four corners times the largest `sin θ` over the cell: an upper envelope of
//! `luminance × sin θ`, so every direction with radiance has a positive density (the estimator
//! stays unbiased whatever the envelope's looseness). A density `p(u, v)` on the image square
//! becomes `p(ω) = p(u, v) / (2π² sin θ)` per solid angle (the Jacobian of `(u, v) ↦ ω`, since
//! `dω = sin θ dθ dφ = 2π² sin θ du dv`).
//!
//! pbrt-v4's layout ([`EnvMap::new_equal_area`]): a square image in Clarberg's equal-area
//! octahedral mapping ([`crate::sampling::equal_area`]) around the local +z axis, radiance the
//! nearest texel (as pbrt-v4's `ImageInfiniteLight`), sampled per texel in proportion to its
//! channel average (pbrt's sampling distribution); the mapping preserves area, so
//! `p(ω) = p(u, v) / 4π`.
//!
//! Parameters (Mitsuba): `filename`, `scale` (default 1), `to_world` (rotation); neumann's
//! `mapping` (`latlong`, the default, or `equal_area`).
//!
//! With a [`Portal`] (pbrt-v4's `portal`) the map shines only through that rectangle: its
//! radiance arrives along rays that cross the portal, and light sampling picks points of the
//! portal (the `_from` methods, which take the point the light is seen from).

use crate::image::Image;
use crate::math::{luminance, Rgb, Transform, Vec2, Vec3, INV_4PI, PI};
use crate::sampling::equal_area::{equal_area_sphere_to_square, equal_area_square_to_sphere};
use crate::sampling::PiecewiseConstant2D;
use std::sync::Arc;

pub use super::portal::Portal;

/// How image coordinates cover the sphere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Mitsuba's latitude-longitude layout, bilinear (+y up).
    LatLong,
    /// pbrt-v4's equal-area octahedral square, nearest texel (+z up).
    EqualArea,
}

/// An environment map with its sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    layout: Layout,
    image: Arc<Image>,
    /// What light sampling under MIS draws from ([`EnvMap::sample`], [`EnvMap::pdf`]):
    /// MIS-compensated where asked.
    distribution: Arc<PiecewiseConstant2D>,
    /// The uncompensated density where `distribution` is compensated: what estimators that
    /// do not combine with BSDF sampling draw from ([`EnvMap::sample_complete`]: light tracing,
    /// light sampling alone), so that every direction with radiance keeps a density there.
    complete: Option<Arc<PiecewiseConstant2D>>,
    /// `∫ luminance dω` of the unscaled map.
    integral: f32,
    scale: f32,
    to_world: Transform,
    to_local: Transform,
    /// The window the map shines through (`None`: everywhere).
    portal: Option<Portal>,
}

/// Why an image and scale do not make an environment map.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EnvMapError {
    /// The image has no pixels.
    #[error("environment map image is empty")]
    Empty,
    /// The scale is negative or not finite.
    #[error("environment map scale must be a non-negative number, got {0}")]
    Scale(f32),
    /// A pixel is negative or not finite.
    #[error("environment map pixel {0} is negative or not finite")]
    Pixel(usize),
    /// An equal-area map must be square.
    #[error("an equal-area (octahedral) environment map must be square, got {0} × {1}")]
    NotSquare(u32, u32),
    /// One row cannot span the sphere's latitudes.
    #[error("environment map must be at least 2 pixels high")]
    TooLow,
    /// Every pixel is black: nothing to sample.
    #[error("environment map is black: nothing to sample (use no emitter instead)")]
    Black,
}

/// The checks both layouts make of an image and scale: not empty, square where `square`, a
/// finite non-negative scale and finite non-negative pixels.
fn checked(image: Arc<Image>, scale: f32, square: bool) -> Result<Arc<Image>, EnvMapError> {
    if image.width == 0 || image.height == 0 {
        return Err(EnvMapError::Empty);
    }
    if square && image.width != image.height {
        return Err(EnvMapError::NotSquare(image.width, image.height));
    }
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(EnvMapError::Scale(scale));
    }
    if let Some(i) = image.pixels.iter().position(|p| !p.is_finite() || p.min_element() < 0.0) {
        return Err(EnvMapError::Pixel(i));
    }
    Ok(image)
}

/// The amount Mitsuba's `mis_compensation` subtracts from every texel's sampling weight: the
/// mean of the texels' `values` (Karlík et al. 2019, "MIS compensation: optimizing sampling
/// techniques in multiple importance sampling"), or 0 for a map whose mean is within 1 % of its
/// minimum (near-constant: nothing would be left to sample), as Mitsuba's `envmap` decides.
/// Where the offset removes a direction's density, only BSDF sampling reaches it: unbiased
/// under MIS, as Mitsuba documents the option for.
fn mis_offset(values: impl Iterator<Item = f32>) -> f32 {
    let (mut sum, mut n, mut min) = (0.0f64, 0usize, f32::INFINITY);
    for v in values {
        sum += f64::from(v);
        n += 1;
        min = min.min(v);
    }
    let mean = (sum / n.max(1) as f64) as f32;
    if mean - min <= 0.01 * mean {
        0.0
    } else {
        mean
    }
}

impl EnvMap {
    /// An environment from `image` (owned or shared), radiance multiplied by `scale`, rotated by
    /// `to_world`.
    pub fn new(image: impl Into<Arc<Image>>, scale: f32, to_world: Transform) -> Result<EnvMap, EnvMapError> {
        EnvMap::new_latlong(image, scale, to_world, false)
    }

    /// [`EnvMap::new`], its sampling density MIS-compensated where `mis_compensation` (Mitsuba's
    /// parameter, after Karlík et al. 2019): each cell weighted by `max(luminance − mean, 0)`
    /// instead of its luminance — no offset for a map whose mean is within 1 % of its minimum —,
    /// so directions no brighter than the map's mean are left to BSDF sampling; the complete
    /// density stays for [`EnvMap::sample_complete`]. The radiance and its integral are the same.
    pub fn new_latlong(
        image: impl Into<Arc<Image>>,
        scale: f32,
        to_world: Transform,
        mis_compensation: bool,
    ) -> Result<EnvMap, EnvMapError> {
        let image = checked(image.into(), scale, false)?;
        if image.height < 2 {
            return Err(EnvMapError::TooLow);
        }
        let (w, h) = (image.width as usize, image.height as usize);
        let lum = |x: usize, y: usize| luminance(image.pixels[y * w + x % w]);
        let offset = if mis_compensation { mis_offset(image.pixels.iter().map(|&p| luminance(p))) } else { 0.0 };
        let mut complete = Vec::with_capacity(if offset > 0.0 { w * (h - 1) } else { 0 });
        let theta = |y: usize| PI * y as f32 / (h - 1) as f32;
        let mut func = Vec::with_capacity(w * (h - 1));
        let mut integral = 0.0f64;
        for y in 0..h - 1 {
            let (t0, t1) = (theta(y), theta(y + 1));
            let sin_max = if t0 <= 0.5 * PI && t1 >= 0.5 * PI { 1.0 } else { t0.sin().max(t1.sin()) };
            let sin_mid = (0.5 * (t0 + t1)).sin();
            for x in 0..w {
                let c = [lum(x, y), lum(x + 1, y), lum(x, y + 1), lum(x + 1, y + 1)];
                let top = c.iter().fold(0.0f32, |a, &b| a.max(b));
                func.push((top - offset).max(0.0) * sin_max);
                if offset > 0.0 {
                    complete.push(top * sin_max);
                }
                integral += (c.iter().sum::<f32>() * 0.25 * sin_mid) as f64;
            }
        }
        let distribution = PiecewiseConstant2D::new(&func, w, h - 1).ok_or(EnvMapError::Black)?;
        // (Where the compensated density has mass, the complete one, never smaller, has too.)
        let complete = if offset > 0.0 { PiecewiseConstant2D::new(&complete, w, h - 1) } else { None };
        // ∫ luminance dω ≈ Σ cells (mean corner luminance) sin θ_mid · 2π² / (W (H - 1)).
        let integral = (integral * 2.0 * (PI * PI) as f64 / (w * (h - 1)) as f64) as f32;
        Ok(EnvMap::assemble(Layout::LatLong, image, distribution, complete, integral, scale, to_world))
    }

    /// The map from its parts: `distribution`, the light-sampling density, and `complete`, the
    /// uncompensated one where that is MIS-compensated.
    fn assemble(
        layout: Layout,
        image: Arc<Image>,
        distribution: PiecewiseConstant2D,
        complete: Option<PiecewiseConstant2D>,
        integral: f32,
        scale: f32,
        to_world: Transform,
    ) -> EnvMap {
        EnvMap {
            layout,
            image,
            distribution: Arc::new(distribution),
            complete: complete.map(Arc::new),
            integral,
            scale,
            to_world,
            to_local: to_world.inverse(),
            portal: None,
        }
    }

    /// The same map shining only through `portal`.
    pub fn with_portal(self, portal: Portal) -> EnvMap {
        EnvMap { portal: Some(portal), ..self }
    }

    /// The portal, if the map has one.
    pub fn portal(&self) -> Option<&Portal> {
        self.portal.as_ref()
    }

    /// Radiance arriving at `o` from unit world direction `d`: [`EnvMap::eval`], or zero if a
    /// portal does not let it through.
    #[inline]
    pub fn eval_from(&self, o: Vec3, d: Vec3) -> Rgb {
        match &self.portal {
            Some(portal) if portal.crossing(o, d).is_none() => Rgb::ZERO,
            _ => self.eval(d),
        }
    }

    /// A direction of light arriving at `p_ref`: [`EnvMap::sample`], or through a uniform
    /// point of the portal. `(direction, radiance, solid-angle pdf)`.
    #[inline]
    pub fn sample_from(&self, p_ref: Vec3, u: Vec2) -> Option<(Vec3, Rgb, f32)> {
        match &self.portal {
            None => self.sample(u),
            Some(portal) => {
                let (wi, pdf) = portal.sample(p_ref, u)?;
                Some((wi, self.eval(wi), pdf))
            }
        }
    }

    /// [`EnvMap::eval_from`] from `o` and [`EnvMap::pdf_from`] at `p_ref` of one direction
    /// (the same bits), sharing the image coordinates where there is no portal.
    #[inline]
    pub fn eval_pdf_from(&self, o: Vec3, p_ref: Vec3, d: Vec3) -> (Rgb, f32) {
        match &self.portal {
            None => self.eval_pdf(d),
            Some(_) => (self.eval_from(o, d), self.pdf_from(p_ref, d)),
        }
    }

    /// Density of [`EnvMap::sample_from`] at `p_ref` for the unit world direction `d`.
    #[inline]
    pub fn pdf_from(&self, p_ref: Vec3, d: Vec3) -> f32 {
        match &self.portal {
            None => self.pdf(d),
            Some(portal) => portal.pdf(p_ref, d),
        }
    }

    /// pbrt-v4's equal-area environment: a square `image` (see the module notes), radiance
    /// multiplied by `scale`, local +z (the square's centre) turned by `to_world`.
    /// `mis_compensation` as in [`EnvMap::new_latlong`], on pbrt's per-texel channel averages
    /// (pbrt-v4's own `compensatedDistribution`, which its path tracer samples, subtracts their
    /// mean likewise).
    pub fn new_equal_area(
        image: impl Into<Arc<Image>>,
        scale: f32,
        to_world: Transform,
        mis_compensation: bool,
    ) -> Result<EnvMap, EnvMapError> {
        let image = checked(image.into(), scale, true)?;
        let (w, h) = (image.width as usize, image.height as usize);
        let func: Vec<f32> = image.pixels.iter().map(|p| (p.x + p.y + p.z) / 3.0).collect();
        let offset = if mis_compensation { mis_offset(func.iter().copied()) } else { 0.0 };
        let complete = PiecewiseConstant2D::new(&func, w, h).ok_or(EnvMapError::Black)?;
        let (distribution, complete) = if offset > 0.0 {
            let compensated: Vec<f32> = func.iter().map(|v| (v - offset).max(0.0)).collect();
            (PiecewiseConstant2D::new(&compensated, w, h).ok_or(EnvMapError::Black)?, Some(complete))
        } else {
            (complete, None)
        };
        let sum: f64 = image.pixels.iter().map(|&p| luminance(p) as f64).sum();
        let integral = (sum * 4.0 * PI as f64 / (w * h) as f64) as f32;
        Ok(EnvMap::assemble(Layout::EqualArea, image, distribution, complete, integral, scale, to_world))
    }

    /// pbrt-v4's illuminance of an equal-area map at a point facing its +z, which its
    /// `illuminance` parameter divides by: `2π/N Σ luminance · cos θ` over the N texels whose
    /// centre lies above the horizon. (pbrt's normalisation; the integral it estimates,
    /// `∫ L cos θ dω`, has `4π/N` there, so pbrt's maps come out twice as bright as asked.)
    pub fn pbrt_illuminance(image: &Image) -> f32 {
        let (w, h) = (image.width as usize, image.height as usize);
        let mut sum = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let d =
                    equal_area_square_to_sphere(Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32));
                if d.z > 0.0 {
                    sum += (luminance(image.pixels[y * w + x]) * d.z) as f64;
                }
            }
        }
        (sum * 2.0 * PI as f64 / (w * h).max(1) as f64) as f32
    }

    /// The nearest texel of equal-area coordinates (pbrt's `LookupNearest`).
    #[inline]
    fn nearest(&self, uv: Vec2) -> Rgb {
        let (w, h) = (self.image.width as usize, self.image.height as usize);
        let x = ((uv.x * w as f32) as usize).min(w - 1);
        let y = ((uv.y * h as f32) as usize).min(h - 1);
        self.image.pixels[y * w + x] * self.scale
    }

    /// Which layout the map has.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// Image coordinates of a local unit direction.
    #[inline]
    fn uv(d: Vec3) -> Vec2 {
        let mut u = d.x.atan2(-d.z) * (0.5 / PI);
        if u < 0.0 {
            u += 1.0;
        }
        Vec2::new(u.min(crate::math::ONE_MINUS_EPSILON), crate::math::safe_acos(d.y) / PI)
    }

    /// Local unit direction of image coordinates, and sin θ.
    #[inline]
    fn direction(uv: Vec2) -> (Vec3, f32) {
        let (sin_phi, cos_phi) = (2.0 * PI * uv.x).sin_cos();
        let (sin_theta, cos_theta) = (PI * uv.y).sin_cos();
        (Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi), sin_theta)
    }

    /// Half a texel in u: the offset between image coordinates and the bilinear cell grid.
    #[inline]
    fn half_texel(&self) -> f32 {
        0.5 / self.image.width as f32
    }

    /// Bilinear interpolation of the texels around image coordinates `uv`.
    #[inline]
    fn lookup(&self, uv: Vec2) -> Rgb {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        let mut u = uv.x - self.half_texel();
        u -= crate::math::floor(u);
        let x = u * w as f32;
        let y = (uv.y * (h - 1) as f32).clamp(0.0, (h - 1) as f32);
        let (i, j) = ((x as i64).min(w - 1), (y as i64).min(h - 2));
        let (fx, fy) = (x - i as f32, y - j as f32);
        // The next column, wrapping around (a select: `% w` was an integer division).
        let (i1, j1) = (if i + 1 < w { i + 1 } else { 0 }, j + 1);
        let px = |a: i64, b: i64| self.image.pixels[(b * w + a) as usize];
        let top = px(i, j) * (1.0 - fx) + px(i1, j) * fx;
        let bottom = px(i, j1) * (1.0 - fx) + px(i1, j1) * fx;
        (top * (1.0 - fy) + bottom * fy) * self.scale
    }

    /// Cell-grid coordinates (the distribution's domain) of image coordinates.
    #[inline]
    fn to_grid(&self, uv: Vec2) -> Vec2 {
        let mut u = uv.x - self.half_texel();
        u -= crate::math::floor(u);
        Vec2::new(u.min(crate::math::ONE_MINUS_EPSILON), uv.y)
    }

    /// Radiance arriving from world direction `d` (unit).
    #[inline]
    pub fn eval(&self, d: Vec3) -> Rgb {
        let local = self.to_local.apply_vector(d).normalize();
        self.radiance_at(self.coords(local))
    }

    /// [`EnvMap::eval`] and [`EnvMap::pdf`] of one direction (the same bits), mapping it to
    /// image coordinates once.
    #[inline]
    pub fn eval_pdf(&self, d: Vec3) -> (Rgb, f32) {
        let local = self.to_local.apply_vector(d).normalize();
        let c = self.coords(local);
        (self.radiance_at(c), self.pdf_at(local, c))
    }

    /// Image coordinates of a local unit direction in this map's layout.
    #[inline]
    fn coords(&self, local: Vec3) -> Vec2 {
        match self.layout {
            Layout::LatLong => Self::uv(local),
            Layout::EqualArea => equal_area_sphere_to_square(local),
        }
    }

    /// Radiance at image coordinates (bilinear for latitude-longitude maps, nearest texel for
    /// equal-area squares).
    #[inline]
    fn radiance_at(&self, c: Vec2) -> Rgb {
        match self.layout {
            Layout::LatLong => self.lookup(c),
            Layout::EqualArea => self.nearest(c),
        }
    }

    /// Solid-angle density of [`EnvMap::sample`] for the local unit direction `local` at its
    /// image coordinates `c`.
    #[inline]
    fn pdf_at(&self, local: Vec3, c: Vec2) -> f32 {
        self.pdf_in(&self.distribution, local, c)
    }

    /// [`EnvMap::pdf_at`] of the density `dist` (one of the map's two).
    #[inline]
    fn pdf_in(&self, dist: &PiecewiseConstant2D, local: Vec3, c: Vec2) -> f32 {
        if self.layout == Layout::EqualArea {
            return dist.pdf(c) * INV_4PI;
        }
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        dist.pdf(self.to_grid(c)) / (2.0 * PI * PI * sin_theta)
    }

    /// A world direction sampled proportionally to luminance (less the map's mean where
    /// MIS-compensated), its radiance and its solid-angle pdf: what light sampling under MIS
    /// draws.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, Rgb, f32)> {
        self.sample_in(&self.distribution, u)
    }

    /// [`EnvMap::sample`] from the complete density: the same unless the map is
    /// MIS-compensated, where every direction with radiance has a density here (for light
    /// tracing and light sampling that no BSDF sampling complements).
    #[inline]
    pub fn sample_complete(&self, u: Vec2) -> Option<(Vec3, Rgb, f32)> {
        self.sample_in(self.complete.as_deref().unwrap_or(&self.distribution), u)
    }

    /// Solid-angle density of [`EnvMap::sample_complete`] for world direction `d`.
    pub fn pdf_complete(&self, d: Vec3) -> f32 {
        let local = self.to_local.apply_vector(d).normalize();
        self.pdf_in(self.complete.as_deref().unwrap_or(&self.distribution), local, self.coords(local))
    }

    /// Whether light sampling leaves the directions no brighter than the map's mean to BSDF
    /// sampling (Mitsuba's `mis_compensation`, in effect).
    pub fn is_compensated(&self) -> bool {
        self.complete.is_some()
    }

    /// [`EnvMap::sample_from`] from the complete density ([`EnvMap::sample_complete`]; through
    /// a portal, the portal's own sampling, which has no compensation).
    #[inline]
    pub fn sample_from_complete(&self, p_ref: Vec3, u: Vec2) -> Option<(Vec3, Rgb, f32)> {
        match &self.portal {
            None => self.sample_complete(u),
            Some(_) => self.sample_from(p_ref, u),
        }
    }

    /// A direction drawn from the density `dist`, its radiance and solid-angle pdf.
    #[inline]
    fn sample_in(&self, dist: &PiecewiseConstant2D, u: Vec2) -> Option<(Vec3, Rgb, f32)> {
        let s = dist.sample(u);
        if self.layout == Layout::EqualArea {
            if s.pdf <= 0.0 {
                return None;
            }
            let d = equal_area_square_to_sphere(s.value);
            return Some((self.to_world.apply_vector(d).normalize(), self.nearest(s.value), s.pdf * INV_4PI));
        }
        let mut uv = Vec2::new(s.value.x + self.half_texel(), s.value.y);
        if uv.x >= 1.0 {
            uv.x -= 1.0;
        }
        let (d, sin_theta) = Self::direction(uv);
        if sin_theta <= 0.0 || s.pdf <= 0.0 {
            return None;
        }
        let pdf = s.pdf / (2.0 * PI * PI * sin_theta);
        Some((self.to_world.apply_vector(d).normalize(), self.lookup(uv), pdf))
    }

    /// Solid-angle density of [`EnvMap::sample`] for world direction `d`.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        let local = self.to_local.apply_vector(d).normalize();
        self.pdf_at(local, self.coords(local))
    }

    /// `∫ luminance(L) dω` over the sphere (W m⁻² sr⁻¹ · sr), for power estimates.
    pub fn integral_luminance(&self) -> f32 {
        self.integral * self.scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::u2;

    /// A high-dynamic-range test sky: dim gradient, a bright sun and a black band.
    pub(crate) fn test_sky(w: u32, h: u32) -> Image {
        let mut pixels = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let sun = x == w / 3 && y == h / 4;
                let black = y == h / 2 || y == h / 2 + 1;
                let base = Rgb::new(0.2 + x as f32 / w as f32, 0.3, 0.5 + y as f32 / h as f32);
                pixels.push(if black {
                    Rgb::ZERO
                } else if sun {
                    Rgb::splat(5000.0)
                } else {
                    base
                });
            }
        }
        Image { width: w, height: h, pixels }
    }

    #[test]
    fn mapping_round_trips() {
        for (u, v) in [(0.1f32, 0.2f32), (0.6, 0.9), (0.99, 0.5), (0.3, 0.01)] {
            let (d, _) = EnvMap::direction(Vec2::new(u, v));
            let back = EnvMap::uv(d);
            assert!((back - Vec2::new(u, v)).abs().max_element() < 1e-4, "{u},{v} -> {back}");
        }
        // +y is the zenith (row 0); -z is u = 0.
        assert!(EnvMap::uv(Vec3::Y).y < 1e-6);
        assert!(EnvMap::uv(-Vec3::Z).x < 1e-6);
    }

    /// Mitsuba's texel placement: texel (i, j) at u = (i + ½)/W, v = j/(H - 1), bilinear between,
    /// periodic in u; and the power estimate agrees with a Monte Carlo integral.
    #[test]
    fn texels_sit_where_mitsuba_puts_them() {
        let img = test_sky(16, 8);
        let env = EnvMap::new(img.clone(), 1.0, Transform::IDENTITY).unwrap();
        for (i, j) in [(0usize, 0usize), (5, 3), (15, 7), (15, 2)] {
            let l = env.lookup(Vec2::new((i as f32 + 0.5) / 16.0, j as f32 / 7.0));
            assert!((l - img.pixels[j * 16 + i]).abs().max_element() < 1e-3 * l.max_element().max(1.0), "{i},{j}");
        }
        // Halfway between the last and the first column: their average (periodic).
        let mid = env.lookup(Vec2::new(0.999_99, 2.0 / 7.0));
        let expected = 0.5 * (img.pixels[2 * 16 + 15] + img.pixels[2 * 16]);
        assert!((mid - expected).abs().max_element() < 1e-3, "{mid} vs {expected}");
        assert_power_estimate(&env, 4);
    }

    /// `integral_luminance` against a Monte Carlo estimate of `∫ luminance dω` (3 %).
    fn assert_power_estimate(env: &EnvMap, seed: u64) {
        let mut rng = crate::sampling::Pcg32::new(3, seed);
        let mc = crate::testkit::sphere_integral_mc(400_000, &mut rng, |d| luminance(env.eval(d)) as f64);
        let rel = (env.integral_luminance() as f64 - mc).abs() / mc;
        assert!(rel < 0.03, "power estimate {} vs Monte Carlo {mc}", env.integral_luminance());
    }

    /// χ² of `sample` against `pdf` over the sphere, and each sample's pdf and radiance
    /// against `pdf` and `eval`.
    fn assert_samples_match_pdf_and_eval(env: &EnvMap, seed: u64) {
        super::super::check_environment_sampling(|u| env.sample(u), |d| env.pdf(d), |d| env.eval(d), 500_000, seed);
    }

    #[test]
    fn sampling_matches_pdf_and_eval() {
        let to_world = Transform::rotate(Vec3::new(0.2, 1.0, 0.1), 40.0).unwrap();
        let env = EnvMap::new(test_sky(16, 8), 2.0, to_world).unwrap();
        assert_samples_match_pdf_and_eval(&env, 2);
        // Between two black rows the radiance is zero: never sampled, zero pdf.
        let (band, _) = EnvMap::direction(Vec2::new(0.3, 4.5 / 7.0));
        assert_eq!(env.pdf(to_world.apply_vector(band)), 0.0);
    }

    /// `eval_pdf` is `eval` and `pdf` bit for bit, in both layouts (directions at random and
    /// the poles, where the density is 0).
    #[test]
    fn eval_pdf_is_eval_and_pdf() {
        let to_world = Transform::rotate(Vec3::new(0.2, 1.0, 0.1), 40.0).unwrap();
        let maps = [
            EnvMap::new(test_sky(16, 8), 2.0, to_world).unwrap(),
            EnvMap::new_equal_area(test_sky(16, 16), 1.5, to_world, false).unwrap(),
        ];
        let mut rng = crate::sampling::Pcg32::new(4, 4);
        for env in &maps {
            let poles = [Vec3::Y, -Vec3::Y].map(|d| to_world.apply_vector(d));
            let random = (0..2000).map(|_| crate::sampling::sample_uniform_sphere(u2(&mut rng)).value);
            for d in poles.into_iter().chain(random) {
                let ((l, p), l2, p2) = (env.eval_pdf(d), env.eval(d), env.pdf(d));
                assert!(l.to_array().map(f32::to_bits) == l2.to_array().map(f32::to_bits), "{d}: {l} vs {l2}");
                assert_eq!(p.to_bits(), p2.to_bits(), "{d}: {p} vs {p2}");
            }
        }
    }

    #[test]
    fn equal_area_maps_sample_as_their_pdf_and_radiance_say() {
        let to_world = Transform::rotate(Vec3::new(0.3, 0.2, 1.0), 70.0).unwrap();
        let env = EnvMap::new_equal_area(test_sky(16, 16), 1.5, to_world, false).unwrap();
        assert_eq!(env.layout(), Layout::EqualArea);
        assert_samples_match_pdf_and_eval(&env, 3);
        // Texel (x, y) holds the direction of the square's point ((x + ½)/W, (y + ½)/H) in
        // the light's frame (+z at the centre): pbrt-v4's layout.
        let img = test_sky(16, 16);
        for (x, y) in [(0usize, 0usize), (8, 8), (15, 3), (5, 12)] {
            let local = equal_area_square_to_sphere(Vec2::new((x as f32 + 0.5) / 16.0, (y as f32 + 0.5) / 16.0));
            let l = env.eval(to_world.apply_vector(local));
            assert!((l - img.pixels[y * 16 + x] * 1.5).abs().max_element() < 1e-4, "{x},{y}");
        }
        assert_power_estimate(&env, 5);
        assert!(matches!(
            EnvMap::new_equal_area(test_sky(16, 8), 1.0, Transform::IDENTITY, false),
            Err(EnvMapError::NotSquare(16, 8))
        ));
        // pbrt's illuminance of a white map: half of π (see pbrt_illuminance).
        let white = Image { width: 64, height: 64, pixels: vec![Rgb::ONE; 64 * 64] };
        assert!((EnvMap::pbrt_illuminance(&white) - 0.5 * PI).abs() < 0.01, "{}", EnvMap::pbrt_illuminance(&white));
    }

    /// Mitsuba's `mis_compensation`: in both layouts the sampling still follows its pdf and the
    /// radiance (χ²), only texels brighter than the map's mean keep density, the radiance and
    /// its integral are unchanged, and a near-constant map is left as it was.
    #[test]
    fn mis_compensation_samples_only_what_is_brighter_than_the_mean() {
        let to_world = Transform::rotate(Vec3::new(0.2, 1.0, 0.1), 40.0).unwrap();
        let plain = EnvMap::new(test_sky(16, 8), 2.0, to_world).unwrap();
        let compensated = EnvMap::new_latlong(test_sky(16, 8), 2.0, to_world, true).unwrap();
        assert_samples_match_pdf_and_eval(&compensated, 6);
        assert_eq!(compensated.integral_luminance(), plain.integral_luminance());
        // The sun (texel 5, 2, about 40× the mean) keeps its density, the sky around it (about
        // 1, below the mean of about 40) loses it: only the sun's four cells are sampled.
        let (sun, _) = EnvMap::direction(Vec2::new(5.5 / 16.0 + 0.01, 2.0 / 7.0 + 0.01));
        let (sky, _) = EnvMap::direction(Vec2::new(0.8, 0.1));
        let (sun, sky) = (to_world.apply_vector(sun), to_world.apply_vector(sky));
        assert!(compensated.pdf(sun) > plain.pdf(sun), "{} vs {}", compensated.pdf(sun), plain.pdf(sky));
        assert_eq!(compensated.pdf(sky), 0.0);
        assert!(plain.pdf(sky) > 0.0);
        assert_eq!(compensated.eval(sky), plain.eval(sky));
        let mut rng = crate::sampling::Pcg32::new(5, 5);
        for _ in 0..1000 {
            let (d, ..) = compensated.sample(u2(&mut rng)).unwrap();
            let uv = EnvMap::uv(to_world.inverse().apply_vector(d));
            assert!(
                (uv.x - 5.5 / 16.0).abs() < 1.0 / 16.0 + 1e-4 && (uv.y - 2.0 / 7.0).abs() < 1.0 / 7.0 + 1e-4,
                "{uv}"
            );
        }
        let square = EnvMap::new_equal_area(test_sky(16, 16), 1.5, to_world, true).unwrap();
        assert_samples_match_pdf_and_eval(&square, 7);
        let bright = square.sample(Vec2::new(0.5, 0.5)).unwrap().0;
        assert!(square.pdf(bright) > 0.0 && square.pdf(sky) == 0.0);
        // A map whose mean is within 1 % of its minimum keeps its whole density.
        let mut flat = Image { width: 8, height: 4, pixels: vec![Rgb::ONE; 32] };
        flat.pixels[5] = Rgb::splat(1.2);
        let (a, b) = (
            EnvMap::new(flat.clone(), 1.0, Transform::IDENTITY).unwrap(),
            EnvMap::new_latlong(flat, 1.0, Transform::IDENTITY, true).unwrap(),
        );
        for d in [Vec3::X, Vec3::Y, Vec3::new(0.3, -0.4, 0.5).normalize()] {
            assert_eq!(a.pdf(d).to_bits(), b.pdf(d).to_bits());
        }
    }

    /// A compensated map keeps its complete density for the estimators that light sampling
    /// carries alone: `sample_complete` and `pdf_complete` are the uncompensated map's `sample`
    /// and `pdf` bit for bit, in both layouts, and only its MIS density differs.
    #[test]
    fn mis_compensated_maps_keep_the_complete_density() {
        let to_world = Transform::rotate(Vec3::new(0.2, 1.0, 0.1), 40.0).unwrap();
        let pairs = [
            (
                EnvMap::new(test_sky(16, 8), 2.0, to_world).unwrap(),
                EnvMap::new_latlong(test_sky(16, 8), 2.0, to_world, true).unwrap(),
            ),
            (
                EnvMap::new_equal_area(test_sky(16, 16), 1.5, to_world, false).unwrap(),
                EnvMap::new_equal_area(test_sky(16, 16), 1.5, to_world, true).unwrap(),
            ),
        ];
        let mut rng = crate::sampling::Pcg32::new(8, 8);
        for (plain, compensated) in &pairs {
            assert!(compensated.is_compensated() && !plain.is_compensated());
            let mut differ = 0;
            for _ in 0..500 {
                let u = u2(&mut rng);
                let (a, b) = (plain.sample(u), compensated.sample_complete(u));
                assert_eq!(format!("{a:?}"), format!("{b:?}"));
                let d = crate::sampling::sample_uniform_sphere(u2(&mut rng)).value;
                assert_eq!(plain.pdf(d).to_bits(), compensated.pdf_complete(d).to_bits());
                differ += usize::from(plain.pdf(d) != compensated.pdf(d));
            }
            assert!(differ > 300, "{differ}");
        }
    }

    /// What the option is for: irradiance at an upward-facing point from one cosine-weighted
    /// sample and one light sample per estimate, combined by the balance heuristic. With the
    /// compensated density the estimate is the same within noise (unbiased: BSDF sampling covers
    /// what light sampling left out) and its variance lower (measured: 0.15 of it).
    #[test]
    fn mis_compensation_lowers_the_variance_of_mis() {
        let frame = crate::math::Frame::from_z(Vec3::Y);
        let estimate = |env: &EnvMap, seed: u64| {
            let mut rng = crate::sampling::Pcg32::new(9, seed);
            crate::estimators::Estimate::from_values((0..40_000).map(|_| {
                let mut f = 0.0f64;
                let s = crate::sampling::sample_cosine_hemisphere_malley(u2(&mut rng));
                let d = frame.to_world(s.value);
                f += (luminance(env.eval(d)) * s.value.z / (s.pdf + env.pdf(d))) as f64;
                if let Some((d, l, pdf)) = env.sample(u2(&mut rng)) {
                    if d.y > 0.0 {
                        f += (luminance(l) * d.y / (pdf + d.y / PI)) as f64;
                    }
                }
                f
            }))
        };
        // A sky without a sun: a gradient with a brighter patch, where light sampling alone
        // spends most samples on the dim majority.
        let mut sky = test_sky(64, 32);
        for (i, p) in sky.pixels.iter_mut().enumerate() {
            if *p == Rgb::splat(5000.0) || (i % 64 > 10 && i % 64 < 22 && i / 64 > 4 && i / 64 < 10) {
                *p = Rgb::splat(8.0);
            }
        }
        let plain = estimate(&EnvMap::new(sky.clone(), 1.0, Transform::IDENTITY).unwrap(), 1);
        let compensated = estimate(&EnvMap::new_latlong(sky, 1.0, Transform::IDENTITY, true).unwrap(), 2);
        let sigma = (plain.std_error().powi(2) + compensated.std_error().powi(2)).sqrt();
        assert!((plain.value - compensated.value).abs() < 4.0 * sigma, "{} vs {}", plain.value, compensated.value);
        assert!(
            compensated.sample_variance < 0.5 * plain.sample_variance,
            "compensated {} vs plain {}",
            compensated.sample_variance,
            plain.sample_variance
        );
    }

    #[test]
    fn importance_sampling_beats_cosine_sampling_on_a_hdr_sky() {
        // Irradiance at an upward-facing point: E = ∫ L cos θ dω over the upper hemisphere.
        let env = EnvMap::new(test_sky(64, 32), 1.0, Transform::IDENTITY).unwrap();
        let frame = crate::math::Frame::from_z(Vec3::Y);
        let n = 20_000;
        let mut rng = crate::sampling::Pcg32::new(7, 7);
        let cosine = crate::estimators::Estimate::from_values((0..n).map(|_| {
            let s = crate::sampling::sample_cosine_hemisphere_malley(u2(&mut rng));
            let d = frame.to_world(s.value);
            (crate::math::luminance(env.eval(d)) * s.value.z / s.pdf) as f64
        }));
        let importance = crate::estimators::Estimate::from_values((0..n).map(|_| match env.sample(u2(&mut rng)) {
            Some((d, l, pdf)) if d.y > 0.0 => (crate::math::luminance(l) * d.y / pdf) as f64,
            _ => 0.0,
        }));
        assert!(
            (cosine.value - importance.value).abs()
                < 4.0 * (cosine.std_error().powi(2) + importance.std_error().powi(2)).sqrt()
        );
        assert!(
            importance.sample_variance * 20.0 < cosine.sample_variance,
            "importance {} vs cosine {}",
            importance.sample_variance,
            cosine.sample_variance
        );
    }
}
