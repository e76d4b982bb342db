//! Mitsuba's `roughplastic`: a rough dielectric coating (microfacet reflection) over a diffuse
//! base.
//!
//! `f cos θᵢ = F(wo·m) D(m) G / (4 cos θₒ) · s  +  ρ' / (π η²) · T(cos θₒ) T(cos θᵢ) cos θᵢ`, where
//! `T(μ)` is the fraction of light the rough coating transmits at incidence μ (the integral of
//! the rough dielectric's transmission lobe), and `ρ' = ρ / (1 - R_int)` (or
//! `ρ / (1 - ρ R_int)` with `nonlinear`) accounts for internal reflections with
//! `R_int = 2 ∫₀¹ R_int(μ) μ dμ` the coating's diffuse reflectance seen from inside. Both are
//! computed when the BSDF is built exactly as Mitsuba 3 computes them (Gauss–Legendre
//! quadrature over visible normals, a 64-entry table of `T` interpolated linearly in `cos θ`,
//! and `R_int` as twice the table's mean of `R_int(μ) μ`), so that images match Mitsuba's.
//!
//! Sampling picks the specular lobe with probability ∝ `(1 - T(cos θₒ)) s / (s + d)` against
//! `T(cos θₒ) d / (s + d)`.
//!
//! Parameters (Mitsuba): `diffuse_reflectance` (0.5, texturable), `specular_reflectance` (1, texturable), `int_ior`
//! (1.49), `ext_ior`, `distribution` (beckmann, ggx), `alpha` (0.1), `nonlinear` (false).

use super::fresnel::{fresnel_dielectric, reflect_about, refract_about};
use super::microfacet::{Microfacet, MicrofacetType};
use super::plastic::{coated_diffuse_albedo, specular_sampling_weight};
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::quadrature::gauss_legendre;
use crate::math::{Rgb, Vec2, Vec3, INV_PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::sample_cosine_hemisphere_malley;
use crate::texture::Texture;

const TABLE: usize = 64;

/// Rough plastic.
#[derive(Clone, Debug)]
pub struct RoughPlastic {
    /// Microfacet distribution of the coating.
    pub distribution: Microfacet,
    /// Base albedo ρ (texturable).
    pub diffuse_reflectance: Texture,
    /// Specular scale (texturable).
    pub specular_reflectance: Texture,
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

/// Which albedos [`coating_albedos`] sums (the tables need one each; the other stays 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Albedos {
    /// `R` alone (the internal reflectance).
    Reflected,
    /// `T` alone (the external transmittance).
    Transmitted,
    /// Both.
    #[cfg(test)]
    Both,
}

/// The reflected and transmitted albedos `(R, T)` of a rough dielectric interface (relative
/// index `eta`) lit at incidence `mu`: `∫ F D G |wo·m| / (cos θₒ) dω_m` over microfacet normals,
/// with `(1 − F)` and the refracted direction for `T` (for visible-normal sampling the weight of
/// a sampled normal is `F G1(w, m)`, w the scattered direction). Mitsuba's `eval_reflectance` and
/// `eval_transmittance`: visible normals sampled at the nodes of an `n × n` Gauss–Legendre rule
/// (`n` = 32 from outside, `η > 1`; 128 from inside, where total internal reflection makes the
/// integrand rough). `R + T < 1`: single scattering loses what the masking removes. Only the
/// albedos `which` names are summed (the other is 0).
fn coating_albedos(distribution: &Microfacet, eta: f32, mu: f32, which: Albedos) -> (f32, f32) {
    let (want_r, want_t) = (which != Albedos::Transmitted, which != Albedos::Reflected);
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let (u, weights) = quadrature_grid(if eta > 1.0 { 32 } else { 128 });
    let visible = distribution.samples_visible_normals();
    let (mut r, mut t) = (0.0f64, 0.0f64);
    // The n × n product rule's normals, with the work of one coordinate done once per node.
    let mut visit = |i: usize, j: usize, m: Vec3| {
        let (f, cos_t, _, eta_ti) = fresnel_dielectric(wo.dot(m), eta);
        // D G |wo·m| / (cos θₒ p(m)): for visible normals (p = G1(wo) |wo·m| D / cos θₒ) the
        // masking of the scattered direction, G1(w, m), as Mitsuba evaluates it (without
        // D, G and the density again: the tables take a quarter less time).
        let ratio = |w: Vec3| {
            if visible {
                distribution.g1(w, m)
            } else {
                distribution.d(m) * distribution.g(wo, w, m) * wo.dot(m).abs() / (wo.z * distribution.pdf(wo, m))
            }
        };
        let weight = weights[i] * weights[j] * 0.25;
        let wr = reflect_about(wo, m);
        if want_r && wr.z > 0.0 {
            r += weight * (f * ratio(wr)) as f64;
        }
        if want_t && f < 1.0 {
            let wt = refract_about(wo, m, cos_t, eta_ti);
            if wt.z < 0.0 {
                t += weight * ((1.0 - f) * ratio(wt)) as f64;
            }
        }
    };
    if visible {
        // Mitsuba's quadrature takes every normal (a density that rounds to zero does not
        // make its normal's masking and Fresnel terms zero).
        distribution.sample_grid_normals(wo, u, u, &mut visit);
    } else {
        distribution.sample_grid(wo, u, u, |i, j, m| {
            if m.pdf > 0.0 {
                visit(i, j, m.value)
            }
        });
    }
    (r as f32, t as f32)
}

/// The `n`-point Gauss–Legendre rule mapped to [0, 1] (nodes as `f32`, weights on [-1, 1]), for
/// the tables' `n` = 32 and 128, computed once per process (finding 128 roots by Newton's
/// method took an eighth of a table's time when done per table entry).
fn quadrature_grid(n: usize) -> (&'static [f32], &'static [f64]) {
    use std::sync::OnceLock;
    static RULES: [OnceLock<(Vec<f32>, Vec<f64>)>; 2] = [OnceLock::new(), OnceLock::new()];
    let rule = |n: usize| {
        let (nodes, weights) = gauss_legendre(n);
        (nodes.iter().map(|&x| (0.5 * x + 0.5) as f32).collect(), weights)
    };
    let (u, w) = match n {
        32 => RULES[0].get_or_init(|| rule(32)),
        128 => RULES[1].get_or_init(|| rule(128)),
        _ => unreachable!("the coating tables use 32 or 128 nodes"),
    };
    (u, w)
}

/// The coating's tables: `T(μₖ)` from outside at Mitsuba's `μₖ = max(10⁻⁶, k / 63)`, and the
/// internal diffuse reflectance `R_int = 2 ∫ R_int(μ) μ dμ` as Mitsuba sums it (twice the mean of
/// `R_int(μₖ) μₖ` over the table). Computed in parallel once per distinct (distribution, η) and
/// kept for the process: scenes often repeat one rough plastic on many shapes.
fn coating_tables(distribution: Microfacet, eta: f32) -> std::sync::Arc<(Vec<f32>, f32)> {
    use rayon::prelude::*;
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex, OnceLock};
    type Key = (u8, u32, u32, u32, u32);
    type Tables = Arc<(Vec<f32>, f32)>;
    static CACHE: OnceLock<Mutex<HashMap<Key, Tables>>> = OnceLock::new();
    let (kind, exponent) = match distribution.kind {
        MicrofacetType::Beckmann => (0, 0.0),
        MicrofacetType::Ggx => (1, 0.0),
        MicrofacetType::BlinnPhong(e) => (2, e),
    };
    let key = (kind, exponent.to_bits(), distribution.alpha_u.to_bits(), distribution.alpha_v.to_bits(), eta.to_bits());
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(t) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return t.clone();
    }
    let mu = |k: usize| (k as f32 / (TABLE - 1) as f32).max(1e-6);
    let external: Vec<f32> = (0..TABLE)
        .into_par_iter()
        .map(|k| coating_albedos(&distribution, eta, mu(k), Albedos::Transmitted).1)
        .collect();
    let internal: f64 = (0..TABLE)
        .into_par_iter()
        .map(|k| (coating_albedos(&distribution, 1.0 / eta, mu(k), Albedos::Reflected).0 * mu(k)) as f64)
        .sum::<f64>();
    let tables = Arc::new((external, (2.0 * internal / TABLE as f64).clamp(0.0, 1.0) as f32));
    cache.lock().unwrap_or_else(|e| e.into_inner()).insert(key, tables.clone());
    tables
}

impl RoughPlastic {
    /// Rough plastic with the given parameters (tables computed here, or reused).
    pub fn new(
        distribution: Microfacet,
        diffuse_reflectance: impl Into<Texture>,
        specular_reflectance: impl Into<Texture>,
        eta: f32,
        nonlinear: bool,
    ) -> Self {
        let (diffuse_reflectance, specular_reflectance) = (diffuse_reflectance.into(), specular_reflectance.into());
        let specular_weight = specular_sampling_weight(diffuse_reflectance.mean(), specular_reflectance.mean());
        let tables = coating_tables(distribution, eta);
        let (external_transmittance, internal_reflectance) = (tables.0.clone(), tables.1);
        RoughPlastic {
            distribution,
            diffuse_reflectance,
            specular_reflectance,
            eta,
            nonlinear,
            external_transmittance,
            internal_reflectance,
            specular_weight,
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

    fn diffuse_albedo(&self, ctx: &BsdfContext) -> Rgb {
        coated_diffuse_albedo(ctx.eval(&self.diffuse_reflectance), self.internal_reflectance, self.nonlinear)
    }

    /// `f cos θᵢ` (specular + diffuse).
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let m = (wo + wi).normalize();
        self.value(ctx, wo, wi, m, self.distribution.d(m), self.distribution.g1(wo, m))
    }

    /// Density of [`RoughPlastic::sample`].
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let m = (wo + wi).normalize();
        self.density(wo, wi, m, self.distribution.pdf(wo, m))
    }

    /// [`RoughPlastic::eval`] and [`RoughPlastic::pdf`] at once (the same bits), sharing the
    /// half vector, `D` and `G1(wo)`.
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let m = (wo + wi).normalize();
        let (d, g1_o) = (self.distribution.d(m), self.distribution.g1(wo, m));
        (self.value(ctx, wo, wi, m, d, g1_o), self.density(wo, wi, m, self.distribution.pdf_given(wo, m, d, g1_o)))
    }

    /// `f cos θᵢ` at the half vector `m` with `d = D(m)`, `g1_o = G1(wo, m)`.
    fn value(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3, m: Vec3, d: f32, g1_o: f32) -> Rgb {
        let f = fresnel_dielectric(wo.dot(m), self.eta).0;
        let spec = f * d * (self.distribution.g1(wi, m) * g1_o) / (4.0 * wo.z);
        let diff = self.transmittance(wo.z) * self.transmittance(wi.z) * INV_PI / (self.eta * self.eta) * wi.z;
        ctx.eval(&self.specular_reflectance) * spec + self.diffuse_albedo(ctx) * diff
    }

    /// The mixture density at `wi` from the half vector `m`'s density `pdf_m`.
    fn density(&self, wo: Vec3, wi: Vec3, m: Vec3, pdf_m: f32) -> f32 {
        let (ps, pd) = self.probabilities(wo.z);
        ps * pdf_m / (4.0 * wo.dot(m).abs()) + pd * wi.z * INV_PI
    }

    /// Specular (visible normal, reflected) or diffuse (cosine) direction, weighted by the full
    /// mixture.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
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
        let (f, pdf) = self.eval_pdf(ctx, wo, wi);
        (pdf > 0.0).then(|| BsdfSample { wi, pdf, weight: f / pdf, delta: false, null: false, eta: 1.0 })
    }
}

impl RoughPlastic {
    /// Mitsuba's `roughplastic`: the plastic's parameters and an isotropic microfacet
    /// distribution.
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let (diffuse, specular, eta, nonlinear) = super::plastic::plastic_props(o, b)?;
        Ok(Bsdf::RoughPlastic(RoughPlastic::new(Microfacet::from_props(o, false)?, diffuse, specular, eta, nonlinear)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmittance_tables_are_physical() {
        let p =
            RoughPlastic::new(Microfacet::new(MicrofacetType::Ggx, 0.1, 0.1), Rgb::splat(0.5), Rgb::ONE, 1.49, false);
        // Near normal incidence a smooth-ish coating transmits ≈ 1 - F(1) = 0.961.
        assert!((p.transmittance(1.0) - 0.961).abs() < 0.01, "{}", p.transmittance(1.0));
        assert!(p.transmittance(0.05) < p.transmittance(1.0));
        // Seen from inside, total internal reflection makes the coating reflect most light
        // (0.596 for a smooth 1.49 interface; Mitsuba's sum over its 64-entry table gives 63/64
        // of the integral, and masking takes a little more).
        assert!((p.internal_reflectance - 0.55).abs() < 0.02, "{}", p.internal_reflectance);
        // Single scattering loses energy: R + T < 1 at grazing angles, ≈ 1 near the normal.
        let (r, t) = coating_albedos(&p.distribution, 1.49, 1.0, Albedos::Both);
        assert!((r + t - 1.0).abs() < 0.01 && r + t <= 1.0 + 1e-4, "{r} + {t}");
        let (r, t) = coating_albedos(&p.distribution, 1.49, 0.1, Albedos::Both);
        assert!(r + t < 0.99, "{r} + {t}");
    }
}
