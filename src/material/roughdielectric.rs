//! Mitsuba's `roughdielectric`: rough glass by the microfacet model of Walter et al. 2007
//! ("Microfacet Models for Refraction through Rough Surfaces").
//!
//! With `e` the ratio of the index on `wi`'s side to the index on `wo`'s side, the microfacet
//! normal is `m ∝ wo + wi` for reflection and `m ∝ -(wo + e wi)` for refraction (oriented to
//! +z). The BSDF (radiance transport, times `|cos θᵢ|`) is
//! - reflection: `F D G / (4 |cos θₒ|)`,
//! - refraction: `(1 - F) D G |wi·m| |wo·m| / (|cos θₒ| (wo·m + e wi·m)²)`,
//!
//! with `F = F(wo·m)`. Sampling takes a visible normal seen from `wo`, then reflects with
//! probability F and refracts otherwise; the refraction Jacobian is
//! `dωₘ/dωᵢ = e² |wi·m| / (wo·m + e wi·m)²`.
//!
//! Parameters (Mitsuba): `int_ior`, `ext_ior`, `distribution`, `alpha` / `alpha_u` / `alpha_v`,
//! `specular_reflectance`, `specular_transmittance`.

use super::fresnel::{fresnel_dielectric, reflect_about, refract_about};
use super::microfacet::{Microfacet, Roughness};
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{Rgb, Vec2, Vec3};
use crate::props::{Obj, Result as PropResult};
use crate::texture::Texture;

/// Rough dielectric interface.
#[derive(Clone, Debug)]
pub struct RoughDielectric {
    /// Microfacet distribution (roughness texturable).
    pub roughness: Roughness,
    /// `int_ior / ext_ior`.
    pub eta: f32,
    /// Reflection scale (texturable).
    pub specular_reflectance: Texture,
    /// Transmission scale (texturable).
    pub specular_transmittance: Texture,
}

/// Geometry of a (wo, wi) pair: microfacet normal (upper hemisphere), whether it is a
/// reflection, and the index ratio `e` (wi side over wo side).
struct Config {
    m: Vec3,
    reflect: bool,
    e: f32,
}

/// What the value and the density of one `(wo, wi)` pair share.
struct Pair {
    /// The pair's microfacet geometry.
    c: Config,
    /// `wo · m`.
    wom: f32,
    /// `wi · m`.
    wim: f32,
    /// `|cos θₒ|`.
    cos_o: f32,
    /// The microfacet distribution there.
    dist: Microfacet,
    /// `D(m)`.
    d: f32,
    /// `G1(wo, m)`.
    g1_o: f32,
    /// Dielectric Fresnel reflectance at `wo · m`.
    f: f32,
}

impl RoughDielectric {
    /// The index ratio across the interface for a refraction from `wo`'s side (wi's side over
    /// wo's).
    fn refraction_ratio(&self, wo: Vec3) -> f32 {
        if wo.z > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        }
    }

    fn config(&self, wo: Vec3, wi: Vec3) -> Option<Config> {
        if wo.z == 0.0 || wi.z == 0.0 {
            return None;
        }
        let reflect = wo.z * wi.z > 0.0;
        // Index ratio across the interface, from wo's side to wi's side.
        let e = if reflect { 1.0 } else { self.refraction_ratio(wo) };
        let m = if reflect { wo + wi } else { -(wo + wi * e) };
        let len = m.length();
        if len == 0.0 {
            return None;
        }
        let m = m / len;
        let m = if m.z < 0.0 { -m } else { m };
        Some(Config { m, reflect, e })
    }

    /// `f |cos θᵢ|` for both reflection and refraction.
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        let Some(p) = self.pair(ctx, wo, wi) else { return Rgb::ZERO };
        self.value(ctx, &p, wi)
    }

    /// Density of [`RoughDielectric::sample`] choosing `wi` (solid angle).
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        let Some(p) = self.pair(ctx, wo, wi) else { return 0.0 };
        self.density(&p, wo)
    }

    /// [`RoughDielectric::eval`] and [`RoughDielectric::pdf`] at once (the same bits), sharing
    /// the half vector, the Fresnel term, `D` and `G1(wo)`.
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        let Some(p) = self.pair(ctx, wo, wi) else { return (Rgb::ZERO, 0.0) };
        (self.value(ctx, &p, wi), self.density(&p, wo))
    }

    /// What the value and the density of `(wo, wi)` share; `None` where both are 0 (no
    /// half vector, or a direction on the back of it).
    fn pair(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Option<Pair> {
        let c = self.config(wo, wi)?;
        let (wom, wim) = (wo.dot(c.m), wi.dot(c.m));
        // Directions must lie on the same side of the microfacet as of the macro-surface.
        if wom * wo.z <= 0.0 || wim * wi.z <= 0.0 {
            return None;
        }
        let dist = self.roughness.at(ctx);
        let (d, g1_o) = (dist.d(c.m), dist.g1(wo, c.m));
        let (f, ..) = fresnel_dielectric(wom, self.eta);
        Some(Pair { c, wom, wim, cos_o: wo.z.abs(), dist, d, g1_o, f })
    }

    /// [`RoughDielectric::eval`] of a pair.
    fn value(&self, ctx: &BsdfContext, p: &Pair, wi: Vec3) -> Rgb {
        let (c, wom, wim, d, f) = (&p.c, p.wom, p.wim, p.d, p.f);
        let g = p.dist.g1(wi, c.m) * p.g1_o;
        let cos_o = p.cos_o;
        if c.reflect {
            ctx.eval(&self.specular_reflectance) * (f * d * g / (4.0 * cos_o))
        } else {
            let denom = wom + c.e * wim;
            ctx.eval(&self.specular_transmittance) * ((1.0 - f) * d * g * (wim * wom).abs() / (cos_o * denom * denom))
        }
    }

    /// [`RoughDielectric::pdf`] of a pair.
    fn density(&self, p: &Pair, wo: Vec3) -> f32 {
        // G1 is even in the direction: `G1(wo)` serves the density seen from the front.
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let pdf_m = p.dist.pdf_given(wo_up, p.c.m, p.d, p.g1_o);
        wi_pdf(pdf_m, p.f, p.c.reflect, p.c.e, p.wom, p.wim)
    }

    /// A visible normal from `wo`, then reflection (probability F) or refraction.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let distribution = self.roughness.at(ctx);
        let sampled = distribution.sample(wo_up, u);
        let m = sampled.value;
        let wom = wo.dot(m);
        let (f, cos_t, eta_it, eta_ti) = fresnel_dielectric(wom, self.eta);
        let reflected = u1 <= f;
        let (wi, eta) = if reflected {
            (reflect_about(wo, m), 1.0)
        } else {
            if cos_t == 0.0 {
                return None;
            }
            (refract_about(wo, m, cos_t, eta_ti), eta_it)
        };
        // A reflection must stay on wo's side and a refraction must cross; otherwise the
        // microfacet sent the ray through the macro-surface and the sample is void.
        if (wi.z * wo.z > 0.0) != reflected {
            return None;
        }
        if !distribution.samples_visible_normals() {
            let pdf = self.pdf(ctx, wo, wi);
            if pdf <= 0.0 || pdf.is_nan() {
                return None;
            }
            let weight = self.eval(ctx, wo, wi) / pdf;
            return weight.is_finite().then_some(BsdfSample { wi, pdf, weight, delta: false, null: false, eta });
        }
        // Visible normals: pdf(m) = G1(wo, m) |wo·m| D(m) / |cos θₒ|, and the choice between
        // reflection and refraction has probability F or 1 − F, so [`RoughDielectric::pdf`] and
        // [`RoughDielectric::eval`] share D, G1(wo) and F, which cancel in the weight: G1(wi, m)
        // for a reflection, G1(wi, m) / e² for a refraction (e the index ratio across the
        // interface), Mitsuba's weights. The density is theirs, from the values at hand.
        let g1 = distribution.g1(wi, m);
        let e = if reflected { 1.0 } else { self.refraction_ratio(wo) };
        let pdf = wi_pdf(sampled.pdf, f, reflected, e, wom, wi.dot(m));
        let weight = if reflected {
            ctx.eval(&self.specular_reflectance) * g1
        } else {
            ctx.eval(&self.specular_transmittance) * (g1 / (e * e))
        };
        if pdf <= 0.0 || pdf.is_nan() || g1 <= 0.0 {
            return None;
        }
        weight.is_finite().then_some(BsdfSample { wi, pdf, weight, delta: false, null: false, eta })
    }
}

/// Density of `wi` (solid angle) given the microfacet normal `m`'s density `pdf_m` and the
/// Fresnel reflectance `f` at `wo·m`: a reflection (probability F, Jacobian 1 / (4 |wo·m|)) or a
/// refraction (probability 1 − F, Jacobian e² |wi·m| / (wo·m + e wi·m)², `e` the index ratio
/// across the interface).
fn wi_pdf(pdf_m: f32, f: f32, reflect: bool, e: f32, wom: f32, wim: f32) -> f32 {
    if reflect {
        pdf_m * f / (4.0 * wom.abs())
    } else {
        let denom = wom + e * wim;
        pdf_m * (1.0 - f) * e * e * wim.abs() / (denom * denom)
    }
}

impl RoughDielectric {
    /// Mitsuba's `roughdielectric`: the dielectric's parameters and the microfacet
    /// distribution's (roughness and scales texturable).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let (eta, specular_reflectance, specular_transmittance) = super::dielectric::dielectric_props(o, b)?;
        Ok(Bsdf::RoughDielectric(RoughDielectric {
            roughness: Roughness::from_props(o, b)?,
            eta,
            specular_reflectance,
            specular_transmittance,
        }))
    }
}
