//! Mitsuba's `conductor` (smooth metal: a perfect mirror with Fresnel reflectance) and
//! `roughconductor` (microfacet metal, Cook–Torrance with Smith shadowing).
//!
//! Parameters (Mitsuba): `eta`, `k` (complex index of refraction relative to the exterior, RGB
//! or textures; or a named `material`; the default, no material, is a perfect mirror with
//! reflectance 1), `specular_reflectance` (RGB scale or texture, default 1); for
//! `roughconductor` also `distribution` (`beckmann` | `ggx`), `alpha` or `alpha_u` / `alpha_v`
//! (default 0.1, numbers or textures), and `sample_visible` (always on here).

use super::conductor_presets::{conductor_names, named_conductor};
use super::fresnel::{fresnel_conductor, reflect, reflect_about};
use super::microfacet::{Microfacet, Roughness};
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Rgb, Vec2, Vec3};
use crate::props::{nearest, Obj, Result as PropResult};
use crate::texture::Texture;

/// The Fresnel term of a conductor: its complex index of refraction relative to the exterior,
/// per RGB channel (texturable, as in Mitsuba).
#[derive(Clone, Debug)]
pub struct ConductorIor {
    /// Real part per channel.
    pub eta: Texture,
    /// Imaginary part (absorption) per channel.
    pub k: Texture,
}

impl ConductorIor {
    /// A constant index `eta + i k`.
    pub fn constant(eta: Rgb, k: Rgb) -> ConductorIor {
        ConductorIor { eta: eta.into(), k: k.into() }
    }

    /// Fresnel reflectance at `cos θ` at `ctx` (1 everywhere when `None`: a perfect mirror).
    #[inline]
    pub fn reflectance(ior: &Option<ConductorIor>, ctx: &BsdfContext, cos_theta: f32) -> Rgb {
        match ior {
            None => Rgb::ONE,
            Some(c) => fresnel_conductor(cos_theta, ctx.eval(&c.eta), ctx.eval(&c.k)),
        }
    }

    /// Its textures (none for a perfect mirror).
    pub fn textures(ior: &Option<ConductorIor>) -> impl Iterator<Item = &Texture> {
        ior.iter().flat_map(|c| [&c.eta, &c.k])
    }
}

/// Smooth conductor: delta reflection with Fresnel reflectance.
#[derive(Clone, Debug)]
pub struct Conductor {
    /// Complex index of refraction (`None`: perfect mirror).
    pub ior: Option<ConductorIor>,
    /// Reflectance scale (texturable).
    pub specular_reflectance: Texture,
}

impl Conductor {
    /// Mirror reflection of `wo`, weight `F(cos θ) · specular_reflectance`. One-sided.
    #[inline]
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let weight = ctx.eval(&self.specular_reflectance) * ConductorIor::reflectance(&self.ior, ctx, wo.z);
        Some(BsdfSample { wi: reflect(wo), pdf: 1.0, weight, delta: true, null: false, eta: 1.0 })
    }
}

/// Rough conductor: `f = F(wo·m) D(m) G(wi, wo, m) / (4 cos θᵢ cos θₒ)`, `m = (wi + wo)/|wi + wo|`,
/// sampled through the visible normals seen from `wo`.
#[derive(Clone, Debug)]
pub struct RoughConductor {
    /// Microfacet distribution (roughness texturable).
    pub roughness: Roughness,
    /// Complex index of refraction (`None`: perfect reflector).
    pub ior: Option<ConductorIor>,
    /// Reflectance scale (texturable).
    pub specular_reflectance: Texture,
}

impl RoughConductor {
    /// `f cos θᵢ`; 0 unless both directions are above the surface.
    #[inline]
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let distribution = self.roughness.at(ctx);
        let m = (wo + wi).normalize();
        let (d, g1_o) = (distribution.d(m), distribution.g1(wo, m));
        self.value(ctx, &distribution, wo, wi, m, d, g1_o)
    }

    /// [`RoughConductor::eval`] and [`RoughConductor::pdf`] at once (the same bits), sharing
    /// the half vector, `D` and `G1(wo)`.
    #[inline]
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let distribution = self.roughness.at(ctx);
        let m = (wo + wi).normalize();
        let (d, g1_o) = (distribution.d(m), distribution.g1(wo, m));
        let pdf = distribution.pdf_given(wo, m, d, g1_o) / (4.0 * wo.dot(m).abs());
        (self.value(ctx, &distribution, wo, wi, m, d, g1_o), pdf)
    }

    /// `f cos θᵢ` for the half vector `m` with `d = D(m)` and `g1_o = G1(wo, m)`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn value(&self, ctx: &BsdfContext, dist: &Microfacet, wo: Vec3, wi: Vec3, m: Vec3, d: f32, g1_o: f32) -> Rgb {
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = dist.g1(wi, m) * g1_o;
        let f = ConductorIor::reflectance(&self.ior, ctx, wi.dot(m));
        ctx.eval(&self.specular_reflectance) * f * (d * g / (4.0 * wo.z))
    }

    /// Density of [`RoughConductor::sample`]: `pdf(m) / (4 |wo·m|)` (Jacobian of reflection).
    #[inline]
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let m = (wo + wi).normalize();
        self.roughness.at(ctx).pdf(wo, m) / (4.0 * wo.dot(m).abs())
    }

    /// A visible microfacet normal from `wo`, reflected.
    #[inline]
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let distribution = self.roughness.at(ctx);
        let m = distribution.sample(wo, u);
        if m.pdf <= 0.0 {
            return None;
        }
        let wi = reflect_about(wo, m.value);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = m.pdf / (4.0 * wo.dot(m.value).abs());
        let weight = if distribution.samples_visible_normals() {
            // f cos θᵢ / pdf with pdf(m) = G1(wo, m) (wo·m) D(m) / cos θₒ: D and G1(wo) cancel,
            // leaving F G1(wi, m) (Mitsuba's weight), without evaluating D and G1(wo) again.
            let f = ConductorIor::reflectance(&self.ior, ctx, wi.dot(m.value));
            ctx.eval(&self.specular_reflectance) * f * distribution.g1(wi, m.value)
        } else {
            self.eval(ctx, wo, wi) / pdf
        };
        (pdf > 0.0 && weight.is_finite()).then_some(BsdfSample { wi, pdf, weight, delta: false, null: false, eta: 1.0 })
    }
}

impl ConductorIor {
    /// The complex index of a conductor: `eta` and `k` (defaults 0 and 1, texturable), or a
    /// named `material` (default `none`, Mitsuba's perfect mirror: `None`), not both.
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Option<ConductorIor>> {
        if o.has("eta") || o.has("k") {
            if o.has("material") {
                return Err(o.error_at("material", "give either 'material' or 'eta'/'k'"));
            }
            let eta = b.texture_of(o, "eta", Rgb::ZERO, SpectrumKind::Unbounded)?;
            let k = b.texture_of(o, "k", Rgb::ONE, SpectrumKind::Unbounded)?;
            return Ok(Some(ConductorIor { eta, k }));
        }
        let name = o.string_opt("material")?.unwrap_or_else(|| "none".into());
        named_conductor(&name).ok_or_else(|| {
            let hint = nearest(&name, conductor_names()).map(|n| format!(" (did you mean '{n}'?)")).unwrap_or_default();
            o.error_at("material", format!("unknown conductor material '{name}'{hint}"))
        })
    }
}

impl Conductor {
    /// Mitsuba's `conductor`: `material` or `eta`/`k`, `specular_reflectance` (1, texturable).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        Ok(Bsdf::Conductor(Conductor {
            ior: ConductorIor::from_props(o, b)?,
            specular_reflectance: b.texture(o, "specular_reflectance", Rgb::ONE)?,
        }))
    }
}

impl RoughConductor {
    /// Mitsuba's `roughconductor`: the conductor's parameters and the microfacet distribution's
    /// (anisotropic `alpha_u`/`alpha_v` allowed; the roughness and `specular_reflectance` may be
    /// textures).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        Ok(Bsdf::RoughConductor(RoughConductor {
            roughness: Roughness::from_props(o, b)?,
            ior: ConductorIor::from_props(o, b)?,
            specular_reflectance: b.texture(o, "specular_reflectance", Rgb::ONE)?,
        }))
    }
}
