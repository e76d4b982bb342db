//! The hair scattering model of Chiang et al. 2016 ("A practical and controllable hair and fur
//! model for production path tracing") in its two conventions ([`HairConvention`]): Mitsuba 3's
//! `hair` BSDF and pbrt-v4's `HairBxDF` (neumann's `pbrt_hair` plugin).
//!
//! The fibre is a dielectric cylinder (index `eta`, 1.55) with an absorbing interior (σₐ per
//! unit of the fibre's diameter). Light leaves it after `p` internal paths: `R` (p = 0, reflected
//! at the surface), `TT` (p = 1), `TRT` (p = 2), and everything longer in one term (p = 3).
//! Each term is a product of
//! - a longitudinal lobe `M_p(θᵢ, θₒ)` (d'Eon et al.'s, variance `v_p` from `beta_m`; the
//!   cuticle's scales tilt the lobes by `2^k alpha`),
//! - an attenuation `A_p` (Fresnel at the fibre's surface and the transmittance of the paths
//!   through the interior),
//! - an azimuthal lobe `N_p(φ)` (a logistic of scale `s` from `beta_n`, trimmed to [−π, π],
//!   about the exit angle of the path; uniform for p = 3).
//!
//! Frames: pbrt's has x along the fibre (the curve's ∂p/∂u) and z the shading normal, so that
//! sin θ = x, φ = atan2(z, y), and where across the fibre the ray hit is the surface's `v`:
//! `h = 2v − 1`. Mitsuba's has y along the fibre (on its round curves the shading frame's second
//! tangent, ∂p/∂v), sin θ = y, φ = atan2(z, x), and `h = sin γ` with γ the angle between the
//! normal and the viewing direction projected across the fibre (signed: positive toward −x).
//! `eval` returns `Σ_p M_p A_p N_p` (pbrt's `f` times |cos θᵢ|; Mitsuba's `eval`). Sampling
//! chooses `p` by the mean (pbrt) or the luminance (Mitsuba) of `A_p`, then θᵢ from `M_p` and φ
//! from `N_p`: exactly the density `pdf` returns. `M_p` uses the Bessel function to 2·10⁻⁷
//! (`bessel_i0`), where both renderers truncate its series at ten terms (low by up to a few
//! per cent where `cos θᵢ cos θₒ / v` nears 12; their densities then disagree with their own
//! sampling).
//!
//! Colour, pbrt-v4's parameters: `sigma_a` (absorption per diameter), else `reflectance` (the
//! colour after many scatterings, turned into σₐ by Chiang et al.'s fit in `beta_n`), else the
//! `eumelanin` and `pheomelanin` concentrations (σₐ = cₑ (0.419, 0.697, 1.37) +
//! cₚ (0.187, 0.4, 1.05)), and without any of them eumelanin 1.3 (brown hair). Mitsuba's:
//! `sigma_a` times `scale`, else the concentrations, 1.3 and 0.2 by default.

use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::spectrum::SpectrumKind;
use crate::math::{safe_asin, safe_sqrt, Rgb, Vec2, Vec3, PI};
use crate::props::{Obj, Result as PropResult};
use crate::texture::Texture;

/// Number of explicit scattering terms (R, TT, TRT); longer paths are term `P_MAX`.
const P_MAX: usize = 3;

/// σₐ per unit concentration of eumelanin (pbrt-v4's RGB).
const EUMELANIN: Rgb = Rgb::new(0.419, 0.697, 1.37);
/// σₐ per unit concentration of pheomelanin (pbrt-v4's RGB).
const PHEOMELANIN: Rgb = Rgb::new(0.187, 0.4, 1.05);

/// Where the absorption of the fibre's interior comes from.
#[derive(Clone, Debug)]
pub enum HairColour {
    /// σₐ per unit of the diameter, per channel.
    Absorption(Texture),
    /// The colour after multiple scattering, converted to σₐ with `beta_n`.
    Reflectance(Texture),
    /// Melanin concentrations (scalar textures): eumelanin, pheomelanin.
    Melanin(Texture, Texture),
}

/// Which renderer's frame and term selection the model follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HairConvention {
    /// pbrt-v4's: the fibre along local x, `h = 2v − 1`, terms chosen by the mean of `A_p`.
    Pbrt,
    /// Mitsuba 3's: the fibre along local y, `h` from the viewing direction, terms chosen by the
    /// luminance of `A_p`.
    Mitsuba,
}

/// The hair BSDF.
#[derive(Clone, Debug)]
pub struct Hair {
    /// Whose frame and term selection.
    pub convention: HairConvention,
    /// The interior's absorption.
    pub colour: HairColour,
    /// Index of refraction of the fibre.
    pub eta: f32,
    /// Longitudinal roughness, in [0, 1].
    pub beta_m: f32,
    /// Azimuthal roughness, in [0, 1].
    pub beta_n: f32,
    /// Tilt of the cuticle's scales (degrees).
    pub alpha: f32,
}

/// The quantities of the model that depend on its parameters only (pbrt's constructor).
struct Lobes {
    /// Longitudinal variances `v_p`.
    v: [f32; P_MAX + 1],
    /// Logistic scale of the azimuthal lobes.
    s: f32,
    /// sin and cos of `2^k alpha`, k = 0, 1, 2.
    sin2k: [f32; P_MAX],
    cos2k: [f32; P_MAX],
}

impl Lobes {
    fn new(h: &Hair) -> Lobes {
        let bm = h.beta_m;
        let v0 = (0.726 * bm + 0.812 * bm * bm + 3.7 * bm.powi(20)).powi(2);
        let v = [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0];
        let bn = h.beta_n;
        const SQRT_PI_OVER_8: f32 = 0.626_657_07;
        let s = SQRT_PI_OVER_8 * (0.265 * bn + 1.194 * bn * bn + 5.372 * bn.powi(22));
        let mut sin2k = [0.0; P_MAX];
        let mut cos2k = [0.0; P_MAX];
        sin2k[0] = h.alpha.to_radians().sin();
        cos2k[0] = (1.0 - sin2k[0] * sin2k[0]).max(0.0).sqrt();
        for i in 1..P_MAX {
            sin2k[i] = 2.0 * cos2k[i - 1] * sin2k[i - 1];
            cos2k[i] = cos2k[i - 1] * cos2k[i - 1] - sin2k[i - 1] * sin2k[i - 1];
        }
        Lobes { v, s, sin2k, cos2k }
    }

    /// `(sin θₒ', cos θₒ')` of term `p`: θₒ tilted by the scales (R by −2α, TT by α, TRT by 4α).
    fn tilted(&self, p: usize, sin_o: f32, cos_o: f32) -> (f32, f32) {
        let (s, c) = match p {
            0 => (sin_o * self.cos2k[1] - cos_o * self.sin2k[1], cos_o * self.cos2k[1] + sin_o * self.sin2k[1]),
            1 => (sin_o * self.cos2k[0] + cos_o * self.sin2k[0], cos_o * self.cos2k[0] - sin_o * self.sin2k[0]),
            2 => (sin_o * self.cos2k[2] + cos_o * self.sin2k[2], cos_o * self.cos2k[2] - sin_o * self.sin2k[2]),
            _ => (sin_o, cos_o),
        };
        (s, c.abs())
    }
}

/// `e^(−x) √x I₀(x)` for `x ≥ 3.75`: Abramowitz and Stegun's 9.8.2 in `t = 3.75 / x`
/// (relative error below 1.9·10⁻⁷).
#[inline]
fn scaled_bessel_i0_large(x: f32) -> f32 {
    const C: [f64; 9] = [
        0.398_942_28,
        0.013_285_92,
        0.002_253_19,
        -0.001_575_65,
        0.009_162_81,
        -0.020_577_06,
        0.026_355_37,
        -0.016_476_33,
        0.003_923_77,
    ];
    let t = 3.75 / x as f64;
    C.iter().rev().fold(0.0, |acc, c| acc * t + c) as f32
}

/// The modified Bessel function of the first kind, order 0, to a relative 2·10⁻⁷ (Abramowitz
/// and Stegun's 9.8.1 below 3.75, 9.8.2 above; pbrt and Mitsuba sum ten terms of its series,
/// about 1 % low near x = 12, where their densities then disagree with their exact
/// von Mises–Fisher sampling).
fn bessel_i0(x: f32) -> f32 {
    let x = x.abs();
    if x < 3.75 {
        const C: [f64; 7] = [1.0, 3.515_622_9, 3.089_942_4, 1.206_749_2, 0.265_973_2, 0.036_076_8, 0.004_581_3];
        let t2 = (x as f64 / 3.75) * (x as f64 / 3.75);
        C.iter().rev().fold(0.0, |acc, c| acc * t2 + c) as f32
    } else {
        scaled_bessel_i0_large(x) * x.exp() / x.sqrt()
    }
}

/// `ln I₀(x)` to the same accuracy, without overflow for large x.
fn log_bessel_i0(x: f32) -> f32 {
    let x = x.abs();
    if x < 3.75 {
        bessel_i0(x).ln()
    } else {
        x - 0.5 * x.ln() + scaled_bessel_i0_large(x).ln()
    }
}

/// d'Eon et al.'s longitudinal lobe of variance `v`.
fn mp(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32) -> f32 {
    let a = cos_i * cos_o / v;
    let b = sin_i * sin_o / v;
    if v <= 0.1 {
        (log_bessel_i0(a) - b - 1.0 / v + std::f32::consts::LN_2 + (1.0 / (2.0 * v)).ln()).exp()
    } else {
        ((-b).exp() * bessel_i0(a)) / ((1.0 / v).sinh() * 2.0 * v)
    }
}

/// The attenuations `A_p` of the four terms at `cos θₒ`, `h`, with the transmittance `t` of one
/// pass through the interior.
fn ap(cos_o: f32, eta: f32, h: f32, t: Rgb) -> [Rgb; P_MAX + 1] {
    let cos_gamma_o = safe_sqrt(1.0 - h * h);
    let f = super::fresnel::fresnel_dielectric(cos_o * cos_gamma_o, eta).0;
    let mut a = [Rgb::ZERO; P_MAX + 1];
    a[0] = Rgb::splat(f);
    a[1] = t * ((1.0 - f) * (1.0 - f));
    for p in 2..P_MAX {
        a[p] = a[p - 1] * t * f;
    }
    let denom = Rgb::ONE - t * f;
    a[P_MAX] =
        Rgb::from_array(std::array::from_fn(
            |c| {
                if denom[c] > 0.0 {
                    a[P_MAX - 1][c] * f * t[c] / denom[c]
                } else {
                    0.0
                }
            },
        ));
    a
}

/// The azimuthal exit angle of term `p`.
#[inline]
fn phi(p: usize, gamma_o: f32, gamma_t: f32) -> f32 {
    2.0 * p as f32 * gamma_t - 2.0 * gamma_o + p as f32 * PI
}

#[inline]
fn logistic(x: f32, s: f32) -> f32 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

#[inline]
fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

/// The logistic of scale `s` restricted to [−π, π] and renormalised.
#[inline]
fn trimmed_logistic(x: f32, s: f32) -> f32 {
    logistic(x, s) / (logistic_cdf(PI, s) - logistic_cdf(-PI, s))
}

/// Inverts the CDF of [`trimmed_logistic`] at `u` (in double precision: in single, the CDF
/// rounds to 1 in the far tail and u near 1 lands on ±π, where the density is ~0).
fn sample_trimmed_logistic(u: f32, s: f32) -> f32 {
    let (u, s, pi) = (u as f64, s as f64, std::f64::consts::PI);
    let cdf = |x: f64| 1.0 / (1.0 + (-x / s).exp());
    let k = cdf(pi) - cdf(-pi);
    let x = -s * (1.0 / (u * k + cdf(-pi)) - 1.0).ln();
    (x as f32).clamp(-PI, PI)
}

/// The azimuthal lobe of term `p` at the azimuth difference `dphi`.
fn np(dphi: f32, p: usize, s: f32, gamma_o: f32, gamma_t: f32) -> f32 {
    let mut d = dphi - phi(p, gamma_o, gamma_t);
    // Into [−π, π].
    d -= (2.0 * PI) * crate::math::floor((d + PI) / (2.0 * PI));
    trimmed_logistic(d, s)
}

/// What `wo` and the fibre fix: the angles, the refracted ray's γₜ and the transmittance.
struct Outgoing {
    sin_o: f32,
    cos_o: f32,
    phi_o: f32,
    gamma_o: f32,
    gamma_t: f32,
    a: [Rgb; P_MAX + 1],
    /// The terms' sampling probabilities (their `A_p` averaged over the channels, normalised).
    a_pdf: [f32; P_MAX + 1],
}

impl Hair {
    /// σₐ at `ctx` (per unit diameter, ≥ 0).
    fn sigma_a(&self, ctx: &BsdfContext) -> Rgb {
        match &self.colour {
            HairColour::Absorption(t) => ctx.eval(t).max(Rgb::ZERO),
            HairColour::Reflectance(t) => {
                let bn = self.beta_n;
                let fit =
                    5.969 - 0.215 * bn + 2.532 * bn * bn - 10.73 * bn.powi(3) + 5.574 * bn.powi(4) + 0.245 * bn.powi(5);
                let c = ctx.eval(t);
                Rgb::from_array(std::array::from_fn(|i| {
                    let r = c[i].clamp(1e-4, 1.0);
                    (r.ln() / fit).powi(2)
                }))
            }
            HairColour::Melanin(e, p) => EUMELANIN * ctx.scalar(e).max(0.0) + PHEOMELANIN * ctx.scalar(p).max(0.0),
        }
    }

    /// `h` ∈ [−1, 1]: where across the fibre (the surface's v) the ray hit.
    #[inline]
    fn h(ctx: &BsdfContext) -> f32 {
        (2.0 * ctx.uv.y - 1.0).clamp(-1.0, 1.0)
    }

    /// `(sin θ, φ)` of a local direction in the convention's frame.
    #[inline]
    fn angles(&self, w: Vec3) -> (f32, f32) {
        match self.convention {
            HairConvention::Pbrt => (w.x.clamp(-1.0, 1.0), w.z.atan2(w.y)),
            HairConvention::Mitsuba => (w.y.clamp(-1.0, 1.0), w.z.atan2(w.x)),
        }
    }

    /// The local direction of `(sin θ, cos θ, φ)` (the inverse of [`Hair::angles`]).
    #[inline]
    fn direction(&self, sin_t: f32, cos_t: f32, phi: f32) -> Vec3 {
        let (s, c) = phi.sin_cos();
        match self.convention {
            HairConvention::Pbrt => Vec3::new(sin_t, cos_t * c, cos_t * s),
            HairConvention::Mitsuba => Vec3::new(cos_t * c, sin_t, cos_t * s),
        }
    }

    /// `(h, γₒ)`: where across the fibre, and the angle of incidence there in the cross-section.
    fn offset(&self, ctx: &BsdfContext, wo: Vec3) -> (f32, f32) {
        match self.convention {
            HairConvention::Pbrt => {
                let h = Self::h(ctx);
                (h, safe_asin(h))
            }
            HairConvention::Mitsuba => {
                let proj = (wo.x * wo.x + wo.z * wo.z).sqrt();
                let gamma = if proj == 0.0 { 0.0 } else { (wo.z / proj).clamp(-1.0, 1.0).acos() };
                let gamma = if wo.x < 0.0 { gamma } else { -gamma };
                (gamma.sin(), gamma)
            }
        }
    }

    fn outgoing(&self, ctx: &BsdfContext, wo: Vec3) -> Outgoing {
        let (h, gamma_o) = self.offset(ctx, wo);
        let (sin_o, phi_o) = self.angles(wo);
        let cos_o = safe_sqrt(1.0 - sin_o * sin_o);
        let sin_t = sin_o / self.eta;
        let cos_t = safe_sqrt(1.0 - sin_t * sin_t);
        let etap = safe_sqrt(self.eta * self.eta - sin_o * sin_o) / cos_o;
        let sin_gamma_t = h / etap;
        let cos_gamma_t = safe_sqrt(1.0 - sin_gamma_t * sin_gamma_t);
        let gamma_t = safe_asin(sin_gamma_t);
        let t = Rgb::from_array((-self.sigma_a(ctx) * (2.0 * cos_gamma_t / cos_t)).to_array().map(f32::exp));
        let a = ap(cos_o, self.eta, h, t);
        let weight = |x: &Rgb| match self.convention {
            HairConvention::Pbrt => x.element_sum() / 3.0,
            HairConvention::Mitsuba => crate::math::luminance(*x),
        };
        let sum: f32 = a.iter().map(weight).sum();
        let a_pdf = std::array::from_fn(|p| if sum > 0.0 { weight(&a[p]) / sum } else { 0.0 });
        Outgoing { sin_o, cos_o, phi_o, gamma_o, gamma_t, a, a_pdf }
    }

    /// The products `M_p N_p` of the four terms at `wi` (N uniform, 1/2π, for the last).
    fn lobes_at(&self, l: &Lobes, o: &Outgoing, wi: Vec3) -> [f32; P_MAX + 1] {
        let (sin_i, phi_i) = self.angles(wi);
        let cos_i = safe_sqrt(1.0 - sin_i * sin_i);
        let dphi = phi_i - o.phi_o;
        std::array::from_fn(|p| {
            if p < P_MAX {
                let (s, c) = l.tilted(p, o.sin_o, o.cos_o);
                mp(cos_i, c, sin_i, s, l.v[p]) * np(dphi, p, l.s, o.gamma_o, o.gamma_t)
            } else {
                mp(cos_i, o.cos_o, sin_i, o.sin_o, l.v[P_MAX]) / (2.0 * PI)
            }
        })
    }

    /// `Σ_p M_p A_p N_p` and `Σ_p M_p P(p) N_p` of the products `m` (the value and the density).
    fn sums(o: &Outgoing, m: &[f32; P_MAX + 1]) -> (Rgb, f32) {
        let f = (0..=P_MAX).fold(Rgb::ZERO, |acc, p| acc + o.a[p] * m[p]);
        let pdf = (0..=P_MAX).map(|p| o.a_pdf[p] * m[p]).sum();
        (f, pdf)
    }

    /// `f(wo, wi) |cos θᵢ|` = `Σ_p M_p A_p N_p` (local frame).
    pub fn eval(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        self.eval_pdf(ctx, wo, wi).0
    }

    /// The density of [`Hair::sample`] at `wi` (solid angle).
    pub fn pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        self.eval_pdf(ctx, wo, wi).1
    }

    /// [`Hair::eval`] and [`Hair::pdf`] at once: both are sums over the same terms `M_p` of
    /// the same outgoing geometry, computed once.
    pub fn eval_pdf(&self, ctx: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        let o = self.outgoing(ctx, wo);
        let (v, p) = Self::sums(&o, &self.lobes_at(&Lobes::new(self), &o, wi));
        (if v.is_finite() { v } else { Rgb::ZERO }, if p.is_finite() { p } else { 0.0 })
    }

    /// A term chosen with `u1` by its mean attenuation, θᵢ from its `M_p` with `u`, φ from its
    /// `N_p` with what is left of `u1`.
    pub fn sample(&self, ctx: &BsdfContext, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        let l = Lobes::new(self);
        let o = self.outgoing(ctx, wo);
        // The term, and u1 remapped to [0, 1) within its bucket.
        let (mut p, mut start) = (P_MAX, 0.0);
        for (k, &w) in o.a_pdf.iter().enumerate() {
            if u1 < start + w || k == P_MAX {
                p = k;
                break;
            }
            start += w;
        }
        if o.a_pdf[p] <= 0.0 {
            return None;
        }
        let uc = ((u1 - start) / o.a_pdf[p]).clamp(0.0, 1.0 - f32::EPSILON);
        let (sin_op, cos_op) = l.tilted(p, o.sin_o, o.cos_o);
        let v = l.v[p];
        let cos_theta = 1.0 + v * (u.x.max(1e-5) + (1.0 - u.x) * (-2.0 / v).exp()).ln();
        let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
        let cos_phi = (2.0 * PI * u.y).cos();
        let sin_i = (-cos_theta * sin_op + sin_theta * cos_phi * cos_op).clamp(-1.0, 1.0);
        let cos_i = safe_sqrt(1.0 - sin_i * sin_i);
        let dphi =
            if p < P_MAX { phi(p, o.gamma_o, o.gamma_t) + sample_trimmed_logistic(uc, l.s) } else { 2.0 * PI * uc };
        let phi_i = o.phi_o + dphi;
        let wi = self.direction(sin_i, cos_i, phi_i);
        let (f, pdf) = Self::sums(&o, &self.lobes_at(&l, &o, wi));
        (pdf > 0.0 && pdf.is_finite() && f.is_finite()).then(|| BsdfSample {
            wi,
            pdf,
            weight: f / pdf,
            delta: false, null: false,
            eta: 1.0,
        })
    }

    /// Mitsuba's `hair`: `longitudinal_roughness`, `azimuthal_roughness` (0.3 each, in [0, 1]),
    /// `scale_tilt` (2°), `int_ior` (amber, 1.55) and `ext_ior` (air), which must differ; the
    /// absorption `sigma_a` (a texture) times `scale` (1), else the concentrations `eumelanin`
    /// (1.3) and `pheomelanin` (0.2), not both.
    pub fn mitsuba_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let unit = |name: &str| o.float_checked(name, 0.3, |x| (0.0..=1.0).contains(&x), "a number in [0, 1]");
        let (beta_m, beta_n) = (unit("longitudinal_roughness")?, unit("azimuthal_roughness")?);
        let alpha = o.float_checked("scale_tilt", 2.0, f32::is_finite, "a number of degrees")?;
        let eta = super::fresnel::eta_from_props(o, 1.55)?;
        if !(eta > 0.0 && eta.is_finite() && eta != 1.0) {
            return Err(
                o.error_at("int_ior", "the interior and exterior indices of refraction must be positive and differ")
            );
        }
        let colour = if o.has("sigma_a") {
            if let Some(p) = ["eumelanin", "pheomelanin"].into_iter().find(|p| o.has(p)) {
                return Err(o.error_at(p, "give either sigma_a or the pigment concentrations, not both"));
            }
            let scale = o.float("scale", 1.0)?;
            let sigma_a = b.texture_of(o, "sigma_a", Rgb::ZERO, SpectrumKind::Unbounded)?;
            HairColour::Absorption(sigma_a.times(Texture::Constant(Rgb::splat(scale))))
        } else {
            let c = |name: &str, default: f32| o.float(name, default).map(|v| Texture::Constant(Rgb::splat(v)));
            HairColour::Melanin(c("eumelanin", 1.3)?, c("pheomelanin", 0.2)?)
        };
        Ok(Bsdf::Hair(Box::new(Hair { convention: HairConvention::Mitsuba, colour, eta, beta_m, beta_n, alpha })))
    }

    /// pbrt-v4's `hair` (neumann's `pbrt_hair` plugin): `sigma_a`, `reflectance` (both
    /// texturable colours), `eumelanin`, `pheomelanin` (texturable scalars), `eta` (1.55),
    /// `beta_m` (0.3), `beta_n` (0.3), `alpha` (2°).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let unit = |name: &str, default: f32| {
            o.float_checked(name, default, |x| (0.0..=1.0).contains(&x), "a number in [0, 1]")
        };
        let (beta_m, beta_n) = (unit("beta_m", 0.3)?, unit("beta_n", 0.3)?);
        let eta = o.float_checked("eta", 1.55, |x| x > 0.0 && x.is_finite(), "a positive number")?;
        let alpha = o.float_checked("alpha", 2.0, f32::is_finite, "a number of degrees")?;
        let colour = if o.has("sigma_a") {
            HairColour::Absorption(b.texture_of(o, "sigma_a", Rgb::ZERO, SpectrumKind::Unbounded)?)
        } else if o.has("reflectance") {
            HairColour::Reflectance(b.texture(o, "reflectance", Rgb::ONE)?)
        } else if o.has("eumelanin") || o.has("pheomelanin") {
            HairColour::Melanin(
                b.texture_of(o, "eumelanin", Rgb::ZERO, SpectrumKind::Unbounded)?,
                b.texture_of(o, "pheomelanin", Rgb::ZERO, SpectrumKind::Unbounded)?,
            )
        } else {
            HairColour::Melanin(Texture::Constant(Rgb::splat(1.3)), Texture::Constant(Rgb::ZERO))
        };
        for other in ["reflectance", "eumelanin", "pheomelanin"] {
            // pbrt-v4 reads the first of sigma_a, reflectance, melanin that is given.
            if o.has(other)
                && !matches!(
                    (&colour, other),
                    (HairColour::Reflectance(_), "reflectance") | (HairColour::Melanin(..), _)
                )
            {
                return Err(o.error_at(other, "give one of sigma_a, reflectance, or eumelanin/pheomelanin"));
            }
        }
        Ok(Bsdf::Hair(Box::new(Hair { convention: HairConvention::Pbrt, colour, eta, beta_m, beta_n, alpha })))
    }

    /// The textures the BSDF reads.
    pub fn textures(&self) -> Vec<&Texture> {
        match &self.colour {
            HairColour::Absorption(t) | HairColour::Reflectance(t) => vec![t],
            HairColour::Melanin(e, p) => vec![e, p],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, u2, Chi2Config, SPHERE};

    fn hair(sigma_a: Rgb, beta_m: f32, beta_n: f32, alpha: f32) -> Hair {
        Hair {
            convention: HairConvention::Pbrt,
            colour: HairColour::Absorption(Texture::Constant(sigma_a)),
            eta: 1.55,
            beta_m,
            beta_n,
            alpha,
        }
    }

    fn at(v: f32) -> BsdfContext<'static> {
        BsdfContext { uv: Vec2::new(0.3, v), mesh: None, textures: None, si: None, memo: None }
    }

    fn directions() -> Vec<Vec3> {
        vec![
            Vec3::new(0.3, 0.5, 0.81).normalize(),
            Vec3::new(-0.7, 0.2, -0.3).normalize(),
            Vec3::new(0.05, -0.9, 0.4).normalize(),
        ]
    }

    /// A fibre that absorbs nothing scatters all light: the albedo `∫ f |cos θᵢ| dωᵢ` is 1, by
    /// quadrature of `eval` over the sphere (pbrt's white-furnace test), for smooth and rough
    /// fibres, at several offsets across the fibre and directions; and the sampling weight is
    /// exactly 1 there (the terms are sampled by their attenuation).
    #[test]
    fn white_furnace() {
        for (bm, bn) in [(0.2, 0.2), (0.3, 0.6), (0.6, 0.9)] {
            let h = hair(Rgb::ZERO, bm, bn, 2.0);
            for v in [0.1, 0.5, 0.85] {
                let ctx = at(v);
                for wo in directions() {
                    let albedo =
                        crate::testkit::integrate_pdf_2d(&SPHERE, [32, 64], |wi| h.eval(&ctx, wo, *wi).x as f64);
                    assert!((albedo - 1.0).abs() < 0.03, "β ({bm}, {bn}), v {v}, wo {wo}: albedo {albedo}");
                    let mut rng = crate::sampling::Pcg32::new(7, 1);
                    for _ in 0..200 {
                        let s = h.sample(&ctx, wo, rng.next_f32(), u2(&mut rng)).unwrap();
                        assert!((s.weight - Rgb::ONE).abs().max_element() < 1e-3, "{}", s.weight);
                    }
                }
            }
        }
    }

    /// Sampling draws directions with the density `pdf` returns (χ² over the sphere), for a
    /// coloured, absorbing fibre seen from several sides and offsets, and that density
    /// integrates to one.
    #[test]
    fn sample_matches_pdf() {
        let h = hair(Rgb::new(0.2, 0.6, 1.5), 0.3, 0.4, 2.0);
        let mut k = 0;
        for v in [0.2, 0.7] {
            let ctx = at(v);
            for wo in directions() {
                k += 1;
                let total = crate::testkit::integrate_pdf_2d(&SPHERE, [32, 64], |wi| h.pdf(&ctx, wo, *wi) as f64);
                assert!((total - 1.0).abs() < 0.02, "∫ pdf = {total}");
                let out = chi2_2d(
                    &SPHERE,
                    [31, 61],
                    300_000,
                    |r| h.sample(&ctx, wo, r.next_f32(), u2(r)).map(|s| s.wi),
                    |wi| h.pdf(&ctx, wo, *wi) as f64,
                    &Chi2Config::default().with_seed(100 + k),
                );
                assert!(out.passed(), "v {v}, wo {wo}: {out}");
            }
        }
    }

    /// Absorption darkens: eumelanin-rich hair reflects less than blonde, red channel last; the
    /// reflectance parameterisation inverts to about the colour asked for after many
    /// scatterings (its σₐ grows as the colour darkens).
    #[test]
    fn colour_parameters() {
        let ctx = at(0.5);
        let melanin = |e: f32| Hair {
            convention: HairConvention::Pbrt,
            colour: HairColour::Melanin(Texture::Constant(Rgb::splat(e)), Texture::Constant(Rgb::ZERO)),
            ..hair(Rgb::ZERO, 0.3, 0.3, 2.0)
        };
        let s = melanin(1.3).sigma_a(&ctx);
        assert!((s - EUMELANIN * 1.3).abs().max_element() < 1e-6);
        let albedo = |h: &Hair| {
            let wo = Vec3::new(0.2, 0.3, 0.93).normalize();
            crate::testkit::integrate_pdf_2d(&SPHERE, [32, 64], |wi| h.eval(&ctx, wo, *wi).x as f64)
        };
        assert!(albedo(&melanin(8.0)) < albedo(&melanin(0.3)));
        let reflect = |c: f32| Hair {
            convention: HairConvention::Pbrt,
            colour: HairColour::Reflectance(Texture::Constant(Rgb::splat(c))),
            ..hair(Rgb::ZERO, 0.3, 0.3, 2.0)
        };
        assert!(reflect(0.2).sigma_a(&ctx).x > reflect(0.8).sigma_a(&ctx).x);
        assert!(reflect(1.0).sigma_a(&ctx).x < 1e-6);
    }

    /// `I₀` and `ln I₀` within 10⁻⁶ and 5·10⁻⁷ (relative; `ln I₀` absolute below 1) of the
    /// series summed in double precision to convergence, over 0–80.
    #[test]
    fn bessel_i0_is_accurate() {
        for k in 0..=1600 {
            let x = (k as f32 * 0.05) as f64;
            let q = 0.25 * x * x;
            let (mut term, mut sum) = (1.0f64, 1.0f64);
            for i in 1..200 {
                term *= q / (i * i) as f64;
                sum += term;
            }
            if x < 40.0 {
                let got = bessel_i0(x as f32) as f64;
                assert!((got / sum - 1.0).abs() < 1e-6, "I0({x}) = {got} vs {sum}");
            }
            let got = log_bessel_i0(x as f32) as f64;
            assert!((got - sum.ln()).abs() < 5e-7 * sum.ln().max(1.0), "ln I0({x}) = {got} vs {}", sum.ln());
        }
    }

    /// Mitsuba's `hair`: `eval` and `pdf` equal Mitsuba 3.9.1's (scalar_rgb) for its defaults
    /// (`A`: eumelanin 1.3, pheomelanin 0.2) and for `B` (`sigma_a` (0.2, 0.4, 0.9) × `scale`
    /// 1.5, roughness 0.2 and 0.5, `scale_tilt` 3°, `int_ior` 1.6), directions on both sides (its
    /// `si.wi` is our `wo`). To 1 %: Mitsuba truncates the Bessel series of `M_p` at ten terms
    /// (0.35 % low on the first row); with its series instead (tried) every row agrees to 2·10⁻⁴.
    #[test]
    fn mitsuba_convention_matches_mitsuba() {
        use crate::material::tests::{assert_matches_mitsuba_within, MitsubaRow};
        let rows: &[MitsubaRow] = &[
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.1293154, 0.129268, 0.1292573],
                0.6363897,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [0.7419985, 0.6359987, 0.2119996],
                [1.002183e-05, 1.714972e-06, 4.420893e-08],
                1.65452e-05,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [-0.3504559, 0.1001303, -0.9312114],
                [0.03736037, 0.01680006, 0.002301859],
                0.09907525,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [0.1154701, -0.5773503, 0.8082904],
                [0.004603649, 0.003464574, 0.003182078],
                0.01814711,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [-0.2500864, -0.2000691, 0.9473274],
                [8.108599e-05, 2.488308e-05, 1.521906e-05],
                0.000126494,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [0.7419985, 0.6359987, 0.2119996],
                [0.004774022, 0.00475332, 0.004750253],
                0.01665254,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [-0.3504559, 0.1001303, -0.9312114],
                [0.01400745, 0.007119063, 0.001329938],
                0.028584,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [0.1154701, -0.5773503, 0.8082904],
                [0.0001584011, 0.0001175032, 0.0001114006],
                0.000440196,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.2500864, -0.2000691, 0.9473274],
                [3.354502e-05, 9.954832e-06, 7.321222e-06],
                5.196343e-05,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [0.7419985, 0.6359987, 0.2119996],
                [0.001123623, 0.0002075006, 3.509336e-06],
                0.001362604,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.3504559, 0.1001303, -0.9312114],
                [4.607188e-05, 5.169829e-06, 2.49201e-07],
                4.750479e-05,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [0.1154701, -0.5773503, 0.8082904],
                [5.802453e-05, 1.036931e-05, 1.677417e-07],
                6.949198e-05,
            ),
            (
                'A',
                [0.1301889, 0.9113224, -0.3905667],
                [-0.2500864, -0.2000691, 0.9473274],
                [1.293386e-05, 6.417137e-07, 3.941416e-10],
                1.383049e-05,
            ),
            (
                'A',
                [0.1301889, 0.9113224, -0.3905667],
                [0.7419985, 0.6359987, 0.2119996],
                [1.209245e-06, 5.999403e-08, 3.572992e-11],
                1.293067e-06,
            ),
            (
                'A',
                [0.1301889, 0.9113224, -0.3905667],
                [-0.3504559, 0.1001303, -0.9312114],
                [0.0006956107, 0.0004645401, 0.0004286817],
                0.002202349,
            ),
            (
                'A',
                [0.1301889, 0.9113224, -0.3905667],
                [0.1154701, -0.5773503, 0.8082904],
                [0.0001895022, 5.974368e-05, 4.910503e-06],
                0.0003593015,
            ),
            (
                'B',
                [0.3007679, 0.200512, 0.9323806],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.09794067, 0.0953683, 0.09426193],
                0.2625282,
            ),
            (
                'B',
                [0.3007679, 0.200512, 0.9323806],
                [0.7419985, 0.6359987, 0.2119996],
                [4.467951e-05, 1.302226e-05, 7.513869e-07],
                5.168973e-05,
            ),
            (
                'B',
                [0.3007679, 0.200512, 0.9323806],
                [-0.3504559, 0.1001303, -0.9312114],
                [0.0006848817, 0.0003675722, 0.0001012586],
                0.001139123,
            ),
            (
                'B',
                [0.3007679, 0.200512, 0.9323806],
                [0.1154701, -0.5773503, 0.8082904],
                [0.01226079, 0.004443138, 0.001197902],
                0.01608422,
            ),
            (
                'B',
                [-0.8601653, 0.161281, 0.483843],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.008912737, 0.006423355, 0.005174931],
                0.01564301,
            ),
            (
                'B',
                [-0.8601653, 0.161281, 0.483843],
                [0.7419985, 0.6359987, 0.2119996],
                [8.026951e-05, 5.494444e-05, 4.822917e-05],
                0.0001364143,
            ),
            (
                'B',
                [-0.8601653, 0.161281, 0.483843],
                [-0.3504559, 0.1001303, -0.9312114],
                [0.00274476, 0.001513957, 0.0004478222],
                0.003872235,
            ),
            (
                'B',
                [-0.8601653, 0.161281, 0.483843],
                [0.1154701, -0.5773503, 0.8082904],
                [0.001234282, 0.0005835974, 0.0002853685],
                0.001596643,
            ),
            (
                'B',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.0004585535, 0.0001323745, 6.15426e-06],
                0.0004618301,
            ),
            (
                'B',
                [0.5976143, -0.7171372, 0.3585686],
                [0.7419985, 0.6359987, 0.2119996],
                [0.03017595, 0.01214737, 0.001954959],
                0.03655134,
            ),
            (
                'B',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.3504559, 0.1001303, -0.9312114],
                [0.0001298701, 2.031723e-05, 3.957412e-07],
                0.0001011201,
            ),
            (
                'B',
                [0.5976143, -0.7171372, 0.3585686],
                [0.1154701, -0.5773503, 0.8082904],
                [0.0001149631, 3.379363e-05, 1.595572e-06],
                0.0001168332,
            ),
            (
                'B',
                [0.1301889, 0.9113224, -0.3905667],
                [-0.2500864, -0.2000691, 0.9473274],
                [2.404359e-05, 2.710689e-06, 1.901962e-08],
                1.958279e-05,
            ),
            (
                'B',
                [0.1301889, 0.9113224, -0.3905667],
                [0.7419985, 0.6359987, 0.2119996],
                [3.268282e-08, 3.575771e-09, 1.606138e-11],
                2.640097e-08,
            ),
            (
                'B',
                [0.1301889, 0.9113224, -0.3905667],
                [-0.3504559, 0.1001303, -0.9312114],
                [4.153947e-05, 9.370143e-06, 2.451851e-07],
                4.318145e-05,
            ),
            (
                'B',
                [0.1301889, 0.9113224, -0.3905667],
                [0.1154701, -0.5773503, 0.8082904],
                [0.0002356575, 2.775453e-05, 2.166953e-06],
                0.0001946884,
            ),
        ];
        let config = |k: char| {
            let (colour, beta_m, beta_n, alpha, eta) = match k {
                'A' => (
                    HairColour::Melanin(Rgb::splat(1.3).into(), Rgb::splat(0.2).into()),
                    0.3,
                    0.3,
                    2.0,
                    1.55 / 1.000277,
                ),
                _ => (HairColour::Absorption(Rgb::new(0.3, 0.6, 1.35).into()), 0.2, 0.5, 3.0, 1.6 / 1.000277),
            };
            Bsdf::Hair(Box::new(Hair { convention: HairConvention::Mitsuba, colour, eta, beta_m, beta_n, alpha }))
        };
        assert_matches_mitsuba_within(1e-2, rows, config, |_, _, pdf| pdf);
    }
}
