//! Volumetric path tracing (Mitsuba's `volpath`): the path tracer extended to participating
//! media.
//!
//! Inside a medium the distance to the next interaction is sampled from the exponential
//! distribution by inversion (`t = -ln(1 - ξ)/σₜ`, [`Medium::sample_free_flight`]). If it falls
//! before the next surface the path scatters there: the throughput takes `σₛ Tr / p`, direct
//! light is estimated by light sampling with the transmittance of the shadow ray through media
//! and null boundaries (and MIS against phase-function sampling), and the path continues along
//! a direction sampled from the phase function. Otherwise the path reaches the surface with
//! weight `Tr / P(pass)` and proceeds as in [`super::PathIntegrator`] (emission with MIS, NEE
//! with transmittance, BSDF sampling, Russian roulette).
//!
//! Media: the camera's medium to start with; crossing a shape's surface (through a `null`
//! BSDF, or by refraction) enters its `interior` when going against its normal and its
//! `exterior` when going along it. Null surfaces are not path vertices (they do not count
//! toward `max_depth`).
//!
//! Parameters (Mitsuba): `max_depth` (segments, -1 unlimited), `rr_depth` (5),
//! `hide_emitters` (false).

use super::trace::{self, Mis, PathSettings, PrevVertex};
use super::{Integrator, RadianceSample};
use crate::geometry::interaction::SHADOW_EPSILON;
use crate::light::LightSampleContext;
use crate::material::TextureMemo;
use crate::math::float::offset_ray_origin;
use crate::math::{Ray, Rgb, Vec3};
use crate::medium::{FreeFlight, Medium};
use crate::sampling::{Pcg32, Sampler};
use crate::scene::Scene;

/// Crossings of null surfaces allowed along one segment (guards against degenerate geometry).
const MAX_NULL_CROSSINGS: u32 = 256;

/// Mitsuba's `volpath`.
#[derive(Clone, Debug, Default)]
pub struct VolPathIntegrator {
    /// `max_depth`, `rr_depth`, `hide_emitters`.
    pub settings: PathSettings,
    /// pbrt-v4's path regularization (`regularize`, false): after the path's first
    /// non-specular bounce — a BSDF sample that is no delta, a scattering in a medium, a
    /// subsurface exit — its BSDFs are seen widened ([`crate::material::Bsdf::regularized`]).
    pub regularize: bool,
}

/// The medium a ray leaving shape `shape`'s surface along `d` (geometric normal `ng`) starts
/// in: the shape's interior when `d` is against the normal, else its exterior; a shape without
/// media keeps the current one. Every ray leaving such a surface takes it, reflected or
/// transmitted, camera, BSDF or shadow ray (Mitsuba's `target_medium`, pbrt-v4's `GetMedium`):
/// where media overlap or a shape declares one side only, the side's declaration wins over the
/// medium the path arrived in (a ray reflected off the outside of a shape with an interior
/// medium only starts in vacuum).
#[inline]
pub(crate) fn medium_after(scene: &Scene, shape: u32, ng: Vec3, d: Vec3, current: Option<u32>) -> Option<u32> {
    let s = &scene.shapes()[shape as usize];
    if s.interior.is_none() && s.exterior.is_none() {
        return current;
    }
    if d.dot(ng) < 0.0 {
        s.interior
    } else {
        s.exterior
    }
}

/// How light travelling along `d` crosses the surface at `si` unscattered, as
/// [`crate::material::Bsdf::null_transmission`] gives it: `(T, P)`, the factor it is multiplied by and the
/// probability that BSDF sampling takes that crossing; `None` where nothing passes (an opaque
/// BSDF, or `T = 0`).
pub(super) fn null_transmission(
    scene: &Scene,
    si: &crate::geometry::SurfaceInteraction,
    d: Vec3,
) -> Option<(Rgb, f32)> {
    let bsdf = &scene.bsdfs()[scene.shapes()[si.shape as usize].bsdf as usize];
    if !bsdf.may_pass() {
        return None;
    }
    let cos_theta = si.ns.dot(d) / d.length();
    bsdf.null_transmission(&scene.bsdf_context(si), cos_theta).filter(|(t, _)| *t != Rgb::ZERO)
}

/// Transmittance along the shadow ray `ray` (segment `t ∈ (0, t_max)`, its end at
/// `ray.at(1)`) starting in `medium`: the product of the media's transmittances over the
/// pieces between null surfaces (estimates for heterogeneous media, from `rng`); zero if
/// anything else blocks it.
pub fn transmittance(scene: &Scene, mut ray: Ray, mut medium: Option<u32>, rng: &mut Pcg32) -> Rgb {
    let target = ray.at(1.0);
    let mut tr = Rgb::ONE;
    let media: &[Medium] = scene.media();
    for _ in 0..MAX_NULL_CROSSINGS {
        let length = ray.d.length();
        let hit = scene.intersect(&ray);
        if let Some(si) = &hit {
            // Null surfaces pass it on; a filter, a thin dielectric or a mask's transparent
            // part only a share of it (Mitsuba's `eval_null_transmission`).
            match null_transmission(scene, si, ray.d) {
                Some((t, _)) => tr *= t,
                None => return Rgb::ZERO,
            }
        }
        if let Some(m) = medium {
            let t_end = hit.as_ref().map_or(ray.t_max.min(1.0), |si| si.t);
            tr *= media[m as usize].transmittance(&Ray::new(ray.o, ray.d / length), length * t_end, rng);
            if tr == Rgb::ZERO {
                return tr;
            }
        }
        let Some(si) = &hit else { return tr };
        medium = medium_after(scene, si.shape, si.ng, ray.d, medium);
        let o = si.offset_origin(ray.d);
        ray = Ray::bounded(o, target - o, 1.0 - SHADOW_EPSILON).at_time(ray.time);
    }
    Rgb::ZERO
}

/// The generator of a path's tracking decisions in heterogeneous media
/// ([`trace::path_rng`]); scenes without such media draw none (their images stay as they were).
pub fn tracking_rng(scene: &Scene, sampler: &mut Sampler) -> Pcg32 {
    if scene.media().iter().any(Medium::is_heterogeneous) {
        trace::path_rng(sampler)
    } else {
        Pcg32::default()
    }
}

impl Integrator for VolPathIntegrator {
    fn name(&self) -> &'static str {
        "volpath"
    }

    fn sample(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler, _terms: &mut [Rgb]) -> RadianceSample {
        let mut covered = false;
        let max_depth = self.settings.max_segments();
        let hide = self.settings.hide_emitters;
        let mis = Mis::POWER;
        let media = scene.media();
        let mut l = Rgb::ZERO;
        let mut beta = Rgb::ONE;
        let mut eta = 1.0f32;
        // Unit direction (free-flight distances are lengths), keeping the camera's clip range.
        let len = camera_ray.d.length();
        let mut ray = Ray::bounded(camera_ray.o, camera_ray.d / len, camera_ray.t_max * len).at_time(camera_ray.time);
        let mut medium = scene.camera_medium();
        let mut prev: Option<PrevVertex> = None;
        let mut depth = 0u32;
        let mut crossings = 0u32;
        let mut rng = tracking_rng(scene, sampler);
        // pbrt-v4's `anyNonSpecularBounces` (which starts regularization).
        let mut non_specular = false;
        if max_depth == 0 {
            let hit = scene.intersect(camera_ray).is_some();
            return RadianceSample { l, alpha: trace::coverage(scene, hit, self.settings.hide_emitters) };
        }
        loop {
            let hit = scene.intersect(&ray);
            let t_surface = hit.as_ref().map_or(f32::INFINITY, |si| si.t);

            // Free flight through the current medium.
            if let Some(m) = medium {
                let medium_ref = &media[m as usize];
                // Light an emissive medium gives off along the segment (nothing otherwise).
                l += beta * medium_ref.emitted(&ray, t_surface, &mut rng);
                let (u_channel, u_t) = (sampler.next_1d(), sampler.next_1d());
                match medium_ref.sample_free_flight(&ray, t_surface, beta, u_channel, u_t, &mut rng) {
                    FreeFlight::Scatter { t, weight } => {
                        beta *= weight;
                        let p = ray.at(t);
                        let wo = -ray.d;
                        let phase = &medium_ref.phase;
                        if depth + 1 >= max_depth || beta == Rgb::ZERO {
                            break;
                        }
                        covered = true;
                        let (u_light, u_light2) = (sampler.next_1d(), sampler.next_2d());
                        // A point in a medium has no normal.
                        let light_ctx = LightSampleContext { p, n: Vec3::ZERO };
                        let nee = medium_ref.sample_emitters;
                        if nee {
                            l += beta
                                * trace::sample_direct(
                                    scene,
                                    &light_ctx,
                                    u_light,
                                    u_light2,
                                    &mis,
                                    |wi, _| {
                                        // A phase function samples its own value.
                                        let v = phase.eval(p, wo, wi);
                                        (Rgb::splat(v), v)
                                    },
                                    |ls| {
                                        let (lp, ln) = (ls.p, ls.n);
                                        let target = if ln == Vec3::ZERO {
                                            lp
                                        } else {
                                            offset_ray_origin(lp, ls.p_error, ln, p - lp)
                                        };
                                        transmittance(
                                            scene,
                                            Ray::bounded(p, target - p, 1.0 - SHADOW_EPSILON).at_time(ray.time),
                                            medium,
                                            &mut rng,
                                        )
                                    },
                                );
                        }
                        let s = phase.sample(p, wo, sampler.next_2d());
                        if s.pdf <= 0.0 {
                            break; // (degenerate SGGX flakes: no direction to scatter into)
                        }
                        // Without emitter sampling, emission found by phase sampling counts in
                        // full, as after a specular bounce.
                        prev = Some(PrevVertex { ctx: light_ctx, pdf: s.pdf, delta: !nee });
                        non_specular = true;
                        ray = Ray::new(p, s.value).at_time(ray.time);
                        depth += 1;
                        crossings = 0;
                        if !super::russian_roulette(&mut beta, eta, depth, self.settings.rr_depth, sampler.next_1d()) {
                            break;
                        }
                        continue;
                    }
                    FreeFlight::Pass { weight } => beta *= weight,
                }
            }

            // Bound by reference (moved out of the `Option`, the interaction would be copied by
            // wide loads right after `intersect` wrote it field by field, and wait for those
            // stores to reach the cache).
            let Some(si) = &hit else {
                trace::escaped(scene, ray.o, ray.d, prev.as_ref(), hide, &mis, |le, w| l += beta * le * w);
                break;
            };
            let shape = scene.shapes()[si.shape as usize];
            let bsdf = if self.regularize && non_specular {
                &scene.regularized_bsdfs()[shape.bsdf as usize]
            } else {
                &scene.bsdfs()[shape.bsdf as usize]
            };
            let wo = -ray.d;

            // Emission found by the path (not for hidden emitters seen by the camera).
            let hidden = depth == 0 && hide && shape.light.is_some();
            if let Some(li) = shape.light.filter(|_| !hidden) {
                let le = scene.lights()[li as usize].le(si.ns, wo, si.uv);
                if le != Rgb::ZERO {
                    let w = trace::emission_weight(prev.as_ref(), hide, &mis, |c| {
                        trace::light_pdf_at(scene, c, li, si.p, si.ng)
                    });
                    l += beta * le * w;
                }
            }
            // Null boundaries (and hidden emitters) are crossed, not scattered from.
            if bsdf.is_null() || hidden {
                crossings += 1;
                if crossings > MAX_NULL_CROSSINGS {
                    break;
                }
                if bsdf.is_null() {
                    // (`None`: a filter that lets nothing through.)
                    let Some((t, _)) = null_transmission(scene, si, ray.d) else { break };
                    beta *= t;
                    medium = medium_after(scene, si.shape, si.ng, ray.d, medium);
                }
                ray = si.spawn_ray(ray.d);
                continue;
            }
            // At the last vertex only a crossing that does not scatter (a thin dielectric's
            // transmission, a mask's transparent part) can go on, as in Mitsuba.
            let last = depth + 1 >= max_depth;
            if last && !bsdf.may_pass() {
                covered = true;
                break;
            }
            // Textures and normal maps looked up once for this vertex's BSDF calls.
            let memo = TextureMemo::default();
            let vertex = trace::SurfaceVertex::new(scene, si, bsdf, &memo, wo);
            let (ctx, frame, wo_local) = (&vertex.ctx, vertex.frame, vertex.wo_local);
            let light_ctx = LightSampleContext { p: si.p, n: si.ns };
            let (u_light, u_light2) = (sampler.next_1d(), sampler.next_2d());
            if !bsdf.is_delta() && !last {
                // The shadow ray starts in the medium on the light's side of the surface.
                let side_medium = |wi: Vec3| medium_after(scene, si.shape, si.ng, wi, medium);
                l += beta
                    * trace::sample_direct_bsdf(scene, &light_ctx, (u_light, u_light2), &mis, &vertex, |ls| {
                        transmittance(scene, si.spawn_ray_to(ls.p, ls.n, ls.p_error), side_medium(ls.wi), &mut rng)
                    });
            }
            let (u_bsdf, u_bsdf2) = (sampler.next_1d(), sampler.next_2d());
            let bs = bsdf.sample(ctx, wo_local, u_bsdf, u_bsdf2);
            // Coverage, Mitsuba 3.9.1's `valid_ray` in its volumetric path tracers: a surface
            // vertex whose sample is not a null crossing, the last one too (or a scattering in a
            // medium the path goes on from).
            covered |= !bs.as_ref().is_some_and(|b| b.null);
            let Some(bs) = bs else { break };
            if last && !bs.null {
                break;
            }
            beta *= bs.weight;
            eta *= bs.eta;
            non_specular |= !bs.delta && !bs.null;
            let wi = frame.to_world(bs.wi);
            // The vertex MIS refers to next: this one, or where the light leaves a subsurface
            // material it refracted into (the BSSRDF's probe finds that point).
            let vertex = if let Some(sss) = bsdf.subsurface().filter(|_| !bs.null && bs.wi.z * wo_local.z < 0.0) {
                let u = (sampler.next_1d(), sampler.next_1d(), sampler.next_2d());
                let Some((exit, w)) = super::subsurface::probe_exit(scene, sss, ctx, si, shape.bsdf, u, &mut rng)
                else {
                    break;
                };
                beta *= w;
                let exit_ctx = LightSampleContext { p: exit.p, n: exit.ns };
                let (u_light, u_light2) = (sampler.next_1d(), sampler.next_2d());
                let sss_eta = sss.eta;
                l += beta
                    * trace::sample_direct(
                        scene,
                        &exit_ctx,
                        u_light,
                        u_light2,
                        &mis,
                        |wi, _| super::subsurface::exit_lobe(&exit, sss_eta, wi),
                        |ls| {
                            let side = medium_after(scene, exit.shape, exit.ng, ls.wi, medium);
                            transmittance(scene, exit.spawn_ray_to(ls.p, ls.n, ls.p_error), side, &mut rng)
                        },
                    );
                let Some((wi, w, pdf)) = super::subsurface::sample_exit_lobe(&exit, sss_eta, sampler.next_2d()) else {
                    break;
                };
                beta *= w;
                non_specular = true;
                medium = medium_after(scene, exit.shape, exit.ng, wi, medium);
                ray = exit.spawn_ray(wi);
                PrevVertex { ctx: exit_ctx, pdf, delta: false }
            } else {
                medium = medium_after(scene, si.shape, si.ng, wi, medium);
                ray = si.spawn_ray(wi);
                if bs.null {
                    // Passed straight through: not a bounce, and not the vertex MIS refers to.
                    crossings += 1;
                    if crossings > MAX_NULL_CROSSINGS {
                        break;
                    }
                    continue;
                }
                PrevVertex { ctx: light_ctx, pdf: bs.pdf, delta: bs.delta }
            };
            prev = Some(vertex);
            depth += 1;
            crossings = 0;
            if !super::russian_roulette(&mut beta, eta, depth, self.settings.rr_depth, sampler.next_1d()) {
                break;
            }
        }
        RadianceSample { l, alpha: trace::coverage(scene, covered, self.settings.hide_emitters) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, FovAxis};
    use crate::geometry::{Geometry, Sphere, TriangleMesh};
    use crate::material::Bsdf;
    use crate::math::Transform;
    use crate::medium::PhaseFunction;
    use crate::render::{render, RenderSettings};
    use crate::scene::SceneBuilder;
    use std::sync::atomic::AtomicBool;

    /// A cube of `medium` (the cube [-1, 1]³, null boundary) under a uniform sky of radiance
    /// 1, seen by a 12×12 camera at z = 5.
    fn cube_in_furnace(medium: Medium) -> crate::scene::Scene {
        let mut b = SceneBuilder::new();
        let null = b.add_bsdf(Bsdf::Null);
        let m = b.add_medium(medium);
        let s = b.add_shape(Geometry::Mesh(TriangleMesh::cube()), null, None);
        b.set_shape_media(s, Some(m), None);
        b.add_constant_environment(Rgb::ONE);
        b.set_camera(camera(12, 12, 30.0));
        b.build().unwrap()
    }

    /// A unit sphere of `shell` (around a diffuse ball of albedo ½ and radius ½ if `ball`)
    /// under a uniform sky of radiance 1, seen by a 12×12 camera at z = 5.
    fn shell_scene(shell: Bsdf, ball: bool) -> crate::scene::Scene {
        use crate::material::Diffuse;
        let mut b = SceneBuilder::new();
        let s = b.add_bsdf(shell);
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), s, None);
        if ball {
            let d = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
            b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 0.5, false)), d, None);
        }
        b.add_constant_environment(Rgb::ONE);
        b.set_camera(camera(12, 12, 30.0));
        b.build().unwrap()
    }

    /// The mean of a 12×12 image's four central pixels.
    fn centre(image: &[Rgb]) -> Rgb {
        (image[5 * 12 + 5] + image[5 * 12 + 6] + image[6 * 12 + 5] + image[6 * 12 + 6]) * 0.25
    }

    fn camera(w: u32, h: u32, fov: f32) -> Camera {
        let t = Transform::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y).unwrap();
        Camera::perspective(t, fov, FovAxis::X, w, h).unwrap()
    }

    /// An index-matched sphere of non-absorbing medium (albedo 1, HG g = 0.6, optical radius 2)
    /// under a uniform sky of radiance 1: light is only redirected, never lost, so every pixel
    /// — through the sphere or past it — has radiance 1. Tests free flights, phase sampling,
    /// NEE with transmittance through the null boundary, and MIS with the environment.
    /// Emissive media (pbrt-v4's `Le`), with no other light, under both volumetric path
    /// tracers. A ball of absorbing medium (albedo 0, σₜ (1.5, 0.5, 1), radius 1) seen through
    /// its centre shows `Lₑ (1 − e^(−2 σₜ))`. A camera deep inside an emissive scattering medium
    /// (albedo (0.6, 0.8, 0.3), σₜ (4, 6, 9), HG g 0.3, a sphere of radius 6 with an
    /// index-matched boundary: the light that diffuses out is below e⁻¹⁵ of it) sees `Lₑ`
    /// everywhere: emission `σₐ Lₑ` balances absorption `σₐ L`.
    /// Homogeneous media (the closed form along each segment) and heterogeneous ones (the
    /// collision estimator) alike.
    #[test]
    fn emissive_media_glow_as_the_transport_equation_says() {
        use crate::integrator::VolPathMisIntegrator;
        use crate::medium::{volume::Volume, Coefficients, Heterogeneous};
        let le = Rgb::new(2.0, 1.0, 0.5);
        // Chromatic (σₜ and albedo differ per channel), so that the channels' tracking and
        // volpathmis's spectral MIS are exercised.
        let emissive = |sigma_t: Rgb, albedo: Rgb, g: f32, heterogeneous: bool| {
            let coefficients = if heterogeneous {
                // Constant volumes over the box [-6, 6]³, which holds both spheres.
                let to_world = Transform::translate(Vec3::splat(-6.0)) * Transform::scale(Vec3::splat(12.0)).unwrap();
                let sigma = Volume::constant(sigma_t / sigma_t.max_element(), to_world);
                let albedo = Volume::constant(albedo, to_world);
                Coefficients::Heterogeneous(Box::new(Heterogeneous::new(sigma, albedo, sigma_t.max_element())))
            } else {
                Coefficients::Homogeneous(crate::medium::Homogeneous { sigma_t, albedo })
            };
            Medium {
                coefficients,
                phase: PhaseFunction::HenyeyGreenstein { g },
                sample_emitters: true,
                radiance: Some(Volume::constant(le, Transform::IDENTITY)),
            }
        };
        let integrators: [(&str, Box<dyn Integrator>); 2] = [
            ("volpath", Box::new(VolPathIntegrator::default())),
            ("volpathmis", Box::new(VolPathMisIntegrator::default())),
        ];
        for heterogeneous in [false, true] {
            for (name, integrator) in &integrators {
                // The absorbing ball, from outside.
                let mut b = SceneBuilder::new();
                let null = b.add_bsdf(Bsdf::Null);
                let sigma_ball = Rgb::new(1.5, 0.5, 1.0);
                let m = b.add_medium(emissive(sigma_ball, Rgb::ZERO, 0.0, heterogeneous));
                let s = b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), null, None);
                b.set_shape_media(s, Some(m), None);
                b.set_camera(camera(12, 12, 2.0));
                let scene = b.build().unwrap();
                let settings = RenderSettings { spp: 64, seed: 21, ..Default::default() };
                let out = render(&scene, integrator.as_ref(), &settings, &AtomicBool::new(false)).unwrap();
                let c = centre(&out.film.image());
                let expect = le * (Rgb::ONE - (-2.0 * sigma_ball).exp());
                for k in 0..3 {
                    let tol = if heterogeneous { 0.03 } else { 1e-3 };
                    assert!(
                        (c[k] - expect[k]).abs() <= tol * expect[k],
                        "{name}, heterogeneous {heterogeneous}: ball {c} vs {expect}"
                    );
                }

                // Deep inside a scattering one.
                let mut b = SceneBuilder::new();
                let null = b.add_bsdf(Bsdf::Null);
                let m = b.add_medium(emissive(Rgb::new(4.0, 6.0, 9.0), Rgb::new(0.6, 0.8, 0.3), 0.3, heterogeneous));
                let s = b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 6.0, false)), null, None);
                b.set_shape_media(s, Some(m), None);
                b.set_camera_medium(Some(m));
                b.set_camera(camera(4, 4, 60.0));
                let scene = b.build().unwrap();
                let settings = RenderSettings { spp: 1024, seed: 22, ..Default::default() };
                let out = render(&scene, integrator.as_ref(), &settings, &AtomicBool::new(false)).unwrap();
                let mean = out.film.image().iter().fold(Rgb::ZERO, |a, &p| a + p) / 16.0;
                // Standard error of the 16 pixels' mean, per channel.
                let var = out.film.variance_of_mean().iter().fold(Rgb::ZERO, |a, &v| a + v) / 256.0;
                for k in 0..3 {
                    let se = var[k].sqrt();
                    assert!(se < 0.01 * le[k], "{name}: too noisy to see a bias ({se})");
                    assert!(
                        (mean[k] - le[k]).abs() <= 4.0 * se + 1e-3 * le[k],
                        "{name}, heterogeneous {heterogeneous}: inside {mean} vs {le} (se {se})"
                    );
                }
            }
        }
    }

    #[test]
    fn index_matched_scattering_sphere_is_invisible_in_a_furnace() {
        for phase in [PhaseFunction::Isotropic, PhaseFunction::HenyeyGreenstein { g: 0.6 }] {
            let mut b = SceneBuilder::new();
            let null = b.add_bsdf(Bsdf::Null);
            let m = b.add_medium(Medium::homogeneous(Rgb::new(1.0, 2.0, 3.0), Rgb::ONE, phase.clone()).unwrap());
            let s = b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), null, None);
            b.set_shape_media(s, Some(m), None);
            b.add_constant_environment(Rgb::ONE);
            b.set_camera(camera(12, 12, 30.0));
            let scene = b.build().unwrap();
            let out = render(
                &scene,
                &VolPathIntegrator::default(),
                &RenderSettings { spp: 1024, seed: 1, ..Default::default() },
                &AtomicBool::new(false),
            )
            .unwrap();
            let (mean, se) = out.film.mean_and_std_error();
            println!("{phase:?}: mean {mean:.5} ± {se:.5}");
            assert!(se < 0.003, "too noisy: {se}");
            assert!((mean - 1.0).abs() < 3.0 * se + 1e-4, "{phase:?}: mean {mean} ± {se}");
            let centre = out.film.image()[6 * 12 + 6];
            assert!((centre - Rgb::ONE).abs().max_element() < 0.15, "centre pixel {centre}");
        }
    }

    /// A closed polarizing filter (Mitsuba's `polarizer` as its RGB variants see it: half of
    /// the light times `transmittance`) in a white furnace: a camera ray through it crosses it
    /// twice, so the centre pixel is exactly (T/2)², the corners 1, with every integrator that
    /// meets it (volpath and volpathmis cross it, with their shadow rays; path samples its delta
    /// lobe). A sphere of the filter around a diffuse ball: direct light from the sky reaches
    /// the ball attenuated once, on shadow rays and BSDF-sampled ones alike.
    #[test]
    fn polarizing_filters_pass_their_share() {
        use crate::integrator::{Integrator, PathIntegrator, VolPathMisIntegrator};
        use crate::material::{Filter, FilterKind};
        use crate::texture::Texture;
        let t = Rgb::new(0.9, 0.6, 0.3);
        let filter =
            Bsdf::Filter(Filter { kind: FilterKind::LinearPolarizer, scale: 0.5, transmittance: Texture::Constant(t) });
        let integrators: [(&str, Box<dyn Integrator>); 3] = [
            ("volpath", Box::new(VolPathIntegrator::default())),
            ("volpathmis", Box::new(VolPathMisIntegrator::default())),
            ("path", Box::new(PathIntegrator::default())),
        ];
        for ball in [false, true] {
            let scene = shell_scene(filter.clone(), ball);
            for (name, integrator) in &integrators {
                let settings = RenderSettings { spp: 1024, seed: 3, ..Default::default() };
                let out = render(&scene, integrator.as_ref(), &settings, &AtomicBool::new(false)).unwrap();
                let image = out.film.image();
                let (centre, corner) = (centre(&image), image[0]);
                assert!((corner - Rgb::ONE).abs().max_element() < 1e-5, "{name}: corner {corner}");
                // Through the filter twice; or once to the ball (albedo ½ under the sky seen
                // through the filter, radiance ½ · T/2 everywhere on it: a convex ball does not
                // see itself).
                let expected = if ball { t * 0.5 * 0.5 * t * 0.5 } else { t * 0.5 * t * 0.5 };
                let err = (centre - expected).abs().max_element();
                let tol = if ball { 0.02 * expected.max_element() } else { 1e-5 };
                assert!(err <= tol, "{name} ball {ball}: centre {centre}, expected {expected}");
            }
        }
        // A filter that lets nothing through is black, not a hole.
        let opaque = Bsdf::Filter(Filter {
            kind: FilterKind::LinearPolarizer,
            scale: 0.5,
            transmittance: Texture::Constant(Rgb::ZERO),
        });
        let scene = shell_scene(opaque, true);
        for (name, integrator) in &integrators {
            let settings = RenderSettings { spp: 64, seed: 3, ..Default::default() };
            let image = render(&scene, integrator.as_ref(), &settings, &AtomicBool::new(false)).unwrap().film.image();
            assert_eq!(centre(&image), Rgb::ZERO, "{name}: an opaque filter");
        }
    }

    /// Coverage as Mitsuba 3.9.1's volumetric path tracers have it (measured there): null
    /// crossings cover nothing — a null sphere against a hidden white sky gives alpha 0 and no
    /// light —, and a surface behind them covers the sample even at `max_depth` 1, where the
    /// surface is the last vertex (its emission alone counts).
    #[test]
    fn null_crossings_cover_nothing_and_a_last_surface_does() {
        use crate::integrator::fixtures::{null_sphere_before_a_wall, sample_toward};
        let scene = null_sphere_before_a_wall();
        let sample = |max_depth: i32, target: Vec3| {
            let settings = PathSettings { max_depth, hide_emitters: true, ..Default::default() };
            sample_toward(&scene, &VolPathIntegrator { settings, regularize: false }, target)
        };
        let sky = sample(4, Vec3::new(0.0, 0.6, 0.0));
        assert_eq!((sky.l, sky.alpha), (Rgb::ZERO, 0.0));
        assert_eq!(sample(1, Vec3::new(0.0, 0.0, -2.0)).alpha, 1.0);
    }

    /// Surfaces light crosses unscattered — a thin dielectric's transmission, a mask's
    /// transparent part — are not bounces for the volumetric path tracers, and shadow rays
    /// cross them with their share (Mitsuba's `Null` lobe and `eval_null_transmission`): a
    /// diffuse ball (albedo ½) inside a sphere that lets 0.6 through (an index-matched thin
    /// dielectric with `specular_transmittance` 0.6; a mask of opacity 0.4 over a black
    /// BSDF), under a uniform sky, at `max_depth` 2 (direct light only): through the sphere to
    /// the ball and from it to the sky, ½ · 0.6 · 0.6 = 0.18. Were the crossing a bounce, the
    /// ball would be black at this depth (and light sampling from it blocked). A mask of
    /// opacity ½ over that pane has two null lobes and lets 0.8 through: ½ · 0.8² = 0.32.
    #[test]
    fn thin_dielectrics_and_masks_are_crossed_not_bounced() {
        use crate::integrator::{Integrator, VolPathMisIntegrator};
        use crate::material::{Diffuse, ThinDielectric};
        use crate::texture::Texture;
        let thin = Bsdf::ThinDielectric(ThinDielectric {
            eta: 1.0,
            specular_reflectance: Texture::Constant(Rgb::ONE),
            specular_transmittance: Texture::Constant(Rgb::splat(0.6)),
        });
        let black = Bsdf::Diffuse(Diffuse { reflectance: Texture::Constant(Rgb::ZERO) });
        let mask = Bsdf::Mask { opacity: Texture::Constant(Rgb::splat(0.4)), bsdf: std::sync::Arc::new(black) };
        // Two null lobes in one BSDF: half the light passes the mask, half the pane (0.6 of it).
        let masked_pane =
            Bsdf::Mask { opacity: Texture::Constant(Rgb::splat(0.5)), bsdf: std::sync::Arc::new(thin.clone()) };
        let settings = PathSettings { max_depth: 2, ..Default::default() };
        let integrators: [(&str, Box<dyn Integrator>); 2] = [
            ("volpath", Box::new(VolPathIntegrator { settings, regularize: false })),
            ("volpathmis", Box::new(VolPathMisIntegrator { settings })),
        ];
        for (shell, share) in [(thin, 0.6), (mask, 0.6), (masked_pane, 0.8)] {
            let scene = shell_scene(shell.clone(), true);
            for (name, integrator) in &integrators {
                let settings = RenderSettings { spp: 1024, seed: 5, ..Default::default() };
                let image =
                    render(&scene, integrator.as_ref(), &settings, &AtomicBool::new(false)).unwrap().film.image();
                let centre = centre(&image);
                let expected = 0.5 * share * share;
                let err = (centre - Rgb::splat(expected)).abs().max_element();
                assert!(err <= 0.02 * expected, "{name} {}: centre {centre}, expected {expected}", shell.plugin_name());
            }
        }
    }

    /// A heterogeneous medium: a non-absorbing grid (density from 0 to 3 m⁻¹, coloured so the
    /// channels track differently) filling the box of an index-matched cube, under a uniform
    /// sky: every pixel has radiance 1 (delta/spectral tracking, ratio-tracked shadow rays, MIS
    /// with the environment). The same scene with absorption (albedo 0.5) against the
    /// homogeneous medium of the same constant coefficients, as a constant volume.
    #[test]
    fn heterogeneous_media_conserve_and_agree_with_homogeneous() {
        use crate::image::GridVolume;
        use crate::medium::volume::{GridFilter, GridWrap, Volume};
        use crate::medium::{Coefficients, Heterogeneous};
        use std::sync::Arc;
        let n = 6;
        let data: Vec<f32> = (0..n * n * n * 3).map(|i| 1.5 + 1.5 * ((i as f32) * 0.71).sin()).collect();
        let grid = Arc::new(GridVolume { res: [n; 3], channels: 3, bbox: [[0.0; 3], [1.0; 3]], data });
        let to_world = Transform::translate(Vec3::splat(-1.0)) * Transform::scale(Vec3::splat(2.0)).unwrap();
        let sigma = Volume::grid(grid, GridFilter::Trilinear, GridWrap::Clamp, to_world).unwrap();
        let render_with = |medium: Medium, spp: u32| {
            let scene = cube_in_furnace(medium);
            let settings = RenderSettings { spp, seed: 5, ..Default::default() };
            render(&scene, &VolPathIntegrator::default(), &settings, &AtomicBool::new(false)).unwrap()
        };
        let hetero = |sigma_t: Volume, albedo: Rgb| Medium {
            coefficients: Coefficients::Heterogeneous(Box::new(Heterogeneous::new(
                sigma_t,
                Volume::constant(albedo, to_world),
                1.0,
            ))),
            phase: PhaseFunction::HenyeyGreenstein { g: 0.3 },
            sample_emitters: true,
            radiance: None,
        };
        let out = render_with(hetero(sigma, Rgb::ONE), 1024);
        let (mean, se) = out.film.mean_and_std_error();
        println!("furnace: mean {mean:.5} ± {se:.5}");
        assert!(se < 0.003 && (mean - 1.0).abs() < 3.0 * se + 1e-4, "mean {mean} ± {se}");
        let sigma = Rgb::new(0.5, 1.5, 3.0);
        let albedo = Rgb::splat(0.5);
        let a = render_with(hetero(Volume::constant(sigma, to_world), albedo), 1024);
        let mut homogeneous = Medium::homogeneous(sigma, albedo, PhaseFunction::HenyeyGreenstein { g: 0.3 }).unwrap();
        homogeneous.sample_emitters = false;
        let b = render_with(homogeneous, 1024);
        for c in 0..3 {
            let mean = |img: &[Rgb]| img.iter().map(|p| p[c] as f64).sum::<f64>() / img.len() as f64;
            let se = |v: &[Rgb]| v.iter().map(|p| p[c] as f64).sum::<f64>().sqrt() / v.len() as f64;
            let (ma, mb) = (mean(&a.film.image()), mean(&b.film.image()));
            let s = (se(&a.film.variance_of_mean()).powi(2) + se(&b.film.variance_of_mean()).powi(2)).sqrt();
            println!("channel {c}: heterogeneous {ma:.5}, homogeneous without NEE {mb:.5} ± {s:.5}");
            assert!((ma - mb).abs() < 3.0 * s + 1e-4, "channel {c}: {ma} vs {mb} ± {s}");
            assert!(ma < 0.95, "absorption shows");
        }
    }

    /// SGGX microflakes (fibres below, surface-like flakes above, blended in space; a matrix
    /// with eigenvalues above 1 too) in a non-absorbing cube under a uniform sky of radiance 1:
    /// whatever the direction-dependent extinction, light is only redirected, so every pixel is
    /// 1, for `volpath` and `volpathmis` alike (phase sampling, its density in NEE and MIS, and
    /// the projected area in free flights and transmittance must all agree). Mitsuba 3.9.1
    /// fails this test (its `sggx` samples directions that do not follow its own density; the
    /// README's Mitsuba section has the numbers). With absorption (albedo 0.8) the two
    /// integrators agree with each other.
    #[test]
    fn sggx_microflakes_conserve_energy() {
        use crate::image::GridVolume;
        use crate::integrator::volpathmis::VolPathMisIntegrator;
        use crate::medium::phase::SggxPhase;
        use crate::medium::volume::{GridFilter, GridWrap, Volume, Volume6};
        use crate::medium::{Coefficients, Heterogeneous};
        use std::sync::Arc;
        let to_world = Transform::translate(Vec3::splat(-1.0)) * Transform::scale(Vec3::splat(2.0)).unwrap();
        let texels =
            [[0.02, 1.0, 1.0, 0.0, 0.0, 0.0], [1.0, 0.09, 0.09, 0.0, 0.3, 0.0], [2.5, 0.4, 1.2, 0.3, 0.5, -0.2]];
        let grid = GridVolume {
            res: [1, 3, 1],
            channels: 6,
            bbox: [[0.0; 3], [1.0; 3]],
            data: texels.iter().flatten().copied().collect(),
        };
        let flakes = Arc::new(SggxPhase::new(
            Volume6::grid(Arc::new(grid), GridFilter::Trilinear, GridWrap::Clamp, to_world).unwrap(),
        ));
        let scene_with = |albedo: f32| {
            let h = Heterogeneous::new(
                Volume::constant(Rgb::splat(3.0), to_world),
                Volume::constant(Rgb::splat(albedo), to_world),
                1.0,
            )
            .with_flakes(flakes.clone());
            let medium = Medium {
                coefficients: Coefficients::Heterogeneous(Box::new(h)),
                phase: PhaseFunction::Sggx(flakes.clone()),
                sample_emitters: true,
                radiance: None,
            };
            cube_in_furnace(medium)
        };
        let settings = RenderSettings { spp: 512, seed: 5, ..Default::default() };
        let never = AtomicBool::new(false);
        let furnace = scene_with(1.0);
        let a = render(&furnace, &VolPathIntegrator::default(), &settings, &never).unwrap();
        let b = render(&furnace, &VolPathMisIntegrator::default(), &settings, &never).unwrap();
        for (name, out) in [("volpath", &a), ("volpathmis", &b)] {
            let (mean, se) = out.film.mean_and_std_error();
            println!("{name} furnace: mean {mean:.5} ± {se:.5}");
            assert!(se < 0.003 && (mean - 1.0).abs() < 3.0 * se + 1e-4, "{name}: mean {mean} ± {se}");
        }
        let lossy = scene_with(0.8);
        let a = render(&lossy, &VolPathIntegrator::default(), &settings, &never).unwrap();
        let b = render(&lossy, &VolPathMisIntegrator::default(), &settings, &never).unwrap();
        let ((ma, sa), (mb, sb)) = (a.film.mean_and_std_error(), b.film.mean_and_std_error());
        println!("albedo 0.8: volpath {ma:.5} ± {sa:.5}, volpathmis {mb:.5} ± {sb:.5}");
        assert!(ma < 0.9 && (ma - mb).abs() < 3.0 * (sa * sa + sb * sb).sqrt() + 1e-4, "{ma} vs {mb}");
    }

    /// Hostile SGGX grids give no NaN or infinite sample: a zero matrix (no flakes: the medium is
    /// empty), a flat one (S of rank one, D a delta: zero density everywhere), one that is not
    /// positive (negative diagonal and huge off-diagonal entries) and a tiny one, side by side
    /// along x.
    #[test]
    fn degenerate_sggx_grids_stay_finite() {
        use crate::image::GridVolume;
        use crate::medium::phase::SggxPhase;
        use crate::medium::volume::{GridFilter, GridWrap, Volume, Volume6};
        use crate::medium::{Coefficients, Heterogeneous};
        use std::sync::Arc;
        let to_world = Transform::translate(Vec3::splat(-1.0)) * Transform::scale(Vec3::splat(2.0)).unwrap();
        let texels = [
            [0.0; 6],
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [-1.0, 0.5, -2.0, 30.0, -40.0, 25.0],
            [1e-30, 1e-30, 1e-30, 0.0, 0.0, 0.0],
        ];
        let grid = GridVolume {
            res: [4, 1, 1],
            channels: 6,
            bbox: [[0.0; 3], [1.0; 3]],
            data: texels.iter().flatten().copied().collect(),
        };
        let flakes = Arc::new(SggxPhase::new(
            Volume6::grid(Arc::new(grid), GridFilter::Nearest, GridWrap::Clamp, to_world).unwrap(),
        ));
        let h = Heterogeneous::new(
            Volume::constant(Rgb::splat(2.0), to_world),
            Volume::constant(Rgb::splat(0.9), to_world),
            1.0,
        )
        .with_flakes(flakes.clone());
        let scene = cube_in_furnace(Medium {
            coefficients: Coefficients::Heterogeneous(Box::new(h)),
            phase: PhaseFunction::Sggx(flakes),
            sample_emitters: true,
            radiance: None,
        });
        let settings = RenderSettings { spp: 64, seed: 1, ..Default::default() };
        let out = render(&scene, &VolPathIntegrator::default(), &settings, &AtomicBool::new(false)).unwrap();
        // The film drops (and counts) non-finite samples: none may reach it.
        assert_eq!(out.film.dropped(), 0, "samples with NaN or infinite radiance");
        let image = out.film.image();
        assert!(image.iter().all(|p| p.min_element() >= 0.0), "a negative pixel");
        // The zero matrix's quarter is empty: its pixels see the sky.
        assert!(image[6 * 12 + 1].x > 0.99, "{}", image[6 * 12 + 1]);
    }

    /// A purely absorbing slab of thickness d (null boundaries, σₜ per channel) in front of a
    /// uniform sky: each pixel sees `e^(-σₜ d / cos θ)` (θ the ray's angle to the slab normal),
    /// the Beer–Lambert law; checked per channel on the image mean against the same law
    /// averaged over each pixel.
    #[test]
    fn slab_transmittance_follows_beer_lambert() {
        let d = 0.4f32;
        let sigma = Rgb::new(0.5, 2.0, 5.0);
        let mut b = SceneBuilder::new();
        let null = b.add_bsdf(Bsdf::Null);
        let m = b.add_medium(Medium::homogeneous(sigma, Rgb::ZERO, PhaseFunction::Isotropic).unwrap());
        let mut slab = TriangleMesh::cube();
        slab.transform(&Transform::scale(Vec3::new(3.0, 3.0, d / 2.0)).unwrap());
        let s = b.add_shape(Geometry::Mesh(slab), null, None);
        b.set_shape_media(s, Some(m), None);
        b.add_constant_environment(Rgb::ONE);
        let cam = camera(16, 16, 40.0);
        b.set_camera(cam.clone());
        let scene = b.build().unwrap();
        let out = render(
            &scene,
            &VolPathIntegrator::default(),
            &RenderSettings { spp: 1024, seed: 2, ..Default::default() },
            &AtomicBool::new(false),
        )
        .unwrap();
        let img = out.film.image();
        let var = out.film.variance_of_mean();
        // Expected per pixel: average over a 4×4 grid of film positions.
        for c in 0..3 {
            let (mut got, mut want, mut v) = (0.0f64, 0.0f64, 0.0f64);
            for y in 0..16 {
                for x in 0..16 {
                    let i = y * 16 + x;
                    got += img[i][c] as f64;
                    v += var[i][c] as f64;
                    let mut e = 0.0f64;
                    for k in 0..16 {
                        let f = crate::math::Vec2::new(
                            x as f32 + (k % 4) as f32 / 4.0 + 0.125,
                            y as f32 + (k / 4) as f32 / 4.0 + 0.125,
                        );
                        let dir = cam.generate_ray(f, crate::math::Vec2::ZERO).d;
                        e += (-(sigma[c] as f64) * d as f64 / dir.z.abs() as f64).exp() / 16.0;
                    }
                    want += e;
                }
            }
            let (got, want, se) = (got / 256.0, want / 256.0, v.sqrt() / 256.0);
            println!("channel {c}: {got:.5} vs Beer–Lambert {want:.5} ± {se:.5}");
            assert!((got - want).abs() < 3.0 * se + 2e-4 * want, "channel {c}: {got} vs {want}");
        }
    }

    /// The camera's far clip bounds camera rays as in the path tracer: with everything beyond
    /// it (and no environment), the image is black.
    #[test]
    fn camera_rays_respect_the_far_clip() {
        let mut scene = crate::scene::cornell::cornell_box(8, 8).unwrap();
        let cam = scene.camera().clone().with_clip(0.01, 0.5).unwrap();
        scene.set_camera(cam);
        let out = render(
            &scene,
            &VolPathIntegrator::default(),
            &RenderSettings { spp: 4, ..Default::default() },
            &AtomicBool::new(false),
        )
        .unwrap();
        assert!(out.film.image().iter().all(|c| *c == Rgb::ZERO));
    }

    /// A mirror sphere that declares an interior medium only, seen by a camera in an absorbing
    /// fog (σₜ 0.5) from 4 units: the reflected ray leaves the sphere's outside, whose
    /// declared medium is none, so it travels in vacuum to the white sky, and the centre pixels
    /// show `e^(-0.5 · 4)`, in both volumetric path tracers (Mitsuba's `target_medium` rule;
    /// Mitsuba 3.9.1 renders 0.1333 ± 0.002 at 4096 spp). Keeping the fog for a ray reflected
    /// on the side it came from, as neumann did, made it black: the fog never ends.
    #[test]
    fn a_ray_leaving_a_surface_takes_the_medium_its_shape_declares_on_that_side() {
        let text = r#"<scene version="3.0.0">
            <medium type="homogeneous" id="fog"><float name="sigma_t" value="0.5"/><float name="albedo" value="0"/></medium>
            <sensor type="perspective"><float name="fov" value="2"/><ref name="medium" id="fog"/>
                <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/><rfilter type="box"/></film>
            </sensor>
            <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
            <shape type="sphere">
                <float name="radius" value="1"/><bsdf type="conductor"><string name="material" value="none"/></bsdf>
                <medium type="homogeneous" name="interior"><float name="sigma_t" value="1"/></medium>
            </shape>
        </scene>"#;
        let scene = crate::load::mitsuba::load_scene_text(std::path::Path::new("fog.xml"), text, &[]).unwrap().scene;
        let want = (-2.0f64).exp();
        let integrators: [&dyn Integrator; 2] =
            [&VolPathIntegrator::default(), &crate::integrator::VolPathMisIntegrator::default()];
        for integrator in integrators {
            let settings = RenderSettings { spp: 1024, seed: 5, ..Default::default() };
            let out = render(&scene, integrator, &settings, &AtomicBool::new(false)).unwrap();
            let (mean, se) = out.film.mean_and_std_error();
            println!("{}: {mean:.5} ± {se:.5}, e^-2 = {want:.5}", integrator.name());
            assert!(se < 0.005 && (mean - want).abs() < 4.0 * se, "{}: {mean} ± {se}", integrator.name());
        }
    }

    /// Without media, volpath is the path tracer: the same Cornell box mean within noise.
    #[test]
    fn without_media_it_matches_the_path_tracer() {
        let scene = crate::scene::cornell::cornell_box(16, 16).unwrap();
        let never = AtomicBool::new(false);
        let a = render(
            &scene,
            &VolPathIntegrator::default(),
            &RenderSettings { spp: 512, seed: 3, ..Default::default() },
            &never,
        )
        .unwrap();
        let b = render(
            &scene,
            &crate::integrator::PathIntegrator::default(),
            &RenderSettings { spp: 512, seed: 4, ..Default::default() },
            &never,
        )
        .unwrap();
        let ((ma, sa), (mb, sb)) = (a.film.mean_and_std_error(), b.film.mean_and_std_error());
        assert!((ma - mb).abs() < 3.0 * (sa * sa + sb * sb).sqrt(), "volpath {ma} ± {sa}, path {mb} ± {sb}");
    }
}
