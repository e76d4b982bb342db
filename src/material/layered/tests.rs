//! The layered BSDF against closed forms and itself. Its `eval` and `pdf` are random-walk
//! estimates (pbrt-v4's), so the generic tests (`eval / pdf` equal to the sample's weight, χ²
//! of samples against `pdf`) do not apply; instead:
//! - a smooth coating over a Lambertian base has a closed-form albedo
//!   `F + (1 − F) R (1 − Fᵢ) / (1 − R Fᵢ)` (`Fᵢ` the internal diffuse Fresnel reflectance):
//!   the sampled weights and the integral of `eval` must both give it;
//! - with no absorption (white base, white medium) every walk's energy leaves: albedo 1;
//! - per direction bin, the samples' weights and `eval` integrate to the same values (the
//!   sampled distribution is the one `eval` describes), for rough coatings, conductor bases and
//!   a scattering medium;
//! - MIS with the `pdf` estimate and another strategy stays unbiased; the pdf is positive
//!   wherever `eval` is;
//! - an index-matched coating over a smooth conductor is that conductor; two-sidedness and
//!   determinism.

use super::*;
use crate::estimators::Estimate;
use crate::material::diffuse_fresnel_reflectance;
use crate::material::fresnel::{fresnel_conductor, fresnel_dielectric};
use crate::material::microfacet::MicrofacetType;
use crate::sampling::{sample_uniform_hemisphere, Pcg32};
use crate::testkit::u2;

const CTX: BsdfContext = BsdfContext { uv: Vec2::ZERO, mesh: None, textures: None, si: None, memo: None };

fn c(v: f32) -> Texture {
    Texture::Constant(Rgb::splat(v))
}

fn coated_diffuse(r: Rgb, alpha: f32, thickness: f32, albedo: Option<f32>, g: f32, max_depth: u32) -> Layered {
    Layered {
        eta: 1.5,
        alpha: Box::new([c(alpha), c(alpha)]),
        base: Base::Diffuse { reflectance: Texture::Constant(r) },
        thickness: c(thickness),
        albedo: albedo.map(c),
        g: c(g),
        max_depth,
        n_samples: 1,
        regularized: false,
    }
}

fn coated_gold(eta: f32, alpha: f32, base_alpha: f32) -> Layered {
    Layered {
        eta,
        alpha: Box::new([c(alpha), c(alpha)]),
        base: Base::Conductor {
            ior: crate::material::named_conductor("Au").flatten().expect("gold"),
            alpha: Box::new([c(base_alpha), c(base_alpha)]),
        },
        thickness: c(1e-7),
        albedo: None,
        g: c(0.0),
        max_depth: 10,
        n_samples: 1,
        regularized: false,
    }
}

fn dir(theta_deg: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    Vec3::new(t.sin(), 0.0, t.cos())
}

/// The mean sampled weight (channel x) from `wo`, with its standard error.
fn sampled_albedo(b: &Layered, wo: Vec3, n: usize, seed: u64) -> Estimate {
    let mut rng = Pcg32::new(seed, 1);
    Estimate::from_values(
        (0..n).map(|_| b.sample(&CTX, wo, rng.next_f32(), u2(&mut rng)).map_or(0.0, |s| s.weight.x as f64)),
    )
}

/// `∫ eval dω` (channel x) over the upper hemisphere by uniform sampling, with its error.
fn eval_albedo(b: &Layered, wo: Vec3, n: usize, seed: u64) -> Estimate {
    let mut rng = Pcg32::new(seed, 2);
    Estimate::from_values((0..n).map(|_| {
        let s = sample_uniform_hemisphere(u2(&mut rng));
        (b.eval(&CTX, wo, s.value).x / s.pdf) as f64
    }))
}

#[test]
fn smooth_coating_over_lambertian_matches_the_closed_form() {
    let eta = 1.5f32;
    let f_int = diffuse_fresnel_reflectance(1.0 / eta);
    for (k, (r, theta)) in [(1.0f32, 0.0f32), (0.8, 45.0), (0.3, 75.0)].into_iter().enumerate() {
        let b = coated_diffuse(Rgb::splat(r), 0.0, 1e-7, None, 0.0, 1000);
        let wo = dir(theta);
        let f = fresnel_dielectric(wo.z, eta).0;
        let diffuse = (1.0 - f) * r * (1.0 - f_int) / (1.0 - r * f_int);
        let s = sampled_albedo(&b, wo, 200_000, k as u64);
        assert!(
            (s.value - (f + diffuse) as f64).abs() < 4.0 * s.std_error() + 1e-3,
            "R {r}, θ {theta}: sampled albedo {} ± {} vs closed form {}",
            s.value,
            s.std_error(),
            f + diffuse
        );
        // eval has no delta lobe: it integrates to the diffuse part alone.
        let e = eval_albedo(&b, wo, 200_000, k as u64);
        assert!(
            (e.value - diffuse as f64).abs() < 4.0 * e.std_error() + 1e-3,
            "R {r}, θ {theta}: ∫ eval {} ± {} vs {diffuse}",
            e.value,
            e.std_error()
        );
    }
}

#[test]
fn without_absorption_all_energy_leaves() {
    // White base under a thick white medium: whatever the walk does, it ends outside.
    for (k, g) in [0.0f32, 0.7].into_iter().enumerate() {
        let b = coated_diffuse(Rgb::ONE, 0.0, 1.0, Some(1.0), g, 100_000);
        let s = sampled_albedo(&b, dir(30.0), 100_000, 10 + k as u64);
        assert!((s.value - 1.0).abs() < 4.0 * s.std_error() + 2e-3, "g {g}: albedo {} ± {}", s.value, s.std_error());
        let f = fresnel_dielectric(dir(30.0).z, 1.5).0 as f64;
        let e = eval_albedo(&b, dir(30.0), 100_000, 10 + k as u64);
        assert!((e.value + f - 1.0).abs() < 4.0 * e.std_error() + 2e-3, "g {g}: ∫ eval + F = {}", e.value + f);
    }
    // An absorbing medium makes it darker.
    let dark = sampled_albedo(&coated_diffuse(Rgb::ONE, 0.0, 1.0, Some(0.5), 0.0, 100), dir(30.0), 20_000, 12);
    assert!(dark.value < 0.6, "{}", dark.value);
}

#[test]
fn samples_are_distributed_as_eval_says() {
    let cases: Vec<(&str, Layered)> = vec![
        ("rough coat, diffuse", coated_diffuse(Rgb::new(0.7, 0.5, 0.2), 0.3, 0.01, None, 0.0, 10)),
        ("rough coat, scattering medium", coated_diffuse(Rgb::splat(0.6), 0.2, 0.5, Some(0.9), 0.4, 10)),
        ("rough coat, rough gold", coated_gold(1.5, 0.25, 0.3)),
        ("smooth coat, rough gold", coated_gold(1.5, 0.0, 0.3)),
    ];
    let (nt, np) = (6usize, 8usize);
    let bin = |w: Vec3| -> Option<usize> {
        if w.z <= 0.0 {
            return None;
        }
        let t = ((w.z * nt as f32) as usize).min(nt - 1);
        let p = ((crate::math::spherical_phi(w) / (2.0 * crate::math::PI) * np as f32) as usize).min(np - 1);
        Some(t * np + p)
    };
    for (k, (name, b)) in cases.iter().enumerate() {
        for wo in [dir(20.0), Vec3::new(0.5, 0.6, 0.62).normalize()] {
            let n = 200_000usize;
            let acc = |values: &mut dyn FnMut(&mut Pcg32) -> Option<(Vec3, f32)>, seed: u64| {
                let (mut sum, mut sq) = (vec![0.0f64; nt * np], vec![0.0f64; nt * np]);
                let mut rng = Pcg32::new(seed, k as u64);
                for _ in 0..n {
                    if let Some((w, v)) = values(&mut rng) {
                        if let Some(i) = bin(w) {
                            sum[i] += v as f64;
                            sq[i] += (v as f64).powi(2);
                        }
                    }
                }
                let mean: Vec<f64> = sum.iter().map(|s| s / n as f64).collect();
                let var: Vec<f64> = sq.iter().zip(&mean).map(|(q, m)| (q / n as f64 - m * m) / n as f64).collect();
                (mean, var)
            };
            let (ms, vs) = acc(
                &mut |r| b.sample(&CTX, wo, r.next_f32(), u2(r)).filter(|s| !s.delta).map(|s| (s.wi, s.weight.x)),
                1,
            );
            let (me, ve) = acc(
                &mut |r| {
                    let s = sample_uniform_hemisphere(u2(r));
                    Some((s.value, b.eval(&CTX, wo, s.value).x / s.pdf))
                },
                2,
            );
            let mut worst = 0.0f64;
            for i in 0..nt * np {
                let z = (ms[i] - me[i]) / (vs[i] + ve[i]).sqrt().max(1e-9);
                worst = worst.max(z.abs());
            }
            let (ts, te) = (ms.iter().sum::<f64>(), me.iter().sum::<f64>());
            assert!(worst < 5.0, "{name}, wo {wo}: a bin differs by {worst:.1} σ");
            assert!((ts - te).abs() < 0.02 * te.max(0.05), "{name}, wo {wo}: totals {ts} vs {te}");
        }
    }
}

#[test]
fn mis_with_the_pdf_estimate_is_unbiased() {
    // ∫ f cos L over a bright cap around the mirror direction, estimated (a) by eval alone with
    // uniform directions and (b) by MIS between BSDF sampling and cosine sampling, each
    // weighted by the power heuristic with pdf(): both converge to the same value.
    let b = coated_diffuse(Rgb::new(0.6, 0.6, 0.6), 0.15, 0.01, None, 0.0, 10);
    let wo = dir(40.0);
    let light = |w: Vec3| if w.dot(dir(-40.0)) > 0.95 || w.x > 0.5 { 1.0f32 } else { 0.0 };
    let mut rng = Pcg32::new(21, 0);
    let n = 200_000;
    let reference = Estimate::from_values((0..n).map(|_| {
        let s = sample_uniform_hemisphere(u2(&mut rng));
        (b.eval(&CTX, wo, s.value).x * light(s.value) / s.pdf) as f64
    }));
    let mis = Estimate::from_values((0..n).map(|_| {
        let mut v = 0.0f32;
        if let Some(s) = b.sample(&CTX, wo, rng.next_f32(), u2(&mut rng)) {
            let pl = crate::sampling::cosine_hemisphere_pdf(s.wi);
            v += s.weight.x * light(s.wi) * s.pdf.powi(2) / (s.pdf.powi(2) + pl * pl);
        }
        let l = crate::sampling::sample_cosine_hemisphere_malley(u2(&mut rng));
        let pb = b.pdf(&CTX, wo, l.value);
        assert!(pb > 0.0 || b.eval(&CTX, wo, l.value).x == 0.0, "pdf 0 where eval is not");
        v += b.eval(&CTX, wo, l.value).x * light(l.value) / l.pdf * l.pdf.powi(2) / (l.pdf.powi(2) + pb * pb);
        v as f64
    }));
    let se = (reference.std_error().powi(2) + mis.std_error().powi(2)).sqrt();
    assert!((reference.value - mis.value).abs() < 4.0 * se, "eval {} vs MIS {} (σ {se})", reference.value, mis.value);
    assert!(reference.value > 0.05);
}

#[test]
fn index_matched_coating_over_a_smooth_conductor_is_the_conductor() {
    let b = coated_gold(1.0, 0.0, 0.0);
    assert!(Bsdf::Layered(Box::new(b.clone())).is_delta());
    let gold = crate::material::named_conductor("Au").flatten().expect("gold");
    for theta in [0.0f32, 30.0, 60.0, 85.0] {
        let wo = dir(theta);
        let s = b.sample(&CTX, wo, 0.3, Vec2::new(0.4, 0.6)).expect("a sample");
        assert!(s.delta && (s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-5);
        let expected = fresnel_conductor(wo.z, CTX.eval(&gold.eta), CTX.eval(&gold.k)) * tr(1e-7, wo).powi(2);
        assert!((s.weight - expected).abs().max_element() < 1e-4, "θ {theta}: {} vs {expected}", s.weight);
    }
    // A smooth coating over a smooth conductor has no non-delta part.
    assert_eq!(b.eval(&CTX, dir(10.0), dir(-10.0)), Rgb::ZERO);
}

#[test]
fn two_sided_and_deterministic() {
    let b = coated_diffuse(Rgb::splat(0.5), 0.2, 0.1, Some(0.5), 0.0, 10);
    let mut rng = Pcg32::new(3, 3);
    for _ in 0..200 {
        let wo = sample_uniform_hemisphere(u2(&mut rng)).value;
        let wi = sample_uniform_hemisphere(u2(&mut rng)).value;
        let a = b.eval(&CTX, wo, wi);
        assert_eq!(a, b.eval(&CTX, wo, wi));
        assert_eq!(a, b.eval(&CTX, -wo, -wi));
        assert_eq!(b.pdf(&CTX, wo, wi), b.pdf(&CTX, -wo, -wi));
        assert!(a.is_finite() && a.min_element() >= 0.0);
        // Opaque base: nothing reaches the other side, though the pdf mixes in the sphere.
        assert_eq!(b.eval(&CTX, wo, -wi), Rgb::ZERO);
        assert!(b.pdf(&CTX, wo, -wi) > 0.0);
        let (u1, u) = (rng.next_f32(), u2(&mut rng));
        let s1 = b.sample(&CTX, -wo, u1, u).map(|s| (s.wi, s.weight));
        assert_eq!(s1, b.sample(&CTX, -wo, u1, u).map(|s| (s.wi, s.weight)));
        if let Some((w, _)) = s1 {
            assert!(w.z < 0.0, "sampled from below, the walk returns below");
        }
    }
}

fn interfaces() -> Vec<(&'static str, Interface)> {
    let ggx = |a: f32, b: f32| Some(crate::material::microfacet::Microfacet::new(MicrofacetType::Ggx, a, b));
    vec![
        ("rough dielectric", Interface::Dielectric { eta: 1.5, mf: ggx(0.3, 0.3) }),
        ("anisotropic dielectric", Interface::Dielectric { eta: 1.33, mf: ggx(0.1, 0.4) }),
        ("diffuse", Interface::Diffuse { r: Rgb::new(0.2, 0.5, 0.9) }),
        (
            "rough conductor",
            Interface::Conductor { eta: Rgb::new(0.2, 0.4, 1.4), k: Rgb::new(3.9, 2.4, 1.8), mf: ggx(0.25, 0.25) },
        ),
    ]
}

#[test]
fn interfaces_sample_as_their_pdf_and_value_say() {
    use crate::testkit::{chi2_2d, Chi2Config, SPHERE};
    let mut seed = 0;
    for (name, i) in interfaces() {
        for wo in [dir(10.0), Vec3::new(0.6, -0.3, 0.74).normalize(), Vec3::new(0.3, 0.2, -0.93).normalize()] {
            for lobes in [Lobes::All, Lobes::Reflection, Lobes::Transmission] {
                seed += 1;
                if crate::testkit::integrate_pdf_2d(&SPHERE, [16, 16], |wi| i.pdf(wo, *wi, lobes) as f64) < 1e-6 {
                    continue;
                }
                let out = chi2_2d(
                    &SPHERE,
                    [31, 61],
                    200_000,
                    |r| i.sample(wo, r.next_f32(), u2(r), Mode::Radiance, lobes).map(|s| s.wi),
                    |wi| i.pdf(wo, *wi, lobes) as f64,
                    &Chi2Config::default().with_seed(seed),
                );
                assert!(out.passed(), "{name}, wo {wo}, {lobes:?}: {out}");
                let mut rng = Pcg32::new(seed, 7);
                for _ in 0..1000 {
                    let Some(s) = i.sample(wo, rng.next_f32(), u2(&mut rng), Mode::Radiance, lobes) else { continue };
                    let (f, p) = (i.f(wo, s.wi, Mode::Radiance), i.pdf(wo, s.wi, lobes));
                    assert!((s.pdf - p).abs() <= 1e-3 * p.max(1e-2), "{name} {lobes:?}: pdf {} vs {p}", s.pdf);
                    assert!(
                        (s.f - f).abs().max_element() <= 1e-3 * f.max_element().max(1e-2),
                        "{name}: f {} vs {f}",
                        s.f
                    );
                    assert_eq!(s.reflection, s.wi.z * wo.z > 0.0);
                }
            }
        }
    }
}
