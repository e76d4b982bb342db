//! The interfaces of a layered BSDF, with pbrt-v4's conventions (its `DielectricBxDF`,
//! `DiffuseBxDF` and `ConductorBxDF`), which the random walk of [`super::Layered`] needs and
//! neumann's own BSDFs do not give: sampling restricted to reflection or transmission, values
//! *without* the cosine, both sides of the surface, and the adjoint (importance) mode.
//!
//! Local frame (normal +z); `wo` and `wi` point away from the surface. `f` is the BSDF value
//! (sr⁻¹, no cosine); `pdf` per unit solid angle (for specular lobes, the discrete
//! probability of the lobe). Microfacets are GGX (pbrt's Trowbridge–Reitz) with Smith's
//! height-uncorrelated `G = 1 / (1 + Λ(wo) + Λ(wi))`, sampled by visible normals; a roughness
//! below 10⁻³ is smooth (pbrt's `EffectivelySmooth`).

use crate::material::fresnel::fresnel_conductor;
use crate::material::microfacet::Microfacet;
use crate::math::{Rgb, Vec2, Vec3, INV_PI};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere_malley};

/// Which way light is carried: radiance (from lights, as a path tracer gathers it) or
/// importance (from the camera); only refraction's `1/η²` differs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Radiance: transmission scales by `1/η²`.
    Radiance,
    /// Importance (adjoint): no scaling.
    Importance,
}

impl Mode {
    /// The other mode.
    pub fn adjoint(self) -> Mode {
        match self {
            Mode::Radiance => Mode::Importance,
            Mode::Importance => Mode::Radiance,
        }
    }
}

/// Which lobes a query may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lobes {
    /// Reflection and transmission.
    All,
    /// Reflection only.
    Reflection,
    /// Transmission only.
    Transmission,
}

impl Lobes {
    fn reflection(self) -> bool {
        self != Lobes::Transmission
    }
    fn transmission(self) -> bool {
        self != Lobes::Reflection
    }
}

/// A sampled direction at an interface.
#[derive(Clone, Copy, Debug)]
pub struct IfaceSample {
    /// BSDF value (no cosine).
    pub f: Rgb,
    /// The sampled direction (unit, local).
    pub wi: Vec3,
    /// Its density (solid angle), or the lobe probability for a specular lobe.
    pub pdf: f32,
    /// Whether a specular (delta) lobe chose it.
    pub specular: bool,
    /// Whether it lies on `wo`'s side.
    pub reflection: bool,
}

/// One interface of a layered BSDF, its parameters evaluated at the shading point.
#[derive(Clone, Copy, Debug)]
pub enum Interface {
    /// A dielectric boundary with relative index `eta` (inside over outside, the inside below
    /// the normal); smooth when `mf` is `None`.
    Dielectric {
        /// Relative index of refraction.
        eta: f32,
        /// Microfacet distribution (GGX), `None` if smooth.
        mf: Option<Microfacet>,
    },
    /// Lambertian reflection on both sides.
    Diffuse {
        /// Albedo.
        r: Rgb,
    },
    /// A conductor of complex relative index `eta + i k`; smooth when `mf` is `None`.
    Conductor {
        /// Real part.
        eta: Rgb,
        /// Imaginary part.
        k: Rgb,
        /// Microfacet distribution (GGX), `None` if smooth.
        mf: Option<Microfacet>,
    },
}

/// A microfacet distribution, or `None` when pbrt would call it smooth (α < 10⁻³).
pub fn rough_or_smooth(mf: Microfacet) -> Option<Microfacet> {
    (mf.alpha_u.max(mf.alpha_v) >= 1e-3).then_some(mf)
}

fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// pbrt's unpolarized dielectric Fresnel reflectance for `cos θᵢ` of either sign.
fn fr_dielectric(cos_i: f32, eta: f32) -> f32 {
    crate::material::fresnel::fresnel_dielectric(cos_i.clamp(-1.0, 1.0), eta).0
}

/// Refraction of `wi` through a boundary of normal `n` and relative index `eta` (pbrt's
/// `Refract`): `(wt, η')` with `η'` the index crossed from `wi`'s side, or `None` under total
/// internal reflection.
fn refract(wi: Vec3, mut n: Vec3, mut eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    Some((-wi / eta + n * (cos_i / eta - cos_t), eta))
}

/// Smith's `Λ(w)` for GGX.
fn lambda(mf: &Microfacet, w: Vec3) -> f32 {
    let xy = (mf.alpha_u * w.x).powi(2) + (mf.alpha_v * w.y).powi(2);
    if xy == 0.0 {
        return 0.0;
    }
    let tan2 = xy / (w.z * w.z);
    if !tan2.is_finite() {
        return 0.0;
    }
    0.5 * ((1.0 + tan2).sqrt() - 1.0)
}

fn g(mf: &Microfacet, wo: Vec3, wi: Vec3) -> f32 {
    1.0 / (1.0 + lambda(mf, wo) + lambda(mf, wi))
}

/// Density of visible normals `G1(w) |w·m| D(m) / |cos θ_w|` (pbrt's `D(w, wm)`), for `w` on
/// either side.
fn visible_pdf(mf: &Microfacet, w: Vec3, m: Vec3) -> f32 {
    if w.z == 0.0 {
        return 0.0;
    }
    mf.d(m) * w.dot(m).abs() / ((1.0 + lambda(mf, w)) * w.z.abs())
}

/// A visible normal for `w` on either side (sampled as seen from the upper side).
fn sample_visible(mf: &Microfacet, w: Vec3, u: Vec2) -> Vec3 {
    let w_up = if w.z < 0.0 { -w } else { w };
    mf.sample(w_up, u).value
}

impl Interface {
    /// Whether the interface only scatters specularly.
    pub fn is_specular(&self) -> bool {
        match self {
            Interface::Dielectric { mf, .. } | Interface::Conductor { mf, .. } => mf.is_none(),
            Interface::Diffuse { .. } => false,
        }
    }

    /// The BSDF value `f(wo, wi)` (no cosine; 0 for specular interfaces).
    pub fn f(&self, wo: Vec3, wi: Vec3, mode: Mode) -> Rgb {
        match *self {
            Interface::Diffuse { r } => {
                if same_hemisphere(wo, wi) {
                    r * INV_PI
                } else {
                    Rgb::ZERO
                }
            }
            Interface::Conductor { eta, k, mf } => {
                let Some(mf) = mf else { return Rgb::ZERO };
                if !same_hemisphere(wo, wi) {
                    return Rgb::ZERO;
                }
                let (co, ci) = (wo.z.abs(), wi.z.abs());
                let wm = wi + wo;
                if ci == 0.0 || co == 0.0 || wm.length_squared() == 0.0 {
                    return Rgb::ZERO;
                }
                let wm = face_forward(wm.normalize());
                let fr = fresnel_conductor(wo.dot(wm).abs(), eta, k);
                fr * (mf.d(wm) * g(&mf, wo, wi) / (4.0 * ci * co))
            }
            Interface::Dielectric { eta, mf } => {
                let Some(mf) = mf else { return Rgb::ZERO };
                if eta == 1.0 {
                    return Rgb::ZERO;
                }
                let Some((wm, etap, reflect)) = half_vector(wo, wi, eta) else { return Rgb::ZERO };
                let (co, ci) = (wo.z, wi.z);
                let fr = fr_dielectric(wo.dot(wm), eta);
                let v = if reflect {
                    mf.d(wm) * g(&mf, wo, wi) * fr / (4.0 * ci * co).abs()
                } else {
                    let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * ci * co;
                    let mut ft = mf.d(wm) * (1.0 - fr) * g(&mf, wo, wi) * (wi.dot(wm) * wo.dot(wm) / denom).abs();
                    if mode == Mode::Radiance {
                        ft /= etap * etap;
                    }
                    ft
                };
                Rgb::splat(finite_or_zero(v))
            }
        }
    }

    /// The density of [`Interface::sample`] choosing `wi` for `wo` with the lobes `lobes`
    /// (0 for specular interfaces).
    pub fn pdf(&self, wo: Vec3, wi: Vec3, lobes: Lobes) -> f32 {
        match *self {
            Interface::Diffuse { .. } => {
                if !lobes.reflection() || !same_hemisphere(wo, wi) {
                    0.0
                } else {
                    cosine_hemisphere_pdf(Vec3::new(wi.x, wi.y, wi.z.abs()))
                }
            }
            Interface::Conductor { mf, .. } => {
                let Some(mf) = mf else { return 0.0 };
                if !lobes.reflection() || !same_hemisphere(wo, wi) {
                    return 0.0;
                }
                let wm = wo + wi;
                if wm.length_squared() == 0.0 {
                    return 0.0;
                }
                let wm = face_forward(wm.normalize());
                finite_or_zero(visible_pdf(&mf, wo, wm) / (4.0 * wo.dot(wm).abs()))
            }
            Interface::Dielectric { eta, mf } => {
                let Some(mf) = mf else { return 0.0 };
                if eta == 1.0 {
                    return 0.0;
                }
                let Some((wm, etap, reflect)) = half_vector(wo, wi, eta) else { return 0.0 };
                let r = fr_dielectric(wo.dot(wm), eta);
                let (pr, pt) = lobe_weights(r, lobes);
                if pr + pt == 0.0 {
                    return 0.0;
                }
                let p = if reflect {
                    visible_pdf(&mf, wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt)
                } else {
                    let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
                    visible_pdf(&mf, wo, wm) * wi.dot(wm).abs() / denom * pt / (pr + pt)
                };
                finite_or_zero(p)
            }
        }
    }

    /// Samples `wi` for `wo` from `uc` (lobe) and `u` (direction), with the lobes `lobes`.
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: Mode, lobes: Lobes) -> Option<IfaceSample> {
        match *self {
            Interface::Diffuse { r } => {
                if !lobes.reflection() {
                    return None;
                }
                let s = sample_cosine_hemisphere_malley(u);
                let wi = if wo.z < 0.0 { Vec3::new(s.value.x, s.value.y, -s.value.z) } else { s.value };
                Some(IfaceSample { f: r * INV_PI, wi, pdf: s.pdf, specular: false, reflection: true })
            }
            Interface::Conductor { eta, k, mf } => {
                if !lobes.reflection() || wo.z == 0.0 {
                    return None;
                }
                let Some(mf) = mf else {
                    let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                    let f = fresnel_conductor(wi.z.abs(), eta, k) / wi.z.abs();
                    return Some(IfaceSample { f, wi, pdf: 1.0, specular: true, reflection: true });
                };
                let wm = sample_visible(&mf, wo, u);
                let wi = crate::material::fresnel::reflect_about(wo, wm);
                if !same_hemisphere(wo, wi) {
                    return None;
                }
                let pdf = visible_pdf(&mf, wo, wm) / (4.0 * wo.dot(wm).abs());
                let (co, ci) = (wo.z.abs(), wi.z.abs());
                let fr = fresnel_conductor(wo.dot(wm).abs(), eta, k);
                let f = fr * (mf.d(wm) * g(&mf, wo, wi) / (4.0 * ci * co));
                valid(IfaceSample { f, wi, pdf, specular: false, reflection: true })
            }
            Interface::Dielectric { eta, mf } => match mf.filter(|_| eta != 1.0) {
                None => {
                    let r = fr_dielectric(wo.z, eta);
                    let (pr, pt) = lobe_weights(r, lobes);
                    if pr + pt == 0.0 {
                        return None;
                    }
                    if uc < pr / (pr + pt) {
                        let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                        let f = Rgb::splat(r / wi.z.abs());
                        return Some(IfaceSample { f, wi, pdf: pr / (pr + pt), specular: true, reflection: true });
                    }
                    let (wi, etap) = refract(wo, Vec3::Z, eta)?;
                    let mut ft = (1.0 - r) / wi.z.abs();
                    if mode == Mode::Radiance {
                        ft /= etap * etap;
                    }
                    valid(IfaceSample { f: Rgb::splat(ft), wi, pdf: pt / (pr + pt), specular: true, reflection: false })
                }
                Some(mf) => {
                    let wm = sample_visible(&mf, wo, u);
                    let r = fr_dielectric(wo.dot(wm), eta);
                    let (pr, pt) = lobe_weights(r, lobes);
                    if pr + pt == 0.0 {
                        return None;
                    }
                    if uc < pr / (pr + pt) {
                        let wi = crate::material::fresnel::reflect_about(wo, wm);
                        if !same_hemisphere(wo, wi) {
                            return None;
                        }
                        let pdf = visible_pdf(&mf, wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt);
                        let f = mf.d(wm) * g(&mf, wo, wi) * r / (4.0 * wi.z * wo.z);
                        return valid(IfaceSample { f: Rgb::splat(f), wi, pdf, specular: false, reflection: true });
                    }
                    let (wi, etap) = refract(wo, wm, eta)?;
                    if same_hemisphere(wo, wi) || wi.z == 0.0 {
                        return None;
                    }
                    let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
                    let pdf = visible_pdf(&mf, wo, wm) * wi.dot(wm).abs() / denom * pt / (pr + pt);
                    let mut ft =
                        (1.0 - r) * mf.d(wm) * g(&mf, wo, wi) * (wi.dot(wm) * wo.dot(wm) / (wi.z * wo.z * denom)).abs();
                    if mode == Mode::Radiance {
                        ft /= etap * etap;
                    }
                    valid(IfaceSample { f: Rgb::splat(ft), wi, pdf, specular: false, reflection: false })
                }
            },
        }
    }
}

/// pbrt's generalized half vector of a rough dielectric: `(wm, η', reflect)` with `wm` facing
/// +z, or `None` where the configuration is degenerate or a microfacet's back is seen.
fn half_vector(wo: Vec3, wi: Vec3, eta: f32) -> Option<(Vec3, f32, bool)> {
    let (co, ci) = (wo.z, wi.z);
    let reflect = ci * co > 0.0;
    let etap = if reflect {
        1.0
    } else if co > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let wm = wi * etap + wo;
    if ci == 0.0 || co == 0.0 || wm.length_squared() == 0.0 {
        return None;
    }
    let wm = face_forward(wm.normalize());
    if wm.dot(wi) * ci < 0.0 || wm.dot(wo) * co < 0.0 {
        return None;
    }
    Some((wm, etap, reflect))
}

fn face_forward(m: Vec3) -> Vec3 {
    if m.z < 0.0 {
        -m
    } else {
        m
    }
}

/// Lobe selection weights `(R, T)` restricted to `lobes`.
fn lobe_weights(r: f32, lobes: Lobes) -> (f32, f32) {
    (if lobes.reflection() { r } else { 0.0 }, if lobes.transmission() { 1.0 - r } else { 0.0 })
}

fn finite_or_zero(v: f32) -> f32 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

/// The sample if its value and density are usable (finite, positive, off the horizon).
fn valid(s: IfaceSample) -> Option<IfaceSample> {
    let ok = s.pdf > 0.0 && s.pdf.is_finite() && s.wi.z != 0.0 && s.f.max_element() > 0.0 && s.f.is_finite();
    ok.then_some(s)
}
