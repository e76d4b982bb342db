//! Participating media: Mitsuba's `homogeneous` ([`homogeneous`]) and `heterogeneous`
//! ([`heterogeneous`], on the volume textures of [`volume`]) media, with a phase function
//! ([`phase`]).
//!
//! A medium has extinction `σₜ` (m⁻¹, per colour channel), single-scattering albedo
//! `α = σₛ / σₜ` and a phase function. Media sit inside shapes (`interior`, `exterior` on the
//! shape) and around the camera (the sensor's medium). A shape with a `null` BSDF is an
//! index-matched boundary: rays cross it and change medium.
//!
//! An integrator asks a medium three things along a ray segment: where the next real
//! interaction is ([`Medium::sample_free_flight`], with the throughput weight that keeps the
//! estimate unbiased), how much light gets through ([`Medium::transmittance`], exact for
//! homogeneous media, an unbiased estimate for heterogeneous ones), and, for an emissive medium
//! (neumann's `radiance`, pbrt-v4's `Le`), how much light it emits along the segment toward the
//! segment's start ([`Medium::emitted`]).

pub mod heterogeneous;
pub mod homogeneous;
pub mod majorant;
pub mod phase;
pub mod presets;

/// Volume textures (in the texture layer: Mitsuba's `volume` surface texture reads them too).
pub use crate::texture::volume;
pub use heterogeneous::Heterogeneous;
pub use homogeneous::Homogeneous;
pub use phase::PhaseFunction;

use crate::image::VolumeSource;
use crate::math::spectrum::SpectrumKind;
use crate::math::{Ray, Rgb};
use crate::props::{Obj, Result as PropResult, SceneError};
use crate::sampling::{sample_exponential, Pcg32};

/// What a free-flight sample found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FreeFlight {
    /// A scattering event at distance `t`; `weight` (for homogeneous media `σₛ Tr(t) / p(t)`)
    /// multiplies the path throughput (absorption included: the path continues with the
    /// scattered fraction).
    Scatter {
        /// Distance along the (unit-direction) ray.
        t: f32,
        /// Throughput factor.
        weight: Rgb,
    },
    /// No interaction before `t_max` (the next surface); `weight` (homogeneous:
    /// `Tr(t_max) / P(pass)`) multiplies the throughput.
    Pass {
        /// Throughput factor.
        weight: Rgb,
    },
}

/// A tentative collision along a ray (Mitsuba's `sample_interaction`), for integrators that
/// weigh the tracking decisions themselves (`volpathmis`): collisions are drawn at the rate of
/// the majorant in one channel along the part of the segment where the medium is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tentative {
    /// The majorant's optical depth per channel from the segment's start to the collision, or
    /// to the segment's end where there is none (`∫ σ̄ dt`, zero outside the medium).
    pub optical_depth: Rgb,
    /// The majorant per channel at the collision (homogeneous media: σₜ, so every collision is
    /// real; heterogeneous ones: the bound σ̄ of the collision's cell, grey); zero without one.
    pub majorant: Rgb,
    /// The collision, if one was drawn before `t1`.
    pub collision: Option<Collision>,
}

impl Tentative {
    /// The free flight's density per channel (at the collision: `σ̄(t) e^(-∫σ̄)`; passing to the
    /// end: `e^(-∫σ̄)`) and its majorant transmittance `e^(-∫σ̄)`.
    #[inline]
    pub fn pdf_and_transmittance(&self) -> (Rgb, Rgb) {
        let tr = (-self.optical_depth).exp();
        (if self.collision.is_some() { tr * self.majorant } else { tr }, tr)
    }
}

/// The coefficients at a tentative collision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collision {
    /// Distance along the ray.
    pub t: f32,
    /// Extinction σₜ (m⁻¹).
    pub sigma_t: Rgb,
    /// Scattering σₛ = α σₜ.
    pub sigma_s: Rgb,
    /// Null extinction σₙ = majorant − σₜ.
    pub sigma_n: Rgb,
}

/// The coefficients of a medium (closed set).
#[derive(Clone, Debug)]
pub enum Coefficients {
    /// Constant everywhere.
    Homogeneous(Homogeneous),
    /// From volume textures.
    Heterogeneous(Box<Heterogeneous>),
}

/// A participating medium.
#[derive(Clone, Debug)]
pub struct Medium {
    /// Extinction and albedo.
    pub coefficients: Coefficients,
    /// Phase function.
    pub phase: PhaseFunction,
    /// Whether paths scattering in the medium sample emitters (next-event estimation; Mitsuba's
    /// `sample_emitters`, true). Off, light is found by phase sampling alone (same expectation;
    /// faster where shadow rays cannot get out, e.g. inside a dielectric).
    pub sample_emitters: bool,
    /// Emitted radiance `Lₑ(x)` (W m⁻² sr⁻¹ per channel, world space; pbrt-v4's emissive media):
    /// the medium adds `σₐ(x) Lₑ(x)` per unit length to the radiance along every ray through
    /// it, `σₐ = σₜ (1 − α)`. `None`: it emits nothing. A homogeneous medium's is constant.
    pub radiance: Option<volume::Volume>,
}

impl Medium {
    /// A homogeneous medium; `None` unless σₜ ≥ 0 (finite) and the albedo lies in [0, 1].
    pub fn homogeneous(sigma_t: Rgb, albedo: Rgb, phase: PhaseFunction) -> Option<Medium> {
        let ok = (0..3).all(|c| sigma_t[c] >= 0.0 && sigma_t[c].is_finite() && (0.0..=1.0).contains(&albedo[c]));
        ok.then_some(Medium {
            coefficients: Coefficients::Homogeneous(Homogeneous { sigma_t, albedo }),
            phase,
            sample_emitters: true,
            radiance: None,
        })
    }

    /// The light this medium emits along `ray` (unit direction) over `[0, t_max)` toward the
    /// ray's origin, `∫₀^t_max Tr(0, t) σₐ(x_t) Lₑ(x_t) dt` (zero for a medium that does not
    /// emit): exact for homogeneous media, `σₐ Lₑ (1 − e^(−σₜ t_max)) / σₜ` per channel; for
    /// heterogeneous ones an unbiased estimate (the collision estimator over a ratio-tracking
    /// walk, numbers from `rng`; [`Heterogeneous::emitted`]).
    #[inline]
    pub fn emitted(&self, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> Rgb {
        let Some(radiance) = &self.radiance else { return Rgb::ZERO };
        match &self.coefficients {
            Coefficients::Homogeneous(h) => h.emitted(radiance.eval(ray.o), t_max),
            Coefficients::Heterogeneous(h) => h.emitted(ray, t_max, radiance, rng),
        }
    }

    /// Whether the coefficients vary (tracking needs a random-number generator).
    #[inline]
    pub fn is_heterogeneous(&self) -> bool {
        matches!(self.coefficients, Coefficients::Heterogeneous(_))
    }

    /// Samples the distance to the next interaction along `ray` (unit direction) up to `t_max`
    /// (possibly infinite). `beta` is the path throughput so far, `u_channel` and `u` the
    /// sampler's numbers for this flight, `rng` the rest (heterogeneous media only).
    #[inline]
    pub fn sample_free_flight(
        &self,
        ray: &Ray,
        t_max: f32,
        beta: Rgb,
        u_channel: f32,
        u: f32,
        rng: &mut Pcg32,
    ) -> FreeFlight {
        match &self.coefficients {
            Coefficients::Homogeneous(h) => h.sample_free_flight(t_max, u_channel, u),
            Coefficients::Heterogeneous(h) => h.sample_free_flight(ray, t_max, beta, u, rng),
        }
    }

    /// Draws a tentative collision along `ray` (unit direction) before `t_max` at the majorant
    /// rate of `channel`, from `u`.
    #[inline]
    pub fn sample_tentative(&self, ray: &Ray, t_max: f32, channel: usize, u: f32) -> Tentative {
        match &self.coefficients {
            Coefficients::Homogeneous(h) => {
                let sigma = h.sigma_t[channel];
                let t = if sigma > 0.0 { sample_exponential(u, sigma).value } else { f32::INFINITY };
                let collision = (t < t_max).then_some(Collision {
                    t,
                    sigma_t: h.sigma_t,
                    sigma_s: h.sigma_t * h.albedo,
                    sigma_n: Rgb::ZERO,
                });
                let end = collision.map_or(t_max, |c| c.t);
                Tentative { optical_depth: h.sigma_t * end, majorant: h.sigma_t, collision }
            }
            Coefficients::Heterogeneous(h) => h.sample_tentative(ray, t_max, u),
        }
    }

    /// Transmittance along `ray` (unit direction) over `[0, t_max)`: exact for homogeneous
    /// media, an unbiased estimate (ratio tracking, numbers from `rng`) for heterogeneous ones.
    #[inline]
    pub fn transmittance(&self, ray: &Ray, t_max: f32, rng: &mut Pcg32) -> Rgb {
        match &self.coefficients {
            Coefficients::Homogeneous(h) => h.transmittance(t_max),
            Coefficients::Heterogeneous(h) => h.transmittance(ray, t_max, rng),
        }
    }
}

/// A medium plugin's constructor (`files` reads grid volumes).
pub type MediumPlugin = fn(&Obj, &mut dyn VolumeSource) -> PropResult<Medium>;

/// Every medium plugin by its (Mitsuba) name.
pub const MEDIUM_PLUGINS: &[(&str, MediumPlugin)] =
    &[("homogeneous", homogeneous_from_props), ("heterogeneous", heterogeneous_from_props)];

/// What every medium plugin reads: one nested `<phase>` (isotropic if none; see
/// [`PhaseFunction::from_props`]), `sample_emitters` (true) and `has_spectral_extinction`
/// (true; see below). `radiance` is the plugin's own.
fn common(
    o: &Obj,
    coefficients: Coefficients,
    radiance: Option<volume::Volume>,
    files: &mut dyn VolumeSource,
) -> PropResult<Medium> {
    o.check_children(&["phase"])?;
    let phases = o.nested("phase");
    if phases.len() > 1 {
        return Err(SceneError::at(&phases[1].loc, "a medium takes one <phase>"));
    }
    let phase = match phases.first() {
        None => PhaseFunction::Isotropic,
        Some(p) => PhaseFunction::from_props(p, files)?,
    };
    let sample_emitters = o.bool("sample_emitters", true)?;
    // Mitsuba's `has_spectral_extinction` (true): false tells Mitsuba's integrators that the
    // extinction is the same in every channel, so that they track one channel without spectral
    // MIS. neumann tracks spectrally either way: the same image where the extinction is grey,
    // the unbiased one (which Mitsuba's is not) where it is not, which it says.
    if !o.bool("has_spectral_extinction", true)? {
        let grey = match &coefficients {
            Coefficients::Homogeneous(h) => h.sigma_t.x == h.sigma_t.y && h.sigma_t.y == h.sigma_t.z,
            Coefficients::Heterogeneous(h) => h.sigma_t.is_grey(),
        };
        if !grey {
            let at = o.get("has_spectral_extinction").map_or_else(|| o.loc.position(), |p| p.loc.position());
            files.warn(format!(
                "warning: {at}: has_spectral_extinction is false but this medium's sigma_t differs between \
                 channels: Mitsuba would track it in one channel without spectral MIS (biased); neumann tracks \
                 it spectrally (unbiased)"
            ));
        }
    }
    Ok(Medium { coefficients, phase, sample_emitters, radiance })
}

/// neumann's `radiance` of an emissive medium (pbrt-v4's `Le`; Mitsuba 3.9.1's media do not
/// emit): a `<float>`, `<rgb>` or `<spectrum>` (an illuminant, any non-negative value) or, where
/// `grid` allows, a nested `<volume>`; `None` where absent or zero everywhere.
fn radiance_param(o: &Obj, grid: bool, files: &mut dyn VolumeSource) -> PropResult<Option<volume::Volume>> {
    use crate::props::Value;
    let radiance = match o.get("radiance").map(|p| &p.value) {
        None => return Ok(None),
        Some(Value::Object(_)) if !grid => {
            return Err(o.error_at("radiance", "a homogeneous medium's radiance is a <float>, <rgb> or <spectrum>"))
        }
        Some(Value::Object(_)) => {
            let v = volume::volume_param(o, "radiance", 0.0, SpectrumKind::Illuminant, files)?;
            volume::check_range(o, "radiance", &v, 0.0, f32::INFINITY)?;
            v
        }
        Some(_) => {
            let c = o.rgb("radiance", Rgb::ZERO, SpectrumKind::Illuminant)?;
            if !(0..3).all(|k| c[k] >= 0.0 && c[k].is_finite()) {
                return Err(o.error_at("radiance", format!("radiance must be finite and ≥ 0, got {c}")));
            }
            volume::Volume::constant(c, crate::math::Transform::IDENTITY)
        }
    };
    Ok((radiance.max() > 0.0).then_some(radiance))
}

/// Mitsuba's `homogeneous`: `sigma_t` (1 m⁻¹) × `scale` (1), `albedo` (0.75), a `<phase>`,
/// `sample_emitters`; neumann's `radiance` (none: an emissive medium, [`Medium::radiance`]). An
/// `<rgb>` `sigma_t` or `albedo` must lie in [0, 1] (Mitsuba reads it as a reflectance).
fn homogeneous_from_props(o: &Obj, files: &mut dyn VolumeSource) -> PropResult<Medium> {
    let scale = o.float_checked("scale", 1.0, |s| s >= 0.0 && s.is_finite(), "a non-negative number")?;
    let sigma_t = constant_coefficient(o, "sigma_t", 1.0, SpectrumKind::Illuminant, files)? * scale;
    if !(0..3).all(|c| sigma_t[c] >= 0.0 && sigma_t[c].is_finite()) {
        return Err(o.error_at("sigma_t", format!("sigma_t must be non-negative, got {sigma_t}")));
    }
    let albedo = constant_coefficient(o, "albedo", 0.75, SpectrumKind::Reflectance, files)?;
    if !(0..3).all(|c| (0.0..=1.0).contains(&albedo[c])) {
        return Err(o.error_at("albedo", format!("albedo must lie in [0, 1], got {albedo}")));
    }
    let radiance = radiance_param(o, false, files)?;
    let medium = common(o, Coefficients::Homogeneous(Homogeneous { sigma_t, albedo }), radiance, files)?;
    if medium.phase.microflakes().is_some() {
        // Its extinction follows the flakes' S grid from point to point: not homogeneous.
        let phase = &o.nested("phase")[0];
        return Err(phase.error(
            "an sggx phase function needs a heterogeneous medium (its extinction varies with the S grid); \
             give the medium type=\"heterogeneous\" with the same sigma_t and albedo",
        ));
    }
    Ok(medium)
}

/// A homogeneous medium's coefficient `name`: a `<float>`, `<rgb>` or `<spectrum>`
/// ([`volume::constant_param`]), or a `constvolume`, whose value it takes (as Mitsuba's
/// `homogeneous`, which reads its coefficients as volumes); another volume is an error.
fn constant_coefficient(
    o: &Obj,
    name: &str,
    default: f32,
    kind: SpectrumKind,
    files: &mut dyn VolumeSource,
) -> PropResult<Rgb> {
    if !matches!(o.get(name).map(|p| &p.value), Some(crate::props::Value::Object(_))) {
        return volume::constant_param(o, name, default, kind);
    }
    let v = volume::volume_param(o, name, default, kind, files)?;
    if !v.is_constant() {
        return Err(o.error_at(
            name,
            format!("a homogeneous medium's {name} is constant (a constvolume, float, rgb or spectrum): give a heterogeneous medium this volume"),
        ));
    }
    Ok(v.mean())
}

/// Mitsuba's `heterogeneous` ([`Heterogeneous::from_props`]), a `<phase>`, `sample_emitters`;
/// neumann's `radiance` (none; a constant or a `<volume>`: an emissive medium, which emits only
/// where it has extinction, inside the `sigma_t` volume's box).
fn heterogeneous_from_props(o: &Obj, files: &mut dyn VolumeSource) -> PropResult<Medium> {
    let h = Heterogeneous::from_props(o, files)?;
    let radiance = radiance_param(o, true, files)?;
    let mut medium = common(o, Coefficients::Heterogeneous(Box::new(h.clone())), radiance, files)?;
    if let Some(flakes) = medium.phase.microflakes() {
        medium.coefficients = Coefficients::Heterogeneous(Box::new(h.with_flakes(flakes.clone())));
    }
    Ok(medium)
}
