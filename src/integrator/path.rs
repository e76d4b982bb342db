//! The path tracer (Mitsuba's `path`): backward tracing from the camera with next-event
//! estimation, MIS and Russian roulette.
//!
//! At every vertex the path adds `Lₑ` from emitters it hits and, by next-event estimation,
//! light sampled on one emitter (chosen with probability proportional to power); the two
//! strategies for direct light (BSDF sampling finds emitters by chance, light sampling aims at
//! them) are combined with the power heuristic. Russian roulette ends paths of low throughput
//! `β` from `rr_depth` on, with survival probability `q = min(max(β), 0.95)` and `β /= q`,
//! which keeps the estimator unbiased.
//!
//! `max_depth` has Mitsuba's meaning: the longest path has `max_depth` segments. 1: only
//! emitters seen directly; 2: direct illumination; -1: unlimited.
//!
//! Parameters (Mitsuba): `max_depth` (default -1), `rr_depth` (5), `hide_emitters` (false).

use super::Integrator;
use crate::math::{Ray, Rgb, Vec3};
use crate::sampling::{power_heuristic, Sampler};
use crate::scene::Scene;

/// How direct light is estimated at each vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectStrategy {
    /// Light sampling and BSDF sampling combined by the power heuristic.
    Mis,
    /// Light sampling only (emitters hit by BSDF-sampled rays after a non-specular bounce do
    /// not count).
    Light,
    /// BSDF sampling only (no next-event estimation).
    Bsdf,
}

/// Unidirectional path tracer.
#[derive(Clone, Debug)]
pub struct PathIntegrator {
    /// Longest path in segments; negative for unlimited.
    pub max_depth: i32,
    /// Depth (path vertices after the camera) from which Russian roulette applies.
    pub rr_depth: u32,
    /// Direct-light strategy.
    pub strategy: DirectStrategy,
    /// Whether emitters seen directly by the camera are hidden.
    pub hide_emitters: bool,
}

impl Default for PathIntegrator {
    fn default() -> Self {
        PathIntegrator { max_depth: -1, rr_depth: 5, strategy: DirectStrategy::Mis, hide_emitters: false }
    }
}

impl Integrator for PathIntegrator {
    fn name(&self) -> &'static str {
        "path"
    }

    fn li(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler) -> Rgb {
        let max_depth = if self.max_depth < 0 { u32::MAX } else { self.max_depth as u32 };
        let mut l = Rgb::ZERO;
        if max_depth == 0 {
            return l;
        }
        let geometries = scene.geometries();
        let mut beta = Rgb::ONE;
        let mut ray = *camera_ray;
        // The previous vertex (position, BSDF pdf of the direction taken, whether delta).
        let mut prev: Option<(Vec3, f32, bool)> = None;
        let mut depth = 0u32;
        loop {
            let Some(si) = scene.intersect(&ray) else { break };
            let wo = -ray.d.normalize();
            let shape = scene.shapes()[si.shape as usize];

            // Emission found by the path itself.
            if let Some(light_index) = shape.light {
                let le = scene.lights()[light_index as usize].le(si.ns, wo);
                if le != Rgb::ZERO {
                    let weight = match prev {
                        None => {
                            if self.hide_emitters {
                                0.0
                            } else {
                                1.0
                            }
                        }
                        Some((_, _, true)) => 1.0,
                        Some((p_prev, pdf_bsdf, false)) => match self.strategy {
                            DirectStrategy::Bsdf => 1.0,
                            DirectStrategy::Light => 0.0,
                            DirectStrategy::Mis => {
                                let light = &scene.lights()[light_index as usize];
                                let pdf_light =
                                    scene.light_pmf(light_index) * light.pdf_li(geometries, p_prev, si.p, si.ng);
                                power_heuristic(1, pdf_bsdf, 1, pdf_light)
                            }
                        },
                    };
                    l += beta * le * weight;
                }
            }
            if depth + 1 >= max_depth {
                break;
            }

            let bsdf = &scene.bsdfs()[shape.bsdf as usize];
            let frame = si.frame();
            let wo_local = frame.to_local(wo);

            // Next-event estimation (its random numbers are drawn whether used or not, so that
            // every vertex consumes the same sampler dimensions).
            let u_light = sampler.next_1d();
            let u_light2 = sampler.next_2d();
            if self.strategy != DirectStrategy::Bsdf && !bsdf.is_delta() {
                if let Some((light_index, pmf)) = scene.sample_light(u_light) {
                    let light = &scene.lights()[light_index as usize];
                    if let Some(ls) = light.sample_li(geometries, si.p, u_light2) {
                        let wi_local = frame.to_local(ls.wi);
                        let f = bsdf.eval(wo_local, wi_local);
                        if f != Rgb::ZERO && !scene.occluded(&si.spawn_ray_to(ls.p, ls.n, ls.p_error)) {
                            let contribution = if ls.delta {
                                f * ls.li / pmf
                            } else {
                                let pdf_light = pmf * ls.pdf;
                                let w = match self.strategy {
                                    DirectStrategy::Mis => {
                                        power_heuristic(1, pdf_light, 1, bsdf.pdf(wo_local, wi_local))
                                    }
                                    _ => 1.0,
                                };
                                f * ls.li * (w / pdf_light)
                            };
                            l += beta * contribution;
                        }
                    }
                }
            }

            // Continue the path by BSDF sampling.
            let u_bsdf = sampler.next_1d();
            let u_bsdf2 = sampler.next_2d();
            let Some(bs) = bsdf.sample(wo_local, u_bsdf, u_bsdf2) else { break };
            beta *= bs.weight;
            let wi = frame.to_world(bs.wi);
            prev = Some((si.p, bs.pdf, bs.delta));
            ray = si.spawn_ray(wi);
            depth += 1;

            // Russian roulette.
            let u_rr = sampler.next_1d();
            let beta_max = beta.max_element();
            if !(beta_max > 0.0) {
                break;
            }
            if depth >= self.rr_depth {
                let q = beta_max.min(0.95);
                if u_rr >= q {
                    break;
                }
                beta /= q;
            }
        }
        l
    }
}
