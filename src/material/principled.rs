//! Mitsuba's `principled`: the Disney BSDF (Burley 2012, 2015) as Mitsuba 3.9 implements it.
//!
//! Lobes, all in the local frame (`wo` toward the viewer, `wi` toward the light):
//! - diffuse with retro-reflection, `brdf · base/π · ((1 − F_i/2)(1 − F_o/2) + R_r (F_o + F_i +
//!   F_o F_i (R_r − 1)))` with `R_r = 2 roughness cos²θ_d` and Schlick weights `F = (1 − cos)⁵`,
//!   blended toward Hanrahan–Krueger's fake subsurface by `flatness`; plus `sheen`;
//! - main specular reflection, GGX with `α = max(0.001, roughness² / aspect)` (`aspect =
//!   √(1 − 0.9 anisotropic)`), Fresnel mixing the dielectric term with Schlick's for `metallic`
//!   (toward `base_color`) and `spec_tint`;
//! - specular transmission (rough glass of `eta`, tinted by `√base_color`), weight
//!   `(1 − metallic) spec_trans`;
//! - clearcoat: GTR1 with `α = lerp(0.1, 0.001, clearcoat_gloss)`, Schlick Fresnel of 0.04,
//!   Smith GGX masking of roughness 0.25, weight `clearcoat / 4`.
//!
//! `brdf = (1 − metallic)(1 − spec_trans)`. Sampling picks a lobe with Mitsuba's probabilities
//! (diffuse `brdf`, clearcoat `clearcoat / 4`, specular 1 split between reflection and
//! transmission by the dielectric Fresnel term, each times its sampling rate; inside the
//! material only the specular lobes), then samples GGX visible normals, GTR1 normals or the
//! cosine hemisphere; the density is the mixture of the lobes' densities. `eta` is given
//! directly or through `specular` (`eta = 2 / (1 − √(0.08 specular)) − 1`, default 0.5).

use super::fresnel::{fresnel_dielectric, reflect_about, refract_about};
use super::microfacet::{Microfacet, MicrofacetType};
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{lerp, luminance, Rgb, Vec2, Vec3, INV_PI, PI};
use crate::props::{Obj, Result as PropResult, Value};
use crate::texture::Texture;

/// Mitsuba's principled BSDF. Optional parameters are `None` where the scene leaves them out
/// (or gives the float 0): their lobes are off, as Mitsuba switches them off.
#[derive(Clone, Debug)]
pub struct Principled {
    /// Base colour (RGB).
    pub base_color: Texture,
    /// Roughness in [0, 1].
    pub roughness: Texture,
    /// Anisotropy in [0, 1].
    pub anisotropic: Option<Texture>,
    /// Weight of specular transmission.
    pub spec_trans: Option<Texture>,
    /// Weight of the sheen.
    pub sheen: Option<Texture>,
    /// Tint of the sheen toward the base colour.
    pub sheen_tint: Option<Texture>,
    /// Blend of the diffuse toward fake subsurface scattering.
    pub flatness: Option<Texture>,
    /// Tint of the dielectric specular toward the base colour.
    pub spec_tint: Option<Texture>,
    /// Metallic weight.
    pub metallic: Option<Texture>,
    /// Clearcoat weight.
    pub clearcoat: Option<Texture>,
    /// Clearcoat glossiness.
    pub clearcoat_gloss: Texture,
    /// Relative index of refraction of the specular lobes.
    pub eta: f32,
    /// Sampling rates of the main specular, clearcoat and diffuse lobes.
    pub rates: [f32; 3],
}

/// The parameters evaluated at one shading point.
struct Params {
    base: Rgb,
    roughness: f32,
    metallic: f32,
    clearcoat: f32,
    /// GGX roughness (α_u, α_v).
    alpha: (f32, f32),
    /// Weight of the reflection-only lobes, `(1 − metallic)(1 − spec_trans)`.
    brdf: f32,
    /// Weight of the transmissive lobe, `(1 − metallic) spec_trans` (0 without transmission).
    bsdf: f32,
}

/// Schlick's weight `(1 − cos)⁵`, cos clamped to [0, 1].
#[inline]
pub(super) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel with normal reflectance `r0` at `cos_i` (about the microfacet), using the
/// transmitted angle when light leaves the denser side, as Mitsuba's `calc_schlick`.
#[inline]
pub(super) fn schlick(r0: Rgb, cos_i: f32, eta: f32) -> Rgb {
    let (eta_it, eta_ti) = if cos_i >= 0.0 { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let w = if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
        schlick_weight(cos_t2.max(0.0).sqrt())
    };
    Rgb::splat(w) * (Rgb::ONE - r0) + r0
}

/// Smith GGX masking of roughness `alpha` (the clearcoat's): 0 when `v` sees the back of `m`.
#[inline]
fn smith_ggx1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// What [`Principled::eval`] and [`Principled::pdf`] share for one pair of directions.
struct Pair {
    /// `cos θₒ` (not 0).
    cos_o: f32,
    /// `wo` and `wi` on one side of the surface.
    reflect: bool,
    /// `wo` and `wi` on opposite sides.
    refract: bool,
    /// The generalized half vector (toward +z, not zero).
    wh: Vec3,
    /// The relative index along the path, seen from `wo`'s side.
    eta_path: f32,
    /// The specular GGX distribution.
    dist: Microfacet,
    /// The dielectric Fresnel reflectance at `wo · wh`.
    f_diel: f32,
    /// Whether a reflection through `wh` can join `wo` and `wi`.
    refl_ok: bool,
    /// Whether a refraction through `wh` can.
    refr_ok: bool,
    /// `D(wh)`.
    d: f32,
    /// `G1(wo, wh)`.
    g1_o: f32,
}

/// Burley's GTR1 distribution of the clearcoat, roughness `alpha`.
struct Gtr1 {
    alpha: f32,
}

impl Gtr1 {
    fn d(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let r = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * m.z * m.z));
        if r * m.z > 1e-20 {
            r
        } else {
            0.0
        }
    }

    /// Density of [`Gtr1::sample`]: `D(m) cos θ_m`.
    fn pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 {
            0.0
        } else {
            m.z * self.d(m)
        }
    }

    fn sample(&self, u: Vec2) -> Vec3 {
        let (sin_phi, cos_phi) = (2.0 * PI * u.x).sin_cos();
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let (sin_t, cos_t) = ((1.0 - cos2).max(0.0).sqrt(), cos2.max(0.0).sqrt());
        Vec3::new(cos_phi * sin_t, sin_phi * sin_t, cos_t)
    }
}

/// Whether `wo` and `wi` lie on the sides of the microfacet `m` that a reflection (or a
/// refraction) through it needs, `m` taken on `wo`'s side of the surface.
#[inline]
pub(super) fn compatible(m: Vec3, wo: Vec3, wi: Vec3, cos_o: f32, reflection: bool) -> bool {
    let m = if cos_o < 0.0 { -m } else { m };
    wo.dot(m) > 0.0 && if reflection { wi.dot(m) > 0.0 } else { wi.dot(-m) > 0.0 }
}

/// The GGX roughness `(α_u, α_v)` of a roughness and (if the parameter is on) an anisotropy, as
/// Disney's notes and Mitsuba map them: `α = max(0.001, roughness² / aspect)`, `max(0.001,
/// roughness² aspect)` with `aspect = √(1 − 0.9 anisotropic)`.
pub(super) fn ggx_alpha(roughness: f32, anisotropic: Option<f32>) -> (f32, f32) {
    let r2 = roughness * roughness;
    match anisotropic {
        None => (r2.max(0.001), r2.max(0.001)),
        Some(a) => {
            let aspect = (1.0 - 0.9 * a).sqrt();
            ((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
        }
    }
}

/// A scalar parameter that may be off (0 then).
#[inline]
pub(super) fn scalar(t: &Option<Texture>, ctx: &BsdfContext) -> f32 {
    t.as_ref().map_or(0.0, |t| ctx.scalar(t))
}

/// Disney's diffuse lobe without the `base/π` factor: `(1 − F_i/2)(1 − F_o/2)` plus the
/// retro-reflection `R_r (F_o + F_i + F_o F_i (R_r − 1))`, `R_r = 2 roughness cos²θ_d`, blended
/// toward Hanrahan–Krueger's fake subsurface `1.25 (F_ss (1/(cos θ_i + cos θ_o) − ½) + ½)` by
/// `flatness` (if on). Cosines are absolute.
pub(super) fn disney_diffuse(roughness: f32, cos_i: f32, cos_o: f32, cos_d: f32, flatness: Option<f32>) -> f32 {
    let (f_in, f_out) = (schlick_weight(cos_i), schlick_weight(cos_o));
    let f_diff = (1.0 - 0.5 * f_out) * (1.0 - 0.5 * f_in);
    let rr = 2.0 * roughness * cos_d * cos_d;
    let f_retro = rr * (f_in + f_out + f_in * f_out * (rr - 1.0));
    match flatness {
        None => f_diff + f_retro,
        Some(flatness) => {
            let fss90 = rr / 2.0;
            let fss = lerp(1.0, fss90, f_in) * lerp(1.0, fss90, f_out);
            let f_ss = 1.25 * (fss * (1.0 / (cos_i + cos_o) - 0.5) + 0.5);
            lerp(f_diff + f_retro, f_ss, flatness)
        }
    }
}

/// The sheen's colour: white tinted toward the base colour's hue (`base / luminance`) by
/// `tint` (if on).
pub(super) fn sheen_color(base: Rgb, tint: Option<f32>) -> Rgb {
    match tint {
        None => Rgb::ONE,
        Some(t) => {
            let lum = luminance(base);
            let c = if lum > 0.0 { base / lum } else { Rgb::ONE };
            Rgb::ONE + (c - Rgb::ONE) * t
        }
    }
}

/// A lobe switch of Mitsuba's principled BSDFs (its `get_flag`): the parameter `name` as a
/// texture, or `None` if it is left out or given as the float 0.
pub(super) fn optional_parameter(o: &Obj, b: &mut dyn BsdfBuilder, name: &str) -> PropResult<Option<Texture>> {
    let off = match o.get(name).map(|p| &p.value) {
        None => true,
        Some(Value::Float(v)) => *v == 0.0,
        Some(_) => false,
    };
    let t = b.texture_of(o, name, Rgb::ZERO, crate::math::spectrum::SpectrumKind::Unbounded)?;
    Ok((!off).then_some(t))
}

impl Principled {
    fn params(&self, ctx: &BsdfContext) -> Params {
        let s = |t: &Option<Texture>| scalar(t, ctx);
        let roughness = ctx.scalar(&self.roughness);
        let alpha = ggx_alpha(roughness, self.anisotropic.as_ref().map(|_| s(&self.anisotropic)));
        let (metallic, spec_trans) = (s(&self.metallic), s(&self.spec_trans));
        Params {
            base: ctx.eval(&self.base_color),
            roughness,
            metallic,
            clearcoat: s(&self.clearcoat),
            alpha,
            brdf: (1.0 - metallic) * (1.0 - spec_trans),
            bsdf: (1.0 - metallic) * spec_trans,
        }
    }

    fn clearcoat_distribution(&self, ctx: &BsdfContext) -> Gtr1 {
        Gtr1 { alpha: lerp(0.1, 0.001, ctx.scalar(&self.clearcoat_gloss)) }
    }

    /// The lobe probabilities (diffuse, clearcoat, specular transmission, specular reflection)
    /// for the dielectric Fresnel term `f`, normalized, as Mitsuba chooses lobes.
    fn lobe_probabilities(&self, p: &Params, f: f32, front: bool) -> [f32; 4] {
        let [spec_rate, cc_rate, diff_rate] = self.rates;
        // Lobes that are off have weight 0 (their parameters read 0).
        let (diffuse, clearcoat, trans, reflect) = if front {
            (
                p.brdf * diff_rate,
                0.25 * p.clearcoat * cc_rate,
                spec_rate * p.bsdf * (1.0 - f),
                spec_rate * (1.0 - p.bsdf * (1.0 - f)),
            )
        } else {
            (0.0, 0.0, if self.spec_trans.is_some() { 1.0 - f } else { 0.0 }, f)
        };
        let total = diffuse + clearcoat + trans + reflect;
        [diffuse / total, clearcoat / total, trans / total, reflect / total]
    }

    /// The generalized half vector of `(wo, wi)` (toward +z) and whether it is a reflection.
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let reflect = wo.z * wi.z > 0.0;
        let eta_path = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let wh = (wo + wi * if reflect { 1.0 } else { eta_path }).normalize_or_zero();
        (if wh.z < 0.0 { -wh } else { wh }, eta_path)
    }

    /// `f(wo, wi) |cos θᵢ|`. (The pair is read where `pair` wrote it, by reference.)
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        let p = self.params(ctx);
        self.pair(&p, wo, wi).as_ref().map_or(Rgb::ZERO, |q| self.eval_pair(ctx, &p, q, wo, wi))
    }

    /// Density of [`Principled::sample`] choosing `wi`.
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        let p = self.params(ctx);
        self.pair(&p, wo, wi).as_ref().map_or(0.0, |q| self.pdf_pair(ctx, &p, q, wo, wi))
    }

    /// [`Principled::eval`] and [`Principled::pdf`] at once (the same bits), sharing the
    /// parameters, the half vector, the Fresnel term, `D` and `G1(wo)`.
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        let p = self.params(ctx);
        self.pair(&p, wo, wi)
            .as_ref()
            .map_or((Rgb::ZERO, 0.0), |q| (self.eval_pair(ctx, &p, q, wo, wi), self.pdf_pair(ctx, &p, q, wo, wi)))
    }

    /// What the value and the density of `(wo, wi)` share; `None` where both are 0 (`wo` in
    /// the surface's plane, or no half vector).
    fn pair(&self, p: &Params, wo: Vec3, wi: Vec3) -> Option<Pair> {
        let cos_o = wo.z;
        if cos_o == 0.0 {
            return None;
        }
        let (wh, eta_path) = self.half_vector(wo, wi);
        if wh == Vec3::ZERO {
            return None;
        }
        let dist = Microfacet::new(MicrofacetType::Ggx, p.alpha.0, p.alpha.1);
        let (f_diel, ..) = fresnel_dielectric(wo.dot(wh), self.eta);
        Some(Pair {
            cos_o,
            reflect: cos_o * wi.z > 0.0,
            refract: cos_o * wi.z < 0.0,
            wh,
            eta_path,
            dist,
            f_diel,
            refl_ok: compatible(wh, wo, wi, cos_o, true),
            refr_ok: compatible(wh, wo, wi, cos_o, false),
            d: dist.d(wh),
            g1_o: dist.g1(wo, wh),
        })
    }

    /// [`Principled::eval`] from the parameters and the pair's shared terms.
    fn eval_pair(&self, ctx: &BsdfContext, p: &Params, q: &Pair, wo: Vec3, wi: Vec3) -> Rgb {
        let (brdf, bsdf) = (p.brdf, p.bsdf);
        let (cos_o, cos_i, wh, f_diel, d) = (q.cos_o, wi.z, q.wh, q.f_diel, q.d);
        let front = cos_o > 0.0;
        let g = q.g1_o * q.dist.g1(wi, wh);
        let mut value = Rgb::ZERO;
        if q.reflect && q.refl_ok && f_diel > 0.0 {
            let spec_tint = scalar(&self.spec_tint, ctx);
            let lum = if self.spec_tint.is_some() { luminance(p.base) } else { 1.0 };
            let f = if front {
                let cos = wo.dot(wh);
                let mut schlick_part = Rgb::ZERO;
                if self.metallic.is_some() {
                    schlick_part += schlick(p.base, cos, self.eta) * p.metallic;
                }
                if self.spec_tint.is_some() {
                    let tint = if lum > 0.0 { p.base / lum } else { Rgb::ONE };
                    let eta_it = if cos >= 0.0 { self.eta } else { 1.0 / self.eta };
                    let r0 = ((eta_it - 1.0) / (eta_it + 1.0)).powi(2);
                    schlick_part += schlick(tint * r0, cos, self.eta) * ((1.0 - p.metallic) * spec_tint);
                }
                Rgb::splat((1.0 - p.metallic) * (1.0 - spec_tint) * f_diel) + schlick_part
            } else {
                Rgb::splat(bsdf * f_diel)
            };
            value += f * (d * g / (4.0 * cos_o.abs()));
        }
        if bsdf > 0.0 && q.refract && q.refr_ok && f_diel < 1.0 {
            // Radiance transport: the solid angle compresses by 1/η² across the interface.
            let eta_path = q.eta_path;
            let scale = 1.0 / (eta_path * eta_path);
            let (ow, iw) = (wo.dot(wh), wi.dot(wh));
            let denom = ow + eta_path * iw;
            let t = (scale * (1.0 - f_diel) * d * g * eta_path * eta_path * ow * iw / (cos_o * denom * denom)).abs();
            value += Rgb::new(p.base.x.max(0.0).sqrt(), p.base.y.max(0.0).sqrt(), p.base.z.max(0.0).sqrt()) * (bsdf * t);
        }
        if p.clearcoat > 0.0 && q.reflect && q.refl_ok && front {
            let f_cc = schlick(Rgb::splat(0.04), wo.dot(wh), self.eta).x;
            let d_cc = self.clearcoat_distribution(ctx).d(wh);
            let g_cc = smith_ggx1(wo, wh, 0.25) * smith_ggx1(wi, wh, 0.25);
            value += Rgb::splat(p.clearcoat * 0.25 * f_cc * d_cc * g_cc * cos_i.abs());
        }
        if brdf > 0.0 && q.reflect && front {
            let cos_d = wh.dot(wi);
            let flatness = self.flatness.as_ref().map(|_| scalar(&self.flatness, ctx));
            let lobe = disney_diffuse(p.roughness, cos_i.abs(), cos_o.abs(), cos_d, flatness);
            value += p.base * (brdf * cos_i.abs() * INV_PI * lobe);
            let sheen = scalar(&self.sheen, ctx);
            if sheen > 0.0 && 1.0 - p.metallic > 0.0 {
                let tint = sheen_color(p.base, self.sheen_tint.as_ref().map(|_| scalar(&self.sheen_tint, ctx)));
                value += tint * (sheen * (1.0 - p.metallic) * schlick_weight(cos_d.abs()) * cos_i.abs());
            }
        }
        if value.is_finite() {
            value
        } else {
            Rgb::ZERO
        }
    }

    /// [`Principled::pdf`] from the parameters and the pair's shared terms.
    fn pdf_pair(&self, ctx: &BsdfContext, p: &Params, q: &Pair, wo: Vec3, wi: Vec3) -> f32 {
        let (cos_o, wh, eta_path) = (q.cos_o, q.wh, q.eta_path);
        let front = cos_o > 0.0;
        // Seen from inside without transmission nothing is sampled (Mitsuba's pdf is not zero
        // there, but its value is: the density differs only where the BSDF vanishes).
        if !front && p.bsdf <= 0.0 {
            return 0.0;
        }
        let [p_diffuse, p_clearcoat, p_trans, p_reflect] = self.lobe_probabilities(p, q.f_diel, front);
        let (ow, iw) = (wo.dot(wh), wi.dot(wh));
        let jacobian = if self.spec_trans.is_some() && !q.reflect {
            (eta_path * eta_path * iw / (ow + eta_path * iw).powi(2)).abs()
        } else {
            (1.0 / (4.0 * iw)).abs()
        };
        // The visible-normal density seen from `wo` on the front; G1 is even in `wo`.
        let wo_up = if cos_o < 0.0 { -wo } else { wo };
        let pdf_wh = || q.dist.pdf_given(wo_up, wh, q.d, q.g1_o);
        let mut pdf = 0.0;
        let refl_ok = q.reflect && q.refl_ok;
        if refl_ok {
            pdf += p_reflect * pdf_wh() * jacobian;
        }
        if q.reflect {
            pdf += p_diffuse * wi.z * INV_PI;
        }
        if self.spec_trans.is_some() && q.refract && q.refr_ok {
            pdf += p_trans * pdf_wh() * jacobian;
        }
        if self.clearcoat.is_some() && refl_ok {
            pdf += p_clearcoat * self.clearcoat_distribution(ctx).pdf(wh) * jacobian;
        }
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// A lobe chosen by `u1` with Mitsuba's probabilities, then its direction from `u`.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        let cos_o = wo.z;
        if cos_o == 0.0 {
            return None;
        }
        let p = self.params(ctx);
        let front = cos_o > 0.0;
        if !(front || p.bsdf > 0.0) {
            return None;
        }
        let dist = Microfacet::new(MicrofacetType::Ggx, p.alpha.0, p.alpha.1);
        let wo_up = if cos_o < 0.0 { -wo } else { wo };
        let m = dist.sample(wo_up, u).value;
        let (f_diel, cos_t, eta_it, eta_ti) = fresnel_dielectric(wo.dot(m), self.eta);
        let [p_diffuse, p_clearcoat, p_trans, _] = self.lobe_probabilities(&p, f_diel, front);
        let mut eta = 1.0;
        let wi = if u1 < p_diffuse {
            let wi = crate::sampling::sample_cosine_hemisphere_malley(u).value;
            (cos_o * wi.z > 0.0).then_some(wi)?
        } else if u1 < p_diffuse + p_clearcoat {
            let m_cc = self.clearcoat_distribution(ctx).sample(u);
            let wi = reflect_about(wo, m_cc);
            (compatible(m_cc, wo, wi, cos_o, true) && cos_o * wi.z > 0.0).then_some(wi)?
        } else if u1 < p_diffuse + p_clearcoat + p_trans {
            let wi = refract_about(wo, m, cos_t, eta_ti);
            eta = eta_it;
            (compatible(m, wo, wi, cos_o, false) && cos_o * wi.z < 0.0).then_some(wi)?
        } else {
            let wi = reflect_about(wo, m);
            (compatible(m, wo, wi, cos_o, true) && cos_o * wi.z > 0.0).then_some(wi)?
        };
        // Read in place (see `eval`): moved out of the `Option` right after `pair` wrote it,
        // it would be copied by wide loads that wait for `pair`'s stores to reach the cache.
        let q = self.pair(&p, wo, wi);
        let q = q.as_ref()?;
        let pdf = self.pdf_pair(ctx, &p, q, wo, wi);
        if pdf <= 0.0 {
            return None;
        }
        let weight = self.eval_pair(ctx, &p, q, wo, wi) / pdf;
        weight.is_finite().then_some(BsdfSample { wi, pdf, weight, delta: false, null: false, eta })
    }

    /// Every texture of its parameters.
    pub fn textures(&self) -> Vec<&Texture> {
        let mut v = vec![&self.base_color, &self.roughness, &self.clearcoat_gloss];
        for t in [
            &self.anisotropic,
            &self.spec_trans,
            &self.sheen,
            &self.sheen_tint,
            &self.flatness,
            &self.spec_tint,
            &self.metallic,
            &self.clearcoat,
        ] {
            v.extend(t.iter());
        }
        v
    }

    /// Mitsuba's `principled`: `base_color` (0.5), `roughness` (0.5), `anisotropic`,
    /// `spec_trans`, `sheen`, `sheen_tint`, `flatness`, `spec_tint`, `metallic`, `clearcoat`,
    /// `clearcoat_gloss` (all 0 and texturable; a lobe whose weight is left out, or given as the
    /// float 0, is off), `eta` or `specular` (0.5; not both), and the sampling rates
    /// `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate` (1).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let unbounded = crate::math::spectrum::SpectrumKind::Unbounded;
        let optional = |b: &mut dyn BsdfBuilder, name: &str| optional_parameter(o, b, name);
        let anisotropic = optional(b, "anisotropic")?;
        let spec_trans = optional(b, "spec_trans")?;
        let sheen = optional(b, "sheen")?;
        let sheen_tint = optional(b, "sheen_tint")?;
        let flatness = optional(b, "flatness")?;
        let spec_tint = optional(b, "spec_tint")?;
        let metallic = optional(b, "metallic")?;
        let clearcoat = optional(b, "clearcoat")?;
        let eta = match (o.has("eta"), o.has("specular")) {
            (true, true) => return Err(o.error_at("eta", "give either 'eta' or 'specular', not both (as Mitsuba)")),
            (true, false) => {
                let eta = o.float_checked("eta", 1.5, |e| e > 0.0 && e.is_finite(), "positive")?;
                if spec_trans.is_some() && eta == 1.0 {
                    1.001
                } else {
                    eta
                }
            }
            (false, _) => {
                let mut specular = o.float_checked("specular", 0.5, |s| (0.0..12.5).contains(&s), "in [0, 12.5)")?;
                if spec_trans.is_some() && specular == 0.0 {
                    specular = 1e-3;
                }
                2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
            }
        };
        let rate = |n| o.float_checked(n, 1.0, |r| r >= 0.0 && r.is_finite(), "≥ 0");
        let rates =
            [rate("main_specular_sampling_rate")?, rate("clearcoat_sampling_rate")?, rate("diffuse_reflectance_sampling_rate")?];
        Ok(Bsdf::Principled(Box::new(Principled {
            base_color: b.texture(o, "base_color", Rgb::splat(0.5))?,
            roughness: b.texture_of(o, "roughness", Rgb::splat(0.5), unbounded)?,
            clearcoat_gloss: b.texture_of(o, "clearcoat_gloss", Rgb::ZERO, unbounded)?,
            anisotropic,
            spec_trans,
            sheen,
            sheen_tint,
            flatness,
            spec_tint,
            metallic,
            clearcoat,
            eta,
            rates,
        })))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::tests::{assert_matches_mitsuba, MitsubaRow};

    fn constant(v: f32) -> Option<Texture> {
        Some(Rgb::splat(v).into())
    }

    /// The three configurations the reference values below were computed with.
    fn config(k: char) -> Principled {
        let specular_eta = |s: f32| 2.0 / (1.0 - (0.08 * s).sqrt()) - 1.0;
        let base = Principled {
            base_color: Rgb::splat(0.5).into(),
            roughness: Rgb::splat(0.5).into(),
            anisotropic: None,
            spec_trans: None,
            sheen: None,
            sheen_tint: None,
            flatness: None,
            spec_tint: None,
            metallic: None,
            clearcoat: None,
            clearcoat_gloss: Rgb::ZERO.into(),
            eta: specular_eta(0.5),
            rates: [1.0; 3],
        };
        match k {
            'A' => Principled {
                base_color: Rgb::new(0.8, 0.3, 0.2).into(),
                roughness: Rgb::splat(0.3).into(),
                metallic: constant(0.4),
                eta: specular_eta(0.6),
                spec_tint: constant(0.3),
                sheen: constant(0.5),
                sheen_tint: constant(0.4),
                clearcoat: constant(0.7),
                clearcoat_gloss: Rgb::splat(0.5).into(),
                anisotropic: constant(0.5),
                ..base
            },
            'B' => Principled {
                base_color: Rgb::new(0.9, 0.9, 0.7).into(),
                roughness: Rgb::splat(0.2).into(),
                spec_trans: constant(0.6),
                eta: 1.4,
                ..base
            },
            _ => Principled {
                base_color: Rgb::new(0.5, 0.6, 0.7).into(),
                roughness: Rgb::splat(0.7).into(),
                flatness: constant(0.6),
                ..base
            },
        }
    }

    /// `eval` and `pdf` equal Mitsuba 3.9.1's for the same parameters and directions (its
    /// `si.wi` is our `wo`): all lobes, anisotropy, transmission from both sides, flatness.
    #[test]
    fn matches_mitsuba() {
        let rows: &[MitsubaRow] = &[
        ('A', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.1491884, 0.05899792, 0.04095982], 0.1307671),
        ('A', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.03278917, 0.012387, 0.008306559], 0.02554113),
        ('A', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, -0.9323806], [0.0, 0.0, 0.0], 0.0),
        ('A', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.2285522, 0.09208096, 0.06478671], 0.2396849),
        ('A', [0.2009163, -0.1004581, -0.9744439], [-0.4000088, 0.3000066, 0.8660191], [0.0, 0.0, 0.0], 0.0),
        ('A', [0.2009163, -0.1004581, -0.9744439], [0.7419985, 0.6359987, 0.2119996], [0.0, 0.0, 0.0], 0.0),
        ('A', [0.2009163, -0.1004581, -0.9744439], [-0.3007679, -0.200512, -0.9323806], [0.0, 0.0, 0.0], 0.2316994),
        ('A', [0.2009163, -0.1004581, -0.9744439], [0.1003721, 0.05018603, 0.9936835], [0.0, 0.0, 0.0], 0.0),
        ('B', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.09990081, 0.09990081, 0.07784797], 0.08580185),
        ('B', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.0229002, 0.0229002, 0.01781386], 0.01940236),
        ('B', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, -0.9323806], [0.1083223, 0.1083223, 0.0955313], 0.1598641),
        ('B', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.1149802, 0.1149802, 0.08967623], 0.1022889),
        ('B', [0.2009163, -0.1004581, -0.9744439], [-0.4000088, 0.3000066, 0.8660191], [0.05239661, 0.05239661, 0.04620947], 0.04697129),
        ('B', [0.2009163, -0.1004581, -0.9744439], [0.7419985, 0.6359987, 0.2119996], [0.0, 0.0, 0.0], 0.0),
        ('B', [0.2009163, -0.1004581, -0.9744439], [-0.3007679, -0.200512, -0.9323806], [0.002713408, 0.002713408, 0.002713408], 0.004522618),
        ('B', [0.2009163, -0.1004581, -0.9744439], [0.1003721, 0.05018603, 0.9936835], [0.003501232, 0.003501232, 0.003087797], 0.003138301),
        ('C', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.1217365, 0.1442595, 0.1667824], 0.2531789),
        ('C', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.03773365, 0.045071, 0.05240835], 0.05579122),
        ('C', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, -0.9323806], [0.0, 0.0, 0.0], 0.0),
        ('C', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.1349566, 0.1599251, 0.1848936], 0.2846563),
        ('C', [0.2009163, -0.1004581, -0.9744439], [-0.4000088, 0.3000066, 0.8660191], [0.0, 0.0, 0.0], 0.0),
        ('C', [0.2009163, -0.1004581, -0.9744439], [0.7419985, 0.6359987, 0.2119996], [0.0, 0.0, 0.0], 0.0),
        ('C', [0.2009163, -0.1004581, -0.9744439], [-0.3007679, -0.200512, -0.9323806], [0.0, 0.0, 0.0], 0.2879162),
        ('C', [0.2009163, -0.1004581, -0.9744439], [0.1003721, 0.05018603, 0.9936835], [0.0, 0.0, 0.0], 0.0),
        ];
        assert_matches_mitsuba(rows, |k| Bsdf::Principled(Box::new(config(k))), |k, wo, pdf| {
            // Mitsuba's pdf from inside a material that does not transmit is not zero, where
            // the BSDF is (see `pdf`).
            if wo.z < 0.0 && config(k).spec_trans.is_none() {
                0.0
            } else {
                pdf
            }
        });
    }
}
