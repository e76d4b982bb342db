//! Mitsuba's `plastic`: a smooth dielectric coating over a diffuse base.
//!
//! Light either reflects specularly off the coating (probability F) or enters, scatters
//! diffusely in the base, and leaves through the coating. Multiple internal reflections at the
//! coating are accounted for by the diffuse Fresnel reflectance `F_dr` of its inside: with base
//! albedo ρ the effective diffuse lobe is
//! `f_d = ρ / (1 - F_dr) · (1 - F(cos θᵢ)) (1 - F(cos θₒ)) / (π η²)` (or `ρ / (1 - ρ F_dr)` with
//! `nonlinear`, which also darkens and saturates colours as real plastics do). `F_dr(1/η) =
//! 2 ∫₀¹ F(μ) μ dμ` is integrated numerically here rather than taken from a fit.
//!
//! Sampling chooses the specular lobe with probability proportional to
//! `F(cos θₒ) · s / (s + d)` against `(1 - F(cos θₒ)) · d / (s + d)`, `s` and `d` being the mean
//! specular and diffuse reflectances (Mitsuba's rule).
//!
//! Parameters (Mitsuba): `diffuse_reflectance` (0.5, texturable), `specular_reflectance` (1, texturable), `int_ior`
//! (polypropylene, 1.49), `ext_ior` (air), `nonlinear` (false).

use super::fresnel::eta_from_props;
use super::fresnel::{fresnel_dielectric, reflect};
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::texture::Texture;
use crate::math::{Rgb, Vec2, Vec3, INV_PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::sample_cosine_hemisphere_malley;

/// Smooth plastic.
#[derive(Clone, Debug)]
pub struct Plastic {
    /// Base albedo ρ (texturable).
    pub diffuse_reflectance: Texture,
    /// Specular scale (texturable).
    pub specular_reflectance: Texture,
    /// `int_ior / ext_ior` of the coating.
    pub eta: f32,
    /// Mitsuba's `nonlinear` internal-scattering model.
    pub nonlinear: bool,
    /// Diffuse Fresnel reflectance of the coating seen from inside.
    fdr_int: f32,
    /// Probability weight of the specular lobe.
    specular_weight: f32,
}

/// Hemispherical-average Fresnel reflectance `2 ∫₀¹ F(μ, η) μ dμ` (for light arriving
/// diffusely at an interface of relative index η).
pub fn diffuse_fresnel_reflectance(eta: f32) -> f32 {
    let n = 2048;
    let mut sum = 0.0f64;
    for i in 0..n {
        let mu = (i as f64 + 0.5) / n as f64;
        sum += fresnel_dielectric(mu as f32, eta).0 as f64 * mu;
    }
    (2.0 * sum / n as f64) as f32
}

/// Probability weight of the specular lobe of a coated material: `s / (s + d)` with `s`, `d` the
/// mean specular and diffuse reflectances (½ when both are black). Shared by `plastic` and
/// `roughplastic`.
pub(super) fn specular_sampling_weight(diffuse: Rgb, specular: Rgb) -> f32 {
    let d = diffuse.element_sum() / 3.0;
    let s = specular.element_sum() / 3.0;
    if s + d > 0.0 {
        s / (s + d)
    } else {
        0.5
    }
}

/// Albedo of the base once internal reflections at the coating (diffuse reflectance `r_int`
/// seen from inside) are summed: `ρ / (1 - r_int)`, or `ρ / (1 - ρ r_int)` for the `nonlinear`
/// model. Shared by `plastic` and `roughplastic`.
pub(super) fn coated_diffuse_albedo(rho: Rgb, r_int: f32, nonlinear: bool) -> Rgb {
    if nonlinear {
        rho / (Rgb::ONE - rho * r_int)
    } else {
        rho / (1.0 - r_int)
    }
}

impl Plastic {
    /// Plastic with the given parameters.
    pub fn new(
        diffuse_reflectance: impl Into<Texture>,
        specular_reflectance: impl Into<Texture>,
        eta: f32,
        nonlinear: bool,
    ) -> Plastic {
        let (diffuse_reflectance, specular_reflectance) = (diffuse_reflectance.into(), specular_reflectance.into());
        let specular_weight = specular_sampling_weight(diffuse_reflectance.mean(), specular_reflectance.mean());
        Plastic {
            diffuse_reflectance,
            specular_reflectance,
            eta,
            nonlinear,
            fdr_int: diffuse_fresnel_reflectance(1.0 / eta),
            specular_weight,
        }
    }

    fn diffuse_albedo(&self, ctx: &BsdfContext) -> Rgb {
        coated_diffuse_albedo(ctx.eval(&self.diffuse_reflectance), self.fdr_int, self.nonlinear)
    }

    fn probabilities(&self, cos_o: f32) -> (f32, f32) {
        let f = fresnel_dielectric(cos_o, self.eta).0;
        let ps = f * self.specular_weight;
        let pd = (1.0 - f) * (1.0 - self.specular_weight);
        let total = ps + pd;
        (ps / total, pd / total)
    }

    /// The diffuse part `f_d cos θᵢ` (the specular part is a delta).
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let fo = fresnel_dielectric(wo.z, self.eta).0;
        let fi = fresnel_dielectric(wi.z, self.eta).0;
        self.diffuse_albedo(ctx) * ((1.0 - fo) * (1.0 - fi) * INV_PI / (self.eta * self.eta) * wi.z)
    }

    /// Density of the diffuse lobe's directions (the specular lobe has none).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        self.probabilities(wo.z).1 * wi.z * INV_PI
    }

    /// Specular reflection (delta) or a cosine-weighted diffuse direction.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (ps, pd) = self.probabilities(wo.z);
        if u1 < ps {
            let f = fresnel_dielectric(wo.z, self.eta).0;
            Some(BsdfSample {
                wi: reflect(wo),
                pdf: ps,
                weight: ctx.eval(&self.specular_reflectance) * (f / ps),
                delta: true, null: false,
                eta: 1.0,
            })
        } else {
            let wi = sample_cosine_hemisphere_malley(u).value;
            let pdf = pd * wi.z * INV_PI;
            if pdf <= 0.0 {
                return None;
            }
            Some(BsdfSample { wi, pdf, weight: self.eval(ctx, wo, wi) / pdf, delta: false, null: false, eta: 1.0 })
        }
    }
}

/// The parameters both plastics read: `diffuse_reflectance` (0.5, texturable),
/// `specular_reflectance` (1, texturable), `eta` from `int_ior` (polypropylene, 1.49) and
/// `ext_ior`, `nonlinear` (false).
pub(crate) fn plastic_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<(Texture, Texture, f32, bool)> {
    let diffuse = b.texture(o, "diffuse_reflectance", Rgb::splat(0.5))?;
    let specular = b.texture(o, "specular_reflectance", Rgb::ONE)?;
    for (name, t) in [("diffuse_reflectance", &diffuse), ("specular_reflectance", &specular)] {
        if !t.mesh_attributes().is_empty() {
            // Mitsuba refuses it too: the lobe-selection weight needs the texture's mean.
            return Err(o.error_at(
                name,
                format!("a plastic's {name} cannot be a mesh_attribute (its sampling weight needs the texture's mean)"),
            ));
        }
    }
    Ok((
        diffuse,
        specular,
        eta_from_props(o, 1.49)?,
        o.bool("nonlinear", false)?,
    ))
}

impl Plastic {
    /// Mitsuba's `plastic` : `diffuse_reflectance` (0.5), `specular_reflectance` (1), `int_ior` (1.49), `ext_ior` (air), `nonlinear` (false).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let (diffuse, specular, eta, nonlinear) = plastic_props(o, b)?;
        Ok(Bsdf::Plastic(Plastic::new(diffuse, specular, eta, nonlinear)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diffuse_fresnel_reflectance_known_values() {
        // Light inside a 1.5 medium hitting its boundary diffusely: ≈ 0.596 (total internal
        // reflection beyond the critical angle); from outside: ≈ 0.092.
        assert!((diffuse_fresnel_reflectance(1.0 / 1.5) - 0.596).abs() < 0.003);
        assert!((diffuse_fresnel_reflectance(1.5) - 0.092).abs() < 0.003);
        assert!(diffuse_fresnel_reflectance(1.0) < 1e-6);
    }

    #[test]
    fn energy_balance_of_a_white_plastic() {
        // With ρ = 1 (linear model) the outgoing energy stays ≤ 1, and the specular lobe's
        // probability follows Fresnel.
        let p = Plastic::new(Rgb::ONE, Rgb::ONE, 1.49, false);
        for wo in [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.95, 0.0, 0.312).normalize()] {
            let mut rng = crate::sampling::Pcg32::new(2, 2);
            let n = 100_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                if let Some(s) = p.sample(&BsdfContext::default(), wo, rng.next_f32(), crate::testkit::u2(&mut rng)) {
                    sum += s.weight.x as f64;
                }
            }
            let albedo = sum / n as f64;
            assert!(albedo <= 1.01 && albedo > 0.5, "{wo}: {albedo}");
        }
    }
}
