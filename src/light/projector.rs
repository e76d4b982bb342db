//! Mitsuba's `projector` emitter: a point light that projects an image through a pinhole, like a
//! slide projector (the adjoint of the perspective camera, with the same field-of-view
//! parameters).
//!
//! In its local frame (`to_world`) it shines along +z; a point `x` in local coordinates (z > 0)
//! sees the texel at `uv = ((1 − x/(z tanₓ)) / 2, (1 − y/(z tan_y)) / 2)` (the perspective
//! camera's film mapping, u right and v down, over the texture's aspect ratio). Mitsuba scales
//! the arriving light so that the *irradiance* on the plane z = 1 facing the projector is
//! `π · scale · texture(uv)`: the radiance-like value of a light sample is
//! `π · scale · texture(uv) / (z² cos θ)` (θ from the axis), i.e. an intensity
//! `I(ω) = π · scale · texture / cos³θ` for a unit-scale `to_world`. Nothing is emitted outside the
//! image's frustum.
//!
//! pbrt-v4's `projection` light is the same pinhole with another meaning of the image
//! ([`ProjectorEmission::Intensity`]): the texel is the intensity itself, `I(ω) = scale ·
//! texture(uv)` (W sr⁻¹), so the projected pattern falls off as cos³θ on a plane facing it.

use super::{EmissionSample, LightSample};
use crate::math::{Rgb, Transform, Vec2, Vec3, PI};
use crate::props::fov::{fov_from_props, tan_half, FovAxis};
use crate::props::{Obj, Result};
use crate::texture::Texture;

/// What a projector's image means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProjectorEmission {
    /// Mitsuba's: irradiance `π · scale · texture` on the plane at unit distance facing it.
    Irradiance,
    /// pbrt-v4's `projection` light: intensity `scale · texture` (W sr⁻¹) toward each texel.
    Intensity,
}

/// A projector light.
#[derive(Clone, Debug)]
pub struct Projector {
    /// Local frame → world.
    to_world: Transform,
    /// World → local frame.
    to_local: Transform,
    /// Position (world).
    position: Vec3,
    /// `to_world` applied to +z (not normalized, as Mitsuba's cosine uses it).
    axis: Vec3,
    /// Tangents of the half fields of view along local x and y.
    tan_half: Vec2,
    /// The projected image (irradiance at unit distance, before `π · scale`).
    irradiance: Texture,
    /// `scale`.
    scale: f32,
    /// What the image means.
    emission: ProjectorEmission,
}

impl Projector {
    /// A projector placed by `to_world` with a full field of view `fov_deg` (in (0°, 180°))
    /// along `axis` of its image, projecting `irradiance` (whose resolution sets the aspect
    /// ratio) times `scale`.
    pub fn new(to_world: Transform, fov_deg: f32, axis: FovAxis, irradiance: Texture, scale: f32) -> Projector {
        let (w, h) = irradiance.resolution();
        Projector {
            position: to_world.apply_point(Vec3::ZERO),
            axis: to_world.apply_vector(Vec3::Z),
            to_local: to_world.inverse(),
            to_world,
            tan_half: tan_half(fov_deg, axis, w as f32 / h as f32),
            irradiance,
            scale,
            emission: ProjectorEmission::Irradiance,
        }
    }

    /// The same projector with its image meaning `emission`.
    pub fn with_emission(self, emission: ProjectorEmission) -> Projector {
        Projector { emission, ..self }
    }

    /// Mitsuba's `projector`: `irradiance` (a texture, required; its resolution sets the aspect
    /// ratio), `scale` (1), `to_world`, and the perspective camera's `fov` / `fov_axis` /
    /// `focal_length`; neumann's `emission` (`irradiance`, Mitsuba's meaning and the default, or
    /// `intensity`, pbrt-v4's `projection` light) and `power` (W of luminance: the scale that
    /// emits it, as pbrt-v4's `power`).
    pub fn from_props(o: &Obj, irradiance: Texture) -> Result<Projector> {
        let to_world = o.transform("to_world")?;
        let scale = o.float("scale", 1.0)?;
        let (fov, axis) = fov_from_props(o)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(o.error_at("fov", format!("field of view must be in (0, 180) degrees, got {fov}")));
        }
        let emission = match o.choice("emission", &["irradiance", "intensity"])?.as_str() {
            "intensity" => ProjectorEmission::Intensity,
            _ => ProjectorEmission::Irradiance,
        };
        let p = Projector::new(to_world, fov, axis, irradiance, 1.0).with_emission(emission);
        match o.float_opt("power")? {
            None => Ok(Projector { scale, ..p }),
            Some(power) => {
                // As pbrt-v4: `scale` still multiplies the power asked for, and an intensity
                // image's power is pbrt's estimate from its texel centres.
                let unit = match emission {
                    ProjectorEmission::Intensity => p.intensity_power(p.irradiance.resolution()),
                    ProjectorEmission::Irradiance => p.power(),
                };
                if !(power > 0.0 && power.is_finite() && unit > 0.0 && unit.is_finite()) {
                    return Err(o.error_at(
                        "power",
                        format!("needs a positive power and an image that is not black, got {power}"),
                    ));
                }
                Ok(Projector { scale: scale * power / unit, ..p })
            }
        }
    }

    /// The texture coordinates of the local point `local` (`None` behind the projector or
    /// outside the image).
    fn uv(&self, local: Vec3) -> Option<Vec2> {
        if local.z <= 0.0 {
            return None;
        }
        let uv = Vec2::new(
            0.5 * (1.0 - local.x / (local.z * self.tan_half.x)),
            0.5 * (1.0 - local.y / (local.z * self.tan_half.y)),
        );
        (uv.x >= 0.0 && uv.x <= 1.0 && uv.y >= 0.0 && uv.y <= 1.0).then_some(uv)
    }

    /// Light arriving at `p_ref` (a delta light: `pdf` 1).
    pub fn sample_li(&self, p_ref: Vec3) -> Option<LightSample> {
        let local = self.to_local.apply_point(p_ref);
        let uv = self.uv(local)?;
        let d = self.position - p_ref;
        let dist = d.length();
        if dist == 0.0 {
            return None;
        }
        let wi = d / dist;
        let cos = -self.axis.dot(wi);
        let li = match self.emission {
            ProjectorEmission::Irradiance => self.irradiance.eval(uv) * (PI * self.scale / (local.z * local.z * cos)),
            ProjectorEmission::Intensity => self.irradiance.eval(uv) * (self.scale / (dist * dist)),
        };
        (cos > 0.0 && li.is_finite()).then(|| LightSample::from_point(self.position, wi, li))
    }

    /// Intensity (W sr⁻¹) toward the unit world direction `d`.
    pub fn intensity_toward(&self, d: Vec3) -> Rgb {
        // The light arriving at unit distance along d, times distance² = 1.
        self.sample_li(self.position + d).map_or(Rgb::ZERO, |s| s.li)
    }

    /// A ray of projected light: its image position uniform in uv, through the pinhole; the
    /// weight `π · scale · area · texture(uv)` (`area` the image's extent at unit distance;
    /// `scale · area · texture(uv) · cos³θ` for an intensity image, whose direction density is
    /// `1 / (area cos³θ)`), whose mean is the emitted power.
    pub fn sample_le(&self, u_dir: Vec2) -> Option<EmissionSample> {
        let x = (1.0 - 2.0 * u_dir.x) * self.tan_half.x;
        let y = (1.0 - 2.0 * u_dir.y) * self.tan_half.y;
        let d = self.to_world.apply_vector(Vec3::new(x, y, 1.0)).try_normalize()?;
        let weight = self.irradiance.eval(u_dir) * (self.scale * self.area() * self.density_factor(x, y));
        Some(EmissionSample { p: self.position, p_error: Vec3::ZERO, n: Vec3::ZERO, d, weight })
    }

    /// What turns `scale · texture` into emitted power per unit image area at unit distance,
    /// at the image point `(x, y, 1)` (local): π for an irradiance image, cos³θ (the solid angle
    /// per unit area there) for an intensity image.
    #[inline]
    fn density_factor(&self, x: f32, y: f32) -> f32 {
        match self.emission {
            ProjectorEmission::Irradiance => PI,
            ProjectorEmission::Intensity => (1.0 + x * x + y * y).powf(-1.5),
        }
    }

    /// The image's extent on the plane at unit distance.
    fn area(&self) -> f32 {
        4.0 * self.tan_half.x * self.tan_half.y
    }

    /// Emitted power (luminance, W): `π · scale · area · mean(texture)`; for an intensity image
    /// `scale · area · mean(texture · cos³θ)`, summed at the texel centres (as pbrt-v4 does) or
    /// on a 256² grid of the image if that is finer.
    pub fn power(&self) -> f32 {
        if self.emission == ProjectorEmission::Irradiance {
            return PI * self.scale * self.area() * crate::math::luminance(self.irradiance.mean());
        }
        let (w, h) = self.irradiance.resolution();
        self.intensity_power((w.clamp(256, 2048), h.clamp(256, 2048)))
    }

    /// `scale · area · mean(luminance(texture) · cos³θ)` of an intensity image, the mean taken
    /// over the centres of an `nx × ny` grid of the image.
    fn intensity_power(&self, (nx, ny): (u32, u32)) -> f32 {
        let mut sum = 0.0f64;
        for j in 0..ny {
            for i in 0..nx {
                let uv = Vec2::new((i as f32 + 0.5) / nx as f32, (j as f32 + 0.5) / ny as f32);
                let (x, y) = ((1.0 - 2.0 * uv.x) * self.tan_half.x, (1.0 - 2.0 * uv.y) * self.tan_half.y);
                sum += (crate::math::luminance(self.irradiance.eval(uv)) * self.density_factor(x, y)) as f64;
            }
        }
        self.scale * self.area() * (sum / (nx * ny) as f64) as f32
    }

    /// Position (world).
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// The unit axis, and the cosine of the widest angle of the image's frustum from it.
    pub fn cone(&self) -> (Vec3, f32) {
        let corner = Vec3::new(self.tan_half.x, self.tan_half.y, 1.0);
        (self.axis.normalize(), 1.0 / corner.length())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Transform;

    fn projector(texture: Texture) -> Projector {
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y).unwrap();
        Projector::new(to_world, 60.0, FovAxis::X, texture, 2.0)
    }

    /// The irradiance on the plane at unit distance facing a constant projector is π·scale·E;
    /// the weights of emitted rays average to the power, which integrating the intensity
    /// over the frustum gives too; points outside the frustum get nothing.
    #[test]
    fn irradiance_power_and_frustum() {
        let p = projector(Texture::Constant(Rgb::splat(0.5)));
        // Point on the axis at distance 3 (the plane z = 3 in the projector's frame).
        let s = p.sample_li(Vec3::new(0.0, 0.0, 1.0)).unwrap();
        assert!((s.li.x - PI * 2.0 * 0.5 / 9.0).abs() < 1e-5, "{}", s.li.x);
        // Off axis on the same plane: E = li cos θ, the same 1/z² law times cos θ / cos θ.
        let off = Vec3::new(1.0, 0.5, 1.0);
        let s = p.sample_li(off).unwrap();
        let cos = s.wi.dot(Vec3::Z);
        assert!((s.li.x * cos * 9.0 - PI * 2.0 * 0.5).abs() < 1e-4, "irradiance on the plane z = 3 is uniform");
        assert!(p.sample_li(Vec3::new(5.0, 0.0, 1.0)).is_none(), "outside the frustum");
        assert!(p.sample_li(Vec3::new(0.0, 0.0, 6.0)).is_none(), "behind");
        // Power: mean emitted weight vs the integral of the intensity over the sphere.
        let mut rng = crate::sampling::Pcg32::new(3, 5);
        let n = 200_000;
        let mut mean = 0.0f64;
        let mut integral = 0.0f64;
        for _ in 0..n {
            mean += p.sample_le(crate::testkit::u2(&mut rng)).unwrap().weight.x as f64 / n as f64;
            let w = crate::sampling::sample_uniform_sphere(crate::testkit::u2(&mut rng));
            integral += p.intensity_toward(w.value).x as f64 / w.pdf as f64 / n as f64;
        }
        let want = (PI * 2.0 * 0.5 * p.area()) as f64;
        assert!((mean - want).abs() < 1e-3 * want, "{mean} vs {want}");
        assert!((integral - want).abs() < 0.03 * want, "{integral} vs {want}");
        assert!((p.power() as f64 - want).abs() < 1e-3 * want);
    }

    /// pbrt-v4's `projection` light: the texel is the intensity, so the light on the axis at
    /// distance 3 is scale · texture / 9 and off the axis on the same plane the irradiance falls
    /// as cos³θ; emitted rays' weights, the intensity integrated over the sphere and `power()`
    /// agree.
    #[test]
    fn intensity_images_fall_off_as_cos_cubed() {
        let p = projector(Texture::Constant(Rgb::splat(0.5))).with_emission(ProjectorEmission::Intensity);
        let s = p.sample_li(Vec3::new(0.0, 0.0, 1.0)).unwrap();
        assert!((s.li.x - 2.0 * 0.5 / 9.0).abs() < 1e-6, "{}", s.li.x);
        let s = p.sample_li(Vec3::new(1.0, 0.5, 1.0)).unwrap();
        let cos = s.wi.dot(Vec3::Z);
        assert!((s.li.x * cos * 9.0 - 2.0 * 0.5 * cos.powi(3)).abs() < 1e-5, "E = I cos³θ / z²");
        let mut rng = crate::sampling::Pcg32::new(7, 5);
        let n = 400_000;
        let (mut mean, mut integral) = (0.0f64, 0.0f64);
        for _ in 0..n {
            mean += p.sample_le(crate::testkit::u2(&mut rng)).unwrap().weight.x as f64 / n as f64;
            let w = crate::sampling::sample_uniform_sphere(crate::testkit::u2(&mut rng));
            integral += p.intensity_toward(w.value).x as f64 / w.pdf as f64 / n as f64;
        }
        let power = p.power() as f64;
        assert!((mean - power).abs() < 2e-3 * power, "{mean} vs {power}");
        assert!((integral - power).abs() < 0.03 * power, "{integral} vs {power}");
    }
}
