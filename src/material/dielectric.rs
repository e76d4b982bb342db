//! Mitsuba's `dielectric` (smooth glass: Fresnel-weighted choice of specular reflection or
//! refraction) and `thindielectric` (a thin pane: reflection or straight transmission, with the
//! internal reflections summed).
//!
//! Parameters (Mitsuba): `int_ior`, `ext_ior` (numbers or names such as `bk7`, `water`, `air`;
//! defaults 1.5046 and 1.000277), `specular_reflectance`, `specular_transmittance` (RGB scales
//! or textures, default 1). Both are two-sided: the side is told by the sign of `cos θ`.
//!
//! Radiance is not invariant across a refraction: it scales with `η²`. For paths traced from
//! the camera (radiance transport) the refracted weight carries `η_ti²` (Mitsuba's convention),
//! and the sample reports the relative index `eta = η_it` so that Russian roulette can undo the
//! scaling when judging the throughput.

use super::fresnel::eta_from_props;
use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::{Bsdf, BsdfBuilder, BsdfSample};
use super::BsdfContext;
use crate::math::{Rgb, Vec3};
use crate::props::{Obj, Result as PropResult};
use crate::texture::{Texture, TextureSource};

/// Smooth dielectric interface.
#[derive(Clone, Debug)]
pub struct Dielectric {
    /// `int_ior / ext_ior`.
    pub eta: f32,
    /// Reflection scale (texturable).
    pub specular_reflectance: Texture,
    /// Transmission scale (texturable).
    pub specular_transmittance: Texture,
}

impl Dielectric {
    /// Reflection with probability F, refraction otherwise (`u1` chooses).
    #[inline]
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let (f, cos_t, eta_it, eta_ti) = fresnel_dielectric(wo.z, self.eta);
        if u1 <= f {
            let weight = ctx.eval(&self.specular_reflectance);
            Some(BsdfSample { wi: reflect(wo), pdf: f, weight, delta: true, null: false, eta: 1.0 })
        } else {
            let wi = refract(wo, cos_t, eta_ti);
            Some(BsdfSample {
                wi,
                pdf: 1.0 - f,
                weight: ctx.eval(&self.specular_transmittance) * (eta_ti * eta_ti),
                delta: true, null: false,
                eta: eta_it,
            })
        }
    }
}

/// Thin dielectric pane: no refraction offset, internal reflections summed.
#[derive(Clone, Debug)]
pub struct ThinDielectric {
    /// `int_ior / ext_ior`.
    pub eta: f32,
    /// Reflection scale (texturable).
    pub specular_reflectance: Texture,
    /// Transmission scale (texturable).
    pub specular_transmittance: Texture,
}

impl ThinDielectric {
    /// Total reflectance of the pane: `R + T² R / (1 - R²) = 2R / (1 + R)` for a single
    /// interface reflectance R.
    #[inline]
    pub fn reflectance(&self, cos_theta: f32) -> f32 {
        let r = fresnel_dielectric(cos_theta.abs(), self.eta).0;
        if r < 1.0 {
            2.0 * r / (1.0 + r)
        } else {
            1.0
        }
    }

    /// Reflection with probability R, straight transmission (`wi = -wo`) otherwise.
    #[inline]
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        if u1 <= r {
            let weight = ctx.eval(&self.specular_reflectance);
            Some(BsdfSample { wi: reflect(wo), pdf: r, weight, delta: true, null: false, eta: 1.0 })
        } else {
            let weight = ctx.eval(&self.specular_transmittance);
            Some(BsdfSample { wi: -wo, pdf: 1.0 - r, weight, delta: true, null: true, eta: 1.0 })
        }
    }
}

/// The parameters every dielectric plugin reads: `eta` from `int_ior` (BK7, 1.5046) and
/// `ext_ior` (air), `specular_reflectance` and `specular_transmittance` (1, texturable).
pub(crate) fn dielectric_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<(f32, Texture, Texture)> {
    Ok((
        eta_from_props(o, 1.5046)?,
        b.texture(o, "specular_reflectance", Rgb::ONE)?,
        b.texture(o, "specular_transmittance", Rgb::ONE)?,
    ))
}

impl Dielectric {
    /// Mitsuba's `dielectric` : `int_ior` (BK7, 1.5046), `ext_ior` (air), `specular_reflectance`, `specular_transmittance` (1).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let (eta, specular_reflectance, specular_transmittance) = dielectric_props(o, b)?;
        Ok(Bsdf::Dielectric(Dielectric { eta, specular_reflectance, specular_transmittance }))
    }
}

impl ThinDielectric {
    /// Mitsuba's `thindielectric` : `int_ior` (BK7, 1.5046), `ext_ior` (air), `specular_reflectance`, `specular_transmittance` (1).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let (eta, specular_reflectance, specular_transmittance) = dielectric_props(o, b)?;
        Ok(Bsdf::ThinDielectric(ThinDielectric { eta, specular_reflectance, specular_transmittance }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glass_splits_energy_by_fresnel() {
        let d = Dielectric { eta: 1.5, specular_reflectance: Rgb::ONE.into(), specular_transmittance: Rgb::ONE.into() };
        for wo in
            [Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.8, -0.6), Vec3::new(0.99, 0.0, -0.141).normalize()]
        {
            let (f, ..) = fresnel_dielectric(wo.z, 1.5);
            let mut rng = crate::sampling::Pcg32::new(1, 1);
            let n = 100_000;
            let (mut refl, mut energy) = (0usize, 0.0f64);
            for _ in 0..n {
                let s = d.sample(&BsdfContext::default(), wo, rng.next_f32()).unwrap();
                assert!((s.wi.length() - 1.0).abs() < 1e-5);
                if s.wi.z * wo.z > 0.0 {
                    refl += 1;
                    assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
                    energy += s.weight.x as f64;
                } else {
                    // Undo the radiance scaling: importance is conserved.
                    energy += (s.weight.x * s.eta * s.eta) as f64;
                    let sin_o = wo.x.hypot(wo.y);
                    let sin_i = s.wi.x.hypot(s.wi.y);
                    let (n_o, n_i) = if wo.z > 0.0 { (1.0, 1.5) } else { (1.5, 1.0) };
                    assert!((n_o * sin_o - n_i * sin_i).abs() < 1e-5, "Snell");
                }
            }
            let frac = refl as f64 / n as f64;
            assert!(
                (frac - f as f64).abs() < 4.0 * (f as f64 * (1.0 - f as f64) / n as f64).sqrt() + 1e-9,
                "{wo}: {frac} vs {f}"
            );
            assert!((energy / n as f64 - 1.0).abs() < 1e-5, "lossless glass must conserve energy");
        }
    }

    #[test]
    fn thin_pane_reflects_and_transmits_everything() {
        let t = ThinDielectric { eta: 1.5, specular_reflectance: Rgb::ONE.into(), specular_transmittance: Rgb::ONE.into() };
        let r0 = 0.04f32; // ((1.5-1)/(1.5+1))²
        assert!((t.reflectance(1.0) - 2.0 * r0 / (1.0 + r0)).abs() < 1e-6);
        let wo = Vec3::new(0.3, 0.4, -0.866).normalize();
        let s = t.sample(&BsdfContext::default(), wo, 0.99).unwrap();
        assert_eq!(s.wi, -wo);
        assert_eq!(s.weight, Rgb::ONE);
        let s = t.sample(&BsdfContext::default(), wo, 0.0).unwrap();
        assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
    }
}
