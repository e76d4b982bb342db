//! Emitters as a closed enum: `sample_li` / `pdf_li` / `le`, and their power for light
//! selection.
//!
//! Measures: `sample_li` returns a density per unit **solid angle** at the reference point (so
//! it can be MIS-combined with BSDF sampling); delta lights (points) flag `delta` instead and
//! their pdf is a probability (1).

mod bvh;
mod envmap;
mod goniometric;
mod portal;
mod projector;
mod registry;
mod sampler;
mod sun_position;
mod sunsky;

pub use bvh::{LightBounds, LightBvh};
pub use envmap::{EnvMap, EnvMapError, Layout as EnvMapLayout};
pub use goniometric::{Goniometric, GoniometricError};
pub use portal::{Portal, PortalError};
pub use projector::{Projector, ProjectorEmission};
pub use registry::{
    area_opacity_from_props, area_radiance_from_props, emitter_plugin, timed_sunsky, EmitterPlugin, EMITTER_PLUGINS,
};
pub use sampler::{LightSampleContext, LightSampler, LightSamplerKind, InvalidLightPower};
pub(crate) use sampler::selection_powers;
pub use sun_position::{day_number, sun_direction, DateTime, Location};
pub use sunsky::{SunPlacement, SunSky, SunSkyError, SunSkyParams};

use crate::geometry::{Geometry, ShapeSample};
use crate::math::{luminance, Rgb, Vec2, Vec3, PI};
use crate::texture::Texture;

/// An emitter.
#[derive(Clone, Debug)]
pub enum Light {
    /// Mitsuba's `area` emitter: radiance leaving the front side of a shape (both sides if
    /// `two_sided`, pbrt-v4's `twosided`), constant or a texture over the shape's (u, v).
    /// Parameters: `radiance` (W m⁻² sr⁻¹ per channel).
    Area {
        /// Index of the emitting shape.
        shape: u32,
        /// Emitted radiance.
        radiance: Texture,
        /// Whether the back emits too.
        two_sided: bool,
    },
    /// Mitsuba's `directionalarea` emitter: a shape that emits only along its front (shading)
    /// normal, a delta in direction. `radiance` (W m⁻² per channel, constant or a texture over
    /// the shape's (u, v)) is the irradiance it delivers on a surface facing it, so the shape
    /// sends out power `A · radiance`. As in Mitsuba, only light tracing (`ptracer`) shows its
    /// light: no camera or BSDF ray and no shadow ray can meet a delta direction, so for the
    /// other integrators it emits nothing (and is not chosen for next-event estimation).
    DirectionalArea {
        /// Index of the emitting shape.
        shape: u32,
        /// Power per unit area, emitted along the normal.
        radiance: Texture,
    },
    /// Mitsuba's `constant` emitter: uniform radiance arriving from every direction at
    /// infinity. Parameters: `radiance` (W m⁻² sr⁻¹ per channel). `center` / `radius` bound the
    /// scene (filled in when the scene is built), to place shadow-ray endpoints and estimate power.
    Constant {
        /// Radiance from every direction.
        radiance: Rgb,
        /// Centre of the scene's bounding sphere.
        center: Vec3,
        /// Radius of the scene's bounding sphere.
        radius: f32,
    },
    /// Mitsuba's `envmap` emitter (see [`EnvMap`]). `center` / `radius` bound the scene.
    EnvMap {
        /// The map and its sampling distribution.
        map: Box<EnvMap>,
        /// Centre of the scene's bounding sphere.
        center: Vec3,
        /// Radius of the scene's bounding sphere.
        radius: f32,
    },
    /// Mitsuba's `sunsky` emitter (see [`SunSky`]). `center` / `radius` bound the scene.
    SunSky {
        /// The sun, the sky and their sampling distribution.
        sky: Box<SunSky>,
        /// Centre of the scene's bounding sphere.
        center: Vec3,
        /// Radius of the scene's bounding sphere.
        radius: f32,
    },
    /// Mitsuba's `directional` emitter: parallel light of irradiance `irradiance` (W m⁻² per
    /// channel, on a surface facing it) travelling along `direction`. `center` / `radius` bound
    /// the scene (filled in when the scene is built).
    Directional {
        /// Unit direction the light travels in (world).
        direction: Vec3,
        /// Irradiance on a surface perpendicular to the light.
        irradiance: Rgb,
        /// Centre of the scene's bounding sphere.
        center: Vec3,
        /// Radius of the scene's bounding sphere.
        radius: f32,
    },
    /// Mitsuba's `spot` emitter: a point source of intensity `intensity` (W sr⁻¹) shining along
    /// its local +z, full strength within `beam_width`, falling off linearly in angle to zero at
    /// `cutoff_angle` (Mitsuba's defaults: cutoff 20°, beam width ¾ of the cutoff).
    Spot {
        /// Position (world).
        position: Vec3,
        /// Frame whose +z is the spot axis.
        frame: crate::math::Frame,
        /// Intensity on the axis.
        intensity: Rgb,
        /// Cutoff angle (radians).
        cutoff: f32,
        /// Beam width (radians, ≤ cutoff).
        beam: f32,
        /// An image projected over the cutoff cone (Mitsuba's `texture`), multiplying the
        /// intensity.
        texture: Option<Box<crate::texture::Texture>>,
        /// The shape of the falloff between the beam and the cutoff.
        falloff: SpotFalloff,
    },
    /// Mitsuba's `projector` emitter (see [`Projector`]).
    Projector(Box<Projector>),
    /// pbrt-v4's goniometric light (see [`Goniometric`]).
    Goniometric(Box<Goniometric>),
    /// Mitsuba's `point` emitter: an isotropic point source. Parameters: `position`,
    /// `intensity` (W sr⁻¹ per channel).
    Point {
        /// Position (world).
        position: Vec3,
        /// Radiant intensity.
        intensity: Rgb,
    },
}

/// What a shape's `<emitter>` makes it: the emission a shape carries before it has an index.
#[derive(Clone, Debug)]
pub enum ShapeEmission {
    /// [`Light::Area`]: Lambertian emission of `radiance` from the front (both sides if
    /// `two_sided`).
    Area {
        /// Emitted radiance.
        radiance: Texture,
        /// Whether the back emits too.
        two_sided: bool,
    },
    /// [`Light::DirectionalArea`]: `radiance` sent along the normal only.
    DirectionalArea {
        /// Power per unit area.
        radiance: Texture,
    },
}

impl ShapeEmission {
    /// The emitted radiance (or, along the normal, power per area) over the shape's uv.
    pub fn radiance(&self) -> &Texture {
        match self {
            ShapeEmission::Area { radiance, .. } | ShapeEmission::DirectionalArea { radiance } => radiance,
        }
    }

    /// The light this emission makes of shape `shape`.
    pub fn light(self, shape: u32) -> Light {
        match self {
            ShapeEmission::Area { radiance, two_sided } => Light::Area { shape, radiance, two_sided },
            ShapeEmission::DirectionalArea { radiance } => Light::DirectionalArea { shape, radiance },
        }
    }
}

/// How a spot light fades between its beam width and its cutoff angle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpotFalloff {
    /// Mitsuba's: linear in the angle θ.
    Linear,
    /// pbrt-v4's: `smoothstep` in cos θ (`t²(3 − 2t)` with `t` the position of cos θ between
    /// the cutoff's and the beam's cosines).
    SmoothStep,
}

/// Incident radiance sampled toward a light.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the reference point toward the light (world).
    pub wi: Vec3,
    /// Radiance arriving along `-wi` (unoccluded): `Lₑ` for area lights, `I / r²` for points.
    pub li: Rgb,
    /// Density of `wi` per unit solid angle (1 for delta lights).
    pub pdf: f32,
    /// Point on the light.
    pub p: Vec3,
    /// Geometric normal at `p` (zero for points).
    pub n: Vec3,
    /// Error bound of `p`.
    pub p_error: Vec3,
    /// Whether the light is a delta distribution in direction (unreachable by BSDF sampling).
    pub delta: bool,
}

/// An area light's sample: the shape's sample `s` seen along `wi` (unit, toward it) with emitted
/// radiance `li`; `None` on the back of a one-sided emitter, which does not emit.
#[inline(always)]
fn area_light_sample(s: &ShapeSample, wi: Vec3, li: Rgb, two_sided: bool) -> Option<LightSample> {
    if !two_sided && s.ns.dot(wi) >= 0.0 {
        return None;
    }
    Some(LightSample { wi, li, pdf: s.pdf, p: s.p, n: s.ng, p_error: s.p_error, delta: false })
}

impl LightSample {
    /// Light from a point source at `p` arriving along `-wi` (unit, toward `p`) as `li`: a
    /// delta sample (pdf 1, no normal, exact position).
    pub fn from_point(p: Vec3, wi: Vec3, li: Rgb) -> LightSample {
        LightSample { wi, li, pdf: 1.0, p, n: Vec3::ZERO, p_error: Vec3::ZERO, delta: true }
    }
}

/// A ray of light leaving an emitter, sampled for light tracing ([`Light::sample_le`]).
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    /// Origin on the light (for lights at infinity: on a disk outside the scene's bounding
    /// sphere, facing it).
    pub p: Vec3,
    /// Error bound of `p`.
    pub p_error: Vec3,
    /// Geometric normal at `p` (zero for points and lights at infinity).
    pub n: Vec3,
    /// Unit direction the light travels in.
    pub d: Vec3,
    /// `Lₑ |cos θ| / (p_A(p) p_ω(d))`: the power the ray carries (W per channel), for one
    /// sample. For point and spot lights `I(d) / p_ω(d)`.
    pub weight: Rgb,
}

/// Emission from a light toward a given point, without a direction sampled
/// ([`Light::sample_le_position`]): what light tracing connects straight to the camera.
#[derive(Clone, Copy, Debug)]
pub struct EmissionPosition {
    /// Point on the light.
    pub p: Vec3,
    /// Error bound of `p`.
    pub p_error: Vec3,
    /// Geometric normal at `p`.
    pub ng: Vec3,
    /// Shading normal (which side emits).
    pub ns: Vec3,
    /// `1 / p_A(p)`: divides the emitted radiance.
    pub inv_pdf: f32,
    /// Texture coordinates of `p` (area lights with a textured radiance; zero otherwise).
    pub uv: Vec2,
}


/// A point of an area emitter's shape, uniform by area, with its texture coordinates where the
/// radiance is a texture (zero for a constant radiance, which then keeps the shapes' fastest
/// sampling, e.g. quads as parallelograms).
#[inline]
fn area_emission_point(shape: &Geometry, radiance: &Texture, u: Vec2) -> Option<(crate::geometry::ShapeSample, Vec2)> {
    match radiance {
        Texture::Constant(_) => Some((shape.sample_area(u)?, Vec2::ZERO)),
        _ => shape.sample_area_uv(u),
    }
}

/// A distance from `p_ref` that reaches past everything in the scene (bounding sphere `center`,
/// `radius`): where shadow rays toward lights at infinity end.
#[inline]
fn beyond_scene(p_ref: Vec3, center: Vec3, radius: f32) -> f32 {
    2.0 * (radius + (p_ref - center).length()) + 1.0
}

/// A direction sampled toward a light at infinity, `(wi, li, pdf)`, as the light sample at
/// `p_ref` whose shadow ray ends beyond everything in the scene.
#[inline]
fn sample_at_infinity(p_ref: Vec3, center: Vec3, radius: f32, (wi, li, pdf): (Vec3, Rgb, f32)) -> LightSample {
    let far = beyond_scene(p_ref, center, radius);
    LightSample { wi, li, pdf, p: p_ref + wi * far, n: Vec3::ZERO, p_error: Vec3::ZERO, delta: false }
}

impl Light {
    /// Emitted power (luminance of the radiant flux, W) used to choose lights proportionally:
    /// `π A L` for a one-sided Lambertian area emitter of area `A`, `4π I` for a point light.
    pub fn power(&self, shapes: &[Geometry]) -> f32 {
        match self {
            Light::Area { shape, radiance, two_sided } => {
                let sides = if *two_sided { 2.0 } else { 1.0 };
                sides * PI * shapes[*shape as usize].area() * luminance(radiance.mean())
            }
            Light::DirectionalArea { shape, radiance } => shapes[*shape as usize].area() * luminance(radiance.mean()),
            Light::Point { intensity, .. } => 4.0 * PI * luminance(*intensity),
            // Flux through the scene's bounding sphere: irradiance π L over its area 4π R².
            Light::Constant { radiance, radius, .. } => 4.0 * PI * PI * radius * radius * luminance(*radiance),
            Light::EnvMap { map, radius, .. } => PI * radius * radius * map.integral_luminance(),
            Light::SunSky { sky, radius, .. } => PI * radius * radius * sky.integral_luminance(),
            // Flux through the scene's cross-section.
            Light::Directional { irradiance, radius, .. } => PI * radius * radius * luminance(*irradiance),
            // ∫ falloff dω, with the transition band counted at half strength.
            // (exact for the smoothstep, whose integral over the band is half its width in cos θ).
            Light::Spot { intensity, cutoff, beam, texture, .. } => {
                let tex = texture.as_ref().map_or(1.0, |t| luminance(t.mean()));
                2.0 * PI * (1.0 - 0.5 * (cutoff.cos() + beam.cos())) * luminance(*intensity) * tex
            }
            Light::Projector(p) => p.power(),
            Light::Goniometric(g) => g.power(),
        }
    }

    /// [`Light::power`] where single precision overflows: the lights at infinity (whose power
    /// is their flux through the scene's bounding sphere or cross-section, `∝ R²`) in double
    /// precision, so that a scene some 10¹⁹ units wide still has one. Otherwise `power` itself
    /// (an area or point light whose power overflows stays infinite: its emission does).
    pub fn power_f64(&self, shapes: &[Geometry]) -> f64 {
        let p = self.power(shapes);
        if p.is_finite() {
            return f64::from(p);
        }
        let pi = std::f64::consts::PI;
        let r2 = |r: f32| f64::from(r) * f64::from(r);
        match self {
            Light::Constant { radiance, radius, .. } => 4.0 * pi * pi * r2(*radius) * f64::from(luminance(*radiance)),
            Light::EnvMap { map, radius, .. } => pi * r2(*radius) * f64::from(map.integral_luminance()),
            Light::SunSky { sky, radius, .. } => pi * r2(*radius) * f64::from(sky.integral_luminance()),
            Light::Directional { irradiance, radius, .. } => pi * r2(*radius) * f64::from(luminance(*irradiance)),
            _ => f64::from(p),
        }
    }

    /// Whether the light is a delta distribution (cannot be hit by rays).
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point { .. }
                | Light::Spot { .. }
                | Light::Directional { .. }
                | Light::DirectionalArea { .. }
                | Light::Projector(_)
                | Light::Goniometric(_)
        )
    }

    /// A spot light's emission toward the unit direction `w_local` of its frame: the falloff,
    /// times its texture where it has one (Mitsuba's uv: ½ + ½ (x, y) / (z tan cutoff)).
    #[inline]
    fn spot_profile(
        w_local: Vec3,
        cutoff: f32,
        beam: f32,
        texture: &Option<Box<crate::texture::Texture>>,
        shape: SpotFalloff,
    ) -> Rgb {
        let falloff = Self::spot_falloff(w_local.z, cutoff, beam, shape);
        match texture {
            Some(t) if falloff > 0.0 => {
                let k = 0.5 / (w_local.z * cutoff.tan());
                t.eval(Vec2::new(0.5 + w_local.x * k, 0.5 + w_local.y * k)) * falloff
            }
            _ => Rgb::splat(falloff),
        }
    }

    /// Spot falloff for a unit direction `w_local` in the spot's frame: 1 inside the beam, 0
    /// beyond the cutoff, `shape` between.
    #[inline]
    fn spot_falloff(cos_theta: f32, cutoff: f32, beam: f32, shape: SpotFalloff) -> f32 {
        if cos_theta >= beam.cos() {
            1.0
        } else if cos_theta <= cutoff.cos() {
            0.0
        } else {
            match shape {
                SpotFalloff::Linear => ((cutoff - crate::math::safe_acos(cos_theta)) / (cutoff - beam)).clamp(0.0, 1.0),
                SpotFalloff::SmoothStep => {
                    let t = ((cos_theta - cutoff.cos()) / (beam.cos() - cutoff.cos())).clamp(0.0, 1.0);
                    t * t * (3.0 - 2.0 * t)
                }
            }
        }
    }

    /// Whether the light sits at infinity (seen by rays that escape the scene).
    pub fn is_infinite(&self) -> bool {
        matches!(self, Light::Constant { .. } | Light::EnvMap { .. } | Light::SunSky { .. })
    }

    /// Radiance arriving from an infinite light along a ray from `o` that escaped in direction
    /// `d` (world, unit; the origin matters to an environment map with a portal); zero for
    /// lights that are not at infinity.
    #[inline]
    pub fn le_escaped(&self, o: Vec3, d: Vec3) -> Rgb {
        match self {
            Light::Constant { radiance, .. } => *radiance,
            Light::EnvMap { map, .. } => map.eval_from(o, d),
            Light::SunSky { sky, .. } => sky.eval(d),
            _ => Rgb::ZERO,
        }
    }

    /// [`Light::le_escaped`] and, with `p_ref` given, [`Light::pdf_li_direction`] at `p_ref` of
    /// the same direction (else 0): the same bits, an environment map's image coordinates
    /// found once.
    #[inline]
    pub fn le_pdf_escaped(&self, o: Vec3, d: Vec3, p_ref: Option<Vec3>) -> (Rgb, f32) {
        match (self, p_ref) {
            (Light::EnvMap { map, .. }, Some(p_ref)) => map.eval_pdf_from(o, p_ref, d),
            (_, Some(p_ref)) => (self.le_escaped(o, d), self.pdf_li_direction(p_ref, d)),
            (_, None) => (self.le_escaped(o, d), 0.0),
        }
    }

    /// [`Light::sample_li`] for an estimator that light sampling carries alone (no BSDF
    /// sampling MIS-combined with it: `direct` without BSDF samples, the light-only
    /// strategies): the same, except that an MIS-compensated environment map draws from its
    /// complete density ([`EnvMap::sample_complete`]), which leaves no direction with radiance
    /// out. Its pdf is then that density's, which no `pdf_li` reports (none is needed: such
    /// an estimator weighs nothing by it).
    pub fn sample_li_complete(&self, shapes: &[Geometry], p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        match self {
            Light::EnvMap { map, center, radius } if map.is_compensated() => {
                Some(sample_at_infinity(p_ref, *center, *radius, map.sample_from_complete(p_ref, u)?))
            }
            _ => self.sample_li(shapes, p_ref, u),
        }
    }

    /// Samples incident light at `p_ref`. `None` when nothing can arrive (back side, degenerate).
    #[inline]
    pub fn sample_li(&self, shapes: &[Geometry], p_ref: Vec3, u: Vec2) -> Option<LightSample> {
        match self {
            Light::Area { shape, radiance, two_sided } => {
                let shape = &shapes[*shape as usize];
                // The shape's sample read in place: moved out of the `Option`, it was copied by
                // wide loads right after the call wrote it field by field (a store-forwarding
                // stall, most of this function's own time on a sphere light).
                match radiance {
                    Texture::Constant(c) => {
                        let sampled = shape.sample_solid_angle(p_ref, u);
                        let (s, wi) = sampled.as_ref()?;
                        area_light_sample(s, *wi, *c, *two_sided)
                    }
                    t => {
                        let sampled = shape.sample_solid_angle_uv(p_ref, u);
                        let (s, wi, uv) = sampled.as_ref()?;
                        area_light_sample(s, *wi, t.eval(*uv), *two_sided)
                    }
                }
            }
            Light::Constant { radiance, center, radius } => {
                let s = crate::sampling::sample_uniform_sphere(u);
                Some(sample_at_infinity(p_ref, *center, *radius, (s.value, *radiance, s.pdf)))
            }
            Light::SunSky { sky, center, radius } => Some(sample_at_infinity(p_ref, *center, *radius, sky.sample(u)?)),
            Light::EnvMap { map, center, radius } => {
                Some(sample_at_infinity(p_ref, *center, *radius, map.sample_from(p_ref, u)?))
            }
            Light::Directional { direction, irradiance, center, radius } => {
                let wi = -*direction;
                let far = beyond_scene(p_ref, *center, *radius);
                Some(LightSample {
                    wi,
                    li: *irradiance,
                    pdf: 1.0,
                    p: p_ref + wi * far,
                    n: Vec3::ZERO,
                    p_error: Vec3::ZERO,
                    delta: true,
                })
            }
            Light::Spot { position, frame, intensity, cutoff, beam, texture, falloff } => {
                let d = *position - p_ref;
                let dist2 = d.length_squared();
                if dist2 == 0.0 {
                    return None;
                }
                let wi = d / dist2.sqrt();
                let profile = Self::spot_profile(frame.to_local(-wi), *cutoff, *beam, texture, *falloff);
                if profile.max_element() <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    li: *intensity * profile / dist2,
                    pdf: 1.0,
                    p: *position,
                    n: Vec3::ZERO,
                    p_error: Vec3::ZERO,
                    delta: true,
                })
            }
            Light::Projector(p) => p.sample_li(p_ref),
            Light::Goniometric(g) => g.sample_li(p_ref),
            // Emission along the normal only: no point but the one straight below could receive it.
            Light::DirectionalArea { .. } => None,
            Light::Point { position, intensity } => {
                let d = *position - p_ref;
                let dist2 = d.length_squared();
                if dist2 == 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi: d / dist2.sqrt(),
                    li: *intensity / dist2,
                    pdf: 1.0,
                    p: *position,
                    n: Vec3::ZERO,
                    p_error: Vec3::ZERO,
                    delta: true,
                })
            }
        }
    }

    /// Solid-angle density with which [`Light::sample_li`] from `p_ref` picks the point `p` (with
    /// geometric normal `ng`) on this light; 0 for delta lights. For lights at infinity, `p`
    /// only gives the direction (see [`Light::pdf_li_direction`]).
    #[inline]
    pub fn pdf_li(&self, shapes: &[Geometry], p_ref: Vec3, p: Vec3, ng: Vec3) -> f32 {
        match self {
            Light::Area { shape, .. } => shapes[*shape as usize].pdf_solid_angle(p_ref, p, ng),
            Light::Point { .. }
            | Light::Spot { .. }
            | Light::Directional { .. }
            | Light::DirectionalArea { .. }
            | Light::Projector(_)
            | Light::Goniometric(_) => 0.0,
            Light::Constant { .. } | Light::EnvMap { .. } | Light::SunSky { .. } => {
                self.pdf_li_direction(p_ref, (p - p_ref).normalize_or_zero())
            }
        }
    }

    /// Solid-angle density with which [`Light::sample_li`] picks direction `wi` toward an
    /// infinite light (0 for other lights).
    #[inline]
    pub fn pdf_li_direction(&self, p_ref: Vec3, wi: Vec3) -> f32 {
        match self {
            Light::Constant { .. } => crate::sampling::uniform_sphere_pdf(),
            Light::EnvMap { map, .. } => map.pdf_from(p_ref, wi),
            Light::SunSky { sky, .. } => sky.pdf(wi),
            _ => 0.0,
        }
    }

    /// Samples a ray leaving the light (light tracing): a position (by area on area lights),
    /// then a direction (cosine-weighted about the front normal for area lights, uniform over
    /// the sphere for points, uniform in the cutoff cone for spots). Lights at infinity send
    /// parallel rays from a disk of the scene's bounding radius facing the sampled direction.
    /// `u_pos` chooses the position, `u_dir` the direction. `None` if nothing is emitted.
    pub fn sample_le(&self, shapes: &[Geometry], u_pos: Vec2, u_dir: Vec2) -> Option<EmissionSample> {
        use crate::sampling::{
            sample_cosine_hemisphere_malley, sample_uniform_cone, sample_uniform_disk_concentric, sample_uniform_sphere,
        };
        let parallel = |d: Vec3, center: Vec3, radius: f32| {
            // Origin on a disk of radius R perpendicular to d, one radius before the sphere.
            let frame = crate::math::Frame::from_z(d);
            let q = sample_uniform_disk_concentric(u_pos).value * radius;
            (center + frame.to_world(Vec3::new(q.x, q.y, -2.0 * radius)), PI * radius * radius)
        };
        // A direction sampled toward a light at infinity, `(wi, li, pdf)`, as a parallel ray
        // travelling along `-wi` from outside the scene.
        let from_infinity = |(wi, li, pdf): (Vec3, Rgb, f32), center: Vec3, radius: f32| {
            let (p, area) = parallel(-wi, center, radius);
            EmissionSample { p, p_error: Vec3::ZERO, n: Vec3::ZERO, d: -wi, weight: li * (area / pdf) }
        };
        let s = match self {
            Light::Area { shape, radiance, two_sided } => {
                let (ps, uv) = area_emission_point(&shapes[*shape as usize], radiance, u_pos)?;
                let le = radiance.eval(uv);
                // Two-sided: a side with probability ½ (u_dir.x reused), weight doubled.
                let (u_dir, side, sides) = match two_sided {
                    true if u_dir.x < 0.5 => (Vec2::new(2.0 * u_dir.x, u_dir.y), 1.0, 2.0),
                    true => (Vec2::new((2.0 * u_dir.x - 1.0).min(crate::math::ONE_MINUS_EPSILON), u_dir.y), -1.0, 2.0),
                    false => (u_dir, 1.0, 1.0),
                };
                let local = sample_cosine_hemisphere_malley(u_dir);
                if local.pdf <= 0.0 || ps.pdf <= 0.0 {
                    return None;
                }
                let d = crate::math::Frame::from_z(ps.ns * side).to_world(local.value);
                // Le cos θ / (p_A · p_side · cos θ / π) = sides · π Le / p_A.
                EmissionSample { p: ps.p, p_error: ps.p_error, n: ps.ng, d, weight: le * (sides * PI / ps.pdf) }
            }
            Light::DirectionalArea { shape, radiance } => {
                // Along the normal: the power of the position, radiance / p_A (Mitsuba's area × radiance).
                let (ps, uv) = area_emission_point(&shapes[*shape as usize], radiance, u_pos)?;
                if ps.pdf <= 0.0 {
                    return None;
                }
                EmissionSample { p: ps.p, p_error: ps.p_error, n: ps.ng, d: ps.ns, weight: radiance.eval(uv) / ps.pdf }
            }
            Light::Point { position, intensity } => {
                let d = sample_uniform_sphere(u_dir);
                EmissionSample {
                    p: *position,
                    p_error: Vec3::ZERO,
                    n: Vec3::ZERO,
                    d: d.value,
                    weight: *intensity / d.pdf,
                }
            }
            Light::Spot { position, frame, intensity, cutoff, beam, texture, falloff } => {
                let d = sample_uniform_cone(u_dir, cutoff.cos());
                let profile = Self::spot_profile(d.value, *cutoff, *beam, texture, *falloff);
                if profile.max_element() <= 0.0 || d.pdf <= 0.0 {
                    return None;
                }
                let weight = *intensity * profile / d.pdf;
                EmissionSample { p: *position, p_error: Vec3::ZERO, n: Vec3::ZERO, d: frame.to_world(d.value), weight }
            }
            Light::Projector(p) => p.sample_le(u_dir)?,
            Light::Goniometric(g) => g.sample_le(u_dir)?,
            Light::Directional { direction, irradiance, center, radius } => {
                let (p, area) = parallel(*direction, *center, *radius);
                EmissionSample { p, p_error: Vec3::ZERO, n: Vec3::ZERO, d: *direction, weight: *irradiance * area }
            }
            Light::Constant { radiance, center, radius } => {
                let wi = sample_uniform_sphere(u_dir);
                from_infinity((wi.value, *radiance, wi.pdf), *center, *radius)
            }
            Light::SunSky { sky, center, radius } => from_infinity(sky.sample(u_dir)?, *center, *radius),
            // Light tracing draws from the map's complete density: nothing else would reach
            // what an MIS-compensated one leaves out.
            Light::EnvMap { map, center, radius } => match map.portal() {
                None => from_infinity(map.sample_complete(u_dir)?, *center, *radius),
                Some(portal) => {
                    // Through the portal: a point uniform on it, a direction from the map's
                    // distribution (rays that do not enter through it carry nothing). The ray
                    // starts beyond the scene so that what stands outside the window shades it.
                    let (wi, li, pdf) = map.sample(u_dir)?;
                    let cos = wi.dot(portal.normal());
                    if cos <= 0.0 {
                        return None;
                    }
                    let q = portal.point(u_pos);
                    let p = q + wi * beyond_scene(q, *center, *radius);
                    EmissionSample { p, p_error: Vec3::ZERO, n: Vec3::ZERO, d: -wi, weight: li * (portal.area() * cos / pdf) }
                }
            },
        };
        (s.weight.is_finite() && s.weight.max_element() > 0.0).then_some(s)
    }

    /// A position on the light for connecting it straight to the camera (the emitter vertex of
    /// a light path seen directly): by area, for area lights only. As in Mitsuba's `ptracer`,
    /// delta lights are never connected to the camera (point, spot, projector and goniometric
    /// lights sit at a point no camera ray can meet, directional ones along one direction), so
    /// the light tracer's image shows them exactly where the path tracer's does: nowhere. Lights
    /// at infinity are seen by the camera rays that escape (`None` here too).
    pub fn sample_le_position(&self, shapes: &[Geometry], u_pos: Vec2) -> Option<EmissionPosition> {
        match self {
            Light::Area { shape, radiance, .. } => {
                let (s, uv) = area_emission_point(&shapes[*shape as usize], radiance, u_pos)?;
                (s.pdf > 0.0).then(|| EmissionPosition {
                    p: s.p,
                    p_error: s.p_error,
                    ng: s.ng,
                    ns: s.ns,
                    inv_pdf: 1.0 / s.pdf,
                    uv,
                })
            }
            _ => None,
        }
    }

    /// The radiance an area light emits from `pos` toward the unit direction `d` (world): front
    /// side only unless two-sided; zero for every other light (none has a position to connect).
    pub fn emitted_toward(&self, pos: &EmissionPosition, d: Vec3) -> Rgb {
        match self {
            Light::Area { radiance, two_sided, .. } if pos.ns.dot(d) > 0.0 || (*two_sided && pos.ns.dot(d) < 0.0) => {
                radiance.eval(pos.uv)
            }
            _ => Rgb::ZERO,
        }
    }

    /// Whether [`Light::le`] reads the surface's texture coordinates (an area light with a
    /// radiance texture that is not constant).
    pub fn reads_uv(&self) -> bool {
        matches!(self, Light::Area { radiance, .. } if !matches!(radiance, Texture::Constant(_)))
    }

    /// Radiance emitted from a surface point with shading normal `ns` and texture coordinates
    /// `uv` toward `wo` (world); zero off area lights (a directional area light's delta in
    /// direction is never met by a ray).
    #[inline]
    pub fn le(&self, ns: Vec3, wo: Vec3, uv: Vec2) -> Rgb {
        match self {
            Light::Area { radiance, two_sided, .. } if ns.dot(wo) > 0.0 || (*two_sided && ns.dot(wo) < 0.0) => {
                radiance.eval(uv)
            }
            _ => Rgb::ZERO,
        }
    }
}

/// The checks of a light at infinity's direction sampling (`sample` returning direction,
/// radiance and solid-angle density): χ² of `sample` against `pdf` over the sphere with `n`
/// draws, and 2000 samples' density and radiance against `pdf` and `eval`.
#[cfg(test)]
pub(crate) fn check_environment_sampling(
    sample: impl Fn(Vec2) -> Option<(Vec3, Rgb, f32)>,
    pdf: impl Fn(Vec3) -> f32,
    eval: impl Fn(Vec3) -> Rgb,
    n: usize,
    seed: u64,
) {
    use crate::testkit::{chi2_2d, u2, Chi2Config, SPHERE};
    let cfg = Chi2Config::default().with_seed(seed);
    let out = chi2_2d(&SPHERE, [31, 61], n, |r| sample(u2(r)).map(|s| s.0), |d| pdf(*d) as f64, &cfg);
    assert!(out.passed(), "{out}");
    let mut rng = crate::sampling::Pcg32::new(1, seed);
    for _ in 0..2000 {
        let (d, l, p) = sample(u2(&mut rng)).expect("a sample");
        assert!((p - pdf(d)).abs() <= 1e-3 * p, "{p} vs {}", pdf(d));
        assert!((l - eval(d)).abs().max_element() <= 1e-3 * l.abs().max_element().max(1e-3), "{l} vs {}", eval(d));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Sphere, TriangleMesh};
    use crate::math::Transform;
    use crate::testkit::{chi2_2d, u2, Chi2Config, SPHERE};

    /// Directions sampled toward each light shape follow `pdf_li` (χ² over the sphere of
    /// directions at the reference point), and the pdf integrates to one over the directions
    /// that see the light's front.
    #[test]
    fn area_light_sampling_matches_pdf() {
        let mut rect = TriangleMesh::rectangle();
        rect.transform(&(Transform::translate(Vec3::new(0.2, 0.1, 1.5)) * Transform::rotate(Vec3::X, 160.0).unwrap()));
        let mut disk_geo = Geometry::Disk(
            crate::geometry::Disk::new(
                Transform::translate(Vec3::new(-0.5, 0.0, 1.0)) * Transform::rotate(Vec3::Y, 200.0).unwrap(),
                false,
            )
            .unwrap(),
        );
        disk_geo.prepare_sampling();
        // pbrt-v4's partial disk: an annulus sector (hole of radius 0.3, 200°), facing the
        // origin from +x (off the poles of the direction cells, whose slivers there a cut edge
        // could hide from the quadrature).
        let annulus = Geometry::Disk(
            crate::geometry::Disk::new(
                Transform::translate(Vec3::new(1.6, 0.1, 0.3)) * Transform::rotate(Vec3::Y, -100.0).unwrap(),
                false,
            )
            .and_then(|d| d.partial(0.3, 200f32.to_radians()))
            .unwrap(),
        );
        let mut shapes = vec![
            Geometry::Mesh(rect),
            Geometry::Sphere(Sphere::new(Vec3::new(0.0, 0.3, 2.0), 0.7, false)),
            disk_geo,
            annulus,
        ];
        for s in &mut shapes {
            assert!(s.prepare_sampling());
        }
        let p_ref = Vec3::new(0.0, 0.0, 0.0);
        for k in 0..shapes.len() {
            let light = Light::Area { shape: k as u32, radiance: Rgb::ONE.into(), two_sided: false };
            // pdf over directions: find the hit on this shape along w (brute force, one shape).
            let pdf = |w: &Vec3| -> f64 {
                let ray = crate::math::Ray::new(p_ref, *w);
                let hit = match &shapes[k] {
                    Geometry::Mesh(m) => (0..m.len()).find_map(|i| {
                        let pre = crate::geometry::triangle::RayPrecomp::new(&ray);
                        crate::geometry::triangle::intersect_triangle(&pre, &m.triangle(i), f32::INFINITY)
                            .map(|h| (ray.at(h.t()), m.face_normal(i)))
                    }),
                    Geometry::Sphere(s) => {
                        // Inside the subtended cone, with f32 tolerance at the silhouette (where
                        // a ray test would be decided by round-off).
                        let to_c = (s.center - p_ref).as_dvec3();
                        let cos_max = (1.0 - (s.radius as f64).powi(2) / to_c.length_squared()).sqrt();
                        (w.as_dvec3().dot(to_c.normalize()) >= cos_max - 1e-6).then(|| {
                            let p = s.center - s.radius * (s.center - p_ref).normalize();
                            (p, (p - s.center).normalize())
                        })
                    }
                    Geometry::Disk(d) => d.intersect(&ray, f32::INFINITY).map(|(_, q)| (d.surface(q).0.p, d.normal())),
                    // Cylinders sample area like disks; their area sampling is χ²-tested in
                    // (φ, z) beside them (silhouette slivers of a tube defeat a direction test).
                    Geometry::Cylinder(_)
                    | Geometry::SdfGrid(_)
                    | Geometry::Curves(_)
                    | Geometry::LinearCurves(_)
                    | Geometry::BSplineCurves(_)
                    | Geometry::Ellipsoids(_) => {
                        unreachable!("not among the shapes tested here")
                    }
                };
                match hit {
                    Some((p, n)) if n.dot(-*w) > 0.0 => light.pdf_li(&shapes, p_ref, p, n) as f64,
                    _ => 0.0,
                }
            };
            let out = chi2_2d(
                &SPHERE,
                [51, 101],
                400_000,
                |r| light.sample_li(&shapes, p_ref, u2(r)).map(|s| s.wi),
                pdf,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "shape {k}: {out}");
        }
    }

    /// An area light whose radiance is a texture: light samples carry the texture's value at the
    /// sampled point (the rectangle's u grows along +x: a checkerboard of two columns gives the
    /// left colour on the left), and emitted rays carry π ∫ L dA (the texture's mean here).
    #[test]
    fn textured_area_light() {
        let mut rect = TriangleMesh::rectangle();
        rect.transform(&Transform::translate(Vec3::new(0.0, 0.0, 2.0)));
        rect.flip_normals = true; // facing −z, toward the origin
        let mut g = Geometry::Mesh(rect);
        assert!(g.prepare_sampling());
        let shapes = [g];
        let (c0, c1) = (Rgb::new(4.0, 1.0, 0.5), Rgb::new(0.5, 1.0, 4.0));
        let texture = Texture::checkerboard(c0, c1, crate::math::Mat3::from_scale(Vec2::new(1.0, 0.5)));
        let light = Light::Area { shape: 0, radiance: texture, two_sided: false };
        let mut rng = crate::sampling::Pcg32::new(4, 4);
        let mut seen = [false; 2];
        for _ in 0..200 {
            let s = light.sample_li(&shapes, Vec3::ZERO, u2(&mut rng)).unwrap();
            // u < ½ (x < 0) is colour 0 (u and v both below ½ after the v scale).
            let want = if s.p.x < 0.0 { c0 } else { c1 };
            assert_eq!(s.li, want, "at {}", s.p);
            seen[usize::from(s.p.x >= 0.0)] = true;
        }
        assert!(seen[0] && seen[1]);
        let n = 100_000;
        let mean: f64 = (0..n)
            .map(|_| light.sample_le(&shapes, u2(&mut rng), u2(&mut rng)).map_or(0.0, |e| e.weight.x as f64))
            .sum::<f64>()
            / n as f64;
        let want = (PI * 4.0 * 0.5 * (c0.x + c1.x)) as f64;
        assert!((mean - want).abs() < 0.02 * want, "{mean} vs {want}");
        assert!((light.power(&shapes) - PI * 4.0 * luminance(0.5 * (c0 + c1))).abs() < 1e-3);
    }

    #[test]
    fn point_light_falls_off_with_distance_squared() {
        let l = Light::Point { position: Vec3::new(0.0, 0.0, 2.0), intensity: Rgb::splat(8.0) };
        let s = l.sample_li(&[], Vec3::ZERO, Vec2::ZERO).unwrap();
        assert!(s.delta && (s.li - Rgb::splat(2.0)).length() < 1e-6 && (s.wi - Vec3::Z).length() < 1e-6);
        assert_eq!(l.pdf_li(&[], Vec3::ZERO, Vec3::Z, Vec3::Z), 0.0);
        assert!((l.power(&[]) - 4.0 * PI * 8.0).abs() < 1e-3);
    }

    /// `sample_le` carries each light's whole flux: the mean of its weights equals the
    /// emitted power (per channel) — `π A Lₑ` (area), `4π I` (point), `I ∫ falloff dω` (spot,
    /// by quadrature over θ), `E π R²` (directional), `4π L · π R²` (constant) — and its rays
    /// leave the right way: area rays from the front, parallel rays from outside the scene's
    /// bounding sphere along the light's direction, passing within R of its centre.
    #[test]
    fn sample_le_carries_the_emitted_power() {
        use crate::math::Frame;
        use crate::sampling::Pcg32;
        let mut rect = TriangleMesh::rectangle();
        rect.transform(&Transform::scale(Vec3::new(0.5, 2.0, 1.0)).unwrap());
        let mut rect = Geometry::Mesh(rect);
        assert!(rect.prepare_sampling());
        let shapes = [rect];
        let (center, radius) = (Vec3::new(1.0, 0.0, -1.0), 3.0);
        let (cutoff, beam) = (0.5f32, 0.3f32);
        // ∫ falloff dω = 2π ∫ falloff(cos θ) sin θ dθ.
        let spot_integral = {
            let n = 20_000;
            let h = cutoff as f64 / n as f64;
            (0..n)
                .map(|i| {
                    let t = (i as f64 + 0.5) * h;
                    Light::spot_falloff(t.cos() as f32, cutoff, beam, SpotFalloff::Linear) as f64 * t.sin() * h
                })
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI
        };
        let lights = [
            (
                Light::Area { shape: 0, radiance: Rgb::new(1.0, 2.0, 3.0).into(), two_sided: false },
                PI as f64 * 4.0 * 0.5 * 2.0,
            ),
            // pbrt-v4's two-sided emitter: twice the flux, half of it from the back.
            (
                Light::Area { shape: 0, radiance: Rgb::new(1.0, 2.0, 3.0).into(), two_sided: true },
                2.0 * PI as f64 * 4.0 * 0.5 * 2.0,
            ),
            (Light::Point { position: Vec3::ONE, intensity: Rgb::new(1.0, 2.0, 3.0) }, 4.0 * PI as f64),
            (
                Light::Spot {
                    position: Vec3::ONE,
                    frame: Frame::from_z(Vec3::new(0.3, -1.0, 0.2).normalize()),
                    intensity: Rgb::new(1.0, 2.0, 3.0),
                    cutoff,
                    beam,
                    texture: None,
                    falloff: SpotFalloff::Linear,
                },
                spot_integral,
            ),
            (
                Light::Directional {
                    direction: Vec3::new(1.0, -2.0, 0.5).normalize(),
                    irradiance: Rgb::new(1.0, 2.0, 3.0),
                    center,
                    radius,
                },
                (PI * radius * radius) as f64,
            ),
            (
                Light::Constant { radiance: Rgb::new(1.0, 2.0, 3.0), center, radius },
                (4.0 * PI * PI * radius * radius) as f64,
            ),
            // Mitsuba's directional area light: area × radiance, all of it along the normal.
            (Light::DirectionalArea { shape: 0, radiance: Rgb::new(1.0, 2.0, 3.0).into() }, 4.0 * 0.5 * 2.0),
        ];
        for (k, (light, flux_per_unit)) in lights.iter().enumerate() {
            if matches!(light, Light::Area { .. } | Light::DirectionalArea { .. }) {
                // (The others' powers only steer light selection, some approximately.)
                let phi = light.power(&shapes) as f64;
                let want = flux_per_unit * luminance(Rgb::new(1.0, 2.0, 3.0)) as f64;
                assert!((phi - want).abs() < 1e-4 * want, "light {k}: power {phi} vs {want}");
            }
            let mut rng = Pcg32::new(4, k as u64);
            let n = 200_000;
            let mut sum = [0.0f64; 3];
            let mut back = 0usize;
            for _ in 0..n {
                let s = light.sample_le(&shapes, u2(&mut rng), u2(&mut rng)).expect("emits");
                assert!((s.d.length() - 1.0).abs() < 1e-4, "light {k}: unit direction");
                match light {
                    Light::Area { two_sided: false, .. } => {
                        assert!(s.d.dot(s.n) > 0.0, "area light emits from its front")
                    }
                    Light::Area { .. } => {
                        back += usize::from(s.d.dot(s.n) < 0.0);
                        assert!(s.d.dot(s.n) != 0.0);
                    }
                    Light::Directional { direction, .. } => assert!((s.d - *direction).length() < 1e-5),
                    Light::DirectionalArea { .. } => assert!((s.d - s.n).length() < 1e-5, "along the normal"),
                    Light::Constant { .. } => {
                        assert!((s.p - center).length() > radius, "origin outside the bounding sphere");
                        let closest = s.p + s.d * (center - s.p).dot(s.d);
                        assert!((closest - center).length() <= radius * (1.0 + 1e-4), "ray misses the scene");
                    }
                    _ => {}
                }
                for (c, total) in sum.iter_mut().enumerate() {
                    *total += s.weight[c] as f64;
                }
            }
            if matches!(light, Light::Area { two_sided: true, .. }) {
                let f = back as f64 / n as f64;
                assert!((f - 0.5).abs() < 0.01, "two-sided: {f} of the rays leave the back");
            }
            for (c, total) in sum.iter().enumerate() {
                let (mean, want) = (total / n as f64, flux_per_unit * (c + 1) as f64);
                assert!((mean - want).abs() < 0.01 * want, "light {k}, channel {c}: {mean} vs {want}");
            }
        }
    }

    /// A sun and sky as a light: `sample_li` returns what `le_escaped` and `pdf_li_direction`
    /// give for its direction, and light tracing emits `π R² ∫ L dω` per channel in parallel
    /// rays from outside the scene's bounding sphere that pass within R of its centre (a 20°
    /// sun, so that uniform directions estimate the integral well).
    #[test]
    fn sunsky_light_samples_and_emits_its_radiance() {
        use crate::sampling::Pcg32;
        let params = SunSkyParams {
            sun: SunPlacement::Direction(Vec3::new(0.2, 0.4, 0.6)),
            sun_aperture: 20.0,
            complex_sun: true,
            ..SunSkyParams::default()
        };
        let (center, radius) = (Vec3::new(1.0, 0.0, -1.0), 3.0);
        let sky = SunSky::new(&params).unwrap();
        let light = Light::SunSky { sky: Box::new(sky.clone()), center, radius };
        assert!(light.is_infinite());
        let mut rng = Pcg32::new(8, 8);
        for _ in 0..2000 {
            let ls = light.sample_li(&[], center, u2(&mut rng)).unwrap();
            assert!((ls.li - light.le_escaped(center, ls.wi)).abs().max_element() <= 1e-3 * ls.li.abs().max_element());
            assert!((ls.pdf - light.pdf_li_direction(center, ls.wi)).abs() <= 1e-3 * ls.pdf);
            assert!((ls.p - center).length() > radius, "the shadow ray ends beyond the scene");
        }
        let mut integral = [0.0f64; 3];
        for (c, v) in integral.iter_mut().enumerate() {
            let mut rng = Pcg32::new(9, c as u64);
            *v = crate::testkit::sphere_integral_mc(400_000, &mut rng, |d| sky.eval(d)[c] as f64);
        }
        let n = 400_000;
        let mut sum = [0.0f64; 3];
        for _ in 0..n {
            let Some(s) = light.sample_le(&[], u2(&mut rng), u2(&mut rng)) else { continue };
            assert!((s.p - center).length() > radius, "origin outside the bounding sphere");
            let closest = s.p + s.d * (center - s.p).dot(s.d);
            assert!((closest - center).length() <= radius * (1.0 + 1e-4), "ray misses the scene");
            for (c, total) in sum.iter_mut().enumerate() {
                *total += s.weight[c] as f64;
            }
        }
        for c in 0..3 {
            let (mean, want) = (sum[c] / n as f64, integral[c] * (PI * radius * radius) as f64);
            assert!((mean - want).abs() < 0.02 * want, "channel {c}: {mean} vs {want}");
        }
    }

    /// A directional area light reaches nothing but by light tracing, as in Mitsuba: no
    /// direction toward it can be sampled or met (zero radiance toward any ray, zero density),
    /// and it has no position to connect straight to a camera.
    #[test]
    fn directional_area_light_is_met_only_by_its_own_rays() {
        let mut rect = Geometry::Mesh(TriangleMesh::rectangle());
        assert!(rect.prepare_sampling());
        let shapes = [rect];
        let light = Light::DirectionalArea { shape: 0, radiance: Rgb::splat(2.0).into() };
        let mut rng = crate::sampling::Pcg32::new(2, 0);
        for _ in 0..100 {
            let p_ref = Vec3::new(0.0, 0.0, 1.0) + (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5);
            assert!(light.sample_li(&shapes, p_ref, u2(&mut rng)).is_none());
            assert_eq!(light.pdf_li(&shapes, p_ref, Vec3::ZERO, Vec3::Z), 0.0);
            assert_eq!(light.le(Vec3::Z, Vec3::Z, Vec2::ZERO), Rgb::ZERO);
        }
        assert!(light.is_delta() && !light.is_infinite());
        assert!(light.sample_le_position(&shapes, Vec2::splat(0.5)).is_none());
        assert_eq!(LightBounds::of(&light, &shapes), None, "never chosen for next-event estimation");
    }
}
