//! pbrt-v4's layered BSDF (`coateddiffuse`, `coatedconductor`): a dielectric coating of
//! thickness `thickness` over a diffuse or conductor base, with an optional scattering medium
//! (albedo `albedo`, Henyey–Greenstein `g`, unit extinction) between them, evaluated and
//! sampled by random walks between the two interfaces (Guo et al. 2018, "Position-Free Monte
//! Carlo Simulation for Arbitrary Layered BSDFs", as pbrt-v4 §14.3 implements it).
//!
//! - [`Layered::sample`] walks from `wo` until the path leaves the layers (at most
//!   `max_depth` scattering events, with Russian roulette past 3): its weight `f |cos θᵢ| / p`
//!   is exact for the walk taken. The pdf it returns is [`Layered::pdf`]'s estimate (for MIS),
//!   not the walk's density, which has no closed form.
//! - [`Layered::eval`] estimates `f(wo, wi) |cos θᵢ|` with `nsamples` bidirectional walks
//!   (the walk from `wo` joined to one sampled from `wi` by next-event estimation at the
//!   interfaces and in the medium, MIS-weighted): unbiased, so the image converges to the
//!   layered model.
//! - [`Layered::pdf`] estimates the density of the reflection and the first
//!   transmission–reflection–transmission lobe and mixes it 9:1 with the uniform sphere
//!   (pbrt's `Lerp(0.9, 1/4π, ·)`), so it is positive everywhere `eval` may be.
//!
//! One deliberate difference from pbrt-v4: where `eval` joins a direction sampled at the base
//! (or in the medium) to `wi` through a rough coating, pbrt weights that strategy against the
//! other (the direction sampled from `wi`) with the coating's density of `wi` given the
//! direction, a density of a different variable; the two MIS weights then do not sum to one,
//! and pbrt's `eval` of a rough coating exceeds what its own sampling delivers (by 6–10 % of
//! the light through the coating at α = 0.3–0.6, measured here). neumann weights with the other
//! strategy's density of the same direction, and `eval` and `sample` agree (tested).
//!
//! The random numbers beyond the three a BSDF sample takes come from a PCG32 seeded by a hash
//! of the query (`wo`, and the sample's numbers or `wi`): every call is a deterministic
//! function of its arguments, as pbrt-v4 does it. Two-sided, like pbrt's coated materials
//! (seen from below, both directions are mirrored).
//!
//! Units: `thickness` in units of the medium's mean free path (extinction 1), so with no
//! medium (`albedo` 0) each crossing still attenuates by `exp(-thickness / |cos θ|)`, as in
//! pbrt-v4 (default 0.01).

mod interface;
#[cfg(test)]
mod tests;

pub use interface::{Interface, Lobes, Mode};

use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample, ConductorIor};
use crate::material::microfacet::{Microfacet, MicrofacetType};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Rgb, Vec2, Vec3, INV_4PI, ONE_MINUS_EPSILON};
use crate::medium::phase::PhaseFunction;
use crate::props::{Obj, Result as PropResult};
use crate::sampling::hash::hash;
use crate::sampling::rng::Pcg32;
use crate::texture::Texture;
use interface::rough_or_smooth;

/// The base under the coating.
#[derive(Clone, Debug)]
pub enum Base {
    /// Lambertian, of albedo `reflectance` (pbrt's `coateddiffuse`).
    Diffuse {
        /// Albedo (texturable).
        reflectance: Texture,
    },
    /// A conductor (pbrt's `coatedconductor`); its index is relative to the outside and
    /// divided by the coating's at the shading point, as pbrt-v4 does.
    Conductor {
        /// Complex index of refraction.
        ior: ConductorIor,
        /// GGX roughness `(α_u, α_v)` (textures; below 10⁻³ smooth).
        alpha: Box<[Texture; 2]>,
    },
}

/// A layered BSDF (pbrt-v4's `LayeredBxDF` with a dielectric top).
#[derive(Clone, Debug)]
pub struct Layered {
    /// Relative index of refraction of the coating.
    pub eta: f32,
    /// GGX roughness of the coating `(α_u, α_v)` (textures; below 10⁻³ smooth).
    pub alpha: Box<[Texture; 2]>,
    /// The base.
    pub base: Base,
    /// Thickness of the layer in mean free paths (scalar texture, > 0).
    pub thickness: Texture,
    /// Single-scattering albedo of the medium between the interfaces (`None`: no medium).
    pub albedo: Option<Texture>,
    /// Henyey–Greenstein asymmetry of the medium (scalar texture).
    pub g: Texture,
    /// Maximum number of scattering events of a walk.
    pub max_depth: u32,
    /// Number of walks per evaluation.
    pub n_samples: u32,
    /// Whether the coating's and a conductor base's roughness are regularized (pbrt-v4's
    /// `LayeredBxDF::Regularize`, [`super::microfacet::regularize_alpha`]).
    pub regularized: bool,
}

/// The layered BSDF's parameters at one shading point.
#[derive(Clone, Copy, Debug)]
struct Stack {
    top: Interface,
    bottom: Interface,
    thickness: f32,
    albedo: Option<Rgb>,
    /// The medium's Henyey–Greenstein asymmetry (see [`Stack::phase`]).
    phase_g: f32,
    max_depth: u32,
    n_samples: u32,
}

/// A direction sampled by a walk: its weight `f |cos θᵢ| / p`, and `p` itself (meaningful
/// as a density only for specular walks, where it is the product of lobe probabilities).
#[derive(Clone, Copy, Debug)]
struct WalkSample {
    wi: Vec3,
    weight: Rgb,
    pdf: f32,
    specular: bool,
}

/// Seed of the walks' random numbers (pbrt's `GetOptions().seed` is 0 by default).
const SEED: u64 = 0x006c_6179_6572_6564;

fn bits(v: Vec3) -> u64 {
    hash(&[v.x.to_bits() as u64, v.y.to_bits() as u64, v.z.to_bits() as u64])
}

/// Uniform numbers in `[0, 1)` from a generator (pbrt's `min(Uniform, OneMinusEpsilon)`).
fn uniform(rng: &mut Pcg32) -> f32 {
    rng.next_f32().min(ONE_MINUS_EPSILON)
}

/// Transmittance through a slab of height `dz` along `w` (extinction 1).
fn tr(dz: f32, w: Vec3) -> f32 {
    if dz.abs() <= f32::MIN_POSITIVE {
        1.0
    } else {
        (-(dz / w.z).abs()).exp()
    }
}

/// Veach's power heuristic with one sample of each strategy.
fn power_heuristic(f: f32, g: f32) -> f32 {
    crate::sampling::power_heuristic(1, f, 1, g)
}

fn mirror(w: Vec3) -> Vec3 {
    -w
}

impl Layered {
    /// The parameters at `ctx`.
    fn at(&self, ctx: &BsdfContext) -> Stack {
        let scalar = |t: &Texture| ctx.scalar(t);
        let alpha = |t: &Texture| {
            let a = scalar(t);
            if self.regularized {
                super::microfacet::regularize_alpha(a)
            } else {
                a
            }
        };
        let ggx = |a: &[Texture; 2]| rough_or_smooth(Microfacet::new(MicrofacetType::Ggx, alpha(&a[0]), alpha(&a[1])));
        let top = Interface::Dielectric { eta: self.eta, mf: ggx(&self.alpha) };
        let bottom = match &self.base {
            Base::Diffuse { reflectance } => Interface::Diffuse { r: ctx.eval(reflectance).clamp(Rgb::ZERO, Rgb::ONE) },
            Base::Conductor { ior, alpha } => Interface::Conductor {
                eta: ctx.eval(&ior.eta) / self.eta,
                k: ctx.eval(&ior.k) / self.eta,
                mf: ggx(alpha),
            },
        };
        Stack {
            top,
            bottom,
            thickness: scalar(&self.thickness).max(f32::MIN_POSITIVE),
            albedo: self.albedo.as_ref().map(|a| ctx.eval(a)).filter(|a| a.max_element() > 0.0),
            phase_g: scalar(&self.g).clamp(-0.99, 0.99),
            max_depth: self.max_depth,
            n_samples: self.n_samples.max(1),
        }
    }

    /// `f(wo, wi) |cos θᵢ|`, estimated by random walks (deterministic in `wo`, `wi`).
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        let v = self.at(ctx).f(wo, wi, Mode::Radiance) * wi.z.abs();
        if v.is_finite() {
            v.max(Rgb::ZERO)
        } else {
            Rgb::ZERO
        }
    }

    /// The density estimate used for MIS (deterministic in `wo`, `wi`).
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        let p = self.at(ctx).pdf(wo, wi, Mode::Radiance);
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    /// Samples `wi` by a random walk through the layers.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        let stack = self.at(ctx);
        let s = stack.sample(wo, u1, u, Mode::Radiance)?;
        let weight = s.weight;
        if !weight.is_finite() || weight.max_element() <= 0.0 {
            return None;
        }
        if s.specular {
            return Some(BsdfSample { wi: s.wi, pdf: s.pdf, weight, delta: true, null: false, eta: 1.0 });
        }
        let pdf = stack.pdf(wo, s.wi, Mode::Radiance);
        (pdf > 0.0 && pdf.is_finite()).then_some(BsdfSample { wi: s.wi, pdf, weight, delta: false, null: false, eta: 1.0 })
    }

    /// Whether every walk is specular (smooth coating over a smooth conductor, no medium).
    pub fn is_delta(&self) -> bool {
        let smooth = |a: &[Texture; 2]| a.iter().all(|t| matches!(t, Texture::Constant(c) if c.max_element() < 1e-3));
        smooth(&self.alpha)
            && matches!(&self.base, Base::Conductor { alpha, .. } if smooth(alpha))
            && self.albedo.as_ref().is_none_or(|a| matches!(a, Texture::Constant(c) if c.max_element() <= 0.0))
    }

    /// Its textures.
    pub fn textures(&self) -> Vec<&Texture> {
        let mut v: Vec<&Texture> = self.alpha.iter().collect();
        v.push(&self.thickness);
        v.push(&self.g);
        v.extend(self.albedo.iter());
        match &self.base {
            Base::Diffuse { reflectance } => v.push(reflectance),
            Base::Conductor { ior, alpha } => {
                v.extend([&ior.eta, &ior.k]);
                v.extend(alpha.iter());
            }
        }
        v
    }

    /// The base's diffuse albedo (the `albedo` AOV), black for a conductor base.
    pub fn diffuse_reflectance(&self, ctx: &BsdfContext) -> Rgb {
        match &self.base {
            Base::Diffuse { reflectance } => ctx.eval(reflectance),
            Base::Conductor { .. } => Rgb::ZERO,
        }
    }
}

impl Stack {
    /// The medium's phase function (Henyey–Greenstein, which reads no position).
    #[inline]
    fn phase(&self) -> PhaseFunction {
        PhaseFunction::HenyeyGreenstein { g: self.phase_g }
    }

    /// pbrt-v4's `LayeredBxDF::f` (no cosine), two-sided.
    fn f(&self, mut wo: Vec3, mut wi: Vec3, mode: Mode) -> Rgb {
        if wo.z < 0.0 {
            wo = mirror(wo);
            wi = mirror(wi);
        }
        let (top, bottom, thickness) = (&self.top, &self.bottom, self.thickness);
        // Entered through the top (two-sided); the exit is the top for reflection.
        let same = wo.z * wi.z > 0.0;
        let (exit, non_exit, exit_z) = if same { (top, bottom, thickness) } else { (bottom, top, 0.0) };
        let n = self.n_samples as f32;
        let mut f = if same { top.f(wo, wi, mode) * n } else { Rgb::ZERO };
        let mut rng = Pcg32::new(hash(&[SEED, bits(wo)]), bits(wi));
        let r = &mut rng;
        for _ in 0..self.n_samples {
            let uc = uniform(r);
            let Some(wos) = top.sample(wo, uc, Vec2::new(uniform(r), uniform(r)), mode, Lobes::Transmission) else {
                continue;
            };
            let uc = uniform(r);
            let Some(wis) = exit.sample(wi, uc, Vec2::new(uniform(r), uniform(r)), mode.adjoint(), Lobes::Transmission)
            else {
                continue;
            };
            let mut beta = wos.f * wos.wi.z.abs() / wos.pdf;
            let mut z = thickness;
            let mut w = wos.wi;
            for depth in 0..self.max_depth {
                if depth > 3 && beta.max_element() < 0.25 {
                    let q = (1.0 - beta.max_element()).max(0.0);
                    if uniform(r) < q {
                        break;
                    }
                    beta /= 1.0 - q;
                }
                match self.albedo {
                    None => {
                        z = if z == thickness { 0.0 } else { thickness };
                        beta *= tr(thickness, w);
                    }
                    Some(albedo) => {
                        let dz = -(-uniform(r)).ln_1p() * w.z.abs();
                        let zp = if w.z > 0.0 { z + dz } else { z - dz };
                        if zp == z {
                            continue;
                        }
                        if 0.0 < zp && zp < thickness {
                            // Scattering in the medium: next-event estimation through the exit
                            // along the presampled wis, then a phase-function sample.
                            let wt = if exit.is_specular() {
                                1.0
                            } else {
                                power_heuristic(wis.pdf, self.phase().eval(Vec3::ZERO, -w, -wis.wi))
                            };
                            f += beta * albedo * self.phase().eval(Vec3::ZERO, -w, -wis.wi) * wt * tr(zp - exit_z, wis.wi) * wis.f
                                / wis.pdf;
                            let ps = self.phase().sample(Vec3::ZERO, -w, Vec2::new(uniform(r), uniform(r)));
                            if ps.pdf == 0.0 || ps.value.z == 0.0 {
                                continue;
                            }
                            // The phase function is sampled exactly: p / pdf = 1.
                            beta *= albedo;
                            w = ps.value;
                            z = zp;
                            if ((z < exit_z && w.z > 0.0) || (z > exit_z && w.z < 0.0)) && !exit.is_specular() {
                                let f_exit = exit.f(-w, wi, mode);
                                if f_exit.max_element() > 0.0 {
                                    // The other strategy's density of this direction
                                    // (see the module notes: not pbrt's reverse density).
                                    let wt = power_heuristic(ps.pdf, exit.pdf(wi, -w, Lobes::Transmission));
                                    f += beta * tr(zp - exit_z, ps.value) * f_exit * wt;
                                }
                            }
                            continue;
                        }
                        z = zp.clamp(0.0, thickness);
                    }
                }
                if z == exit_z {
                    // Reflection at the exit interface.
                    let uc = uniform(r);
                    let Some(bs) = exit.sample(-w, uc, Vec2::new(uniform(r), uniform(r)), mode, Lobes::Reflection)
                    else {
                        break;
                    };
                    beta *= bs.f * bs.wi.z.abs() / bs.pdf;
                    w = bs.wi;
                } else {
                    if !non_exit.is_specular() {
                        // Next-event estimation along the presampled wis.
                        let wt = if exit.is_specular() {
                            1.0
                        } else {
                            power_heuristic(wis.pdf, non_exit.pdf(-w, -wis.wi, Lobes::All))
                        };
                        f += beta * non_exit.f(-w, -wis.wi, mode) * wis.wi.z.abs() * wt * tr(thickness, wis.wi) * wis.f
                            / wis.pdf;
                    }
                    let uc = uniform(r);
                    let Some(bs) = non_exit.sample(-w, uc, Vec2::new(uniform(r), uniform(r)), mode, Lobes::Reflection)
                    else {
                        break;
                    };
                    beta *= bs.f * bs.wi.z.abs() / bs.pdf;
                    w = bs.wi;
                    if !exit.is_specular() {
                        let f_exit = exit.f(-w, wi, mode);
                        if f_exit.max_element() > 0.0 {
                            let wt = if non_exit.is_specular() {
                                1.0
                            } else {
                                power_heuristic(bs.pdf, exit.pdf(wi, -w, Lobes::Transmission))
                            };
                            f += beta * tr(thickness, bs.wi) * f_exit * wt;
                        }
                    }
                }
            }
        }
        f / n
    }

    /// pbrt-v4's `LayeredBxDF::Sample_f`, keeping the walk's weight `f |cos| / p` as one
    /// running product (pbrt multiplies `f` and `p` apart, which underflow together in f32
    /// after a few dozen scattering events in a thick medium).
    fn sample(&self, mut wo: Vec3, uc: f32, u: Vec2, mode: Mode) -> Option<WalkSample> {
        let flip = wo.z < 0.0;
        if flip {
            wo = mirror(wo);
        }
        let out = |wi: Vec3, weight: Rgb, pdf: f32, specular: bool| WalkSample {
            wi: if flip { mirror(wi) } else { wi },
            weight,
            pdf,
            specular,
        };
        let bs = self.top.sample(wo, uc, u, mode, Lobes::All)?;
        if bs.reflection {
            return Some(out(bs.wi, bs.f * bs.wi.z.abs() / bs.pdf, bs.pdf, bs.specular));
        }
        let mut w = bs.wi;
        let mut specular = bs.specular;
        let mut beta = bs.f * bs.wi.z.abs() / bs.pdf;
        let mut pdf = bs.pdf;
        let mut z = self.thickness;
        let mut rng = Pcg32::new(
            hash(&[SEED, bits(wo)]),
            hash(&[uc.to_bits() as u64, u.x.to_bits() as u64, u.y.to_bits() as u64]),
        );
        let r = &mut rng;
        for depth in 0..self.max_depth {
            let rr_beta = beta.max_element();
            if depth > 3 && rr_beta < 0.25 {
                let q = (1.0 - rr_beta).max(0.0);
                if uniform(r) < q {
                    return None;
                }
                beta /= 1.0 - q;
                pdf *= 1.0 - q;
            }
            if w.z == 0.0 {
                return None;
            }
            match self.albedo {
                Some(albedo) => {
                    let dz = -(-uniform(r)).ln_1p() * w.z.abs();
                    let zp = if w.z > 0.0 { z + dz } else { z - dz };
                    if zp == z {
                        return None;
                    }
                    if 0.0 < zp && zp < self.thickness {
                        let ps = self.phase().sample(Vec3::ZERO, -w, Vec2::new(uniform(r), uniform(r)));
                        if ps.pdf == 0.0 || ps.value.z == 0.0 {
                            return None;
                        }
                        // The free flight and the phase function are sampled exactly.
                        beta *= albedo;
                        pdf *= ps.pdf;
                        specular = false;
                        w = ps.value;
                        z = zp;
                        continue;
                    }
                    z = zp.clamp(0.0, self.thickness);
                }
                None => {
                    z = if z == self.thickness { 0.0 } else { self.thickness };
                    beta *= tr(self.thickness, w);
                }
            }
            let iface = if z == 0.0 { &self.bottom } else { &self.top };
            let uc = uniform(r);
            let bs = iface.sample(-w, uc, Vec2::new(uniform(r), uniform(r)), mode, Lobes::All)?;
            beta *= bs.f / bs.pdf;
            pdf *= bs.pdf;
            specular &= bs.specular;
            w = bs.wi;
            beta *= bs.wi.z.abs();
            if !bs.reflection {
                // Left the layers (through the top: both bases here are opaque).
                return Some(out(w, beta, pdf, specular));
            }
        }
        None
    }

    /// pbrt-v4's `LayeredBxDF::PDF`: an estimate of the reflection and first
    /// transmission–reflection–transmission lobes, mixed 9:1 with the uniform sphere.
    fn pdf(&self, mut wo: Vec3, mut wi: Vec3, mode: Mode) -> f32 {
        if wo.z < 0.0 {
            wo = mirror(wo);
            wi = mirror(wi);
        }
        let mut rng = Pcg32::new(hash(&[SEED, bits(wi)]), bits(wo));
        let r = &mut rng;
        let n = self.n_samples as f32;
        let same = wo.z * wi.z > 0.0;
        let mut sum = if same { n * self.top.pdf(wo, wi, Lobes::Reflection) } else { 0.0 };
        let (t_iface, r_iface) = (&self.top, &self.bottom);
        for _ in 0..self.n_samples {
            if !same {
                // Transmission through both interfaces: the bases here are opaque.
                continue;
            }
            let wos = t_iface.sample(wo, uniform(r), Vec2::new(uniform(r), uniform(r)), mode, Lobes::Transmission);
            let wis =
                t_iface.sample(wi, uniform(r), Vec2::new(uniform(r), uniform(r)), mode.adjoint(), Lobes::Transmission);
            let (Some(wos), Some(wis)) = (wos, wis) else { continue };
            if t_iface.is_specular() {
                sum += r_iface.pdf(-wos.wi, -wis.wi, Lobes::All);
                continue;
            }
            let Some(rs) = r_iface.sample(-wos.wi, uniform(r), Vec2::new(uniform(r), uniform(r)), mode, Lobes::All)
            else {
                continue;
            };
            if r_iface.is_specular() {
                sum += t_iface.pdf(-rs.wi, wi, Lobes::All);
            } else {
                let r_pdf = r_iface.pdf(-wos.wi, -wis.wi, Lobes::All);
                sum += power_heuristic(wis.pdf, r_pdf) * r_pdf;
                let t_pdf = t_iface.pdf(-rs.wi, wi, Lobes::All);
                sum += power_heuristic(rs.pdf, t_pdf) * t_pdf;
            }
        }
        0.1 * INV_4PI + 0.9 * (sum / n)
    }
}

/// pbrt's `maxdepth` and `nsamples` (10 and 1) as Mitsuba-style `max_depth` / `nsamples`.
fn walk_props(o: &Obj) -> PropResult<(u32, u32)> {
    let int = |name: &str, default: i64, max: i64| -> PropResult<u32> {
        let v = o.int(name, default)?;
        if (1..=max).contains(&v) {
            Ok(v as u32)
        } else {
            Err(o.error_at(name, format!("must lie in 1..={max}, got {v}")))
        }
    };
    Ok((int("max_depth", 10, 1000)?, int("nsamples", 1, 256)?))
}

/// A GGX roughness pair from `{prefix}alpha` or `{prefix}alpha_u` / `{prefix}alpha_v` (0: smooth).
fn alpha_pair(o: &Obj, b: &mut dyn BsdfBuilder, prefix: &str) -> PropResult<Box<[Texture; 2]>> {
    let (a, au, av) = (format!("{prefix}alpha"), format!("{prefix}alpha_u"), format!("{prefix}alpha_v"));
    let t = |b: &mut dyn BsdfBuilder, n: &str| b.texture_of(o, n, Rgb::ZERO, SpectrumKind::Unbounded);
    if o.has(&au) || o.has(&av) {
        if o.has(&a) {
            return Err(o.error_at(&a, format!("give either '{a}' or '{au}'/'{av}'")));
        }
        return Ok(Box::new([t(b, &au)?, t(b, &av)?]));
    }
    let x = t(b, &a)?;
    Ok(Box::new([x.clone(), x]))
}

/// The layer's common parameters: `thickness` (0.01), `albedo` (0: none), `g` (0), walks.
fn layer(o: &Obj, b: &mut dyn BsdfBuilder, eta_name: &str, prefix: &str, base: Base) -> PropResult<Bsdf> {
    let eta = o.float_checked(eta_name, 1.5, |e| e > 0.0 && e.is_finite(), "positive")?;
    let alpha = alpha_pair(o, b, prefix)?;
    let thickness = b.texture_of(o, "thickness", Rgb::splat(0.01), SpectrumKind::Unbounded)?;
    let albedo = b.texture_opt(o, "albedo", SpectrumKind::Reflectance)?;
    let g = b.texture_of(o, "g", Rgb::ZERO, SpectrumKind::Unbounded)?;
    let (max_depth, n_samples) = walk_props(o)?;
    Ok(Bsdf::Layered(Box::new(Layered {
        eta,
        alpha,
        base,
        thickness,
        albedo,
        g,
        max_depth,
        n_samples,
        regularized: false,
    })))
}

impl Layered {
    /// `coateddiffuse` (pbrt-v4's): `reflectance` (0.5), coating `eta` (1.5) and GGX `alpha` or
    /// `alpha_u`/`alpha_v` (0: smooth), `thickness` (0.01), `albedo` (none), `g` (0),
    /// `max_depth` (10), `nsamples` (1).
    pub fn coated_diffuse_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let reflectance = b.texture(o, "reflectance", Rgb::splat(0.5))?;
        layer(o, b, "eta", "", Base::Diffuse { reflectance })
    }

    /// `coatedconductor` (pbrt-v4's): coating `interface_eta` (1.5) and `interface_alpha[_u|_v]`
    /// (0); the conductor's `material` or `eta`/`k` (default Cu) and `conductor_alpha[_u|_v]`
    /// (0); `thickness`, `albedo`, `g`, `max_depth`, `nsamples` as `coateddiffuse`.
    pub fn coated_conductor_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let ior = if o.has("eta") || o.has("k") || o.has("material") {
            ConductorIor::from_props(o, b)?
        } else {
            crate::material::named_conductor("Cu").flatten()
        }
        .ok_or_else(|| o.error_at("material", "a coated conductor needs a conductor, not the perfect mirror 'none'"))?;
        let alpha = alpha_pair(o, b, "conductor_")?;
        layer(o, b, "interface_eta", "interface_", Base::Conductor { ior, alpha })
    }
}
