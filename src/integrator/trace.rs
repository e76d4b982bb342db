//! The tracing core every integrator shares (Tungsten's `TraceBase`, Mitsuba's
//! `sample_emitter_direction` + `eval_pdf`): path-length settings, next-event estimation with
//! multiple importance sampling generic over visibility, the MIS weight of emission found by
//! BSDF or phase sampling, the escaped-ray rule and the hidden-emitter rule.
//!
//! Direct light at a vertex `x` by light sampling (one sample of `n_light`):
//! choose a light with the scene's light sampler (probability `P(l | x)`), sample a point on it
//! ([`crate::light::Light::sample_li`], density `p_l(ω)` per solid angle), and add
//! `f(ω) Lₑ Tr w_l / (P(l | x) p_l(ω) n_light)`, where `f` is the BSDF times the cosine (or the
//! phase function), `Tr` the visibility (0 or 1 for occlusion, the transmittance through media)
//! and `w_l` the MIS weight against the `n_bsdf` BSDF samples (Veach's power or balance
//! heuristic with sample counts, or 1). Emission that a BSDF-sampled direction finds gets the
//! complementary weight [`emission_weight`]; both use the same `P(l | x) p_l(ω)`, evaluated at
//! the vertex the direction left from.

use crate::geometry::SurfaceInteraction;
use crate::light::{LightSample, LightSampleContext};
use crate::material::{Bsdf, BsdfContext};
use crate::math::{Frame, Ray, Rgb, Vec2, Vec3};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::{balance_heuristic, power_heuristic};
use crate::scene::Scene;

/// The most segments a path may have whatever `max_depth` says (65,536): paths end there. Only
/// Russian roulette held off beyond it (`rr_depth` ≥ 65,536) in a scene that loses almost no
/// light lets a path get that far — its light after 65,536 bounces is ρ⁶⁵⁵³⁶ of the first, and
/// a lossless closed scene's radiance diverges —, and such a path would otherwise run for
/// ever, deaf to an interrupt (the render loop checks it between samples).
pub const MAX_SEGMENTS: u32 = 1 << 16;

/// Path-length settings of the path-space integrators (`path`, `volpath`, `ptracer`), with
/// Mitsuba's names and defaults.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathSettings {
    /// Longest path in segments (`max_depth`; -1: unlimited). 1 shows the emitters only, 2 adds
    /// direct light (Mitsuba's meaning).
    pub max_depth: i32,
    /// Russian roulette applies from this many segments on (`rr_depth`, ≥ 1).
    pub rr_depth: u32,
    /// Emitters seen directly by the camera are invisible (`hide_emitters`): camera rays pass
    /// through emitting shapes and environments are black to them; lighting is unchanged.
    pub hide_emitters: bool,
}

impl Default for PathSettings {
    fn default() -> Self {
        PathSettings { max_depth: -1, rr_depth: 5, hide_emitters: false }
    }
}

impl PathSettings {
    /// Checked settings: `max_depth ≥ -1`, `rr_depth ≥ 1`. The error names the bad parameter.
    pub fn new(max_depth: i64, rr_depth: i64, hide_emitters: bool) -> Result<PathSettings, (&'static str, String)> {
        if max_depth < -1 || max_depth > i32::MAX as i64 {
            return Err(("max_depth", format!("max_depth must be -1 (unlimited) or ≥ 0, got {max_depth}")));
        }
        if !(1..=u32::MAX as i64).contains(&rr_depth) {
            return Err(("rr_depth", format!("rr_depth must be ≥ 1, got {rr_depth}")));
        }
        Ok(PathSettings { max_depth: max_depth as i32, rr_depth: rr_depth as u32, hide_emitters })
    }

    /// The longest path in segments: `max_depth`, at most [`MAX_SEGMENTS`] (also when
    /// unlimited).
    #[inline]
    pub fn max_segments(&self) -> u32 {
        if self.max_depth < 0 {
            MAX_SEGMENTS
        } else {
            (self.max_depth as u32).min(MAX_SEGMENTS)
        }
    }

    /// Whether a path of `segments` segments is within `max_depth`.
    #[inline]
    pub fn allows(&self, segments: u32) -> bool {
        segments <= self.max_segments()
    }

    /// `max_depth` for messages: a number or "unlimited".
    pub fn depth_text(&self) -> String {
        if self.max_depth < 0 {
            "unlimited".into()
        } else {
            self.max_depth.to_string()
        }
    }
}

/// How many hidden emitters a camera ray may pass through before it gives up (a ray inside a
/// stack of emitting shells).
pub const MAX_HIDDEN_SKIPS: u32 = 64;

/// The MIS heuristic combining light and BSDF sampling.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MisHeuristic {
    /// Veach's balance heuristic `w_a = n_a p_a / (n_a p_a + n_b p_b)`.
    Balance,
    /// Veach's power heuristic with exponent 2, `w_a = (n_a p_a)² / ((n_a p_a)² + (n_b p_b)²)`.
    #[default]
    Power,
}

crate::choices!(MisHeuristic, "MIS heuristic", {
    MisHeuristic::Balance => "balance", "balance heuristic";
    MisHeuristic::Power => "power", "power heuristic (exponent 2)";
});

/// How next-event estimation and BSDF sampling share direct light at a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mis {
    /// Both strategies, weighted by `heuristic` with `n_light` light samples and `n_bsdf` BSDF
    /// samples per vertex.
    Combine {
        /// The heuristic.
        heuristic: MisHeuristic,
        /// Light samples per vertex.
        n_light: u32,
        /// BSDF samples per vertex.
        n_bsdf: u32,
    },
    /// Light sampling alone counts direct light (weight 1); emitters found by BSDF sampling add
    /// nothing (weight 0).
    LightOnly,
    /// BSDF sampling alone counts direct light (no next-event estimation).
    BsdfOnly,
}

impl Mis {
    /// One light and one BSDF sample per vertex, power heuristic.
    pub const POWER: Mis = Mis::Combine { heuristic: MisHeuristic::Power, n_light: 1, n_bsdf: 1 };

    /// Weight of a light sample of density `p_light` against BSDF density `p_bsdf()` (only
    /// evaluated when needed).
    #[inline(always)]
    pub fn light_weight(&self, p_light: f32, p_bsdf: impl FnOnce() -> f32) -> f32 {
        match *self {
            Mis::Combine { heuristic, n_light, n_bsdf } => heuristic.weight(n_light, p_light, n_bsdf, p_bsdf),
            Mis::LightOnly => 1.0,
            Mis::BsdfOnly => 0.0,
        }
    }

    /// Whether [`Mis::light_weight`] looks at the BSDF density (a light sample's weight
    /// depends on it).
    #[inline(always)]
    pub fn needs_bsdf_pdf(&self) -> bool {
        matches!(*self, Mis::Combine { n_bsdf, .. } if n_bsdf > 0)
    }

    /// Whether [`Mis::bsdf_weight`] looks at the light-sampling density.
    #[inline(always)]
    pub fn needs_light_pdf(&self) -> bool {
        matches!(*self, Mis::Combine { n_light, .. } if n_light > 0)
    }

    /// Weight of emission found by a BSDF sample of density `p_bsdf` against the light-sampling
    /// density `p_light()` of the same direction (only evaluated when needed).
    #[inline(always)]
    pub fn bsdf_weight(&self, p_bsdf: f32, p_light: impl FnOnce() -> f32) -> f32 {
        match *self {
            Mis::Combine { heuristic, n_light, n_bsdf } => heuristic.weight(n_bsdf, p_bsdf, n_light, p_light),
            Mis::LightOnly => 0.0,
            Mis::BsdfOnly => 1.0,
        }
    }
}

impl MisHeuristic {
    /// Weight of `n_a` samples of density `p_a` against `n_b` samples of the other strategy,
    /// whose density `p_b()` is evaluated only if `n_b > 0` (else the weight is 1).
    #[inline(always)]
    fn weight(self, n_a: u32, p_a: f32, n_b: u32, p_b: impl FnOnce() -> f32) -> f32 {
        if n_b == 0 {
            return 1.0;
        }
        let pb = p_b();
        match self {
            MisHeuristic::Power => power_heuristic(n_a, p_a, n_b, pb),
            MisHeuristic::Balance => balance_heuristic(n_a, p_a, n_b, pb),
        }
    }
}

/// The vertex a path left from, as MIS at the next vertex needs it.
#[derive(Clone, Copy, Debug)]
pub struct PrevVertex {
    /// Where lights would have been sampled from (the light sampler's context).
    pub ctx: LightSampleContext,
    /// Density (solid angle) of the direction the path took from it.
    pub pdf: f32,
    /// Whether that direction came from a delta distribution (specular), which light sampling
    /// cannot produce.
    pub delta: bool,
}

/// Weight of emission found along a path (rather than by light sampling): 1 (or 0 with
/// `hide_emitters`) for camera rays (`prev` is `None`); 1 after a specular bounce; otherwise the
/// BSDF sample's MIS weight against light sampling from `prev`, whose density `pdf_light(ctx)`
/// (light selection included) is evaluated only if needed.
#[inline]
pub fn emission_weight(
    prev: Option<&PrevVertex>,
    hide_emitters: bool,
    mis: &Mis,
    pdf_light: impl FnOnce(&LightSampleContext) -> f32,
) -> f32 {
    match prev {
        None => f32::from(u8::from(!hide_emitters)),
        Some(v) if v.delta => 1.0,
        Some(v) => mis.bsdf_weight(v.pdf, || pdf_light(&v.ctx)),
    }
}

/// The escaped-ray rule: a ray from `o` that leaves the scene in unit direction `d` sees each
/// light at infinity; `add(Lₑ, w)` receives each one's radiance with its [`emission_weight`]
/// (`prev`: the vertex the ray left, `None` for camera rays).
#[inline]
pub fn escaped(
    scene: &Scene,
    o: Vec3,
    d: Vec3,
    prev: Option<&PrevVertex>,
    hide_emitters: bool,
    mis: &Mis,
    mut add: impl FnMut(Rgb, f32),
) {
    // Where the weight compares with light sampling, the light's density comes with its radiance.
    let p_ref = prev.filter(|v| !v.delta && mis.needs_light_pdf()).map(|v| v.ctx.p);
    for &i in scene.infinite_lights() {
        let light = &scene.lights()[i as usize];
        let (le, pdf) = light.le_pdf_escaped(o, d, p_ref);
        if le == Rgb::ZERO {
            continue;
        }
        let w = emission_weight(prev, hide_emitters, mis, |ctx| scene.light_pmf(ctx, i) * pdf);
        add(le, w);
    }
}

/// Light-sampling density (selection included) from `ctx` of the point `p` (geometric normal
/// `ng`) on light `i`: what [`emission_weight`] compares a BSDF sample with at an emitter hit.
#[inline]
pub fn light_pdf_at(scene: &Scene, ctx: &LightSampleContext, i: u32, p: Vec3, ng: Vec3) -> f32 {
    scene.light_pmf(ctx, i) * scene.lights()[i as usize].pdf_li(scene.geometries(), ctx.p, p, ng)
}

/// One light sample at `ctx` (Mitsuba's `sample_emitter_direction` with the BSDF's `eval_pdf`):
/// `eval(ω, with_pdf)` is the BSDF × cosine or phase value toward the unit world direction `ω`
/// and, where `with_pdf` (MIS against a light that BSDF sampling can reach), its sampling
/// density (else any number: it is not read); `visibility(sample)` the fraction of light that
/// arrives (0 or 1 for occlusion, the transmittance through media; see [`occlusion`]). Returns
/// `value Lₑ Tr w / (P(l) p_l n_light)` (module docs), zero when nothing arrives.
#[inline(always)]
pub fn sample_direct(
    scene: &Scene,
    ctx: &LightSampleContext,
    u: f32,
    u2: Vec2,
    mis: &Mis,
    eval: impl FnOnce(Vec3, bool) -> (Rgb, f32),
    visibility: impl FnOnce(&LightSample) -> Rgb,
) -> Rgb {
    let n_light = match *mis {
        Mis::Combine { n_light, .. } => n_light.max(1),
        Mis::LightOnly => 1,
        Mis::BsdfOnly => return Rgb::ZERO,
    };
    let Some((index, pmf)) = scene.sample_light(ctx, u) else { return Rgb::ZERO };
    let light = &scene.lights()[index as usize];
    // An MIS-compensated density leaves directions to BSDF sampling: only where it is combined.
    let ls = if mis.needs_bsdf_pdf() {
        light.sample_li(scene.geometries(), ctx.p, u2)
    } else {
        light.sample_li_complete(scene.geometries(), ctx.p, u2)
    };
    let Some(ls) = ls else { return Rgb::ZERO };
    // The density is computed with the value, before the shadow ray (Mitsuba traces that
    // first): sharing their terms costs less than the density alone after the shadow ray, even
    // where the light turns out occluded.
    let (f, pdf) = eval(ls.wi, !ls.delta && mis.needs_bsdf_pdf());
    if f == Rgb::ZERO {
        return Rgb::ZERO;
    }
    let tr = visibility(&ls);
    if tr == Rgb::ZERO {
        return Rgb::ZERO;
    }
    if ls.delta {
        f * ls.li * tr / (pmf * n_light as f32)
    } else {
        let p_light = pmf * ls.pdf;
        let w = mis.light_weight(p_light, || pdf);
        f * ls.li * tr * (w / (p_light * n_light as f32))
    }
}

/// A surface vertex as its BSDF sees it: the BSDF, where on the surface, the shading frame and the
/// outgoing direction in it.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceVertex<'a> {
    /// The BSDF.
    pub bsdf: &'a Bsdf,
    /// Texture coordinates for textured parameters.
    pub ctx: BsdfContext<'a>,
    /// Shading frame (normal on +z).
    pub frame: Frame,
    /// Unit direction toward the previous vertex, in `frame`.
    pub wo_local: Vec3,
}

impl<'a> SurfaceVertex<'a> {
    /// The vertex at `si` as `bsdf` sees it from the unit world direction `wo`, its texture
    /// lookups kept in `memo`. Made in place: the context is not copied after its fields were
    /// written (a copy right after such stores waits for them to reach the cache).
    #[inline(always)]
    pub fn new(
        scene: &'a Scene,
        si: &'a SurfaceInteraction,
        bsdf: &'a Bsdf,
        memo: &'a crate::material::TextureMemo,
        wo: Vec3,
    ) -> SurfaceVertex<'a> {
        let frame = si.frame();
        let wo_local = frame.to_local(wo);
        SurfaceVertex { bsdf, ctx: scene.bsdf_context(si).with_memo(memo), frame, wo_local }
    }

    /// BSDF × |cos θᵢ| toward the unit world direction `wi`.
    #[inline]
    pub fn eval(&self, wi: Vec3) -> Rgb {
        self.bsdf.eval(&self.ctx, self.wo_local, self.frame.to_local(wi))
    }

    /// [`SurfaceVertex::eval`] and, where `with_pdf`, the BSDF's sampling density (solid angle)
    /// of the unit world direction `wi` (0 otherwise), computed together.
    #[inline]
    pub fn eval_pdf(&self, wi: Vec3, with_pdf: bool) -> (Rgb, f32) {
        let wi = self.frame.to_local(wi);
        if with_pdf {
            self.bsdf.eval_pdf(&self.ctx, self.wo_local, wi)
        } else {
            (self.bsdf.eval(&self.ctx, self.wo_local, wi), 0.0)
        }
    }
}

/// [`sample_direct`] at a surface vertex `v`, with its BSDF as value and density; `u` are the
/// light selection and position numbers.
#[inline(always)]
pub fn sample_direct_bsdf(
    scene: &Scene,
    ctx: &LightSampleContext,
    u: (f32, Vec2),
    mis: &Mis,
    v: &SurfaceVertex,
    visibility: impl FnOnce(&LightSample) -> Rgb,
) -> Rgb {
    sample_direct(scene, ctx, u.0, u.1, mis, |wi, with_pdf| v.eval_pdf(wi, with_pdf), visibility)
}

/// Visibility of a light sample from a surface point by a shadow ray (no media): 1 or 0.
#[inline]
pub fn occlusion<'a>(scene: &'a Scene, si: &'a SurfaceInteraction) -> impl FnOnce(&LightSample) -> Rgb + 'a {
    move |ls| if scene.occluded(&si.spawn_ray_to(ls.p, ls.n, ls.p_error)) { Rgb::ZERO } else { Rgb::ONE }
}

/// Follows a camera ray through emitters hidden from the camera (`hide_emitters`): the first
/// hit that is not an emitting shape, after at most [`MAX_HIDDEN_SKIPS`] of them (`None` if the
/// ray escapes or gives up); `ray` becomes the ray that reached it (to take its direction). The
/// hidden emitters passed through do not cover the pixel (Mitsuba's `valid_ray`). The hit comes
/// with its surface interaction not yet computed: the caller computes it where it keeps it.
#[inline]
pub fn skip_hidden_emitters<'a>(
    scene: &'a Scene,
    ray: &'a mut Ray,
    slot: &'a mut crate::scene::HitSlot,
) -> Option<crate::scene::DeferredHit<'a>> {
    scene.intersect_deferred_past_emitters(ray, MAX_HIDDEN_SKIPS, slot)
}

impl PathSettings {
    /// Mitsuba's `max_depth` (-1), `rr_depth` (5) and `hide_emitters` (false), checked.
    pub fn from_props(o: &Obj) -> PropResult<PathSettings> {
        PathSettings::from_props_with_depth(o, -1)
    }

    /// [`PathSettings::from_props`] with another default `max_depth` (Mitsuba's differentiable
    /// integrators, `prb` and its kin, default to 6).
    pub fn from_props_with_depth(o: &Obj, default_max_depth: i64) -> PropResult<PathSettings> {
        PathSettings::new(
            o.int("max_depth", default_max_depth)?,
            o.int("rr_depth", 5)?,
            o.bool("hide_emitters", false)?,
        )
        .map_err(|(name, message)| o.error_at(name, message))
    }
}

/// A generator for the random decisions a path makes in unbounded number (delta and ratio
/// tracking's collisions), seeded from two of the sampler's numbers so that it is as
/// deterministic as the sampler.
pub fn path_rng(sampler: &mut crate::sampling::Sampler) -> crate::sampling::Pcg32 {
    use crate::sampling::hash::hash;
    let (a, b) = (sampler.next_1d(), sampler.next_1d());
    crate::sampling::Pcg32::new(hash(&[u64::from(a.to_bits())]), hash(&[u64::from(b.to_bits()), 1]))
}

/// A camera sample's coverage (the alpha channel), Mitsuba 3's rule: 1 if the path hit a
/// surface, or if an environment (constant or envmap emitter) is there to be seen
/// (`hide_emitters` off); else 0.
#[inline]
pub fn coverage(scene: &Scene, hit_surface: bool, hide_emitters: bool) -> f32 {
    f32::from(u8::from(hit_surface || (!hide_emitters && !scene.infinite_lights().is_empty())))
}


#[cfg(test)]
mod tests {
    use super::*;

    /// The two weights of one sample pair sum to one for every heuristic and sample count, and
    /// the single-strategy settings give 1 to their strategy and 0 to the other.
    #[test]
    fn light_and_bsdf_weights_are_complementary() {
        for heuristic in [MisHeuristic::Power, MisHeuristic::Balance] {
            for (n_light, n_bsdf) in [(1, 1), (2, 3), (4, 1)] {
                let mis = Mis::Combine { heuristic, n_light, n_bsdf };
                for (pl, pb) in [(0.3f32, 2.0f32), (1.0, 1.0), (7.0, 0.01)] {
                    let s = mis.light_weight(pl, || pb) + mis.bsdf_weight(pb, || pl);
                    assert!((s - 1.0).abs() < 1e-6, "{mis:?} {pl} {pb}: {s}");
                }
            }
        }
        assert_eq!(Mis::LightOnly.light_weight(0.5, || panic!("not needed")), 1.0);
        assert_eq!(Mis::LightOnly.bsdf_weight(0.5, || panic!("not needed")), 0.0);
        assert_eq!(Mis::BsdfOnly.bsdf_weight(0.5, || panic!("not needed")), 1.0);
        let no_bsdf = Mis::Combine { heuristic: MisHeuristic::Power, n_light: 1, n_bsdf: 0 };
        assert_eq!(no_bsdf.light_weight(0.5, || panic!("not needed")), 1.0);
    }

    /// Inside a closed white sphere (albedo 1, lit by a point light) with Russian roulette held
    /// off, no path ever loses its light: every integrator still ends each path at
    /// [`MAX_SEGMENTS`] segments (it would otherwise run for ever, deaf to an interrupt), and
    /// the image stays finite.
    #[test]
    fn lossless_closed_scenes_without_roulette_end() {
        use crate::camera::{Camera, FovAxis};
        use crate::geometry::{Geometry, Sphere};
        use crate::integrator::{LightTracer, PathIntegrator, VolPathIntegrator, VolPathMisIntegrator};
        use crate::material::{Bsdf, Diffuse};
        use crate::math::{Transform, Vec3};
        use crate::render::{render, render_light_paths, RenderSettings};
        use crate::scene::SceneBuilder;
        use std::sync::atomic::AtomicBool;
        let mut b = SceneBuilder::new();
        let white = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::ONE)));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 2.0, true)), white, None);
        b.add_point_light(Vec3::new(0.0, 1.0, 0.0), Rgb::ONE);
        b.set_camera(Camera::perspective(Transform::IDENTITY, 40.0, FovAxis::X, 1, 1).unwrap());
        let scene = b.build().unwrap();
        let settings = PathSettings { max_depth: -1, rr_depth: u32::MAX, hide_emitters: false };
        let run = RenderSettings { spp: 2, seed: 1, threads: 1, ..Default::default() };
        let never = AtomicBool::new(false);
        let images = [
            render(&scene, &PathIntegrator { settings, ..Default::default() }, &run, &never).unwrap(),
            render(&scene, &VolPathIntegrator { settings, regularize: false }, &run, &never).unwrap(),
            render(&scene, &VolPathMisIntegrator { settings }, &run, &never).unwrap(),
            render_light_paths(&scene, &LightTracer { settings }, &run, &never).unwrap(),
        ];
        for out in images {
            let px = out.film.image()[0];
            assert!(px.is_finite() && px.min_element() > 0.0, "{px}");
        }
    }

    #[test]
    fn path_settings_are_checked() {
        assert_eq!(PathSettings::new(-1, 5, false).unwrap(), PathSettings::default());
        assert_eq!(PathSettings::new(-2, 5, false).unwrap_err().0, "max_depth");
        assert_eq!(PathSettings::new(3, 0, false).unwrap_err().0, "rr_depth");
        let s = PathSettings::new(2, 5, true).unwrap();
        assert!(s.allows(2) && !s.allows(3) && s.max_segments() == 2 && s.depth_text() == "2");
        assert!(PathSettings::default().allows(MAX_SEGMENTS) && PathSettings::default().depth_text() == "unlimited");
        assert!(!PathSettings::default().allows(MAX_SEGMENTS + 1));
        assert_eq!(PathSettings::new(1 << 20, 5, false).unwrap().max_segments(), MAX_SEGMENTS);
    }
}
