//! Volumetric path tracing with spectral and null-scattering MIS (Mitsuba's `volpathmis`,
//! after Miller, Georgiev and Jarosz 2019, "A null-scattering path integral formulation of
//! light transport"), here over the three RGB channels.
//!
//! Each path picks one channel `c` and tracks in it: tentative collisions at the rate of the
//! channel's majorant (homogeneous media: σₜ,c, every collision real; heterogeneous ones: the
//! scalar bound σ̄), each real with probability `σₜ,c / σ̄` (else null: the path goes straight
//! on). Instead of a throughput, the path carries for every pair (contributing channel j,
//! sampling channel k) the ratio `p_k / f_j` of the path's density had channel k been chosen to
//! its contribution in channel j ([`Ratios`]). A contribution in channel j is then
//! `f_j / mean_k p_k`: the balance heuristic over the channels (one-sample MIS), so every
//! channel's estimate stays unbiased however differently the channels attenuate.
//!
//! Next-event estimation and phase/BSDF sampling are combined the same way over whole paths: a
//! shadow ray is tracked through media with ratio tracking (each null collision multiplies
//! by σₙ), and the ratios of the unidirectional technique that would have produced the same path
//! (the phase or BSDF density times the probability of making each of those collisions null,
//! σₙ,k / σ̄) are kept beside it; emission found by phase or BSDF sampling is weighted against
//! the light-sampling density of the same path. The weight of either is
//! `f_j / mean_k (p_nee,k + p_uni,k)`.
//!
//! Tracking decisions draw from a per-path generator seeded from the sampler; directions,
//! light samples and Russian roulette from the sampler. Parameters (Mitsuba): `max_depth`,
//! `rr_depth` (5), `hide_emitters`. Rules shared with [`super::VolPathIntegrator`]: null
//! boundaries change the medium without counting as vertices; hidden emitters are passed
//! through by camera rays.

use super::trace::{self, PathSettings};
use super::volpath::{medium_after, null_transmission};
use super::{Integrator, RadianceSample};
use crate::geometry::interaction::SHADOW_EPSILON;
use crate::light::{LightSample, LightSampleContext};
use crate::material::TextureMemo;
use crate::math::float::offset_ray_origin;
use crate::math::{Ray, Rgb, Vec3};
use crate::medium::Medium;
use crate::sampling::{Pcg32, Sampler};
use crate::scene::Scene;

/// Crossings of null surfaces allowed along one segment (guards against degenerate geometry).
const MAX_NULL_CROSSINGS: u32 = 256;
/// Tentative collisions allowed along one segment (as [`crate::medium::heterogeneous::MAX_TRACKING_STEPS`]).
const MAX_COLLISIONS: u32 = crate::medium::heterogeneous::MAX_TRACKING_STEPS;

/// Mitsuba's `volpathmis`.
#[derive(Clone, Debug, Default)]
pub struct VolPathMisIntegrator {
    /// `max_depth`, `rr_depth`, `hide_emitters`.
    pub settings: PathSettings,
}

/// For each contributing channel j (row) and sampling channel k (column), the product of the
/// path's densities in channel k over its contributions in channel j.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ratios([[f32; 3]; 3]);

impl Ratios {
    /// An empty path.
    pub const ONE: Ratios = Ratios([[1.0; 3]; 3]);

    /// Multiplies in a factor of density `p` (per sampling channel) and contribution `f` (per
    /// contributing channel). A zero contribution, or one so small against its density that
    /// the ratio overflows, makes the ratio +∞ (`0/0` and `0 · ∞` too): the weight `f_j / mean_k
    /// p_k` is then 0, whichever technique it is combined with. (Mapping such ratios to 0
    /// instead, as if that technique could not make the path, gave a light sample whose BSDF
    /// value was denormal against its large light density the full weight of the BSDF
    /// technique's ratio: a glossy floor lighting a sphere from a small light came out 50×
    /// too bright.)
    #[inline]
    pub fn update(&mut self, p: Rgb, f: Rgb) {
        for j in 0..3 {
            for k in 0..3 {
                let r = p[k] / f[j] * self.0[j][k];
                self.0[j][k] = if r.is_nan() { f32::INFINITY } else { r };
            }
        }
    }

    /// [`Ratios::update`] with the same density and contribution in every channel.
    #[inline]
    pub fn update_scalar(&mut self, p: f32, f: Rgb) {
        self.update(Rgb::splat(p), f)
    }

    /// The path's weight per channel, `f_j / mean_k p_k` (0 where every ratio is 0, or one is
    /// +∞).
    #[inline]
    pub fn weight(&self) -> Rgb {
        self.combined_weight(&Ratios([[0.0; 3]; 3]))
    }

    /// The weight of a path that two techniques can sample, `f_j / mean_k (p_k + p'_k)`.
    #[inline]
    pub fn combined_weight(&self, other: &Ratios) -> Rgb {
        let mut w = Rgb::ZERO;
        for j in 0..3 {
            let sum: f32 = (0..3).map(|k| self.0[j][k] + other.0[j][k]).sum();
            w[j] = if sum == 0.0 || !sum.is_finite() { 0.0 } else { 3.0 / sum };
        }
        w
    }

    /// Whether every channel's weight is zero (the path carries nothing).
    #[inline]
    pub fn is_zero(&self) -> bool {
        self.weight() == Rgb::ZERO
    }
}

/// Where a shadow ray starts and how it reaches the light sample.
enum ShadowOrigin {
    /// From a point in a medium (no surface offset), at the path's time.
    Medium(Vec3, f32),
    /// From a surface interaction.
    Surface(crate::geometry::SurfaceInteraction),
}

/// One light sample's ratios: light sampling's (`nee`) and the unidirectional technique's
/// (`uni`) that would produce the same path, with the emitted radiance and the sample.
struct LightPath {
    nee: Ratios,
    uni: Ratios,
    li: Rgb,
    sample: LightSample,
}

/// Walks one medium segment `ray` (unit direction) of length `t_max` for a shadow ray,
/// multiplying the free-flight factors and every tentative collision into both techniques'
/// ratios; false when nothing can get through.
fn track_shadow(
    medium: &Medium,
    ray: &Ray,
    t_max: f32,
    channel: usize,
    rng: &mut Pcg32,
    nee: &mut Ratios,
    uni: &mut Ratios,
) -> bool {
    let mut o = ray.o;
    let mut remaining = t_max;
    for _ in 0..MAX_COLLISIONS {
        let seg = Ray::new(o, ray.d);
        let tent = medium.sample_tentative(&seg, remaining, channel, rng.next_f32());
        let (pdf, tr) = tent.pdf_and_transmittance();
        nee.update(pdf, tr);
        uni.update(pdf, tr);
        let Some(c) = tent.collision else { return !(nee.is_zero() && uni.is_zero()) };
        // The collision is null for ratio tracking; unidirectional sampling would have had to
        // make it null too.
        nee.update_scalar(1.0, c.sigma_n);
        uni.update(c.sigma_n / tent.majorant, c.sigma_n);
        if nee.is_zero() && uni.is_zero() {
            return false;
        }
        o = seg.at(c.t);
        remaining -= c.t;
    }
    false
}

impl VolPathMisIntegrator {
    /// Samples a light from `ctx` and tracks the shadow ray to it through media and null
    /// surfaces (starting in `medium`), from the path's ratios `path`.
    #[allow(clippy::too_many_arguments)]
    fn sample_light(
        &self,
        scene: &Scene,
        ctx: &LightSampleContext,
        origin: &ShadowOrigin,
        mut medium: Option<u32>,
        path: &Ratios,
        channel: usize,
        sampler: &mut Sampler,
        rng: &mut Pcg32,
    ) -> Option<LightPath> {
        let (u, u2) = (sampler.next_1d(), sampler.next_2d());
        let (index, pmf) = scene.sample_light(ctx, u)?;
        let light = &scene.lights()[index as usize];
        let ls = light.sample_li(scene.geometries(), ctx.p, u2)?;
        let p_light = if ls.delta { pmf } else { pmf * ls.pdf };
        if p_light.is_nan() || p_light <= 0.0 || ls.li == Rgb::ZERO {
            return None;
        }
        let (mut nee, mut uni) = (*path, *path);
        nee.update_scalar(p_light, Rgb::ONE);
        let mut ray = match origin {
            ShadowOrigin::Medium(p, time) => {
                let target = if ls.n == Vec3::ZERO { ls.p } else { offset_ray_origin(ls.p, ls.p_error, ls.n, *p - ls.p) };
                Ray::bounded(*p, target - *p, 1.0 - SHADOW_EPSILON).at_time(*time)
            }
            ShadowOrigin::Surface(si) => {
                medium = medium_after(scene, si.shape, si.ng, ls.wi, medium);
                si.spawn_ray_to(ls.p, ls.n, ls.p_error)
            }
        };
        let target = ray.at(1.0);
        for _ in 0..MAX_NULL_CROSSINGS {
            let length = ray.d.length();
            let hit = scene.intersect(&ray);
            if let Some(si) = &hit {
                // Null surfaces pass it on; a filter, a thin dielectric or a mask's transparent
                // part only a share T of it, which BSDF sampling would have chosen with
                // probability P (1 for `null` and filters).
                let (t, p) = null_transmission(scene, si, ray.d)?;
                if t != Rgb::ONE || p != 1.0 {
                    nee.update_scalar(1.0, t);
                    uni.update_scalar(p, t);
                }
            }
            if let Some(m) = medium {
                let t_end = hit.as_ref().map_or(ray.t_max.min(1.0), |si| si.t);
                let unit = Ray::new(ray.o, ray.d / length);
                if !track_shadow(&scene.media()[m as usize], &unit, length * t_end, channel, rng, &mut nee, &mut uni) {
                    return None;
                }
            }
            let Some(si) = &hit else { return Some(LightPath { nee, uni, li: ls.li, sample: ls }) };
            medium = medium_after(scene, si.shape, si.ng, ray.d, medium);
            let o = si.offset_origin(ray.d);
            ray = Ray::bounded(o, target - o, 1.0 - SHADOW_EPSILON).at_time(ray.time);
        }
        None
    }
}

impl Integrator for VolPathMisIntegrator {
    fn name(&self) -> &'static str {
        "volpathmis"
    }

    fn sample(&self, scene: &Scene, camera_ray: &Ray, sampler: &mut Sampler, _terms: &mut [Rgb]) -> RadianceSample {
        let max_depth = self.settings.max_segments();
        let hide = self.settings.hide_emitters;
        if max_depth == 0 {
            let hit = scene.intersect(camera_ray).is_some();
            return RadianceSample { l: Rgb::ZERO, alpha: trace::coverage(scene, hit, hide) };
        }
        let channel = ((sampler.next_1d() * 3.0) as usize).min(2);
        let mut rng = trace::path_rng(sampler);
        let media = scene.media();
        let mut l = Rgb::ZERO;
        let mut covered = false;
        let mut path = Ratios::ONE;
        // The ratios the light-sampling technique would have for the path up to its last real
        // vertex (reset there, then continued through null collisions with their ratio factor).
        let mut path_nee = Ratios::ONE;
        // Emission found along the path counts in full (camera rays, after specular bounces,
        // after medium vertices that do not sample emitters).
        let mut count_direct = !hide;
        let mut last: Option<LightSampleContext> = None;
        let mut eta = 1.0f32;
        let len = camera_ray.d.length();
        let mut ray = Ray::bounded(camera_ray.o, camera_ray.d / len, camera_ray.t_max * len).at_time(camera_ray.time);
        let mut medium = scene.camera_medium();
        let mut depth = 0u32;
        let mut crossings = 0u32;
        'path: loop {
            let hit = scene.intersect(&ray);
            let t_surface = hit.as_ref().map_or(f32::INFINITY, |si| si.t);

            // Tracking through the current medium up to the surface.
            if let Some(m) = medium {
                let medium_ref = &media[m as usize];
                // Light an emissive medium gives off along the segment (nothing otherwise),
                // weighted as everything the path up to here carries.
                let emitted = medium_ref.emitted(&ray, t_surface, &mut rng);
                if emitted != Rgb::ZERO {
                    l += path.weight() * emitted;
                }
                let mut travelled = 0.0f32;
                let mut scattered = None;
                for _ in 0..MAX_COLLISIONS {
                    let seg = Ray::new(ray.at(travelled), ray.d);
                    let tent = medium_ref.sample_tentative(&seg, t_surface - travelled, channel, rng.next_f32());
                    let (pdf, tr) = tent.pdf_and_transmittance();
                    path.update(pdf, tr);
                    path_nee.update(pdf, tr);
                    let Some(c) = tent.collision else { break };
                    let real = rng.next_f32() < c.sigma_t[channel] / tent.majorant[channel];
                    if !real {
                        path.update(c.sigma_n / tent.majorant, c.sigma_n);
                        path_nee.update_scalar(1.0, c.sigma_n);
                        travelled += c.t;
                        if path.is_zero() {
                            break 'path;
                        }
                        continue;
                    }
                    path.update(c.sigma_t / tent.majorant, c.sigma_s);
                    scattered = Some(seg.at(c.t));
                    break;
                }
                if let Some(p) = scattered {
                    depth += 1;
                    if depth >= max_depth || path.is_zero() {
                        break;
                    }
                    covered = true;
                    let wo = -ray.d;
                    let phase = &medium_ref.phase;
                    let ctx = LightSampleContext { p, n: Vec3::ZERO };
                    let nee = medium_ref.sample_emitters;
                    count_direct = !nee;
                    if nee {
                        let origin = ShadowOrigin::Medium(p, ray.time);
                        if let Some(mut lp) =
                            self.sample_light(scene, &ctx, &origin, medium, &path, channel, sampler, &mut rng)
                        {
                            let value = phase.eval(p, wo, lp.sample.wi);
                            lp.nee.update_scalar(1.0, Rgb::splat(value));
                            lp.uni.update_scalar(if lp.sample.delta { 0.0 } else { value }, Rgb::splat(value));
                            if !lp.sample.delta {
                                let q = self.survival(&path, value, Rgb::splat(value), eta, depth);
                                lp.uni.update_scalar(q, Rgb::ONE);
                            }
                            l += lp.nee.combined_weight(&lp.uni) * lp.li;
                        }
                    }
                    path_nee = path;
                    let s = phase.sample(p, wo, sampler.next_2d());
                    if s.pdf <= 0.0 {
                        break; // (degenerate SGGX flakes: no direction to scatter into)
                    }
                    path.update_scalar(s.pdf, Rgb::splat(s.pdf));
                    path_nee.update_scalar(1.0, Rgb::splat(s.pdf));
                    ray = Ray::new(p, s.value).at_time(ray.time);
                    last = Some(ctx);
                    crossings = 0;
                    if !self.roulette(&mut path, eta, depth, sampler) {
                        break;
                    }
                    continue;
                }
            }

            // Emission found by the path. (The interaction bound by reference: moved out of the
            // `Option` right after `intersect` wrote it, it would be copied by wide loads that
            // wait for those stores to reach the cache.)
            let Some(si) = &hit else {
                for &i in scene.infinite_lights() {
                    if depth == 0 && hide {
                        break;
                    }
                    let light = &scene.lights()[i as usize];
                    let le = light.le_escaped(ray.o, ray.d);
                    if le == Rgb::ZERO {
                        continue;
                    }
                    l += le * self.emission_weight(&path, &path_nee, count_direct || depth == 0, last.as_ref(), |c| {
                        scene.light_pmf(c, i) * light.pdf_li_direction(c.p, ray.d)
                    });
                }
                break;
            };
            let shape = scene.shapes()[si.shape as usize];
            let bsdf = &scene.bsdfs()[shape.bsdf as usize];
            let wo = -ray.d;
            let hidden = depth == 0 && hide && shape.light.is_some();
            if let Some(li) = shape.light.filter(|_| !hidden) {
                let le = scene.lights()[li as usize].le(si.ns, wo, si.uv);
                if le != Rgb::ZERO {
                    l += le * self.emission_weight(&path, &path_nee, count_direct || depth == 0, last.as_ref(), |c| {
                        trace::light_pdf_at(scene, c, li, si.p, si.ng)
                    });
                }
            }
            if bsdf.is_null() || hidden {
                crossings += 1;
                if crossings > MAX_NULL_CROSSINGS {
                    break;
                }
                if bsdf.is_null() {
                    // (`None`: a filter that lets nothing through.)
                    let Some((t, _)) = null_transmission(scene, si, ray.d) else { break };
                    if t != Rgb::ONE {
                        path.update_scalar(1.0, t);
                        path_nee.update_scalar(1.0, t);
                    }
                    medium = medium_after(scene, si.shape, si.ng, ray.d, medium);
                }
                ray = si.spawn_ray(ray.d);
                continue;
            }
            // At the last vertex only a crossing that does not scatter (a thin dielectric's
            // transmission, a mask's transparent part) can go on, as in Mitsuba.
            let at_last = depth + 1 >= max_depth;
            if at_last && !bsdf.may_pass() {
                covered = true;
                break;
            }
            let frame = si.frame();
            let wo_local = frame.to_local(wo);
            // Textures and normal maps looked up once for this vertex's BSDF calls.
            let memo = TextureMemo::default();
            let ctx = scene.bsdf_context(si).with_memo(&memo);
            let light_ctx = LightSampleContext { p: si.p, n: si.ns };
            if !bsdf.is_delta() && !at_last {
                let origin = ShadowOrigin::Surface(*si);
                if let Some(mut lp) =
                    self.sample_light(scene, &light_ctx, &origin, medium, &path, channel, sampler, &mut rng)
                {
                    let wi_local = frame.to_local(lp.sample.wi);
                    let (f, pdf) = if lp.sample.delta {
                        (bsdf.eval(&ctx, wo_local, wi_local), 0.0)
                    } else {
                        bsdf.eval_pdf(&ctx, wo_local, wi_local)
                    };
                    lp.nee.update_scalar(1.0, f);
                    lp.uni.update_scalar(pdf, f);
                    if pdf > 0.0 {
                        let eta_after = eta * bsdf.eta_crossed(wo_local, wi_local);
                        lp.uni.update_scalar(self.survival(&path, pdf, f, eta_after, depth + 1), Rgb::ONE);
                    }
                    l += lp.nee.combined_weight(&lp.uni) * lp.li;
                }
            }
            let (u_bsdf, u_bsdf2) = (sampler.next_1d(), sampler.next_2d());
            let bs = bsdf.sample(&ctx, wo_local, u_bsdf, u_bsdf2);
            // Coverage, Mitsuba 3.9.1's `valid_ray` in its volumetric path tracers: a surface
            // vertex whose sample is not a null crossing, the last one too (or a scattering in a
            // medium the path goes on from).
            covered |= !bs.as_ref().is_some_and(|b| b.null);
            let Some(bs) = bs else { break };
            if at_last && !bs.null {
                break;
            }
            let f = bs.weight * bs.pdf;
            if bs.null {
                // Crossed unscattered: as both techniques see the crossing, chosen with
                // probability P and carrying T, the ratio a shadow ray from the last vertex gets
                // here too (the same as the lobe's own unless a mask over a thin dielectric
                // offers two null lobes, which this averages).
                let (t, p) = bsdf.null_transmission(&ctx, wo_local.z).unwrap_or((f, bs.pdf));
                path.update_scalar(p, t);
                path_nee.update_scalar(1.0, t);
            } else {
                // A real vertex: light sampling from here starts from the path's densities.
                path_nee = path;
                path.update_scalar(bs.pdf, f);
                path_nee.update_scalar(1.0, f);
            }
            eta *= bs.eta;
            let wi = frame.to_world(bs.wi);
            medium = medium_after(scene, si.shape, si.ng, wi, medium);
            ray = si.spawn_ray(wi);
            if bs.null {
                // Passed straight through: not a bounce, and not the vertex MIS refers to (a
                // shadow ray from the last one crosses here with the same factor).
                crossings += 1;
                if crossings > MAX_NULL_CROSSINGS {
                    break;
                }
                continue;
            }
            count_direct = bs.delta;
            last = Some(light_ctx);
            depth += 1;
            crossings = 0;
            if !self.roulette(&mut path, eta, depth, sampler) {
                break;
            }
        }
        RadianceSample { l, alpha: trace::coverage(scene, covered, hide) }
    }
}

impl VolPathMisIntegrator {
    /// The weight of emission reached by the path: the path's own weight when it counts in
    /// full, else combined with light sampling from the last real vertex `last` (density
    /// `pdf_light(last)`, selection included).
    #[inline]
    fn emission_weight(
        &self,
        path: &Ratios,
        path_nee: &Ratios,
        count_direct: bool,
        last: Option<&LightSampleContext>,
        pdf_light: impl FnOnce(&LightSampleContext) -> f32,
    ) -> Rgb {
        match last {
            Some(c) if !count_direct => {
                let mut nee = *path_nee;
                nee.update_scalar(pdf_light(c), Rgb::ONE);
                path.combined_weight(&nee)
            }
            _ => path.weight(),
        }
    }

    /// The probability that a path continued in a light sample's direction (density `pdf`,
    /// contribution `f`; `eta` the index ratio after it, `depth` the path's depth after the
    /// vertex) survives the Russian roulette [`Self::roulette`] plays right after that sampling:
    /// the unidirectional technique reaches the light only through it, so light sampling weighs
    /// the same path with the same density (the roulette folds it into the path's densities on
    /// the other side; without it here, deep paths lost light: 0.9 % of a medium of albedo 0.99).
    fn survival(&self, path: &Ratios, pdf: f32, f: Rgb, eta: f32, depth: u32) -> f32 {
        if depth < self.settings.rr_depth {
            return 1.0;
        }
        let mut after = *path;
        after.update_scalar(pdf, f);
        self.survival_probability(&after, eta, depth)
    }

    /// The roulette's survival probability for a path with ratios `path` at `depth` segments
    /// (index ratio `eta`): 1 before `rr_depth`, then `min(max_j weight_j · η², 0.95)`; 0 for
    /// a path that carries nothing.
    #[inline]
    fn survival_probability(&self, path: &Ratios, eta: f32, depth: u32) -> f32 {
        if path.is_zero() {
            return 0.0;
        }
        if depth < self.settings.rr_depth {
            return 1.0;
        }
        let q = (path.weight().max_element() * eta * eta).min(0.95);
        if q.is_nan() {
            0.0
        } else {
            q.max(0.0)
        }
    }

    /// Russian roulette from `rr_depth` segments on, with survival probability
    /// `min(max_j weight_j · η², 0.95)` folded into the path's densities; false when the
    /// path ends.
    #[inline]
    fn roulette(&self, path: &mut Ratios, eta: f32, depth: u32, sampler: &mut Sampler) -> bool {
        let u = sampler.next_1d();
        let q = self.survival_probability(path, eta, depth);
        if u >= q {
            return false;
        }
        if q < 1.0 {
            path.update_scalar(q, Rgb::ONE);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Bsdf;
    use crate::camera::{Camera, FovAxis};
    use crate::geometry::{Geometry, Sphere, TriangleMesh};
    use crate::image::GridVolume;
    use crate::math::Transform;
    use crate::medium::volume::{GridFilter, GridWrap, Volume};
    use crate::medium::{Coefficients, Heterogeneous, PhaseFunction};
    use crate::render::{render, RenderSettings};
    use crate::scene::SceneBuilder;
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;

    /// A chromatic heterogeneous cube (a three-channel grid) and a chromatic homogeneous sphere
    /// behind null boundaries, and either a uniform sky (`lit` false) or a diffuse floor, a
    /// sphere light and a dim sky; both media have albedo `albedo`.
    fn scene(albedo: Rgb, lit: bool) -> crate::scene::Scene {
        let n = 5;
        let data: Vec<f32> = (0..n * n * n * 3).map(|i| 1.6 + 1.4 * ((i as f32) * 0.37).sin()).collect();
        let grid = Arc::new(GridVolume { res: [n; 3], channels: 3, bbox: [[0.0; 3], [1.0; 3]], data });
        let to_world = Transform::translate(Vec3::new(-2.0, -1.0, -1.0)) * Transform::scale(Vec3::splat(2.0)).unwrap();
        let sigma = Volume::grid(grid, GridFilter::Trilinear, GridWrap::Clamp, to_world).unwrap();
        let mut b = SceneBuilder::new();
        let null = b.add_bsdf(Bsdf::Null);
        let hetero = b.add_medium(Medium {
            coefficients: Coefficients::Heterogeneous(Box::new(Heterogeneous::new(
                sigma,
                Volume::constant(albedo, to_world),
                1.0,
            ))),
            phase: PhaseFunction::HenyeyGreenstein { g: 0.4 },
            sample_emitters: true,
            radiance: None,
        });
        let homo = b.add_medium(
            Medium::homogeneous(Rgb::new(0.3, 1.5, 4.0), albedo, PhaseFunction::Isotropic).unwrap(),
        );
        let mut cube = TriangleMesh::cube();
        cube.transform(&Transform::translate(Vec3::new(-1.0, 0.0, 0.0)));
        let s = b.add_shape(Geometry::Mesh(cube), null, None);
        b.set_shape_media(s, Some(hetero), None);
        let s = b.add_shape(Geometry::Sphere(Sphere::new(Vec3::new(1.2, 0.0, 0.0), 0.9, false)), null, None);
        b.set_shape_media(s, Some(homo), None);
        if lit {
            let grey = b.add_bsdf(Bsdf::Diffuse(crate::material::Diffuse::new(Rgb::splat(0.5))));
            let mut plane = TriangleMesh::cube();
            plane.transform(&Transform::scale(Vec3::new(6.0, 0.05, 6.0)).unwrap());
            plane.transform(&Transform::translate(Vec3::new(0.0, -1.2, 0.0)));
            b.add_shape(Geometry::Mesh(plane), grey, None);
            let black = b.add_bsdf(Bsdf::Diffuse(crate::material::Diffuse::new(Rgb::ZERO)));
            let light = Geometry::Sphere(Sphere::new(Vec3::new(0.5, 3.0, 1.0), 0.4, false));
            b.add_shape(light, black, Some(Rgb::new(20.0, 18.0, 15.0)));
            b.add_constant_environment(Rgb::splat(0.1));
        } else {
            b.add_constant_environment(Rgb::ONE);
        }
        let t = Transform::look_at(Vec3::new(0.0, 0.5, 6.0), Vec3::new(0.0, -0.3, 0.0), Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(t, 45.0, FovAxis::X, 12, 12).unwrap());
        b.build().unwrap()
    }

    fn channel_means(scene: &crate::scene::Scene, integrator: &dyn Integrator, spp: u32, seed: u64) -> [(f64, f64); 3] {
        let settings = RenderSettings { spp, seed, ..Default::default() };
        let out = render(scene, integrator, &settings, &AtomicBool::new(false)).unwrap();
        let (img, var) = (out.film.image(), out.film.variance_of_mean());
        let n = img.len() as f64;
        [0, 1, 2].map(|c| {
            let mean = img.iter().map(|p| p[c] as f64).sum::<f64>() / n;
            let se = var.iter().map(|p| p[c] as f64).sum::<f64>().sqrt() / n;
            (mean, se)
        })
    }

    /// Non-absorbing chromatic media in a uniform sky: light is only redirected, so every
    /// pixel is 1 in every channel (tentative collisions in both kinds of media, the ratio
    /// bookkeeping over channels, null-collision MIS with the environment).
    #[test]
    fn white_furnace() {
        let s = scene(Rgb::ONE, false);
        for (c, (mean, se)) in channel_means(&s, &VolPathMisIntegrator::default(), 512, 1).iter().enumerate() {
            println!("channel {c}: {mean:.5} ± {se:.5}");
            assert!(*se < 0.004 && (mean - 1.0).abs() < 3.0 * se + 1e-4, "channel {c}: {mean} ± {se}");
        }
    }

    /// The same furnace with Russian roulette from the first vertex: light sampling must weigh
    /// each path with the survival probability the unidirectional technique's path needed, or
    /// every contribution loses some of its light (the image came out about 1.3 % dark).
    #[test]
    fn white_furnace_with_roulette_from_the_start() {
        let s = scene(Rgb::ONE, false);
        let integrator = VolPathMisIntegrator { settings: PathSettings { rr_depth: 0, ..Default::default() } };
        for (c, (mean, se)) in channel_means(&s, &integrator, 2048, 4).iter().enumerate() {
            println!("channel {c}: {mean:.5} ± {se:.5}");
            assert!(*se < 0.002 && (mean - 1.0).abs() < 3.0 * se + 1e-4, "channel {c}: {mean} ± {se}");
        }
    }

    /// Absorbing chromatic media over a floor lit by a sphere light: the same per-channel image
    /// means as volpath (a different estimator of the same integral).
    #[test]
    fn agrees_with_volpath() {
        let s = scene(Rgb::new(0.9, 0.8, 0.6), true);
        let a = channel_means(&s, &VolPathMisIntegrator::default(), 512, 2);
        let b = channel_means(&s, &super::super::VolPathIntegrator::default(), 512, 3);
        for c in 0..3 {
            let ((ma, sa), (mb, sb)) = (a[c], b[c]);
            let s = (sa * sa + sb * sb).sqrt();
            println!("channel {c}: volpathmis {ma:.5} ± {sa:.5}, volpath {mb:.5} ± {sb:.5}");
            assert!((ma - mb).abs() < 3.0 * s, "channel {c}: {ma} vs {mb} ± {s}");
        }
    }

    /// A glossy floor (Beckmann, α 0.16) under a diffuse sphere, lit by a small far sphere
    /// light, without media: volpathmis must give the path tracer's image. Light samples from
    /// the floor far off its lobe have BSDF values in the denormal range (~1e-42) against a
    /// light density of ~300, so light sampling's ratio overflows; it used to become 0, leaving
    /// the BSDF technique's ratio to give the sample the weight ½ of a path that carries nothing
    /// (the image 50× too bright, Mitsuba's volpathmis agreeing with the path tracer).
    #[test]
    fn agrees_with_the_path_tracer_where_light_samples_overflow_their_ratios() {
        let text = r#"<scene version="3.0.0">
            <sensor type="perspective">
                <float name="fov" value="45"/>
                <transform name="to_world"><lookat origin="0, 1, 4.5" target="-0.7, -0.4, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
            </sensor>
            <shape type="sphere">
                <point name="center" x="3" y="6" z="-4"/><float name="radius" value="0.3"/>
                <emitter type="area"><rgb name="radiance" value="200"/></emitter>
            </shape>
            <shape type="sphere">
                <point name="center" x="-0.73" y="-0.15" z="0.08"/><float name="radius" value="0.56"/>
                <bsdf type="diffuse"/>
            </shape>
            <shape type="rectangle">
                <transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-0.8"/></transform>
                <bsdf type="roughconductor">
                    <string name="distribution" value="beckmann"/><float name="alpha" value="0.16"/>
                    <boolean name="sample_visible" value="false"/>
                </bsdf>
            </shape>
        </scene>"#;
        let file = crate::load::mitsuba::load_scene_text(std::path::Path::new("floor.xml"), text, &[]).unwrap();
        let settings = PathSettings { max_depth: 3, ..Default::default() };
        let a = channel_means(&file.scene, &VolPathMisIntegrator { settings }, 256, 5);
        let path = super::super::PathIntegrator { settings, ..Default::default() };
        let b = channel_means(&file.scene, &path, 256, 6);
        let ((ma, sa), (mb, sb)) = (a[0], b[0]);
        let s = (sa * sa + sb * sb).sqrt();
        println!("volpathmis {ma:.5} ± {sa:.5}, path {mb:.5} ± {sb:.5}");
        assert!(s < 0.05 * mb, "too noisy: ± {s}");
        assert!((ma - mb).abs() < 4.0 * s, "volpathmis {ma} vs path {mb} ± {s}");
    }

    /// The ratio bookkeeping: one factor per channel gives `f_j / mean_k p_k`; two techniques
    /// with complementary densities give their balance-heuristic sum; zero contributions give
    /// zero, never NaN.
    #[test]
    fn ratios_give_the_balance_heuristic_over_channels() {
        let mut r = Ratios::ONE;
        r.update(Rgb::new(1.0, 2.0, 4.0), Rgb::new(2.0, 1.0, 0.5));
        let mean_p = 7.0 / 3.0;
        let w = r.weight();
        for (j, f) in [2.0f32, 1.0, 0.5].iter().enumerate() {
            assert!((w[j] - f / mean_p).abs() < 1e-6, "{w}");
        }
        let (mut a, mut b) = (Ratios::ONE, Ratios::ONE);
        a.update_scalar(0.25, Rgb::ONE);
        b.update_scalar(0.75, Rgb::ONE);
        assert!((a.combined_weight(&b) - Rgb::ONE).abs().max_element() < 1e-6);
        let mut z = Ratios::ONE;
        z.update(Rgb::ONE, Rgb::new(0.0, 1.0, 1.0));
        assert_eq!(z.weight(), Rgb::new(0.0, 1.0, 1.0));
        z.update(Rgb::ZERO, Rgb::ZERO);
        assert!(z.is_zero() && z.weight() == Rgb::ZERO);
        // A light sample of density 300 whose BSDF value is denormal: light sampling's ratio
        // overflows, and the pair's weight is f / (p_light + p_bsdf) ≈ 0, not the BSDF
        // technique's alone.
        let (mut nee, mut uni) = (Ratios::ONE, Ratios::ONE);
        let f = Rgb::splat(5e-43);
        nee.update_scalar(300.0, Rgb::ONE);
        nee.update_scalar(1.0, f);
        uni.update_scalar(5.1e-43, f);
        assert!(nee.combined_weight(&uni).max_element() < 1e-40, "{}", nee.combined_weight(&uni));
    }
}
