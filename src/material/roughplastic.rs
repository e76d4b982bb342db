//! Mitsuba's `roughplastic`: a rough dielectric coating (microfacet reflection) over a diffuse
//! base.
//!
//! `f cos θᵢ = F(wo·m) D(m) G / (4 cos θₒ) · s  +  ρ' / (π η²) · T(cos θₒ) T(cos θᵢ) cos θᵢ`, where
//! `T(μ) = 1 - ∫ f_spec cos` is the fraction of light the rough coating lets through at
//! incidence μ, and `ρ' = ρ / (1 - R_int)` (or `ρ / (1 - ρ R_int)` with `nonlinear`) accounts
//! for internal reflections with `R_int = 1 - 2 ∫₀¹ T_int(μ) μ dμ` the coating's diffuse
//! reflectance seen from inside. Both `T` tables are computed when the BSDF is built, by
//! stratified integration over visible normals (Mitsuba precomputes the same quantities).
//!
//! Sampling picks the specular lobe with probability ∝ `(1 - T(cos θₒ)) s / (s + d)` against
//! `T(cos θₒ) d / (s + d)`.
//!
//! Parameters (Mitsuba): `diffuse_reflectance` (0.5), `specular_reflectance` (1), `int_ior`
//! (1.49), `ext_ior`, `distribution` (beckmann, ggx), `alpha` (0.1), `nonlinear` (false).

use super::fresnel::{fresnel_dielectric, reflect_about};
use super::microfacet::Microfacet;
use super::plastic::{coated_diffuse_albedo, specular_sampling_weight};
use super::{Bsdf, BsdfBuilder, BsdfSample};
use crate::math::{Rgb, Vec2, Vec3, INV_PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::sample_cosine_hemisphere_malley;

const TABLE: usize = 64;

/// Rough plastic.
#[derive(Clone, Debug)]
pub struct RoughPlastic {
    /// Microfacet distribution of the coating.
    pub distribution: Microfacet,
    /// Base albedo ρ.
    pub diffuse_reflectance: Rgb,
    /// Specular scale.
    pub specular_reflectance: Rgb,
    /// `int_ior / ext_ior`.
    pub eta: f32,
    /// Mitsuba's `nonlinear` model.
    pub nonlinear: bool,
    /// `T(μ)` from outside at μ = k / (TABLE - 1).
    external_transmittance: Vec<f32>,
    /// Diffuse reflectance of the coating seen from inside.
    internal_reflectance: f32,
    specular_weight: f32,
}

/// Directional albedo `∫ F D G / (4 cos θₒ) dωᵢ` of a rough dielectric *reflection* at
/// incidence `mu` (relative index `eta`), by stratified sampling of visible normals.
fn specular_albedo(distribution: &Microfacet, eta: f32, mu: f32) -> f32 {
    let mu = mu.clamp(1e-4, 1.0);
    let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let n = 48;
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let m = distribution.sample(wo, u);
            if m.pdf <= 0.0 {
                continue;
            }
            let wi = reflect_about(wo, m.value);
            if wi.z <= 0.0 {
                continue;
            }
            // f cos / pdf for visible-normal sampling: F · G1(wi) (and D, G1(wo) cancel); for
            // Blinn–Phong use the general ratio.
            let pdf = m.pdf / (4.0 * wo.dot(m.value));
            let f =
                fresnel_dielectric(wo.dot(m.value), eta).0 * distribution.d(m.value) * distribution.g(wi, wo, m.value)
                    / (4.0 * wo.z);
            sum += (f / pdf) as f64;
        }
    }
    (sum / (n * n) as f64) as f32
}

impl RoughPlastic {
    /// Rough plastic with the given parameters (tables computed here).
    pub fn new(
        distribution: Microfacet,
        diffuse_reflectance: Rgb,
        specular_reflectance: Rgb,
        eta: f32,
        nonlinear: bool,
    ) -> Self {
        let mu = |k: usize| k as f32 / (TABLE - 1) as f32;
        let external_transmittance = (0..TABLE).map(|k| 1.0 - specular_albedo(&distribution, eta, mu(k))).collect();
        let internal: Vec<f32> = (0..TABLE).map(|k| 1.0 - specular_albedo(&distribution, 1.0 / eta, mu(k))).collect();
        // R_int = 1 - 2 ∫ T_int(μ) μ dμ (trapezoid rule on the table).
        let h = 1.0 / (TABLE - 1) as f32;
        let integral: f32 =
            (0..TABLE).map(|k| internal[k] * mu(k) * if k == 0 || k == TABLE - 1 { 0.5 } else { 1.0 }).sum::<f32>() * h;
        RoughPlastic {
            distribution,
            diffuse_reflectance,
            specular_reflectance,
            eta,
            nonlinear,
            external_transmittance,
            internal_reflectance: (1.0 - 2.0 * integral).clamp(0.0, 1.0),
            specular_weight: specular_sampling_weight(diffuse_reflectance, specular_reflectance),
        }
    }

    /// Coating transmittance `T(μ)` from outside.
    pub fn transmittance(&self, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (TABLE - 1) as f32;
        let k = (x as usize).min(TABLE - 2);
        let t = x - k as f32;
        self.external_transmittance[k] * (1.0 - t) + self.external_transmittance[k + 1] * t
    }

    fn probabilities(&self, cos_o: f32) -> (f32, f32) {
        let t = self.transmittance(cos_o);
        let ps = (1.0 - t) * self.specular_weight;
        let pd = t * (1.0 - self.specular_weight);
        let total = ps + pd;
        if total <= 0.0 {
            return (0.0, 1.0);
        }
        (ps / total, pd / total)
    }

    fn diffuse_albedo(&self) -> Rgb {
        coated_diffuse_albedo(self.diffuse_reflectance, self.internal_reflectance, self.nonlinear)
    }

    /// `f cos θᵢ` (specular + diffuse).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let m = (wo + wi).normalize();
        let f = fresnel_dielectric(wo.dot(m), self.eta).0;
        let spec = f * self.distribution.d(m) * self.distribution.g(wi, wo, m) / (4.0 * wo.z);
        let diff = self.transmittance(wo.z) * self.transmittance(wi.z) * INV_PI / (self.eta * self.eta) * wi.z;
        self.specular_reflectance * spec + self.diffuse_albedo() * diff
    }

    /// Density of [`RoughPlastic::sample`].
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let (ps, pd) = self.probabilities(wo.z);
        let m = (wo + wi).normalize();
        ps * self.distribution.pdf(wo, m) / (4.0 * wo.dot(m).abs()) + pd * wi.z * INV_PI
    }

    /// Specular (visible normal, reflected) or diffuse (cosine) direction, weighted by the full
    /// mixture.
    pub fn sample(&self, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (ps, _) = self.probabilities(wo.z);
        let wi = if u1 < ps {
            reflect_about(wo, self.distribution.sample(wo, u).value)
        } else {
            sample_cosine_hemisphere_malley(u).value
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then(|| BsdfSample { wi, pdf, weight: self.eval(wo, wi) / pdf, delta: false, eta: 1.0 })
    }
}

impl RoughPlastic {
    /// Mitsuba's `roughplastic`: the plastic's parameters and an isotropic microfacet
    /// distribution.
    pub fn from_props(o: &Obj, _: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let (diffuse, specular, eta, nonlinear) = super::plastic::plastic_props(o)?;
        Ok(Bsdf::RoughPlastic(RoughPlastic::new(Microfacet::from_props(o, false)?, diffuse, specular, eta, nonlinear)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::microfacet::MicrofacetType;

    #[test]
    fn transmittance_tables_are_physical() {
        let p =
            RoughPlastic::new(Microfacet::new(MicrofacetType::Ggx, 0.1, 0.1), Rgb::splat(0.5), Rgb::ONE, 1.49, false);
        // Near normal incidence a smooth-ish coating transmits ≈ 1 - F(1) = 0.961.
        assert!((p.transmittance(1.0) - 0.961).abs() < 0.01, "{}", p.transmittance(1.0));
        assert!(p.transmittance(0.05) < p.transmittance(1.0));
        // Seen from inside, total internal reflection makes the coating reflect most light
        // (≈ 0.6 for a smooth 1.49 interface).
        assert!((p.internal_reflectance - 0.6).abs() < 0.05, "{}", p.internal_reflectance);
    }
}
