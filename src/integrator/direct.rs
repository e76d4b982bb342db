//! Mitsuba's `direct` integrator: emission seen directly plus single-scattered light (the first
//! two terms `Lₑ + T Lₑ` of the Neumann series), estimated at the first hit with
//! `emitter_samples` light samples and `bsdf_samples` BSDF samples combined by multi-sample MIS
//! (power heuristic with the sample counts, Veach's `w_s = (n_s p_s)² / Σ_t (n_t p_t)²`).
//!
//! Parameters (Mitsuba): `shading_samples` (default 1; the default of both counts),
//! `emitter_samples`, `bsdf_samples`, `hide_emitters` (false). With one count zero the other
//! strategy alone is used (weight 1), which makes this the classic "light sampling only" or
//! "BSDF sampling only" direct-lighting estimator.

use super::Integrator;
use crate::light::LightSampleContext;
use crate::material::BsdfContext;
use crate::math::{Ray, Rgb, Vec3};
use crate::sampling::Sampler;
use crate::scene::Scene;

/// The direct-illumination integrator.
#[derive(Clone, Copy, Debug)]
pub struct DirectIntegrator {
    /// Light samples per camera ray.
    pub emitter_samples: u32,
    /// BSDF samples per camera ray.
    pub bsdf_samples: u32,
    /// Whether emitters seen directly by the camera are hidden (camera rays pass through
    /// emitting shapes, as in Mitsuba 3).
    pub hide_emitters: bool,
}

impl Default for DirectIntegrator {
    fn default() -> Self {
        DirectIntegrator { emitter_samples: 1, bsdf_samples: 1, hide_emitters: false }
    }
}

/// Multi-sample power heuristic for a sample of strategy `a` (count `na`, density `pa`) against
/// strategy `b`.
#[inline]
fn weight(na: u32, pa: f32, nb: u32, pb: f32) -> f32 {
    let (a, b) = (na as f32 * pa, nb as f32 * pb);
    if a <= 0.0 {
        return 0.0;
    }
    if !b.is_finite() {
        return 0.0;
    }
    let w = (a * a) / (a * a + b * b);
    if w.is_finite() {
        w
    } else {
        1.0
    }
}

impl Integrator for DirectIntegrator {
    fn name(&self) -> &'static str {
        "direct"
    }

    fn li(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler) -> Rgb {
        let geometries = scene.geometries();
        let mut ray = *camera_ray;
        let mut skipped = 0;
        let (si, shape) = loop {
            let Some(si) = scene.intersect(&ray) else {
                if self.hide_emitters {
                    return Rgb::ZERO;
                }
                let d = ray.d.normalize();
                return scene.infinite_lights().iter().map(|&i| scene.lights()[i as usize].le_escaped(d)).sum();
            };
            let shape = scene.shapes()[si.shape as usize];
            // Hidden emitters are invisible to camera rays (Mitsuba 3): the ray passes through.
            if self.hide_emitters && shape.light.is_some() {
                skipped += 1;
                if skipped > super::path::MAX_HIDDEN_SKIPS {
                    return Rgb::ZERO;
                }
                ray = si.spawn_ray(ray.d);
                continue;
            }
            break (si, shape);
        };
        let wo = -ray.d.normalize();
        let mut l = Rgb::ZERO;
        if let (Some(i), false) = (shape.light, self.hide_emitters) {
            l += scene.lights()[i as usize].le(si.ns, wo);
        }
        let bsdf = &scene.bsdfs()[shape.bsdf as usize];
        let frame = si.frame();
        let wo_local = frame.to_local(wo);
        let ctx = BsdfContext { uv: si.uv };
        let (nl, nb) = (self.emitter_samples, self.bsdf_samples);
        let light_ctx = LightSampleContext { p: si.p, n: si.ns };
        let delta_bsdf = bsdf.is_delta();

        // Light sampling.
        for _ in 0..nl {
            let u = sampler.next_1d();
            let u2 = sampler.next_2d();
            if delta_bsdf {
                continue;
            }
            let Some((light_index, pmf)) = scene.sample_light(&light_ctx, u) else { continue };
            let light = &scene.lights()[light_index as usize];
            let Some(ls) = light.sample_li(geometries, si.p, u2) else { continue };
            let wi_local = frame.to_local(ls.wi);
            let f = bsdf.eval(&ctx, wo_local, wi_local);
            if f == Rgb::ZERO || scene.occluded(&si.spawn_ray_to(ls.p, ls.n, ls.p_error)) {
                continue;
            }
            if ls.delta {
                l += f * ls.li / (pmf * nl as f32);
            } else {
                let pdf_light = pmf * ls.pdf;
                let w = weight(nl, pdf_light, nb, bsdf.pdf(&ctx, wo_local, wi_local));
                l += f * ls.li * (w / (pdf_light * nl as f32));
            }
        }

        // BSDF sampling: emission found along the sampled direction.
        for _ in 0..nb {
            let u = sampler.next_1d();
            let u2 = sampler.next_2d();
            let Some(bs) = bsdf.sample(&ctx, wo_local, u, u2) else { continue };
            let wi = frame.to_world(bs.wi);
            let ray = si.spawn_ray(wi);
            // Light-sampling density of the same direction (0 when light sampling cannot reach it).
            let pdf_light = |light_index: u32, p_light: Option<(Vec3, Vec3)>| -> f32 {
                if bs.delta || nl == 0 {
                    return 0.0;
                }
                let light = &scene.lights()[light_index as usize];
                scene.light_pmf(&light_ctx, light_index)
                    * match p_light {
                        Some((p, n)) => light.pdf_li(geometries, si.p, p, n),
                        None => light.pdf_li_direction(wi),
                    }
            };
            let mut le = Rgb::ZERO;
            match scene.intersect(&ray) {
                Some(hit) => {
                    if let Some(i) = scene.shapes()[hit.shape as usize].light {
                        let e = scene.lights()[i as usize].le(hit.ns, -wi);
                        if e != Rgb::ZERO {
                            le += e * weight(nb, bs.pdf, nl, pdf_light(i, Some((hit.p, hit.ng))));
                        }
                    }
                }
                None => {
                    for &i in scene.infinite_lights() {
                        let e = scene.lights()[i as usize].le_escaped(wi);
                        if e != Rgb::ZERO {
                            le += e * weight(nb, bs.pdf, nl, pdf_light(i, None));
                        }
                    }
                }
            }
            // bs.weight = f cos / pdf; divide by the number of BSDF samples.
            l += bs.weight * le / nb as f32;
        }
        l
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::PathIntegrator;
    use crate::render::{render, RenderSettings};
    use crate::scene::cornell::cornell_box;
    use std::sync::atomic::AtomicBool;

    fn mean_and_se(scene: &Scene, integrator: &dyn Integrator, spp: u32, seed: u64) -> (f64, f64) {
        let out =
            render(scene, integrator, &RenderSettings { spp, seed, ..Default::default() }, &AtomicBool::new(false))
                .unwrap();
        out.film.mean_and_std_error()
    }

    /// Every (emitter_samples, bsdf_samples) split estimates the same direct lighting as the path
    /// tracer limited to two segments, on the Cornell box.
    #[test]
    fn sample_splits_agree_with_the_path_tracer_at_depth_two() {
        let scene = cornell_box(24, 24).unwrap();
        let (reference, se_ref) = mean_and_se(&scene, &PathIntegrator { max_depth: 2, ..Default::default() }, 512, 1);
        for (nl, nb) in [(1, 1), (1, 0), (0, 1), (3, 1), (1, 4)] {
            let d = DirectIntegrator { emitter_samples: nl, bsdf_samples: nb, hide_emitters: false };
            let (mean, se) = mean_and_se(&scene, &d, if nb > 0 && nl == 0 { 2048 } else { 256 }, 2);
            let z = (mean - reference) / (se * se + se_ref * se_ref).sqrt();
            assert!(z.abs() < 4.0, "({nl}, {nb}): {mean} vs {reference}, z = {z:.2}");
        }
        // Hiding emitters makes the light transparent to camera rays: the ceiling behind it
        // shows, so the image is darker but not black there.
        let hidden = DirectIntegrator { hide_emitters: true, ..Default::default() };
        let (m_hidden, _) = mean_and_se(&scene, &hidden, 64, 3);
        assert!(m_hidden < reference);
    }

    #[test]
    fn mis_weights_sum_to_one() {
        for (pa, pb) in [(0.3f32, 2.0f32), (1.0, 1.0), (5.0, 0.01)] {
            for (na, nb) in [(1, 1), (2, 3)] {
                let s = weight(na, pa, nb, pb) + weight(nb, pb, na, pa);
                assert!((s - 1.0).abs() < 1e-6);
            }
        }
        assert_eq!(weight(1, 0.5, 0, 3.0), 1.0);
        assert_eq!(weight(0, 0.5, 1, 3.0), 0.0);
    }
}
