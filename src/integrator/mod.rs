//! Integrators: estimators of the radiance arriving at the camera.
//!
//! An integrator implements [`Integrator::li`], one unbiased sample of the radiance along a
//! camera ray; the render driver averages them per pixel. The path tracer samples the Neumann
//! series `L = Σₖ Tᵏ Lₑ` term by term along one path per sample.

pub mod aov;
pub mod depth;
pub mod direct;
#[cfg(test)]
pub(crate) mod fixtures;
pub mod moment;
pub mod path;
mod path_lanes;
pub mod ptracer;
pub mod radiosity;
pub mod subsurface;
pub mod trace;
pub mod volpath;
pub mod volpathmis;

pub use aov::AovIntegrator;
pub use depth::DepthIntegrator;
pub use direct::DirectIntegrator;
pub use moment::MomentIntegrator;
pub use path::{DirectStrategy, MisHeuristic, PathIntegrator};
pub use ptracer::LightTracer;
pub use trace::{Mis, PathSettings};
pub use volpath::VolPathIntegrator;
pub use volpathmis::VolPathMisIntegrator;

use crate::camera::RayDifferentials;
use crate::math::{Ray, Rgb};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::Sampler;
use crate::scene::Scene;

/// One camera sample's outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadianceSample {
    /// Radiance arriving along the camera ray (W m⁻² sr⁻¹ per channel).
    pub l: Rgb,
    /// Coverage: 1 if the camera ray hit a surface (hidden emitters included), 0 if it escaped.
    pub alpha: f32,
}

/// An estimator of incident radiance along camera rays.
pub trait Integrator: Sync {
    /// Name (Mitsuba's plugin name where one exists).
    fn name(&self) -> &'static str;

    /// One sample along `ray` (toward its origin): the radiance and the coverage, with each
    /// contribution also added to `terms[k - 1]`, k the number of path segments it took
    /// (`terms[0]`: `Lₑ` seen directly, `terms[1]`: `T Lₑ`, …; the last entry collects all
    /// longer paths; pass an empty slice to skip them). The sampler is positioned at the pixel
    /// sample; the integrator draws its dimensions in a fixed order. The radiance is the same, bit
    /// for bit, whether terms are kept or not.
    fn sample(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, terms: &mut [Rgb]) -> RadianceSample;

    /// The radiance of [`Integrator::sample`] alone.
    fn li(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler) -> Rgb {
        self.sample(scene, ray, sampler, &mut []).l
    }

    /// Whether [`Integrator::sample`] separates the Neumann-series terms.
    fn has_terms(&self) -> bool {
        false
    }

    /// Names of the arbitrary output variables (AOVs) written by
    /// [`Integrator::sample_aovs`], one per image channel, as Mitsuba names them (`nn.X`,
    /// `m2__arg_0.Y`, …). Empty for integrators that estimate radiance alone.
    fn aov_names(&self) -> Vec<String> {
        Vec::new()
    }

    /// `aov_names().len()`, without building the names (what sampling needs per sample).
    fn aov_count(&self) -> usize {
        0
    }

    /// Whether [`Integrator::sample_aovs`] reads the camera ray's differentials (the render
    /// driver computes them only then).
    fn wants_differentials(&self) -> bool {
        false
    }

    /// How many camera samples [`Integrator::sample_lanes`] traces at once in `scene` (paths in
    /// SIMD lanes, [`crate::math::lanes`]), or 0 where it does not: the render loop then calls
    /// [`Integrator::sample_aovs`] sample by sample. Never asked with terms, AOVs or ray
    /// differentials.
    fn lanes(&self, _scene: &Scene) -> usize {
        0
    }

    /// [`Integrator::sample`] of `rays.len()` (at most [`Integrator::lanes`]) camera samples at
    /// once, `samplers[k]` the sampler of sample `k` positioned after its camera's draws; the
    /// results bit for bit those of `sample`, into `out`.
    fn sample_lanes(&self, scene: &Scene, rays: &[Ray], samplers: &mut [Sampler], out: &mut [RadianceSample]) {
        for ((ray, sampler), out) in rays.iter().zip(samplers).zip(out) {
            *out = self.sample(scene, ray, sampler, &mut []);
        }
    }

    /// [`Integrator::sample`] that also writes one value per [`Integrator::aov_names`] entry
    /// into `aovs` (which has that length). The render driver calls this one, with the camera
    /// ray's differentials scaled to the spacing of the render's samples where
    /// [`Integrator::wants_differentials`] (`None` elsewhere).
    fn sample_aovs(
        &self,
        scene: &Scene,
        ray: &Ray,
        _differentials: Option<&RayDifferentials>,
        sampler: &mut Sampler,
        terms: &mut [Rgb],
        _aovs: &mut [f32],
    ) -> RadianceSample {
        self.sample(scene, ray, sampler, terms)
    }
}

/// [`Integrator::sample`] of an integrator that writes AOVs, with them computed and dropped
/// (for callers that want the radiance alone).
pub(crate) fn sample_without_aovs(
    i: &dyn Integrator,
    scene: &Scene,
    ray: &Ray,
    sampler: &mut Sampler,
    terms: &mut [Rgb],
) -> RadianceSample {
    let mut aovs = vec![0.0; i.aov_count()];
    i.sample_aovs(scene, ray, None, sampler, terms, &mut aovs)
}

/// Russian roulette for camera paths from `rr_depth` on: survival probability
/// `q = min(max(β) η², 0.95)` and `β /= q` (η: product of the relative IORs crossed, undoing the
/// η² radiance scaling of refraction), drawn with `u`. Returns false when the path ends, also
/// when `β` is zero or NaN at any depth.
#[inline]
pub(crate) fn russian_roulette(beta: &mut Rgb, eta: f32, depth: u32, rr_depth: u32, u: f32) -> bool {
    let m = beta.max_element();
    if m <= 0.0 || m.is_nan() {
        return false;
    }
    if depth >= rr_depth {
        let q = (m * eta * eta).min(0.95);
        if u >= q {
            return false;
        }
        *beta /= q;
    }
    true
}

/// Which integrator (the names of scene files and the command line).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Path tracing with next-event estimation and MIS.
    Path,
    /// Direct lighting only.
    Direct,
    /// Light tracing.
    Ptracer,
    /// Radiosity.
    Radiosity,
    /// Volumetric path tracing.
    Volpath,
    /// Volumetric path tracing with spectral and null-scattering MIS.
    VolpathMis,
    /// Mean and second moment of nested integrators' samples.
    Moment,
    /// Arbitrary output variables (geometry, albedo) beside nested integrators' images.
    Aov,
    /// Distance to the first surface.
    Depth,
}

crate::choices!(IntegratorKind, "integrator", {
    IntegratorKind::Path => "path", "path tracing with next-event estimation and MIS (backward, from the camera)";
    IntegratorKind::Direct => "direct", "direct lighting only (Mitsuba's `direct`)";
    IntegratorKind::Ptracer => "ptracer", "light tracing (forward, from the emitters; Mitsuba's `ptracer`)";
    IntegratorKind::Radiosity => "radiosity", "radiosity: finite elements for diffuse scenes, solved then displayed";
    IntegratorKind::Volpath => "volpath", "volumetric path tracing: participating media (Mitsuba's `volpath`)";
    IntegratorKind::VolpathMis => "volpathmis", "volumetric path tracing with spectral and null-scattering MIS (Mitsuba's `volpathmis`)";
    IntegratorKind::Moment => "moment", "path tracing that also records each pixel's second moment as EXR layers (Mitsuba's `moment`)";
    IntegratorKind::Aov => "aov", "path tracing with every geometric AOV (albedo, depth, position, uv, normals, indices, tangents, uv derivatives) as EXR layers (Mitsuba's `aov`)";
    IntegratorKind::Depth => "depth", "the distance to the first surface along each camera ray, 0 where none (Mitsuba's `depth`)";
});

impl IntegratorKind {
    /// Whether the integrator samples lights by next-event estimation (and so takes neumann's
    /// `light_sampler`).
    pub fn samples_lights(self) -> bool {
        matches!(self, IntegratorKind::Path | IntegratorKind::Volpath | IntegratorKind::VolpathMis | IntegratorKind::Direct)
    }

    /// Whether the integrator renders participating media (others ignore them, as Mitsuba's).
    pub fn renders_media(self) -> bool {
        matches!(self, IntegratorKind::Volpath | IntegratorKind::VolpathMis)
    }
}

/// An integrator plugin's constructor.
pub type IntegratorPlugin = fn(&Obj) -> PropResult<AnyIntegrator>;

/// Every integrator plugin by its name (Mitsuba's where it has one).
pub const INTEGRATOR_PLUGINS: &[(&str, IntegratorPlugin)] = &[
    ("path", |o| {
        Ok(AnyIntegrator::Path(PathIntegrator {
            settings: PathSettings::from_props(o)?,
            regularize: o.bool("regularize", false)?,
            ..Default::default()
        }))
    }),
    ("volpath", |o| {
        Ok(AnyIntegrator::VolPath(VolPathIntegrator {
            settings: PathSettings::from_props(o)?,
            regularize: o.bool("regularize", false)?,
        }))
    }),
    ("volpathmis", |o| Ok(AnyIntegrator::VolPathMis(VolPathMisIntegrator { settings: PathSettings::from_props(o)? }))),
    ("ptracer", |o| Ok(AnyIntegrator::Ptracer(LightTracer { settings: PathSettings::from_props(o)? }))),
    ("direct", |o| Ok(AnyIntegrator::Direct(DirectIntegrator::from_props(o)?))),
    ("radiosity", |o| Ok(AnyIntegrator::Radiosity(radiosity::Options::from_props(o)?))),
    // Mitsuba's differentiable and MIS variants render, in primal mode, the same expected image
    // as the estimator they extend (they differ in gradients or in noise): neumann renders them
    // with that estimator, with their defaults (max_depth 6, as Mitsuba's `ADIntegrator`).
    ("prb", |o| Ok(AnyIntegrator::Path(differentiable_path(o)?))),
    ("prb_basic", |o| Ok(AnyIntegrator::Path(differentiable_path(o)?))),
    ("prbvolpath", |o| {
        Ok(AnyIntegrator::VolPath(VolPathIntegrator { settings: PathSettings::from_props_with_depth(o, 6)?, regularize: false }))
    }),
    ("prb_projective", |o| {
        projective_props(o)?;
        Ok(AnyIntegrator::Path(differentiable_path(o)?))
    }),
    // Direct illumination whatever `max_depth` and `rr_depth` say (Mitsuba sets both to 2).
    ("direct_projective", |o| {
        projective_props(o)?;
        let mut path = differentiable_path(o)?;
        (path.settings.max_depth, path.settings.rr_depth) = (2, 2);
        Ok(AnyIntegrator::Path(path))
    }),
    ("moment", |o| Ok(AnyIntegrator::Moment(MomentIntegrator::from_props(o)?))),
    ("aov", |o| Ok(AnyIntegrator::Aov(AovIntegrator::from_props(o)?))),
    ("depth", |o| Ok(AnyIntegrator::Depth(DepthIntegrator::from_props(o)?))),
];

/// The path tracer of Mitsuba's `prb` family: `path`'s settings with max_depth 6 by default.
fn differentiable_path(o: &Obj) -> PropResult<PathIntegrator> {
    Ok(PathIntegrator { settings: PathSettings::from_props_with_depth(o, 6)?, ..Default::default() })
}

/// The parameters of Mitsuba's projective-sampling integrators (`prb_projective`,
/// `direct_projective`), checked as Mitsuba checks them: they steer only the sampling of
/// gradients at discontinuities, never the rendered image.
fn projective_props(o: &Obj) -> PropResult<()> {
    for name in ["sppc", "sppp", "sppi", "guiding_rounds"] {
        if o.int(name, 0)? < 0 {
            return Err(o.error_at(name, format!("'{name}' must be ≥ 0")));
        }
    }
    o.choice("guiding", &["octree", "none", "grid"])?;
    o.bool("guiding_proj", true)?;
    o.choice("project_seed", &["both", "bsdf", "emitter"])?;
    Ok(())
}

/// The integrators nested in `o` (Mitsuba's `moment` and `aov`), in document order, each with
/// its name: the `name` attribute, else `_arg_0`, `_arg_1`, … counting the unnamed ones (as
/// Mitsuba 3 names them). Only camera-ray integrators may be nested.
pub fn nested_integrators(o: &Obj) -> PropResult<Vec<(String, AnyIntegrator)>> {
    o.check_children(&["integrator"])?;
    let mut found: Vec<(usize, Option<String>, std::rc::Rc<Obj>)> =
        o.children.iter().map(|c| (c.loc.offset, None, c.clone())).collect();
    for p in &o.props {
        if let crate::props::Value::Object(c) = &p.value {
            if c.tag == "integrator" {
                p.used.set(true);
                found.push((p.loc.offset, Some(p.name.clone()), c.clone()));
            }
        }
    }
    found.sort_by_key(|f| f.0);
    let mut unnamed = 0;
    let mut out = Vec::new();
    for (_, name, c) in found {
        let name = name.unwrap_or_else(|| {
            unnamed += 1;
            format!("_arg_{}", unnamed - 1)
        });
        let integrator = integrator_from_props(&c)?;
        if integrator.camera().is_none() {
            return Err(crate::props::SceneError::at(
                &c.loc,
                format!(
                    "the {} integrator cannot be nested in '{}': only integrators that trace camera rays can",
                    c.ty, o.ty
                ),
            ));
        }
        out.push((name, integrator));
    }
    Ok(out)
}

/// The constructor of the integrator plugin `name`.
pub fn integrator_plugin(name: &str) -> Option<IntegratorPlugin> {
    INTEGRATOR_PLUGINS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// The integrator `o` describes, built by its plugin (an unknown plugin name is a located error
/// listing the names, with the nearest).
pub fn integrator_from_props(o: &Obj) -> PropResult<AnyIntegrator> {
    o.built.set(true);
    let plugin = integrator_plugin(&o.ty)
        .ok_or_else(|| o.unknown_plugin(&INTEGRATOR_PLUGINS.iter().map(|p| p.0).collect::<Vec<_>>()))?;
    plugin(o)
}

/// One of neumann's integrators, chosen at run time (by the scene file or the command line).
/// The render driver (`render::render_integrator`) renders it.
#[derive(Clone, Debug)]
pub enum AnyIntegrator {
    /// Mitsuba's `path`.
    Path(PathIntegrator),
    /// Mitsuba's `direct`.
    Direct(DirectIntegrator),
    /// Mitsuba's `ptracer` (light tracing).
    Ptracer(LightTracer),
    /// neumann's `radiosity` (finite elements; solved before rendering).
    Radiosity(radiosity::Options),
    /// Mitsuba's `volpath` (path tracing with participating media).
    VolPath(VolPathIntegrator),
    /// Mitsuba's `volpathmis` (volumetric path tracing with spectral MIS).
    VolPathMis(VolPathMisIntegrator),
    /// Mitsuba's `moment` (nested integrators' mean and second moment).
    Moment(MomentIntegrator),
    /// Mitsuba's `aov` (arbitrary output variables).
    Aov(AovIntegrator),
    /// Mitsuba's `depth` (distance to the first surface).
    Depth(DepthIntegrator),
}

impl Default for AnyIntegrator {
    fn default() -> Self {
        AnyIntegrator::Path(PathIntegrator::default())
    }
}

impl AnyIntegrator {
    /// Which integrator this is.
    pub fn kind(&self) -> IntegratorKind {
        match self {
            AnyIntegrator::Path(_) => IntegratorKind::Path,
            AnyIntegrator::Direct(_) => IntegratorKind::Direct,
            AnyIntegrator::Ptracer(_) => IntegratorKind::Ptracer,
            AnyIntegrator::Radiosity(_) => IntegratorKind::Radiosity,
            AnyIntegrator::VolPath(_) => IntegratorKind::Volpath,
            AnyIntegrator::VolPathMis(_) => IntegratorKind::VolpathMis,
            AnyIntegrator::Moment(_) => IntegratorKind::Moment,
            AnyIntegrator::Aov(_) => IntegratorKind::Aov,
            AnyIntegrator::Depth(_) => IntegratorKind::Depth,
        }
    }

    /// The integrator as a camera-ray integrator (all but the light tracer and radiosity, which
    /// the render driver runs its own way).
    pub fn camera(&self) -> Option<&dyn Integrator> {
        match self {
            AnyIntegrator::Path(i) => Some(i),
            AnyIntegrator::Direct(i) => Some(i),
            AnyIntegrator::VolPath(i) => Some(i),
            AnyIntegrator::VolPathMis(i) => Some(i),
            AnyIntegrator::Moment(i) => Some(i),
            AnyIntegrator::Aov(i) => Some(i),
            AnyIntegrator::Depth(i) => Some(i),
            AnyIntegrator::Ptracer(_) | AnyIntegrator::Radiosity(_) => None,
        }
    }

    /// Plugin name.
    pub fn name(&self) -> &'static str {
        crate::choice::Choice::name(self.kind())
    }

    /// The integrator `kind` with its default settings, keeping the path-length settings
    /// `settings` where it has them (`hide_emitters` for `direct`). `moment` wraps a path tracer;
    /// `aov` wraps a path tracer and records every AOV type, each named after its type.
    pub fn with_kind(kind: IntegratorKind, settings: PathSettings) -> AnyIntegrator {
        match kind {
            IntegratorKind::Path => AnyIntegrator::Path(PathIntegrator { settings, ..Default::default() }),
            IntegratorKind::Direct => {
                AnyIntegrator::Direct(DirectIntegrator { hide_emitters: settings.hide_emitters, ..Default::default() })
            }
            IntegratorKind::Ptracer => AnyIntegrator::Ptracer(LightTracer { settings }),
            IntegratorKind::Radiosity => AnyIntegrator::Radiosity(radiosity::Options::default()),
            IntegratorKind::Volpath => AnyIntegrator::VolPath(VolPathIntegrator { settings, regularize: false }),
            IntegratorKind::VolpathMis => AnyIntegrator::VolPathMis(VolPathMisIntegrator { settings }),
            IntegratorKind::Moment => {
                let path = AnyIntegrator::with_kind(IntegratorKind::Path, settings);
                AnyIntegrator::Moment(MomentIntegrator { nested: vec![("_arg_0".into(), path)] })
            }
            IntegratorKind::Aov => {
                use crate::choice::Choice;
                let path = AnyIntegrator::with_kind(IntegratorKind::Path, settings);
                let aovs = aov::AovKind::CHOICES.iter().map(|c| (c.1.to_string(), c.0)).collect();
                AnyIntegrator::Aov(AovIntegrator { aovs, nested: vec![("_arg_0".into(), path)], image_layers: true })
            }
            IntegratorKind::Depth => AnyIntegrator::Depth(DepthIntegrator),
        }
    }

    /// The path-length settings of the path-space integrators (`path`, `volpath`, `ptracer`).
    pub fn path_settings(&self) -> Option<&PathSettings> {
        match self {
            AnyIntegrator::Path(p) => Some(&p.settings),
            AnyIntegrator::Ptracer(t) => Some(&t.settings),
            AnyIntegrator::VolPath(v) => Some(&v.settings),
            AnyIntegrator::VolPathMis(v) => Some(&v.settings),
            AnyIntegrator::Moment(m) => m.nested[0].1.path_settings(),
            AnyIntegrator::Aov(a) => a.nested.first()?.1.path_settings(),
            AnyIntegrator::Direct(_) | AnyIntegrator::Radiosity(_) | AnyIntegrator::Depth(_) => None,
        }
    }

    /// Mutable [`AnyIntegrator::path_settings`].
    pub fn path_settings_mut(&mut self) -> Option<&mut PathSettings> {
        match self {
            AnyIntegrator::Path(p) => Some(&mut p.settings),
            AnyIntegrator::Ptracer(t) => Some(&mut t.settings),
            AnyIntegrator::VolPath(v) => Some(&mut v.settings),
            AnyIntegrator::VolPathMis(v) => Some(&mut v.settings),
            AnyIntegrator::Moment(m) => m.nested[0].1.path_settings_mut(),
            AnyIntegrator::Aov(a) => a.nested.first_mut()?.1.path_settings_mut(),
            AnyIntegrator::Direct(_) | AnyIntegrator::Radiosity(_) | AnyIntegrator::Depth(_) => None,
        }
    }

    /// One line describing the integrator and its main settings.
    pub fn describe(&self) -> String {
        match self {
            AnyIntegrator::Path(p) => format!("path tracer, max_depth {}", p.settings.depth_text()),
            AnyIntegrator::Direct(d) => {
                format!("direct lighting, {} emitter + {} BSDF samples", d.emitter_samples, d.bsdf_samples)
            }
            AnyIntegrator::Ptracer(t) => format!("light tracer, max_depth {}", t.settings.depth_text()),
            AnyIntegrator::VolPath(v) => format!("volumetric path tracer, max_depth {}", v.settings.depth_text()),
            AnyIntegrator::VolPathMis(v) => {
                format!("volumetric path tracer with spectral MIS, max_depth {}", v.settings.depth_text())
            }
            AnyIntegrator::Radiosity(o) => format!(
                "radiosity, patch size {}, {} form-factor rays per patch, {}{}",
                o.patch_size,
                o.rays_per_patch,
                o.method,
                if o.smooth { ", smooth" } else { ", flat" }
            ),
            AnyIntegrator::Moment(m) => format!("moments of {}", describe_nested(&m.nested)),
            AnyIntegrator::Depth(_) => "distance to the first surface".into(),
            AnyIntegrator::Aov(a) if !a.image_layers && a.nested.len() == 1 => format!(
                "{}, AOVs {}",
                a.nested[0].1.describe(),
                a.aovs.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ")
            ),
            AnyIntegrator::Aov(a) => format!(
                "AOVs [{}] beside {}",
                a.aovs.iter().map(|(n, k)| format!("{n}:{k}")).collect::<Vec<_>>().join(", "),
                describe_nested(&a.nested)
            ),
        }
    }
}

/// "name (description), …" of nested integrators.
fn describe_nested(nested: &[(String, AnyIntegrator)]) -> String {
    if nested.is_empty() {
        return "no nested integrator".into();
    }
    nested.iter().map(|(n, i)| format!("{n} ({})", i.describe())).collect::<Vec<_>>().join(", ")
}
