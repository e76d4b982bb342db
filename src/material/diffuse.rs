//! Lambertian (ideal diffuse) reflection, Mitsuba's `diffuse`.
//!
//! `f(wo, wi) = ρ / π` for `wo`, `wi` on the front side; sampled by the cosine-weighted
//! hemisphere (Malley), so `f cos θᵢ / p = ρ`. Parameters (Mitsuba): `reflectance` (RGB in
//! [0, 1] or a texture, default 0.5).

use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{Rgb, Vec2, Vec3, INV_PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere_malley};
use crate::texture::Texture;

/// Lambertian BSDF with albedo `reflectance`.
#[derive(Clone, Debug)]
pub struct Diffuse {
    /// Albedo ρ per channel (constant or textured).
    pub reflectance: Texture,
}

impl Diffuse {
    /// A diffuse BSDF of constant albedo.
    pub fn new(reflectance: Rgb) -> Diffuse {
        Diffuse { reflectance: Texture::Constant(reflectance) }
    }
}

impl Diffuse {
    /// `ρ/π cos θᵢ` when both directions are on the front side, else 0.
    #[inline]
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        ctx.eval(&self.reflectance) * (INV_PI * wi.z)
    }

    /// `cos θᵢ / π` when both directions are on the front side, else 0.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        cosine_hemisphere_pdf(wi)
    }

    /// [`Diffuse::eval`] and [`Diffuse::pdf`] in one (the same bits as the two calls).
    #[inline]
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        (ctx.eval(&self.reflectance) * (INV_PI * wi.z), cosine_hemisphere_pdf(wi))
    }

    /// Cosine-weighted `wi`; weight ρ. `None` from the back side.
    #[inline]
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, _u1: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let s = sample_cosine_hemisphere_malley(u);
        Some(BsdfSample { wi: s.value, pdf: s.pdf, weight: ctx.eval(&self.reflectance), delta: false, null: false, eta: 1.0 })
    }
}

impl Diffuse {
    /// Mitsuba's `diffuse`: `reflectance` (texturable, default 0.5).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        Ok(Bsdf::Diffuse(Diffuse { reflectance: b.texture(o, "reflectance", Rgb::splat(0.5))? }))
    }
}

#[cfg(test)]
mod tests {
    use super::super::Bsdf;
    use super::*;
    use crate::testkit::{chi2_2d, u2, Chi2Config, HEMISPHERE};

    #[test]
    fn sample_matches_pdf_and_eval() {
        let b = Bsdf::Diffuse(Diffuse::new(Rgb::new(0.2, 0.5, 0.9)));
        let ctx = BsdfContext::default();
        for (k, wo) in
            [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.1, 0.99, 0.1).normalize()].into_iter().enumerate()
        {
            let out = chi2_2d(
                &HEMISPHERE,
                [11, 21],
                300_000,
                |r| b.sample(&ctx, wo, r.next_f32(), u2(r)).map(|s| s.wi),
                |wi| b.pdf(&ctx, wo, *wi) as f64,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "wo = {wo}: {out}");
            let mut rng = crate::sampling::Pcg32::new(k as u64, 1);
            for _ in 0..1000 {
                let s = b.sample(&ctx, wo, rng.next_f32(), u2(&mut rng)).unwrap();
                assert!((s.pdf - b.pdf(&ctx, wo, s.wi)).abs() < 1e-5);
                let w = b.eval(&ctx, wo, s.wi) / s.pdf;
                assert!((w - s.weight).abs().max_element() < 1e-4, "{w} vs {}", s.weight);
            }
        }
    }

    #[test]
    fn one_sided_and_reciprocal() {
        let b = Diffuse::new(Rgb::splat(0.7));
        let ctx = BsdfContext::default();
        let below = Vec3::new(0.0, 0.6, -0.8);
        assert!(b.sample(&ctx, below, 0.5, Vec2::splat(0.3)).is_none());
        assert_eq!(b.eval(&ctx, below, Vec3::Z), Rgb::ZERO);
        assert_eq!(b.eval(&ctx, Vec3::Z, below), Rgb::ZERO);
        let (a, c) = (Vec3::new(0.3, 0.1, 0.9).normalize(), Vec3::new(-0.5, 0.2, 0.6).normalize());
        // f is symmetric: eval/cos θᵢ agrees both ways.
        assert!((b.eval(&ctx, a, c) / c.z - b.eval(&ctx, c, a) / a.z).abs().max_element() < 1e-6);
    }

    #[test]
    fn albedo_is_the_reflectance() {
        // ∫ f cos dω estimated by uniform hemisphere sampling equals ρ.
        let b = Diffuse::new(Rgb::splat(0.6));
        let mut rng = crate::sampling::Pcg32::new(4, 4);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let s = crate::sampling::sample_uniform_hemisphere(u2(&mut rng));
            sum += (b.eval(&BsdfContext::default(), Vec3::Z, s.value).x / s.pdf) as f64;
        }
        let mean = sum / n as f64;
        assert!((mean - 0.6).abs() < 4.0 * 0.6 * (1.0f64 / 3.0).sqrt() * 2.0 / (n as f64).sqrt() + 1e-4, "{mean}");
    }
}
