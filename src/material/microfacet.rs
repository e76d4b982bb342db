//! Microfacet distributions: GGX (Trowbridge–Reitz), Beckmann and Blinn–Phong, isotropic or
//! anisotropic, with Smith shadowing and visible-normal sampling.
//!
//! All in the local frame (macro-surface normal +z). `D(m)` is the distribution of microfacet
//! normals, normalized so that `∫ D(m) cos θ_m dω_m = 1` (projected area of the microsurface
//! equals the macro-surface's). The Smith masking function `G1(w, m)` gives the fraction of
//! microfacets with normal `m` visible from `w`; with it, the *visible normal* distribution
//! `D_w(m) = G1(w, m) max(0, w·m) D(m) / cos θ_w` integrates to one and is what rough BSDFs
//! sample (Heitz 2014), which keeps their weights bounded.
//!
//! - GGX: `D(m) = 1 / (π αᵤ αᵥ (m_x²/αᵤ² + m_y²/αᵥ² + m_z²)²)`; visible normals sampled by Heitz's
//!   2018 method (hemisphere of the stretched configuration).
//! - Beckmann: `D(m) = exp(-(m_x²/αᵤ² + m_y²/αᵥ²)/cos²θ) / (π αᵤ αᵥ cos⁴θ)`; visible normals
//!   sampled by Jakob's 2014 inversion of the slope distribution (Newton on `erf`).
//! - Blinn–Phong with exponent n: `D(m) = (n+2)/(2π) cosⁿ θ_m`. Sampling `D(m) cos θ_m` needs
//!   `p(cos θ_m) = (n+2) cos^(n+1) θ_m` (from `dω = d cos θ dφ`): the seeds' power law with
//!   exponent n+1, hence `cos θ_m = ξ^(1/(n+2))`. Its shadowing uses the Beckmann G1 with the
//!   equivalent roughness `α = √(2/(n+2))` (Walter et al. 2007). It samples `D(m) cos θ_m`, not
//!   the visible normals.

use crate::math::special::{erf, erfinv, exp};
use crate::math::spectrum::SpectrumKind;
use crate::math::{safe_sqrt, Rgb, Vec2, Vec3, INV_PI, PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::{sample_power, Sample};
use crate::texture::{Texture, TextureSource};

/// Which microfacet distribution (Mitsuba's `distribution` parameter, plus Blinn–Phong).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MicrofacetType {
    /// Beckmann.
    Beckmann,
    /// GGX / Trowbridge–Reitz.
    Ggx,
    /// Blinn–Phong with the given exponent (sampled by the power law).
    BlinnPhong(f32),
}

/// A microfacet distribution with roughness `alpha_u` (along the tangent, x) and `alpha_v` (y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    /// Distribution type.
    pub kind: MicrofacetType,
    /// Roughness along x.
    pub alpha_u: f32,
    /// Roughness along y.
    pub alpha_v: f32,
}

const MIN_ALPHA: f32 = 1e-4;
const INV_SQRT_PI: f32 = 0.564_189_6;

impl Microfacet {
    /// A Beckmann or GGX distribution; roughness is clamped to ≥ 10⁻⁴.
    pub fn new(kind: MicrofacetType, alpha_u: f32, alpha_v: f32) -> Microfacet {
        Microfacet { kind, alpha_u: alpha_u.max(MIN_ALPHA), alpha_v: alpha_v.max(MIN_ALPHA) }
    }

    /// Blinn–Phong with exponent `n ≥ 0` (roughness fields hold the equivalent Beckmann α).
    pub fn blinn_phong(n: f32) -> Microfacet {
        let n = n.max(0.0);
        let a = (2.0 / (n + 2.0)).sqrt();
        Microfacet { kind: MicrofacetType::BlinnPhong(n), alpha_u: a, alpha_v: a }
    }

    /// Whether [`Microfacet::sample`] samples visible normals (GGX and Beckmann), so that its
    /// density is `G1(wi, m) (wi·m) D(m) / cos θᵢ` and sampling weights simplify.
    pub fn samples_visible_normals(&self) -> bool {
        !matches!(self.kind, MicrofacetType::BlinnPhong(_))
    }

    /// Whether the distribution is anisotropic.
    pub fn is_anisotropic(&self) -> bool {
        self.alpha_u != self.alpha_v
    }

    /// Microfacet normal density `D(m)` (per unit solid angle of m, projected-area normalized).
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        let cos2 = m.z * m.z;
        if m.z <= 0.0 {
            return 0.0;
        }
        let (au, av) = (self.alpha_u, self.alpha_v);
        let r = match self.kind {
            MicrofacetType::Ggx => {
                let s = (m.x / au).powi(2) + (m.y / av).powi(2) + cos2;
                1.0 / (PI * au * av * s * s)
            }
            MicrofacetType::Beckmann => {
                let e = ((m.x / au).powi(2) + (m.y / av).powi(2)) / cos2;
                exp(-e) / (PI * au * av * cos2 * cos2)
            }
            MicrofacetType::BlinnPhong(n) => (n + 2.0) * 0.5 * INV_PI * m.z.powf(n),
        };
        if r.is_finite() {
            r
        } else {
            0.0
        }
    }

    /// Smith `Λ(w)`, from which `G1 = 1 / (1 + Λ)`.
    #[inline]
    fn lambda(&self, w: Vec3) -> f32 {
        let xy_alpha2 = (self.alpha_u * w.x).powi(2) + (self.alpha_v * w.y).powi(2);
        if xy_alpha2 == 0.0 {
            return 0.0;
        }
        let tan2_alpha2 = xy_alpha2 / (w.z * w.z);
        match self.kind {
            MicrofacetType::Ggx => 0.5 * (-1.0 + (1.0 + tan2_alpha2).sqrt()),
            MicrofacetType::Beckmann | MicrofacetType::BlinnPhong(_) => {
                let a = 1.0 / tan2_alpha2.sqrt();
                // From a = 4 on, erf(a) is 1 in single precision and Λ under 2⁻²⁵: every use,
                // 1 / (1 + Λ), is exactly 1 either way (tested), without the erf and the
                // exponential. Smooth surfaces seen away from grazing are all there.
                if a >= BECKMANN_LAMBDA_ZERO {
                    return 0.0;
                }
                beckmann_lambda(a)
            }
        }
    }

    /// Smith masking `G1(w, m)`: 0 when `w` sees the back of `m` or of the macro-surface.
    #[inline]
    pub fn g1(&self, w: Vec3, m: Vec3) -> f32 {
        if w.dot(m) * w.z <= 0.0 {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(w))
    }

    /// Separable shadowing-masking `G(wi, wo, m) = G1(wi, m) G1(wo, m)` (as Mitsuba 3).
    #[inline]
    pub fn g(&self, wi: Vec3, wo: Vec3, m: Vec3) -> f32 {
        self.g1(wi, m) * self.g1(wo, m)
    }

    /// Density of [`Microfacet::sample`] producing `m` for the direction `wi` (z > 0): the visible
    /// normal density `G1(wi, m) max(0, wi·m) D(m) / cos θᵢ` for GGX and Beckmann, `D(m) cos θ_m`
    /// for Blinn–Phong. Per unit solid angle of `m`.
    #[inline]
    pub fn pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        match self.kind {
            MicrofacetType::BlinnPhong(_) => self.d(m) * m.z.max(0.0),
            _ => self.visible_pdf(wi, m, || 1.0 / (1.0 + self.lambda(wi))),
        }
    }

    /// [`Microfacet::pdf`] from `d = D(m)` and `g1 = G1(wi, m)` evaluated already (by
    /// [`Microfacet::d`] and [`Microfacet::g1`], as a BSDF's value needs them): the same density,
    /// bit for bit, without evaluating them again.
    #[inline]
    pub fn pdf_given(&self, wi: Vec3, m: Vec3, d: f32, g1: f32) -> f32 {
        match self.kind {
            MicrofacetType::BlinnPhong(_) => d * m.z.max(0.0),
            _ if wi.z <= 0.0 => 0.0,
            _ => visible_density(wi, m, d, g1),
        }
    }

    /// The visible normal density `G1(wi, m) max(0, wi·m) D(m) / cos θᵢ` with `G1(wi, ·)` where
    /// `wi` sees the front of `m` given by `g1_front` (it does not depend on `m`: `1 / (1 + Λ(wi))`,
    /// which [`Microfacet::sample_grid`] computes once per direction).
    #[inline(always)]
    fn visible_pdf(&self, wi: Vec3, m: Vec3, g1_front: impl FnOnce() -> f32) -> f32 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        // As `g1`: zero where `wi` sees the back of `m` or of the macro-surface.
        let g1 = if wi.dot(m) * wi.z <= 0.0 { 0.0 } else { g1_front() };
        visible_density(wi, m, self.d(m), g1)
    }

    /// Samples a microfacet normal for the direction `wi` (local, z > 0) from `u ∈ [0,1)²`:
    /// a visible normal for GGX and Beckmann, `D(m) cos θ_m` for Blinn–Phong.
    #[inline]
    pub fn sample(&self, wi: Vec3, u: Vec2) -> Sample<Vec3> {
        let m = match self.kind {
            MicrofacetType::Ggx => self.sample_ggx_visible(wi, u),
            MicrofacetType::Beckmann => self.sample_beckmann_visible(wi, u),
            MicrofacetType::BlinnPhong(n) => {
                let cos_theta = sample_power(u.x, n + 1.0).value;
                let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
                let (s, c) = crate::math::sin_cos_2pi(u.y);
                Vec3::new(sin_theta * c, sin_theta * s, cos_theta)
            }
        };
        Sample::solid_angle(m, self.pdf(wi, m))
    }

    /// The normal [`Microfacet::sample`] samples, without its density (GGX and Beckmann).
    #[inline]
    pub(crate) fn sample_visible_normal(&self, wi: Vec3, u: Vec2) -> Vec3 {
        match self.kind {
            MicrofacetType::Ggx => self.sample_ggx_visible(wi, u),
            _ => self.sample_beckmann_visible(wi, u),
        }
    }

    /// Heitz 2018: sample the visible hemisphere of the stretched (α = 1) configuration as a
    /// disk warped toward the projected hemisphere, then unstretch.
    fn sample_ggx_visible(&self, wi: Vec3, u: Vec2) -> Vec3 {
        let view = GgxView::new(self, wi);
        let phi = 2.0 * PI * u.y;
        view.normal(self, u.x.sqrt(), (phi.cos(), phi.sin()))
    }

    /// Jakob 2014: sample the slope distribution of the stretched configuration seen from `wi`
    /// by inverting its CDF in x (Newton–bisection on `erf`) and y (`erfinv`), then rotate and
    /// unstretch.
    fn sample_beckmann_visible(&self, wi: Vec3, u: Vec2) -> Vec3 {
        let (slopes, cos_phi, sin_phi) = self.beckmann_view(wi);
        let (sx, sy) = slopes.combine(slopes.x(u.x), slopes.y(u.y));
        self.beckmann_normal(cos_phi, sin_phi, sx, sy)
    }

    /// What Beckmann visible-normal sampling for `wi` computes before it looks at `u`: the
    /// slope sampler of the stretched direction, and that direction's azimuth (cos φ, sin φ).
    #[inline(always)]
    fn beckmann_view(&self, wi: Vec3) -> (BeckmannSlopes, f32, f32) {
        let ws = Vec3::new(self.alpha_u * wi.x, self.alpha_v * wi.y, wi.z).normalize();
        let xy = (ws.x * ws.x + ws.y * ws.y).sqrt();
        let (cos_phi, sin_phi) = if xy > 0.0 { (ws.x / xy, ws.y / xy) } else { (1.0, 0.0) };
        (BeckmannSlopes::new(ws.z), cos_phi, sin_phi)
    }

    /// The microfacet normal of stretched slopes `(sx, sy)` sampled in the frame of azimuth φ:
    /// rotated by φ, then unstretched.
    #[inline(always)]
    fn beckmann_normal(&self, cos_phi: f32, sin_phi: f32, sx: f32, sy: f32) -> Vec3 {
        let (rx, ry) = (cos_phi * sx - sin_phi * sy, sin_phi * sx + cos_phi * sy);
        Vec3::new(-rx * self.alpha_u, -ry * self.alpha_v, 1.0).normalize()
    }

    /// Calls `f(i, j, s)` for every `i < ux.len()`, `j < uy.len()` (row by row) with the sample
    /// `s` that [`Microfacet::sample`] gives for `wi` and `u = (ux[i], uy[j])`, bit for bit: a
    /// product grid of random numbers, as quadrature over visible normals uses. The normals come
    /// from [`Microfacet::sample_grid_normals`]; `G1(wi)` of the density is computed once.
    pub fn sample_grid(&self, wi: Vec3, ux: &[f32], uy: &[f32], mut f: impl FnMut(usize, usize, Sample<Vec3>)) {
        if let MicrofacetType::BlinnPhong(_) = self.kind {
            for (i, &x) in ux.iter().enumerate() {
                for (j, &y) in uy.iter().enumerate() {
                    f(i, j, self.sample(wi, Vec2::new(x, y)));
                }
            }
            return;
        }
        let g1_front = 1.0 / (1.0 + self.lambda(wi));
        self.sample_grid_normals(wi, ux, uy, |i, j, m| {
            f(i, j, Sample::solid_angle(m, self.visible_pdf(wi, m, || g1_front)));
        });
    }

    /// [`Microfacet::sample_grid`]'s normals alone, without their density (what Mitsuba's
    /// `eval_reflectance` quadrature uses: it never looks at the density, whose `D(m)` costs an
    /// exponential per Beckmann normal). The work that depends on one coordinate only is done
    /// once per coordinate: for Beckmann the Newton inversion of the x slope per `ux[i]` and the
    /// y slope per `uy[j]`, for GGX the disk radius and angle; what remains per normal is its
    /// normalization.
    pub fn sample_grid_normals(&self, wi: Vec3, ux: &[f32], uy: &[f32], mut f: impl FnMut(usize, usize, Vec3)) {
        match self.kind {
            MicrofacetType::Beckmann => {
                let (slopes, cos_phi, sin_phi) = self.beckmann_view(wi);
                let xs: Vec<f32> = ux.iter().map(|&u| slopes.x(u)).collect();
                let ys: Vec<(f32, f32)> = uy.iter().map(|&u| slopes.y(u)).collect();
                product_grid(&xs, &ys, f, |x, y| {
                    let (sx, sy) = slopes.combine(x, y);
                    self.beckmann_normal(cos_phi, sin_phi, sx, sy)
                });
            }
            MicrofacetType::Ggx => {
                let view = GgxView::new(self, wi);
                let rs: Vec<f32> = ux.iter().map(|&u| u.sqrt()).collect();
                let angles: Vec<(f32, f32)> = uy
                    .iter()
                    .map(|&u| {
                        let phi = 2.0 * PI * u;
                        (phi.cos(), phi.sin())
                    })
                    .collect();
                product_grid(&rs, &angles, f, |r, angle| view.normal(self, r, angle));
            }
            MicrofacetType::BlinnPhong(_) => {
                for (i, &x) in ux.iter().enumerate() {
                    for (j, &y) in uy.iter().enumerate() {
                        f(i, j, self.sample(wi, Vec2::new(x, y)).value);
                    }
                }
            }
        }
    }
}

/// Calls `f(i, j, normal(xs[i], ys[j]))` row by row: a product grid from per-coordinate parts.
#[inline(always)]
fn product_grid<X: Copy, Y: Copy>(
    xs: &[X],
    ys: &[Y],
    mut f: impl FnMut(usize, usize, Vec3),
    normal: impl Fn(X, Y) -> Vec3,
) {
    for (i, &x) in xs.iter().enumerate() {
        for (j, &y) in ys.iter().enumerate() {
            f(i, j, normal(x, y));
        }
    }
}

/// What GGX visible-normal sampling (Heitz 2018) for one direction computes before it looks at
/// `u`: the stretched direction `vh`, the frame `(t1, t2)` around it, and the warp's blend `s`.
#[derive(Clone, Copy, Debug)]
struct GgxView {
    vh: Vec3,
    t1: Vec3,
    t2: Vec3,
    s: f32,
}

impl GgxView {
    #[inline(always)]
    fn new(md: &Microfacet, wi: Vec3) -> GgxView {
        let vh = Vec3::new(md.alpha_u * wi.x, md.alpha_v * wi.y, wi.z).normalize();
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt() } else { Vec3::X };
        GgxView { vh, t1, t2: vh.cross(t1), s: 0.5 * (1.0 + vh.z) }
    }

    /// The normal of the disk point at radius `r = √u.x` and angle `(cos, sin)` of `2π u.y`:
    /// warped toward the projected hemisphere, lifted onto it, unstretched.
    #[inline(always)]
    fn normal(&self, md: &Microfacet, r: f32, (cos_phi, sin_phi): (f32, f32)) -> Vec3 {
        let p1 = r * cos_phi;
        let p2 = (1.0 - self.s) * safe_sqrt(1.0 - p1 * p1) + self.s * (r * sin_phi);
        let nh = self.t1 * p1 + self.t2 * p2 + self.vh * safe_sqrt(1.0 - p1 * p1 - p2 * p2);
        Vec3::new(md.alpha_u * nh.x, md.alpha_v * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// Where [`Microfacet::lambda`] of Beckmann stops evaluating: `1 / (1 + Λ(a))` is exactly 1 from
/// here on.
pub(crate) const BECKMANN_LAMBDA_ZERO: f32 = 4.0;

/// Beckmann's Smith `Λ` at `a = 1 / (α tan θ)`: `(erf(a) − 1) / 2 + e^(−a²) / (2a√π)`.
#[inline]
pub(crate) fn beckmann_lambda(a: f32) -> f32 {
    0.5 * (erf(a) - 1.0) + exp(-a * a) * INV_SQRT_PI / (2.0 * a)
}

/// Jakob's sampling of the slopes of visible Beckmann microfacets (α = 1) seen at `cos θᵢ`,
/// split by random number: the x slope depends on `u.x` alone (the inversion of its CDF), the
/// y slope on `u.y` alone; at normal incidence (a 2D Gaussian, sampled in polar form) the
/// radius on `u.x` and the direction on `u.y`. [`BeckmannSlopes::combine`] makes the pair.
#[derive(Clone, Copy, Debug)]
struct BeckmannSlopes {
    /// Normal incidence (`cos θᵢ > 0.9999`): polar sampling of the Gaussian.
    normal: bool,
    tan_theta_i: f32,
    /// `erf(cot θᵢ)`: the CDF's upper end in `b = erf(x)`.
    c: f32,
    /// Exponent of the initial guess's fit.
    fit: f32,
    /// `1 / (1 + c + tan θᵢ e^(-cot² θᵢ) / √π)`: the CDF's normalization.
    normalization: f32,
}

impl BeckmannSlopes {
    #[inline(always)]
    fn new(cos_theta_i: f32) -> BeckmannSlopes {
        if cos_theta_i > 0.9999 {
            return BeckmannSlopes { normal: true, tan_theta_i: 0.0, c: 0.0, fit: 0.0, normalization: 0.0 };
        }
        let sin_theta_i = safe_sqrt(1.0 - cos_theta_i * cos_theta_i);
        let tan_theta_i = sin_theta_i / cos_theta_i;
        let cot_theta_i = 1.0 / tan_theta_i;
        let c = erf(cot_theta_i);
        let theta_i = cos_theta_i.acos();
        let fit = 1.0 + theta_i * (-0.876 + theta_i * (0.4265 - 0.0594 * theta_i));
        let normalization = 1.0 / (1.0 + c + INV_SQRT_PI * tan_theta_i * exp(-cot_theta_i * cot_theta_i));
        BeckmannSlopes { normal: false, tan_theta_i, c, fit, normalization }
    }

    /// The part of `u.x`: the x slope, or at normal incidence the radius.
    #[inline(always)]
    fn x(&self, ux: f32) -> f32 {
        if self.normal {
            return safe_sqrt(-(-ux).ln_1p());
        }
        // The CDF of the x slope, F(x) ∝ 1 + erf(x) + tan θᵢ e^(-x²)/√π over (-∞, cot θᵢ],
        // inverted by a safeguarded Newton iteration on b = erf(x) ∈ (a, c).
        let (tan_theta_i, normalization) = (self.tan_theta_i, self.normalization);
        let (mut a, mut c) = (-1.0f32, self.c);
        let sample_x = ux.max(1e-6);
        let mut b = c - (1.0 + c) * (1.0 - sample_x).powf(self.fit);
        for _ in 0..20 {
            if !(b >= a && b <= c) {
                b = 0.5 * (a + c);
            }
            let inv_erf = erfinv(b);
            let value = normalization * (1.0 + b + INV_SQRT_PI * tan_theta_i * exp(-inv_erf * inv_erf)) - sample_x;
            let derivative = normalization * (1.0 - inv_erf * tan_theta_i);
            if value.abs() < 1e-6 {
                // Converged at b, whose inverse is at hand.
                return inv_erf;
            }
            if value > 0.0 {
                c = b;
            } else {
                a = b;
            }
            b -= value / derivative;
        }
        erfinv(b)
    }

    /// The part of `u.y`: the y slope (second entry unused), or at normal incidence the
    /// direction `(sin 2πu, cos 2πu)`.
    #[inline(always)]
    fn y(&self, uy: f32) -> (f32, f32) {
        if self.normal {
            crate::math::sin_cos_2pi(uy)
        } else {
            (erfinv(2.0 * uy.max(1e-6) - 1.0), 0.0)
        }
    }

    /// The slopes `(x, y)` from the two parts.
    #[inline(always)]
    fn combine(&self, x: f32, y: (f32, f32)) -> (f32, f32) {
        if self.normal {
            (x * y.1, x * y.0)
        } else {
            (x, y.0)
        }
    }
}

/// The microfacet distribution of a rough surface whose roughness may vary over it (Mitsuba's
/// textured `alpha`, `alpha_u`, `alpha_v` of `roughconductor` and `roughdielectric`).
#[derive(Clone, Debug)]
pub struct Roughness {
    /// The distribution (its roughness replaced by the textures' where they are given).
    pub distribution: Microfacet,
    /// Roughness textures (α_u, α_v; their luminance), if the roughness varies over the surface.
    pub textures: Option<Box<[Texture; 2]>>,
    /// Whether the textures' roughness is regularized ([`regularize_alpha`]) where it is
    /// looked up (a constant distribution is regularized once, when made).
    pub regularized: bool,
}

/// pbrt-v4's path regularization of a Trowbridge–Reitz (GGX) roughness `α`: below 0.3 it is
/// doubled and clamped to [0.1, 0.3] (a smooth surface, α = 0, becomes α = 0.1); from 0.3 on it
/// is kept. Biased — near-specular paths blur into ones the light sampling can find — and
/// applied only after a path's first non-specular bounce (`regularize` of `path`, `volpath`).
#[inline]
pub fn regularize_alpha(alpha: f32) -> f32 {
    if alpha < 0.3 {
        (2.0 * alpha).clamp(0.1, 0.3)
    } else {
        alpha
    }
}

impl From<Microfacet> for Roughness {
    fn from(distribution: Microfacet) -> Roughness {
        Roughness { distribution, textures: None, regularized: false }
    }
}

impl Roughness {
    /// The distribution at `ctx` (textured roughness evaluated there, clamped to ≥ 10⁻⁴).
    #[inline]
    pub fn at(&self, ctx: &super::BsdfContext) -> Microfacet {
        match &self.textures {
            None => self.distribution,
            Some(t) => {
                let alpha = |t: &Texture| {
                    let a = ctx.scalar(t);
                    if self.regularized {
                        regularize_alpha(a)
                    } else {
                        a
                    }
                };
                Microfacet::new(self.distribution.kind, alpha(&t[0]), alpha(&t[1]))
            }
        }
    }

    /// This roughness under pbrt-v4's path regularization ([`regularize_alpha`]).
    pub fn regularized(&self) -> Roughness {
        let d = self.distribution;
        if matches!(d.kind, MicrofacetType::BlinnPhong(_)) {
            return self.clone();
        }
        Roughness {
            distribution: Microfacet::new(d.kind, regularize_alpha(d.alpha_u), regularize_alpha(d.alpha_v)),
            textures: self.textures.clone(),
            regularized: true,
        }
    }

    /// The roughness textures (none if the roughness is constant).
    pub fn textures(&self) -> impl Iterator<Item = &Texture> {
        self.textures.iter().flat_map(|t| t.iter())
    }

    /// Mitsuba's anisotropic rough-surface parameters ([`Microfacet::from_props`]), where
    /// `alpha` or `alpha_u` / `alpha_v` may be textures (then `distribution` is `beckmann` or
    /// `ggx`).
    pub fn from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Roughness> {
        let textured =
            ["alpha", "alpha_u", "alpha_v"].iter().any(|n| matches!(o.object_opt(n, "texture"), Ok(Some(_))));
        if !textured {
            return Microfacet::from_props(o, true).map(Roughness::from);
        }
        let (au, av) = if o.has("alpha") {
            if o.has("alpha_u") || o.has("alpha_v") {
                return Err(o.error_at("alpha", "give either 'alpha' or 'alpha_u'/'alpha_v'"));
            }
            let a = b.texture_of(o, "alpha", Rgb::splat(0.1), SpectrumKind::Unbounded)?;
            (a.clone(), a)
        } else {
            both_alphas(o)?;
            let a = |b: &mut dyn TextureSource, n| b.texture_of(o, n, Rgb::splat(0.1), SpectrumKind::Unbounded);
            (a(b, "alpha_u")?, a(b, "alpha_v")?)
        };
        Ok(Roughness {
            distribution: Microfacet::kind_from_props(o)?,
            textures: Some(Box::new([au, av])),
            regularized: false,
        })
    }
}

impl Microfacet {
    /// A distribution of Mitsuba's `distribution` (`beckmann` or `ggx`) whose roughness comes
    /// from elsewhere (textures): α = 0.1 here.
    pub fn kind_from_props(o: &Obj) -> PropResult<Microfacet> {
        let kind = match o.choice("distribution", &["beckmann", "ggx"])?.as_str() {
            "beckmann" => MicrofacetType::Beckmann,
            _ => MicrofacetType::Ggx,
        };
        o.bool("sample_visible", true)?;
        Ok(Microfacet::new(kind, 0.1, 0.1))
    }

    /// Mitsuba's rough-surface parameters: `distribution` (`beckmann` (default), `ggx`, `phong`
    /// with `exponent` or `alpha` → `n = 2/α² − 2`), `alpha` (0.1) or, if `anisotropic`,
    /// `alpha_u` / `alpha_v`; `sample_visible` is read (visible normals are always sampled).
    pub fn from_props(o: &Obj, anisotropic: bool) -> PropResult<Microfacet> {
        let kind = match o.choice("distribution", &["beckmann", "ggx", "phong"])?.as_str() {
            "beckmann" => MicrofacetType::Beckmann,
            "ggx" => MicrofacetType::Ggx,
            _ => {
                // Blinn–Phong (Mitsuba 0.6's "phong"): exponent given, or from alpha by n = 2/α² - 2.
                let n = match o.float_opt("exponent")? {
                    Some(n) => n,
                    None => {
                        let a = o.float_checked("alpha", 0.1, |a| a > 0.0, "positive")?;
                        2.0 / (a * a) - 2.0
                    }
                };
                if !(n >= 0.0 && n.is_finite()) {
                    return Err(o.error_at("exponent", format!("the Phong exponent must be ≥ 0, got {n}")));
                }
                return Ok(Microfacet::blinn_phong(n));
            }
        };
        let rough = |name: &str, default: f32| o.float_checked(name, default, |a| a >= 0.0 && a.is_finite(), "≥ 0");
        let (au, av) = if anisotropic && (o.has("alpha_u") || o.has("alpha_v")) {
            if o.has("alpha") {
                return Err(o.error_at("alpha", "give either 'alpha' or 'alpha_u'/'alpha_v'"));
            }
            both_alphas(o)?;
            (rough("alpha_u", 0.1)?, rough("alpha_v", 0.1)?)
        } else {
            let a = rough("alpha", 0.1)?;
            (a, a)
        };
        o.bool("sample_visible", true)?;
        Ok(Microfacet::new(kind, au, av))
    }
}

/// Anisotropic roughness needs both `alpha_u` and `alpha_v`, as Mitsuba 3.9.1 requires.
fn both_alphas(o: &Obj) -> PropResult<()> {
    match (o.has("alpha_u"), o.has("alpha_v")) {
        (true, false) => Err(o.error_at("alpha_u", "'alpha_u' needs 'alpha_v' too (Mitsuba requires both)")),
        (false, true) => Err(o.error_at("alpha_v", "'alpha_v' needs 'alpha_u' too (Mitsuba requires both)")),
        _ => Ok(()),
    }
}

/// `G1(wi, m) max(0, wi·m) D(m) / cos θᵢ` for `cos θᵢ > 0` (one expression, so that every
/// caller's density has the same bits).
#[inline(always)]
fn visible_density(wi: Vec3, m: Vec3, d: f32, g1: f32) -> f32 {
    g1 * wi.dot(m).max(0.0) * d / wi.z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, integrate_pdf_2d, u2, Chi2Config, HEMISPHERE, SPHERE};

    fn distributions() -> Vec<Microfacet> {
        vec![
            Microfacet::new(MicrofacetType::Ggx, 0.3, 0.3),
            Microfacet::new(MicrofacetType::Ggx, 0.05, 0.4),
            Microfacet::new(MicrofacetType::Ggx, 0.9, 0.9),
            Microfacet::new(MicrofacetType::Beckmann, 0.3, 0.3),
            Microfacet::new(MicrofacetType::Beckmann, 0.6, 0.15),
            Microfacet::blinn_phong(20.0),
        ]
    }

    fn incident() -> Vec<Vec3> {
        vec![Vec3::Z, Vec3::new(0.5, 0.2, 0.84).normalize(), Vec3::new(-0.95, 0.1, 0.2).normalize()]
    }

    #[test]
    fn d_is_projected_area_normalized() {
        for md in distributions() {
            let total = integrate_pdf_2d(&HEMISPHERE, [128, 32], |m| (md.d(*m) * m.z) as f64);
            assert!((total - 1.0).abs() < 2e-3, "{md:?}: ∫ D cos = {total}");
        }
    }

    #[test]
    fn visible_normal_density_integrates_to_one() {
        // ∫ G1(wi, m) max(0, wi·m) D(m) dm = cos θᵢ: Smith's G1 is consistent with D.
        for md in distributions() {
            for wi in incident() {
                let total = integrate_pdf_2d(&HEMISPHERE, [128, 64], |m| md.pdf(wi, *m) as f64);
                assert!((total - 1.0).abs() < 3e-3, "{md:?}, wi {wi}: ∫ pdf = {total}");
            }
        }
    }

    #[test]
    fn sampling_matches_pdf() {
        let mut k = 0;
        for md in distributions() {
            for wi in incident() {
                k += 1;
                let out = chi2_2d(
                    &SPHERE,
                    [41, 41],
                    400_000,
                    |r| Some(md.sample(wi, u2(r)).value),
                    |m| md.pdf(wi, *m) as f64,
                    &Chi2Config::default().with_seed(k),
                );
                assert!(out.passed(), "{md:?}, wi {wi}: {out}");
                let s = md.sample(wi, Vec2::new(0.3, 0.6));
                assert!((s.pdf - md.pdf(wi, s.value)).abs() <= 1e-4 * s.pdf.max(1.0));
            }
        }
    }

    /// `sample_grid` gives `sample`'s normal and density and `sample_grid_normals` its normal,
    /// bit for bit, for every distribution.
    #[test]
    fn sample_grid_is_sample_bit_for_bit() {
        // Grids with nodes near 0 and 1, over directions at normal incidence (Beckmann's polar
        // branch), in the xz-plane (the coating tables' case), grazing, and off the plane.
        let us: Vec<f32> = [1e-7, 0.01, 0.2, 0.5, 0.73, 0.999, 1.0 - 1e-7].to_vec();
        let vs: Vec<f32> = [0.0, 0.05, 0.31, 0.5, 0.5001, 0.97].to_vec();
        let mut dirs = incident();
        dirs.extend([
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(1.0, 0.0, 1e-4).normalize(),
            Vec3::new(0.01, 0.0, 1.0).normalize(),
        ]);
        let mut ds = distributions();
        ds.extend([
            Microfacet::new(MicrofacetType::Beckmann, 0.02, 0.02),
            Microfacet::new(MicrofacetType::Beckmann, 1.5, 1.5),
        ]);
        let mut seen = 0;
        for md in ds {
            for &wi in &dirs {
                md.sample_grid(wi, &us, &vs, |i, j, s| {
                    let t = md.sample(wi, Vec2::new(us[i], vs[j]));
                    let bits = |s: &Sample<Vec3>| (s.value.to_array().map(f32::to_bits), s.pdf.to_bits());
                    assert_eq!(bits(&s), bits(&t), "{md:?}, wi {wi}, u ({}, {})", us[i], vs[j]);
                    seen += 1;
                });
                md.sample_grid_normals(wi, &us, &vs, |i, j, m| {
                    let t = md.sample(wi, Vec2::new(us[i], vs[j])).value;
                    assert_eq!(m.to_array().map(f32::to_bits), t.to_array().map(f32::to_bits), "{md:?}, wi {wi}");
                    seen += 1;
                });
            }
        }
        assert_eq!(seen, 2 * 8 * 6 * us.len() * vs.len());
    }

    /// Λ's shortcut changes no bit of G1: from a = 4 on (every 61st float up to ∞), the full
    /// formula's `1 / (1 + Λ)` is exactly 1, and just below 4 it is not yet.
    #[test]
    fn beckmann_lambda_vanishes_from_four_on() {
        let g1 = |a: f32| 1.0 / (1.0 + beckmann_lambda(a));
        let first = BECKMANN_LAMBDA_ZERO.to_bits();
        for bits in (first..f32::INFINITY.to_bits()).step_by(61).chain([first, f32::INFINITY.to_bits() - 1]) {
            let a = f32::from_bits(bits);
            assert_eq!(g1(a), 1.0, "a = {a:e}");
        }
        assert!(g1(3.0) < 1.0, "the shortcut starts where Λ still matters below it");
        let md = Microfacet::new(MicrofacetType::Beckmann, 0.1, 0.1);
        let w = Vec3::new(0.2, 0.0, 1.0).normalize();
        assert_eq!(md.g1(w, Vec3::Z), 1.0);
    }

    #[test]
    fn masking_limits() {
        let md = Microfacet::new(MicrofacetType::Ggx, 0.5, 0.5);
        assert_eq!(md.g1(Vec3::Z, Vec3::Z), 1.0);
        let grazing = Vec3::new(1.0, 0.0, 1e-3).normalize();
        assert!(md.g1(grazing, Vec3::Z) < 0.01);
        // A microfacet facing away from w is invisible.
        let w = Vec3::new(0.8, 0.0, 0.6);
        assert_eq!(md.g1(w, Vec3::new(-0.9, 0.0, 0.3).normalize()), 0.0);
        // Beckmann and GGX agree for small roughness near normal incidence.
        let b = Microfacet::new(MicrofacetType::Beckmann, 0.05, 0.05);
        let g = Microfacet::new(MicrofacetType::Ggx, 0.05, 0.05);
        let w = Vec3::new(0.3, 0.0, 0.95).normalize();
        assert!((b.g1(w, Vec3::Z) - g.g1(w, Vec3::Z)).abs() < 1e-3);
    }
}
