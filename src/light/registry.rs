//! Emitter plugins by name: the registry the scene loaders look emitters up in. A new emitter
//! adds its constructor here (or beside it) and one line to [`EMITTER_PLUGINS`].
//!
//! Mitsuba's `area` emitter is not here: it is a property of the shape that emits, whose loader
//! reads its `radiance` ([`area_radiance_from_props`]).

use super::{
    DateTime, EnvMap, Goniometric, Light, Location, Projector, SpotFalloff, SunPlacement, SunSky, SunSkyParams,
};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Frame, Rgb, Vec3};
use crate::props::{Obj, Result};
use crate::texture::{Texture, TextureSource};

/// An emitter plugin's constructor (lights at infinity get the scene's bounds when it is built);
/// textured parameters and images come from the loader ([`TextureSource`]).
pub type EmitterPlugin = fn(&Obj, &mut dyn TextureSource) -> Result<Light>;

/// Every emitter plugin that stands on its own, by its (Mitsuba) name.
pub const EMITTER_PLUGINS: &[(&str, EmitterPlugin)] = &[
    ("point", point),
    ("spot", spot),
    ("projector", projector),
    ("goniometric", goniometric),
    ("directional", directional),
    ("constant", constant),
    ("envmap", envmap),
    ("sunsky", sunsky),
];

/// The constructor of the emitter plugin `name`.
pub fn emitter_plugin(name: &str) -> Option<EmitterPlugin> {
    EMITTER_PLUGINS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// Mitsuba's `area` emitter: `radiance` (W m⁻² sr⁻¹, an emission spectrum, default 1), a
/// colour or a texture over the shape's (u, v).
pub fn area_radiance_from_props(o: &Obj, textures: &mut dyn TextureSource) -> Result<crate::texture::Texture> {
    let t = textures.texture_of(o, "radiance", Rgb::ONE, SpectrumKind::Illuminant)?;
    if t.uses_position() {
        return Err(o.error_at("radiance", not_by_position("radiance")));
    }
    Ok(t)
}

/// neumann's `opacity` of an area emitter (pbrt-v4's alpha on an area light): the texture its
/// radiance is multiplied by, `None` when absent. Looked up by uv, as the radiance is.
pub fn area_opacity_from_props(o: &Obj, textures: &mut dyn TextureSource) -> Result<Option<crate::texture::Texture>> {
    if !o.has("opacity") {
        return Ok(None);
    }
    let t = textures.texture(o, "opacity", Rgb::ONE)?;
    if t.uses_position() {
        return Err(o.error_at("opacity", not_by_position("opacity")));
    }
    Ok(Some(t))
}

/// The error for a texture that varies with position (pbrt-v4's projections, 3D patterns,
/// `directionmix`) as an emitter's parameter: emitters look textures up by uv.
fn not_by_position(name: &str) -> String {
    format!(
        "a texture that varies with position or normal (a spherical, cylindrical or planar mapping, a 3D pattern,          directionmix) is not implemented as the '{name}' of an emitter: emitters look their textures up by uv"
    )
}

/// Mitsuba's `point`: `position` or `to_world` (not both), `intensity` (W sr⁻¹, 1).
fn point(o: &Obj, textures: &mut dyn TextureSource) -> Result<Light> {
    let position = match o.point_opt("position")? {
        Some(p) => {
            if o.has("to_world") {
                return Err(o.error_at("position", "give either 'position' or 'to_world'"));
            }
            p
        }
        None => o.transform("to_world")?.apply_point(Vec3::ZERO),
    };
    Ok(Light::Point { position, intensity: uniform_emission(o, "intensity", textures)? })
}

/// Mitsuba's `spot`: `to_world` (shining along local +z), `intensity` (1), `cutoff_angle`
/// (20°), `beam_width` (¾ of the cutoff; at most the cutoff, as Mitsuba clamps it), `texture`
/// (optional: an image projected over the cutoff cone, multiplying the intensity; uv = ½ + ½
/// (x, y) / (z tan cutoff) in the local frame);
/// neumann's `falloff`: `linear` in angle (Mitsuba's, the default) or `smoothstep` in cos θ
/// (pbrt-v4's).
fn spot(o: &Obj, textures: &mut dyn TextureSource) -> Result<Light> {
    let to_world = o.transform("to_world")?;
    let cutoff = o.float_checked("cutoff_angle", 20.0, |c| c > 0.0 && c <= 180.0, "in (0, 180] degrees")?;
    // A beam wider than the cutoff is the cutoff (a hard-edged cone), as Mitsuba 3.9.1 renders it.
    let beam = o.float_checked("beam_width", cutoff * 0.75, |b| b >= 0.0 && b.is_finite(), "≥ 0")?.min(cutoff);
    let axis = to_world.apply_vector(Vec3::Z).normalize();
    // The local frame's x and y orient a texture: to_world's axes, made orthonormal.
    let frame = Frame::from_zx(axis, to_world.apply_vector(Vec3::X));
    Ok(Light::Spot {
        position: to_world.apply_point(Vec3::ZERO),
        frame,
        intensity: uniform_emission(o, "intensity", textures)?,
        cutoff: cutoff.to_radians(),
        beam: beam.to_radians(),
        texture: without_mesh_attributes(o, "texture", textures.texture_opt(o, "texture", SpectrumKind::Reflectance)?)?
            .map(Box::new),
        falloff: match o.choice("falloff", &["linear", "smoothstep"])?.as_str() {
            "smoothstep" => SpotFalloff::SmoothStep,
            _ => SpotFalloff::Linear,
        },
    })
}

/// Rejects a `mesh_attribute` texture where there is no mesh to read it from.
fn without_mesh_attributes(
    o: &Obj,
    name: &str,
    t: Option<crate::texture::Texture>,
) -> Result<Option<crate::texture::Texture>> {
    match t {
        Some(t) if !t.mesh_attributes().is_empty() => {
            Err(o.error_at(name, format!("a mesh_attribute texture cannot be the '{name}' of a {} emitter", o.ty)))
        }
        Some(t) if t.uses_position() => Err(o.error_at(name, format!("{} (a {} emitter)", not_by_position(name), o.ty))),
        t => Ok(t),
    }
}

/// neumann's `goniometric` (pbrt-v4's; see [`Goniometric`]): `filename` (a square equal-area
/// image, required; sRGB-decoded if 8-bit), `intensity` (1, W sr⁻¹ where the diagram is 1),
/// `scale` (1), `power` (pbrt-v4's: the intensity scaled by power / (4π × the diagram's mean),
/// on top of `scale`), `to_world`.
fn goniometric(o: &Obj, textures: &mut dyn TextureSource) -> Result<Light> {
    let image = textures.image(o, "filename", false)?;
    let intensity = o.rgb("intensity", Rgb::ONE, SpectrumKind::Illuminant)?;
    let scale = o.float_checked("scale", 1.0, |s| s >= 0.0 && s.is_finite(), "a non-negative number")?;
    let to_world = o.transform("to_world")?;
    let mut g = Goniometric::new(to_world, &image, intensity * scale).map_err(|e| o.error_at("filename", e.to_string()))?;
    if let Some(power) = o.float_opt("power")? {
        let k = g.power() / crate::math::luminance(intensity * scale).max(f32::MIN_POSITIVE);
        if !(power > 0.0 && power.is_finite() && k > 0.0) {
            return Err(o.error_at("power", format!("needs a positive power and a diagram that is not black, got {power}")));
        }
        g = Goniometric::new(to_world, &image, intensity * scale * (power / k)).map_err(|e| o.error_at("filename", e.to_string()))?;
    }
    Ok(Light::Goniometric(Box::new(g)))
}

/// Mitsuba's `projector` (see [`Projector`]): `irradiance` (a texture, required), `scale`,
/// `to_world`, `fov` / `fov_axis` / `focal_length`.
fn projector(o: &Obj, textures: &mut dyn TextureSource) -> Result<Light> {
    let irradiance = textures.texture_opt(o, "irradiance", SpectrumKind::Illuminant)?;
    let irradiance = without_mesh_attributes(o, "irradiance", irradiance)?
        .ok_or_else(|| o.error("the projector needs an 'irradiance' (a texture or a colour)"))?;
    Ok(Light::Projector(Box::new(Projector::from_props(o, irradiance)?)))
}

/// Mitsuba's `directional`: `direction` or `to_world` (local +z), `irradiance` (W m⁻², 1).
fn directional(o: &Obj, textures: &mut dyn TextureSource) -> Result<Light> {
    let d = match o.point_opt("direction")? {
        Some(d) => d,
        None => o.transform("to_world")?.apply_vector(Vec3::Z),
    };
    if !(d.length() > 0.0 && d.is_finite()) {
        return Err(o.error_at("direction", "the direction must be a non-zero vector"));
    }
    Ok(Light::Directional {
        direction: d.normalize(),
        irradiance: uniform_emission(o, "irradiance", textures)?,
        center: Vec3::ZERO,
        radius: 0.0,
    })
}

/// An emitter parameter that Mitsuba reads as an emission texture but requires to be the same
/// everywhere: a colour, or a texture that does not vary (`srgb`, `rawconstant`).
fn uniform_emission(o: &Obj, name: &str, textures: &mut dyn TextureSource) -> Result<Rgb> {
    uniform_texture(o, name, Rgb::ONE, SpectrumKind::Illuminant, textures)
}

/// An emitter parameter of spectrum `kind` (default `default`) that Mitsuba reads as a texture
/// but requires to be the same everywhere.
fn uniform_texture(
    o: &Obj,
    name: &str,
    default: Rgb,
    kind: SpectrumKind,
    textures: &mut dyn TextureSource,
) -> Result<Rgb> {
    match textures.texture_of(o, name, default, kind)? {
        Texture::Constant(c) => Ok(c),
        _ => Err(o.error_at(
            name,
            format!(
                "the {} emitter's '{name}' must be the same everywhere (as Mitsuba requires), not a varying texture",
                o.ty
            ),
        )),
    }
}

/// Mitsuba's `constant`: `radiance` (1) from every direction.
fn constant(o: &Obj, textures: &mut dyn TextureSource) -> Result<Light> {
    Ok(Light::Constant { radiance: uniform_emission(o, "radiance", textures)?, center: Vec3::ZERO, radius: 0.0 })
}

/// Mitsuba's `sunsky` (Hošek–Wilkie sun and sky, see [`SunSky`]): `turbidity` (3), `albedo`
/// (0.3, a reflectance the same everywhere), `sun_scale` and `sky_scale` (1), `sun_aperture`
/// (0.5358°), `complex_sun` (false), `to_world` (the local +z is the zenith); the sun's place
/// either as `sun_direction` (world) or as a time and place — `latitude` (35.6894),
/// `longitude` (139.6917), `timezone` (9), `year` (2010), `month` (7), `day` (10), `hour`
/// (15), `minute` and `second` (0) — never both.
fn sunsky(o: &Obj, textures: &mut dyn TextureSource) -> Result<Light> {
    const TIME: [&str; 9] = ["latitude", "longitude", "timezone", "year", "month", "day", "hour", "minute", "second"];
    let sun = match o.point_opt("sun_direction")? {
        Some(d) => {
            if let Some(name) = TIME.iter().find(|n| o.has(n)) {
                return Err(o.error_at(
                    name,
                    "a sunsky takes either sun_direction or a time and place (latitude, …, second), not both (as in Mitsuba)",
                ));
            }
            SunPlacement::Direction(d)
        }
        None => {
            let (t, l) = (DateTime::default(), Location::default());
            let int = |name: &str, default: i32| -> Result<i32> {
                let v = o.int(name, default as i64)?;
                i32::try_from(v).map_err(|_| o.error_at(name, format!("{v} is out of range")))
            };
            // As in Mitsuba, month and day are not range-checked: the Julian-day formula rolls a
            // day past the month's end into the next month.
            let real = |name: &str, default: f32| o.float_checked(name, default, f32::is_finite, "finite");
            let time = DateTime {
                year: int("year", t.year)?,
                month: int("month", t.month)?,
                day: int("day", t.day)?,
                hour: real("hour", t.hour)?,
                minute: real("minute", t.minute)?,
                second: real("second", t.second)?,
            };
            let place = Location {
                latitude: real("latitude", l.latitude)?,
                longitude: real("longitude", l.longitude)?,
                timezone: real("timezone", l.timezone)?,
            };
            SunPlacement::Time(time, place)
        }
    };
    sunsky_with(o, textures, sun)
}

/// The sunsky `o` with the sun placed by `sun`: the parameters `sunsky` and `timed_sunsky`
/// share (`turbidity`, `albedo`, `sun_scale`, `sky_scale`, `sun_aperture`, `complex_sun`,
/// `to_world`), and its errors located.
fn sunsky_with(o: &Obj, textures: &mut dyn TextureSource, sun: SunPlacement) -> Result<Light> {
    let d = SunSkyParams::default();
    let params = SunSkyParams {
        sun,
        turbidity: o.float("turbidity", d.turbidity)?,
        albedo: uniform_texture(o, "albedo", d.albedo, SpectrumKind::Reflectance, textures)?,
        sun_scale: o.float("sun_scale", d.sun_scale)?,
        sky_scale: o.float("sky_scale", d.sky_scale)?,
        sun_aperture: o.float("sun_aperture", d.sun_aperture)?,
        complex_sun: o.bool("complex_sun", d.complex_sun)?,
        to_world: o.transform("to_world")?,
    };
    let sky = SunSky::new(&params).map_err(|e| {
        use super::SunSkyError as E;
        let at = match e {
            E::Turbidity(_) => "turbidity",
            E::Albedo(_) => "albedo",
            E::Scale(name, _) => name,
            E::Aperture(_) => "sun_aperture",
            E::Direction(_) => "sun_direction",
            E::Transform => "to_world",
            E::Overflow => {
                if o.has("sky_scale") {
                    "sky_scale"
                } else {
                    "sun_scale"
                }
            }
        };
        if o.has(at) {
            o.error_at(at, e.to_string())
        } else {
            o.error(e.to_string())
        }
    })?;
    Ok(Light::SunSky { sky: Box::new(sky), center: Vec3::ZERO, radius: 0.0 })
}

/// Mitsuba's `timed_sunsky` seen by rays at time `ray_time` (the sensor's, when its shutter
/// does not open over an interval): the sunsky (Mitsuba's `sunsky`'s shared parameters and
/// `latitude`, `longitude`, `timezone`) at the moment Mitsuba maps that time to. The emitter's
/// own `shutter_open` (0) to `shutter_close` (1) spans the days from `start_year` (2025),
/// `start_month` (1), `start_day` (1) to `end_year` (the start's plus one), `end_month`,
/// `end_day` (the start's) — at least one, whole days between the dates —, each day the hours
/// from `window_start_time` (7) to `window_end_time` (19): the time's fraction f of the
/// shutter falls on day ⌊f · days⌋ after the start, at the window's fraction of what is left.
pub fn timed_sunsky(o: &Obj, textures: &mut dyn TextureSource, ray_time: f32) -> Result<Light> {
    let open = o.float_checked("shutter_open", 0.0, f32::is_finite, "finite")?;
    let close = o.float_checked("shutter_close", 1.0, |c| c.is_finite() && c > open, "after shutter_open")?;
    let hour =
        |name: &str, default: f32| o.float_checked(name, default, |h| (0.0..=24.0).contains(&h), "an hour in [0, 24]");
    let (window_start, window_end) = (hour("window_start_time", 7.0)?, hour("window_end_time", 19.0)?);
    if window_start > window_end {
        return Err(o.error_at("window_end_time", "the window ends before it starts"));
    }
    let int = |name: &str, default: i32| -> Result<i32> {
        let v = o.int(name, default as i64)?;
        i32::try_from(v).map_err(|_| o.error_at(name, format!("{v} is out of range")))
    };
    let (year, month, day) = (int("start_year", 2025)?, int("start_month", 1)?, int("start_day", 1)?);
    let (end_year, end_month, end_day) = (int("end_year", year + 1)?, int("end_month", month)?, int("end_day", day)?);
    let days = super::day_number(end_year, end_month, end_day) - super::day_number(year, month, day);
    if days < 0 {
        return Err(o.error_at("end_year", "the end date is before the start date (as Mitsuba refuses it)"));
    }
    let days = days.max(1) as f32;
    let l = super::Location::default();
    let real = |name: &str, default: f32| o.float_checked(name, default, f32::is_finite, "finite");
    let place = super::Location {
        latitude: real("latitude", l.latitude)?,
        longitude: real("longitude", l.longitude)?,
        timezone: real("timezone", l.timezone)?,
    };
    // Mitsuba's mapping of the time to a day and an hour (single precision, as Mitsuba's).
    let f = (ray_time - open) / (close - open);
    let t = f * (days - f32::EPSILON / 2.0);
    let whole = t.floor();
    let time = super::DateTime {
        year,
        month,
        day: day.saturating_add(whole as i32),
        hour: window_start + (window_end - window_start) * (t - whole),
        minute: 0.0,
        second: 0.0,
    };
    sunsky_with(o, textures, SunPlacement::Time(time, place))
}

/// Mitsuba's `envmap`: `filename` (lat-long PNG or EXR), `scale` (1), `to_world`,
/// `mis_compensation` (false: the sampling density leaves directions no brighter than the
/// map's mean to BSDF sampling, as Mitsuba's; see `EnvMap::new_latlong`); neumann's `mapping`
/// (`latlong`, or pbrt-v4's `equal_area` square, which may take pbrt-v4's `illuminance`, or
/// `pbrt`: the equal-area square if the image is square, else pbrt-v3's latitude-longitude
/// layout, `u = φ/2π` with `φ = atan2(y, x)` and `v = θ/π` from the local +z).
fn envmap(o: &Obj, images: &mut dyn TextureSource) -> Result<Light> {
    let image = images.image(o, "filename", false)?;
    let scale = o.float("scale", 1.0)?;
    let mis_compensation = o.bool("mis_compensation", false)?;
    let mut to_world = o.transform("to_world")?;
    let mut mapping = o.choice("mapping", &["latlong", "equal_area", "pbrt"])?;
    if mapping == "pbrt" {
        mapping = if image.width == image.height { "equal_area".into() } else { "latlong".into() };
        if mapping == "latlong" {
            if o.has("illuminance") {
                return Err(o.error_at(
                    "illuminance",
                    "an illuminance is implemented for pbrt-v4's equal-area maps, not for latitude-longitude images",
                ));
            }
            // pbrt-v3's (x, y, z) of Mitsuba's local (x, y, z) is (−z, x, y): Mitsuba's u =
            // atan2(x, −z)/2π and v = acos(y)/π become atan2(y, x)/2π and acos(z)/π (a
            // reflection: the two layouts run φ in opposite senses).
            let m = crate::math::Mat4::from_cols(
                crate::math::Vec4::new(0.0, 1.0, 0.0, 0.0),
                crate::math::Vec4::new(0.0, 0.0, 1.0, 0.0),
                crate::math::Vec4::new(-1.0, 0.0, 0.0, 0.0),
                crate::math::Vec4::W,
            );
            to_world = to_world * crate::math::Transform::from_matrix(m).expect("orthogonal");
        }
    }
    let map = match mapping.as_str() {
        "equal_area" => {
            let mut scale = scale;
            if let Some(e) = o.float_opt("illuminance")? {
                let k = EnvMap::pbrt_illuminance(&image);
                if !(e > 0.0 && e.is_finite() && k > 0.0) {
                    return Err(
                        o.error_at("illuminance", "needs a positive illuminance and a map lit above its horizon")
                    );
                }
                scale *= e / k;
            }
            EnvMap::new_equal_area(image, scale, to_world, mis_compensation)
        }
        _ => EnvMap::new_latlong(image, scale, to_world, mis_compensation),
    }
    .map_err(|e| o.error(e.to_string()))?;
    // neumann's `portal_p0` … `portal_p3` (pbrt-v4's portal: the map shines only through that
    // rectangle, world space).
    let names = ["portal_p0", "portal_p1", "portal_p2", "portal_p3"];
    let map = if names.iter().any(|n| o.has(n)) {
        let mut corners = [Vec3::ZERO; 4];
        for (c, n) in corners.iter_mut().zip(names) {
            *c = o.point_opt(n)?.ok_or_else(|| o.error_at(names[0], "a portal needs all four corners portal_p0 … portal_p3"))?;
        }
        map.with_portal(super::Portal::new(corners).map_err(|e| o.error_at(names[0], e.to_string()))?)
    } else {
        map
    };
    Ok(Light::EnvMap { map: Box::new(map), center: Vec3::ZERO, radius: 0.0 })
}
