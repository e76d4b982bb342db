//! Light selection for next-event estimation: which emitter a shading point samples.
//!
//! A [`LightSampler`] chooses one light with a discrete probability that may depend on the
//! shading point `(p, n)`; MIS at an emitter found by BSDF sampling needs the same probability
//! for the previous vertex, which [`LightSampler::pmf`] returns (the estimator is unbiased for any
//! choice that gives every light that can contribute a positive probability):
//!
//! - `bvh` (default): the light BVH ([`super::LightBvh`]), probability proportional to a bound on
//!   each light's contribution at the point (pbrt-v4's default);
//! - `power`: proportional to emitted power, the same everywhere (pbrt-v4's `power`);
//! - `uniform`: every light alike (Mitsuba 3's rule).

use super::{Light, LightBvh};
use crate::geometry::Geometry;
use crate::math::Vec3;
use crate::sampling::AliasTable;

/// A light's power is not a finite non-negative number (its radiance overflows single precision,
/// or is negative): there is no distribution to choose lights by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InvalidLightPower;

/// The lights' powers as the alias tables that choose by power take them: each light's
/// [`Light::power`], or, where one overflows single precision but not double (the lights at
/// infinity of a scene some 10¹⁹ units wide), all of them relative to the largest. `None` if a
/// power is infinite, NaN or negative.
pub(crate) fn selection_powers(lights: &[Light], shapes: &[Geometry]) -> Option<Vec<f32>> {
    let powers: Vec<f64> = lights.iter().map(|l| l.power_f64(shapes)).collect();
    let max = powers.iter().copied().fold(0.0, f64::max);
    if !max.is_finite() || powers.iter().any(|p| p.is_nan() || *p < 0.0) {
        return None;
    }
    let scale = if max > f64::from(f32::MAX) { 1.0 / max } else { 1.0 };
    Some(powers.iter().map(|p| (p * scale) as f32).collect())
}

/// Which light sampler a render uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSamplerKind {
    /// Light BVH: importance bounded by power, distance and orientation at the shading point.
    #[default]
    Bvh,
    /// Proportional to power.
    Power,
    /// Uniform over the lights.
    Uniform,
}

crate::choices!(LightSamplerKind, "light sampler", {
    LightSamplerKind::Bvh => "bvh", "light BVH: by a bound on each light's contribution at the shading point";
    LightSamplerKind::Power => "power", "by emitted power, the same everywhere";
    LightSamplerKind::Uniform => "uniform", "every light alike (Mitsuba's rule)";
});

/// Where a light is chosen for: the shading point and its unit normal (zero for a point in a
/// medium, which has no normal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSampleContext {
    /// Shading point (world).
    pub p: Vec3,
    /// Unit shading normal at `p` (world), or zero.
    pub n: Vec3,
}

/// A light sampler built for one scene's lights.
#[derive(Clone, Debug)]
pub enum LightSampler {
    /// No light can be chosen.
    Empty,
    /// Every one of `count` lights with probability `1 / count`.
    Uniform {
        /// Number of lights.
        count: u32,
    },
    /// Proportional to power (the alias table over the lights' powers).
    Power(AliasTable),
    /// The light BVH, mixed with uniform selection among the lights it can choose (see
    /// `defensive_share` in this file).
    Bvh {
        /// The tree.
        bvh: LightBvh,
        /// The probability of choosing uniformly instead of by the tree.
        share: f32,
        /// The lights the tree can choose (of positive power, reachable by next-event
        /// estimation: [`LightBvh::selectable`]), which the uniform share chooses among.
        lit: Vec<u32>,
    },
}

/// The share of light-BVH selection given to uniform selection among the `lit` lights the tree can
/// choose (defensive mixture sampling, Hesterberg 1995). The BVH's importance bounds a light's
/// unshadowed contribution by its power, distance and orientation, not by the BSDF, and can give
/// a light that a glossy surface reflects toward the eye a tiny probability (a spot seen in a
/// glossy cube beside a larger area light, `scenes/blender_export.xml`: 3× the variance of
/// Mitsuba's uniform choice on the floor by the cube, relMSE 1.6× Mitsuba's over the image, 1.08×
/// with the mixture); the mixture bounds each light's weight by `N / share`. Half with at most
/// eight lights, where uniform choice costs at most a factor N; a tenth with more, where the
/// tree's choice is what makes many lights affordable (`many_lights`, 160 lights: relMSE 0.115
/// of Mitsuba's with the tree alone, 0.124 with a tenth, 0.184 with half).
pub fn defensive_share(lit: usize) -> f32 {
    if lit <= 8 {
        0.5
    } else {
        0.1
    }
}

impl LightSampler {
    /// The sampler of `kind` for `lights` on `shapes`. Where every light's power is zero
    /// (lights switched off: Mitsuba renders such a scene black) there is nothing worth
    /// choosing, and power or BVH selection is [`LightSampler::Empty`]; uniform selection still
    /// chooses among them, as Mitsuba does. Errors if a power is not finite or is negative.
    pub fn new(
        kind: LightSamplerKind,
        lights: &[Light],
        shapes: &[Geometry],
    ) -> Result<LightSampler, InvalidLightPower> {
        if lights.is_empty() {
            return Ok(LightSampler::Empty);
        }
        let powers = selection_powers(lights, shapes).ok_or(InvalidLightPower)?;
        if powers.iter().all(|&p| p == 0.0) {
            return Ok(match kind {
                LightSamplerKind::Uniform => LightSampler::Uniform { count: lights.len() as u32 },
                LightSamplerKind::Power | LightSamplerKind::Bvh => LightSampler::Empty,
            });
        }
        let power = AliasTable::new(&powers).ok_or(InvalidLightPower)?;
        Ok(match kind {
            LightSamplerKind::Uniform => LightSampler::Uniform { count: lights.len() as u32 },
            LightSamplerKind::Power => LightSampler::Power(power),
            LightSamplerKind::Bvh => {
                let bvh = LightBvh::new(lights, shapes);
                let lit: Vec<u32> = (0..lights.len() as u32).filter(|&i| bvh.selectable(i)).collect();
                if lit.is_empty() {
                    return Ok(LightSampler::Empty);
                }
                LightSampler::Bvh { bvh, share: defensive_share(lit.len()), lit }
            }
        })
    }

    /// Chooses a light for `ctx` with `u ∈ [0, 1)`: its index and the probability of choosing
    /// it. `None` if there is none to choose (the BVH also returns `None` when no light can
    /// reach the point).
    #[inline]
    pub fn sample(&self, ctx: &LightSampleContext, u: f32) -> Option<(u32, f32)> {
        match self {
            LightSampler::Empty => None,
            LightSampler::Uniform { count } => Some((((u * *count as f32) as u32).min(count - 1), 1.0 / *count as f32)),
            LightSampler::Power(table) => {
                let (s, _) = table.sample(u);
                Some((s.value as u32, s.pdf))
            }
            LightSampler::Bvh { bvh, share, lit } => {
                let eps = *share;
                let uniform = eps / lit.len() as f32;
                if u < eps {
                    let k = ((u / eps * lit.len() as f32) as usize).min(lit.len() - 1);
                    let i = lit[k];
                    Some((i, uniform + (1.0 - eps) * bvh.pmf(ctx.p, ctx.n, i)))
                } else {
                    let u = ((u - eps) / (1.0 - eps)).min(crate::math::ONE_MINUS_EPSILON);
                    let (i, p) = bvh.sample(ctx.p, ctx.n, u)?;
                    debug_assert!(bvh.selectable(i));
                    Some((i, uniform + (1.0 - eps) * p))
                }
            }
        }
    }

    /// Probability that [`LightSampler::sample`] at `ctx` chooses light `i`.
    #[inline]
    pub fn pmf(&self, ctx: &LightSampleContext, i: u32) -> f32 {
        match self {
            LightSampler::Empty => 0.0,
            LightSampler::Uniform { count } => 1.0 / *count as f32,
            LightSampler::Power(table) => table.pmf(i as usize),
            LightSampler::Bvh { bvh, share, lit } => {
                if !bvh.selectable(i) {
                    return 0.0;
                }
                share / lit.len() as f32 + (1.0 - share) * bvh.pmf(ctx.p, ctx.n, i)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choice::Choice;
    use crate::geometry::{Disk, Sphere, TriangleMesh};
    use crate::math::{Ray, Rgb, Transform};
    use crate::testkit::{chi2_2d, u2, Chi2Config, SPHERE};

    /// Area lights around a point (disjoint as seen from it) and an environment.
    fn lights_around(p: Vec3) -> (Vec<Light>, Vec<Geometry>) {
        let mut quad = TriangleMesh::rectangle();
        quad.transform(
            &(Transform::translate(p + Vec3::new(0.0, 0.0, 2.0)) * Transform::rotate(Vec3::X, 170.0).unwrap()),
        );
        quad.prepare_normals();
        let disk = Disk::new(
            Transform::translate(p + Vec3::new(-2.0, 0.5, 0.0)) * Transform::rotate(Vec3::Y, 80.0).unwrap(),
            false,
        )
        .unwrap();
        let mut shapes = vec![
            Geometry::Mesh(quad),
            Geometry::Sphere(Sphere::new(p + Vec3::new(0.0, -2.0, -1.0), 0.8, false)),
            Geometry::Sphere(Sphere::new(p + Vec3::new(3.0, 1.0, 0.0), 0.05, false)),
            Geometry::Disk(disk),
        ];
        for s in &mut shapes {
            assert!(s.prepare_sampling());
        }
        let lights = vec![
            Light::Area { shape: 0, radiance: Rgb::splat(2.0).into(), two_sided: false },
            Light::Area { shape: 1, radiance: Rgb::new(1.0, 0.5, 0.2).into(), two_sided: false },
            Light::Area { shape: 2, radiance: Rgb::splat(300.0).into(), two_sided: true },
            Light::Area { shape: 3, radiance: Rgb::splat(1.0).into(), two_sided: false },
            Light::Constant { radiance: Rgb::splat(0.3), center: p, radius: 10.0 },
        ];
        (lights, shapes)
    }

    /// The direction density of "choose a light, then `sample_li`" is
    /// `Σ_lights pmf(ctx, i) · pdf_li(i, ω)`, the density MIS evaluates at BSDF-sampled hits, for
    /// every sampler kind (χ² over the sphere of directions). Fails if `pmf` and `sample`
    /// disagree, or `pdf_li` and `sample_li` do, for any light type.
    #[test]
    fn light_sampling_density_through_each_sampler() {
        let p = Vec3::new(0.5, 0.2, -0.3);
        let n = Vec3::new(0.2, 0.3, 1.0).normalize();
        let ctx = LightSampleContext { p, n };
        let (lights, shapes) = lights_around(p);
        for (k, (kind, name, _)) in LightSamplerKind::CHOICES.iter().enumerate() {
            let sampler = LightSampler::new(*kind, &lights, &shapes).unwrap();
            let pdf = |w: &Vec3| -> f64 {
                let ray = Ray::new(p, *w);
                let mut total = 0.0f64;
                for (i, light) in lights.iter().enumerate() {
                    let density = match light {
                        Light::Area { shape, .. } => {
                            let g = &shapes[*shape as usize];
                            let hit = match g {
                                Geometry::Mesh(m) => (0..m.len()).find_map(|t| {
                                    let pre = crate::geometry::triangle::RayPrecomp::new(&ray);
                                    crate::geometry::triangle::intersect_triangle(&pre, &m.triangle(t), f32::INFINITY)
                                        .map(|h| (ray.at(h.t()), m.face_normal(t)))
                                }),
                                Geometry::Sphere(s) => s.intersect(&ray, f32::INFINITY).map(|h| {
                                    let (sp, _) = s.surface(&ray, h.t);
                                    (sp.p, sp.n)
                                }),
                                Geometry::Disk(d) => {
                                    d.intersect(&ray, f32::INFINITY).map(|(_, q)| (d.surface(q).0.p, d.normal()))
                                }
                                Geometry::Cylinder(_)
                                | Geometry::SdfGrid(_)
                                | Geometry::Curves(_)
                                | Geometry::LinearCurves(_)
                                | Geometry::BSplineCurves(_)
                                | Geometry::Ellipsoids(_) => None,
                            };
                            match hit {
                                Some((q, nq)) if nq.dot(-*w) > 0.0 => light.pdf_li(&shapes, p, q, nq),
                                _ => 0.0,
                            }
                        }
                        _ => light.pdf_li_direction(p, *w),
                    };
                    total += (sampler.pmf(&ctx, i as u32) * density) as f64;
                }
                total
            };
            let out = chi2_2d(
                &SPHERE,
                [61, 121],
                600_000,
                |r| {
                    let (i, _) = sampler.sample(&ctx, r.next_f32())?;
                    lights[i as usize].sample_li(&shapes, p, u2(r)).map(|s| s.wi)
                },
                pdf,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "{name}: {out}");
        }
    }

    /// The light BVH mixed with uniform choice: each choice reports the light's full pmf (from
    /// either branch), the pmfs sum to one, no light the tree can choose falls below
    /// `share / N` even where its bound is tiny (the point faces away from the small sphere), and
    /// a light without power is never chosen.
    #[test]
    fn bvh_choice_is_mixed_with_uniform_choice() {
        let p = Vec3::new(0.5, 0.2, -0.3);
        let (mut lights, shapes) = lights_around(p);
        lights.push(Light::Area { shape: 3, radiance: Rgb::ZERO.into(), two_sided: false });
        let sampler = LightSampler::new(LightSamplerKind::Bvh, &lights, &shapes).unwrap();
        let LightSampler::Bvh { share, ref lit, .. } = sampler else { panic!("{sampler:?}") };
        assert_eq!((share, lit.len()), (0.5, 5), "the dark light is left out");
        for n in [Vec3::new(0.2, 0.3, 1.0).normalize(), Vec3::new(-1.0, -0.2, 0.1).normalize()] {
            let ctx = LightSampleContext { p, n };
            let pmfs: Vec<f32> = (0..lights.len() as u32).map(|i| sampler.pmf(&ctx, i)).collect();
            assert!((pmfs.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{pmfs:?}");
            assert!(pmfs[..5].iter().all(|&q| q >= share / 5.0 - 1e-6) && pmfs[5] == 0.0, "{pmfs:?}");
            let mut counts = [0u32; 6];
            let m = 200_000;
            for k in 0..m {
                let u = (k as f32 + 0.5) / m as f32;
                let (i, q) = sampler.sample(&ctx, u).unwrap();
                assert_eq!(q, pmfs[i as usize], "light {i} at u = {u}");
                counts[i as usize] += 1;
            }
            for (i, &c) in counts.iter().enumerate() {
                assert!((c as f32 / m as f32 - pmfs[i]).abs() < 2e-3, "light {i}: {c} of {m} vs {}", pmfs[i]);
            }
        }
    }

    #[test]
    fn kinds_parse_and_print() {
        for &(kind, name, _) in LightSamplerKind::CHOICES {
            assert_eq!(name.parse::<LightSamplerKind>().unwrap(), kind);
            assert_eq!(kind.to_string(), name);
        }
        assert!("bhv".parse::<LightSamplerKind>().unwrap_err().contains("bvh, power, uniform"));
        assert_eq!(LightSamplerKind::default(), LightSamplerKind::Bvh);
    }
}
