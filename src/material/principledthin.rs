//! Mitsuba's `principledthin`: the thin-surface variant of the Disney BSDF (Burley 2015) as
//! Mitsuba 3.9 implements it, for leaves, paper and cloth: a two-sided sheet with no interior.
//!
//! Seen from either side alike (directions are mirrored to the front first). Lobes:
//! - specular reflection, GGX of `roughness` (and `anisotropic`), weight `spec_trans`, Fresnel
//!   of the sheet's `eta` blended toward a tinted Schlick term by `spec_tint`;
//! - specular transmission straight through (a reflection mirrored to the other side, no
//!   bending), GGX of the roughness scaled by `0.65 eta − 0.35` (Burley 2015, Fig. 15), weight
//!   `spec_trans (1 − F)`, tinted by `base_color`;
//! - diffuse reflection with retro-reflection, fake subsurface (`flatness`) and sheen, weight
//!   `(1 − spec_trans)(1 − diff_trans / 2)`;
//! - Lambertian transmission, weight `(1 − spec_trans) diff_trans / 2` (`diff_trans` in [0, 2]).
//!
//! Sampled as Mitsuba samples it: a lobe by the probabilities `spec_trans / 2` (times each
//! specular sampling rate, twice), `(1 − spec_trans)(1 − d)` and `(1 − spec_trans) d` (times the
//! diffuse rates), `d = diff_trans / 2`, then GGX visible normals or cosine hemispheres.

use super::fresnel::{fresnel_dielectric, reflect_about};
use super::microfacet::{Microfacet, MicrofacetType};
use super::principled::{
    compatible, disney_diffuse, ggx_alpha, optional_parameter, scalar, schlick, schlick_weight, sheen_color,
};
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{luminance, Rgb, Vec2, Vec3, INV_PI};
use crate::props::{Obj, Result as PropResult};
use crate::texture::Texture;

/// Mitsuba's thin principled BSDF. Optional parameters are `None` where the scene leaves them
/// out (or gives the float 0): their lobes are off, as Mitsuba switches them off.
#[derive(Clone, Debug)]
pub struct PrincipledThin {
    /// Base colour (RGB).
    pub base_color: Texture,
    /// Roughness in [0, 1].
    pub roughness: Texture,
    /// Anisotropy in [0, 1].
    pub anisotropic: Option<Texture>,
    /// Weight of the specular lobes.
    pub spec_trans: Option<Texture>,
    /// Diffuse transmission in [0, 2].
    pub diff_trans: Option<Texture>,
    /// Weight of the sheen.
    pub sheen: Option<Texture>,
    /// Tint of the sheen toward the base colour.
    pub sheen_tint: Option<Texture>,
    /// Blend of the diffuse toward fake subsurface scattering.
    pub flatness: Option<Texture>,
    /// Tint of the specular reflection toward the base colour.
    pub spec_tint: Option<Texture>,
    /// The sheet's index of refraction (1.5).
    pub eta: Texture,
    /// Sampling rates: specular reflection, specular transmission, diffuse reflection, diffuse
    /// transmission.
    pub rates: [f32; 4],
}

/// The parameters at one shading point (off ones read 0).
struct Params {
    base: Rgb,
    roughness: f32,
    anisotropic: Option<f32>,
    spec_trans: f32,
    /// `diff_trans / 2`.
    diff_trans: f32,
    eta: f32,
}

impl PrincipledThin {
    fn params(&self, ctx: &BsdfContext) -> Params {
        Params {
            base: ctx.eval(&self.base_color),
            roughness: ctx.scalar(&self.roughness),
            anisotropic: self.anisotropic.as_ref().map(|_| scalar(&self.anisotropic, ctx)),
            spec_trans: scalar(&self.spec_trans, ctx),
            diff_trans: scalar(&self.diff_trans, ctx) / 2.0,
            eta: ctx.scalar(&self.eta),
        }
    }

    /// GGX of the specular reflection and of the (roughness-scaled) transmission.
    fn distributions(p: &Params) -> (Microfacet, Microfacet) {
        let (au, av) = ggx_alpha(p.roughness, p.anisotropic);
        let (tu, tv) = ggx_alpha((0.65 * p.eta - 0.35) * p.roughness, p.anisotropic);
        (Microfacet::new(MicrofacetType::Ggx, au, av), Microfacet::new(MicrofacetType::Ggx, tu, tv))
    }

    /// Lobe probabilities: specular reflection, specular transmission, diffuse reflection,
    /// diffuse transmission (normalized).
    fn lobe_probabilities(&self, p: &Params) -> [f32; 4] {
        let [r_sr, r_st, r_dr, r_dt] = self.rates;
        let probs = [
            p.spec_trans * r_sr / 2.0,
            p.spec_trans * r_st / 2.0,
            r_dr * (1.0 - p.spec_trans) * (1.0 - p.diff_trans),
            r_dt * (1.0 - p.spec_trans) * p.diff_trans,
        ];
        let total: f32 = probs.iter().sum();
        probs.map(|x| x / total)
    }

    /// `wo`, `wi` mirrored so that `wo` is on the front, and the half vector of `wo` and `wi`
    /// reflected to the front.
    fn frontal(wo: Vec3, wi: Vec3) -> (Vec3, Vec3, Vec3) {
        let s = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let (wo, wi) = (wo * s, wi * s);
        let wi_r = Vec3::new(wi.x, wi.y, wi.z.abs());
        (wo, wi, (wo + wi_r).normalize_or_zero())
    }

    /// `f(wo, wi) |cos θᵢ|`.
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        self.eval_with(ctx, &self.params(ctx), wo, wi)
    }

    /// [`PrincipledThin::eval`] with the parameters evaluated at `ctx` already.
    fn eval_with(&self, ctx: &BsdfContext, p: &Params, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z == 0.0 {
            return Rgb::ZERO;
        }
        let base = p.base;
        let (wo, wi, wh) = PrincipledThin::frontal(wo, wi);
        let (cos_o, cos_i) = (wo.z, wi.z);
        let (reflect, refract) = (cos_i > 0.0, cos_i < 0.0);
        let mut value = Rgb::ZERO;
        if p.spec_trans > 0.0 && wh != Vec3::ZERO {
            let (f_diel, ..) = fresnel_dielectric(wo.dot(wh), p.eta);
            let (spec, trans) = PrincipledThin::distributions(p);
            if reflect && compatible(wh, wo, wi, cos_o, true) {
                let spec_tint = scalar(&self.spec_tint, ctx);
                let f_schlick = if self.spec_tint.is_some() {
                    let lum = luminance(base);
                    let tint = if lum > 0.0 { base / lum } else { Rgb::ONE };
                    let r0 = ((p.eta - 1.0) / (p.eta + 1.0)).powi(2);
                    schlick(tint * r0, wo.dot(wh), p.eta)
                } else {
                    Rgb::ZERO
                };
                let f = Rgb::splat(f_diel) * (1.0 - spec_tint) + f_schlick * spec_tint;
                value += f * (p.spec_trans * spec.d(wh) * spec.g(wo, wi, wh) / (4.0 * cos_o));
            }
            if refract && compatible(wh, wo, wi, cos_o, false) {
                let t = p.spec_trans * (1.0 - f_diel) * trans.d(wh) * trans.g(wo, wi, wh) / (4.0 * cos_o);
                value += base * t;
            }
        }
        if reflect && p.spec_trans < 1.0 && p.diff_trans < 1.0 {
            let cos_d = wh.dot(wi);
            let flatness = self.flatness.as_ref().map(|_| scalar(&self.flatness, ctx));
            let lobe = disney_diffuse(p.roughness, cos_i.abs(), cos_o.abs(), cos_d, flatness);
            let weight = (1.0 - p.spec_trans) * (1.0 - p.diff_trans);
            value += base * (weight * cos_i * INV_PI * lobe);
            let sheen = scalar(&self.sheen, ctx);
            if sheen > 0.0 {
                let tint = sheen_color(base, self.sheen_tint.as_ref().map(|_| scalar(&self.sheen_tint, ctx)));
                value += tint * (sheen * weight * schlick_weight(cos_d.abs()) * cos_i.abs());
            }
        }
        if refract && p.spec_trans < 1.0 && p.diff_trans > 0.0 {
            value += base * ((1.0 - p.spec_trans) * p.diff_trans * INV_PI * cos_i.abs());
        }
        if value.is_finite() {
            value
        } else {
            Rgb::ZERO
        }
    }

    /// Density of [`PrincipledThin::sample`] choosing `wi`.
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_with(&self.params(ctx), wo, wi)
    }

    /// [`PrincipledThin::eval`] and [`PrincipledThin::pdf`] at once (the same bits), with the
    /// parameters' textures looked up once.
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        let p = self.params(ctx);
        (self.eval_with(ctx, &p, wo, wi), self.pdf_with(&p, wo, wi))
    }

    /// [`PrincipledThin::pdf`] with the parameters evaluated already.
    fn pdf_with(&self, p: &Params, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        let [p_sr, p_st, p_dr, p_dt] = self.lobe_probabilities(p);
        let (wo, wi, wh) = PrincipledThin::frontal(wo, wi);
        let (reflect, refract) = (wi.z > 0.0, wi.z < 0.0);
        let mut pdf = 0.0;
        if self.spec_trans.is_some() && wh != Vec3::ZERO {
            let wi_r = Vec3::new(wi.x, wi.y, wi.z.abs());
            let jacobian = (1.0 / (4.0 * wi_r.dot(wh))).abs();
            let (spec, trans) = PrincipledThin::distributions(p);
            if reflect && compatible(wh, wo, wi, wo.z, true) {
                pdf += p_sr * spec.pdf(wo, wh) * jacobian;
            }
            if refract && compatible(wh, wo, wi, wo.z, false) {
                pdf += p_st * trans.pdf(wo, wh) * jacobian;
            }
        }
        if reflect {
            pdf += p_dr * wi.z * INV_PI;
        }
        if self.diff_trans.is_some() && refract {
            pdf += p_dt * -wi.z * INV_PI;
        }
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// A lobe chosen by `u1` with Mitsuba's probabilities, then its direction from `u`.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let p = self.params(ctx);
        let [p_sr, p_st, p_dr, _] = self.lobe_probabilities(&p);
        let side = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let wo_f = wo * side;
        let wi_f = if u1 < p_sr {
            let m = PrincipledThin::distributions(&p).0.sample(wo_f, u).value;
            let wi = reflect_about(wo_f, m);
            (compatible(m, wo_f, wi, wo_f.z, true) && wi.z > 0.0).then_some(wi)?
        } else if u1 < p_sr + p_st {
            let m = PrincipledThin::distributions(&p).1.sample(wo_f, u).value;
            let r = reflect_about(wo_f, m);
            let wi = Vec3::new(r.x, r.y, -r.z);
            (compatible(m, wo_f, wi, wo_f.z, false) && wi.z < 0.0).then_some(wi)?
        } else if u1 < p_sr + p_st + p_dr {
            crate::sampling::sample_cosine_hemisphere_malley(u).value
        } else if self.diff_trans.is_some() {
            -crate::sampling::sample_cosine_hemisphere_malley(u).value
        } else {
            return None;
        };
        let wi = wi_f * side;
        let pdf = self.pdf_with(&p, wo, wi);
        if pdf <= 0.0 {
            return None;
        }
        let weight = self.eval_with(ctx, &p, wo, wi) / pdf;
        weight.is_finite().then_some(BsdfSample { wi, pdf, weight, delta: false, null: false, eta: 1.0 })
    }

    /// Every texture of its parameters.
    pub fn textures(&self) -> Vec<&Texture> {
        let mut v = vec![&self.base_color, &self.roughness, &self.eta];
        for t in
            [&self.anisotropic, &self.spec_trans, &self.diff_trans, &self.sheen, &self.sheen_tint, &self.flatness, &self.spec_tint]
        {
            v.extend(t.iter());
        }
        v
    }

    /// Mitsuba's `principledthin`: `base_color` (0.5), `roughness` (0.5), `eta` (1.5),
    /// `anisotropic`, `spec_trans`, `diff_trans` (in [0, 2]), `sheen`, `sheen_tint`, `flatness`,
    /// `spec_tint` (all 0 and texturable; a lobe whose weight is left out, or given as the float
    /// 0, is off), and the sampling rates `specular_reflectance_sampling_rate`,
    /// `specular_transmittance_sampling_rate`, `diffuse_reflectance_sampling_rate`,
    /// `diffuse_transmittance_sampling_rate` (1).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let unbounded = crate::math::spectrum::SpectrumKind::Unbounded;
        let rate = |n| o.float_checked(n, 1.0, |r| r >= 0.0 && r.is_finite(), "≥ 0");
        let rates = [
            rate("specular_reflectance_sampling_rate")?,
            rate("specular_transmittance_sampling_rate")?,
            rate("diffuse_reflectance_sampling_rate")?,
            rate("diffuse_transmittance_sampling_rate")?,
        ];
        Ok(Bsdf::PrincipledThin(Box::new(PrincipledThin {
            base_color: b.texture(o, "base_color", Rgb::splat(0.5))?,
            roughness: b.texture_of(o, "roughness", Rgb::splat(0.5), unbounded)?,
            eta: b.texture_of(o, "eta", Rgb::splat(1.5), unbounded)?,
            anisotropic: optional_parameter(o, b, "anisotropic")?,
            spec_trans: optional_parameter(o, b, "spec_trans")?,
            diff_trans: optional_parameter(o, b, "diff_trans")?,
            sheen: optional_parameter(o, b, "sheen")?,
            sheen_tint: optional_parameter(o, b, "sheen_tint")?,
            flatness: optional_parameter(o, b, "flatness")?,
            spec_tint: optional_parameter(o, b, "spec_tint")?,
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

    fn config(k: char) -> PrincipledThin {
        let base = PrincipledThin {
            base_color: Rgb::splat(0.5).into(),
            roughness: Rgb::splat(0.5).into(),
            anisotropic: None,
            spec_trans: None,
            diff_trans: None,
            sheen: None,
            sheen_tint: None,
            flatness: None,
            spec_tint: None,
            eta: Rgb::splat(1.5).into(),
            rates: [1.0; 4],
        };
        match k {
            'A' => PrincipledThin {
                base_color: Rgb::new(0.7, 0.3, 0.2).into(),
                roughness: Rgb::splat(0.3).into(),
                spec_trans: constant(0.6),
                diff_trans: constant(0.8),
                eta: Rgb::splat(1.33).into(),
                spec_tint: constant(0.4),
                anisotropic: constant(0.5),
                ..base
            },
            'B' => PrincipledThin {
                base_color: Rgb::new(0.4, 0.7, 0.3).into(),
                roughness: Rgb::splat(0.6).into(),
                sheen: constant(0.7),
                sheen_tint: constant(0.5),
                flatness: constant(0.4),
                diff_trans: constant(1.2),
                ..base
            },
            _ => PrincipledThin { base_color: Rgb::new(0.5, 0.5, 0.8).into(), roughness: Rgb::splat(0.4).into(), ..base },
        }
    }

    /// `eval` and `pdf` equal Mitsuba 3.9.1's for the same parameters and directions (its
    /// `si.wi` is our `wo`), from both sides of the sheet.
    #[test]
    fn matches_mitsuba() {
        let rows: &[MitsubaRow] = &[
            ('A', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.04688761, 0.02024289, 0.01358171], 0.07682913),
            ('A', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.01124391, 0.00482647, 0.003222109], 0.01675749),
            ('A', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, -0.9323806], [61.90474, 26.5306, 17.68707], 45.15805),
            ('A', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.05632186, 0.02495195, 0.01710947], 0.1350841),
            ('A', [0.3007679, 0.200512, 0.9323806], [0.404061, -0.1010153, -0.9091373], [0.03593585, 0.01540108, 0.01026739], 0.04887114),
            ('A', [0.2009163, -0.1004581, -0.9744439], [-0.4000088, 0.3000066, 0.8660191], [0.05568069, 0.02386316, 0.01590877], 0.06219324),
            ('A', [0.2009163, -0.1004581, -0.9744439], [0.7419985, 0.6359987, 0.2119996], [0.007557934, 0.003239115, 0.00215941], 0.01079705),
            ('A', [0.2009163, -0.1004581, -0.9744439], [-0.3007679, -0.200512, -0.9323806], [0.05360245, 0.02393067, 0.01651272], 0.1407385),
            ('A', [0.2009163, -0.1004581, -0.9744439], [0.1003721, 0.05018603, 0.9936835], [0.1287341, 0.05517176, 0.03678117], 0.1186214),
            ('A', [0.2009163, -0.1004581, -0.9744439], [0.404061, -0.1010153, -0.9091373], [0.05042401, 0.02207227, 0.01498433], 0.1030619),
            ('B', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.03872701, 0.06777217, 0.0290453], 0.110265),
            ('B', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.01171296, 0.02049712, 0.008784904], 0.02699262),
            ('B', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, -0.9323806], [0.07122863, 0.1246501, 0.05342147], 0.1780716),
            ('B', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.0435024, 0.07612919, 0.0326268], 0.1265197),
            ('B', [0.3007679, 0.200512, 0.9323806], [0.404061, -0.1010153, -0.9091373], [0.06945297, 0.1215427, 0.05208973], 0.1736324),
            ('B', [0.2009163, -0.1004581, -0.9744439], [-0.4000088, 0.3000066, 0.8660191], [0.06615898, 0.1157782, 0.04961924], 0.1653975),
            ('B', [0.2009163, -0.1004581, -0.9744439], [0.7419985, 0.6359987, 0.2119996], [0.01619557, 0.02834225, 0.01214668], 0.04048894),
            ('B', [0.2009163, -0.1004581, -0.9744439], [-0.3007679, -0.200512, -0.9323806], [0.04094301, 0.07165027, 0.03070726], 0.1187144),
            ('B', [0.2009163, -0.1004581, -0.9744439], [0.1003721, 0.05018603, 0.9936835], [0.07591182, 0.1328457, 0.05693387], 0.1897796),
            ('B', [0.2009163, -0.1004581, -0.9744439], [0.404061, -0.1010153, -0.9091373], [0.04007225, 0.07012644, 0.03005419], 0.1157549),
            ('C', [0.3007679, 0.200512, 0.9323806], [-0.4000088, 0.3000066, 0.8660191], [0.1378324, 0.1378324, 0.2205319], 0.2756624),
            ('C', [0.3007679, 0.200512, 0.9323806], [0.7419985, 0.6359987, 0.2119996], [0.03496424, 0.03496424, 0.05594278], 0.06748156),
            ('C', [0.3007679, 0.200512, 0.9323806], [-0.3007679, -0.200512, -0.9323806], [0.0, 0.0, 0.0], 0.0),
            ('C', [0.3007679, 0.200512, 0.9323806], [0.1003721, 0.05018603, 0.9936835], [0.1581497, 0.1581497, 0.2530395], 0.3162993),
            ('C', [0.3007679, 0.200512, 0.9323806], [0.404061, -0.1010153, -0.9091373], [0.0, 0.0, 0.0], 0.0),
            ('C', [0.2009163, -0.1004581, -0.9744439], [-0.4000088, 0.3000066, 0.8660191], [0.0, 0.0, 0.0], 0.0),
            ('C', [0.2009163, -0.1004581, -0.9744439], [0.7419985, 0.6359987, 0.2119996], [0.0, 0.0, 0.0], 0.0),
            ('C', [0.2009163, -0.1004581, -0.9744439], [-0.3007679, -0.200512, -0.9323806], [0.148393, 0.148393, 0.2374289], 0.296786),
            ('C', [0.2009163, -0.1004581, -0.9744439], [0.1003721, 0.05018603, 0.9936835], [0.0, 0.0, 0.0], 0.0),
            ('C', [0.2009163, -0.1004581, -0.9744439], [0.404061, -0.1010153, -0.9091373], [0.1446939, 0.1446939, 0.2315103], 0.2893874),
        ];
        assert_matches_mitsuba(rows, |k| Bsdf::PrincipledThin(Box::new(config(k))), |_, _, pdf| pdf);
    }
}
