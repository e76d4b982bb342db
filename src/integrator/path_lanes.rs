//! The path tracer in SIMD lanes: `W` camera samples traced side by side, one path per lane
//! ([`crate::math::lanes`]), bit for bit what [`PathIntegrator::trace`] gives each of them.
//!
//! The lanes share the path's depth (they start together and each bounce advances every live
//! lane), so a lane that ends (escaped, absorbed by Russian roulette, past `max_depth`) is masked
//! off until the batch is done. What is the same work in every lane runs in lanes: the shading
//! frame, the direction to the viewer, the value, density and sample of a constant `diffuse`
//! BSDF and of a `roughconductor` of constant parameters ([`RoughConductorW`]), the MIS
//! weights, the throughput and Russian roulette. What branches by lane or reads scattered
//! memory runs lane by lane with the scalar code: ray queries, surface interactions, emission
//! found by the path, light selection, light samples (but those of rectangles and of whole
//! spheres seen from outside, of constant radiance, which run in lanes), environment light of
//! escaped rays (and the sampler's draws, but for the independent sampler's, which run in
//! lanes: [`Pcg32Lanes`]). Those
//! loops visit the set lanes only (`ones`): testing each lane in turn mispredicted a branch on
//! every unpredictable lane, which cost more than the lanes saved. Per-lane records (the surface
//! interaction, the previous vertex) are written in place, never moved: a moved record is read
//! by wide loads right after its narrow stores, and such a load waits for them.
//!
//! The render loop hands it a tile's camera samples in batches of `W` that span pixels (each
//! with its own sampler, positioned after the camera's draws), so that passes of few samples
//! per pixel fill the lanes too.
//!
//! Scenes it takes ([`PathIntegrator::lane_support`]): every BSDF `diffuse`, `conductor`,
//! `roughconductor`, `plastic`, `roughplastic`, `dielectric` or `roughdielectric` (a `diffuse`
//! of constant reflectance and a GGX or Beckmann `roughconductor` of constant parameters in
//! lanes, the others lane by lane with the scalar BSDF code: the lanes then still share the
//! rest of the vertex, the sampler and the MIS arithmetic), any
//! shapes and lights, `hide_emitters` or not; the default strategy (light and BSDF sampling,
//! power heuristic), no regularization. Anything else is traced by the scalar code.

use super::path::{DirectStrategy, MisHeuristic, PathIntegrator};
use super::trace::{self, Mis, PrevVertex};
use super::RadianceSample;
use crate::geometry::sphere::sample_cone_lanes;
use crate::geometry::{Geometry, SurfaceInteraction};
use crate::light::{Light, LightSampleContext};
use crate::material::lanes::RoughConductorW;
use crate::material::{Bsdf, Diffuse, TextureMemo};
use crate::math::lanes::{ones, sin_cos_quarter, FrameW, Fw, Mw, V3w};
use crate::math::{Ray, Rgb, Vec3, INV_PI};
use crate::sampling::rng::Pcg32Lanes;
use crate::sampling::Sampler;
use crate::scene::{HitSlot, Scene};
use crate::texture::Texture;

/// [`crate::sampling::power_heuristic`] with one sample of each strategy, in lanes.
#[inline(always)]
fn power_heuristic<const W: usize>(f: Fw<W>, g: Fw<W>) -> Fw<W> {
    let (f, g) = (1.0 * f, 1.0 * g);
    let (f2, g2) = (f * f, g * g);
    let inf = Fw::splat(f32::INFINITY);
    let r = f2 / (f2 + g2);
    let r = Fw::select((f2 + g2).le(Fw::splat(0.0)), Fw::splat(0.0), r);
    Fw::select(f2.eq(inf), Fw::select(g2.eq(inf), Fw::splat(0.5), Fw::splat(1.0)), r)
}

/// [`crate::sampling::sample_cosine_hemisphere_malley`] in lanes: the direction and its density.
#[inline(always)]
fn sample_cosine_hemisphere<const W: usize>(ux: Fw<W>, uy: Fw<W>) -> (V3w<W>, Fw<W>) {
    // The concentric disk: both wedges' ratio in one division (the one the scalar code makes).
    let (ax, ay) = (2.0 * ux - 1.0, 2.0 * uy - 1.0);
    let wide = ax.abs().gt(ay.abs());
    let (num, den) = (Fw::select(wide, ay, ax), Fw::select(wide, ax, ay));
    let (s, c) = sin_cos_quarter(std::f32::consts::FRAC_PI_4 * (num / den));
    let centre = ax.eq(Fw::splat(0.0)) & ay.eq(Fw::splat(0.0));
    let zero = Fw::splat(0.0);
    let dx = Fw::select(centre, zero, Fw::select(wide, den * c, den * s));
    let dy = Fw::select(centre, zero, Fw::select(wide, den * s, den * c));
    let z = (1.0 - (dx * dx + dy * dy)).max(zero).sqrt().max(Fw::splat(1e-7));
    (V3w::new(dx, dy, z), z * INV_PI)
}

/// Lane `k` of `v` as an `Rgb`.
#[inline(always)]
fn rgb<const W: usize>(v: &V3w<W>, k: usize) -> Rgb {
    v.lane(k)
}

/// Writes `c` into lane `k` of `v`.
#[inline(always)]
fn set<const W: usize>(v: &mut V3w<W>, k: usize, c: Vec3) {
    (v.x.0[k], v.y.0[k], v.z.0[k]) = (c.x, c.y, c.z);
}

/// Whether the lanes take BSDF `b`: a constant `diffuse` and a constant GGX or Beckmann
/// `roughconductor` run in lanes; the others listed here lane by lane with the scalar code
/// (they never pass light straight through, as `null` and `mask` do, whose crossings the lanes
/// do not track).
fn lane_bsdf(b: &Bsdf) -> bool {
    matches!(
        b,
        Bsdf::Diffuse(_)
            | Bsdf::Conductor(_)
            | Bsdf::RoughConductor(_)
            | Bsdf::Plastic(_)
            | Bsdf::RoughPlastic(_)
            | Bsdf::Dielectric(_)
            | Bsdf::RoughDielectric(_)
    )
}

impl PathIntegrator {
    /// Whether [`PathIntegrator::trace_lanes`] takes `scene` (module docs).
    pub(crate) fn lane_support(&self, scene: &Scene) -> bool {
        self.strategy == DirectStrategy::Mis
            && self.heuristic == MisHeuristic::Power
            && !self.regularize
            && self.settings.max_segments() > 0
            && scene.bsdfs().iter().all(lane_bsdf)
    }

    /// `rays.len() ≤ W` camera samples at once, `samplers[k]` lane `k`'s sampler positioned
    /// after the camera's draws; `out[k]` receives what [`PathIntegrator::trace`] and
    /// [`super::Integrator::sample`] give that sample, bit for bit. The scene must be one
    /// [`PathIntegrator::lane_support`] takes.
    // Lane loops index several per-lane arrays by the lane.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(crate) fn trace_lanes<const W: usize>(
        &self,
        scene: &Scene,
        rays: &[Ray],
        samplers: &mut [Sampler],
        out: &mut [RadianceSample],
    ) {
        let n = rays.len();
        debug_assert!(n <= W && samplers.len() == n && out.len() == n && self.lane_support(scene));
        let max_depth = self.settings.max_segments();
        let hide = self.settings.hide_emitters;
        let mis = Mis::POWER;
        let mut ray: [Ray; W] = [Ray::new(Vec3::ZERO, Vec3::Z); W];
        ray[..n].copy_from_slice(rays);
        let mut live = Mw::<W>::from_fn(|k| k < n);
        let mut covered = Mw::<W>::NONE;
        let mut l = V3w::<W>::splat(Vec3::ZERO);
        let mut beta = V3w::<W>::splat(Vec3::ONE);
        let mut eta = Fw::<W>::splat(1.0);
        // The previous vertex of each lane's path (where `has_prev[k]`), its fields written in
        // place: a record built and then moved is copied by a wide load spanning its narrower
        // stores, which waits for them to reach the cache.
        let no_prev = PrevVertex { ctx: LightSampleContext { p: Vec3::ZERO, n: Vec3::Z }, pdf: 0.0, delta: false };
        let mut prev: [PrevVertex; W] = [no_prev; W];
        let mut has_prev = [false; W];
        // Each lane's vertex, written in place by the surface interaction (a move of the
        // record into an `Option` was a copy by wide loads right after the interaction's narrow
        // stores: a failed store-to-load forward on most of them); the lanes of `has` have one.
        let blank = SurfaceInteraction {
            p: Vec3::ZERO,
            p_error: Vec3::ZERO,
            t: 0.0,
            ng: Vec3::Z,
            ns: Vec3::Z,
            uv: crate::math::Vec2::ZERO,
            dpdu: Vec3::X,
            dpdv: Vec3::ZERO,
            shape: 0,
            prim: 0,
            bary: crate::math::Vec2::ZERO,
            time: 0.0,
        };
        let mut si: [SurfaceInteraction; W] = [blank; W];
        let mut has: Mw<W>;
        let mut slots: [HitSlot; W] = std::array::from_fn(|_| HitSlot::default());
        let mut depth = 0u32;
        // The vertex's rough conductors in lanes (cleared and filled at each vertex).
        let mut conductors = RoughConductorW::<W>::default();
        // The independent sampler's generators in lanes, where every lane has one (a lane
        // draws exactly what its sampler would); other samplers draw lane by lane.
        let mut rng = samplers.iter_mut().all(|s| matches!(s, Sampler::Independent(_))).then(|| {
            Pcg32Lanes::<W>::gather(samplers.iter_mut().map(|s| match s {
                Sampler::Independent(s) => &*s.rng_mut(),
                _ => unreachable!("every sampler is independent"),
            }))
        });
        loop {
            // Camera rays pass through emitters hidden from the camera (`hide_emitters`), and
            // what they escape to stays hidden: as the scalar path does.
            let hidden = hide && depth == 0;
            // The closest hits of the live lanes' rays, one by one.
            if !hidden {
                for k in ones(live) {
                    scene.intersect_into(&ray[k], &mut slots[k]);
                }
            }
            // Lane by lane: emission found by the path, escapes.
            has = Mw::NONE;
            for k in ones(live) {
                let b = rgb(&beta, k);
                let hit = if hidden {
                    trace::skip_hidden_emitters(scene, &mut ray[k], &mut slots[k])
                } else {
                    scene.deferred(&ray[k], &slots[k])
                };
                let Some(hit) = hit else {
                    if !hidden {
                        let d = ray[k].d.normalize();
                        let mut lk = rgb(&l, k);
                        let prev = has_prev[k].then_some(&prev[k]);
                        trace::escaped(scene, ray[k].o, d, prev, hide, &mis, |le, w| lk += b * le * w);
                        set(&mut l, k, lk);
                    }
                    live.0[k] = 0;
                    continue;
                };
                if depth + 1 >= max_depth && hit.light().is_none() {
                    live.0[k] = 0;
                    continue;
                }
                hit.interaction_into(&mut si[k]);
                let s = &si[k];
                let wo = -ray[k].d.normalize();
                if let Some(light_index) = scene.shapes()[s.shape as usize].light {
                    let le = scene.lights()[light_index as usize].le(s.ns, wo, s.uv);
                    if le != Rgb::ZERO {
                        let weight = trace::emission_weight(has_prev[k].then_some(&prev[k]), hide, &mis, |c| {
                            trace::light_pdf_at(scene, c, light_index, s.p, s.ng)
                        });
                        let lk = rgb(&l, k) + b * le * weight;
                        set(&mut l, k, lk);
                    }
                }
                if depth + 1 >= max_depth {
                    live.0[k] = 0;
                    continue;
                }
                has.0[k] = u32::MAX;
            }
            if !live.any() {
                break;
            }

            // The vertex in lanes: frame, viewer direction, albedo and the sampler's numbers.
            // (Lanes without a vertex read the last one they had, or a blank: masked off below.)
            let ns = V3w::<W>::from_fn(|k| si[k].ns);
            let dpdu = V3w::<W>::from_fn(|k| si[k].dpdu);
            let frame = FrameW::from_zx(ns, dpdu);
            let d = V3w::<W>::from_fn(|k| ray[k].d);
            let wo_local = frame.to_local(-d.normalize());
            let mut rho = V3w::<W>::splat(Rgb::ZERO);
            // The lanes whose BSDF is a constant diffuse one (in lanes); the rest go lane by lane.
            let mut plain = Mw::<W>::NONE;
            // The lanes whose BSDF is a `roughconductor` of constant parameters (in lanes).
            let mut rough = Mw::<W>::NONE;
            conductors.clear();
            for k in ones(has) {
                match &scene.bsdfs()[scene.shapes()[si[k].shape as usize].bsdf as usize] {
                    Bsdf::Diffuse(Diffuse { reflectance: Texture::Constant(c) }) => {
                        set(&mut rho, k, *c);
                        plain.0[k] = u32::MAX;
                    }
                    Bsdf::RoughConductor(b) if conductors.set(k, b) => rough.0[k] = u32::MAX,
                    _ => {}
                }
            }
            let generic = has & !plain & !rough;
            let mut u = [[0.0f32; W]; 6];
            if let Some(rng) = &mut rng {
                for d in &mut u {
                    *d = rng.next_f32(&has.0);
                }
            } else {
                for k in ones(has) {
                    let sampler = &mut samplers[k];
                    let (a, b, c, e) = (sampler.next_1d(), sampler.next_2d(), sampler.next_1d(), sampler.next_2d());
                    (u[0][k], u[1][k], u[2][k], u[3][k], u[4][k], u[5][k]) = (a, b.x, b.y, c, e.x, e.y);
                }
            }

            // The BSDF sample that continues the path (cosine-weighted, above the surface only).
            let (wi_bsdf, pdf_bsdf) = sample_cosine_hemisphere(Fw(u[4]), Fw(u[5]));
            let above = wo_local.z.gt(Fw::splat(0.0));

            // Next-event estimation: the light and its sample lane by lane, then the BSDF's
            // value and density and the MIS weight in lanes.
            let mut ls_wi = V3w::<W>::splat(Vec3::Z);
            let mut ls_li = V3w::<W>::splat(Vec3::ZERO);
            let mut ls_p = V3w::<W>::splat(Vec3::ZERO);
            let mut ls_n = V3w::<W>::splat(Vec3::ZERO);
            let mut ls_err = V3w::<W>::splat(Vec3::ZERO);
            let mut ls_pdf = Fw::<W>::splat(1.0);
            let mut pmf = Fw::<W>::splat(1.0);
            let mut sampled = Mw::<W>::NONE;
            let mut delta = Mw::<W>::NONE;
            // Lanes whose light is a parallelogram of constant radiance (a rectangle light):
            // its sample in lanes below, as `TriangleMesh::sample_area` and
            // `Light::sample_li` compute it.
            let mut quad = Mw::<W>::NONE;
            let mut two_sided = Mw::<W>::NONE;
            let (mut q_o, mut q_e1, mut q_e2) = (ls_p, ls_p, ls_p);
            let (mut q_mismatch, mut q_density) = (Fw::<W>::splat(0.0), Fw::<W>::splat(0.0));
            // Lanes whose light is a whole sphere of constant radiance seen from outside: the
            // cone it subtends sampled in lanes below, as `Sphere::sample_solid_angle`,
            // `Geometry::sample_solid_angle` and `Light::sample_li` compute it.
            let (mut ball, mut flip) = (Mw::<W>::NONE, Mw::<W>::NONE);
            let (mut b_c, mut b_r) = (ls_p, Fw::<W>::splat(1.0));
            for k in ones(has) {
                let s = &si[k];
                let ctx = LightSampleContext { p: s.p, n: s.ns };
                let Some((index, p)) = scene.sample_light(&ctx, u[0][k]) else { continue };
                pmf.0[k] = p;
                let light = &scene.lights()[index as usize];
                if let Light::Area { shape, radiance: Texture::Constant(c), two_sided: both } = light {
                    match &scene.geometries()[*shape as usize] {
                        Geometry::Mesh(m) => {
                            if let Some(([o, e1, e2, n], mismatch, density)) = m.parallelogram_sampling() {
                                (quad.0[k], two_sided.0[k]) = (u32::MAX, if *both { u32::MAX } else { 0 });
                                set(&mut q_o, k, o);
                                set(&mut q_e1, k, e1);
                                set(&mut q_e2, k, e2);
                                set(&mut ls_n, k, n);
                                set(&mut ls_li, k, *c);
                                (q_mismatch.0[k], q_density.0[k]) = (mismatch, density);
                                continue;
                            }
                        }
                        // A whole sphere seen from outside: its cone sampled in lanes below.
                        Geometry::Sphere(sphere)
                            if !sphere.clip.is_partial()
                                && (s.p - sphere.center).length_squared()
                                    > sphere.radius * sphere.radius * (1.0 + 1e-4) =>
                        {
                            (ball.0[k], two_sided.0[k]) = (u32::MAX, if *both { u32::MAX } else { 0 });
                            flip.0[k] = if sphere.flip { u32::MAX } else { 0 };
                            set(&mut b_c, k, sphere.center);
                            b_r.0[k] = sphere.radius;
                            set(&mut ls_li, k, *c);
                            continue;
                        }
                        _ => {}
                    }
                }
                let Some(ls) = light.sample_li(scene.geometries(), s.p, crate::math::Vec2::new(u[1][k], u[2][k]))
                else {
                    continue;
                };
                set(&mut ls_wi, k, ls.wi);
                set(&mut ls_li, k, ls.li);
                set(&mut ls_p, k, ls.p);
                set(&mut ls_n, k, ls.n);
                set(&mut ls_err, k, ls.p_error);
                (ls_pdf.0[k], sampled.0[k], delta.0[k]) = (ls.pdf, u32::MAX, if ls.delta { u32::MAX } else { 0 });
            }
            let p_ref = V3w::<W>::from_fn(|k| si[k].p);
            if quad.any() {
                // The point: o + u₁ e₁ + u₂ e₂ with its error bound; its density per solid
                // angle from the vertex, p_A r³ / |n · d|; none where the light faces away.
                let (a, b) = (q_e1.scale(Fw(u[1])), q_e2.scale(Fw(u[2])));
                let err = (q_o.abs() + a.abs() + b.abs()).scale(Fw::splat(crate::math::float::gamma(6))) + q_mismatch;
                let p = q_o + a + b;
                let d = p - p_ref;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                let wi = d / dist;
                let pdf = q_density * dist2 * dist / ls_n.dot(d).abs();
                let ok =
                    quad & pdf.gt(Fw::splat(0.0)) & pdf.is_finite() & (two_sided | ls_n.dot(wi).lt(Fw::splat(0.0)));
                ls_wi = V3w::select(quad, wi, ls_wi);
                ls_p = V3w::select(quad, p, ls_p);
                ls_err = V3w::select(quad, err, ls_err);
                ls_pdf = Fw::select(quad, pdf, ls_pdf);
                sampled = sampled | ok;
            }
            if ball.any() {
                // The point in the cone, the unit direction to it (none where it has no length)
                // and, for a one-sided light, none where the light faces away.
                let (p, v, err, pdf) = sample_cone_lanes(b_c, b_r, p_ref, Fw(u[1]), Fw(u[2]));
                let n = V3w::select(flip, -v, v);
                let d = p - p_ref;
                let rcp = 1.0 / d.length();
                let wi = d.scale(rcp);
                let ok = ball & rcp.is_finite() & rcp.gt(Fw::splat(0.0)) & (two_sided | !n.dot(wi).ge(Fw::splat(0.0)));
                ls_wi = V3w::select(ball, wi, ls_wi);
                ls_p = V3w::select(ball, p, ls_p);
                ls_n = V3w::select(ball, n, ls_n);
                ls_err = V3w::select(ball, err, ls_err);
                ls_pdf = Fw::select(ball, pdf, ls_pdf);
                sampled = sampled | ok;
            }
            // The other BSDFs lane by lane, by the scalar code in the scalar path's order: the
            // sample that continues the path, then the value and density toward the light
            // sample (none for a delta BSDF, whose vertex takes no light sample).
            let zero = V3w::<W>::splat(Vec3::ZERO);
            let (mut g_f, mut g_pdf) = (zero, Fw::<W>::splat(0.0));
            let (mut g_ok, mut g_delta) = (Mw::<W>::NONE, Mw::<W>::NONE);
            let (mut g_weight, mut g_wi) = (zero, V3w::<W>::splat(Vec3::Z));
            let (mut g_sample_pdf, mut g_eta) = (Fw::<W>::splat(0.0), Fw::<W>::splat(1.0));
            for k in ones(generic) {
                let s = &si[k];
                let bsdf = &scene.bsdfs()[scene.shapes()[s.shape as usize].bsdf as usize];
                let memo = TextureMemo::default();
                let vertex = trace::SurfaceVertex::new(scene, s, bsdf, &memo, -ray[k].d.normalize());
                let u_bsdf = crate::math::Vec2::new(u[4][k], u[5][k]);
                if let Some(bs) = bsdf.sample(&vertex.ctx, vertex.wo_local, u[3][k], u_bsdf) {
                    set(&mut g_weight, k, bs.weight);
                    set(&mut g_wi, k, vertex.frame.to_world(bs.wi));
                    (g_ok.0[k], g_delta.0[k]) = (u32::MAX, if bs.delta { u32::MAX } else { 0 });
                    (g_sample_pdf.0[k], g_eta.0[k]) = (bs.pdf, bs.eta);
                }
                if !bsdf.is_delta() && sampled.test(k) {
                    let (f, pdf) = vertex.eval_pdf(ls_wi.lane(k), !delta.test(k));
                    set(&mut g_f, k, f);
                    g_pdf.0[k] = pdf;
                }
            }

            let wi = frame.to_local(ls_wi);
            // The rough conductors in lanes, their results where the lane-by-lane BSDFs put
            // theirs: the value and density toward the light sample (no density toward a
            // delta light's: the scalar path evaluates the value alone there), and the sample
            // that continues the path (η unchanged: their `g_eta` stays 1).
            if rough.any() {
                let (rf, rpdf) = conductors.eval_pdf(wo_local, wi);
                g_f = V3w::select(rough, rf, g_f);
                g_pdf = Fw::select(rough & !delta, rpdf, g_pdf);
                let r = conductors.sample(wo_local, Fw(u[4]), Fw(u[5]));
                g_ok = g_ok | (rough & r.ok);
                g_weight = V3w::select(rough, r.weight, g_weight);
                g_wi = V3w::select(rough, frame.to_world(r.wi), g_wi);
                g_sample_pdf = Fw::select(rough, r.pdf, g_sample_pdf);
            }
            let generic = generic | rough;
            let lit = sampled & above & wi.z.gt(Fw::splat(0.0));
            let f = V3w::select(lit, rho.scale(INV_PI * wi.z), zero);
            let pdf = Fw::select(lit, wi.z.max(Fw::splat(0.0)) * INV_PI, Fw::splat(0.0));
            let (f, pdf) = (V3w::select(generic, g_f, f), Fw::select(generic, g_pdf, pdf));
            let mut visible = sampled & !(f.x.eq(Fw::splat(0.0)) & f.y.eq(Fw::splat(0.0)) & f.z.eq(Fw::splat(0.0)));
            for k in ones(visible) {
                if scene.occluded(&si[k].spawn_ray_to(ls_p.lane(k), ls_n.lane(k), ls_err.lane(k))) {
                    visible.0[k] = 0;
                }
            }
            let fl = f * ls_li;
            let p_light = pmf * ls_pdf;
            let w = power_heuristic(p_light, pdf);
            let c = V3w::select(delta, fl / (pmf * 1.0), fl.scale(w / (p_light * 1.0)));
            let nonzero = !(c.x.eq(Fw::splat(0.0)) & c.y.eq(Fw::splat(0.0)) & c.z.eq(Fw::splat(0.0)));
            l = V3w::select(visible & nonzero, l + beta * c, l);

            // Continue by the BSDF sample; Russian roulette.
            covered = covered | has;
            live = live & ((plain & above) | (generic & g_ok));
            beta = V3w::select(live, beta * V3w::select(generic, g_weight, rho), beta);
            eta = Fw::select(live & generic, eta * g_eta, eta);
            let wi_world = V3w::select(generic, g_wi, frame.to_world(wi_bsdf));
            let pdf_next = Fw::select(generic, g_sample_pdf, pdf_bsdf);
            depth += 1;
            for k in ones(live) {
                let s = &si[k];
                (prev[k].ctx.p, prev[k].ctx.n, prev[k].pdf) = (s.p, s.ns, pdf_next.0[k]);
                prev[k].delta = g_delta.test(k);
                ray[k] = s.spawn_ray(wi_world.lane(k));
                has_prev[k] = true;
            }
            let u_rr = match &mut rng {
                Some(rng) => rng.next_f32(&live.0),
                None => {
                    let mut u_rr = [0.0f32; W];
                    for k in ones(live) {
                        u_rr[k] = samplers[k].next_1d();
                    }
                    u_rr
                }
            };
            let m = beta.max_element();
            let mut survive = live & m.gt(Fw::splat(0.0));
            if depth >= self.settings.rr_depth {
                let q = (m * eta * eta).min(Fw::splat(0.95));
                survive = survive & Fw(u_rr).lt(q);
                beta = V3w::select(survive, beta / q, beta);
            }
            live = survive;
            if !live.any() {
                break;
            }
        }
        if let Some(rng) = &rng {
            rng.scatter(samplers.iter_mut().filter_map(|s| match s {
                Sampler::Independent(s) => Some(s.rng_mut()),
                _ => None,
            }));
        }
        for k in 0..n {
            out[k] = RadianceSample { l: rgb(&l, k), alpha: trace::coverage(scene, covered.test(k), hide) };
        }
    }
}

/// Lanes the path tracer runs in on this CPU: 8 with AVX2 (also where AVX-512 is present:
/// sixteen lanes measured no faster than eight on the Cornell box, 1.06× the scalar path
/// each, an AMD Zen 5, 2026-12-07), else 4. The environment variable `NEUMANN_LANES` chooses for measurements: 0 (one sample
/// at a time), 4, 8 or 16 (a width the CPU lacks falls back to the default).
pub(crate) fn lane_width() -> usize {
    static WIDTH: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *WIDTH.get_or_init(|| {
        let asked = std::env::var("NEUMANN_LANES").ok().and_then(|v| v.parse::<usize>().ok());
        if asked == Some(0) || asked == Some(4) {
            return asked.unwrap_or(0);
        }
        #[cfg(target_arch = "x86_64")]
        {
            if asked == Some(16)
                && std::is_x86_feature_detected!("avx512f")
                && std::is_x86_feature_detected!("avx512vl")
                && std::is_x86_feature_detected!("avx512dq")
                && std::is_x86_feature_detected!("avx512bw")
            {
                return 16;
            }
            if std::is_x86_feature_detected!("avx2") {
                return 8;
            }
        }
        4
    })
}

/// [`PathIntegrator::trace_lanes`] compiled for the instruction set [`lane_width`] found.
pub(crate) fn trace_lanes_dispatch(
    p: &PathIntegrator,
    scene: &Scene,
    rays: &[Ray],
    samplers: &mut [Sampler],
    out: &mut [RadianceSample],
) {
    #[cfg(target_arch = "x86_64")]
    {
        /// Sixteen lanes in AVX-512 registers. Safety: the CPU must have these features.
        #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,avx2")]
        unsafe fn avx512(p: &PathIntegrator, s: &Scene, r: &[Ray], m: &mut [Sampler], o: &mut [RadianceSample]) {
            p.trace_lanes::<16>(s, r, m, o)
        }
        /// Eight lanes in AVX2 registers. Safety: the CPU must have AVX2.
        #[target_feature(enable = "avx2")]
        unsafe fn avx2(p: &PathIntegrator, s: &Scene, r: &[Ray], m: &mut [Sampler], o: &mut [RadianceSample]) {
            p.trace_lanes::<8>(s, r, m, o)
        }
        match lane_width() {
            // SAFETY: lane_width found the features each is compiled for.
            16 => return unsafe { avx512(p, scene, rays, samplers, out) },
            8 => return unsafe { avx2(p, scene, rays, samplers, out) },
            _ => {}
        }
    }
    p.trace_lanes::<4>(scene, rays, samplers, out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, FovAxis};
    use crate::geometry::{Geometry, Sphere, TriangleMesh};
    use crate::integrator::trace::PathSettings;
    use crate::integrator::Integrator;
    use crate::math::{Transform, Vec2};
    use crate::sampling::sampler::SamplerKind;
    use crate::scene::SceneBuilder;

    /// A diffuse room of every light kind the lanes meet: an open box of meshes (one face
    /// lit, one-sided), a sphere that emits, a point light (a delta light sample) and a
    /// constant sky through the open side (escaped rays), with a diffuse sphere inside; where
    /// `glossy`, also spheres of each BSDF the lanes take lane by lane (a rough conductor of
    /// each microfacet distribution, a mirror, smooth and rough plastic, smooth and rough glass).
    fn room(glossy: bool) -> Scene {
        let mut b = SceneBuilder::new();
        if glossy {
            use crate::material::microfacet::{Microfacet, MicrofacetType, Roughness};
            use crate::material::{Conductor, ConductorIor, Dielectric, Plastic, RoughConductor, RoughDielectric, RoughPlastic};
            let gold = || Some(ConductorIor::constant(Rgb::new(0.14, 0.37, 1.44), Rgb::new(3.98, 2.38, 1.6)));
            let bsdfs = [
                Bsdf::RoughConductor(RoughConductor {
                    roughness: Roughness::from(Microfacet::new(MicrofacetType::Ggx, 0.2, 0.2)),
                    ior: gold(),
                    specular_reflectance: Rgb::ONE.into(),
                }),
                Bsdf::RoughConductor(RoughConductor {
                    roughness: Roughness::from(Microfacet::new(MicrofacetType::Beckmann, 0.3, 0.1)),
                    ior: None,
                    specular_reflectance: Rgb::splat(0.8).into(),
                }),
                Bsdf::Conductor(Conductor { ior: gold(), specular_reflectance: Rgb::ONE.into() }),
                Bsdf::Plastic(Plastic::new(Rgb::new(0.2, 0.5, 0.3), Rgb::ONE, 1.5, false)),
                Bsdf::RoughPlastic(RoughPlastic::new(
                    Microfacet::new(MicrofacetType::Ggx, 0.15, 0.15),
                    Rgb::new(0.5, 0.2, 0.1),
                    Rgb::ONE,
                    1.5,
                    false,
                )),
                Bsdf::Dielectric(Dielectric {
                    eta: 1.5,
                    specular_reflectance: Rgb::ONE.into(),
                    specular_transmittance: Rgb::ONE.into(),
                }),
                Bsdf::RoughDielectric(RoughDielectric {
                    roughness: Roughness::from(Microfacet::new(MicrofacetType::Ggx, 0.25, 0.25)),
                    eta: 1.33,
                    specular_reflectance: Rgb::ONE.into(),
                    specular_transmittance: Rgb::splat(0.9).into(),
                }),
            ];
            for (i, bsdf) in bsdfs.into_iter().enumerate() {
                let m = b.add_bsdf(bsdf);
                let at = Vec3::new(-0.75 + 0.25 * i as f32, -0.8 + 0.2 * (i % 2) as f32, 0.3 - 0.1 * i as f32);
                // The glass spheres larger: paths through them test the lanes' η (Russian roulette).
                let r = if i >= 5 { 0.3 } else { 0.17 };
                b.add_shape(Geometry::Sphere(Sphere::new(at, r, false)), m, None);
            }
        }
        let white = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::new(0.8, 0.7, 0.6))));
        let red = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::new(0.6, 0.1, 0.1))));
        let faces = [
            (Transform::rotate(Vec3::X, -90.0).unwrap(), Vec3::new(0.0, -1.0, 0.0), white),
            (Transform::rotate(Vec3::X, 90.0).unwrap(), Vec3::new(0.0, 1.0, 0.0), white),
            (Transform::IDENTITY, Vec3::new(0.0, 0.0, -1.0), white),
            (Transform::rotate(Vec3::Y, 90.0).unwrap(), Vec3::new(-1.0, 0.0, 0.0), red),
        ];
        for (turn, at, bsdf) in faces {
            let mut m = TriangleMesh::rectangle();
            m.transform(&(Transform::translate(at) * turn));
            b.add_shape(Geometry::Mesh(m), bsdf, None);
        }
        let mut lamp = TriangleMesh::rectangle();
        lamp.transform(
            &(Transform::translate(Vec3::new(0.0, 0.98, 0.0))
                * Transform::rotate(Vec3::X, 90.0).unwrap()
                * Transform::scale(Vec3::splat(0.3)).unwrap()),
        );
        b.add_shape(Geometry::Mesh(lamp), white, Some(Rgb::new(6.0, 5.0, 4.0)));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::new(0.4, -0.6, -0.2), 0.35, false)), red, None);
        b.add_shape(
            Geometry::Sphere(Sphere::new(Vec3::new(-0.5, 0.5, -0.5), 0.1, false)),
            white,
            Some(Rgb::splat(3.0)),
        );
        b.add_point_light(Vec3::new(0.5, 0.5, 0.5), Rgb::splat(0.4));
        b.add_constant_environment(Rgb::new(0.2, 0.3, 0.5));
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 3.5), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 45.0, FovAxis::X, 8, 8).unwrap());
        b.build().unwrap()
    }

    /// Every sample traced in lanes is the scalar path tracer's, bit for bit: full and partial
    /// batches of each width, several depths (with and without Russian roulette), two samplers,
    /// a diffuse room and one with the BSDFs the lanes take lane by lane, emitters shown and
    /// hidden from the camera.
    #[test]
    fn lanes_match_the_scalar_path_tracer_bit_for_bit() {
        let cases = [(1, 5, false), (2, 5, false), (3, 1, false), (8, 2, false), (-1, 5, false), (2, 5, true), (-1, 2, true)];
        for (glossy, hide_emitters) in [(false, false), (true, false), (true, true)] {
            for &(max_depth, rr_depth, _) in cases.iter().filter(|c| !hide_emitters || c.2) {
                check_lanes(&room(glossy), PathSettings { max_depth, rr_depth, hide_emitters });
            }
        }
    }

    /// [`lanes_match_the_scalar_path_tracer_bit_for_bit`] for one scene and setting.
    fn check_lanes(scene: &Scene, settings: PathSettings) {
        let cam = scene.camera();
        let glossy = scene.bsdfs().len() > 2;
        let integrator = PathIntegrator { settings, ..Default::default() };
        assert!(integrator.lane_support(scene));
        for kind in [SamplerKind::Independent, SamplerKind::Sobol] {
            let mut sampler = kind.make(256, 7);
            let mut rays = Vec::new();
            let mut samplers = Vec::new();
            for i in 0..256u32 {
                let pixel = [i % 8, (i / 8) % 8];
                sampler.start_pixel_sample(pixel, i, 0);
                let film = Vec2::new(pixel[0] as f32, pixel[1] as f32) + sampler.next_2d();
                let (ray, _) = cam.sample_ray(film, sampler.next_2d());
                rays.push(ray);
                samplers.push(sampler.clone());
            }
            let expected: Vec<RadianceSample> = rays
                .iter()
                .zip(&samplers)
                .map(|(r, s)| integrator.sample(scene, r, &mut s.clone(), &mut []))
                .collect();
            let mut lit = 0;
            for width in [4usize, 8, 16] {
                for batch in [width, width - 1, 1] {
                    let mut out = vec![RadianceSample { l: Rgb::ZERO, alpha: 0.0 }; rays.len()];
                    let mut s = samplers.clone();
                    for ((r, m), o) in rays.chunks(batch).zip(s.chunks_mut(batch)).zip(out.chunks_mut(batch)) {
                        match width {
                            4 => integrator.trace_lanes::<4>(scene, r, m, o),
                            8 => integrator.trace_lanes::<8>(scene, r, m, o),
                            _ => integrator.trace_lanes::<16>(scene, r, m, o),
                        }
                    }
                    for (k, (a, e)) in out.iter().zip(&expected).enumerate() {
                        let bits = |s: &RadianceSample| {
                            [s.l.x.to_bits(), s.l.y.to_bits(), s.l.z.to_bits(), s.alpha.to_bits()]
                        };
                        assert_eq!(bits(a), bits(e), "{settings:?}, glossy {glossy}, {kind:?}, width {width}, batch {batch}, sample {k}: {a:?} vs {e:?}");
                        lit += usize::from(a.l != Rgb::ZERO);
                    }
                    // The dispatcher (whatever width this CPU runs) gives the same.
                    let mut s = samplers.clone();
                    let n = rays.len().min(lane_width().max(1));
                    trace_lanes_dispatch(&integrator, scene, &rays[..n], &mut s[..n], &mut out[..n]);
                    assert!(out[..n]
                        .iter()
                        .zip(&expected)
                        .all(|(a, e)| a.l.to_array().map(f32::to_bits) == e.l.to_array().map(f32::to_bits)));
                }
            }
            assert!(lit > 100, "too few samples see light to test anything: {lit} ({settings:?})");
        }
    }

    /// Scenes with a BSDF the lanes do not take (one that passes light straight through), or
    /// settings the lanes do not implement, are left to the scalar code.
    #[test]
    fn lanes_take_their_bsdfs_with_the_default_strategy_only() {
        let scene = room(true);
        let path = PathIntegrator::default();
        assert!(path.lane_support(&scene));
        assert_eq!(path.lanes(&scene), lane_width());
        let hidden = PathIntegrator { settings: PathSettings { hide_emitters: true, ..Default::default() }, ..Default::default() };
        assert!(hidden.lane_support(&scene));
        for other in [
            PathIntegrator { strategy: DirectStrategy::Light, ..Default::default() },
            PathIntegrator { heuristic: MisHeuristic::Balance, ..Default::default() },
            PathIntegrator { regularize: true, ..Default::default() },
            PathIntegrator::with_max_depth(0),
        ] {
            assert!(!other.lane_support(&scene) && other.lanes(&scene) == 0);
        }
        let mut b = SceneBuilder::new();
        let mirror = b.add_bsdf(Bsdf::Null);
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), mirror, None);
        b.add_point_light(Vec3::new(0.0, 3.0, 0.0), Rgb::ONE);
        b.set_camera(Camera::perspective(Transform::IDENTITY, 45.0, FovAxis::X, 4, 4).unwrap());
        assert!(!path.lane_support(&b.build().unwrap()));
    }
}
