//! Materials: BSDFs as a closed enum with `sample` / `eval` / `pdf`.
//!
//! Conventions (Mitsuba 3): directions are in the local shading frame (normal = +z), `wo`
//! points away from the surface toward the viewer, `wi` toward the light. [`Bsdf::eval`]
//! returns the BSDF *times the cosine* `f(wo, wi) |cos θᵢ|`; [`Bsdf::pdf`] is per unit solid
//! angle; [`Bsdf::sample`] returns the sampled `wi`, its pdf and the weight
//! `f |cos θᵢ| / pdf`. BSDFs are one-sided unless stated: seen from the back (`wo.z ≤ 0`) they
//! are black, as in Mitsuba.

pub mod bssrdf;
mod conductor;
mod conductor_presets;
mod dielectric;
mod diffuse;
mod diffusetransmission;
mod filter;
pub mod fresnel;
pub mod hair;
pub mod layered;
pub(crate) mod lanes;
mod measured;
mod memo;
pub mod microfacet;
mod perturbed;
mod plastic;
mod pplastic;
mod principled;
mod principledthin;
mod registry;
mod regularize;
mod roughdielectric;
mod roughplastic;
pub mod subsurface;

pub use conductor::{Conductor, ConductorIor, RoughConductor};
pub use conductor_presets::{conductor_names, named_conductor};
pub use dielectric::{Dielectric, ThinDielectric};
pub use diffuse::Diffuse;
pub use diffusetransmission::DiffuseTransmission;
pub use filter::{Filter, FilterKind};
pub use hair::Hair;
pub use layered::Layered;
pub use measured::Measured;
pub use memo::TextureMemo;
pub use perturbed::{Perturbation, Perturbed};
pub use plastic::{diffuse_fresnel_reflectance, Plastic};
pub use pplastic::PPlastic;
pub use principled::Principled;
pub use principledthin::PrincipledThin;
pub use registry::{bsdf_plugin, BsdfBuilder, BsdfPlugin, BSDF_PLUGINS};
pub use roughdielectric::RoughDielectric;
pub use roughplastic::RoughPlastic;

use crate::math::{Rgb, Vec2, Vec3};
use std::sync::Arc;

/// Where on the surface a BSDF is evaluated (what textured parameters need).
#[derive(Clone, Copy, Debug, Default)]
pub struct BsdfContext<'a> {
    /// Surface texture coordinates.
    pub uv: Vec2,
    /// The mesh point, for `mesh_attribute` textures (None off meshes with attributes).
    pub mesh: Option<crate::geometry::mesh::MeshPoint<'a>>,
    /// The shape's texture attributes, for `mesh_attribute` textures (None on shapes without).
    pub textures: Option<&'a crate::texture::TextureAttributes>,
    /// The surface interaction, for BSDFs that perturb the shading frame (bump maps).
    pub si: Option<&'a crate::geometry::SurfaceInteraction>,
    /// Where lookups made at this point are kept for the next call of the BSDF here (see
    /// [`TextureMemo`]); none: every call looks up again.
    pub memo: Option<&'a TextureMemo>,
}

impl<'a> BsdfContext<'a> {
    /// This context with its lookups remembered in `memo` (one memo per shading point: a
    /// context whose point differs needs its own).
    #[inline]
    pub fn with_memo(self, memo: &'a TextureMemo) -> BsdfContext<'a> {
        BsdfContext { memo: Some(memo), ..self }
    }

    /// The texture `t` here. A constant (most parameters of most scenes) is read without
    /// building the lookup point or calling the general evaluation.
    #[inline(always)]
    pub fn eval(&self, t: &crate::texture::Texture) -> Rgb {
        match t {
            crate::texture::Texture::Constant(c) => *c,
            _ => self.lookup(t),
        }
    }

    /// [`BsdfContext::eval`] of a texture that is not a constant: remembered in the memo.
    fn lookup(&self, t: &crate::texture::Texture) -> Rgb {
        match self.memo {
            Some(memo) => Rgb::from(memo.get_or(t, memo::Lookup::Color, || t.eval_at(&self.point()).into())),
            None => t.eval_at(&self.point()),
        }
    }

    /// The texture `t` here as a scalar ([`crate::texture::Texture::eval_scalar`]; a constant
    /// read directly, as in [`BsdfContext::eval`]).
    #[inline(always)]
    pub fn scalar(&self, t: &crate::texture::Texture) -> f32 {
        match t {
            crate::texture::Texture::Constant(c) => crate::math::luminance(*c),
            _ => self.lookup_scalar(t),
        }
    }

    /// [`BsdfContext::scalar`] of a texture that is not a constant: remembered in the memo.
    fn lookup_scalar(&self, t: &crate::texture::Texture) -> f32 {
        match self.memo {
            Some(memo) => memo.get_or(t, memo::Lookup::Scalar, || [t.eval_scalar(&self.point()), 0.0, 0.0])[0],
            None => t.eval_scalar(&self.point()),
        }
    }

    /// Where textures are looked up: the uv, and the hit's position and geometric normal where
    /// there is a hit.
    #[inline]
    pub fn point(&self) -> crate::texture::TexPoint<'_> {
        let (p, n) = self.si.map_or((Vec3::ZERO, Vec3::Z), |si| (si.p, si.ng));
        crate::texture::TexPoint { uv: self.uv, p, n, mesh: self.mesh.as_ref(), textures: self.textures }
    }
}

/// The outcome of sampling a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled incident direction (local frame, unit).
    pub wi: Vec3,
    /// Its density per unit solid angle; for delta lobes, the discrete probability of the lobe.
    pub pdf: f32,
    /// `f(wo, wi) |cos θᵢ| / pdf`: the factor the path throughput is multiplied by.
    pub weight: Rgb,
    /// Whether `wi` was chosen by a delta (specular) lobe, which light sampling cannot reach.
    pub delta: bool,
    /// Relative index of refraction crossed (`η_it` for refraction, 1 otherwise), for Russian
    /// roulette to see through the η² radiance scaling.
    pub eta: f32,
    /// Whether the light passed straight through unscattered (`wi = -wo`: `null`, a filter, a
    /// thin dielectric's transmission, a mask's transparent part) — Mitsuba's `Null` lobe
    /// flag. The volumetric path tracers do not count such a crossing as a bounce (nor as the
    /// vertex that light sampling and MIS refer to), as Mitsuba's `volpath` and `volpathmis`.
    pub null: bool,
}

/// The BSDFs (closed set, dispatched by `match`).
#[derive(Clone, Debug)]
pub enum Bsdf {
    /// Lambertian reflection `ρ / π`.
    Diffuse(Diffuse),
    /// pbrt-v4's diffuse reflection and transmission, from both sides.
    DiffuseTransmission(DiffuseTransmission),
    /// pbrt-v4's hair fibre (Chiang et al. 2016).
    Hair(Box<Hair>),
    /// Smooth conductor (mirror with Fresnel reflectance).
    Conductor(Conductor),
    /// Microfacet conductor.
    RoughConductor(RoughConductor),
    /// Smooth dielectric (glass).
    Dielectric(Dielectric),
    /// Microfacet dielectric (rough glass).
    RoughDielectric(RoughDielectric),
    /// Smooth plastic: dielectric coating over a diffuse base.
    Plastic(Plastic),
    /// Rough plastic: microfacet coating over a diffuse base.
    RoughPlastic(RoughPlastic),
    /// Mitsuba's `pplastic` (polarized plastic), unpolarized.
    PPlastic(Box<PPlastic>),
    /// Mitsuba's `measured`: tabulated data of the RGL material database.
    Measured(Box<Measured>),
    /// Mitsuba's `principled`: the Disney BSDF.
    Principled(Box<Principled>),
    /// Mitsuba's `principledthin`: the Disney BSDF of a thin sheet.
    PrincipledThin(Box<PrincipledThin>),
    /// Thin dielectric pane.
    ThinDielectric(ThinDielectric),
    /// pbrt-v4's layered BSDF (`coateddiffuse`, `coatedconductor`): a stochastic random walk
    /// between a dielectric coating and a base.
    Layered(Box<Layered>),
    /// Mitsuba's `blendbsdf`: `(1 - w) f₀ + w f₁` with blend weight `w ∈ [0, 1]` (constant or
    /// textured, luminance used).
    Blend {
        /// Blend weight toward the second BSDF.
        weight: crate::texture::Texture,
        /// The two BSDFs.
        bsdfs: [Arc<Bsdf>; 2],
    },
    /// Mitsuba's `mask`: opacity α (constant or textured); with probability 1 - α light passes
    /// straight through (a delta "null" lobe, `wi = -wo`, weight 1).
    Mask {
        /// Opacity.
        opacity: crate::texture::Texture,
        /// The BSDF of the opaque part.
        bsdf: Arc<Bsdf>,
    },
    /// Mitsuba's `null`: no surface at all, light passes straight through (a delta lobe
    /// `wi = -wo` of weight 1). Marks index-matched boundaries of participating media.
    Null,
    /// Mitsuba's `polarizer`, `circular` and `retarder` as its RGB variants render them: a null
    /// surface that passes a share of the light ([`Filter`]).
    Filter(Filter),
    /// Mitsuba's `twosided`: the front BSDF on the front side, the back BSDF (often the same) on
    /// the back side, each seen as if from its front.
    TwoSided([Arc<Bsdf>; 2]),
    /// Mitsuba's `normalmap` and `bumpmap`, pbrt-v4's `displacement`: a nested BSDF under a
    /// perturbed shading normal.
    Perturbed(Perturbed),
    /// pbrt-v4's `subsurface`: a dielectric boundary over a BSSRDF ([`subsurface`]).
    Subsurface(Box<subsurface::Subsurface>),
}

impl Bsdf {
    /// The BSDF's plugin name in scene files (Mitsuba's: `diffuse`, `roughconductor`, …), for
    /// messages.
    pub fn plugin_name(&self) -> &'static str {
        match self {
            Bsdf::Diffuse(_) => "diffuse",
            Bsdf::DiffuseTransmission(_) => "diffusetransmission",
            Bsdf::Hair(h) => match h.convention {
                hair::HairConvention::Mitsuba => "hair",
                hair::HairConvention::Pbrt => "pbrt_hair",
            },
            Bsdf::Conductor(_) => "conductor",
            Bsdf::RoughConductor(_) => "roughconductor",
            Bsdf::Dielectric(_) => "dielectric",
            Bsdf::RoughDielectric(_) => "roughdielectric",
            Bsdf::Plastic(_) => "plastic",
            Bsdf::RoughPlastic(_) => "roughplastic",
            Bsdf::PPlastic(_) => "pplastic",
            Bsdf::Measured(_) => "measured",
            Bsdf::Principled(_) => "principled",
            Bsdf::PrincipledThin(_) => "principledthin",
            Bsdf::ThinDielectric(_) => "thindielectric",
            Bsdf::Layered(l) => match l.base {
                layered::Base::Diffuse { .. } => "coateddiffuse",
                layered::Base::Conductor { .. } => "coatedconductor",
            },
            Bsdf::Blend { .. } => "blendbsdf",
            Bsdf::Mask { .. } => "mask",
            Bsdf::Null => "null",
            Bsdf::Filter(f) => f.kind.name(),
            Bsdf::TwoSided(_) => "twosided",
            Bsdf::Subsurface(_) => "pbrt_subsurface",
            Bsdf::Perturbed(p) => match p.perturbation {
                Perturbation::NormalMap { .. } => "normalmap",
                Perturbation::BumpMap { .. } => "bumpmap",
                Perturbation::Displacement { .. } => "displacement",
            },
        }
    }

    /// Whether the volumetric path tracers cross this surface instead of scattering from it:
    /// `null` and the polarizing [`Filter`]s.
    #[inline]
    pub fn is_null(&self) -> bool {
        matches!(self, Bsdf::Null | Bsdf::Filter(_))
    }

    /// How light crosses the surface unscattered (along a straight line, Mitsuba's `Null`
    /// lobe), arriving at angle `cos_theta` to the shading normal: `(T, P)`, the factor `T` it
    /// is multiplied by (Mitsuba's `eval_null_transmission`, what a shadow ray of the
    /// volumetric path tracers carries through) and the probability `P` that [`Bsdf::sample`]
    /// chooses that crossing. `null` (1, 1); a filter its transmission, always; a thin
    /// dielectric `T = (1 − R) t` with its pane reflectance `R` and `specular_transmittance`
    /// `t`, chosen with `P = 1 − R`; a mask of opacity `a` over a BSDF crossed with `(T', P')`:
    /// `T = 1 − a + a T'` and `P = 1 − a + a P'`. `None` for every other BSDF (opaque to
    /// shadow rays, as Mitsuba's default `eval_null_transmission` of zero), `blendbsdf` and
    /// `twosided` included, as in Mitsuba.
    #[inline]
    pub fn null_transmission(&self, ctx: &BsdfContext, cos_theta: f32) -> Option<(Rgb, f32)> {
        match self {
            Bsdf::Null => Some((Rgb::ONE, 1.0)),
            Bsdf::Filter(f) => Some((f.transmission(ctx), 1.0)),
            Bsdf::ThinDielectric(b) => {
                let p = 1.0 - b.reflectance(cos_theta);
                Some((ctx.eval(&b.specular_transmittance) * p, p))
            }
            Bsdf::Mask { opacity, bsdf } => {
                let a = blend_weight(opacity, ctx);
                let (t, p) = bsdf.null_transmission(ctx, cos_theta).unwrap_or((Rgb::ZERO, 0.0));
                Some((Rgb::splat(1.0 - a) + t * a, 1.0 - a + a * p))
            }
            _ => None,
        }
    }

    /// Whether [`Bsdf::null_transmission`] can let light through (a cheap test before the
    /// textures are looked up).
    #[inline]
    pub fn may_pass(&self) -> bool {
        matches!(self, Bsdf::Null | Bsdf::Filter(_) | Bsdf::ThinDielectric(_) | Bsdf::Mask { .. })
    }

    /// Whether the BSDF has a transmission or null lobe by Mitsuba's component flags, whatever
    /// its parameters' values (a `principledthin` always has one; a `principled` has one where
    /// `spec_trans` is given other than as the float 0): what Mitsuba's `twosided` refuses to
    /// nest.
    pub fn has_transmission_lobe(&self) -> bool {
        match self {
            Bsdf::Dielectric(_)
            | Bsdf::RoughDielectric(_)
            | Bsdf::ThinDielectric(_)
            | Bsdf::Mask { .. }
            | Bsdf::DiffuseTransmission(_)
            | Bsdf::Hair(_)
            | Bsdf::Null
            | Bsdf::Filter(_)
            | Bsdf::PrincipledThin(_)
            | Bsdf::Subsurface(_) => true,
            Bsdf::Principled(b) => b.spec_trans.is_some(),
            Bsdf::Blend { bsdfs, .. } => distinct(bsdfs).iter().any(|c| c.has_transmission_lobe()),
            Bsdf::Perturbed(n) => n.bsdf.has_transmission_lobe(),
            _ => false,
        }
    }

    /// Whether the BSDF can scatter light to the other side of the surface (transmission or a
    /// null lobe), so that direct light may arrive from the whole sphere: a transmission lobe
    /// ([`Bsdf::has_transmission_lobe`]) with some weight (a `principledthin` without
    /// `spec_trans` or `diff_trans` only reflects).
    pub fn transmits(&self) -> bool {
        match self {
            Bsdf::PrincipledThin(b) => b.spec_trans.is_some() || b.diff_trans.is_some(),
            Bsdf::Blend { bsdfs, .. } => distinct(bsdfs).iter().any(|c| c.transmits()),
            Bsdf::Perturbed(n) => n.bsdf.transmits(),
            _ => self.has_transmission_lobe(),
        }
    }
}

/// Flips a local direction to the other side (z → -z).
#[inline]
fn flip(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

impl Bsdf {
    /// `f(wo, wi) |cos θᵢ|` (local frame); 0 for delta BSDFs.
    #[inline]
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Bsdf::Diffuse(b) => b.eval(ctx, wo, wi),
            Bsdf::DiffuseTransmission(b) => b.eval(ctx, wo, wi),
            Bsdf::Hair(b) => b.eval(ctx, wo, wi),
            Bsdf::RoughConductor(b) => b.eval(ctx, wo, wi),
            Bsdf::RoughDielectric(b) => b.eval(ctx, wo, wi),
            Bsdf::Plastic(b) => b.eval(ctx, wo, wi),
            Bsdf::RoughPlastic(b) => b.eval(ctx, wo, wi),
            Bsdf::Principled(b) => b.eval(ctx, wo, wi),
            Bsdf::PPlastic(b) => b.eval(ctx, wo, wi),
            Bsdf::Measured(b) => b.eval(ctx, wo, wi),
            Bsdf::PrincipledThin(b) => b.eval(ctx, wo, wi),
            Bsdf::Layered(b) => b.eval(ctx, wo, wi),
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) | Bsdf::ThinDielectric(_) | Bsdf::Null | Bsdf::Filter(_) => Rgb::ZERO,
            Bsdf::Blend { weight, bsdfs } => {
                let w = blend_weight(weight, ctx);
                bsdfs[0].eval(ctx, wo, wi) * (1.0 - w) + bsdfs[1].eval(ctx, wo, wi) * w
            }
            Bsdf::Mask { opacity, bsdf } => bsdf.eval(ctx, wo, wi) * blend_weight(opacity, ctx),
            Bsdf::Perturbed(n) => n.eval(ctx, wo, wi),
            Bsdf::Subsurface(s) => s.surface.eval(ctx, wo, wi),
            Bsdf::TwoSided(b) => {
                if wo.z >= 0.0 {
                    b[0].eval(ctx, wo, wi)
                } else {
                    b[1].eval(ctx, flip(wo), flip(wi))
                }
            }
        }
    }

    /// [`Bsdf::eval`] and [`Bsdf::pdf`] at once, the same bits as the two calls: where a light
    /// sample needs both (MIS), the microfacet BSDFs share their half vector, `D`, `G1(wo)`
    /// and textured parameters between them, the hair fibre its longitudinal and azimuthal
    /// terms, a measured BSDF its inverted warp (Mitsuba's `eval_pdf`).
    #[inline]
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        match self {
            Bsdf::Diffuse(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::RoughConductor(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::RoughDielectric(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::Principled(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::PrincipledThin(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::Hair(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::Measured(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::RoughPlastic(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::PPlastic(b) => b.eval_pdf(ctx, wo, wi),
            Bsdf::Blend { weight, bsdfs } => {
                let w = blend_weight(weight, ctx);
                let ((f0, p0), (f1, p1)) = (bsdfs[0].eval_pdf(ctx, wo, wi), bsdfs[1].eval_pdf(ctx, wo, wi));
                (f0 * (1.0 - w) + f1 * w, p0 * (1.0 - w) + p1 * w)
            }
            Bsdf::Mask { opacity, bsdf } => {
                let ((f, p), w) = (bsdf.eval_pdf(ctx, wo, wi), blend_weight(opacity, ctx));
                (f * w, p * w)
            }
            Bsdf::TwoSided(b) => {
                if wo.z >= 0.0 {
                    b[0].eval_pdf(ctx, wo, wi)
                } else {
                    b[1].eval_pdf(ctx, flip(wo), flip(wi))
                }
            }
            _ => (self.eval(ctx, wo, wi), self.pdf(ctx, wo, wi)),
        }
    }

    /// Density of [`Bsdf::sample`] choosing `wi`, per unit solid angle; 0 for delta BSDFs.
    #[inline]
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse(b) => b.pdf(wo, wi),
            Bsdf::DiffuseTransmission(b) => b.pdf(ctx, wo, wi),
            Bsdf::Hair(b) => b.pdf(ctx, wo, wi),
            Bsdf::RoughConductor(b) => b.pdf(ctx, wo, wi),
            Bsdf::RoughDielectric(b) => b.pdf(ctx, wo, wi),
            Bsdf::Plastic(b) => b.pdf(wo, wi),
            Bsdf::RoughPlastic(b) => b.pdf(wo, wi),
            Bsdf::Principled(b) => b.pdf(ctx, wo, wi),
            Bsdf::PPlastic(b) => b.pdf(ctx, wo, wi),
            Bsdf::Measured(b) => b.pdf(ctx, wo, wi),
            Bsdf::PrincipledThin(b) => b.pdf(ctx, wo, wi),
            Bsdf::Layered(b) => b.pdf(ctx, wo, wi),
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) | Bsdf::ThinDielectric(_) | Bsdf::Null | Bsdf::Filter(_) => 0.0,
            Bsdf::Blend { weight, bsdfs } => {
                let w = blend_weight(weight, ctx);
                bsdfs[0].pdf(ctx, wo, wi) * (1.0 - w) + bsdfs[1].pdf(ctx, wo, wi) * w
            }
            Bsdf::Mask { opacity, bsdf } => bsdf.pdf(ctx, wo, wi) * blend_weight(opacity, ctx),
            Bsdf::Perturbed(n) => n.pdf(ctx, wo, wi),
            Bsdf::Subsurface(s) => s.surface.pdf(ctx, wo, wi),
            Bsdf::TwoSided(b) => {
                if wo.z >= 0.0 {
                    b[0].pdf(ctx, wo, wi)
                } else {
                    b[1].pdf(ctx, flip(wo), flip(wi))
                }
            }
        }
    }

    /// Samples `wi` for `wo` from one number `u1` (lobe choice) and two `u` (direction).
    #[inline]
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Diffuse(b) => b.sample(ctx, wo, u1, u),
            Bsdf::DiffuseTransmission(b) => b.sample(ctx, wo, u1, u),
            Bsdf::Hair(b) => b.sample(ctx, wo, u1, u),
            Bsdf::Conductor(b) => b.sample(ctx, wo),
            Bsdf::RoughConductor(b) => b.sample(ctx, wo, u),
            Bsdf::Dielectric(b) => b.sample(ctx, wo, u1),
            Bsdf::RoughDielectric(b) => b.sample(ctx, wo, u1, u),
            Bsdf::Plastic(b) => b.sample(ctx, wo, u1, u),
            Bsdf::RoughPlastic(b) => b.sample(ctx, wo, u1, u),
            Bsdf::Principled(b) => b.sample(ctx, wo, u1, u),
            Bsdf::PPlastic(b) => b.sample(ctx, wo, u1, u),
            Bsdf::Measured(b) => b.sample(ctx, wo, u),
            Bsdf::PrincipledThin(b) => b.sample(ctx, wo, u1, u),
            Bsdf::Layered(b) => b.sample(ctx, wo, u1, u),
            Bsdf::ThinDielectric(b) => b.sample(ctx, wo, u1),
            Bsdf::Null => Some(BsdfSample { wi: -wo, pdf: 1.0, weight: Rgb::ONE, delta: true, null: true, eta: 1.0 }),
            Bsdf::Filter(f) => {
                let weight = f.transmission(ctx);
                (weight != Rgb::ZERO).then_some(BsdfSample { wi: -wo, pdf: 1.0, weight, delta: true, null: true, eta: 1.0 })
            }
            Bsdf::Blend { weight, bsdfs } => {
                let w = blend_weight(weight, ctx);
                // Choose a component with its blend probability and reuse u1 for its own choice.
                let (k, u1r, p) = if u1 < w { (1, u1 / w, w) } else { (0, (u1 - w) / (1.0 - w), 1.0 - w) };
                let s = bsdfs[k].sample(ctx, wo, u1r.min(crate::math::ONE_MINUS_EPSILON), u)?;
                if s.delta {
                    // A delta lobe of one component: the other cannot produce this direction.
                    return Some(BsdfSample { pdf: s.pdf * p, ..s });
                }
                let pdf = self.pdf(ctx, wo, s.wi);
                let f = self.eval(ctx, wo, s.wi);
                (pdf > 0.0).then(|| BsdfSample { pdf, weight: f / pdf, ..s })
            }
            Bsdf::Mask { opacity, bsdf } => {
                let a = blend_weight(opacity, ctx);
                if u1 < a {
                    let s = bsdf.sample(ctx, wo, (u1 / a).min(crate::math::ONE_MINUS_EPSILON), u)?;
                    Some(BsdfSample { pdf: s.pdf * a, ..s })
                } else {
                    Some(BsdfSample { wi: -wo, pdf: 1.0 - a, weight: Rgb::ONE, delta: true, null: true, eta: 1.0 })
                }
            }
            Bsdf::Perturbed(n) => n.sample(ctx, wo, u1, u),
            Bsdf::Subsurface(s) => s.surface.sample(ctx, wo, u1, u),
            Bsdf::TwoSided(b) => {
                if wo.z >= 0.0 {
                    b[0].sample(ctx, wo, u1, u)
                } else {
                    b[1].sample(ctx, flip(wo), u1, u).map(|s| BsdfSample { wi: flip(s.wi), ..s })
                }
            }
        }
    }

    /// Relative index of refraction `η_it` crossed between `wo`'s side and `wi`'s side (local
    /// frame): 1 unless the BSDF refracts and the directions lie on opposite sides. Light
    /// tracing multiplies radiance-mode values by `η_it²` to get the adjoint (importance) BSDF,
    /// which lacks the `1/η²` radiance scaling of refraction.
    pub fn eta_crossed(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z * wi.z >= 0.0 {
            return 1.0;
        }
        let eta = match self {
            Bsdf::Dielectric(b) => b.eta,
            Bsdf::RoughDielectric(b) => b.eta,
            Bsdf::Principled(b) => b.eta,
            // No single index describes two refracting components (light tracing takes
            // `eval_adjoint`, lobe by lobe); the product is exact when at most one refracts.
            Bsdf::Blend { bsdfs, .. } => return bsdfs[0].eta_crossed(wo, wi) * bsdfs[1].eta_crossed(wo, wi),
            // The sides of the perturbed frame decide; without the context, those of the
            // original one (they agree for every direction the normal map lets through).
            Bsdf::Perturbed(n) => return n.bsdf.eta_crossed(wo, wi),
            Bsdf::Subsurface(s) => return s.surface.eta_crossed(wo, wi),
            _ => return 1.0,
        };
        if wo.z > 0.0 {
            eta
        } else {
            1.0 / eta
        }
    }

    /// The adjoint BSDF's value (light tracing's importance transport) for light arriving from
    /// `wo` and leaving toward `wi` (local frame): the value with refraction's `1/η²` radiance
    /// scaling removed, lobe by lobe — a blend's is the blend of its components' adjoints, so
    /// components that refract with different indices each get their own `η_it²`.
    pub fn eval_adjoint(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Bsdf::Blend { weight, bsdfs } => {
                let w = blend_weight(weight, ctx);
                bsdfs[0].eval_adjoint(ctx, wo, wi) * (1.0 - w) + bsdfs[1].eval_adjoint(ctx, wo, wi) * w
            }
            Bsdf::Mask { opacity, bsdf } => bsdf.eval_adjoint(ctx, wo, wi) * blend_weight(opacity, ctx),
            Bsdf::Perturbed(n) => n.eval_adjoint(ctx, wo, wi),
            Bsdf::Subsurface(s) => s.surface.eval_adjoint(ctx, wo, wi),
            _ => {
                let eta = self.eta_crossed(wo, wi);
                self.eval(ctx, wo, wi) * (eta * eta)
            }
        }
    }

    /// The weight of a light-tracing (importance) sample `s` drawn by [`Bsdf::sample`] from
    /// `wo`: the adjoint value over the density. `s.weight · η²` of the sampled lobe, except
    /// where a blend mixes lobes at a smooth sample's direction (its weight is the mixture's
    /// value over the mixture's density), which takes [`Bsdf::eval_adjoint`] over the density.
    pub fn adjoint_sample_weight(&self, ctx: &BsdfContext, wo: Vec3, s: &BsdfSample) -> Rgb {
        if s.delta || !self.any_nested(&|b| matches!(b, Bsdf::Blend { .. })) {
            return s.weight * (s.eta * s.eta);
        }
        if s.pdf > 0.0 {
            self.eval_adjoint(ctx, wo, s.wi) / s.pdf
        } else {
            Rgb::ZERO
        }
    }

    /// The diffuse reflectance seen from `wo` (local frame), Mitsuba's
    /// `eval_diffuse_reflectance` (the `albedo` AOV): the reflectance texture of the diffuse
    /// and plastic bases, blended and sided like the BSDF; for the others `π f(wo, n) cos θ` with
    /// the incident direction along the normal (0 for delta BSDFs).
    pub fn diffuse_reflectance(&self, ctx: &BsdfContext, wo: Vec3) -> Rgb {
        match self {
            Bsdf::Diffuse(b) => ctx.eval(&b.reflectance),
            Bsdf::DiffuseTransmission(b) => ctx.eval(&b.reflectance),
            Bsdf::Plastic(b) => ctx.eval(&b.diffuse_reflectance),
            Bsdf::RoughPlastic(b) => ctx.eval(&b.diffuse_reflectance),
            Bsdf::Principled(b) => ctx.eval(&b.base_color),
            Bsdf::PrincipledThin(b) => ctx.eval(&b.base_color),
            Bsdf::Layered(b) => b.diffuse_reflectance(ctx),
            Bsdf::Blend { weight, bsdfs } => {
                let w = blend_weight(weight, ctx);
                bsdfs[0].diffuse_reflectance(ctx, wo) * (1.0 - w) + bsdfs[1].diffuse_reflectance(ctx, wo) * w
            }
            Bsdf::TwoSided(b) => {
                if wo.z > 0.0 {
                    b[0].diffuse_reflectance(ctx, wo)
                } else {
                    b[1].diffuse_reflectance(ctx, flip(wo))
                }
            }
            Bsdf::Perturbed(n) => n.bsdf.diffuse_reflectance(ctx, wo),
            Bsdf::Subsurface(s) => s.surface.diffuse_reflectance(ctx, wo),
            _ => self.eval(ctx, wo, Vec3::new(0.0, 0.0, 1.0)) * std::f32::consts::PI,
        }
    }

    /// The mesh attributes its textures read (`mesh_attribute`), which the shapes it is on
    /// must carry.
    pub fn mesh_attributes(&self) -> Vec<&str> {
        self.textures().into_iter().flat_map(|t| t.mesh_attributes()).collect()
    }

    /// Every texture its parameters are (those of nested BSDFs included).
    pub fn textures(&self) -> Vec<&crate::texture::Texture> {
        match self {
            Bsdf::Diffuse(b) => vec![&b.reflectance],
            Bsdf::DiffuseTransmission(b) => vec![&b.reflectance, &b.transmittance],
            Bsdf::Hair(b) => b.textures(),
            Bsdf::Conductor(b) => {
                let mut v = vec![&b.specular_reflectance];
                v.extend(ConductorIor::textures(&b.ior));
                v
            }
            Bsdf::RoughConductor(b) => {
                let mut v = vec![&b.specular_reflectance];
                v.extend(ConductorIor::textures(&b.ior));
                v.extend(b.roughness.textures());
                v
            }
            Bsdf::Dielectric(b) => vec![&b.specular_reflectance, &b.specular_transmittance],
            Bsdf::ThinDielectric(b) => vec![&b.specular_reflectance, &b.specular_transmittance],
            Bsdf::RoughDielectric(b) => {
                let mut v = vec![&b.specular_reflectance, &b.specular_transmittance];
                v.extend(b.roughness.textures());
                v
            }
            Bsdf::Plastic(b) => vec![&b.diffuse_reflectance, &b.specular_reflectance],
            Bsdf::RoughPlastic(b) => vec![&b.diffuse_reflectance, &b.specular_reflectance],
            Bsdf::Principled(b) => b.textures(),
            Bsdf::PPlastic(b) => vec![&b.diffuse_reflectance, &b.specular_reflectance],
            Bsdf::Measured(_) => Vec::new(),
            Bsdf::PrincipledThin(b) => b.textures(),
            Bsdf::Layered(b) => b.textures(),
            Bsdf::Blend { weight, bsdfs } => {
                let mut v = vec![weight];
                v.extend(distinct(bsdfs).iter().flat_map(|b| b.textures()));
                v
            }
            Bsdf::Mask { opacity, bsdf } => {
                let mut v = vec![opacity];
                v.extend(bsdf.textures());
                v
            }
            Bsdf::TwoSided(b) => distinct(b).iter().flat_map(|b| b.textures()).collect(),
            Bsdf::Perturbed(n) => {
                let mut v = vec![match &n.perturbation {
                    Perturbation::NormalMap { map: t, .. }
                    | Perturbation::BumpMap { height: t, .. }
                    | Perturbation::Displacement { displacement: t } => t,
                }];
                v.extend(n.bsdf.textures());
                v
            }
            Bsdf::Subsurface(s) => {
                let mut v = s.textures();
                v.extend(s.surface.textures());
                v
            }
            Bsdf::Null => Vec::new(),
            Bsdf::Filter(f) => vec![&f.transmittance],
        }
    }

    /// Whether the BSDF (or one nested in it) reads the surface's texture coordinates: a
    /// texture that is not constant, or hair (its offset across the fibre is `v`). Scenes where
    /// no BSDF or emitter does skip them on spheres (the scene computes them on demand then).
    pub fn reads_uv(&self) -> bool {
        self.textures().iter().any(|t| !matches!(t, crate::texture::Texture::Constant(_)))
            || self.any_nested(&|b| matches!(b, Bsdf::Hair(_)))
    }

    /// Whether the BSDF (or one nested in it) is a bump map, which reads `∂p/∂v` at hits.
    pub fn perturbs_with_height(&self) -> bool {
        self.any_nested(&|b| {
            matches!(b, Bsdf::Perturbed(p)
                if matches!(p.perturbation, Perturbation::BumpMap { .. } | Perturbation::Displacement { .. }))
        })
    }

    /// Whether `f` holds for the BSDF or for one nested in it (under a normal or bump map, a
    /// two-sided, blend or mask BSDF).
    fn any_nested(&self, f: &impl Fn(&Bsdf) -> bool) -> bool {
        f(self)
            || match self {
                Bsdf::Perturbed(p) => p.bsdf.any_nested(f),
                Bsdf::Subsurface(s) => s.surface.any_nested(f),
                Bsdf::TwoSided(b) | Bsdf::Blend { bsdfs: b, .. } => distinct(b).iter().any(|c| c.any_nested(f)),
                Bsdf::Mask { bsdf, .. } => bsdf.any_nested(f),
                _ => false,
            }
    }

    /// The subsurface material this BSDF is (under normal or bump maps), if it is one.
    pub fn subsurface(&self) -> Option<&subsurface::Subsurface> {
        match self {
            Bsdf::Subsurface(s) => Some(s),
            Bsdf::Perturbed(p) => p.bsdf.subsurface(),
            _ => None,
        }
    }

    /// Whether the BSDF has only delta lobes (light sampling is useless on it).
    #[inline]
    pub fn is_delta(&self) -> bool {
        match self {
            Bsdf::Diffuse(_)
            | Bsdf::DiffuseTransmission(_)
            | Bsdf::Hair(_)
            | Bsdf::RoughConductor(_)
            | Bsdf::RoughDielectric(_)
            | Bsdf::Plastic(_)
            | Bsdf::RoughPlastic(_)
            | Bsdf::Principled(_)
            | Bsdf::PrincipledThin(_)
            | Bsdf::PPlastic(_)
            | Bsdf::Measured(_) => false,
            Bsdf::Conductor(_) | Bsdf::Dielectric(_) | Bsdf::ThinDielectric(_) | Bsdf::Null | Bsdf::Filter(_) => true,
            Bsdf::Layered(b) => b.is_delta(),
            // Recursive, so kept out of line: the leaf cases above inline into the integrators.
            _ => self.is_delta_nested(),
        }
    }

    /// [`Bsdf::is_delta`] of the BSDFs that wrap others.
    #[inline(never)]
    fn is_delta_nested(&self) -> bool {
        match self {
            Bsdf::TwoSided(b) | Bsdf::Blend { bsdfs: b, .. } => distinct(b).iter().all(|c| c.is_delta()),
            Bsdf::Mask { bsdf, .. } => bsdf.is_delta(),
            Bsdf::Perturbed(n) => n.bsdf.is_delta(),
            Bsdf::Subsurface(s) => s.surface.is_delta(),
            leaf => leaf.is_delta(),
        }
    }
}

/// A blend weight or opacity in [0, 1] from a texture (its luminance).
#[inline]
fn blend_weight(t: &crate::texture::Texture, ctx: &BsdfContext) -> f32 {
    ctx.scalar(t).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests;

/// The two nested BSDFs of a `twosided` or `blendbsdf`, or one when both are the same (a
/// `twosided` with one BSDF, or two references to one): queries over the nesting then visit a
/// shared BSDF once, not once per path to it.
fn distinct(b: &[Arc<Bsdf>; 2]) -> &[Arc<Bsdf>] {
    if Arc::ptr_eq(&b[0], &b[1]) {
        &b[..1]
    } else {
        &b[..]
    }
}
