//! Mitsuba's `envmap`: radiance from every direction given by a latitude-longitude image,
//! importance-sampled with a piecewise-constant 2D distribution.
//!
//! Mapping (Mitsuba 3, local frame with +y up): a direction `d` has image coordinates
//! `u = atan2(d.x, -d.z) / 2π` (wrapped to [0, 1)) and `v = acos(d.y) / π`, so row 0 is the
//! zenith. Texels are looked up without interpolation, and the sampling distribution is the
//! texel luminance times `sin θ` at the texel centre, so that the density is proportional to
//! the radiance up to the `sin θ` variation within a texel. A density `p(u, v)` on the image
//! square becomes `p(ω) = p(u, v) / (2π² sin θ)` per solid angle (the Jacobian of
//! `(u, v) ↦ ω`, since `dω = sin θ dθ dφ = 2π² sin θ du dv`).
//!
//! Parameters (Mitsuba): `filename`, `scale` (default 1), `to_world` (rotation).

use crate::load::image::Image;
use crate::math::{luminance, Rgb, Transform, Vec2, Vec3, PI};
use crate::sampling::PiecewiseConstant2D;
use std::sync::Arc;

/// A lat-long environment map with its sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    image: Arc<Image>,
    distribution: Arc<PiecewiseConstant2D>,
    scale: f32,
    to_world: Transform,
    to_local: Transform,
}

impl EnvMap {
    /// An environment from `image`, radiance multiplied by `scale`, rotated by `to_world`.
    pub fn new(image: Image, scale: f32, to_world: Transform) -> Result<EnvMap, String> {
        if image.width == 0 || image.height == 0 {
            return Err("environment map image is empty".into());
        }
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("environment map scale must be a non-negative number, got {scale}"));
        }
        if let Some(i) = image.pixels.iter().position(|p| !p.is_finite() || p.min_element() < 0.0) {
            return Err(format!("environment map pixel {i} is negative or not finite"));
        }
        let (w, h) = (image.width as usize, image.height as usize);
        let mut func = Vec::with_capacity(w * h);
        for y in 0..h {
            let sin_theta = (PI * (y as f32 + 0.5) / h as f32).sin();
            for x in 0..w {
                func.push(luminance(image.pixels[y * w + x]) * sin_theta);
            }
        }
        let distribution = PiecewiseConstant2D::new(&func, w, h)
            .ok_or("environment map is black: nothing to sample (use no emitter instead)")?;
        Ok(EnvMap {
            image: Arc::new(image),
            distribution: Arc::new(distribution),
            scale,
            to_world,
            to_local: to_world.inverse(),
        })
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

    #[inline]
    fn lookup(&self, uv: Vec2) -> Rgb {
        let x = (uv.x * self.image.width as f32) as i64;
        let y = (uv.y * self.image.height as f32) as i64;
        self.image.get(x, y) * self.scale
    }

    /// Radiance arriving from world direction `d` (unit).
    #[inline]
    pub fn eval(&self, d: Vec3) -> Rgb {
        self.lookup(Self::uv(self.to_local.apply_vector(d).normalize()))
    }

    /// A world direction sampled proportionally to luminance, its radiance and its solid-angle
    /// pdf.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, Rgb, f32)> {
        let s = self.distribution.sample(u);
        let (d, sin_theta) = Self::direction(s.value);
        if sin_theta <= 0.0 || s.pdf <= 0.0 {
            return None;
        }
        let pdf = s.pdf / (2.0 * PI * PI * sin_theta);
        Some((self.to_world.apply_vector(d).normalize(), self.lookup(s.value), pdf))
    }

    /// Solid-angle density of [`EnvMap::sample`] for world direction `d`.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        let local = self.to_local.apply_vector(d).normalize();
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.distribution.pdf(Self::uv(local)) / (2.0 * PI * PI * sin_theta)
    }

    /// `∫ luminance(L) dω` over the sphere (W m⁻² sr⁻¹ · sr), for power estimates.
    pub fn integral_luminance(&self) -> f32 {
        self.distribution.integral() * 2.0 * PI * PI * self.scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, u2, Chi2Config, SPHERE};

    /// A high-dynamic-range test sky: dim gradient, a bright sun and a black band.
    pub(crate) fn test_sky(w: u32, h: u32) -> Image {
        let mut pixels = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let sun = x == w / 3 && y == h / 4;
                let black = y == h / 2;
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

    #[test]
    fn sampling_matches_pdf_and_eval() {
        let to_world = Transform::rotate(Vec3::new(0.2, 1.0, 0.1), 40.0).unwrap();
        let env = EnvMap::new(test_sky(16, 8), 2.0, to_world).unwrap();
        let out = chi2_2d(
            &SPHERE,
            [31, 61],
            500_000,
            |r| env.sample(u2(r)).map(|s| s.0),
            |d| env.pdf(*d) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        let mut rng = crate::sampling::Pcg32::new(1, 2);
        for _ in 0..1000 {
            let (d, l, pdf) = env.sample(u2(&mut rng)).unwrap();
            assert!((pdf - env.pdf(d)).abs() <= 1e-3 * pdf, "{pdf} vs {}", env.pdf(d));
            assert!((l - env.eval(d)).abs().max_element() <= 1e-3 * l.max_element().max(1.0));
        }
        // The black band is never sampled and has zero pdf.
        let (band, _) = EnvMap::direction(Vec2::new(0.3, 4.5 / 8.0));
        assert_eq!(env.pdf(to_world.apply_vector(band)), 0.0);
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
