//! BSDFs in SIMD lanes, for the path tracer's lanes (`integrator::path_lanes`):
//! one BSDF per lane with that lane's parameters, evaluated and sampled for all lanes at once
//! by the scalar code's operations in the scalar code's order, so that each lane gets exactly
//! the bits the scalar BSDF gives (the tests below hold them to it). What has no lane form
//! (Beckmann's slope inversion, `erf`, the exponential) runs lane by lane with the scalar
//! functions.
//!
//! All directions are in each lane's local shading frame (normal +z), as the scalar BSDFs take
//! them; values are `f |cos θᵢ|`, densities per unit solid angle of `wi`.

use super::conductor::RoughConductor;
use super::fresnel::fresnel_conductor_channel;
use super::microfacet::{beckmann_lambda, Microfacet, MicrofacetType, BECKMANN_LAMBDA_ZERO};
use crate::math::lanes::{ones, Fw, Mw, V3w};
use crate::math::special::exp;
use crate::math::{Vec2, Vec3, PI};
use crate::texture::Texture;

/// A sample of [`RoughConductorW::sample`] in every lane (where `ok`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SampleW<const W: usize> {
    /// The sampled direction (local frame).
    pub wi: V3w<W>,
    /// Its density per unit solid angle.
    pub pdf: Fw<W>,
    /// `f |cos θᵢ| / pdf`.
    pub weight: V3w<W>,
    /// The lanes that have a sample (the scalar `sample` gave `Some`).
    pub ok: Mw<W>,
}

/// Mitsuba's `roughconductor` with constant parameters in each lane ([`RoughConductor`]: GGX
/// or Beckmann visible-normal sampling, Smith's separable masking, the conductor's exact
/// Fresnel term in double precision).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RoughConductorW<const W: usize> {
    /// Roughness along the tangent (x) and the bitangent (y).
    alpha_u: Fw<W>,
    alpha_v: Fw<W>,
    /// The GGX lanes and the Beckmann lanes (lanes in neither hold no BSDF: what they compute
    /// is never used).
    ggx: Mw<W>,
    beckmann: Mw<W>,
    /// The lanes with a complex index of refraction `eta + i k` (the others reflect all light:
    /// a Fresnel term of 1).
    fresnel: Mw<W>,
    eta: V3w<W>,
    k: V3w<W>,
    /// `specular_reflectance`.
    scale: V3w<W>,
}

impl<const W: usize> Default for RoughConductorW<W> {
    fn default() -> Self {
        let one = Fw::splat(1.0);
        RoughConductorW {
            alpha_u: one,
            alpha_v: one,
            ggx: Mw::NONE,
            beckmann: Mw::NONE,
            fresnel: Mw::NONE,
            eta: V3w::splat(Vec3::ONE),
            k: V3w::splat(Vec3::ZERO),
            scale: V3w::splat(Vec3::ONE),
        }
    }
}

/// The constant of a texture (`None` for the others).
fn constant(t: &Texture) -> Option<Vec3> {
    match t {
        Texture::Constant(c) => Some(*c),
        _ => None,
    }
}

impl<const W: usize> RoughConductorW<W> {
    /// No lane holds a conductor any more (their parameters stay, unused, until `set` again).
    #[inline(always)]
    pub fn clear(&mut self) {
        (self.ggx, self.beckmann, self.fresnel) = (Mw::NONE, Mw::NONE, Mw::NONE);
    }

    /// Puts `b` into lane `k`, if its parameters are constant and its distribution GGX or
    /// Beckmann (what the lanes compute); `false` (lane `k` untouched) otherwise. (Not inlined:
    /// its checks, inlined into the lanes' loop, cost every other lane instructions.)
    #[inline(never)]
    pub fn set(&mut self, k: usize, b: &RoughConductor) -> bool {
        let d = b.roughness.distribution;
        let ggx = match d.kind {
            MicrofacetType::Ggx => true,
            MicrofacetType::Beckmann => false,
            MicrofacetType::BlinnPhong(_) => return false,
        };
        let Some(scale) = constant(&b.specular_reflectance) else { return false };
        if b.roughness.textures.is_some() {
            return false;
        }
        let (eta, kk) = match &b.ior {
            None => (Vec3::ONE, Vec3::ZERO),
            Some(ior) => match (constant(&ior.eta), constant(&ior.k)) {
                (Some(eta), Some(kk)) => (eta, kk),
                _ => return false,
            },
        };
        (self.alpha_u.0[k], self.alpha_v.0[k]) = (d.alpha_u, d.alpha_v);
        self.ggx.0[k] = if ggx { u32::MAX } else { 0 };
        self.beckmann.0[k] = if ggx { 0 } else { u32::MAX };
        self.fresnel.0[k] = if b.ior.is_some() { u32::MAX } else { 0 };
        set(&mut self.eta, k, eta);
        set(&mut self.k, k, kk);
        set(&mut self.scale, k, scale);
        true
    }

    /// [`RoughConductor::eval_pdf`] in the lanes: `f |cos θᵢ|` and the density of `wi`.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: V3w<W>, wi: V3w<W>) -> (V3w<W>, Fw<W>) {
        let zero = Fw::splat(0.0);
        let below = wo.z.le(zero) | wi.z.le(zero);
        let m = (wo + wi).normalize();
        let (d, g1_o) = (self.d(m), self.g1(wo, m));
        // `Microfacet::pdf_given` for wo above the surface, over the reflection's Jacobian.
        let pdf = g1_o * wo.dot(m).max(zero) * d / wo.z / (4.0 * wo.dot(m).abs());
        let g = self.g1(wi, m) * g1_o;
        let f = self.fresnel(wi.dot(m));
        let value = (self.scale * f).scale(d * g / (4.0 * wo.z));
        let value = V3w::select(below | d.eq(zero), V3w::splat(Vec3::ZERO), value);
        (value, Fw::select(below, zero, pdf))
    }

    /// [`RoughConductor::sample`] in the lanes, from the random numbers `u`: a visible
    /// microfacet normal, reflected.
    #[inline(always)]
    pub fn sample(&self, wo: V3w<W>, ux: Fw<W>, uy: Fw<W>) -> SampleW<W> {
        let zero = Fw::splat(0.0);
        let m = self.sample_normal(wo, ux, uy);
        // `Microfacet::pdf`: the visible normal density (wo is above the surface where it counts).
        let front = !(wo.dot(m) * wo.z).le(zero);
        let g1_wo = Fw::select(front, 1.0 / (1.0 + self.lambda(wo)), zero);
        let m_pdf = Fw::select(wo.z.le(zero), zero, g1_wo * wo.dot(m).max(zero) * self.d(m) / wo.z);
        let wi = m.scale(2.0 * wo.dot(m)) - wo;
        let pdf = m_pdf / (4.0 * wo.dot(m).abs());
        // f cos θᵢ / pdf = F G1(wi, m): D and G1(wo) cancel (visible normals).
        let weight = (self.scale * self.fresnel(wi.dot(m))).scale(self.g1(wi, m));
        let finite = weight.x.is_finite() & weight.y.is_finite() & weight.z.is_finite();
        let ok = !wo.z.le(zero) & !m_pdf.le(zero) & !wi.z.le(zero) & pdf.gt(zero) & finite;
        SampleW { wi, pdf, weight, ok }
    }

    /// A visible normal for `wo` in each lane ([`Microfacet::sample`]'s): GGX's in lanes,
    /// Beckmann's lane by lane.
    #[inline(always)]
    fn sample_normal(&self, wo: V3w<W>, ux: Fw<W>, uy: Fw<W>) -> V3w<W> {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let mut m = V3w::splat(Vec3::Z);
        if self.ggx.any() {
            // Heitz 2018, as `GgxView`: the stretched direction, the frame around it, the
            // disk point warped toward the projected hemisphere, lifted and unstretched.
            let zero = Fw::splat(0.0);
            let vh = V3w::new(au * wo.x, av * wo.y, wo.z).normalize();
            let lensq = vh.x * vh.x + vh.y * vh.y;
            let tilted = lensq.gt(zero);
            let len = lensq.sqrt();
            let t1 = V3w::select(tilted, V3w::new(-vh.y / len, vh.x / len, zero / len), V3w::splat(Vec3::X));
            let t2 = vh.cross(t1);
            let s = 0.5 * (1.0 + vh.z);
            let phi = 2.0 * PI * uy;
            let (mut cos_phi, mut sin_phi) = (zero, zero);
            for k in ones(self.ggx) {
                (cos_phi.0[k], sin_phi.0[k]) = (phi.0[k].cos(), phi.0[k].sin());
            }
            let r = ux.sqrt();
            let p1 = r * cos_phi;
            let p2 = (1.0 - s) * (1.0 - p1 * p1).max(zero).sqrt() + s * (r * sin_phi);
            let nh = t1.scale(p1) + t2.scale(p2) + vh.scale((1.0 - p1 * p1 - p2 * p2).max(zero).sqrt());
            m = V3w::new(au * nh.x, av * nh.y, nh.z.max(Fw::splat(1e-6))).normalize();
        }
        for k in ones(self.beckmann) {
            let md = Microfacet { kind: MicrofacetType::Beckmann, alpha_u: au.0[k], alpha_v: av.0[k] };
            let n = md.sample_visible_normal(wo.lane(k), Vec2::new(ux.0[k], uy.0[k]));
            set(&mut m, k, n);
        }
        m
    }

    /// [`Microfacet::d`] in the lanes.
    #[inline(always)]
    fn d(&self, m: V3w<W>) -> Fw<W> {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let cos2 = m.z * m.z;
        let (x, y) = (m.x / au, m.y / av);
        let s = x * x + y * y + cos2;
        let ggx = 1.0 / (PI * au * av * s * s);
        let mut r = ggx;
        if self.beckmann.any() {
            let e = (x * x + y * y) / cos2;
            let denominator = PI * au * av * cos2 * cos2;
            for k in ones(self.beckmann) {
                r.0[k] = exp(-e.0[k]) / denominator.0[k];
            }
        }
        let zero = Fw::splat(0.0);
        Fw::select(m.z.le(zero) | !r.is_finite(), zero, r)
    }

    /// Smith's `Λ(w)` in the lanes ([`Microfacet`]'s).
    #[inline(always)]
    fn lambda(&self, w: V3w<W>) -> Fw<W> {
        let zero = Fw::splat(0.0);
        let (x, y) = (self.alpha_u * w.x, self.alpha_v * w.y);
        let xy_alpha2 = x * x + y * y;
        let tan2_alpha2 = xy_alpha2 / (w.z * w.z);
        let mut r = 0.5 * (-1.0 + (1.0 + tan2_alpha2).sqrt());
        if self.beckmann.any() {
            let a = 1.0 / tan2_alpha2.sqrt();
            for k in ones(self.beckmann) {
                r.0[k] = if a.0[k] >= BECKMANN_LAMBDA_ZERO { 0.0 } else { beckmann_lambda(a.0[k]) };
            }
        }
        Fw::select(xy_alpha2.eq(zero), zero, r)
    }

    /// Smith's `G1(w, m)` in the lanes: 0 where `w` sees the back of `m` or of the surface.
    #[inline(always)]
    fn g1(&self, w: V3w<W>, m: V3w<W>) -> Fw<W> {
        let zero = Fw::splat(0.0);
        Fw::select((w.dot(m) * w.z).le(zero), zero, 1.0 / (1.0 + self.lambda(w)))
    }

    /// The Fresnel term at `cos θ` in each lane: [`super::fresnel::fresnel_conductor`] where the
    /// lane has an index of refraction, 1 elsewhere.
    #[inline(always)]
    fn fresnel(&self, cos_theta: Fw<W>) -> V3w<W> {
        if !self.fresnel.any() {
            return V3w::splat(Vec3::ONE);
        }
        let f = V3w::new(
            fresnel_conductor(self.fresnel, cos_theta, self.eta.x, self.k.x),
            fresnel_conductor(self.fresnel, cos_theta, self.eta.y, self.k.y),
            fresnel_conductor(self.fresnel, cos_theta, self.eta.z, self.k.z),
        );
        V3w::select(self.fresnel, f, V3w::splat(Vec3::ONE))
    }
}

/// [`super::fresnel::fresnel_conductor`] of one channel in the lanes of `lanes` (0 in the
/// others), lane by lane by the same function.
#[inline(always)]
fn fresnel_conductor<const W: usize>(lanes: Mw<W>, cos_theta_i: Fw<W>, eta: Fw<W>, k: Fw<W>) -> Fw<W> {
    let mut out = [0.0f32; W];
    for i in ones(lanes) {
        out[i] = fresnel_conductor_channel(cos_theta_i.0[i], eta.0[i], k.0[i]);
    }
    Fw(out)
}

/// Writes `c` into lane `k` of `v`.
#[inline(always)]
fn set<const W: usize>(v: &mut V3w<W>, k: usize, c: Vec3) {
    (v.x.0[k], v.y.0[k], v.z.0[k]) = (c.x, c.y, c.z);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{BsdfContext, ConductorIor};
    use crate::material::microfacet::Roughness;
    use crate::math::Rgb;
    use crate::sampling::Pcg32;

    /// Random rough conductors: GGX and Beckmann, isotropic and not, from near-mirrors to very
    /// rough, with a complex index or a perfect mirror, and a reflectance scale.
    fn conductor(rng: &mut Pcg32) -> RoughConductor {
        let mut r = || rng.next_f32();
        let kind = if r() < 0.5 { MicrofacetType::Ggx } else { MicrofacetType::Beckmann };
        let alpha = |x: f32| 0.002 + x * x * 1.2;
        let (au, av) = (alpha(r()), if r() < 0.5 { alpha(r()) } else { -1.0 });
        let av = if av < 0.0 { au } else { av };
        let ior = (r() < 0.8).then(|| {
            ConductorIor::constant(Rgb::new(0.1 + 2.0 * r(), 0.2 + r(), 1.5 * r()), Rgb::new(5.0 * r(), 3.0 * r(), 1.0 + r()))
        });
        RoughConductor {
            roughness: Roughness::from(Microfacet::new(kind, au, av)),
            ior,
            specular_reflectance: Rgb::new(r(), 0.5 + 0.5 * r(), 1.0).into(),
        }
    }

    /// A direction of the sphere, mostly above the surface, sometimes grazing or below.
    fn direction(rng: &mut Pcg32) -> Vec3 {
        let z = match rng.next_u32() % 8 {
            0 => -rng.next_f32(),
            1 => 1e-4 * rng.next_f32(),
            _ => rng.next_f32(),
        };
        let phi = 2.0 * PI * rng.next_f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }

    fn bits(v: Vec3) -> [u32; 3] {
        v.to_array().map(f32::to_bits)
    }

    /// Value, density and sample of each lane are the scalar `RoughConductor`'s bit for bit,
    /// at widths 4, 8 and 16, GGX, Beckmann and empty lanes mixed.
    #[test]
    fn rough_conductor_lanes_are_the_scalar_bsdf() {
        fn check<const W: usize>(rng: &mut Pcg32) {
            let ctx = BsdfContext::default();
            let mut compared = [0usize; 2];
            for _ in 0..2000 / W {
                let bsdfs: Vec<RoughConductor> = (0..W).map(|_| conductor(rng)).collect();
                // Some lanes hold no conductor (in a batch, other BSDFs' lanes): their garbage
                // must not reach the others.
                let held: Vec<bool> = (0..W).map(|_| !rng.next_u32().is_multiple_of(4)).collect();
                let mut lanes = RoughConductorW::<W>::default();
                for (k, b) in bsdfs.iter().enumerate() {
                    if held[k] {
                        assert!(lanes.set(k, b));
                    }
                }
                let wo: Vec<Vec3> = (0..W).map(|_| direction(rng)).collect();
                let wi: Vec<Vec3> = (0..W).map(|_| direction(rng)).collect();
                let u: Vec<Vec2> = (0..W).map(|_| Vec2::new(rng.next_f32(), rng.next_f32())).collect();
                let (wo_w, wi_w) = (V3w::<W>::from_fn(|k| wo[k]), V3w::<W>::from_fn(|k| wi[k]));
                let (f, pdf) = lanes.eval_pdf(wo_w, wi_w);
                let s = lanes.sample(wo_w, Fw::from_fn(|k| u[k].x), Fw::from_fn(|k| u[k].y));
                for k in (0..W).filter(|&k| held[k]) {
                    let (want_f, want_pdf) = bsdfs[k].eval_pdf(&ctx, wo[k], wi[k]);
                    assert_eq!(bits(f.lane(k)), bits(want_f), "value, lane {k}: {:?} {} {}", bsdfs[k], wo[k], wi[k]);
                    assert_eq!(pdf.0[k].to_bits(), want_pdf.to_bits(), "density, lane {k}");
                    assert_eq!(bits(bsdfs[k].eval(&ctx, wo[k], wi[k])), bits(want_f), "eval and eval_pdf agree");
                    match bsdfs[k].sample(&ctx, wo[k], u[k]) {
                        Some(bs) => {
                            assert!(s.ok.test(k), "lane {k} has no sample where the scalar BSDF has one");
                            assert_eq!(bits(s.wi.lane(k)), bits(bs.wi), "sampled direction, lane {k}");
                            assert_eq!(s.pdf.0[k].to_bits(), bs.pdf.to_bits(), "sample density, lane {k}");
                            assert_eq!(bits(s.weight.lane(k)), bits(bs.weight), "sample weight, lane {k}");
                            compared[0] += 1;
                        }
                        None => {
                            assert!(!s.ok.test(k), "lane {k} has a sample where the scalar BSDF has none");
                            compared[1] += 1;
                        }
                    }
                }
            }
            // Both outcomes occur often enough to mean something.
            assert!(compared[0] > 800 && compared[1] > 100, "{compared:?}");
        }
        let mut rng = Pcg32::new(11, 5);
        check::<4>(&mut rng);
        check::<8>(&mut rng);
        check::<16>(&mut rng);
    }

    /// Textured or Blinn–Phong conductors stay out of the lanes.
    #[test]
    fn only_constant_ggx_and_beckmann_take_a_lane() {
        let mut lanes = RoughConductorW::<4>::default();
        let mut b = conductor(&mut Pcg32::new(1, 1));
        assert!(lanes.set(0, &b));
        b.roughness = Roughness::from(Microfacet::blinn_phong(20.0));
        assert!(!lanes.set(1, &b));
        b.roughness = Roughness::from(Microfacet::new(MicrofacetType::Ggx, 0.1, 0.1));
        b.specular_reflectance = Texture::MeshAttribute { name: "vertex_color".into(), scale: 1.0 };
        assert!(!lanes.set(2, &b));
    }
}
