//! Mitsuba's `pplastic` (polarized plastic) as its RGB variants evaluate it, without
//! polarization: a rough specular reflection added to a diffuse base attenuated by a smooth
//! refraction into and out of the material (not energy conserving, by design):
//!
//! `f cos θᵢ = s F(wo·h) D(h) G / (4 cos θₒ) + ρ/π (1 − F(cos θᵢ))(1 − F(cos θₒ)) cos θᵢ`
//!
//! with `h` the half vector, `F` the dielectric Fresnel term of `eta = int_ior / ext_ior`
//! (polypropylene over air), `s` the `specular_reflectance` (1) and `ρ` the
//! `diffuse_reflectance` (0.5). Sampled as Mitsuba samples it: the specular lobe (visible
//! normals) with probability `s̄ / (ρ̄ + s̄)` of the textures' means (averaged over the
//! channels, as Mitsuba's RGB textures average), else the cosine hemisphere. One-sided.

use super::fresnel::{eta_from_props, fresnel_dielectric, reflect_about};
use super::microfacet::Microfacet;
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{Rgb, Vec2, Vec3, INV_PI};
use crate::props::{Obj, Result as PropResult};
use crate::texture::Texture;

/// Mitsuba's polarized plastic, unpolarized.
#[derive(Clone, Debug)]
pub struct PPlastic {
    /// Diffuse reflectance ρ (texturable).
    pub diffuse_reflectance: Texture,
    /// Specular reflectance scale (texturable).
    pub specular_reflectance: Texture,
    /// Microfacet distribution of the specular lobe.
    pub distribution: Microfacet,
    /// `int_ior / ext_ior`.
    pub eta: f32,
    /// Probability of sampling the specular lobe.
    pub specular_probability: f32,
}

impl PPlastic {
    /// A polarized plastic; the lobe probability from the textures' means.
    pub fn new(diffuse_reflectance: Texture, specular_reflectance: Texture, distribution: Microfacet, eta: f32) -> PPlastic {
        let mean = |t: &Texture| t.mean().element_sum() / 3.0;
        let (d, s) = (mean(&diffuse_reflectance), mean(&specular_reflectance));
        let specular_probability = if d + s > 0.0 { s / (d + s) } else { 0.5 };
        PPlastic { diffuse_reflectance, specular_reflectance, distribution, eta, specular_probability }
    }

    /// `f(wo, wi) cos θᵢ`; 0 unless both directions are above the surface.
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        self.value(ctx, wo, wi, h, self.distribution.d(h), self.distribution.g1(wo, h))
    }

    /// Density of [`PPlastic::sample`] choosing `wi`.
    pub fn pdf(&self, _: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        self.density(wo, wi, h, || self.distribution.pdf(wo, h))
    }

    /// [`PPlastic::eval`] and [`PPlastic::pdf`] at once (the same bits), sharing the half
    /// vector, `D` and `G1(wo)`.
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let h = (wo + wi).normalize();
        let (d, g1_o) = (self.distribution.d(h), self.distribution.g1(wo, h));
        let pdf = self.density(wo, wi, h, || self.distribution.pdf_given(wo, h, d, g1_o));
        (self.value(ctx, wo, wi, h, d, g1_o), pdf)
    }

    /// `f cos θᵢ` at the half vector `h` with `d = D(h)`, `g1_o = G1(wo, h)`.
    fn value(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3, h: Vec3, d: f32, g1_o: f32) -> Rgb {
        let (f, ..) = fresnel_dielectric(wo.dot(h), self.eta);
        let g = g1_o * self.distribution.g1(wi, h);
        let specular = ctx.eval(&self.specular_reflectance) * (f * d * g / (4.0 * wo.z));
        let (r_o, ..) = fresnel_dielectric(wo.z, self.eta);
        let (r_i, ..) = fresnel_dielectric(wi.z, self.eta);
        let diffuse = ctx.eval(&self.diffuse_reflectance) * ((1.0 - r_o) * (1.0 - r_i) * INV_PI * wi.z);
        let value = specular + diffuse;
        if value.is_finite() {
            value
        } else {
            Rgb::ZERO
        }
    }

    /// The mixture density at `wi` from the half vector `h`, whose density is `pdf_h()`.
    fn density(&self, wo: Vec3, wi: Vec3, h: Vec3, pdf_h: impl FnOnce() -> f32) -> f32 {
        let specular = if wo.dot(h) <= 0.0 || wi.dot(h) <= 0.0 { 0.0 } else { pdf_h() / (4.0 * wi.dot(h)) };
        let p = self.specular_probability * specular + (1.0 - self.specular_probability) * wi.z * INV_PI;
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    /// The specular lobe with its probability, else the cosine hemisphere.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u1 < self.specular_probability {
            reflect_about(wo, self.distribution.sample(wo, u).value)
        } else {
            crate::sampling::sample_cosine_hemisphere_malley(u).value
        };
        let (f, pdf) = self.eval_pdf(ctx, wo, wi);
        if pdf <= 0.0 {
            return None;
        }
        let weight = f / pdf;
        weight.is_finite().then_some(BsdfSample { wi, pdf, weight, delta: false, null: false, eta: 1.0 })
    }

    /// Mitsuba's `pplastic`: `diffuse_reflectance` (0.5), `specular_reflectance` (1), both
    /// texturable; `int_ior` (polypropylene, 1.49), `ext_ior` (air), which must differ;
    /// `distribution` (`beckmann`), `alpha` or `alpha_u`/`alpha_v` (0.1), `sample_visible`.
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let eta = eta_from_props(o, 1.49)?;
        if eta == 1.0 {
            return Err(o.error_at("int_ior", "the interior and exterior indices of refraction must differ"));
        }
        let diffuse = b.texture(o, "diffuse_reflectance", Rgb::splat(0.5))?;
        let specular = b.texture(o, "specular_reflectance", Rgb::ONE)?;
        Ok(Bsdf::PPlastic(Box::new(PPlastic::new(diffuse, specular, Microfacet::from_props(o, true)?, eta))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::tests::{assert_matches_mitsuba, MitsubaRow};
    use crate::material::microfacet::MicrofacetType;

    fn config(k: char) -> PPlastic {
        match k {
            'A' => PPlastic::new(
                Rgb::new(0.05, 0.03, 0.1).into(),
                Rgb::ONE.into(),
                Microfacet::new(MicrofacetType::Beckmann, 0.06, 0.06),
                1.49 / 1.000277,
            ),
            _ => PPlastic::new(
                Rgb::new(0.6, 0.4, 0.2).into(),
                Rgb::new(0.9, 0.8, 0.7).into(),
                Microfacet::new(MicrofacetType::Ggx, 0.1, 0.3),
                1.6 / 1.000277,
            ),
        }
    }

    /// `eval` and `pdf` equal Mitsuba 3.9.1's (scalar_rgb) for the same parameters and
    /// directions (its `si.wi` is our `wo`).
    #[test]
    fn matches_mitsuba() {
        let rows: &[MitsubaRow] = &[
            ('A', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.01271337, 0.007628023, 0.02542674], 0.01560353),
            ('A', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.002214344, 0.001328607, 0.004428689], 0.003819708),
            ('A', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, 0.9323806], [0.9384812, 0.9329996, 0.9521855], 22.38281),
            ('A', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.01461033, 0.008766222, 0.02922061], 0.01790505),
            ('A', [-0.8846517, 0.147442, 0.4423259], [-0.4000088, 0.3000066, 0.8660191], [0.01178231, 0.007069383, 0.02356461], 0.01560352),
            ('A', [-0.8846517, 0.147442, 0.4423259], [0.7419985, 0.6359987, 0.2119996], [0.002052177, 0.001231306, 0.004104353], 0.003819708),
            ('A', [-0.8846517, 0.147442, 0.4423259], [-0.3007679, -0.200512, 0.9323806], [0.01270058, 0.007620345, 0.02540115], 0.01679919),
            ('A', [-0.8846517, 0.147442, 0.4423259], [0.1003721, 0.05018603, 0.9936835], [0.01354029, 0.008124176, 0.02708058], 0.01790372),
            ('B', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.1819354, 0.128844, 0.07575262], 0.5636157),
            ('B', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.02558603, 0.01707526, 0.008564495], 0.02380237),
            ('B', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, 0.9323806], [0.2963246, 0.2279547, 0.1595848], 1.993106),
            ('B', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.1750656, 0.1178234, 0.06058114], 0.175175),
            ('B', [-0.8846517, 0.147442, 0.4423259], [-0.4000088, 0.3000066, 0.8660191], [0.1364789, 0.09101401, 0.04554909], 0.09364276),
            ('B', [-0.8846517, 0.147442, 0.4423259], [0.7419985, 0.6359987, 0.2119996], [0.02936445, 0.02087792, 0.01239139], 0.07420791),
            ('B', [-0.8846517, 0.147442, 0.4423259], [-0.3007679, -0.200512, 0.9323806], [0.1471595, 0.09814055, 0.04912158], 0.1010455),
            ('B', [-0.8846517, 0.147442, 0.4423259], [0.1003721, 0.05018603, 0.9936835], [0.1572749, 0.1049702, 0.05266551], 0.1125455),
        ];
        assert_matches_mitsuba(rows, |k| Bsdf::PPlastic(Box::new(config(k))), |_, _, pdf| pdf);
    }
}
