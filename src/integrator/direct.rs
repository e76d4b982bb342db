//! Mitsuba's `direct` integrator: emission seen directly plus single-scattered light (the first
//! two terms `Lₑ + T Lₑ` of the Neumann series), estimated at the first hit with
//! `emitter_samples` light samples and `bsdf_samples` BSDF samples combined by multi-sample MIS
//! (power heuristic with the sample counts, Veach's `w_s = (n_s p_s)² / Σ_t (n_t p_t)²`).
//!
//! Parameters (Mitsuba): `shading_samples` (default 1; the default of both counts),
//! `emitter_samples`, `bsdf_samples`, `hide_emitters` (false). With one count zero the other
//! strategy alone is used (weight 1), which makes this the classic "light sampling only" or
//! "BSDF sampling only" direct-lighting estimator.

use super::trace::{self, Mis, MisHeuristic, PrevVertex};
use super::{Integrator, RadianceSample};
use crate::light::LightSampleContext;
use crate::material::TextureMemo;
use crate::math::{Ray, Rgb};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::Sampler;
use crate::scene::{HitSlot, Scene};

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

impl Integrator for DirectIntegrator {
    fn name(&self) -> &'static str {
        "direct"
    }

    fn sample(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler, _terms: &mut [Rgb]) -> RadianceSample {
        let (l, covered) = self.radiance(scene, camera_ray, sampler);
        RadianceSample { l, alpha: trace::coverage(scene, covered, self.hide_emitters) }
    }
}

impl DirectIntegrator {
    /// The radiance along `camera_ray` and whether the ray hit a surface.
    fn radiance(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler) -> (Rgb, bool) {
        let hide = self.hide_emitters;
        let (nl, nb) = (self.emitter_samples, self.bsdf_samples);
        let mis = Mis::Combine { heuristic: MisHeuristic::Power, n_light: nl, n_bsdf: nb };
        // Hidden emitters are invisible to camera rays (Mitsuba 3): the ray passes through.
        let (hit, ray, covered) = if hide {
            // Covered where a surface is hit behind the hidden emitters (Mitsuba's `direct`).
            let mut ray = *camera_ray;
            let hit = trace::skip_hidden_emitters(scene, &mut ray, &mut HitSlot::default()).map(|h| h.interaction());
            let covered = hit.is_some();
            (hit, ray, covered)
        } else {
            let hit = scene.intersect(camera_ray);
            let covered = hit.is_some();
            (hit, *camera_ray, covered)
        };
        // By reference (a move would copy it by wide loads right after `intersect` wrote it).
        let Some(si) = &hit else {
            let mut l = Rgb::ZERO;
            trace::escaped(scene, ray.o, ray.d.normalize(), None, hide, &mis, |le, w| l += le * w);
            return (l, covered);
        };
        let shape = scene.shapes()[si.shape as usize];
        let wo = -ray.d.normalize();
        let mut l = Rgb::ZERO;
        if let (Some(i), false) = (shape.light, hide) {
            l += scene.lights()[i as usize].le(si.ns, wo, si.uv);
        }
        let bsdf = &scene.bsdfs()[shape.bsdf as usize];
        // Textures and normal maps looked up once for this vertex's BSDF calls.
        let memo = TextureMemo::default();
        let vertex = trace::SurfaceVertex::new(scene, si, bsdf, &memo, wo);
        let (ctx, frame, wo_local) = (&vertex.ctx, vertex.frame, vertex.wo_local);
        let light_ctx = LightSampleContext { p: si.p, n: si.ns };
        let delta_bsdf = bsdf.is_delta();

        // Light sampling.
        for _ in 0..nl {
            let u = sampler.next_1d();
            let u2 = sampler.next_2d();
            if delta_bsdf {
                continue;
            }
            l += trace::sample_direct_bsdf(scene, &light_ctx, (u, u2), &mis, &vertex, trace::occlusion(scene, si));
        }

        // BSDF sampling: emission found along the sampled direction.
        for _ in 0..nb {
            let u = sampler.next_1d();
            let u2 = sampler.next_2d();
            let Some(bs) = bsdf.sample(ctx, wo_local, u, u2) else { continue };
            let wi = frame.to_world(bs.wi);
            let prev = PrevVertex { ctx: light_ctx, pdf: bs.pdf, delta: bs.delta };
            let mut le = Rgb::ZERO;
            // Only an emitter's surface interaction is needed.
            match scene.intersect_deferred(&si.spawn_ray(wi), &mut HitSlot::default()) {
                Some(hit) => {
                    if let Some(i) = hit.light() {
                        let hit = hit.interaction();
                        let e = scene.lights()[i as usize].le(hit.ns, -wi, hit.uv);
                        if e != Rgb::ZERO {
                            let w = trace::emission_weight(Some(&prev), false, &mis, |c| {
                                trace::light_pdf_at(scene, c, i, hit.p, hit.ng)
                            });
                            le += e * w;
                        }
                    }
                }
                None => trace::escaped(scene, si.p, wi, Some(&prev), false, &mis, |e, w| le += e * w),
            }
            // bs.weight = f cos / pdf; divide by the number of BSDF samples.
            l += bs.weight * le / nb as f32;
        }
        (l, covered)
    }
}

impl DirectIntegrator {
    /// Mitsuba's `direct`: `shading_samples` (1; the default of both counts), `emitter_samples`,
    /// `bsdf_samples` (each 0 to 1024, not both 0), `hide_emitters` (false).
    pub fn from_props(o: &Obj) -> PropResult<DirectIntegrator> {
        let count = |name: &str, default: i64| -> PropResult<u32> {
            let v = o.int(name, default)?;
            if (0..=1024).contains(&v) {
                Ok(v as u32)
            } else {
                Err(o.error_at(name, format!("'{name}' must be between 0 and 1024, got {v}")))
            }
        };
        let shading = count("shading_samples", 1)?;
        let d = DirectIntegrator {
            emitter_samples: count("emitter_samples", shading as i64)?,
            bsdf_samples: count("bsdf_samples", shading as i64)?,
            hide_emitters: o.bool("hide_emitters", false)?,
        };
        if d.emitter_samples + d.bsdf_samples == 0 {
            return Err(o.error("needs at least one emitter or BSDF sample"));
        }
        Ok(d)
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
        let (reference, se_ref) = mean_and_se(&scene, &PathIntegrator::with_max_depth(2), 512, 1);
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

    /// Light sampling alone (no BSDF samples) under an MIS-compensated environment map draws
    /// from the map's complete density, so it stays unbiased: the same mean as with the plain
    /// map, where the compensated density alone would miss the sky dimmer than its mean.
    #[test]
    fn light_sampling_alone_ignores_mis_compensation() {
        use crate::camera::{Camera, FovAxis};
        use crate::geometry::{Geometry, Sphere};
        use crate::light::{EnvMap, Light};
        use crate::material::{Bsdf, Diffuse};
        use crate::math::{Transform, Vec3};
        use crate::scene::SceneBuilder;
        // A dim gradient with a bright patch well above its mean.
        let (w, h) = (32usize, 16usize);
        let pixels = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (4..10).contains(&x) && (2..6).contains(&y) {
                    Rgb::splat(20.0)
                } else {
                    Rgb::new(0.2 + x as f32 / w as f32, 0.4, 0.3 + y as f32 / h as f32)
                }
            })
            .collect();
        let sky = crate::load::image::Image { width: w as u32, height: h as u32, pixels };
        let scene = |compensated: bool| {
            let mut b = SceneBuilder::new();
            let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.7))));
            b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), m, None);
            let map = EnvMap::new_latlong(sky.clone(), 1.0, Transform::IDENTITY, compensated).unwrap();
            assert_eq!(map.is_compensated(), compensated);
            b.add_light(Light::EnvMap { map: Box::new(map), center: Vec3::ZERO, radius: 0.0 });
            let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y).unwrap();
            b.set_camera(Camera::perspective(to_world, 30.0, FovAxis::X, 8, 8).unwrap());
            b.build().unwrap()
        };
        let light_only = DirectIntegrator { emitter_samples: 1, bsdf_samples: 0, hide_emitters: true };
        let (plain, se_plain) = mean_and_se(&scene(false), &light_only, 256, 1);
        let (compensated, se) = mean_and_se(&scene(true), &light_only, 256, 2);
        let z = (compensated - plain) / (se * se + se_plain * se_plain).sqrt();
        assert!(z.abs() < 4.0 && plain > 0.01, "{compensated} vs {plain}, z = {z:.2}");
        // Combined with BSDF sampling the compensated density is what light sampling draws.
        let (mis, se_mis) =
            mean_and_se(&scene(true), &DirectIntegrator { hide_emitters: true, ..Default::default() }, 256, 3);
        let z = (mis - plain) / (se_mis * se_mis + se_plain * se_plain).sqrt();
        assert!(z.abs() < 4.0, "{mis} vs {plain}, z = {z:.2}");
    }

    /// A delta light's share does not grow with the number of light samples: a point light of
    /// intensity I at the centre of a diffuse sphere (albedo ρ, radius r, seen from inside)
    /// gives every wall point `ρ I / (π r²)` whatever the split. (Mitsuba 3.9.1's `direct`
    /// weighs each of its `emitter_samples` samples of a delta light by 1 instead of
    /// 1 / `emitter_samples`, which multiplies point and spot lights by that count.)
    #[test]
    fn delta_lights_count_once_whatever_the_sample_counts() {
        use crate::camera::{Camera, FovAxis};
        use crate::geometry::{Geometry, Sphere};
        use crate::material::{Bsdf, Diffuse};
        use crate::math::{Transform, Vec3};
        use crate::scene::SceneBuilder;
        let (rho, intensity, r) = (0.5f32, 3.0f32, 1.5f32);
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(rho))));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, r, true)), m, None);
        b.add_point_light(Vec3::ZERO, Rgb::splat(intensity));
        let to_world = Transform::look_at(Vec3::ZERO, Vec3::new(0.3, 0.2, 1.0), Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 90.0, FovAxis::X, 8, 6).unwrap());
        let scene = b.build().unwrap();
        let expected = f64::from(rho * intensity / (std::f32::consts::PI * r * r));
        for (nl, nb) in [(1, 1), (3, 1), (3, 0), (2, 5)] {
            let d = DirectIntegrator { emitter_samples: nl, bsdf_samples: nb, hide_emitters: false };
            let (mean, _) = mean_and_se(&scene, &d, 4, 5);
            assert!((mean / expected - 1.0).abs() < 1e-4, "({nl}, {nb}): {mean} vs {expected}");
        }
    }
}
