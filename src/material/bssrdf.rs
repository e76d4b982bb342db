//! pbrt-v4's tabulated BSSRDF (`TabulatedBSSRDF`, photon beam diffusion, Habel et al. 2013) for
//! its `subsurface` material: how light entering a translucent surface at one point leaves it
//! at another.
//!
//! The BSSRDF is separable: `S(pₒ, ωₒ, pᵢ, ωᵢ) ≈ (entry transmission) · Sp(|pₒ − pᵢ|) · Sw(ωᵢ)`.
//! The entry is the dielectric boundary's transmission (the surface BSDF); `Sp(r)`, the radial
//! profile (m⁻², per channel), is tabulated once per (`g`, `η`) over the single-scattering
//! albedo `ρ` (100 values) and the optical radius `r σₜ` (64 values) from the single- and
//! multiple-scattering terms of photon beam diffusion ([`BssrdfTable::beam_diffusion`]), and
//! scaled to a medium by `σₜ²`; `Sw` is the exit's normalized Fresnel transmission
//! ([`normalized_fresnel`]).
//!
//! Sampling (pbrt-v4's): a channel, an axis (the normal with probability ½, each tangent ¼),
//! a radius from the channel's profile and an angle give a probe segment along the axis
//! ([`TabulatedBssrdf::sample_probe`]); where it meets the surface is the exit point, whose
//! density per unit area [`TabulatedBssrdf::pdf_sp`] combines every axis (by the exit normal's
//! projection onto it) and every channel.

use crate::material::fresnel::fresnel_dielectric;
use crate::math::spline::{catmull_rom_weights, integrate_catmull_rom, invert_catmull_rom, Spline2D};
use crate::math::{Frame, Rgb, Vec3, INV_4PI, PI};
use rayon::prelude::*;

/// pbrt's polynomial fit of the first Fresnel moment `∫₀¹ F(η, μ) μ dμ` (times 2).
pub fn fresnel_moment1(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta * eta * eta, eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5
    } else {
        -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5
    }
}

/// pbrt's polynomial fit of the second Fresnel moment `∫₀¹ F(η, μ) μ² dμ` (times 3).
pub fn fresnel_moment2(eta: f32) -> f32 {
    let (e2, e3, e4, e5) = (eta * eta, eta * eta * eta, eta.powi(4), eta.powi(5));
    if eta < 1.0 {
        0.27614 - 0.87350 * eta + 1.12077 * e2 - 0.65095 * e3 + 0.07883 * e4 + 0.04860 * e5
    } else {
        let (r, r2, r3) = (1.0 / eta, 1.0 / e2, 1.0 / e3);
        -547.033 + 45.3087 * r3 - 218.725 * r2 + 458.843 * r + 404.557 * eta - 189.519 * e2 + 54.9327 * e3
            - 9.00603 * e4
            + 0.63942 * e5
    }
}

/// Henyey–Greenstein in pbrt-v4's convention (`cos` between the two directions pointing away,
/// so forward scattering is `cos = −1`).
fn hg_pbrt(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * cos;
    INV_4PI * (1.0 - g * g) / (denom * denom.max(0.0).sqrt())
}

/// Photon beam diffusion's multiple-scattering exitance at radius `r` (pbrt-v4's
/// `BeamDiffusionMS`, 100 depths of the real source): a dipole per depth, Grosjean's diffusion
/// coefficient, the boundary's extrapolation distance from the Fresnel moments.
pub fn beam_diffusion_ms(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    let n = 100;
    let sigmap_s = sigma_s * (1.0 - g);
    let sigmap_t = sigma_a + sigmap_s;
    let rhop = sigmap_s / sigmap_t;
    let d_g = (2.0 * sigma_a + sigmap_s) / (3.0 * sigmap_t * sigmap_t);
    let sigma_tr = (sigma_a / d_g).max(0.0).sqrt();
    let (fm1, fm2) = (fresnel_moment1(eta), fresnel_moment2(eta));
    let ze = -2.0 * d_g * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1);
    let (c_phi, c_e) = (0.25 * (1.0 - 2.0 * fm1), 0.5 * (1.0 - 3.0 * fm2));
    let mut ed = 0.0;
    for i in 0..n {
        let zr = -(1.0 - (i as f32 + 0.5) / n as f32).ln() / sigmap_t;
        let zv = -zr + 2.0 * ze;
        let (dr, dv) = ((r * r + zr * zr).sqrt(), (r * r + zv * zv).sqrt());
        let phi_d = INV_4PI / d_g * ((-sigma_tr * dr).exp() / dr - (-sigma_tr * dv).exp() / dv);
        let ed_n = INV_4PI
            * (zr * (1.0 + sigma_tr * dr) * (-sigma_tr * dr).exp() / (dr * dr * dr)
                - zv * (1.0 + sigma_tr * dv) * (-sigma_tr * dv).exp() / (dv * dv * dv));
        let e = phi_d * c_phi + ed_n * c_e;
        let kappa = 1.0 - (-2.0 * sigmap_t * (dr + zr)).exp();
        ed += kappa * rhop * rhop * e;
    }
    ed / n as f32
}

/// Photon beam diffusion's single-scattering exitance at radius `r` (pbrt-v4's
/// `BeamDiffusionSS`: 100 depths below the critical angle's).
pub fn beam_diffusion_ss(sigma_s: f32, sigma_a: f32, g: f32, eta: f32, r: f32) -> f32 {
    let sigma_t = sigma_a + sigma_s;
    let rho = sigma_s / sigma_t;
    let t_crit = r * (eta * eta - 1.0).max(0.0).sqrt();
    let n = 100;
    let mut ess = 0.0;
    for i in 0..n {
        let ti = t_crit - (1.0 - (i as f32 + 0.5) / n as f32).ln() / sigma_t;
        let d = (r * r + ti * ti).sqrt();
        let cos_o = ti / d;
        ess += rho * (-sigma_t * (d + t_crit)).exp() / (d * d)
            * hg_pbrt(cos_o, g)
            * (1.0 - fresnel_dielectric(-cos_o, eta).0)
            * cos_o.abs();
    }
    ess / n as f32
}

/// The radial profile over albedo and optical radius (pbrt-v4's `BSSRDFTable`): for albedo
/// `rho[i]` and optical radius `radius[j]`, `profile[i · len + j] = 2π r (S_ss + S_ms)` (the
/// profile times the circumference, a density over the radius), its running integral over
/// the radius in `cdf` and its total, the effective albedo, in `rho_eff`.
#[derive(Clone, Debug)]
pub struct BssrdfTable {
    /// Single-scattering albedos (0 … 1, denser toward 1).
    pub rho: Vec<f32>,
    /// Optical radii `r σₜ` (0, then 0.0025 × 1.2ᵏ).
    pub radius: Vec<f32>,
    /// `2π r S(r)`, a row per albedo.
    pub profile: Vec<f32>,
    /// The effective albedo of each row: its profile's integral.
    pub rho_eff: Vec<f32>,
    /// Running integrals of the rows.
    pub cdf: Vec<f32>,
}

impl BssrdfTable {
    /// The table of pbrt-v4's `ComputeBeamDiffusionBSSRDF` for phase asymmetry `g` and relative
    /// index `eta` (100 albedos × 64 radii; the rows in parallel).
    pub fn beam_diffusion(g: f32, eta: f32) -> BssrdfTable {
        let (n_rho, n_r) = (100usize, 64usize);
        let mut radius = vec![0.0f32; n_r];
        radius[1] = 2.5e-3;
        for i in 2..n_r {
            radius[i] = radius[i - 1] * 1.2;
        }
        let rho: Vec<f32> = (0..n_rho)
            .map(|i| (1.0 - (-8.0 * i as f32 / (n_rho - 1) as f32).exp()) / (1.0 - (-8.0f32).exp()))
            .collect();
        let rows: Vec<(Vec<f32>, Vec<f32>, f32)> = rho
            .par_iter()
            .map(|&albedo| {
                let profile: Vec<f32> = radius
                    .iter()
                    .map(|&r| {
                        2.0 * PI
                            * r
                            * (beam_diffusion_ss(albedo, 1.0 - albedo, g, eta, r)
                                + beam_diffusion_ms(albedo, 1.0 - albedo, g, eta, r))
                    })
                    .collect();
                let mut cdf = vec![0.0; n_r];
                let total = integrate_catmull_rom(&radius, &profile, &mut cdf);
                (profile, cdf, total)
            })
            .collect();
        let mut table =
            BssrdfTable { rho, radius, profile: Vec::with_capacity(n_rho * n_r), rho_eff: Vec::new(), cdf: Vec::new() };
        for (p, c, t) in rows {
            table.profile.extend(p);
            table.cdf.extend(c);
            table.rho_eff.push(t);
        }
        table
    }

    /// The scattering and absorption coefficients (m⁻¹) that give effective albedo `rho_eff` at
    /// mean free path `mfp` (m), per channel (pbrt-v4's `SubsurfaceFromDiffuse`):
    /// `(σₐ, σₛ)`.
    pub fn from_diffuse(&self, rho_eff: Rgb, mfp: Rgb) -> (Rgb, Rgb) {
        let mut sigma_a = Rgb::ZERO;
        let mut sigma_s = Rgb::ZERO;
        for c in 0..3 {
            let rho = invert_catmull_rom(&self.rho, &self.rho_eff, rho_eff[c]);
            sigma_s[c] = rho / mfp[c];
            sigma_a[c] = (1.0 - rho) / mfp[c];
        }
        (sigma_a, sigma_s)
    }

    /// The profile `2π r S` and the effective albedo interpolated at albedo `rho` and optical
    /// radius `r` (`None` outside the table).
    fn lookup(&self, rho: f32, r: f32) -> Option<(f32, f32)> {
        let (ro, rw) = catmull_rom_weights(&self.rho, rho)?;
        let (xo, xw) = catmull_rom_weights(&self.radius, r)?;
        let n = self.radius.len();
        let (mut sr, mut rho_eff) = (0.0f32, 0.0f32);
        for (j, &wj) in rw.iter().enumerate() {
            if wj == 0.0 {
                continue;
            }
            let row = (ro + j as isize) as usize;
            rho_eff += self.rho_eff[row] * wj;
            for (k, &wk) in xw.iter().enumerate() {
                if wk != 0.0 {
                    sr += self.profile[row * n + (xo + k as isize) as usize] * wj * wk;
                }
            }
        }
        Some((sr, rho_eff))
    }
}

/// The BSSRDF at one entry point: pbrt-v4's `TabulatedBSSRDF` for coefficients `σₐ`, `σₛ`
/// (m⁻¹, per channel).
#[derive(Clone, Copy, Debug)]
pub struct TabulatedBssrdf<'a> {
    /// The entry point (world).
    pub po: Vec3,
    /// The shading normal there (unit).
    pub ns: Vec3,
    /// σₜ = σₐ + σₛ per channel.
    pub sigma_t: Rgb,
    /// σₛ / σₜ per channel (0 where σₜ is).
    pub rho: Rgb,
    /// The profile table.
    pub table: &'a BssrdfTable,
}

/// Probe axis probabilities: the shading frame's two tangents, then its normal (pbrt-v4's).
pub const AXIS_PROB: [f32; 3] = [0.25, 0.25, 0.5];

impl<'a> TabulatedBssrdf<'a> {
    /// The BSSRDF of coefficients `sigma_a`, `sigma_s` at `po` with shading normal `ns`.
    pub fn new(po: Vec3, ns: Vec3, sigma_a: Rgb, sigma_s: Rgb, table: &'a BssrdfTable) -> TabulatedBssrdf<'a> {
        let sigma_t = sigma_a + sigma_s;
        let rho = Rgb::new(
            if sigma_t.x > 0.0 { sigma_s.x / sigma_t.x } else { 0.0 },
            if sigma_t.y > 0.0 { sigma_s.y / sigma_t.y } else { 0.0 },
            if sigma_t.z > 0.0 { sigma_s.z / sigma_t.z } else { 0.0 },
        );
        TabulatedBssrdf { po, ns, sigma_t, rho, table }
    }

    /// Channel `c`'s profile per unit area at distance `r` (m): `Sr(r)` (m⁻²) and the effective
    /// albedo it integrates to; `None` outside the table.
    fn profile(&self, c: usize, r: f32) -> Option<(f32, f32)> {
        let r_optical = r * self.sigma_t[c];
        let (mut sr, rho_eff) = self.table.lookup(self.rho[c], r_optical)?;
        // The table holds 2π r S (a density over the radius) in optical units.
        if r_optical != 0.0 {
            sr /= 2.0 * PI * r_optical;
        }
        Some((sr * self.sigma_t[c] * self.sigma_t[c], rho_eff))
    }

    /// The radial profile `Sr(r)` (m⁻², per channel) at distance `r` (m).
    pub fn sr(&self, r: f32) -> Rgb {
        let mut out = Rgb::ZERO;
        for c in 0..3 {
            out[c] = self.profile(c, r).map_or(0.0, |(sr, _)| sr.max(0.0));
        }
        out
    }

    /// The density (m⁻², per unit area of the plane) of the radius sampled by
    /// [`TabulatedBssrdf::sample_sr`] in each channel, at distance `r`.
    pub fn pdf_sr(&self, r: f32) -> Rgb {
        let mut out = Rgb::ZERO;
        for c in 0..3 {
            let pdf = self.profile(c, r).map_or(0.0, |(sr, rho_eff)| sr / rho_eff);
            out[c] = if pdf.is_finite() { pdf.max(0.0) } else { 0.0 };
        }
        out
    }

    /// A radius (m) from channel `c`'s profile, with `u ∈ [0, 1)`; `None` where the channel
    /// does not scatter or attenuate.
    pub fn sample_sr(&self, c: usize, u: f32) -> Option<f32> {
        if self.sigma_t[c].is_nan() || self.sigma_t[c] <= 0.0 {
            return None;
        }
        let t = &self.table;
        let spline = Spline2D { nodes1: &t.rho, nodes2: &t.radius, values: &t.profile, cdf: &t.cdf };
        let (r, _, _) = spline.sample(self.rho[c], u)?;
        Some(r / self.sigma_t[c])
    }

    /// The frame whose z is the probe axis `axis` (0, 1: the tangents of the shading frame; 2:
    /// the normal).
    fn axis_frame(&self, axis: usize) -> (Vec3, Vec3, Vec3) {
        let f = Frame::from_z(self.ns);
        match axis {
            0 => (f.s, f.t, f.n),
            1 => (f.t, f.n, f.s),
            _ => (f.n, f.s, f.t),
        }
    }

    /// A probe segment `(start, end)` (world) for exit points, pbrt-v4's `SampleSp`: an axis
    /// by `u_axis` ([`AXIS_PROB`]), a radius from channel `c`'s profile by `u.x`, an angle by
    /// `u.y`; the segment crosses the sphere of the profile's 99.9th-percentile radius along the
    /// axis at that radius and angle. `None` beyond that radius.
    pub fn sample_probe(&self, c: usize, u_axis: f32, u: (f32, f32)) -> Option<(Vec3, Vec3)> {
        let axis = if u_axis < AXIS_PROB[0] {
            0
        } else if u_axis < AXIS_PROB[0] + AXIS_PROB[1] {
            1
        } else {
            2
        };
        let (z, x, y) = self.axis_frame(axis);
        let r = self.sample_sr(c, u.0)?;
        let r_max = self.sample_sr(c, 0.999)?;
        if r >= r_max {
            return None;
        }
        let phi = 2.0 * PI * u.1;
        let l = 2.0 * (r_max * r_max - r * r).sqrt();
        let start = self.po + r * (x * phi.cos() + y * phi.sin()) - l * z * 0.5;
        Some((start, start + l * z))
    }

    /// The density per unit area (m⁻², per channel of the radius' sampling) of
    /// [`TabulatedBssrdf::sample_probe`] finding the exit point `pi` with geometric normal
    /// `ni` (before choosing among a probe's several hits): each axis's radial density at the
    /// projected distance times the exit's projected area onto the plane `|ni · axis|`.
    pub fn pdf_sp(&self, pi: Vec3, ni: Vec3) -> Rgb {
        let d = pi - self.po;
        let mut pdf = Rgb::ZERO;
        for (axis, prob) in AXIS_PROB.iter().enumerate() {
            let (z, x, y) = self.axis_frame(axis);
            let r = (d.dot(x).powi(2) + d.dot(y).powi(2)).sqrt();
            pdf += self.pdf_sr(r) * (ni.dot(z).abs() * prob);
        }
        pdf
    }
}

/// pbrt-v4's `NormalizedFresnelBxDF` (the exit's `Sw`) for light leaving toward `cos_i` (local
/// cosine of the direction away from the surface, the side of the outgoing direction): the
/// Fresnel transmission of relative index `eta` normalised by its cosine-weighted hemispherical
/// integral, `(1 − F(cos θᵢ)) / (c π)` with `c = 1 − 2 F₁(1/η)`, times η² (radiance). Zero
/// across the surface.
pub fn normalized_fresnel(cos_i: f32, cos_o: f32, eta: f32) -> f32 {
    if cos_i * cos_o <= 0.0 {
        return 0.0;
    }
    let c = 1.0 - 2.0 * fresnel_moment1(1.0 / eta);
    (1.0 - fresnel_dielectric(cos_i.abs(), eta).0) / (c * PI) * eta * eta
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;
    use std::sync::OnceLock;

    fn table() -> &'static BssrdfTable {
        static T: OnceLock<BssrdfTable> = OnceLock::new();
        T.get_or_init(|| BssrdfTable::beam_diffusion(0.0, 1.33))
    }

    /// The table's shape and its physics: the effective albedo rises with the albedo from 0 to
    /// about 1, each row's running integral rises to it, and the profile is non-negative.
    #[test]
    fn the_table_is_a_profile_per_albedo() {
        let t = table();
        assert_eq!((t.rho.len(), t.radius.len(), t.profile.len()), (100, 64, 6400));
        assert_eq!((t.rho[0], t.rho[99]), (0.0, 1.0));
        assert!(t.rho_eff[0].abs() < 1e-6, "ρ_eff(0) = {}", t.rho_eff[0]);
        assert!(t.rho_eff.windows(2).all(|w| w[1] >= w[0]), "ρ_eff not increasing");
        // Diffusion is an approximation: at albedo 1 (nothing absorbed) the profile's integral
        // overshoots one by 2 % (pbrt's table too: the same formulas), below it falls short.
        assert!(t.rho_eff[99] > 0.95 && t.rho_eff[99] < 1.03, "ρ_eff(1) = {}", t.rho_eff[99]);
        assert!(t.rho_eff[80] < 0.9 * t.rho_eff[99], "ρ_eff({}) = {}", t.rho[80], t.rho_eff[80]);
        assert!(t.profile.iter().all(|&p| p >= 0.0 && p.is_finite()));
        for i in 0..100 {
            assert!((t.cdf[i * 64 + 63] - t.rho_eff[i]).abs() <= 1e-6 * (1.0 + t.rho_eff[i]));
        }
        // Inverting the effective albedo recovers the albedo.
        for &target in &[0.1f32, 0.5, 0.8, 0.95] {
            let rho_eff = {
                let (o, w) = catmull_rom_weights(&t.rho, target).unwrap();
                (0..4).filter(|&k| w[k] != 0.0).map(|k| w[k] * t.rho_eff[(o + k as isize) as usize]).sum::<f32>()
            };
            let (sa, ss) = t.from_diffuse(Rgb::splat(rho_eff), Rgb::splat(0.5));
            let rho = ss.x / (ss.x + sa.x);
            assert!((rho - target).abs() < 2e-3, "{target}: {rho}");
            assert!(((sa.x + ss.x) - 2.0).abs() < 1e-5, "σₜ = 1 / mfp");
        }
    }

    /// The radius density integrates to one over the plane (`∫ pdf_sr 2π r dr`) in every
    /// channel, and sampled radii follow it (χ² over 16 bins of equal probability by the
    /// density's own quadrature), for chromatic coefficients.
    #[test]
    fn radius_sampling_matches_its_density() {
        let b = TabulatedBssrdf::new(Vec3::ZERO, Vec3::Z, Rgb::new(0.5, 2.0, 8.0), Rgb::new(20.0, 15.0, 9.0), table());
        for c in 0..3 {
            let r_max = b.sample_sr(c, 0.9999).unwrap() * 4.0;
            let n = 40_000;
            let h = r_max as f64 / n as f64;
            let mut cdf = vec![0.0f64; n + 1];
            for i in 0..n {
                let r = (i as f64 + 0.5) * h;
                cdf[i + 1] = cdf[i] + b.pdf_sr(r as f32)[c] as f64 * 2.0 * std::f64::consts::PI * r * h;
            }
            assert!((cdf[n] - 1.0).abs() < 5e-3, "channel {c}: ∫ pdf = {}", cdf[n]);
            let bins = 16;
            let mut counts = vec![0usize; bins];
            let mut rng = Pcg32::new(9, c as u64);
            let m = 50_000;
            for _ in 0..m {
                let r = b.sample_sr(c, rng.next_f32()).unwrap() as f64;
                let k = ((r / h) as usize).min(n);
                let f = cdf[k] / cdf[n];
                counts[((f * bins as f64) as usize).min(bins - 1)] += 1;
            }
            let e = m as f64 / bins as f64;
            let chi2: f64 = counts.iter().map(|&k| (k as f64 - e).powi(2) / e).sum();
            // 15 degrees of freedom: p = 1e-4 at 44.
            assert!(chi2 < 44.0, "channel {c}: χ² {chi2}, {counts:?}");
        }
    }

    /// The exit density: probes from a plane's entry point, intersected with the plane (one
    /// hit per probe, found where the probe's line meets z = 0), land with the density
    /// `pdf_sp` — χ² over rings of equal expected counts — for each channel's sampling.
    #[test]
    fn probes_on_a_plane_land_with_pdf_sp() {
        let b = TabulatedBssrdf::new(Vec3::ZERO, Vec3::Z, Rgb::new(1.0, 3.0, 6.0), Rgb::new(10.0, 8.0, 12.0), table());
        let mut rng = Pcg32::new(1, 7);
        for c in 0..3 {
            let r_max = b.sample_sr(c, 0.999).unwrap();
            let rings = 12;
            let n = 60_000;
            let mut counts = vec![0usize; rings + 1];
            for _ in 0..n {
                let Some((s, e)) = b.sample_probe(c, rng.next_f32(), (rng.next_f32(), rng.next_f32())) else {
                    counts[rings] += 1;
                    continue;
                };
                let d = e - s;
                if d.z.abs() < 1e-12 || s.z * e.z > 0.0 {
                    counts[rings] += 1;
                    continue;
                }
                let p = s + d * (-s.z / d.z);
                let r = (p.x * p.x + p.y * p.y).sqrt();
                counts[((r / r_max * rings as f32) as usize).min(rings)] += 1;
            }
            // Expected: the ring integrals of this channel's pdf_sp over the plane (normal +z).
            let m = 4000;
            let mut expect = vec![0.0f64; rings + 1];
            for (k, e) in expect.iter_mut().take(rings).enumerate() {
                for i in 0..m {
                    let r = r_max as f64 * (k as f64 + (i as f64 + 0.5) / m as f64) / rings as f64;
                    let p = b.pdf_sp(Vec3::new(r as f32, 0.0, 0.0), Vec3::Z)[c] as f64;
                    *e += p * 2.0 * std::f64::consts::PI * r * r_max as f64 / rings as f64 / m as f64;
                }
            }
            let inside: f64 = expect.iter().sum();
            expect[rings] = 1.0 - inside;
            let chi2: f64 = counts
                .iter()
                .zip(&expect)
                .filter(|(_, &e)| e * n as f64 > 5.0)
                .map(|(&k, &e)| (k as f64 - e * n as f64).powi(2) / (e * n as f64))
                .sum();
            assert!(
                chi2 < 45.0,
                "channel {c}: χ² {chi2}, {counts:?} vs {:?}",
                expect.iter().map(|e| e * n as f64).collect::<Vec<_>>()
            );
        }
    }

    /// The normalized Fresnel exit lobe integrates to η² (its radiance scaling) over the
    /// hemisphere against the cosine (pbrt's normalisation by the first Fresnel moment, a fit:
    /// within 1.5 %), and is zero across the surface.
    #[test]
    fn normalized_fresnel_integrates_to_eta_squared() {
        for eta in [1.1f32, 1.33, 1.5, 2.0] {
            let n = 100_000;
            let s: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64;
                    normalized_fresnel(mu as f32, 0.5, eta) as f64 * mu * 2.0 * std::f64::consts::PI / n as f64
                })
                .sum();
            let want = (eta * eta) as f64;
            assert!((s - want).abs() < 0.015 * want, "η {eta}: {s} vs {want}");
        }
        assert_eq!(normalized_fresnel(-0.5, 0.5, 1.33), 0.0);
    }
}
