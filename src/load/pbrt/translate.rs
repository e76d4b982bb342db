//! pbrt-v4's plugins as neumann's (Mitsuba-named) plugin objects:
//!
//! - cameras `perspective` (`fov` on the shorter image axis, `lensradius` / `focaldistance` →
//!   thin lens, `screenwindow` and `frameaspectratio` → errors unless default) and
//!   `orthographic`; pbrt's camera space has +x to the image's right, Mitsuba's to its left, so
//!   the sensor's `to_world` is pbrt's world-from-camera times a mirror in x;
//! - `Film` `rgb` / `gbuffer` (`xresolution`, `yresolution`, `cropwindow`, `pixelbounds`;
//!   `filename` is the default output's name only; `iso` and the camera's shutter interval
//!   scale every light by pbrt's imaging ratio; `whitebalance` at its default), `PixelFilter`s (`box`, `gaussian`, `triangle` → tent, `mitchell`,
//!   `sinc`, with pbrt-v4's radii), `Sampler`s (`pixelsamples`; `zsobol`, `sobol`,
//!   `paddedsobol`, `halton` → Owen-scrambled Sobol, `pmj02bn`, `stratified` → stratified,
//!   `independent`), `Integrator`s (`path`, `volpath`, `lightpath` → `ptracer`, `simplepath`,
//!   `randomwalk` → `path`; `bdpt`, `mlt`, `sppm` → `path` with a warning; `maxdepth` bounces →
//!   `max_depth` = `maxdepth` + 1 segments);
//! - shapes `trianglemesh`, `plymesh` (also gzip-compressed), `bilinearmesh` (two triangles per
//!   patch), `sphere`, `disk`, `cylinder` (partial ones too), `curve` (→ neumann's `curve`);
//!   `alpha` (a float or float
//!   texture) → a `mask` of that opacity around the material (pbrt's stochastic alpha test in
//!   expectation) and, on an area light, the emitter's `opacity`;
//! - materials `diffuse`, `conductor` (`eta`/`k` of pbrt's named metals, RGB or spectra, or
//!   `reflectance`; `roughness`, `uroughness`, `vroughness`, `remaproughness`), `dielectric`,
//!   `thindielectric`, `hair`, `mix` (→ `blendbsdf`), `interface` (→ `null`), `coateddiffuse` and
//!   `coatedconductor` (→ the layered BSDF), `diffusetransmission`, `measured` (→ Mitsuba's, RGL
//!   tensor files); reflective ones wrapped in `twosided` (pbrt's BSDFs work from both sides);
//!   `normalmap` → Mitsuba's `normalmap`, `displacement` → neumann's `displacement` bump map;
//! - textures `imagemap`, `checkerboard` (2D and 3D), `scale`, `constant`, `mix`,
//!   `directionmix`, `bilerp`, `dots`, `fbm`, `wrinkled`, `windy`, `marble`, over pbrt's uv,
//!   spherical, cylindrical and planar mappings;
//! - lights `point`, `spot` (smoothstep falloff), `distant`, `infinite` (constant `L` or an
//!   equal-area image), `goniometric`, `projection` (→ a `projector` of intensity), area
//!   `diffuse`, with pbrt-v4's `power` and `illuminance`.
//!
//! Anything else is an error naming it; parameters not read are errors too.

use super::params::{ParamSet, SpectrumParam};
use super::parser::Parser;
use crate::math::{Mat3, Mat4, Rgb, Transform, Vec3};
use crate::props::{Loc, Obj, Prop, SceneError, SpectrumValue, Value};
use std::rc::Rc;

type Result<T> = std::result::Result<T, SceneError>;

/// A new object at `loc`.
pub(super) fn obj(tag: &str, ty: &str, loc: &Loc) -> Obj {
    Obj::new(tag, ty, loc.clone())
}

/// Sets property `name`, located at `loc`.
pub(super) fn set(o: &mut Obj, name: &str, value: Value, loc: &Loc) {
    o.set(name, value, loc.clone());
}

/// The location of parameter `name` (or of the directive).
pub(super) fn ploc(ps: &ParamSet, name: &str) -> Loc {
    ps.params.iter().find(|p| p.name == name).map_or(ps.loc.clone(), |p| p.loc.clone())
}

fn transform(m: Mat4, ps: &ParamSet) -> Result<Transform> {
    Transform::from_matrix(m).ok_or_else(|| ps.error("the current transform is singular"))
}

/// pbrt's default material: `diffuse` with reflectance 0.5.
pub fn default_material() -> Obj {
    let file =
        std::sync::Arc::new(crate::props::SourceFile { path: "pbrt default material".into(), text: String::new() });
    let loc = Loc { file, offset: 0 };
    let mut o = obj("bsdf", "diffuse", &loc);
    set(&mut o, "reflectance", Value::Float(0.5), &loc);
    o
}

/// `Option`: the options that cannot change the expected image (`rendercoordsys`, `wavefront`,
/// `pixelstats`, `msereferenceimage`, `msereferenceout`) are accepted; the others are errors.
pub fn option(_: &mut Parser, ps: &ParamSet) -> Result<()> {
    for p in &ps.params {
        match p.name.as_str() {
            "rendercoordsys" | "wavefront" | "pixelstats" | "msereferenceimage" | "msereferenceout" => p.used.set(true),
            "disablepixeljitter"
            | "disabletexturefiltering"
            | "disablewavelengthjitter"
            | "forcediffuse"
            | "displacementedgescale"
            | "seed" => {
                return Err(ps.error_at(&p.name, format!("Option \"{}\" is not implemented by neumann", p.name)))
            }
            _ => return Err(ps.error_at(&p.name, format!("unknown Option \"{}\"", p.name))),
        }
    }
    Ok(())
}

/// A spectrum parameter as a property value: `illuminant` says how pbrt reads it (lights:
/// RGB as given, named standard illuminants normalised to luminance 1).
fn spectrum_value(ps: &ParamSet, name: &str, s: SpectrumParam, illuminant: bool) -> Result<Value> {
    Ok(match s {
        SpectrumParam::Rgb(c) => Value::Rgb(c),
        SpectrumParam::Constant(v) => Value::Float(v as f64),
        SpectrumParam::Samples(v) if illuminant => Value::Rgb(unit_luminance(&v)),
        SpectrumParam::Samples(v) => Value::Spectrum(SpectrumValue::Samples(v)),
        SpectrumParam::Named(n) if illuminant && n == "stdillum-D65" => Value::Float(1.0),
        SpectrumParam::Named(n) => match named_illuminant(&n).filter(|_| illuminant) {
            Some(samples) => Value::Rgb(unit_luminance(&samples)),
            None => return Err(ps.error_at(name, format!("the named spectrum \"{n}\" is not available here (neumann knows pbrt's metal-*-eta/k for conductors, glass-* for dielectrics, and stdillum-A, -D50, -D65, -F1 … -F12 and illum-acesD60 for lights)")))
        }
        SpectrumParam::Blackbody(t) if illuminant => Value::Rgb(blackbody_rgb(t)),
        SpectrumParam::Blackbody(_) => return Err(ps.error_at(name, "a blackbody spectrum is for emitted light only")),
    })
}

/// The linear sRGB colour of an emission spectrum as pbrt-v4's `SpectrumToXYZ` gives it, not
/// normalised: an rgb as given, a constant or sampled spectrum integrated against the CIE
/// curves, a black body normalised to 1 at its peak (pbrt-v4's `BlackbodySpectrum`).
fn absolute_rgb(ps: &ParamSet, name: &str, s: SpectrumParam) -> Result<Rgb> {
    use crate::math::spectrum::{spectrum_to_rgb, SpectrumKind};
    Ok(match s {
        SpectrumParam::Rgb(c) => c,
        SpectrumParam::Constant(v) => spectrum_to_rgb(&[(360.0, v), (830.0, v)], SpectrumKind::Illuminant),
        SpectrumParam::Samples(v) => spectrum_to_rgb(&v, SpectrumKind::Illuminant),
        SpectrumParam::Blackbody(t) => {
            spectrum_to_rgb(&crate::math::spectrum::blackbody(t, true), SpectrumKind::Illuminant)
        }
        SpectrumParam::Named(n) if n == "stdillum-D65" => Rgb::ONE,
        SpectrumParam::Named(n) => match named_illuminant(&n) {
            Some(samples) => unit_luminance(&samples),
            None => return Err(ps.error_at(name, format!("the named spectrum \"{n}\" is not available here"))),
        },
    })
}

/// pbrt-v4's named standard illuminants (pbrt normalises each to
/// luminance 1, so only the shape matters): CIE illuminant A, Planck's law at 2856 K on the
/// 1931 radiation constant (`S(λ) ∝ λ⁻⁵ / (exp(1.435 × 10⁷ / (2848 λ)) − 1)`, λ in nm, the
/// CIE's definition), and D50, CIE daylight at 5000 K on the 1931 constant (5003 K); and the
/// tabulated ones ([`super::illuminants`]: F1–F12, ACES D60).
fn named_illuminant(name: &str) -> Option<Vec<(f32, f32)>> {
    match name {
        "stdillum-A" => Some(
            (0..=94)
                .map(|i| {
                    let nm = 360.0 + 5.0 * i as f64;
                    let s = 100.0 * (560.0 / nm).powi(5) * ((1.435e7f64 / (2848.0 * 560.0)).exp() - 1.0)
                        / ((1.435e7 / (2848.0 * nm)).exp() - 1.0);
                    (nm as f32, s as f32)
                })
                .collect(),
        ),
        "stdillum-D50" => Some(crate::math::spectrum::daylight(5000.0)),
        _ => super::illuminants::tabulated(name),
    }
}

/// The linear sRGB colour of a black body at `kelvin`, at luminance 1 (pbrt-v4 normalises a
/// light's spectrum to 1 nit, which its sRGB film shows as Y = 1).
pub fn blackbody_rgb(kelvin: f32) -> Rgb {
    unit_luminance(&crate::math::spectrum::blackbody(kelvin, false))
}

/// The linear sRGB colour of an emission spectrum (wavelength nm, value) at luminance 1: pbrt-v4
/// divides a light's spectrum by its luminance, so only its colour matters (its `scale`,
/// `power` or `illuminance` sets the brightness).
fn unit_luminance(samples: &[(f32, f32)]) -> Rgb {
    let rgb = crate::math::spectrum::spectrum_to_rgb(samples, crate::math::spectrum::SpectrumKind::Illuminant);
    rgb / crate::math::luminance(rgb).max(1e-30)
}

/// A texturable parameter: a `texture` reference (to a texture of `class`) or a spectrum or
/// float value; `None` if absent.
fn texturable(p: &Parser, ps: &ParamSet, name: &str, float: bool) -> Result<Option<Value>> {
    match ps.type_of(name) {
        None => Ok(None),
        Some("texture") => {
            let t = ps.string_of(name, "texture")?.expect("present");
            let table = if float { &p.float_textures } else { &p.spectrum_textures };
            match table.get(&t) {
                Some(o) => Ok(Some(Value::Object(o.clone()))),
                None => Err(
                    ps.error_at(name, format!("no {} texture named \"{t}\"", if float { "float" } else { "spectrum" }))
                ),
            }
        }
        Some(_) if float => Ok(Some(Value::Float(ps.float(name, 0.0)? as f64))),
        Some(_) => {
            let s = ps.spectrum(name)?.expect("present");
            spectrum_value(ps, name, s, false).map(Some)
        }
    }
}

/// pbrt-v4's 2D texture mapping of `ps` on `o`: `uv` (`uscale`, `vscale`, `udelta`,
/// `vdelta`: s = su u + du, t = sv v + dv), `spherical`, `cylindrical` or `planar` (`v1`, `v2`,
/// `udelta`, `vdelta`) about the texture's space (the current transform). `after` maps (s, t)
/// on to the lookup coordinates of `o` (an image's t axis points up; a checkerboard cell is
/// half of Mitsuba's).
fn mapping_2d(p: &Parser, ps: &ParamSet, o: &mut Obj, after: Mat3) -> Result<()> {
    let mapping = ps.string("mapping")?.unwrap_or_else(|| "uv".into());
    let st = match mapping.as_str() {
        "uv" => {
            let (su, sv) = (ps.float("uscale", 1.0)?, ps.float("vscale", 1.0)?);
            let (du, dv) = (ps.float("udelta", 0.0)?, ps.float("vdelta", 0.0)?);
            Mat3::from_cols(Vec3::new(su, 0.0, 0.0), Vec3::new(0.0, sv, 0.0), Vec3::new(du, dv, 1.0))
        }
        "spherical" | "cylindrical" | "planar" => {
            set(o, "mapping", Value::String(mapping.clone()), &ploc(ps, "mapping"));
            set(o, "to_world", Value::Transform(transform(p.gs.ctm, ps)?), &ps.loc);
            if mapping == "planar" {
                set(o, "v1", Value::Vector(ps.point("v1", Vec3::X)?), &ploc(ps, "v1"));
                set(o, "v2", Value::Vector(ps.point("v2", Vec3::Y)?), &ploc(ps, "v2"));
                set(o, "udelta", Value::Float(ps.float("udelta", 0.0)? as f64), &ploc(ps, "udelta"));
                set(o, "vdelta", Value::Float(ps.float("vdelta", 0.0)? as f64), &ploc(ps, "vdelta"));
            }
            Mat3::IDENTITY
        }
        other => {
            return Err(ps.error_at(
                "mapping",
                format!("unknown texture mapping \"{other}\" (uv, spherical, cylindrical, planar)"),
            ))
        }
    };
    let m = after * st;
    use crate::math::Vec4;
    let m4 = Mat4::from_cols(
        Vec4::new(m.x_axis.x, m.x_axis.y, 0.0, 0.0),
        Vec4::new(m.y_axis.x, m.y_axis.y, 0.0, 0.0),
        Vec4::Z,
        Vec4::new(m.z_axis.x, m.z_axis.y, 0.0, 1.0),
    );
    let t = Transform::from_matrix(m4).ok_or_else(|| ps.error("uscale and vscale must not be zero"))?;
    if !t.is_identity() {
        set(o, "to_uv", Value::Transform(t), &ps.loc);
    }
    Ok(())
}

/// A texture whose class is one of pbrt's float textures only (`fbm`, `wrinkled`, `windy`) or
/// spectrum textures only (`marble`).
fn only_class(ps: &ParamSet, ty: &str, class: &str, expected: &str) -> Result<()> {
    if class != expected {
        return Err(ps.error(format!("pbrt-v4's \"{ty}\" texture is a {expected} texture, not a {class} one")));
    }
    Ok(())
}

/// A texture of texture space (the current transform): `to_world` on `o`.
fn texture_space(p: &Parser, ps: &ParamSet, o: &mut Obj) -> Result<()> {
    set(o, "to_world", Value::Transform(transform(p.gs.ctm, ps)?), &ps.loc);
    Ok(())
}

/// A noise texture's `octaves` (8) and `roughness` (0.5) on `o`.
fn octave_params(ps: &ParamSet, o: &mut Obj) -> Result<()> {
    set(o, "octaves", Value::Integer(ps.int("octaves", 8)?), &ploc(ps, "octaves"));
    set(o, "roughness", Value::Float(ps.float("roughness", 0.5)? as f64), &ploc(ps, "roughness"));
    Ok(())
}

/// Sets `o`'s texturable `name` from pbrt's `from` (if given).
fn pass_texturable(p: &Parser, ps: &ParamSet, o: &mut Obj, from: &str, name: &str, float: bool) -> Result<()> {
    if let Some(v) = texturable(p, ps, from, float)? {
        set(o, name, v, &ploc(ps, from));
    }
    Ok(())
}

/// `Texture`: `imagemap`, `checkerboard` (2D and 3D), `scale`, `constant`, `mix`,
/// `directionmix`, `bilerp`, `dots`, `fbm`, `wrinkled`, `windy`, `marble`.
pub fn texture(p: &mut Parser, ty: &str, class: &str, ps: &ParamSet) -> Result<Obj> {
    let float = class == "float";
    // pbrt looks images up with t pointing up (1 − t down the rows).
    let flip_t = Mat3::from_cols(Vec3::X, -Vec3::Y, Vec3::new(0.0, 1.0, 1.0));
    let o = match ty {
        "imagemap" => {
            let mut o = obj("texture", "bitmap", &ps.loc);
            let file = ps.string("filename")?.ok_or_else(|| ps.error("an imagemap needs its \"string filename\""))?;
            if float {
                // pbrt-v4's float image: the alpha, or the mean of the colour (not its luminance).
                set(&mut o, "pbrt_scalar", Value::Bool(true), &ps.loc);
            }
            // pbrt-v4 decodes PNG files as sRGB and every other file as linear by default.
            let png = file.to_ascii_lowercase().ends_with(".png");
            set(&mut o, "filename", Value::String(file), &ploc(ps, "filename"));
            let encoding = ps.string("encoding")?.unwrap_or_else(|| if png { "sRGB" } else { "linear" }.into());
            let gamma = encoding.strip_prefix("gamma ").and_then(|g| g.trim().parse::<f32>().ok());
            match (encoding.as_str(), gamma) {
                ("sRGB", _) => {}
                ("linear", _) => set(&mut o, "raw", Value::Bool(true), &ploc(ps, "encoding")),
                (_, Some(g)) if g > 0.0 && g.is_finite() => {
                    set(&mut o, "gamma", Value::Float(g as f64), &ploc(ps, "encoding"))
                }
                (other, _) => {
                    return Err(ps.error_at(
                        "encoding",
                        format!("unknown encoding \"{other}\" (sRGB, linear or \"gamma G\" with G > 0)"),
                    ))
                }
            }
            match ps.string("filter")?.as_deref() {
                None | Some("bilinear") | Some("trilinear") | Some("ewa") => {}
                Some("point") => set(&mut o, "filter_type", Value::String("nearest".into()), &ploc(ps, "filter")),
                Some(other) => return Err(ps.error_at("filter", format!("unknown filter \"{other}\""))),
            }
            // pbrt's anisotropic filtering width: neumann filters by sampling the pixel.
            ps.float("maxanisotropy", 8.0)?;
            let wrap = match ps.string("wrap")?.as_deref() {
                None | Some("repeat") => "repeat",
                Some("clamp") => "clamp",
                Some("octahedralsphere") => "octahedral_sphere",
                Some("black") => "black",
                Some(other) => return Err(ps.error_at("wrap", format!("unknown wrap \"{other}\""))),
            };
            set(&mut o, "wrap_mode", Value::String(wrap.into()), &ps.loc);
            let invert = ps.bool("invert", false)?;
            let scale = ps.float("scale", 1.0)?;
            mapping_2d(p, ps, &mut o, flip_t)?;
            let scaled = if scale != 1.0 {
                scale_texture(Value::Object(Rc::new(o)), scale, &ps.loc, &ploc(ps, "scale"))
            } else {
                o
            };
            // pbrt-v4: max(0, 1 − scale · v).
            if invert {
                let mut inv = obj("texture", "invert", &ps.loc);
                set(&mut inv, "tex", Value::Object(Rc::new(scaled)), &ploc(ps, "invert"));
                inv
            } else {
                scaled
            }
        }
        "checkerboard" => {
            let mut o = obj("texture", "mix", &ps.loc);
            pass_texturable(p, ps, &mut o, "tex1", "tex1", float)?;
            if !ps.has("tex1") {
                set(&mut o, "tex1", Value::Float(1.0), &ps.loc);
            }
            pass_texturable(p, ps, &mut o, "tex2", "tex2", float)?;
            if !ps.has("tex2") {
                set(&mut o, "tex2", Value::Float(0.0), &ps.loc);
            }
            let cells = match ps.int("dimension", 2)? {
                2 => {
                    // pbrt: tex1 where ⌊s⌋ + ⌊t⌋ is even. Mitsuba's checkerboard has color0
                    // where the fractional parts of its (u, v) lie on the same side of ½: the
                    // same cells at half the frequency; its colour lookup gives the amount.
                    let mut c = obj("texture", "checkerboard", &ps.loc);
                    set(&mut c, "color0", Value::Float(0.0), &ps.loc);
                    set(&mut c, "color1", Value::Float(1.0), &ps.loc);
                    mapping_2d(p, ps, &mut c, Mat3::from_scale(crate::math::Vec2::splat(0.5)))?;
                    c
                }
                3 => {
                    let mut c = obj("texture", "checkerboard3d", &ps.loc);
                    set(&mut c, "tex1", Value::Float(0.0), &ps.loc);
                    set(&mut c, "tex2", Value::Float(1.0), &ps.loc);
                    texture_space(p, ps, &mut c)?;
                    c
                }
                d => return Err(ps.error_at("dimension", format!("a checkerboard has dimension 2 or 3, not {d}"))),
            };
            set(&mut o, "amount", Value::Object(Rc::new(cells)), &ps.loc);
            o
        }
        "scale" => {
            let mut o = obj("texture", "scale", &ps.loc);
            pass_texturable(p, ps, &mut o, "tex", "tex", float)?;
            pass_texturable(p, ps, &mut o, "scale", "scale", true)?;
            o
        }
        "constant" => {
            let v = texturable(p, ps, "value", float)?.unwrap_or(Value::Float(1.0));
            let mut o = obj("texture", "scale", &ps.loc);
            set(&mut o, "tex", v, &ploc(ps, "value"));
            o
        }
        "mix" => {
            let mut o = obj("texture", "mix", &ps.loc);
            pass_texturable(p, ps, &mut o, "tex1", "tex1", float)?;
            pass_texturable(p, ps, &mut o, "tex2", "tex2", float)?;
            pass_texturable(p, ps, &mut o, "amount", "amount", true)?;
            o
        }
        "directionmix" => {
            let mut o = obj("texture", "directionmix", &ps.loc);
            pass_texturable(p, ps, &mut o, "tex1", "tex1", float)?;
            pass_texturable(p, ps, &mut o, "tex2", "tex2", float)?;
            set(&mut o, "dir", Value::Vector(ps.point("dir", Vec3::Y)?), &ploc(ps, "dir"));
            texture_space(p, ps, &mut o)?;
            o
        }
        "bilerp" => {
            let mut o = obj("texture", "bilerp", &ps.loc);
            for (name, default) in [("v00", 0.0), ("v01", 1.0), ("v10", 0.0), ("v11", 1.0)] {
                let v = if float {
                    Value::Float(ps.float(name, default)? as f64)
                } else {
                    match ps.spectrum(name)? {
                        Some(s) => spectrum_value(ps, name, s, false)?,
                        None => Value::Float(default as f64),
                    }
                };
                set(&mut o, name, v, &ploc(ps, name));
            }
            mapping_2d(p, ps, &mut o, Mat3::IDENTITY)?;
            o
        }
        "dots" => {
            let mut o = obj("texture", "dots", &ps.loc);
            pass_texturable(p, ps, &mut o, "inside", "inside", float)?;
            pass_texturable(p, ps, &mut o, "outside", "outside", float)?;
            mapping_2d(p, ps, &mut o, Mat3::IDENTITY)?;
            o
        }
        "fbm" | "wrinkled" | "windy" => {
            only_class(ps, ty, class, "float")?;
            let mut o = obj("texture", ty, &ps.loc);
            if ty != "windy" {
                octave_params(ps, &mut o)?;
            }
            texture_space(p, ps, &mut o)?;
            o
        }
        "marble" => {
            only_class(ps, ty, class, "spectrum")?;
            let mut o = obj("texture", "marble", &ps.loc);
            octave_params(ps, &mut o)?;
            set(&mut o, "scale", Value::Float(ps.float("scale", 1.0)? as f64), &ploc(ps, "scale"));
            set(&mut o, "variation", Value::Float(ps.float("variation", 0.2)? as f64), &ploc(ps, "variation"));
            texture_space(p, ps, &mut o)?;
            o
        }
        "ptex" => {
            return Err(
                ps.error("ptex textures (per-face images of Disney's Ptex format) are not implemented by neumann")
            )
        }
        other => {
            return Err(ps.unknown(
                "texture class",
                other,
                &[
                    "bilerp",
                    "checkerboard",
                    "constant",
                    "directionmix",
                    "dots",
                    "fbm",
                    "imagemap",
                    "marble",
                    "mix",
                    "ptex",
                    "scale",
                    "windy",
                    "wrinkled",
                ],
            ))
        }
    };
    Ok(o)
}

/// pbrt-v4's roughness parameters `{prefix}roughness`, `{prefix}uroughness` and
/// `{prefix}vroughness` (default 0) as an α pair (`remaproughness`: α = √roughness).
fn roughness_pair(p: &Parser, ps: &ParamSet, prefix: &str) -> Result<(Value, Value)> {
    let remap = ps.bool("remaproughness", true)?;
    let name = |n: &str| format!("{prefix}{n}");
    let r = texturable(p, ps, &name("roughness"), true)?;
    let u = texturable(p, ps, &name("uroughness"), true)?.or(r.clone()).unwrap_or(Value::Float(0.0));
    let v = texturable(p, ps, &name("vroughness"), true)?.or(r).unwrap_or(Value::Float(0.0));
    let alpha = |x: Value| -> Result<Value> {
        match x {
            Value::Float(f) => Ok(Value::Float(if remap { f.max(0.0).sqrt() } else { f })),
            t if !remap => Ok(t),
            t => {
                let mut o = obj("texture", "sqrt", &ps.loc);
                set(&mut o, "tex", t, &ps.loc);
                Ok(Value::Object(Rc::new(o)))
            }
        }
    };
    Ok((alpha(u)?, alpha(v)?))
}

/// [`roughness_pair`] for neumann's one-lobe BSDFs: `None` when smooth (both zero).
fn roughness(p: &Parser, ps: &ParamSet) -> Result<Option<(Value, Value)>> {
    match roughness_pair(p, ps, "")? {
        (Value::Float(a), Value::Float(b)) if a == 0.0 && b == 0.0 => Ok(None),
        (Value::Float(a), Value::Float(b)) if a == 0.0 || b == 0.0 => Err(ps.error_at(
            "uroughness",
            "one of uroughness and vroughness is zero: neumann needs both rough or both smooth",
        )),
        (u, v) => Ok(Some((u, v))),
    }
}

/// A conductor's complex index from `{prefix}eta` / `{prefix}k` (pbrt's default: copper) or
/// `reflectance`, set on `o` as Mitsuba's `material` or `eta` / `k`.
fn conductor_ior(p: &Parser, ps: &ParamSet, o: &mut Obj, prefix: &str) -> Result<()> {
    let (eta_name, k_name) = (format!("{prefix}eta"), format!("{prefix}k"));
    if ps.has("reflectance") {
        // pbrt-v4: η = 1 and k = 2√r / √(1 − r), which reflects r at normal incidence; a
        // textured reflectance gives k per lookup (neumann's `conductor_k` texture).
        let at = ploc(ps, "reflectance");
        let k = match texturable(p, ps, "reflectance", false)?.expect("present") {
            Value::Rgb(c) => Value::Rgb(c.map(crate::texture::conductor_k)),
            Value::Float(v) => Value::Float(crate::texture::conductor_k(v as f32) as f64),
            Value::Spectrum(SpectrumValue::Samples(v)) => Value::Rgb(
                crate::math::spectrum::spectrum_to_rgb(&v, crate::math::spectrum::SpectrumKind::Reflectance)
                    .map(crate::texture::conductor_k),
            ),
            t @ Value::Object(_) => {
                let mut k = obj("texture", "conductor_k", &at);
                set(&mut k, "tex", t, &at);
                Value::Object(Rc::new(k))
            }
            _ => {
                return Err(
                    ps.error_at("reflectance", "a conductor's reflectance must be an rgb, a constant or a texture")
                )
            }
        };
        set(o, "eta", Value::Float(1.0), &at);
        set(o, "k", k, &at);
        return Ok(());
    }
    let eta = ps.spectrum(&eta_name)?.unwrap_or(SpectrumParam::Named("metal-Cu-eta".into()));
    let k = ps.spectrum(&k_name)?.unwrap_or(SpectrumParam::Named("metal-Cu-k".into()));
    match (&eta, &k) {
        (SpectrumParam::Named(e), SpectrumParam::Named(kk)) => {
            let metal = e.strip_prefix("metal-").and_then(|m| m.strip_suffix("-eta"));
            let metal_k = kk.strip_prefix("metal-").and_then(|m| m.strip_suffix("-k"));
            match (metal, metal_k) {
                (Some(a), Some(b)) if a == b && crate::material::named_conductor(a).is_some() => {
                    set(o, "material", Value::String(a.into()), &ploc(ps, &eta_name))
                }
                _ => return Err(ps.error_at(&eta_name, format!("the conductor spectra \"{e}\" / \"{kk}\" are not available in neumann (named metals: Ag, Al, Au, Cu, MgO, TiO2, …, eta and k of the same metal)"))),
            }
        }
        _ => {
            set(o, "eta", spectrum_value(ps, &eta_name, eta, false)?, &ploc(ps, &eta_name));
            set(o, "k", spectrum_value(ps, &k_name, k, false)?, &ploc(ps, &k_name));
        }
    }
    Ok(())
}

/// The coating's index: a float or a constant / named spectrum (`eta`, `interface.eta`).
fn dielectric_eta(ps: &ParamSet, name: &str) -> Result<f32> {
    Ok(match ps.type_of(name) {
        None => 1.5,
        Some("float") => ps.float(name, 1.5)?,
        Some(_) => match ps.spectrum(name)? {
            Some(SpectrumParam::Constant(v)) => v,
            Some(SpectrumParam::Named(n)) => {
                named_ior(&n).ok_or_else(|| ps.error_at(name, format!("unknown glass \"{n}\"")))?
            }
            _ => return Err(ps.error_at(name, "a spectrally varying eta (dispersion) is not implemented by neumann")),
        },
    })
}

/// pbrt's coated materials' layer: `thickness`, `albedo`, `g`, `maxdepth`, `nsamples`.
fn layer_params(p: &Parser, ps: &ParamSet, o: &mut Obj) -> Result<()> {
    if let Some(t) = texturable(p, ps, "thickness", true)? {
        set(o, "thickness", t, &ploc(ps, "thickness"));
    }
    if let Some(a) = texturable(p, ps, "albedo", false)? {
        set(o, "albedo", a, &ploc(ps, "albedo"));
    }
    if let Some(g) = texturable(p, ps, "g", true)? {
        set(o, "g", g, &ploc(ps, "g"));
    }
    set(o, "max_depth", Value::Integer(ps.int("maxdepth", 10)?), &ploc(ps, "maxdepth"));
    set(o, "nsamples", Value::Integer(ps.int("nsamples", 1)?), &ploc(ps, "nsamples"));
    Ok(())
}

/// `o` wrapped in Mitsuba's `twosided`: pbrt's reflective BSDFs work from both sides.
fn two_sided(o: Obj) -> Obj {
    let mut t = obj("bsdf", "twosided", &o.loc);
    t.children.push(Rc::new(o));
    t
}

/// Whether `name` is one of pbrt-v4's named spectra (its `GetNamedSpectrum`: glasses, metals,
/// standard illuminants, camera sensors' responses); any other string given for a `spectrum`
/// parameter names a spectrum file.
pub fn is_named_spectrum(name: &str) -> bool {
    const METALS: &[&str] = &["Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"];
    const SENSORS: &[&str] = &["canon_eos_", "hasselblad_", "nikon_", "sony_ilce_"];
    if let Some(metal) = name.strip_prefix("metal-") {
        return METALS.iter().any(|m| metal == format!("{m}-eta") || metal == format!("{m}-k"));
    }
    if let Some(illum) = name.strip_prefix("stdillum-") {
        return matches!(illum, "A" | "D50" | "D65") || super::illuminants::tabulated(name).is_some();
    }
    named_ior(name).is_some()
        || name == "illum-acesD60"
        || (SENSORS.iter().any(|p| name.starts_with(p)) && ["_r", "_g", "_b"].iter().any(|c| name.ends_with(c)))
}

/// pbrt's named glasses at the d line (587.6 nm): neumann's dielectrics do not disperse.
fn named_ior(name: &str) -> Option<f32> {
    Some(match name {
        "glass-BK7" => 1.5168,
        "glass-BAF10" => 1.6700,
        "glass-FK51A" => 1.4866,
        "glass-LASF9" => 1.8503,
        "glass-F5" | "glass-SF5" => 1.6034,
        "glass-F10" | "glass-SF10" => 1.7283,
        "glass-F11" | "glass-SF11" => 1.7847,
        _ => return None,
    })
}

/// `Material` / `MakeNamedMaterial`.
pub fn material(p: &mut Parser, ty: &str, ps: &ParamSet) -> Result<Obj> {
    let displacement = texturable(p, ps, "displacement", true)?;
    let mut bsdf = material_bsdf(p, ty, ps)?;
    let ty = if ty.is_empty() || ty == "none" { "interface" } else { ty };
    if displacement.is_some() && (ty == "interface" || ty == "mix") {
        return Err(ps.error_at("displacement", format!("a \"{ty}\" material takes no displacement")));
    }
    // pbrt-v4 applies the normal map when there is one, else the displacement.
    bsdf = match ps.string("normalmap")? {
        Some(file) if ty != "interface" && ty != "mix" => normal_mapped(bsdf, file, &ploc(ps, "normalmap")),
        Some(_) => return Err(ps.error_at("normalmap", format!("a \"{ty}\" material takes no normal map"))),
        None => match displacement {
            Some(d) => displaced(bsdf, d, &ploc(ps, "displacement")),
            None => bsdf,
        },
    };
    Ok(bsdf)
}

/// pbrt-v4's `displacement` (a float texture, world units along the shading normal): neumann's
/// `displacement` bump map, without Mitsuba's invalid-normal flip and shadowing term.
fn displaced(bsdf: Obj, displacement: Value, loc: &Loc) -> Obj {
    let mut n = obj("bsdf", "displacement", loc);
    set(&mut n, "displacement", displacement, loc);
    set(&mut n, "flip_invalid_normals", Value::Bool(false), loc);
    set(&mut n, "use_shadowing_function", Value::Bool(false), loc);
    n.children.push(Rc::new(bsdf));
    n
}

/// pbrt-v4's `normalmap`: tangent-space normals `2 rgb − 1` read linearly, bilinear, repeating,
/// at (u, 1 − v), in the frame of ∂p/∂u and the shading normal: Mitsuba's `normalmap` without
/// its invalid-normal flip and shadowing term, which pbrt does not apply.
fn normal_mapped(bsdf: Obj, file: String, loc: &Loc) -> Obj {
    let mut t = obj("texture", "bitmap", loc);
    set(&mut t, "filename", Value::String(file), loc);
    set(&mut t, "raw", Value::Bool(true), loc);
    set(&mut t, "wrap_mode", Value::String("repeat".into()), loc);
    use crate::math::Vec4;
    let flip = Mat4::from_cols(Vec4::X, Vec4::new(0.0, -1.0, 0.0, 0.0), Vec4::Z, Vec4::new(0.0, 1.0, 0.0, 1.0));
    set(&mut t, "to_uv", Value::Transform(Transform::from_matrix(flip).expect("invertible")), loc);
    let mut n = obj("bsdf", "normalmap", loc);
    set(&mut n, "normalmap", Value::Object(Rc::new(t)), loc);
    set(&mut n, "flip_invalid_normals", Value::Bool(false), loc);
    set(&mut n, "use_shadowing_function", Value::Bool(false), loc);
    n.children.push(Rc::new(bsdf));
    n
}

/// The BSDF of `Material` / `MakeNamedMaterial` type `ty` (its normal map aside).
fn material_bsdf(p: &mut Parser, ty: &str, ps: &ParamSet) -> Result<Obj> {
    let l = &ps.loc;
    Ok(match ty {
        "diffuse" => {
            let mut o = obj("bsdf", "diffuse", l);
            let r = texturable(p, ps, "reflectance", false)?.unwrap_or(Value::Float(0.5));
            set(&mut o, "reflectance", r, &ploc(ps, "reflectance"));
            two_sided(o)
        }
        "conductor" => {
            let rough = roughness(p, ps)?;
            let mut o = obj("bsdf", if rough.is_some() { "roughconductor" } else { "conductor" }, l);
            if let Some((u, v)) = rough {
                set(&mut o, "distribution", Value::String("ggx".into()), l);
                set(&mut o, "alpha_u", u, &ploc(ps, "roughness"));
                set(&mut o, "alpha_v", v, &ploc(ps, "roughness"));
            }
            conductor_ior(p, ps, &mut o, "")?;
            two_sided(o)
        }
        "dielectric" | "thindielectric" => {
            let eta = dielectric_eta(ps, "eta")?;
            let rough = if ty == "dielectric" { roughness(p, ps)? } else { None };
            let kind = match (ty, rough.is_some()) {
                ("thindielectric", _) => "thindielectric",
                (_, true) => "roughdielectric",
                _ => "dielectric",
            };
            let mut o = obj("bsdf", kind, l);
            set(&mut o, "int_ior", Value::Float(eta as f64), &ploc(ps, "eta"));
            set(&mut o, "ext_ior", Value::Float(1.0), l);
            if let Some((u, v)) = rough {
                set(&mut o, "distribution", Value::String("ggx".into()), l);
                set(&mut o, "alpha_u", u, &ploc(ps, "roughness"));
                set(&mut o, "alpha_v", v, &ploc(ps, "roughness"));
            }
            o
        }
        "mix" => {
            let names = match ps.params.iter().find(|q| q.name == "materials") {
                Some(q) => {
                    q.used.set(true);
                    q.values
                        .iter()
                        .filter_map(|v| if let super::params::PVal::Str(s) = v { Some(s.clone()) } else { None })
                        .collect::<Vec<_>>()
                }
                None => Vec::new(),
            };
            let [a, b] = &names[..] else {
                return Err(ps.error_at("materials", "a mix needs \"string materials\" with two names"));
            };
            let at = ploc(ps, "materials");
            let mut o = obj("bsdf", "blendbsdf", l);
            let w = texturable(p, ps, "amount", true)?.unwrap_or(Value::Float(0.5));
            set(&mut o, "weight", w, &ploc(ps, "amount"));
            o.children.push(p.named_material(a, &at));
            o.children.push(p.named_material(b, &at));
            o
        }
        // pbrt-v4: no material ("" or "none") is an interface too, a medium boundary only.
        "interface" | "" | "none" => obj("bsdf", "null", l),
        "coateddiffuse" => {
            let mut o = obj("bsdf", "coateddiffuse", l);
            let r = texturable(p, ps, "reflectance", false)?.unwrap_or(Value::Float(0.5));
            set(&mut o, "reflectance", r, &ploc(ps, "reflectance"));
            let (u, v) = roughness_pair(p, ps, "")?;
            set(&mut o, "alpha_u", u, &ploc(ps, "roughness"));
            set(&mut o, "alpha_v", v, &ploc(ps, "roughness"));
            set(&mut o, "eta", Value::Float(dielectric_eta(ps, "eta")? as f64), &ploc(ps, "eta"));
            layer_params(p, ps, &mut o)?;
            o
        }
        "coatedconductor" => {
            let mut o = obj("bsdf", "coatedconductor", l);
            let (u, v) = roughness_pair(p, ps, "interface.")?;
            set(&mut o, "interface_alpha_u", u, &ploc(ps, "interface.roughness"));
            set(&mut o, "interface_alpha_v", v, &ploc(ps, "interface.roughness"));
            let eta = dielectric_eta(ps, "interface.eta")?;
            set(&mut o, "interface_eta", Value::Float(eta as f64), &ploc(ps, "interface.eta"));
            let (u, v) = roughness_pair(p, ps, "conductor.")?;
            set(&mut o, "conductor_alpha_u", u, &ploc(ps, "conductor.roughness"));
            set(&mut o, "conductor_alpha_v", v, &ploc(ps, "conductor.roughness"));
            conductor_ior(p, ps, &mut o, "conductor.")?;
            layer_params(p, ps, &mut o)?;
            o
        }
        "diffusetransmission" => {
            // pbrt-v4: both albedos times `scale`.
            let scale = ps.float("scale", 1.0)?;
            let mut o = obj("bsdf", "diffusetransmission", l);
            for (name, default) in [("reflectance", 0.25), ("transmittance", 0.25)] {
                let v = texturable(p, ps, name, false)?.unwrap_or(Value::Float(default));
                let v = match v {
                    Value::Object(t) if scale != 1.0 => Value::Object(Rc::new(scale_texture(
                        Value::Object(t),
                        scale,
                        &ploc(ps, name),
                        &ploc(ps, "scale"),
                    ))),
                    v => scaled(v, scale),
                };
                set(&mut o, name, v, &ploc(ps, name));
            }
            o
        }
        "hair" => {
            // pbrt-v4's HairMaterial: the first of sigma_a, reflectance, melanin that is given.
            // pbrt reads all four, so none is an unused parameter.
            let mut o = obj("bsdf", "pbrt_hair", l);
            let sigma_a = texturable(p, ps, "sigma_a", false)?;
            let reflectance = texturable(p, ps, "reflectance", false)?;
            let melanin = [texturable(p, ps, "eumelanin", true)?, texturable(p, ps, "pheomelanin", true)?];
            if let Some(v) = sigma_a {
                set(&mut o, "sigma_a", v, &ploc(ps, "sigma_a"));
            } else if let Some(v) = reflectance {
                set(&mut o, "reflectance", v, &ploc(ps, "reflectance"));
            } else {
                for (name, v) in ["eumelanin", "pheomelanin"].into_iter().zip(melanin) {
                    if let Some(v) = v {
                        set(&mut o, name, v, &ploc(ps, name));
                    }
                }
            }
            for (name, default) in [("eta", 1.55), ("beta_m", 0.3), ("beta_n", 0.3), ("alpha", 2.0)] {
                set(&mut o, name, Value::Float(ps.float(name, default)? as f64), &ploc(ps, name));
            }
            o
        }
        "measured" => {
            let file =
                ps.string("filename")?.ok_or_else(|| ps.error("a measured material needs its \"string filename\""))?;
            let mut o = obj("bsdf", "measured", l);
            set(&mut o, "filename", Value::String(file), &ploc(ps, "filename"));
            two_sided(o)
        }
        "subsurface" => subsurface(p, ps, l)?,
        other => {
            return Err(ps.unknown(
                "material",
                other,
                &[
                    "coatedconductor",
                    "coateddiffuse",
                    "conductor",
                    "dielectric",
                    "diffuse",
                    "diffusetransmission",
                    "hair",
                    "interface",
                    "measured",
                    "mix",
                    "subsurface",
                    "thindielectric",
                ],
            ))
        }
    })
}

/// pbrt-v4's `subsurface` material → neumann's `pbrt_subsurface`: the coefficients by `name`
/// (a measured medium, `crate::medium::presets`, with `g` = 0 as pbrt enforces), or `sigma_a`
/// and `sigma_s` (both, texturable), or `reflectance` (texturable) with `mfp` (1), or pbrt's
/// default skin-like coefficients; `scale` (1), `eta` (1.33), `g` (0), the roughness of its
/// dielectric boundary (`roughness`, `uroughness`, `vroughness`, 0; `remaproughness`).
fn subsurface(p: &mut Parser, ps: &ParamSet, l: &Loc) -> Result<Obj> {
    p.subsurface = true;
    let mut o = obj("bsdf", "pbrt_subsurface", l);
    let mut g = ps.float("g", 0.0)?;
    if let Some(name) = ps.string("name")? {
        let Some((sigma_s, sigma_a)) = crate::medium::presets::preset(&name) else {
            let hint = crate::choice::nearest(&name, crate::medium::presets::preset_names())
                .map(|n| format!("; the nearest is '{n}'"))
                .unwrap_or_default();
            return Err(ps.error_at("name", format!("named medium \"{name}\" not found{hint}")));
        };
        if g != 0.0 {
            p.warnings.push(format!(
                "warning: {}: a non-zero \"g\" is ignored with named scattering coefficients (as pbrt does)",
                ploc(ps, "g").position()
            ));
            g = 0.0;
        }
        set(&mut o, "sigma_a", Value::Rgb(sigma_a), &ploc(ps, "name"));
        set(&mut o, "sigma_s", Value::Rgb(sigma_s), &ploc(ps, "name"));
    } else {
        let sigma_a = texturable(p, ps, "sigma_a", false)?;
        let sigma_s = texturable(p, ps, "sigma_s", false)?;
        match (sigma_a, sigma_s) {
            (Some(a), Some(s)) => {
                set(&mut o, "sigma_a", a, &ploc(ps, "sigma_a"));
                set(&mut o, "sigma_s", s, &ploc(ps, "sigma_s"));
            }
            (Some(_), None) => return Err(ps.error_at("sigma_a", "\"sigma_a\" without \"sigma_s\"")),
            (None, Some(_)) => return Err(ps.error_at("sigma_s", "\"sigma_s\" without \"sigma_a\"")),
            (None, None) => {
                if let Some(r) = texturable(p, ps, "reflectance", false)? {
                    set(&mut o, "reflectance", r, &ploc(ps, "reflectance"));
                    if let Some(m) = texturable(p, ps, "mfp", false)? {
                        set(&mut o, "mfp", m, &ploc(ps, "mfp"));
                    }
                }
            }
        }
    }
    set(&mut o, "g", Value::Float(g as f64), &ploc(ps, "g"));
    set(&mut o, "scale", Value::Float(ps.float("scale", 1.0)? as f64), &ploc(ps, "scale"));
    set(&mut o, "int_ior", Value::Float(ps.float("eta", 1.33)? as f64), &ploc(ps, "eta"));
    set(&mut o, "ext_ior", Value::Float(1.0), l);
    if let Some((u, v)) = roughness(p, ps)? {
        set(&mut o, "distribution", Value::String("ggx".into()), l);
        set(&mut o, "alpha_u", u, &ploc(ps, "roughness"));
        set(&mut o, "alpha_v", v, &ploc(ps, "roughness"));
    }
    Ok(o)
}

/// A light's `scale` times the film's imaging ratio.
fn light_scale(p: &Parser, ps: &ParamSet) -> Result<f32> {
    let s = ps.float("scale", 1.0)?;
    if s.is_nan() || s < 0.0 {
        return Err(ps.error_at("scale", "must be ≥ 0"));
    }
    Ok(s * imaging_ratio(p, ps)?)
}

/// pbrt-v4's imaging ratio, `exposure time × ISO / 100` (the exposure time being the camera's
/// `shutterclose − shutteropen`), times an earlier pbrt-v4's film `scale`: its sensor scales the
/// image by it. Light transport is linear in the emission, so neumann scales every light
/// instead (1 by default).
fn imaging_ratio(p: &Parser, light: &ParamSet) -> Result<f32> {
    let iso = match &p.film {
        Some(f) => f.float("iso", 100.0)?,
        None => 100.0,
    };
    let exposure = match &p.camera {
        Some((c, _)) => c.float("shutterclose", 1.0)? - c.float("shutteropen", 0.0)?,
        None => 1.0,
    };
    // Earlier pbrt-v4's film `scale` (pbrt-v4-scenes' zero-day and sportscar-sky): the image
    // times it, as the imaging ratio is.
    let film_scale = match &p.film {
        Some(f) => f.float("scale", 1.0)?,
        None => 1.0,
    };
    let ratio = exposure * iso / 100.0 * film_scale;
    if !(ratio.is_finite() && ratio > 0.0) {
        let at = p.film.as_ref().filter(|f| f.has("iso")).or(p.camera.as_ref().map(|c| &c.0)).unwrap_or(light);
        return Err(at.error(format!(
            "the imaging ratio (shutterclose − shutteropen) × iso / 100 (× the film's scale) must be positive, got {ratio}"
        )));
    }
    Ok(ratio)
}

/// A `scale` texture: `tex` (written at `at`) times `scale` (written at `scale_at`).
fn scale_texture(tex: Value, scale: f32, at: &Loc, scale_at: &Loc) -> Obj {
    let mut s = obj("texture", "scale", at);
    set(&mut s, "tex", tex, at);
    set(&mut s, "scale", Value::Float(scale as f64), scale_at);
    s
}

/// A colour value (RGB, a number or a spectrum) times `s`; other values (textures, which the
/// callers wrap in a `scale` texture) unchanged.
fn scaled(v: Value, s: f32) -> Value {
    match v {
        Value::Rgb(c) => Value::Rgb(c * s),
        Value::Float(f) => Value::Float(f * s as f64),
        Value::Spectrum(SpectrumValue::Samples(v)) => {
            Value::Spectrum(SpectrumValue::Samples(v.into_iter().map(|(l, x)| (l, x * s)).collect()))
        }
        Value::Spectrum(SpectrumValue::Constant(c)) => Value::Spectrum(SpectrumValue::Constant(c * s)),
        other => other,
    }
}

/// `LightSource`.
pub fn light(p: &mut Parser, ty: &str, ps: &ParamSet) -> Result<Obj> {
    let ctm = p.gs.ctm;
    if p.gs.moving() {
        p.warnings.push(format!(
            "warning: {}: the light's transform moves (ActiveTransform): lights stay at their start transform, as in pbrt-v4",
            ps.loc.position()
        ));
    }
    let l = &ps.loc;
    let spectrum = |name: &str| -> Result<Value> {
        match ps.spectrum(name)? {
            Some(s) => spectrum_value(ps, name, s, true),
            None => Ok(Value::Float(1.0)),
        }
    };
    Ok(match ty {
        "point" => {
            let from = ps.point("from", Vec3::ZERO)?;
            let mut s = light_scale(p, ps)?;
            // pbrt-v4 applies a power only where it is positive.
            let power = ps.float("power", -1.0)?;
            if power > 0.0 {
                s *= power / (4.0 * std::f32::consts::PI);
            }
            let mut o = obj("emitter", "point", l);
            set(&mut o, "position", Value::Point(ctm.transform_point3(from)), l);
            set(&mut o, "intensity", scaled(spectrum("I")?, s), &ploc(ps, "I"));
            o
        }
        "spot" => {
            let from = ps.point("from", Vec3::ZERO)?;
            let to = ps.point("to", Vec3::Z)?;
            let cone = ps.float("coneangle", 30.0)?;
            let delta = ps.float("conedeltaangle", 5.0)?;
            if !(cone > 0.0 && cone <= 180.0 && delta.is_finite()) {
                return Err(ps.error_at(
                    "coneangle",
                    format!("need 0 < coneangle ≤ 180 and a finite conedeltaangle, got {cone} and {delta}"),
                ));
            }
            let beam = (cone - delta).clamp(0.0, cone);
            let mut s = light_scale(p, ps)?;
            let power = ps.float("power", -1.0)?;
            if power > 0.0 {
                // pbrt-v4: the power of the smoothstep cone, 2π((1 − cos β) + (cos β − cos γ)/2).
                let (end, start) = (cone.to_radians().cos(), beam.to_radians().cos());
                s *= power / (2.0 * std::f32::consts::PI * ((1.0 - start) + 0.5 * (start - end)));
            }
            let (wf, wt) = (ctm.transform_point3(from), ctm.transform_point3(to));
            let d = (wt - wf).normalize_or_zero();
            let up = if d.y.abs() > 0.9 { Vec3::X } else { Vec3::Y };
            let t = Transform::look_at(wf, wt, up).ok_or_else(|| ps.error_at("to", "from and to coincide"))?;
            let mut o = obj("emitter", "spot", l);
            set(&mut o, "to_world", Value::Transform(t), l);
            set(&mut o, "intensity", scaled(spectrum("I")?, s), &ploc(ps, "I"));
            set(&mut o, "cutoff_angle", Value::Float(cone as f64), &ploc(ps, "coneangle"));
            set(&mut o, "beam_width", Value::Float(beam as f64), &ploc(ps, "conedeltaangle"));
            set(&mut o, "falloff", Value::String("smoothstep".into()), l);
            o
        }
        "distant" => {
            let from = ps.point("from", Vec3::ZERO)?;
            let to = ps.point("to", Vec3::Z)?;
            let mut s = light_scale(p, ps)?;
            // pbrt-v4: the irradiance of a luminance-1 spectrum times the illuminance (RGB
            // values are taken as given, so their luminance multiplies it).
            let e = ps.float("illuminance", -1.0)?;
            if e > 0.0 {
                s *= e;
            }
            let d = ctm.transform_vector3(to - from).normalize_or_zero();
            if d == Vec3::ZERO {
                return Err(ps.error_at("to", "from and to coincide"));
            }
            let mut o = obj("emitter", "directional", l);
            set(&mut o, "direction", Value::Vector(d), l);
            set(&mut o, "irradiance", scaled(spectrum("L")?, s), &ploc(ps, "L"));
            o
        }
        "infinite" => {
            let mut s = light_scale(p, ps)?;
            // pbrt-v4's portal: four corners in world space.
            let portal = match ps.floats("portal", &["point3", "point"])? {
                None => None,
                Some(v) if v.len() == 12 => Some(std::array::from_fn::<Vec3, 4, _>(|i| {
                    Vec3::new(v[3 * i] as f32, v[3 * i + 1] as f32, v[3 * i + 2] as f32)
                })),
                Some(v) => {
                    return Err(
                        ps.error_at("portal", format!("a portal is 4 points (12 numbers), got {} numbers", v.len()))
                    )
                }
            };
            let e = ps.float("illuminance", -1.0)?;
            // pbrt-v4: "L" with a portal is a one-texel image of L's colour (its XYZ in sRGB,
            // not normalised to luminance 1 as a uniform "L" is) behind the portal.
            let portal_l = match (portal.is_some(), ps.has("filename"), ps.spectrum("L")?) {
                (true, false, Some(l)) => {
                    let c = absolute_rgb(ps, "L", l)?;
                    let name = format!("pbrt-portal-L-{}", p.mesh_count);
                    p.mesh_count += 1;
                    let image = crate::load::memory::EncodedImage {
                        width: 1,
                        height: 1,
                        rgba: vec![[c.x, c.y, c.z, 1.0]],
                        linear: true,
                    };
                    p.memory.images.insert(name.clone(), image);
                    Some(name)
                }
                (true, false, None) => {
                    return Err(ps.error_at("portal", "a portal needs an \"L\" or a \"filename\" (as in pbrt-v4)"))
                }
                _ => None,
            };
            if let Some(file) = portal_l.or(ps.string("filename")?) {
                if ps.has("L") && ps.has("filename") {
                    return Err(ps.error_at("L", "give either \"L\" or \"filename\" (as pbrt-v4 requires)"));
                }
                // pbrt-v4's equal-area octahedral square around the light's +z (or, for an image
                // that is not square, pbrt-v3's latitude-longitude layout about +z).
                let mut o = obj("emitter", "envmap", l);
                set(&mut o, "filename", Value::String(file), &ploc(ps, "filename"));
                set(&mut o, "mapping", Value::String("pbrt".into()), l);
                set(&mut o, "scale", Value::Float(s as f64), &ploc(ps, "scale"));
                if e > 0.0 {
                    set(&mut o, "illuminance", Value::Float(e as f64), &ploc(ps, "illuminance"));
                }
                for (k, corner) in portal.into_iter().flatten().enumerate() {
                    set(&mut o, &format!("portal_p{k}"), Value::Point(corner), &ploc(ps, "portal"));
                }
                set(&mut o, "to_world", Value::Transform(transform(ctm, ps)?), l);
                return Ok(o);
            }
            if e > 0.0 {
                // pbrt-v4: a uniform sky of luminance 1 gives an illuminance of π.
                s *= e / std::f32::consts::PI;
            }
            let mut o = obj("emitter", "constant", l);
            set(&mut o, "radiance", scaled(spectrum("L")?, s), &ploc(ps, "L"));
            o
        }
        "goniometric" => {
            // pbrt-v4: the diagram in the light's frame with y and z swapped (neumann's
            // goniometric has the same layout), `power` over 4π × the diagram's mean.
            let s = light_scale(p, ps)?;
            let file =
                ps.string("filename")?.ok_or_else(|| ps.error("a goniometric light needs its \"string filename\""))?;
            let mut o = obj("emitter", "goniometric", l);
            set(&mut o, "filename", Value::String(file), &ploc(ps, "filename"));
            set(&mut o, "intensity", spectrum("I")?, &ploc(ps, "I"));
            set(&mut o, "scale", Value::Float(s as f64), &ploc(ps, "scale"));
            let power = ps.float("power", -1.0)?;
            if power > 0.0 {
                set(&mut o, "power", Value::Float(power as f64), &ploc(ps, "power"));
            }
            set(&mut o, "to_world", Value::Transform(transform(ctm, ps)?), l);
            o
        }
        "projection" => {
            // pbrt-v4: a pinhole projecting the image as intensity (scale · texel, W sr⁻¹) along
            // the light's +z, `fov` (90°) across the image's shorter side, the nearest texel, the
            // image's s axis along the light's +x and t down its +y → neumann's projector with
            // `emission` `intensity` (whose u runs along −x: mirrored).
            let s = light_scale(p, ps)?;
            let file =
                ps.string("filename")?.ok_or_else(|| ps.error("a projection light needs its \"string filename\""))?;
            let at = ploc(ps, "filename");
            let mut b = obj("texture", "bitmap", &at);
            set(&mut b, "filename", Value::String(file), &at);
            set(&mut b, "filter_type", Value::String("nearest".into()), &at);
            let mirror = Mat4::from_cols_array(&[
                -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0,
            ]);
            set(&mut b, "to_uv", Value::Transform(transform(mirror, ps)?), &at);
            let mut o = obj("emitter", "projector", l);
            set(&mut o, "irradiance", Value::Object(Rc::new(b)), &at);
            set(&mut o, "emission", Value::String("intensity".into()), l);
            set(&mut o, "scale", Value::Float(s as f64), &ploc(ps, "scale"));
            set(&mut o, "fov", Value::Float(ps.float("fov", 90.0)? as f64), &ploc(ps, "fov"));
            set(&mut o, "fov_axis", Value::String("smaller".into()), l);
            let power = ps.float("power", -1.0)?;
            if power > 0.0 {
                set(&mut o, "power", Value::Float(power as f64), &ploc(ps, "power"));
            }
            set(&mut o, "to_world", Value::Transform(transform(ctm, ps)?), l);
            o
        }
        other => {
            return Err(ps.unknown(
                "light",
                other,
                &["distant", "goniometric", "infinite", "point", "projection", "spot"],
            ))
        }
    })
}

/// `MakeNamedMedium`: `homogeneous` (`sigma_a`, `sigma_s` in mm⁻¹… per scene unit, pbrt's
/// defaults, `scale`, `g` → Henyey–Greenstein) as Mitsuba's `homogeneous` (σₜ = σₐ + σₛ, albedo
/// σₛ/σₜ).
pub fn medium(p: &mut Parser, ps: &ParamSet) -> Result<Obj> {
    if p.gs.moving() {
        p.warnings.push(format!(
            "warning: {}: the medium's transform moves (ActiveTransform): media stay at their start transform, as in pbrt-v4",
            ps.loc.position()
        ));
    }
    let ty = ps.string("type")?.ok_or_else(|| ps.error("needs its \"string type\""))?;
    match ty.as_str() {
        "homogeneous" => homogeneous_medium(p, ps),
        "uniformgrid" | "rgbgrid" => grid_medium(p, ps, ty == "rgbgrid"),
        "cloud" => cloud_medium(p, ps),
        "nanovdb" => nanovdb_medium(p, ps),
        other => Err(ps.error_at(
            "type",
            format!("unknown medium \"{other}\" (homogeneous, uniformgrid, rgbgrid, nanovdb, cloud)"),
        )),
    }
}

/// A medium's coefficient `name` (`sigma_a`, `sigma_s`), `default` where absent: an rgb, a
/// constant, or a sampled spectrum (pairs or a file) reduced to RGB as an unbounded quantity
/// (pbrt-v4 reads them as `SpectrumType::Unbounded`); negative values are an error.
fn medium_coefficient(ps: &ParamSet, name: &str, default: Rgb) -> Result<Rgb> {
    let c = match ps.spectrum(name)? {
        None => default,
        Some(SpectrumParam::Rgb(c)) => c,
        Some(SpectrumParam::Constant(v)) => Rgb::splat(v),
        Some(SpectrumParam::Samples(v)) => {
            crate::math::spectrum::spectrum_to_rgb(&v, crate::math::spectrum::SpectrumKind::Unbounded)
        }
        Some(SpectrumParam::Named(n)) => {
            return Err(ps.error_at(name, format!("the named spectrum \"{n}\" is no medium coefficient")))
        }
        Some(SpectrumParam::Blackbody(_)) => {
            return Err(ps.error_at(name, "a blackbody spectrum is for emitted light only"))
        }
    };
    if !(c.is_finite() && c.min_element() >= 0.0) {
        return Err(ps.error_at(name, format!("\"{name}\" must be finite and ≥ 0, got {c}")));
    }
    Ok(c)
}

/// pbrt-v4's `cloud` medium: its procedural density ([`crate::texture::cloud`]: `density` (1),
/// `wispiness` (1), `frequency` (5)) times `sigma_a` and `sigma_s` (1 each) over the box
/// `p0`–`p1` ((0,0,0)–(1,1,1)) of the medium's space (the current transform), `g` →
/// Mitsuba's `heterogeneous` whose σₜ is neumann's `pbrt_cloud` volume (the density times
/// σₐ + σₛ, its peak as `scale`) and whose albedo is σₛ / σₜ.
fn cloud_medium(p: &mut Parser, ps: &ParamSet) -> Result<Obj> {
    let (sa, ss) = (medium_coefficient(ps, "sigma_a", Rgb::ONE)?, medium_coefficient(ps, "sigma_s", Rgb::ONE)?);
    let st = sa + ss;
    let peak = st.max_element();
    let (p0, p1) = (ps.point("p0", Vec3::ZERO)?, ps.point("p1", Vec3::ONE)?);
    if !(p1.cmpgt(p0).all() && (p1 - p0).is_finite()) {
        return Err(ps.error_at("p1", format!("the cloud's box p0 {p0} – p1 {p1} is empty")));
    }
    let mut v = obj("volume", "pbrt_cloud", &ps.loc);
    for name in ["density", "wispiness", "frequency"] {
        if ps.has(name) {
            let x = ps.float(name, 0.0)?;
            if !x.is_finite() {
                return Err(ps.error_at(name, format!("\"{name}\" must be finite")));
            }
            set(&mut v, name, Value::Float(x as f64), &ploc(ps, name));
        }
    }
    set(&mut v, "p0", Value::Point(p0), &ploc(ps, "p0"));
    set(&mut v, "p1", Value::Point(p1), &ploc(ps, "p1"));
    let unit = if peak > 0.0 { st / peak } else { Rgb::ZERO };
    set(&mut v, "value", Value::Rgb(unit), &ploc(ps, "sigma_a"));
    set(&mut v, "to_world", Value::Transform(transform(p.gs.ctm, ps)?), &ps.loc);
    let mut o = obj("medium", "heterogeneous", &ps.loc);
    set(&mut o, "sigma_t", Value::Object(Rc::new(v)), &ps.loc);
    set(&mut o, "scale", Value::Float(peak as f64), &ploc(ps, "sigma_a"));
    let albedo = Rgb::from_array(std::array::from_fn(|c| if st[c] > 0.0 { ss[c] / st[c] } else { 0.0 }));
    set(&mut o, "albedo", Value::Rgb(albedo), &ploc(ps, "sigma_s"));
    phase_g(ps, &mut o)?;
    Ok(o)
}

/// pbrt-v4's `nanovdb` medium: the float grid `gridname` ("density") of the NanoVDB file
/// `filename` (required), read trilinearly at the point's medium-space coordinates through the
/// grid's own map, times `sigma_a` and `sigma_s` (1 each) and `scale` (1), `g`; where the file
/// also has the grid `temperaturename` ("temperature") and `Lescale` (1; earlier pbrt-v4's
/// `LeScale` is read too) is positive, it emits
/// `σₐ` times black-body radiance at `(T − temperatureoffset) · temperaturescale` K (the offset
/// also spelt `temperaturecutoff`; none at or below 100 K) times `Lescale` → Mitsuba's
/// `heterogeneous` whose σₜ is neumann's `nanovdb` volume and whose `radiance` is a
/// `blackbody` volume over another (`required` false: pbrt's temperature grid is optional).
fn nanovdb_medium(p: &mut Parser, ps: &ParamSet) -> Result<Obj> {
    let file = ps
        .string("filename")?
        .ok_or_else(|| ps.error("a nanovdb medium needs its \"string filename\" (as pbrt-v4 requires)"))?;
    let grid = ps.string("gridname")?.unwrap_or_else(|| "density".into());
    let (sa, ss) = (medium_coefficient(ps, "sigma_a", Rgb::ONE)?, medium_coefficient(ps, "sigma_s", Rgb::ONE)?);
    let scale = ps.float("scale", 1.0)?;
    if !(scale >= 0.0 && scale.is_finite()) {
        return Err(ps.error_at("scale", format!("scale must be finite and ≥ 0, got {scale}")));
    }
    let st = sa + ss;
    let peak = st.max_element();
    let to_world = Value::Transform(transform(p.gs.ctm, ps)?);
    let at = ploc(ps, "filename");
    let mut v = obj("volume", "nanovdb", &ps.loc);
    set(&mut v, "filename", Value::String(file.clone()), &at);
    set(&mut v, "grid", Value::String(grid), &ploc(ps, "gridname"));
    set(&mut v, "value", Value::Rgb(if peak > 0.0 { st / peak } else { Rgb::ZERO }), &ploc(ps, "sigma_a"));
    set(&mut v, "to_world", to_world.clone(), &ps.loc);
    let mut o = obj("medium", "heterogeneous", &ps.loc);
    set(&mut o, "sigma_t", Value::Object(Rc::new(v)), &ps.loc);
    set(&mut o, "scale", Value::Float((peak * scale) as f64), &ploc(ps, "scale"));
    let albedo = Rgb::from_array(std::array::from_fn(|c| if st[c] > 0.0 { ss[c] / st[c] } else { 0.0 }));
    set(&mut o, "albedo", Value::Rgb(albedo), &ploc(ps, "sigma_s"));
    phase_g(ps, &mut o)?;
    // Earlier pbrt-v4 spelt it `LeScale` for this medium (pbrt-v4-scenes' explosion.pbrt does).
    let le_name = if ps.has("LeScale") { "LeScale" } else { "Lescale" };
    if ps.has("LeScale") && ps.has("Lescale") {
        return Err(ps.error_at("LeScale", "both \"LeScale\" and \"Lescale\" given: they name one parameter"));
    }
    let le_scale = le_scale_named(ps, le_name)?;
    let temperature = ps.string("temperaturename")?.unwrap_or_else(|| "temperature".into());
    let (offset, t_scale) = temperature_params(ps)?;
    if le_scale > 0.0 && sa.max_element() > 0.0 {
        let mut t = obj("volume", "nanovdb", &ps.loc);
        set(&mut t, "filename", Value::String(file), &at);
        set(&mut t, "grid", Value::String(temperature), &ploc(ps, "temperaturename"));
        set(&mut t, "required", Value::Bool(false), &ps.loc);
        set(&mut t, "to_world", to_world, &ps.loc);
        let b = blackbody_volume(ps, t, None, offset, t_scale, le_scale);
        set(&mut o, "radiance", Value::Object(Rc::new(b)), &ploc(ps, le_name));
    }
    Ok(o)
}

/// pbrt-v4's `temperatureoffset` (or, where absent, `temperaturecutoff`; 0) and
/// `temperaturescale` (1) of its `nanovdb` and `uniformgrid` media, finite.
fn temperature_params(ps: &ParamSet) -> Result<(f32, f32)> {
    let cutoff = ps.float("temperaturecutoff", 0.0)?;
    let offset = ps.float("temperatureoffset", cutoff)?;
    let t_scale = ps.float("temperaturescale", 1.0)?;
    for (name, x) in [("temperatureoffset", offset), ("temperaturescale", t_scale)] {
        if !x.is_finite() {
            return Err(ps.error_at(name, format!("\"{name}\" must be finite, got {x}")));
        }
    }
    Ok((offset, t_scale))
}

/// neumann's `blackbody` volume over the temperature volume `temperature` (and the `weight`
/// volume): pbrt-v4's emission by temperature, `scale · weight · B̂((T − offset) · t_scale)`.
fn blackbody_volume(
    ps: &ParamSet,
    temperature: Obj,
    weight: Option<Obj>,
    offset: f32,
    t_scale: f32,
    scale: f32,
) -> Obj {
    let mut b = obj("volume", "blackbody", &ps.loc);
    set(&mut b, "temperature", Value::Object(Rc::new(temperature)), &ploc(ps, "temperature"));
    if let Some(w) = weight {
        set(&mut b, "weight", Value::Object(Rc::new(w)), &ploc(ps, "Lescale"));
    }
    set(&mut b, "temperature_offset", Value::Float(offset as f64), &ploc(ps, "temperatureoffset"));
    set(&mut b, "temperature_scale", Value::Float(t_scale as f64), &ploc(ps, "temperaturescale"));
    set(&mut b, "scale", Value::Float(scale as f64), &ploc(ps, "Lescale"));
    b
}

/// pbrt-v4's phase function parameter `g` on the medium `o` (Henyey–Greenstein; none at 0).
fn phase_g(ps: &ParamSet, o: &mut Obj) -> Result<()> {
    let g = ps.float("g", 0.0)?;
    if !(g > -1.0 && g < 1.0) {
        return Err(ps.error_at("g", format!("g must lie in (-1, 1), got {g}")));
    }
    if g != 0.0 {
        let mut phase = obj("phase", "hg", &ploc(ps, "g"));
        set(&mut phase, "g", Value::Float(g as f64), &ploc(ps, "g"));
        o.children.push(Rc::new(phase));
    }
    Ok(())
}

/// pbrt-v4's `uniformgrid` (a `density` grid times `sigma_a`, `sigma_s` (1 each) and `scale`)
/// and `rgbgrid` (`sigma_a` and `sigma_s` grids of RGB values, 1 where absent, times `scale`)
/// over the box `p0`–`p1` of the medium's space (the current transform), `nx` × `ny` × `nz`
/// values (x fastest) read trilinearly at texel centres and zero beyond them, as pbrt's
/// `SampledGrid` does → Mitsuba's `heterogeneous` with a σₜ grid and a constant or gridded
/// albedo (neumann's grid `wrap_mode` `zero`).
fn grid_medium(p: &mut Parser, ps: &ParamSet, rgb_grid: bool) -> Result<Obj> {
    let dim = |name: &str| -> Result<usize> {
        let v = ps.int(name, 1)?;
        if !(1..=1 << 14).contains(&v) {
            return Err(ps.error_at(name, format!("\"{name}\" must be 1–16384, got {v}")));
        }
        Ok(v as usize)
    };
    let res = [dim("nx")?, dim("ny")?, dim("nz")?];
    let n = res[0] * res[1] * res[2];
    if n > 1 << 27 {
        return Err(ps.error(format!("a grid of {}×{}×{} values is too large", res[0], res[1], res[2])));
    }
    // pbrt-v4's `uniformgrid` reads the temperature parameters whether or not it has a
    // `temperature` grid (`rgbgrid` does not: they are unused there).
    let (offset, t_scale) = if rgb_grid { (0.0, 1.0) } else { temperature_params(ps)? };
    let (p0, p1) = (ps.point("p0", Vec3::ZERO)?, ps.point("p1", Vec3::ONE)?);
    if !(p1.cmpgt(p0).all() && (p1 - p0).is_finite()) {
        return Err(ps.error_at("p1", format!("the grid's box p0 {p0} – p1 {p1} is empty")));
    }
    let scale = ps.float("scale", 1.0)?;
    if scale < 0.0 {
        return Err(ps.error_at("scale", "scale must be ≥ 0"));
    }
    let values = |name: &str, per: usize, ty: &[&str]| -> Result<Option<Vec<f32>>> {
        match ps.floats(name, ty)? {
            None => Ok(None),
            Some(v) if v.len() == n * per => {
                if v.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                    return Err(ps.error_at(name, format!("\"{name}\" values must be finite and ≥ 0")));
                }
                Ok(Some(v.into_iter().map(|x| x as f32).collect()))
            }
            Some(v) => Err(ps.error_at(
                name,
                format!(
                    "\"{name}\" has {} values for a {}×{}×{} grid ({} expected)",
                    v.len(),
                    res[0],
                    res[1],
                    res[2],
                    n * per
                ),
            )),
        }
    };
    // Emission (pbrt-v4's `Le`): `uniformgrid`, a spectrum normalised to luminance 1 as lights'
    // are, times the `Lescale` grid (without one, a 1 × 1 × 1 grid of 1, which pbrt's lookup
    // reads as a tent: 1 at the box's centre, 1/8 at its corners); `rgbgrid`, a grid of RGB
    // illuminants times the float `Lescale`. pbrt-v4 does not normalise the latter, whose RGB
    // illuminant spectra (the colour times the colour space's D65, scaled to luminance
    // `CIE_Y_integral`) thus render 106.856895 × brighter than the same RGB on a light.
    // With a `temperature` grid (`uniformgrid`, no `Le`: pbrt-v4 refuses both), black bodies
    // at `(T − temperatureoffset) · temperaturescale` K times the `Lescale` grid (the same
    // default tent).
    let temperature = if rgb_grid { None } else { values("temperature", 1, &["float"])? };
    if temperature.is_some() && ps.has("Le") {
        return Err(ps.error_at("Le", "give either \"Le\" or \"temperature\" (pbrt-v4 refuses both)"));
    }
    let temperature_weight = match &temperature {
        None => None,
        Some(_) => Some(match values("Lescale", 1, &["float"])? {
            Some(grid) => grid.iter().flat_map(|s| [*s; 3]).collect::<Vec<f32>>(),
            None => vec![1.0; 3],
        }),
    };
    let radiance: Option<Vec<f32>> = if temperature.is_some() {
        None
    } else if rgb_grid {
        let scale = le_scale(ps)?;
        match values("Le", 3, &["rgb"])? {
            Some(_) if !ps.has("sigma_a") => {
                return Err(ps.error_at("Le", "an rgbgrid with \"Le\" needs \"sigma_a\" values (as pbrt-v4 requires)"))
            }
            Some(le) => Some(le.into_iter().map(|v| v * scale * CIE_Y_INTEGRAL).collect()),
            None => None,
        }
    } else {
        match medium_le(ps)? {
            None => {
                ps.floats("Lescale", &["float"])?;
                None
            }
            Some(le) => Some(match values("Lescale", 1, &["float"])? {
                Some(grid) => grid.iter().flat_map(|s| (le * *s).to_array()).collect(),
                None => le.to_array().to_vec(),
            }),
        }
    }
    .filter(|v| v.iter().any(|x| *x > 0.0));
    let (sigma_t, albedo): (Vec<f32>, std::result::Result<Rgb, Vec<f32>>) = if rgb_grid {
        let sa = values("sigma_a", 3, &["rgb"])?.unwrap_or_else(|| vec![1.0; 3 * n]);
        let ss = values("sigma_s", 3, &["rgb"])?.unwrap_or_else(|| vec![1.0; 3 * n]);
        let st: Vec<f32> = sa.iter().zip(&ss).map(|(a, s)| a + s).collect();
        let al: Vec<f32> = st.iter().zip(&ss).map(|(t, s)| if *t > 0.0 { s / t } else { 0.0 }).collect();
        (st, Err(al))
    } else {
        let density =
            values("density", 1, &["float"])?.ok_or_else(|| ps.error("a uniformgrid needs its \"float density\""))?;
        let (sa, ss) = (medium_coefficient(ps, "sigma_a", Rgb::ONE)?, medium_coefficient(ps, "sigma_s", Rgb::ONE)?);
        let st = sa + ss;
        let st_grid = density.iter().flat_map(|d| (st * *d).to_array()).collect();
        let albedo = Rgb::from_array(std::array::from_fn(|c| if st[c] > 0.0 { ss[c] / st[c] } else { 0.0 }));
        (st_grid, Ok(albedo))
    };
    let box_to_medium = Mat4::from_translation(p0) * Mat4::from_scale(p1 - p0);
    let to_world = transform(p.gs.ctm * box_to_medium, ps)?;
    let volume = |data: Vec<f32>, p: &mut Parser| -> Obj {
        let name = format!("#pbrt-grid-{}", p.mesh_count);
        p.mesh_count += 1;
        // A grid of one value per channel is `uniformgrid`'s default `Lescale` (pbrt's 1 × 1 × 1).
        let res = if data.len() == 3 { [1; 3] } else { res };
        let grid = crate::image::GridVolume { res, channels: 3, bbox: [[0.0; 3], [1.0; 3]], data };
        p.memory.volumes.insert(name.clone(), std::sync::Arc::new(grid));
        let mut v = obj("volume", "gridvolume", &ps.loc);
        set(&mut v, "filename", Value::String(name), &ps.loc);
        set(&mut v, "wrap_mode", Value::String("zero".into()), &ps.loc);
        set(&mut v, "to_world", Value::Transform(to_world), &ps.loc);
        v
    };
    let mut o = obj("medium", "heterogeneous", &ps.loc);
    let st = volume(sigma_t, p);
    set(&mut o, "sigma_t", Value::Object(Rc::new(st)), &ps.loc);
    match albedo {
        Ok(c) => set(&mut o, "albedo", Value::Rgb(c), &ploc(ps, "sigma_s")),
        Err(grid) => {
            let a = volume(grid, p);
            set(&mut o, "albedo", Value::Object(Rc::new(a)), &ploc(ps, "sigma_s"));
        }
    }
    set(&mut o, "scale", Value::Float(scale as f64), &ploc(ps, "scale"));
    if let Some(le) = radiance {
        let v = volume(le, p);
        set(&mut o, "radiance", Value::Object(Rc::new(v)), &ploc(ps, "Le"));
    }
    if let (Some(t), Some(w)) = (temperature, temperature_weight) {
        let t = volume(t.iter().flat_map(|x| [*x; 3]).collect(), p);
        let w = volume(w, p);
        let b = blackbody_volume(ps, t, Some(w), offset, t_scale, 1.0);
        set(&mut o, "radiance", Value::Object(Rc::new(b)), &ploc(ps, "temperature"));
    }
    phase_g(ps, &mut o)?;
    Ok(o)
}

/// `CIE_Y_integral` of pbrt-v4 (∫ ȳ(λ) dλ over its 1 nm tables): the luminance to which it
/// scales its named illuminants, the D65 of RGB illuminant spectra among them.
const CIE_Y_INTEGRAL: f32 = 106.856_895;

/// The float `Lescale` (1) of a `homogeneous` or `rgbgrid` medium, finite and ≥ 0.
fn le_scale(ps: &ParamSet) -> Result<f32> {
    le_scale_named(ps, "Lescale")
}

/// [`le_scale`] under the parameter name `name`.
fn le_scale_named(ps: &ParamSet, name: &str) -> Result<f32> {
    let scale = ps.float(name, 1.0)?;
    if !(scale >= 0.0 && scale.is_finite()) {
        return Err(ps.error_at(name, format!("{name} must be finite and ≥ 0")));
    }
    Ok(scale)
}

/// pbrt-v4's `Le` of a `homogeneous` or `uniformgrid` medium as linear sRGB: an illuminant
/// spectrum normalised to luminance 1, as lights' are (an RGB as given); `None` where absent
/// or zero.
fn medium_le(ps: &ParamSet) -> Result<Option<Rgb>> {
    let Some(s) = ps.spectrum("Le")? else { return Ok(None) };
    let le = match spectrum_value(ps, "Le", s, true)? {
        Value::Rgb(c) => c,
        Value::Float(v) => Rgb::splat(v as f32),
        _ => return Err(ps.error_at("Le", "this spectrum cannot be a medium's emission")),
    };
    if !(0..3).all(|c| le[c] >= 0.0 && le[c].is_finite()) {
        return Err(ps.error_at("Le", format!("Le must be finite and ≥ 0, got {le}")));
    }
    Ok((le.max_element() > 0.0).then_some(le))
}

/// pbrt-v4's `homogeneous` medium: `preset` (a measured medium by name, σₛ and σₐ in mm⁻¹,
/// `crate::medium::presets`; an unknown name is a warning and the parameters count, as in pbrt),
/// else `sigma_a`, `sigma_s` (1 each); `scale`, `g`.
fn homogeneous_medium(p: &mut Parser, ps: &ParamSet) -> Result<Obj> {
    let preset = match ps.string("preset")? {
        None => None,
        Some(name) => match crate::medium::presets::preset(&name) {
            Some(coefficients) => Some(coefficients),
            None => {
                let hint = crate::choice::nearest(&name, crate::medium::presets::preset_names())
                    .map(|n| format!("; the nearest is '{n}'"))
                    .unwrap_or_default();
                p.warnings.push(format!(
                    "warning: {}: medium preset \"{name}\" not found (ignored, as pbrt does{hint})",
                    ploc(ps, "preset").position()
                ));
                None
            }
        },
    };
    let (sigma_s, sigma_a) = match preset {
        Some(c) => c,
        None => (medium_coefficient(ps, "sigma_s", Rgb::ONE)?, medium_coefficient(ps, "sigma_a", Rgb::ONE)?),
    };
    let scale = ps.float("scale", 1.0)?;
    // Emission: `Le` (normalised to luminance 1) × `Lescale`.
    let le_scale = le_scale(ps)?;
    let radiance = medium_le(ps)?.map(|le| le * le_scale).filter(|le| le.max_element() > 0.0);
    let sigma_t = sigma_a + sigma_s;
    if sigma_a.min_element() < 0.0 || sigma_s.min_element() < 0.0 || !sigma_t.is_finite() || scale < 0.0 {
        return Err(ps.error("sigma_a, sigma_s and scale must be finite and ≥ 0"));
    }
    let peak = sigma_t.max_element();
    let albedo = Rgb::from_array(std::array::from_fn(|c| if sigma_t[c] > 0.0 { sigma_s[c] / sigma_t[c] } else { 0.0 }));
    let mut o = obj("medium", "homogeneous", &ps.loc);
    // Mitsuba reads an rgb σₜ in [0, 1]: the peak goes into its scale.
    let unit = if peak > 0.0 { sigma_t / peak } else { Rgb::ZERO };
    set(&mut o, "sigma_t", Value::Rgb(unit), &ploc(ps, "sigma_a"));
    set(&mut o, "scale", Value::Float((peak * scale) as f64), &ploc(ps, "scale"));
    set(&mut o, "albedo", Value::Rgb(albedo), &ploc(ps, "sigma_s"));
    if let Some(le) = radiance {
        set(&mut o, "radiance", Value::Rgb(le), &ploc(ps, "Le"));
    }
    phase_g(ps, &mut o)?;
    Ok(o)
}

/// A shape object with the current material, area light, orientation and transform.
fn shape_obj(p: &mut Parser, ty: &str, ps: &ParamSet, to_world: Option<Transform>) -> Result<Obj> {
    let mut o = obj("shape", ty, &ps.loc);
    if let Some(t) = to_world {
        set(&mut o, "to_world", Value::Transform(t), &ps.loc);
    }
    // pbrt-v4 turns a quadric's normal over where its transform swaps handedness (`flipNormal =
    // reverseOrientation ^ transformSwapsHandedness`). A triangle mesh keeps the side its
    // winding gives in object space, as neumann's mesh transform does (it reverses the winding).
    let swaps = matches!(ty, "sphere" | "disk" | "cylinder") && to_world.is_some_and(|t| t.swaps_handedness());
    if p.gs.reverse ^ swaps {
        set(&mut o, "flip_normals", Value::Bool(true), &ps.loc);
    }
    // pbrt-v4: a shape whose interface has the same medium on both sides is no transition (the
    // ray keeps the medium it is in).
    if p.gs.inside != p.gs.outside {
        for (side, name) in [("interior", p.gs.inside.clone()), ("exterior", p.gs.outside.clone())] {
            if let Some(m) = name.and_then(|n| p.media.get(&n).cloned()) {
                set(&mut o, side, Value::Object(m), &ps.loc);
            }
        }
    }
    let material = p.current_material();
    let mut cut_out = None;
    match texturable(p, ps, "alpha", true)? {
        // pbrt-v4: a constant alpha of 1 is no cut-out.
        None => o.children.push(material),
        Some(Value::Float(a)) if a >= 1.0 => o.children.push(material),
        Some(a) => {
            // pbrt's stochastic alpha test, in expectation: a `mask` of opacity alpha; an area
            // light emits nothing where it is cut out (the emitter's `opacity`).
            let mut m = obj("bsdf", "mask", &ploc(ps, "alpha"));
            set(&mut m, "opacity", a.clone(), &ploc(ps, "alpha"));
            m.children.push(material);
            o.children.push(Rc::new(m));
            cut_out = Some(a);
        }
    }
    if let Some(al) = p.gs.area_light.clone() {
        let s = light_scale(p, &al)?;
        let radiance = match al.string("filename")? {
            // pbrt-v4's image area light: the image's RGB (bilinear, clamped) at (u, 1 − v).
            Some(file) => {
                if al.has("L") {
                    return Err(al.error_at("L", "give either \"L\" or \"filename\" (an image), not both"));
                }
                let at = ploc(&al, "filename");
                let mut b = obj("texture", "bitmap", &at);
                set(&mut b, "filename", Value::String(file), &at);
                set(&mut b, "wrap_mode", Value::String("clamp".into()), &at);
                let flip = Mat4::from_cols_array(&[
                    1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0,
                ]);
                set(&mut b, "to_uv", Value::Transform(transform(flip, &al)?), &at);
                match s {
                    1.0 => Value::Object(Rc::new(b)),
                    s => Value::Object(Rc::new(scale_texture(Value::Object(Rc::new(b)), s, &at, &ploc(&al, "scale")))),
                }
            }
            None => {
                let l = match al.spectrum("L")? {
                    Some(x) => spectrum_value(&al, "L", x, true)?,
                    None => Value::Float(1.0),
                };
                scaled(l, s)
            }
        };
        let mut e = obj("emitter", "area", &al.loc);
        set(&mut e, "radiance", radiance, &ploc(&al, "L"));
        if al.bool("twosided", false)? {
            set(&mut e, "two_sided", Value::Bool(true), &ploc(&al, "twosided"));
        }
        // pbrt-v4: radiance × power / (π · area · sides), where the power is positive.
        let power = al.float("power", -1.0)?;
        if power > 0.0 {
            set(&mut e, "power", Value::Float(power as f64), &ploc(&al, "power"));
        }
        if let Some(a) = cut_out {
            set(&mut e, "opacity", a, &ploc(ps, "alpha"));
        }
        o.children.push(Rc::new(e));
    }
    Ok(o)
}

/// `Shape`: the objects it adds.
pub fn shape(p: &mut Parser, ty: &str, ps: &ParamSet) -> Result<Vec<Rc<Obj>>> {
    let ctm = p.gs.ctm;
    for ignored in ["emissionfilename"] {
        if ps.has(ignored) {
            return Err(ps.error_at(ignored, format!("\"{ignored}\" is not implemented by neumann")));
        }
    }
    let obj = match ty {
        "sphere" => {
            let r = ps.float("radius", 1.0)?;
            let (zmin, zmax, phimax) = (ps.float("zmin", -r)?, ps.float("zmax", r)?, ps.float("phimax", 360.0)?);
            if crate::geometry::SphereClip::from_pbrt(r, zmin, zmax, phimax).is_none() {
                return Err(ps.error("zmin, zmax and phimax leave nothing of the sphere"));
            }
            let mut o = shape_obj(p, "sphere", ps, Some(transform(ctm, ps)?))?;
            set(&mut o, "radius", Value::Float(r as f64), &ploc(ps, "radius"));
            // pbrt clamps zmin and zmax to the sphere and phimax to [0, 360].
            let (lo, hi) = (zmin.min(zmax).clamp(-r, r), zmin.max(zmax).clamp(-r, r));
            set(&mut o, "zmin", Value::Float(lo as f64), &ploc(ps, "zmin"));
            set(&mut o, "zmax", Value::Float(hi as f64), &ploc(ps, "zmax"));
            set(&mut o, "phimax", Value::Float(phimax.clamp(0.0, 360.0) as f64), &ploc(ps, "phimax"));
            set(&mut o, "parameterization", Value::String("pbrt".into()), &ps.loc);
            o
        }
        "disk" => {
            let (h, r, ri, phimax) = (
                ps.float("height", 0.0)?,
                ps.float("radius", 1.0)?,
                ps.float("innerradius", 0.0)?,
                ps.float("phimax", 360.0)?,
            );
            if !(r > 0.0 && ri >= 0.0 && ri < r) {
                return Err(ps.error_at("innerradius", "a disk needs 0 ≤ innerradius < radius"));
            }
            if phimax <= 0.0 || phimax.is_nan() {
                return Err(ps.error_at("phimax", "phimax leaves nothing of the disk"));
            }
            let m = ctm * Mat4::from_translation(Vec3::new(0.0, 0.0, h)) * Mat4::from_scale(Vec3::new(r, r, 1.0));
            let mut o = shape_obj(p, "disk", ps, Some(transform(m, ps)?))?;
            set(&mut o, "parameterization", Value::String("pbrt".into()), &ps.loc);
            set(&mut o, "innerradius", Value::Float((ri / r) as f64), &ploc(ps, "innerradius"));
            set(&mut o, "phimax", Value::Float(phimax.min(360.0) as f64), &ploc(ps, "phimax"));
            o
        }
        "cylinder" => {
            let (r, zmin, zmax, phimax) =
                (ps.float("radius", 1.0)?, ps.float("zmin", -1.0)?, ps.float("zmax", 1.0)?, ps.float("phimax", 360.0)?);
            if phimax <= 0.0 || phimax.is_nan() {
                return Err(ps.error_at("phimax", "phimax leaves nothing of the cylinder"));
            }
            // pbrt orders zmin and zmax; an axis along +z keeps the local x axis (φ = 0) at +x.
            let (zmin, zmax) = (zmin.min(zmax), zmin.max(zmax));
            let mut o = shape_obj(p, "cylinder", ps, Some(transform(ctm, ps)?))?;
            set(&mut o, "p0", Value::Point(Vec3::new(0.0, 0.0, zmin)), &ploc(ps, "zmin"));
            set(&mut o, "p1", Value::Point(Vec3::new(0.0, 0.0, zmax)), &ploc(ps, "zmax"));
            set(&mut o, "phimax", Value::Float(phimax.min(360.0) as f64), &ploc(ps, "phimax"));
            set(&mut o, "radius", Value::Float(r as f64), &ploc(ps, "radius"));
            o
        }
        "trianglemesh" | "bilinearmesh" | "loopsubdiv" => {
            let mesh = match ty {
                "loopsubdiv" => super::mesh::loop_subdivision(ps)?,
                _ => super::mesh::from_params(ps, ty == "bilinearmesh")?,
            };
            let name = format!("#pbrt-mesh-{}", p.mesh_count);
            p.mesh_count += 1;
            p.memory.meshes.insert(name.clone(), mesh);
            let mut o = shape_obj(p, "mesh", ps, Some(transform(ctm, ps)?))?;
            set(&mut o, "filename", Value::String(name), &ps.loc);
            o
        }
        "plymesh" => {
            let file = ps.string("filename")?.ok_or_else(|| ps.error("a plymesh needs its \"string filename\""))?;
            if ps.has("displacement") {
                return Err(ps.error_at("displacement", "displacement is not implemented by neumann"));
            }
            let path = p.resolver.resolve(&file);
            let mesh = super::mesh::read_ply(&path).map_err(|e| ps.error_at("filename", e))?;
            let name = format!("#pbrt-mesh-{}", p.mesh_count);
            p.mesh_count += 1;
            p.memory.meshes.insert(name.clone(), mesh);
            let mut o = shape_obj(p, "mesh", ps, Some(transform(ctm, ps)?))?;
            set(&mut o, "filename", Value::String(name), &ploc(ps, "filename"));
            o
        }
        "curve" => {
            let curves = curve_set(p, ps)?;
            p.curve_pieces += curves.curves.len() << curves.split_depth;
            if p.curve_pieces > MAX_CURVE_PIECES {
                return Err(ps.error_at(
                    "splitdepth",
                    format!("the scene's curves make more than {MAX_CURVE_PIECES} pieces (curves × 2^splitdepth)"),
                ));
            }
            let name = format!("#pbrt-curve-{}", p.mesh_count);
            p.mesh_count += 1;
            p.memory.curves.insert(name.clone(), curves);
            let mut o = shape_obj(p, "curve", ps, Some(transform(ctm, ps)?))?;
            set(&mut o, "filename", Value::String(name), &ps.loc);
            o
        }
        "cone" | "paraboloid" | "hyperboloid" => {
            return Err(ps.error(format!("the \"{ty}\" shape is not implemented by neumann yet")))
        }
        other => {
            return Err(ps.unknown(
                "shape",
                other,
                &["bilinearmesh", "curve", "cylinder", "disk", "loopsubdiv", "plymesh", "sphere", "trianglemesh"],
            ))
        }
    };
    let mut obj = obj;
    if p.gs.moving() {
        // pbrt-v4's animated shapes (every kind): placed by the transform interpolated at each
        // ray's time.
        if p.gs.area_light.is_some() {
            return Err(ps.error("a moving shape cannot carry an AreaLightSource (animated area lights, which pbrt-v4 refuses too)"));
        }
        let (t0, t1) = p.gs.times;
        set(&mut obj, "to_world_end", Value::Transform(transform(p.gs.ctm_end, ps)?), &ps.loc);
        set(&mut obj, "motion_start", Value::Float(t0 as f64), &ps.loc);
        set(&mut obj, "motion_end", Value::Float(t1 as f64), &ps.loc);
    }
    Ok(vec![Rc::new(obj)])
}

/// Most curve pieces (primitives) a scene may make: 2²⁶, about 4 GB of them; `splitdepth` (up
/// to 10) would otherwise let a small file ask for unbounded memory.
pub const MAX_CURVE_PIECES: usize = 1 << 26;

/// pbrt-v4's `curve`: `P` (control points), `basis` (`bezier`, `bspline`), `degree` (3 or
/// 2), `type` (`flat`, `cylinder`, `ribbon` with one normal `N` per segment end), `width` (1),
/// `width0`, `width1`, `splitdepth` (3).
fn curve_set(p: &mut Parser, ps: &ParamSet) -> Result<crate::geometry::CurveSet> {
    use crate::geometry::curve::CurveKind;
    let cp = ps.vec3s("P", &["point3", "point"])?.unwrap_or_default();
    if cp.is_empty() {
        return Err(ps.error("a curve needs its control points \"point3 P\""));
    }
    let bspline = match ps.string("basis")?.as_deref() {
        None | Some("bezier") => false,
        Some("bspline") => true,
        Some(other) => return Err(ps.unknown("basis", other, &["bezier", "bspline"])),
    };
    let degree = ps.int("degree", 3)?;
    let kind = match ps.string("type")?.as_deref() {
        None | Some("flat") => CurveKind::Flat,
        Some("cylinder") => CurveKind::Cylinder,
        Some("ribbon") => CurveKind::Ribbon,
        Some(other) => return Err(ps.unknown("curve type", other, &["cylinder", "flat", "ribbon"])),
    };
    let mut normals = ps.vec3s("N", &["normal3", "normal"])?.unwrap_or_default();
    if !normals.is_empty() && kind != CurveKind::Ribbon {
        // pbrt-v4 ignores them too, with a warning.
        p.warnings.push(format!(
            "warning: {}: curve normals \"N\" are used by \"ribbon\" curves only (ignored, as pbrt does)",
            ploc(ps, "N").position()
        ));
        normals.clear();
    }
    let width = ps.float("width", 1.0)?;
    let w = [ps.float("width0", width)?, ps.float("width1", width)?];
    let split = ps.int("splitdepth", 3)?;
    if !(0..=10).contains(&split) {
        return Err(ps.error_at("splitdepth", format!("splitdepth must be between 0 and 10, got {split}")));
    }
    let degree = usize::try_from(degree).unwrap_or(0);
    crate::geometry::CurveSet::from_control_points(&cp, degree, bspline, kind, &normals, w, split as u32)
        .map_err(|e| ps.error(e.to_string()))
}

/// A copy of a shape object placed by `instance` (applied after its own `to_world`).
pub fn placed(o: &Obj, instance: &Mat4) -> Obj {
    let mut props: Vec<Prop> = Vec::new();
    let mut had = false;
    for p in &o.props {
        let value = match (&p.name[..], &p.value) {
            ("to_world", Value::Transform(t)) => {
                had = true;
                Value::Transform(Transform::from_matrix(*instance * *t.matrix()).unwrap_or(*t))
            }
            // A moving shape's end placement (a moving shape in an object): placed likewise.
            ("to_world_end", Value::Transform(t)) => {
                Value::Transform(Transform::from_matrix(*instance * *t.matrix()).unwrap_or(*t))
            }
            (_, v) => v.clone(),
        };
        props.push(Prop::new(&p.name, value, p.loc.clone()));
    }
    if !had {
        if let Some(t) = Transform::from_matrix(*instance) {
            props.push(Prop::new("to_world", Value::Transform(t), o.loc.clone()));
        }
    }
    Obj { props, children: o.children.clone(), ..Obj::new(&o.tag, &o.ty, o.loc.clone()) }
}
