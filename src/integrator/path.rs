//! The path tracer (Mitsuba's `path`): backward tracing from the camera with next-event
//! estimation, MIS and Russian roulette.
//!
//! At every vertex the path adds `Lₑ` from emitters it hits and, by next-event estimation,
//! light sampled on one emitter (chosen with probability proportional to power); the two
//! strategies for direct light (BSDF sampling finds emitters by chance, light sampling aims at
//! them) are combined with the power heuristic. Russian roulette ends paths of low throughput
//! `β` from `rr_depth` on, with survival probability `q = min(max(β) η², 0.95)` and `β /= q`,
//! which keeps the estimator unbiased (η: product of the relative IORs crossed, which undoes the
//! η² radiance scaling of refraction).
//!
//! `max_depth` has Mitsuba's meaning: the longest path has `max_depth` segments. 1: only
//! emitters seen directly; 2: direct illumination; -1: unlimited.
//!
//! Parameters (Mitsuba): `max_depth` (default -1), `rr_depth` (5), `hide_emitters` (false).

use super::trace::{self, Mis, PathSettings, PrevVertex};
use super::{Integrator, RadianceSample};
use crate::light::LightSampleContext;
use crate::material::{Bsdf, BsdfContext, TextureMemo};
use crate::math::{Frame, Ray, Rgb, Vec3};
use crate::sampling::{sample_cosine_hemisphere_malley, sample_uniform_hemisphere, sample_uniform_sphere, Sampler};
use crate::scene::{HitSlot, Scene};

pub use super::trace::MisHeuristic;

/// How direct light is estimated at each vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DirectStrategy {
    /// Light sampling and BSDF sampling combined by MIS (power heuristic by default).
    #[default]
    Mis,
    /// Light (emitter area) sampling only: emitters hit by BSDF-sampled rays after a
    /// non-specular bounce do not count.
    Light,
    /// BSDF sampling only (no next-event estimation).
    Bsdf,
    /// A direction sampled uniformly over the hemisphere (pdf `1/2π`; the sphere, `1/4π`, for
    /// BSDFs that transmit) and traced to whatever emitter it hits; emitters hit by the path's
    /// own BSDF-sampled rays do not count. The lecture's first estimator of direct light.
    Uniform,
    /// As `Uniform` but cosine-weighted (pdf `cos θ / π`, Malley's method; `|cos θ| / 2π` over
    /// the sphere for BSDFs that transmit).
    Cosine,
}

/// Unidirectional path tracer.
#[derive(Clone, Debug, Default)]
pub struct PathIntegrator {
    /// `max_depth`, `rr_depth`, `hide_emitters`.
    pub settings: PathSettings,
    /// Direct-light strategy.
    pub strategy: DirectStrategy,
    /// MIS heuristic (used by the `Mis` strategy).
    pub heuristic: MisHeuristic,
    /// pbrt-v4's path regularization (`regularize`, false): after the path's first
    /// non-specular bounce its BSDFs are seen widened ([`Bsdf::regularized`]). Biased.
    pub regularize: bool,
}

crate::choices!(DirectStrategy, "direct-light strategy", {
    DirectStrategy::Mis => "mis", "light sampling and BSDF sampling, combined by MIS (power heuristic by default)";
    DirectStrategy::Light => "light", "light (emitter) sampling only";
    DirectStrategy::Bsdf => "bsdf", "BSDF sampling only";
    DirectStrategy::Uniform => "uniform", "uniform hemisphere sampling of directions, traced to emitters";
    DirectStrategy::Cosine => "cosine", "cosine-weighted hemisphere sampling of directions, traced to emitters";
});

impl PathIntegrator {
    /// The default path tracer with at most `max_depth` segments (-1: unlimited).
    pub fn with_max_depth(max_depth: i32) -> PathIntegrator {
        PathIntegrator { settings: PathSettings { max_depth, ..Default::default() }, ..Default::default() }
    }

    /// How light and BSDF sampling share direct light under this strategy (for the direction
    /// strategies, emitters found by the path's own BSDF samples do not count either).
    fn mis(&self) -> Mis {
        match self.strategy {
            DirectStrategy::Mis => Mis::Combine { heuristic: self.heuristic, n_light: 1, n_bsdf: 1 },
            DirectStrategy::Light | DirectStrategy::Uniform | DirectStrategy::Cosine => Mis::LightOnly,
            DirectStrategy::Bsdf => Mis::BsdfOnly,
        }
    }

    /// Direct light at a vertex by sampling a direction independently of lights and BSDF
    /// (uniform or cosine-weighted about the shading normal, on `wo`'s side, or over the whole
    /// sphere for BSDFs that transmit) and tracing it to an emitter.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn direct_by_direction(
        &self,
        scene: &Scene,
        si: &crate::geometry::SurfaceInteraction,
        frame: &Frame,
        bsdf: &Bsdf,
        ctx: &BsdfContext,
        wo_local: Vec3,
        u: crate::math::Vec2,
    ) -> Rgb {
        let (mut w, mut pdf) = if bsdf.transmits() {
            match self.strategy {
                DirectStrategy::Uniform => {
                    let s = sample_uniform_sphere(u);
                    (s.value, s.pdf)
                }
                _ => {
                    // Cosine-weighted on a random side: reuse u.x to choose it.
                    let (side, ux) = if u.x < 0.5 { (1.0, 2.0 * u.x) } else { (-1.0, 2.0 * u.x - 1.0) };
                    let s = sample_cosine_hemisphere_malley(crate::math::Vec2::new(ux.min(0.999_999_9), u.y));
                    (Vec3::new(s.value.x, s.value.y, side * s.value.z), 0.5 * s.pdf)
                }
            }
        } else {
            let s = match self.strategy {
                DirectStrategy::Uniform => sample_uniform_hemisphere(u),
                _ => sample_cosine_hemisphere_malley(u),
            };
            let side = if wo_local.z < 0.0 { -1.0 } else { 1.0 };
            (Vec3::new(s.value.x, s.value.y, side * s.value.z), s.pdf)
        };
        if pdf <= 0.0 {
            return Rgb::ZERO;
        }
        let f = bsdf.eval(ctx, wo_local, w);
        if f == Rgb::ZERO {
            return Rgb::ZERO;
        }
        w = frame.to_world(w).normalize();
        let le = match scene.intersect_deferred(&si.spawn_ray(w), &mut HitSlot::default()) {
            Some(hit) => match hit.light() {
                Some(i) => {
                    let hit = hit.interaction();
                    scene.lights()[i as usize].le(hit.ns, -w, hit.uv)
                }
                None => Rgb::ZERO,
            },
            None => scene.infinite_lights().iter().map(|&i| scene.lights()[i as usize].le_escaped(si.p, w)).sum(),
        };
        pdf = pdf.max(f32::MIN_POSITIVE);
        f * le / pdf
    }

    /// One sample of the radiance along `camera_ray`, handing each contribution to `record`
    /// with the number of path segments it took (`k`: the term `Tᵏ⁻¹ Lₑ` of the Neumann
    /// series, k = 1 for emitters seen directly). [`Integrator::sample`] sums them in order.
    /// Returns the sample's coverage (Mitsuba 3.9.1's `valid_ray`): whether the path went on
    /// from a surface by a BSDF sample other than a null crossing.
    #[inline]
    pub fn trace(
        &self,
        scene: &Scene,
        camera_ray: &Ray,
        sampler: &mut Sampler,
        mut record: impl FnMut(u32, Rgb),
    ) -> bool {
        let max_depth = self.settings.max_segments();
        if max_depth == 0 {
            return scene.intersect_deferred(camera_ray, &mut HitSlot::default()).is_some();
        }
        // Whether every vertex the path went on from so far was a null crossing (a `null`
        // surface, a mask's cut-out): camera rays see through those, so with `hide_emitters` the
        // environment they reach stays hidden as if seen directly (Mitsuba 3.9.1's `path`;
        // emitting shapes behind them show, as there). Its negation is the sample's coverage,
        // Mitsuba's `valid_ray`: set at the first vertex the path goes on from by a BSDF sample
        // that is not a null crossing.
        let mut null_only = true;
        let hide = self.settings.hide_emitters;
        let mis = self.mis();
        let mut beta = Rgb::ONE;
        let mut ray = *camera_ray;
        let mut prev: Option<PrevVertex> = None;
        let mut depth = 0u32;
        // Product of the relative IORs crossed: radiance scales by η² at refractions, which
        // Russian roulette must not mistake for a loss of throughput (Mitsuba's rule).
        let mut eta = 1.0f32;
        // Whether the path went on from a vertex by a non-delta BSDF sample (pbrt-v4's
        // `anyNonSpecularBounces`, which starts regularization).
        let mut non_specular = false;
        // Where each closest-hit query leaves its hit.
        let mut slot = HitSlot::default();
        loop {
            // Escaped: environment light, MIS-weighted like any emitter found by BSDF sampling
            // (hidden, where asked, from camera rays that crossed null surfaces only).
            let escape = |ray: &Ray, record: &mut dyn FnMut(u32, Rgb)| {
                if !(hide && null_only) {
                    let d = ray.d.normalize();
                    trace::escaped(scene, ray.o, d, prev.as_ref(), hide, &mis, |le, w| {
                        record(depth + 1, beta * le * w)
                    });
                }
            };
            // The surface interaction is bound where it is made (not moved out of an `Option`:
            // a copy of it right after the call that wrote it field by field would wait for
            // those stores to reach the cache).
            let si = if depth == 0 && hide {
                // Hidden emitters are invisible to camera rays (Mitsuba 3): the ray passes through.
                match trace::skip_hidden_emitters(scene, &mut ray, &mut slot) {
                    Some(hit) => hit.interaction(),
                    None => {
                        escape(&ray, &mut record);
                        break;
                    }
                }
            } else {
                match scene.intersect_deferred(&ray, &mut slot) {
                    None => {
                        escape(&ray, &mut record);
                        break;
                    }
                    Some(hit) => {
                        // At the path's last vertex only emission counts: the surface
                        // interaction of a shape that does not emit is not needed.
                        if depth + 1 >= max_depth && hit.light().is_none() {
                            break;
                        }
                        hit.interaction()
                    }
                }
            };
            let wo = -ray.d.normalize();
            let shape = scene.shapes()[si.shape as usize];

            // Emission found by the path itself.
            if let Some(light_index) = shape.light {
                let le = scene.lights()[light_index as usize].le(si.ns, wo, si.uv);
                if le != Rgb::ZERO {
                    let weight = trace::emission_weight(prev.as_ref(), hide, &mis, |c| {
                        trace::light_pdf_at(scene, c, light_index, si.p, si.ng)
                    });
                    record(depth + 1, beta * le * weight);
                }
            }
            if depth + 1 >= max_depth {
                break;
            }

            let bsdf = if self.regularize && non_specular {
                &scene.regularized_bsdfs()[shape.bsdf as usize]
            } else {
                &scene.bsdfs()[shape.bsdf as usize]
            };
            // Textures and normal maps looked up once for this vertex's BSDF calls.
            let memo = TextureMemo::default();
            let vertex = trace::SurfaceVertex::new(scene, &si, bsdf, &memo, wo);
            let (ctx, frame, wo_local) = (&vertex.ctx, vertex.frame, vertex.wo_local);
            let light_ctx = LightSampleContext { p: si.p, n: si.ns };

            // Direct light (its random numbers are drawn whether used or not, so that every
            // vertex consumes the same sampler dimensions), then the BSDF sample that continues
            // the path. The BSDF is sampled before the direct-light estimate although it is used
            // after it: the two are independent, and next to each other in program order the
            // processor overlaps their chains of dependent divisions and square roots.
            let u_light = sampler.next_1d();
            let u_light2 = sampler.next_2d();
            let u_bsdf = sampler.next_1d();
            let u_bsdf2 = sampler.next_2d();
            let bs = bsdf.sample(ctx, wo_local, u_bsdf, u_bsdf2);
            if !bsdf.is_delta() {
                let c = match self.strategy {
                    DirectStrategy::Bsdf => Rgb::ZERO,
                    DirectStrategy::Uniform | DirectStrategy::Cosine => {
                        self.direct_by_direction(scene, &si, &frame, bsdf, ctx, wo_local, u_light2)
                    }
                    DirectStrategy::Mis | DirectStrategy::Light => trace::sample_direct_bsdf(
                        scene,
                        &light_ctx,
                        (u_light, u_light2),
                        &mis,
                        &vertex,
                        trace::occlusion(scene, &si),
                    ),
                };
                if c != Rgb::ZERO {
                    record(depth + 2, beta * c);
                }
            }

            // Continue the path by BSDF sampling.
            null_only &= bs.as_ref().is_some_and(|b| b.null);
            let Some(bs) = bs else { break };
            non_specular |= !bs.delta;
            beta *= bs.weight;
            eta *= bs.eta;
            let wi = frame.to_world(bs.wi);
            prev = Some(PrevVertex { ctx: light_ctx, pdf: bs.pdf, delta: bs.delta });
            ray = si.spawn_ray(wi);
            depth += 1;

            // Russian roulette.
            if !super::russian_roulette(&mut beta, eta, depth, self.settings.rr_depth, sampler.next_1d()) {
                break;
            }
        }
        !null_only
    }
}

impl Integrator for PathIntegrator {
    fn name(&self) -> &'static str {
        "path"
    }

    #[inline]
    fn sample(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler, terms: &mut [Rgb]) -> RadianceSample {
        let mut l = Rgb::ZERO;
        let covered = if terms.is_empty() {
            self.trace(scene, camera_ray, sampler, |_, c| l += c)
        } else {
            let last = terms.len() - 1;
            self.trace(scene, camera_ray, sampler, |k, c| {
                l += c;
                terms[(k as usize - 1).min(last)] += c;
            })
        };
        RadianceSample { l, alpha: super::trace::coverage(scene, covered, self.settings.hide_emitters) }
    }

    fn has_terms(&self) -> bool {
        true
    }

    fn lanes(&self, scene: &Scene) -> usize {
        if self.lane_support(scene) {
            super::path_lanes::lane_width()
        } else {
            0
        }
    }

    fn sample_lanes(&self, scene: &Scene, rays: &[Ray], samplers: &mut [Sampler], out: &mut [RadianceSample]) {
        super::path_lanes::trace_lanes_dispatch(self, scene, rays, samplers, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, FovAxis};
    use crate::geometry::{Geometry, Sphere, TriangleMesh};
    use crate::material::{Bsdf, Diffuse};
    use crate::math::Transform;
    use crate::render::{render, RenderSettings};
    use crate::sampling::sampler::SamplerKind;
    use crate::scene::SceneBuilder;
    use std::sync::atomic::AtomicBool;

    /// Image mean and its standard error.
    fn image_mean(film: &crate::film::Film) -> (f64, f64) {
        film.mean_and_std_error()
    }

    /// A point light of intensity I at the centre of a closed diffuse sphere (albedo ρ, radius
    /// r, normals inward), seen from the centre. Direct irradiance at the wall is I / r², so the
    /// once-scattered radiance is `L₁ = ρ I / (π r²)`. Every further bounce scatters the
    /// (uniform) wall radiance once more over a sphere whose interior form factor to itself is
    /// 1, multiplying by ρ: `L = L₁ Σ_{k≥0} ρᵏ = ρ I / (π r² (1 - ρ))`. A path of at most D
    /// segments carries the terms k ≤ D - 2.
    #[test]
    fn point_light_in_closed_sphere_matches_geometric_series() {
        let (rho, intensity, r) = (0.6f32, 5.0f32, 2.0f32);
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(rho))));
        let c = Vec3::new(0.3, -0.2, 1.0);
        b.add_shape(Geometry::Sphere(Sphere::new(c, r, true)), m, None);
        b.add_point_light(c, Rgb::splat(intensity));
        let to_world = Transform::look_at(c, c + Vec3::new(0.2, 0.1, 1.0), Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 100.0, FovAxis::X, 16, 12).unwrap());
        let scene = b.build().unwrap();
        let l1 = (rho * intensity / (std::f32::consts::PI * r * r)) as f64;
        for (max_depth, spp) in [(1, 4), (2, 4), (3, 64), (5, 64), (-1, 256)] {
            let expected = match max_depth {
                -1 => l1 / (1.0 - rho as f64),
                d => (0..(d - 1).max(0)).map(|k| l1 * (rho as f64).powi(k)).sum(),
            };
            let integrator = PathIntegrator::with_max_depth(max_depth);
            let settings = RenderSettings { spp, seed: 3, ..Default::default() };
            let out = render(&scene, &integrator, &settings, &AtomicBool::new(false)).unwrap();
            let (mean, se) = image_mean(&out.film);
            let tol = 3.0 * se + 1e-5 * expected.max(1.0);
            assert!((mean - expected).abs() <= tol, "max_depth {max_depth}: {mean} vs {expected} (±{tol})");
            if max_depth == -1 {
                assert!(se < 0.02 * expected, "test too noisy to detect bias: se {se}");
            }
        }
    }

    /// Form factor from a differential area to a parallel rectangle `a × b` at distance `h`
    /// whose corner lies on the element's normal.
    fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
        let (x, y) = (a / h, b / h);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
    }

    /// Direct light on a diffuse floor from a small parallel rectangular emitter overhead:
    /// `E = π Lₑ F`, reflected radiance `ρ Lₑ F`, with F the form factor of the rectangle seen
    /// from the point below its centre (four corner form factors). Every direct-light strategy
    /// must match it within 3σ.
    #[test]
    fn direct_light_from_parallel_rectangle() {
        let (rho, le, h, a, bb) = (0.7f32, 3.0f32, 1.5f32, 0.4f32, 0.25f32);
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(rho))));
        let mut floor = TriangleMesh::rectangle();
        floor.transform(&(Transform::rotate(Vec3::X, -90.0).unwrap() * Transform::scale(Vec3::splat(10.0)).unwrap()));
        b.add_shape(Geometry::Mesh(floor), m, None);
        let mut light = TriangleMesh::rectangle();
        light.transform(
            &(Transform::translate(Vec3::new(0.0, h, 0.0))
                * Transform::rotate(Vec3::X, 90.0).unwrap()
                * Transform::scale(Vec3::new(a, bb, 1.0)).unwrap()),
        );
        b.add_shape(Geometry::Mesh(light), m, Some(Rgb::splat(le)));
        b.set_camera(Camera::perspective(Transform::IDENTITY, 30.0, FovAxis::X, 1, 1).unwrap());
        let scene = b.build().unwrap();
        let f = 4.0 * corner_form_factor(a as f64, bb as f64, h as f64);
        let expected = rho as f64 * le as f64 * f;
        // A camera ray grazing under the light onto the floor point below its centre.
        let o = Vec3::new(0.0, 0.5, -4.0);
        let ray = Ray::new(o, (Vec3::ZERO - o).normalize());
        for (k, strategy) in [DirectStrategy::Mis, DirectStrategy::Light, DirectStrategy::Bsdf].into_iter().enumerate()
        {
            let integrator = PathIntegrator {
                settings: PathSettings { max_depth: 2, ..Default::default() },
                strategy,
                ..Default::default()
            };
            let mut sampler = SamplerKind::Independent.make(1, k as u64);
            let n = if strategy == DirectStrategy::Bsdf { 400_000 } else { 50_000 };
            let values: Vec<f64> = (0..n)
                .map(|i| {
                    sampler.start_pixel_sample([0, 0], i, 0);
                    integrator.li(&scene, &ray, &mut sampler).x as f64
                })
                .collect();
            let est = crate::estimators::Estimate::from_values(values);
            let tol = 3.0 * est.std_error() + 1e-6;
            assert!((est.value - expected).abs() <= tol, "{strategy:?}: {} vs {expected} (±{tol})", est.value);
            assert!(est.std_error() < 0.01 * expected, "{strategy:?} too noisy to detect bias");
        }
    }

    /// Light-only and BSDF-only direct lighting give the same Cornell box image mean as MIS.
    #[test]
    fn strategies_agree_on_the_cornell_box() {
        let scene = crate::scene::cornell::cornell_box(24, 24).unwrap();
        let mut means = Vec::new();
        let cases = [
            (DirectStrategy::Mis, MisHeuristic::Power, 256),
            (DirectStrategy::Mis, MisHeuristic::Balance, 256),
            (DirectStrategy::Light, MisHeuristic::Power, 256),
            (DirectStrategy::Bsdf, MisHeuristic::Power, 1024),
            (DirectStrategy::Cosine, MisHeuristic::Power, 1024),
            (DirectStrategy::Uniform, MisHeuristic::Power, 1024),
        ];
        for (k, (strategy, heuristic, spp)) in cases.into_iter().enumerate() {
            let integrator =
                PathIntegrator { settings: PathSettings { max_depth: 6, ..Default::default() }, strategy, heuristic, regularize: false };
            let settings = RenderSettings { spp, seed: 100 + k as u64, ..Default::default() };
            let out = render(&scene, &integrator, &settings, &AtomicBool::new(false)).unwrap();
            means.push((strategy, heuristic, image_mean(&out.film)));
        }
        let (_, _, (m0, s0)) = means[0];
        assert!(s0 < 0.01 * m0, "MIS estimate too noisy: {s0} of {m0}");
        for &(strategy, heuristic, (m, s)) in &means[1..] {
            let tol = 3.0 * (s0 * s0 + s * s).sqrt();
            assert!((m - m0).abs() <= tol, "{strategy:?}/{heuristic:?}: {m} vs MIS {m0} (±{tol})");
        }
    }

    /// Direct light on a diffuse floor from a small square light: every strategy is unbiased,
    /// and their variances rank as theory says — light sampling aims at the light, cosine
    /// sampling at least follows the cosine, uniform sampling follows nothing — with margin.
    #[test]
    fn direct_strategies_rank_by_variance_on_a_small_light() {
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.7))));
        let mut floor = TriangleMesh::rectangle();
        floor.transform(&(Transform::rotate(Vec3::X, -90.0).unwrap() * Transform::scale(Vec3::splat(3.0)).unwrap()));
        b.add_shape(Geometry::Mesh(floor), m, None);
        let mut light = TriangleMesh::rectangle();
        light.transform(
            &(Transform::translate(Vec3::new(0.0, 1.5, 0.0))
                * Transform::rotate(Vec3::X, 90.0).unwrap()
                * Transform::scale(Vec3::splat(0.15)).unwrap()),
        );
        b.add_shape(Geometry::Mesh(light), m, Some(Rgb::splat(20.0)));
        let to_world = Transform::look_at(Vec3::new(0.0, 2.5, 3.0), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 40.0, FovAxis::X, 12, 12).unwrap());
        let scene = b.build().unwrap();
        let mut results = Vec::new();
        for (k, strategy) in
            [DirectStrategy::Light, DirectStrategy::Cosine, DirectStrategy::Uniform].into_iter().enumerate()
        {
            let integrator = PathIntegrator {
                settings: PathSettings { max_depth: 2, hide_emitters: true, ..Default::default() },
                strategy,
                ..Default::default()
            };
            let settings = RenderSettings { spp: 2048, seed: 7 + k as u64, ..Default::default() };
            let out = render(&scene, &integrator, &settings, &AtomicBool::new(false)).unwrap();
            let var = out.film.variance_of_mean();
            // Per-sample variance, averaged over pixels and channels.
            let v = var.iter().map(|c| (c.x + c.y + c.z) as f64).sum::<f64>() / (3 * var.len()) as f64 * 2048.0;
            results.push((strategy, image_mean(&out.film), v));
        }
        let (_, (m0, s0), _) = results[0];
        for &(strategy, (m, s), _) in &results[1..] {
            let tol = 3.0 * (s0 * s0 + s * s).sqrt();
            assert!((m - m0).abs() <= tol, "{strategy:?}: {m} vs light sampling {m0} (±{tol})");
        }
        let (vl, vc, vu) = (results[0].2, results[1].2, results[2].2);
        println!("per-sample variance: light {vl:.4e}, cosine {vc:.4e}, uniform {vu:.4e}");
        assert!(vl * 100.0 < vc && vc * 1.3 < vu, "variances light {vl}, cosine {vc}, uniform {vu}");
    }

    /// White furnace: a sphere inside a constant environment of radiance 1, filling the view.
    /// A diffuse sphere of albedo a shows exactly a (it sees only the environment) for any
    /// max_depth ≥ 2; lossless glass and a perfect mirror show 1 (energy conservation).
    #[test]
    fn white_furnace() {
        use crate::material::{Conductor, Dielectric};
        let cases: Vec<(&str, Bsdf, i32, f64)> = vec![
            ("diffuse, direct only", Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))), 2, 0.5),
            ("diffuse", Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))), -1, 0.5),
            ("mirror", Bsdf::Conductor(Conductor { ior: None, specular_reflectance: Rgb::ONE.into() }), -1, 1.0),
            (
                "glass",
                Bsdf::Dielectric(Dielectric {
                    eta: 1.5,
                    specular_reflectance: Rgb::ONE.into(),
                    specular_transmittance: Rgb::ONE.into(),
                }),
                -1,
                1.0,
            ),
        ];
        for (k, (name, bsdf, max_depth, expected)) in cases.into_iter().enumerate() {
            let mut b = SceneBuilder::new();
            let m = b.add_bsdf(bsdf);
            b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), m, None);
            b.add_constant_environment(Rgb::ONE);
            let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y).unwrap();
            b.set_camera(Camera::perspective(to_world, 10.0, FovAxis::X, 12, 12).unwrap());
            let scene = b.build().unwrap();
            let integrator = PathIntegrator::with_max_depth(max_depth);
            let settings = RenderSettings { spp: 64, seed: 10 + k as u64, ..Default::default() };
            let out = render(&scene, &integrator, &settings, &AtomicBool::new(false)).unwrap();
            let (mean, se) = image_mean(&out.film);
            assert!((mean - expected).abs() <= 3.0 * se + 1e-4, "{name}: {mean} vs {expected} (±{se})");
            assert!(se < 0.01, "{name}: too noisy ({se})");
        }
    }

    /// `hide_emitters` (Mitsuba 3): a camera ray passes through an emitting sphere and sees what
    /// is behind it: the Lambertian floor under the sphere, whose radiance (lit by a sun and by
    /// the sphere) is the same seen from a direction that misses the sphere. Without hiding the
    /// camera sees the sphere's radiance.
    #[test]
    fn hidden_emitters_are_transparent_to_camera_rays() {
        use crate::light::Light;
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        let mut floor = TriangleMesh::rectangle();
        floor.transform(&(Transform::rotate(Vec3::X, -90.0).unwrap() * Transform::scale(Vec3::splat(10.0)).unwrap()));
        b.add_shape(Geometry::Mesh(floor), m, None);
        let black = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::ZERO)));
        let sphere = Sphere::new(Vec3::new(0.0, 0.5, -0.5), 0.2, false);
        b.add_shape(Geometry::Sphere(sphere), black, Some(Rgb::splat(7.0)));
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        b.add_light(Light::Directional { direction: d, irradiance: Rgb::ONE, center: Vec3::ZERO, radius: 0.0 });
        b.set_camera(Camera::perspective(Transform::IDENTITY, 30.0, FovAxis::X, 1, 1).unwrap());
        let scene = b.build().unwrap();
        // Mean over many samples of the radiance along a ray from `o` to the floor's origin.
        let radiance = |o: Vec3, hide: bool, direct: bool| {
            let ray = Ray::new(o, (Vec3::ZERO - o).normalize());
            let path = PathIntegrator {
                settings: PathSettings { max_depth: 2, hide_emitters: hide, ..Default::default() },
                ..Default::default()
            };
            let dir = super::super::DirectIntegrator { hide_emitters: hide, ..Default::default() };
            let mut sampler = SamplerKind::Independent.make(4096, 0);
            let n = 4096;
            (0..n)
                .map(|i| {
                    sampler.start_pixel_sample([0, 0], i, 0);
                    (if direct { dir.li(&scene, &ray, &mut sampler) } else { path.li(&scene, &ray, &mut sampler) }).x
                        as f64
                })
                .sum::<f64>()
                / n as f64
        };
        let through_sphere = Vec3::new(0.0, 1.0, -1.0);
        let clear = Vec3::new(0.0, 1.0, 1.0);
        for direct in [false, true] {
            let seen = radiance(clear, false, direct);
            let hidden = radiance(through_sphere, true, direct);
            assert!((hidden - seen).abs() < 0.01 * seen, "direct={direct}: hidden {hidden} vs floor {seen}");
            assert_eq!(radiance(through_sphere, false, direct), 7.0);
        }
    }

    /// Null surfaces are crossed as Mitsuba 3.9.1's `path` crosses them: behind a `null`
    /// sphere (two crossings) a white sky hidden from the camera stays hidden, and a sample is
    /// covered (alpha) only where the path goes on from a surface by a sample that is not a
    /// null crossing — behind the sphere, a diffuse wall with `max_depth` 4 (crossing, crossing,
    /// wall, on), not 3 (the wall is the last vertex). Measured against Mitsuba: the same rgb
    /// and alpha in all four cases.
    #[test]
    fn null_crossings_hide_what_the_camera_does_not_see_and_cover_nothing() {
        use crate::integrator::fixtures::{null_sphere_before_a_wall, sample_toward};
        let scene = null_sphere_before_a_wall();
        let sample = |hide: bool, max_depth: i32, target: Vec3| {
            let settings = PathSettings { max_depth, hide_emitters: hide, ..Default::default() };
            sample_toward(&scene, &PathIntegrator { settings, ..Default::default() }, target)
        };
        let sky = Vec3::new(0.0, 0.6, 0.0);
        let hidden = sample(true, 4, sky);
        assert_eq!((hidden.l, hidden.alpha), (Rgb::ZERO, 0.0));
        let seen = sample(false, 4, sky);
        assert_eq!((seen.l, seen.alpha), (Rgb::ONE, 1.0));
        let at_wall = Vec3::new(0.0, 0.0, -2.0);
        assert_eq!(sample(true, 3, at_wall).alpha, 0.0);
        assert_eq!(sample(true, 4, at_wall).alpha, 1.0);
    }

    /// Directional and spot lights on a diffuse floor, direct light only: the reflected
    /// radiance is `ρ/π E` with `E = E⊥ cos θ` (directional) or `I f(θ) cos θ / r²` (spot, with
    /// its falloff f); both are delta lights, so every sample gives the exact value.
    #[test]
    fn directional_and_spot_lights_on_a_floor() {
        use crate::light::Light;
        use crate::math::Frame;
        let rho = 0.6f32;
        let build = |light: Light| {
            let mut b = SceneBuilder::new();
            let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(rho))));
            let mut floor = TriangleMesh::rectangle();
            floor.transform(
                &(Transform::rotate(Vec3::X, -90.0).unwrap() * Transform::scale(Vec3::splat(10.0)).unwrap()),
            );
            b.add_shape(Geometry::Mesh(floor), m, None);
            b.add_light(light);
            b.set_camera(Camera::perspective(Transform::IDENTITY, 30.0, FovAxis::X, 1, 1).unwrap());
            b.build().unwrap()
        };
        let radiance_at = |scene: &crate::scene::Scene, x: f32| {
            let target = Vec3::new(x, 0.0, 0.0);
            let o = target + Vec3::new(0.0, 1.0, -1.0);
            let integrator = PathIntegrator::with_max_depth(2);
            let mut sampler = SamplerKind::Independent.make(1, 0);
            sampler.start_pixel_sample([0, 0], 0, 0);
            integrator.li(scene, &Ray::new(o, (target - o).normalize()), &mut sampler).x
        };
        let d = Vec3::new(0.3, -1.0, 0.2).normalize();
        let sun =
            build(Light::Directional { direction: d, irradiance: Rgb::splat(2.0), center: Vec3::ZERO, radius: 0.0 });
        let expected = rho / std::f32::consts::PI * 2.0 * -d.y;
        assert!((radiance_at(&sun, 0.0) - expected).abs() < 1e-5 * expected, "directional");

        let (cutoff, beam) = (30f32.to_radians(), 20f32.to_radians());
        let spot_of = |falloff| Light::Spot {
            position: Vec3::new(0.0, 2.0, 0.0),
            frame: Frame::from_z(-Vec3::Y),
            intensity: Rgb::splat(8.0),
            cutoff,
            beam,
            texture: None,
            falloff,
        };
        let spot = build(spot_of(crate::light::SpotFalloff::Linear));
        // pbrt-v4's spot: smoothstep in cos θ between the cutoff's and the beam's cosines.
        let pbrt_spot = build(spot_of(crate::light::SpotFalloff::SmoothStep));
        for theta_deg in [0.0f32, 10.0, 25.0, 35.0] {
            let theta = theta_deg.to_radians();
            let x = 2.0 * theta.tan();
            let r2 = 4.0 + x * x;
            let falloff = if theta <= beam {
                1.0
            } else if theta >= cutoff {
                0.0
            } else {
                (cutoff - theta) / (cutoff - beam)
            };
            let expected = rho / std::f32::consts::PI * 8.0 * falloff * theta.cos() / r2;
            let got = radiance_at(&spot, x);
            assert!((got - expected).abs() <= 1e-4 * expected.max(1e-3), "spot at {theta_deg}°: {got} vs {expected}");
            let t = ((theta.cos() - cutoff.cos()) / (beam.cos() - cutoff.cos())).clamp(0.0, 1.0);
            let expected = rho / std::f32::consts::PI * 8.0 * t * t * (3.0 - 2.0 * t) * theta.cos() / r2;
            let got = radiance_at(&pbrt_spot, x);
            assert!(
                (got - expected).abs() <= 1e-4 * expected.max(1e-3),
                "pbrt spot at {theta_deg}°: {got} vs {expected}"
            );
        }
    }

    /// A `mask` of opacity α over a diffuse ρ is a surface present with probability α: lit by
    /// a directional light of irradiance E at normal incidence it shows `α ρ E / π`, and where
    /// the camera sees past it, the black background. (Mitsuba 3.9.1's `path` shows α² ρ E / π
    /// under delta and area lights, measured — its `volpath`, `direct` and `ptracer` give α.)
    #[test]
    fn a_mask_reflects_in_proportion_to_its_opacity() {
        use crate::light::Light;
        let (alpha, rho, e) = (0.4f32, 0.6f32, 2.0f32);
        let mut b = SceneBuilder::new();
        let diffuse = std::sync::Arc::new(Bsdf::Diffuse(Diffuse::new(Rgb::splat(rho))));
        let m = b.add_bsdf(Bsdf::Mask { opacity: Rgb::splat(alpha).into(), bsdf: diffuse });
        let mut plane = TriangleMesh::rectangle();
        plane.transform(&Transform::scale(Vec3::splat(3.0)).unwrap());
        b.add_shape(Geometry::Mesh(plane), m, None);
        b.add_light(Light::Directional {
            direction: -Vec3::Z,
            irradiance: Rgb::splat(e),
            center: Vec3::ZERO,
            radius: 0.0,
        });
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 20.0, FovAxis::X, 8, 8).unwrap());
        let scene = b.build().unwrap();
        let expected = f64::from(alpha * rho * e / std::f32::consts::PI);
        for depth in [2, 5] {
            let out = render(
                &scene,
                &PathIntegrator::with_max_depth(depth),
                &RenderSettings { spp: 256, seed: 4, ..Default::default() },
                &AtomicBool::new(false),
            )
            .unwrap();
            let (mean, se) = image_mean(&out.film);
            assert!((mean - expected).abs() <= 4.0 * se + 1e-4, "depth {depth}: {mean} ± {se} vs {expected}");
        }
    }

    /// A blend of a diffuse ρ and a perfect mirror (weight w toward the mirror) under a uniform
    /// environment of radiance 1 reflects `(1 − w) ρ + w` whatever the path: each lobe keeps
    /// its own measure (the mirror's discrete probability is never mixed with the diffuse
    /// density). (Mitsuba 3.9.1's `blendbsdf` adds the smooth lobe's value and density at the
    /// mirror direction to the delta sample's and comes out at 0.690 for ρ = w = 0.5, where
    /// this is 0.75, measured.)
    #[test]
    fn a_blend_of_a_mirror_and_a_diffuse_surface_reflects_the_blended_albedo() {
        use crate::material::Conductor;
        let (rho, w) = (0.5f32, 0.5f32);
        let mut b = SceneBuilder::new();
        let diffuse = std::sync::Arc::new(Bsdf::Diffuse(Diffuse::new(Rgb::splat(rho))));
        let mirror =
            std::sync::Arc::new(Bsdf::Conductor(Conductor { ior: None, specular_reflectance: Rgb::ONE.into() }));
        let m = b.add_bsdf(Bsdf::Blend { weight: Rgb::splat(w).into(), bsdfs: [diffuse, mirror] });
        let mut plane = TriangleMesh::rectangle();
        plane.transform(&Transform::scale(Vec3::splat(3.0)).unwrap());
        b.add_shape(Geometry::Mesh(plane), m, None);
        b.add_constant_environment(Rgb::ONE);
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 20.0, FovAxis::X, 8, 8).unwrap());
        let scene = b.build().unwrap();
        let out = render(
            &scene,
            &PathIntegrator::with_max_depth(2),
            &RenderSettings { spp: 256, seed: 6, ..Default::default() },
            &AtomicBool::new(false),
        )
        .unwrap();
        let (mean, se) = image_mean(&out.film);
        let expected = f64::from((1.0 - w) * rho + w);
        assert!((mean - expected).abs() <= 4.0 * se + 1e-4, "{mean} ± {se} vs {expected}");
    }

    /// An environment map that is 1 everywhere lights a diffuse sphere exactly like the
    /// constant environment: the sphere shows its albedo (light sampling through the map's
    /// distribution, BSDF sampling through escaped rays, MIS between them).
    #[test]
    fn uniform_envmap_furnace() {
        use crate::light::{EnvMap, Light};
        use crate::load::image::Image;
        let image = Image { width: 8, height: 4, pixels: vec![Rgb::ONE; 32] };
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), m, None);
        let map = EnvMap::new(image, 1.0, Transform::rotate(Vec3::X, 30.0).unwrap()).unwrap();
        b.add_light(Light::EnvMap { map: Box::new(map), center: Vec3::ZERO, radius: 0.0 });
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 10.0, FovAxis::X, 10, 10).unwrap());
        let scene = b.build().unwrap();
        let out = render(
            &scene,
            &PathIntegrator::default(),
            &RenderSettings { spp: 64, seed: 1, ..Default::default() },
            &AtomicBool::new(false),
        )
        .unwrap();
        let (mean, se) = image_mean(&out.film);
        assert!((mean - 0.5).abs() <= 3.0 * se + 1e-4 && se < 0.01, "{mean} ± {se}");
    }

    /// Surface uv reaches textured BSDF parameters: a checkerboard floor under a vertical
    /// directional light shows `ρ/π E` with the ρ of the checker cell hit.
    #[test]
    fn textured_floor_follows_its_checkerboard() {
        use crate::light::Light;
        use crate::texture::Texture;
        let (rho0, rho1) = (Rgb::splat(0.8), Rgb::splat(0.2));
        let mut b = SceneBuilder::new();
        let checker = Texture::checkerboard(rho0, rho1, crate::math::Mat3::from_scale(crate::math::Vec2::splat(10.0)));
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse { reflectance: checker }));
        let mut floor = TriangleMesh::rectangle();
        floor.transform(&(Transform::rotate(Vec3::X, -90.0).unwrap() * Transform::scale(Vec3::splat(10.0)).unwrap()));
        b.add_shape(Geometry::Mesh(floor), m, None);
        b.add_light(Light::Directional {
            direction: -Vec3::Y,
            irradiance: Rgb::splat(3.0),
            center: Vec3::ZERO,
            radius: 0.0,
        });
        b.set_camera(Camera::perspective(Transform::IDENTITY, 30.0, FovAxis::X, 1, 1).unwrap());
        let scene = b.build().unwrap();
        let integrator = PathIntegrator::with_max_depth(2);
        // uv = ((X/10 + 1)/2, (1 - Z/10)/2); ×10 → cell parity from the fractional parts.
        for (x, rho) in [(0.5f32, rho0.x), (1.5, rho1.x), (2.5, rho0.x)] {
            let target = Vec3::new(x, 0.0, -0.5);
            let o = target + Vec3::new(0.0, 1.0, 1.0);
            let mut sampler = SamplerKind::Independent.make(1, 0);
            sampler.start_pixel_sample([0, 0], 0, 0);
            let l = integrator.li(&scene, &Ray::new(o, (target - o).normalize()), &mut sampler).x;
            let expected = rho / std::f32::consts::PI * 3.0;
            assert!((l - expected).abs() < 1e-4, "x = {x}: {l} vs {expected}");
        }
    }
}
