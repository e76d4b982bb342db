//! pbrt-v4's `diffusetransmission`: Lambertian reflection `R/π` on the side of `wo` and
//! Lambertian transmission `T/π` to the other side, from either side (a thin diffuse sheet such
//! as a leaf or a lampshade). Sampled by choosing reflection or transmission in proportion to
//! the largest channel of `R` and of `T`, then a cosine-weighted direction on that side.
//! Parameters: `reflectance` (0.25), `transmittance` (0.25), both texturable.

use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{Rgb, Vec2, Vec3, INV_PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::sample_cosine_hemisphere_malley;
use crate::texture::Texture;

/// Diffuse reflection and transmission.
#[derive(Clone, Debug)]
pub struct DiffuseTransmission {
    /// Reflected albedo `R` per channel.
    pub reflectance: Texture,
    /// Transmitted albedo `T` per channel.
    pub transmittance: Texture,
}

impl DiffuseTransmission {
    /// `(R, T)` at `ctx`, clamped to [0, 1], and the probability of sampling reflection.
    #[inline]
    fn lobes(&self, ctx: &BsdfContext) -> (Rgb, Rgb, f32) {
        let r = ctx.eval(&self.reflectance).clamp(Rgb::ZERO, Rgb::ONE);
        let t = ctx.eval(&self.transmittance).clamp(Rgb::ZERO, Rgb::ONE);
        let (pr, pt) = (r.max_element(), t.max_element());
        (r, t, if pr + pt > 0.0 { pr / (pr + pt) } else { 0.0 })
    }

    /// `R/π |cos θᵢ|` on `wo`'s side, `T/π |cos θᵢ|` on the other.
    #[inline]
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        let (r, t, _) = self.lobes(ctx);
        if wo.z == 0.0 || wi.z == 0.0 {
            return Rgb::ZERO;
        }
        (if wo.z * wi.z > 0.0 { r } else { t }) * (INV_PI * wi.z.abs())
    }

    /// `|cos θᵢ|/π` times the probability of the lobe on `wi`'s side.
    #[inline]
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        let (_, _, p_reflect) = self.lobes(ctx);
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let p = if wo.z * wi.z > 0.0 { p_reflect } else { 1.0 - p_reflect };
        p * INV_PI * wi.z.abs()
    }

    /// Reflection (probability ∝ max R) or transmission, then a cosine-weighted direction.
    #[inline]
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        let (r, t, p_reflect) = self.lobes(ctx);
        if wo.z == 0.0 || r.max_element() + t.max_element() <= 0.0 {
            return None;
        }
        let s = sample_cosine_hemisphere_malley(u).value;
        let reflect = u1 < p_reflect;
        let same_side = if reflect { wo.z } else { -wo.z };
        let wi = Vec3::new(s.x, s.y, s.z.copysign(same_side));
        let (albedo, p) = if reflect { (r, p_reflect) } else { (t, 1.0 - p_reflect) };
        let pdf = p * INV_PI * s.z;
        (pdf > 0.0).then_some(BsdfSample { wi, pdf, weight: albedo / p, delta: false, null: false, eta: 1.0 })
    }

    /// pbrt-v4's `diffusetransmission`: `reflectance`, `transmittance` (0.25, texturable).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        Ok(Bsdf::DiffuseTransmission(DiffuseTransmission {
            reflectance: b.texture(o, "reflectance", Rgb::splat(0.25))?,
            transmittance: b.texture(o, "transmittance", Rgb::splat(0.25))?,
        }))
    }
}
