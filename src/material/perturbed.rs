//! Mitsuba's `normalmap` and `bumpmap`, and pbrt-v4's `displacement`: a nested BSDF seen
//! through a perturbed shading normal.
//!
//! - `normalmap`: the normal is read from a texture, in tangent space: its RGB `c` gives
//!   `2c − 1` in the local shading frame, whose x follows `∂p/∂u` (read the image with `raw`
//!   so that it is not sRGB-decoded).
//! - `bumpmap`: the normal of the surface displaced along the shading normal by a height field
//!   `h` (a bitmap's luminance, times `scale`): with the slopes `(∂h/∂u, ∂h/∂v)` of the bilinear
//!   interpolant, `∂p/∂u' = ∂p/∂u + n (∂h/∂u − n·∂p/∂u)` (and alike for v), and the normal
//!   `∂p/∂u' × ∂p/∂v'`, turned to the side of the geometric normal.
//! - `displacement` (neumann's plugin for pbrt-v4's material `displacement`): the surface
//!   displaced by a scalar texture `d` (world units) along the shading normal, differentiated as
//!   pbrt-v4's `BumpMap` does, by forward differences of `δ` = [`DISPLACEMENT_DELTA`] in u and v
//!   (the texture looked up at `uv + (δ, 0)` and `p + δ ∂p/∂u`, and alike for v):
//!   `∂p/∂u' = ∂p/∂u + n ((d(u + δ) − d(u)) / δ − n·∂p/∂u)` (pbrt's shading ∂p/∂u is the one
//!   perpendicular to n); any texture, procedural or image. pbrt-v4 takes δ from the ray
//!   differentials (half the pixel's footprint in uv, shrunk with the sample count) where neumann
//!   has none, and adds `d ∂n/∂u`, the turning of the normal, which neumann leaves out (zero on
//!   flat triangles; it scales both tangents alike on spheres).
//!
//! Both as Mitsuba 3.9 applies them (its `PerturbedBSDF`, measured against Mitsuba 3.9.1):
//! - `flip_invalid_normals` (default true): a perturbed normal whose side differs from the
//!   viewer's has its tangential part negated, so that the viewer sees its front (Schüssler et
//!   al. 2017), which leaves no black pixels;
//! - the perturbed frame has that normal `n` and the tangent `x − n nₓ`, normalized;
//! - the nested BSDF is evaluated and sampled in it, and a direction toward the light on
//!   different sides of the perturbed and the original normal carries nothing (no light leaks);
//! - `use_shadowing_function` (default true): values are multiplied by the microfacet shadowing
//!   of Estevez et al. 2019 (the bump-terminator fix), `2 / (1 + √(1 + α² tan²θᵢ))` with
//!   `α² = min(tan²θₙ / 8, 1)`, θᵢ and θₙ measured from the original normal.

use super::memo::Lookup;
use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{Frame, Rgb, Vec2, Vec3};
use crate::props::{Obj, Result as PropResult};
use crate::texture::Texture;
use std::sync::Arc;

/// Where the perturbed normal comes from.
#[derive(Clone, Debug)]
pub enum Perturbation {
    /// Tangent-space normals, encoded as `(n + 1) / 2`.
    NormalMap {
        /// The tangent-space normal, encoded as `(n + 1) / 2`.
        map: Texture,
        /// A factor on the normal's tangential components before it is normalized (glTF's
        /// `normalTexture.scale`; 1 in Mitsuba).
        scale: f32,
    },
    /// pbrt-v4's displacement: a scalar texture (world units along the shading normal),
    /// differentiated by forward differences.
    Displacement {
        /// The displacement.
        displacement: Texture,
    },
    /// A height field (a bitmap's luminance) times `scale`.
    BumpMap {
        /// The height field.
        height: Texture,
        /// Its scale (world units per unit of the texture's value).
        scale: f32,
    },
}

/// A BSDF under a normal or bump map.
#[derive(Clone, Debug)]
pub struct Perturbed {
    /// The perturbation.
    pub perturbation: Perturbation,
    /// The BSDF seen through it.
    pub bsdf: Arc<Bsdf>,
    /// Turn normals that face away from the viewer toward it.
    pub flip_invalid_normals: bool,
    /// Attenuate by the bump-terminator shadowing function.
    pub shadowing: bool,
}

/// The step of pbrt-v4's forward differences of a displacement texture, in u and in v (pbrt's
/// value where a ray has no differentials).
pub const DISPLACEMENT_DELTA: f32 = 0.0005;

/// `tan²θ` of a unit vector in the local frame.
#[inline]
fn tan2(v: Vec3) -> f32 {
    let c2 = v.z * v.z;
    ((1.0 - c2).max(0.0) / c2).max(0.0)
}

/// The shadowing of Estevez et al. 2019 for the perturbed normal `n` and the direction `wi`
/// (both in the original local frame).
#[inline]
pub fn shadow_terminator(n: Vec3, wi: Vec3) -> f32 {
    let alpha2 = (0.125 * tan2(n)).min(1.0);
    let g = 2.0 / (1.0 + (1.0 + alpha2 * tan2(wi)).sqrt());
    if g.is_finite() {
        g
    } else {
        0.0
    }
}

/// The frame of a perturbed normal `n` (local coordinates, not normalized) seen from `wo`: the
/// normal flipped toward the viewer if asked, normalized (+z if degenerate), with the tangent
/// `x − n nₓ` (or +y).
#[inline]
pub fn perturbed_frame(mut n: Vec3, wo: Vec3, flip_invalid_normals: bool) -> Frame {
    if flip_invalid_normals && wo.z * wo.dot(n) <= 0.0 {
        n = Vec3::new(-n.x, -n.y, n.z);
    }
    let len2 = n.length_squared();
    let n = if len2 > 0.0 && len2.is_finite() { n / len2.sqrt() } else { Vec3::Z };
    let s = Vec3::X - n * n.x;
    let s_len2 = s.length_squared();
    let s = if s_len2 > 0.0 && s_len2.is_finite() { s / s_len2.sqrt() } else { Vec3::Y };
    Frame { s, t: n.cross(s), n }
}

impl Perturbation {
    /// The perturbed normal at `ctx` in the local shading frame's coordinates (not normalized;
    /// +z without a surface interaction to perturb).
    fn normal(&self, ctx: &BsdfContext) -> Vec3 {
        match self {
            Perturbation::NormalMap { map, scale } => {
                let n = ctx.eval(map) * 2.0 - Vec3::ONE;
                Vec3::new(n.x * scale, n.y * scale, n.z)
            }
            Perturbation::BumpMap { height, scale } => {
                let Some(si) = ctx.si else { return Vec3::Z };
                let g = height.eval_scalar_grad(ctx.uv) * *scale;
                let n = si.ns;
                let dpdu = si.dpdu + n * (g.x - n.dot(si.dpdu));
                let dpdv = si.dpdv + n * (g.y - n.dot(si.dpdv));
                let mut cr = dpdu.cross(dpdv);
                if si.ng.dot(cr) < 0.0 {
                    cr = -cr;
                }
                si.frame().to_local(cr)
            }
            Perturbation::Displacement { displacement } => {
                let Some(si) = ctx.si else { return Vec3::Z };
                let at = ctx.point();
                let d = displacement.eval_scalar(&at);
                let delta = DISPLACEMENT_DELTA;
                let shifted = |duv: Vec2, dp: Vec3| {
                    let moved = crate::texture::TexPoint { uv: at.uv + duv, p: at.p + dp * delta, ..at };
                    (displacement.eval_scalar(&moved) - d) / delta
                };
                let (gu, gv) = (shifted(Vec2::new(delta, 0.0), si.dpdu), shifted(Vec2::new(0.0, delta), si.dpdv));
                let n = si.ns;
                let dpdu = si.dpdu + n * (gu - n.dot(si.dpdu));
                let dpdv = si.dpdv + n * (gv - n.dot(si.dpdv));
                let mut cr = dpdu.cross(dpdv);
                if si.ng.dot(cr) < 0.0 {
                    cr = -cr;
                }
                si.frame().to_local(cr)
            }
        }
    }
}

impl Perturbed {
    /// The perturbed shading frame at `ctx` for the viewer at `wo` (local coordinates).
    #[inline]
    pub fn frame(&self, ctx: &BsdfContext, wo: Vec3) -> Frame {
        // The normal is the same for every call at this point (the frame depends on `wo`).
        let n =
            match ctx.memo {
                // Computed without the memo: the map's own lookup would take a second slot for
                // what the normal's entry already holds.
                Some(memo) => Vec3::from(memo.get_or(self, Lookup::Normal, || {
                    self.perturbation.normal(&BsdfContext { memo: None, ..*ctx }).into()
                })),
                None => self.perturbation.normal(ctx),
            };
        perturbed_frame(n, wo, self.flip_invalid_normals)
    }

    #[inline]
    fn shadow(&self, f: &Frame, wi: Vec3) -> f32 {
        if self.shadowing {
            shadow_terminator(f.n, wi)
        } else {
            1.0
        }
    }

    /// `f(wo, wi) |cos θᵢ|` of the nested BSDF in the perturbed frame, shadowed.
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        self.eval_nested(ctx, wo, wi, Bsdf::eval)
    }

    /// [`Perturbed::eval`] of the nested BSDF's adjoint ([`Bsdf::eval_adjoint`]), its sides
    /// those of the perturbed frame.
    pub fn eval_adjoint(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        self.eval_nested(ctx, wo, wi, Bsdf::eval_adjoint)
    }

    /// `nested(bsdf, ctx, wo, wi)` in the perturbed frame, shadowed; 0 for a `wi` on different
    /// sides of the two normals.
    #[inline]
    fn eval_nested(
        &self,
        ctx: &BsdfContext,
        wo: Vec3,
        wi: Vec3,
        nested: impl Fn(&Bsdf, &BsdfContext, Vec3, Vec3) -> Rgb,
    ) -> Rgb {
        let f = self.frame(ctx, wo);
        let wi_p = f.to_local(wi);
        if wi.z * wi_p.z <= 0.0 {
            return Rgb::ZERO;
        }
        nested(&self.bsdf, ctx, f.to_local(wo), wi_p) * self.shadow(&f, wi)
    }

    /// Density of [`Perturbed::sample`] choosing `wi` (the nested BSDF's).
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        let f = self.frame(ctx, wo);
        let wi_p = f.to_local(wi);
        if wi.z * wi_p.z <= 0.0 {
            return 0.0;
        }
        self.bsdf.pdf(ctx, f.to_local(wo), wi_p)
    }

    /// The nested BSDF's sample in the perturbed frame, refused if it lies on different sides of
    /// the two normals; its weight shadowed.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        let f = self.frame(ctx, wo);
        let s = self.bsdf.sample(ctx, f.to_local(wo), u1, u)?;
        let wi = f.to_world(s.wi);
        (wi.z * s.wi.z > 0.0).then(|| BsdfSample { wi, weight: s.weight * self.shadow(&f, wi), ..s })
    }

    /// The parameters both plugins share: `flip_invalid_normals` (true),
    /// `use_shadowing_function` (true) and one nested BSDF.
    fn from_props(perturbation: Perturbation, o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let flip_invalid_normals = o.bool("flip_invalid_normals", true)?;
        let shadowing = o.bool("use_shadowing_function", true)?;
        let mut nested = b.nested_bsdfs(o, 1..=1)?;
        let bsdf = nested.pop().expect("one");
        Ok(Bsdf::Perturbed(Perturbed { perturbation, bsdf, flip_invalid_normals, shadowing }))
    }

    /// Mitsuba's `normalmap`: `normalmap` (a texture, required), neumann's `scale` (1, glTF's
    /// `normalTexture.scale`: a factor on the normal's tangential components) and the shared
    /// parameters.
    pub fn normalmap_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        if !o.has("normalmap") {
            return Err(o.error("a normalmap needs its 'normalmap' texture (a bitmap read with raw = true)"));
        }
        let map =
            b.texture_of(o, "normalmap", Rgb::new(0.5, 0.5, 1.0), crate::math::spectrum::SpectrumKind::Unbounded)?;
        // neumann's `scale` (1): glTF's normalTexture.scale.
        let scale = o.float_checked("scale", 1.0, f32::is_finite, "a number")?;
        Perturbed::from_props(Perturbation::NormalMap { map, scale }, o, b)
    }

    /// neumann's `displacement` (pbrt-v4's material `displacement`): `displacement` (a scalar
    /// texture, world units; required), the nested BSDF, and the shared parameters (pbrt applies
    /// neither: its translation sets both false).
    pub fn displacement_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        if !o.has("displacement") {
            return Err(o.error("a displacement needs its 'displacement' texture (world units along the normal)"));
        }
        let displacement =
            b.texture_of(o, "displacement", Rgb::ZERO, crate::math::spectrum::SpectrumKind::Unbounded)?;
        Perturbed::from_props(Perturbation::Displacement { displacement }, o, b)
    }

    /// Mitsuba's `bumpmap`: one nested (unnamed) bitmap texture, the height field; `scale` (1);
    /// and the shared parameters. Mitsuba differentiates only bitmaps, and so does neumann.
    pub fn bumpmap_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let mut textures = b.nested_textures(o)?;
        if textures.len() != 1 {
            return Err(o.error(format!(
                "a bumpmap takes exactly one nested <texture> (its height field), found {}",
                textures.len()
            )));
        }
        let height = textures.pop().expect("one");
        if !matches!(height, Texture::Bitmap { .. }) {
            return Err(
                o.error("a bumpmap's height field must be a bitmap texture (Mitsuba differentiates bitmaps only)")
            );
        }
        let scale = o.float("scale", 1.0)?;
        Perturbed::from_props(Perturbation::BumpMap { height, scale }, o, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Diffuse;

    fn ctx() -> BsdfContext<'static> {
        BsdfContext::default()
    }

    fn map(n: Vec3, bsdf: Bsdf, shadowing: bool) -> Perturbed {
        Perturbed {
            perturbation: Perturbation::NormalMap { map: ((n.normalize() + Vec3::ONE) * 0.5).into(), scale: 1.0 },
            bsdf: Arc::new(bsdf),
            flip_invalid_normals: true,
            shadowing,
        }
    }

    /// A ramp image (0, 0.25, 0.5, 0.75 across four texels along its s axis: slope 1 per unit
    /// of s, bilinear, clamped) looked up through `to_uv`.
    fn ramp(to_uv: glam::Mat3) -> Texture {
        use crate::texture::{Bitmap, Filter, Wrap};
        let image = std::sync::Arc::new(crate::image::Image {
            width: 4,
            height: 1,
            pixels: [0.0, 0.25, 0.5, 0.75].map(Rgb::splat).to_vec(),
        });
        Texture::Bitmap { bitmap: Bitmap { image, filter: Filter::Bilinear, wrap: [Wrap::Clamp; 2] }, to_uv }
    }

    /// A diffuse BSDF under `perturbation`, without Mitsuba's flip and shadowing.
    fn perturbed(perturbation: Perturbation) -> Perturbed {
        let bsdf = Arc::new(Bsdf::Diffuse(Diffuse::new(Rgb::ONE)));
        Perturbed { perturbation, bsdf, flip_invalid_normals: false, shadowing: false }
    }

    /// A hit at `uv` on the plane z = 0 facing +z, with `∂p/∂u = (2, 0, 0)`, `∂p/∂v = (0, 2, 0)`.
    fn flat_hit(uv: Vec2) -> crate::geometry::SurfaceInteraction {
        crate::geometry::SurfaceInteraction {
            p: Vec3::ZERO,
            p_error: Vec3::ZERO,
            t: 1.0,
            ng: Vec3::Z,
            ns: Vec3::Z,
            uv,
            dpdu: Vec3::new(2.0, 0.0, 0.0),
            dpdv: Vec3::new(0.0, 2.0, 0.0),
            shape: 0,
            prim: 0,
            bary: Vec2::ZERO,
            time: 0.0,
        }
    }

    /// A memo (one per shading point) changes no value: a bump map over rough plastic with a
    /// textured albedo, sampled, evaluated and its density taken at many points and directions,
    /// gives the same bits with a memo as without, and the memo keeps the lookups (a second
    /// round of calls reads them back).
    #[test]
    fn a_memo_changes_no_value() {
        use crate::material::microfacet::{Microfacet, MicrofacetType};
        use crate::material::{RoughPlastic, TextureMemo};
        let plastic = RoughPlastic::new(
            Microfacet::new(MicrofacetType::Beckmann, 0.3, 0.3),
            ramp(glam::Mat3::IDENTITY),
            Rgb::ONE,
            1.5,
            false,
        );
        let bump = Bsdf::Perturbed(Perturbed {
            perturbation: Perturbation::BumpMap { height: ramp(glam::Mat3::from_scale(Vec2::splat(3.0))), scale: 0.2 },
            bsdf: Arc::new(Bsdf::RoughPlastic(plastic)),
            flip_invalid_normals: true,
            shadowing: true,
        });
        let bits = |c: Rgb| c.to_array().map(f32::to_bits);
        for k in 0..50 {
            let si = flat_hit(Vec2::new(0.02 * k as f32, 0.5));
            let plain = BsdfContext { uv: si.uv, mesh: None, textures: None, si: Some(&si), memo: None };
            let memo = TextureMemo::default();
            let kept = plain.with_memo(&memo);
            let wo = Vec3::new(0.3 - 0.01 * k as f32, 0.2, 0.8).normalize();
            for round in 0..2 {
                let u = Vec2::new(0.37, 0.01 + 0.019 * k as f32);
                let (a, b) = (bump.sample(&plain, wo, 0.4, u), bump.sample(&kept, wo, 0.4, u));
                assert_eq!(
                    a.map(|s| (bits(s.wi), s.pdf.to_bits(), bits(s.weight))),
                    b.map(|s| (bits(s.wi), s.pdf.to_bits(), bits(s.weight))),
                    "k {k}, round {round}"
                );
                let wi = Vec3::new(-0.4, 0.1 * k as f32 / 50.0, 0.9).normalize();
                assert_eq!(bits(bump.eval(&plain, wo, wi)), bits(bump.eval(&kept, wo, wi)), "k {k}, round {round}");
                assert_eq!(
                    bump.pdf(&plain, wo, wi).to_bits(),
                    bump.pdf(&kept, wo, wi).to_bits(),
                    "k {k}, round {round}"
                );
            }
        }
    }

    /// A bump map's normal on a flat surface with `∂p/∂u = (2, 0, 0)`, `∂p/∂v = (0, 2, 0)`: a
    /// height slope `g` along u (scale included) tilts it to `(−g/2, 0, 1)`, normalized; flipping
    /// the geometric normal's side flips the result back onto it.
    #[test]
    fn bump_maps_tilt_by_the_height_slope() {
        // Slope of the height field along u: 1, times scale 0.3.
        let bump = perturbed(Perturbation::BumpMap { height: ramp(glam::Mat3::IDENTITY), scale: 0.3 });
        let si = flat_hit(Vec2::new(0.5, 0.5));
        let ctx = BsdfContext { uv: si.uv, mesh: None, textures: None, si: Some(&si), memo: None };
        let n = bump.frame(&ctx, Vec3::Z).n;
        let expected = Vec3::new(-0.15, 0.0, 1.0).normalize();
        assert!((n - expected).length() < 1e-5, "{n} vs {expected}");
        let below = crate::geometry::SurfaceInteraction { ng: -Vec3::Z, ..si };
        let ctx = BsdfContext { uv: si.uv, mesh: None, textures: None, si: Some(&below), memo: None };
        assert!(bump.frame(&ctx, Vec3::Z).n.z < 0.0, "turned to the geometric normal's side");
    }

    /// A bump map of zero height leaves even a strongly anisotropic BSDF as it is, on a surface
    /// whose tangent has any orientation in the world: the perturbed frame is built in the
    /// shading frame (its tangent the shading tangent made perpendicular to the new normal).
    /// Mitsuba 3.9.1's `normalmap` builds it so (an identity map leaves its BSDFs as they are);
    /// its `bumpmap` builds that tangent from the world ∂p/∂u read as local coordinates (its
    /// `frame()`), so there a bump of scale 0 changes the BSDF:
    /// measured, a rectangle turned 60° about z and −60° about x under an Ag conductor of α
    /// (0.05, 0.5) lit by a point light renders 0.0137 plain and 9e-19 under the bump map.
    #[test]
    fn a_zero_bump_leaves_an_anisotropic_bsdf_unchanged_whatever_the_tangent() {
        use crate::material::microfacet::{Microfacet, MicrofacetType};
        use crate::material::{ConductorIor, RoughConductor};
        let conductor = Arc::new(Bsdf::RoughConductor(RoughConductor {
            roughness: Microfacet::new(MicrofacetType::Beckmann, 0.05, 0.5).into(),
            ior: Some(ConductorIor::constant(Rgb::new(0.155, 0.117, 0.138), Rgb::new(4.83, 3.12, 2.15))),
            specular_reflectance: Rgb::ONE.into(),
        }));
        let bump = Bsdf::Perturbed(Perturbed {
            perturbation: Perturbation::BumpMap { height: ramp(glam::Mat3::IDENTITY), scale: 0.0 },
            bsdf: conductor.clone(),
            flip_invalid_normals: true,
            shadowing: true,
        });
        let n = Vec3::new(0.0, 0.866_025_4, 0.5);
        let dpdu = Vec3::new(0.5, 0.433_012_7, -0.75);
        let si = crate::geometry::SurfaceInteraction {
            ng: n,
            ns: n,
            dpdu,
            dpdv: n.cross(dpdu),
            ..flat_hit(Vec2::splat(0.5))
        };
        let ctx = BsdfContext { uv: si.uv, mesh: None, textures: None, si: Some(&si), memo: None };
        let mut rng = crate::sampling::Pcg32::new(3, 0);
        let mut compared = 0;
        for _ in 0..200 {
            let mut dir = || {
                let (a, b) = (rng.next_f32() * std::f32::consts::TAU, rng.next_f32());
                Vec3::new(a.cos() * (1.0 - b * b).sqrt(), a.sin() * (1.0 - b * b).sqrt(), b.max(0.05)).normalize()
            };
            let (wo, wi) = (dir(), dir());
            let (a, b) = (bump.eval(&ctx, wo, wi), conductor.eval(&ctx, wo, wi));
            assert!((a - b).abs().max_element() <= 1e-4 * b.max_element().max(1e-3), "{wo} {wi}: {a} vs {b}");
            let (pa, pb) = (bump.pdf(&ctx, wo, wi), conductor.pdf(&ctx, wo, wi));
            assert!((pa - pb).abs() <= 1e-4 * pb.max(1e-3), "{wo} {wi}: pdf {pa} vs {pb}");
            compared += usize::from(b.max_element() > 1e-3);
        }
        assert!(compared > 20, "{compared}");
    }

    /// pbrt-v4's displacement: the same ramp as a displacement of 0.3 world units per unit of
    /// u tilts the normal as the bump map's slope does (forward differences agree with the
    /// bilinear slope inside a texel), a constant displacement tilts nothing, and a ramp along v
    /// tilts it about the other axis.
    #[test]
    fn displacement_tilts_by_its_forward_difference() {
        let displaced = |displacement: Texture| perturbed(Perturbation::Displacement { displacement });
        let si = flat_hit(Vec2::new(0.5, 0.4));
        let ctx = BsdfContext { uv: si.uv, mesh: None, textures: None, si: Some(&si), memo: None };
        let along_u = displaced(ramp(glam::Mat3::IDENTITY).times(Texture::Constant(Rgb::splat(0.3))));
        let n = along_u.frame(&ctx, Vec3::Z).n;
        let expected = Vec3::new(-0.15, 0.0, 1.0).normalize();
        assert!((n - expected).length() < 1e-3, "{n} vs {expected}");
        let flat = displaced(Texture::Constant(Rgb::splat(0.7)));
        assert!((flat.frame(&ctx, Vec3::Z).n - Vec3::Z).length() < 1e-6);
        // The image's s along v: uv (u, v) ↦ (v, u).
        let swap = glam::Mat3::from_cols(glam::Vec3::Y, glam::Vec3::X, glam::Vec3::Z);
        let along_v = displaced(ramp(swap));
        let n = along_v.frame(&ctx, Vec3::Z).n;
        let expected = Vec3::new(0.0, -0.5, 1.0).normalize();
        assert!((n - expected).length() < 1e-3, "{n} vs {expected}");
    }

    /// An unperturbing map ((0.5, 0.5, 1): the normal +z) leaves the BSDF as it is; a tilted
    /// one makes the diffuse cosine about the tilted normal, and lets nothing through from below
    /// the original surface (no light leaks) even where the tilted normal faces it.
    #[test]
    fn frames_and_leaks() {
        let diffuse = Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.6)));
        let flat = map(Vec3::Z, diffuse.clone(), true);
        let (wo, wi) = (Vec3::new(0.2, 0.1, 0.97).normalize(), Vec3::new(-0.5, 0.3, 0.81).normalize());
        assert!((flat.eval(&ctx(), wo, wi) - diffuse.eval(&ctx(), wo, wi)).abs().max_element() < 1e-6);
        let n = Vec3::new(0.6, 0.0, 0.8);
        let tilted = map(n, diffuse.clone(), false);
        let f = tilted.eval(&ctx(), wo, wi).x;
        assert!((f - 0.6 / std::f32::consts::PI * wi.dot(n)).abs() < 1e-5, "{f}");
        // The shadowing function: Mitsuba 3.9.1's BSDF value over its pdf for a diffuse under
        // a normal with cos θₙ = 0.76128 and a light at cos θᵢ = 0.69171 was 0.97644.
        let g = shadow_terminator(
            Vec3::new((1.0f32 - 0.76128 * 0.76128).sqrt(), 0.0, 0.76128),
            Vec3::new((1.0f32 - 0.69171 * 0.69171).sqrt(), 0.0, 0.69171),
        );
        assert!((g - 0.97644).abs() < 1e-4, "{g}");
        let shadowed = map(n, diffuse, true);
        let ratio = shadowed.eval(&ctx(), wo, wi).x / f;
        assert!((ratio - shadow_terminator(n, wi)).abs() < 1e-5, "{ratio}");
        // A normal facing away from the viewer is turned toward it: the viewer at grazing
        // +x sees the surface lit, not black.
        let away = map(Vec3::new(-0.8, 0.0, 0.6), Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.6))), false);
        let wo_grazing = Vec3::new(0.95, 0.0, 0.31).normalize();
        assert!(away.eval(&ctx(), wo_grazing, Vec3::Z).x > 0.0);
        // Above the tilted normal but below the surface: nothing, in eval, pdf and sampling.
        let below = Vec3::new(0.9, 0.0, -0.1).normalize();
        assert!(below.dot(n) > 0.0);
        assert_eq!(tilted.eval(&ctx(), wo, below), Rgb::ZERO);
        assert_eq!(tilted.pdf(&ctx(), wo, below), 0.0);
        let mut rng = crate::sampling::Pcg32::new(5, 1);
        for _ in 0..1000 {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            if let Some(s) = tilted.sample(&ctx(), wo, rng.next_f32(), u) {
                assert!(s.wi.z > 0.0, "a sample below the surface: {}", s.wi);
            }
        }
    }
}
