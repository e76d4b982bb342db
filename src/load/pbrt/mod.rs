//! pbrt-v4 scene files: `neumann render scene.pbrt`.
//!
//! [`lexer`] splits the text into located tokens, [`parser`] executes the directives over pbrt's
//! graphics state (transforms, attribute blocks, named coordinate systems, materials, textures,
//! object instances, `Include` / `Import`), and `translate` turns each camera, film, sampler,
//! filter, integrator, shape, material, texture and light into the plugin objects a Mitsuba file
//! gives ([`crate::props::Obj`]), which the shared builder makes into the scene. Problems are
//! errors at `file:line:col`; a parameter that nothing reads is an error (pbrt-v4 stops on them
//! too), and so is every directive, plugin or parameter neumann does not implement.

mod illuminants;
pub mod lexer;
mod mesh;
pub mod params;
pub mod parser;
mod translate;

use crate::load::overrides::Overrides;
use crate::load::SceneFile;
use crate::math::{Mat4, Vec3};
use crate::props::{Loc, Obj, SceneError, SourceFile, Value};
use params::ParamSet;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;
use translate::{obj, ploc as loc_of, set};

type Result<T> = std::result::Result<T, SceneError>;

/// Loads a pbrt-v4 scene file with settings from outside the file (command-line flags).
pub fn load_pbrt_file(path: &Path, settings: &Overrides) -> Result<SceneFile> {
    let mut parser = parser::Parser::new(path);
    parser.parse_file(path, None)?;
    finish(parser, path, settings)
}

/// Loads a pbrt-v4 scene from text (`path` names it and anchors relative file names).
pub fn load_pbrt_text(path: &Path, text: &str, settings: &Overrides) -> Result<SceneFile> {
    let mut parser = parser::Parser::new(path);
    parser.parse_text(path.to_path_buf(), text.to_string())?;
    finish(parser, path, settings)
}

fn finish(mut parser: parser::Parser, path: &Path, settings: &Overrides) -> Result<SceneFile> {
    let file = Arc::new(SourceFile { path: path.to_path_buf(), text: String::new() });
    parser.finish_checks(&file)?;
    let loc = Loc { file, offset: 0 };
    let mut scene = obj("scene", "scene", &loc);
    scene.children.push(Rc::new(integrator(&mut parser, &loc)?));
    scene.children.push(Rc::new(sensor(&mut parser, &loc)?));
    scene.children.append(&mut parser.emitters);
    // Named materials used before their definition are known now: first those inside named
    // materials (mixes), so that every shape shares its material's one object, then the shapes'.
    let shapes = std::mem::take(&mut parser.shapes);
    scene.children.extend(parser.resolve_named_materials(shapes)?);
    let root = crate::load::overrides::apply(&Rc::new(scene), settings);
    let resolver = parser.resolver.clone();
    let memory = std::mem::take(&mut parser.memory);
    let mut out = crate::load::build::Builder::with_memory(resolver, memory).build(&root)?;
    out.warnings.extend(parser.warnings);
    Ok(out)
}

/// The directive's plugin type.
fn plugin_type(ps: &ParamSet) -> String {
    ps.string("__type").ok().flatten().unwrap_or_default()
}

/// `Integrator` (default `volpath`, pbrt-v4's; neumann's `path` renders the same image without
/// media): `maxdepth` (5 bounces) → `max_depth` = `maxdepth` + 1.
fn integrator(p: &mut parser::Parser, loc: &Loc) -> Result<Obj> {
    let Some(ps) = p.integrator.take() else {
        // pbrt-v4's default, volpath; neumann's path renders the same image without media and
        // subsurface materials.
        let kind = if p.media.is_empty() && !p.subsurface { "path" } else { "volpath" };
        let mut o = obj("integrator", kind, loc);
        set(&mut o, "max_depth", Value::Integer(6), loc);
        return Ok(o);
    };
    let ty = plugin_type(&ps);
    let kind = match ty.as_str() {
        "path" | "simplepath" | "randomwalk" => "path",
        "volpath" | "simplevolpath" => "volpath",
        "lightpath" => "ptracer",
        "bdpt" | "mlt" | "sppm" => {
            p.warnings.push(format!(
                "warning: {}: Integrator \"{ty}\" is not implemented by neumann: rendered by the path tracer (the same expected image, with other noise; caustics may converge slower)",
                ps.loc.position()
            ));
            for name in ["maxdepth", "regularize", "visualizestrategies", "visualizeweights", "bootstrapsamples", "chains", "mutationsperpixel", "largestepprobability", "sigma", "photonsperiteration", "radius", "seed", "iterations"] {
                if let Some(q) = ps.params.iter().find(|q| q.name == name) {
                    if name != "maxdepth" {
                        q.used.set(true);
                    }
                }
            }
            "path"
        }
        "ambientocclusion" | "aov" => return Err(ps.error(format!("the \"{ty}\" integrator is not implemented by neumann (its image is not the rendering equation's solution)"))),
        other => return Err(ps.unknown("integrator", other, &["ambientocclusion", "aov", "bdpt", "lightpath", "mlt", "path", "randomwalk", "simplepath", "simplevolpath", "sppm", "volpath"])),
    };
    let mut o = obj("integrator", kind, &ps.loc);
    let depth = ps.int("maxdepth", 5)?;
    if depth < 0 {
        return Err(ps.error_at("maxdepth", "maxdepth must be ≥ 0"));
    }
    set(&mut o, "max_depth", Value::Integer(depth + 1), &loc_of(&ps, "maxdepth"));
    if ty == "path" || ty == "volpath" {
        if ps.bool("regularize", false)? {
            // pbrt-v4's path regularization (biased): neumann's `regularize`.
            set(&mut o, "regularize", Value::Bool(true), &loc_of(&ps, "regularize"));
        }
        if let Some(s) = ps.string("lightsampler")? {
            let neumann = match s.as_str() {
                "bvh" => "bvh",
                "power" => "power",
                "uniform" => "uniform",
                other => return Err(ps.error_at("lightsampler", format!("unknown light sampler \"{other}\""))),
            };
            set(&mut o, "light_sampler", Value::String(neumann.into()), &loc_of(&ps, "lightsampler"));
        }
        // Earlier pbrt-v4's `rrthreshold` (1; pbrt-v4-scenes' transparent-machines gives 0):
        // Russian roulette where the throughput falls below it. Roulette is unbiased, so the
        // threshold changes noise only: 0 (no roulette) holds neumann's roulette off; any other
        // value keeps neumann's (Mitsuba's rule), with a warning.
        if ps.has("rrthreshold") {
            let t = ps.float("rrthreshold", 1.0)?;
            if !(t >= 0.0 && t.is_finite()) {
                return Err(ps.error_at("rrthreshold", format!("rrthreshold must be finite and ≥ 0, got {t}")));
            }
            if t == 0.0 {
                let never = crate::integrator::trace::MAX_SEGMENTS as i64;
                set(&mut o, "rr_depth", Value::Integer(never), &loc_of(&ps, "rrthreshold"));
            } else {
                p.warnings.push(format!(
                    "warning: {}: \"rrthreshold\" {t}: neumann's Russian roulette (Mitsuba's rule, from the fifth segment) replaces pbrt's threshold; the expected image is the same, the noise differs",
                    loc_of(&ps, "rrthreshold").position()
                ));
            }
        }
    }
    ps.check_unused()?;
    Ok(o)
}

/// The sensor: `Camera`, `Film`, `Sampler`, `PixelFilter`.
fn sensor(p: &mut parser::Parser, loc: &Loc) -> Result<Obj> {
    let (cam, world_from_camera) = match p.camera.take() {
        Some(c) => c,
        None => {
            // pbrt's default: a perspective camera at the origin looking down +z.
            let ps = ParamSet { params: Vec::new(), loc: loc.clone(), what: "Camera".into() };
            (ps, Mat4::IDENTITY)
        }
    };
    let ty = if cam.has("__type") { plugin_type(&cam) } else { "perspective".into() };
    // Film.
    let (mut width, mut height) = (1280i64, 720i64);
    let mut crop: Option<[i64; 4]> = None;
    // pbrt-v4's sensor steps: white balance (K) and the sample clamp.
    let (mut white_balance, mut max_component) = (0.0f32, f32::INFINITY);
    // pbrt-v4's named camera sensors (see `film::sensor::camera`).
    let mut sensor = "cie1931".to_string();
    // The film's diagonal (mm): only the realistic camera's image depends on it.
    let mut diagonal = (35.0f32, loc.clone());
    if let Some(f) = p.film.take() {
        let fty = plugin_type(&f);
        if fty != "rgb" && fty != "gbuffer" {
            return Err(f.error(format!("the \"{fty}\" film is not implemented by neumann (rgb, gbuffer)")));
        }
        width = f.int("xresolution", 1280)?;
        height = f.int("yresolution", 720)?;
        if !(1..=1 << 16).contains(&width) || !(1..=1 << 16).contains(&height) {
            return Err(f.error_at("xresolution", format!("resolution {width}×{height} out of range")));
        }
        if let Some(w) = f.floats("cropwindow", &["float"])? {
            let [x0, x1, y0, y1] = w[..] else { return Err(f.error_at("cropwindow", "takes x0 x1 y0 y1")) };
            // pbrt: pixels ⌈w·x0⌉ … ⌈w·x1⌉ (exclusive).
            let px = |v: f64, n: i64| ((v.clamp(0.0, 1.0) * n as f64).ceil() as i64).clamp(0, n);
            crop = Some([px(x0, width), px(x1, width), px(y0, height), px(y1, height)]);
        }
        if let Some(b) = f.floats("pixelbounds", &["integer"])? {
            let [x0, x1, y0, y1] = b[..] else { return Err(f.error_at("pixelbounds", "takes x0 x1 y0 y1")) };
            crop = Some([x0 as i64, x1 as i64, y0 as i64, y1 as i64]);
        }
        if let Some([x0, x1, y0, y1]) = crop {
            if !(0 <= x0 && x0 < x1 && x1 <= width && 0 <= y0 && y0 < y1 && y1 <= height) {
                return Err(f.error("the crop window is empty or outside the image"));
            }
        }
        // `iso` (with the camera's shutter interval) scales the lights: translate::imaging_ratio.
        f.float("iso", 100.0)?;
        // So does an earlier pbrt-v4's `scale` (current pbrt-v4's films do not read it).
        if f.has("scale") {
            let scale = f.float("scale", 1.0)?;
            if !(scale > 0.0 && scale.is_finite()) {
                return Err(f.error_at("scale", format!("the film's scale must be positive, got {scale}")));
            }
            p.warnings.push(format!(
                "warning: {}: Film \"scale\" {scale}: an earlier pbrt-v4's parameter (current pbrt-v4 does not read it): the image is multiplied by it",
                loc_of(&f, "scale").position()
            ));
        }
        white_balance = f.float("whitebalance", 0.0)?;
        if white_balance != 0.0 && !(1000.0..=40000.0).contains(&white_balance) {
            return Err(f.error_at("whitebalance", format!("a white balance of {white_balance} K: expected 1000–40000 K (or 0: none)")));
        }
        if let Some(s) = f.string("sensor")? {
            if s != "cie1931" && !crate::film::sensor::camera_names().any(|c| c == s) {
                let names: Vec<&str> = crate::film::sensor::camera_names().collect();
                return Err(f.error_at("sensor", format!("unknown sensor \"{s}\" (cie1931, {})", names.join(", "))));
            }
            sensor = s;
        }
        // The output's name and storage cannot change the image: neumann's -o decides.
        diagonal = (f.float("diagonal", 35.0)?, loc_of(&f, "diagonal"));
        for name in ["filename", "savefp16", "writefp16"] {
            if let Some(q) = f.params.iter().find(|q| q.name == name) {
                q.used.set(true);
            }
        }
        max_component = f.float("maxcomponentvalue", f32::INFINITY)?;
        if max_component <= 0.0 {
            return Err(f.error_at("maxcomponentvalue", "\"maxcomponentvalue\" must be positive"));
        }
        f.check_unused()?;
    }
    let mut s = obj("sensor", "perspective", &cam.loc);
    // pbrt's camera space has +x at the image's right; Mitsuba's at its left (below).
    let aspect = width as f32 / height as f32;
    match ty.as_str() {
        "perspective" => {
            let fov = cam.float("fov", 90.0)?;
            if !(fov > 0.0 && fov < 180.0) {
                return Err(cam.error_at("fov", format!("fov must lie in (0, 180), got {fov}")));
            }
            set(&mut s, "fov", Value::Float(fov as f64), &loc_of(&cam, "fov"));
            set(&mut s, "fov_axis", Value::String("smaller".into()), &cam.loc);
            let lens = cam.float("lensradius", 0.0)?;
            if lens > 0.0 {
                s.ty = "thinlens".into();
                set(&mut s, "aperture_radius", Value::Float(lens as f64), &loc_of(&cam, "lensradius"));
                set(
                    &mut s,
                    "focus_distance",
                    Value::Float(cam.float("focaldistance", 1e6)? as f64),
                    &loc_of(&cam, "focaldistance"),
                );
            } else {
                cam.float("focaldistance", 1e6)?;
            }
        }
        "orthographic" => {
            s.ty = "orthographic".into();
            if cam.float("lensradius", 0.0)? > 0.0 {
                return Err(cam.error_at("lensradius", "a thin-lens orthographic camera is not implemented by neumann"));
            }
            cam.float("focaldistance", 1e6)?;
        }
        "spherical" => {
            s.ty = "spherical".into();
            let mapping = match cam.string("mapping")?.as_deref() {
                None | Some("equalarea") => "equal_area",
                Some("equirectangular") => "equirectangular",
                Some(other) => {
                    return Err(cam.error_at(
                        "mapping",
                        format!("unknown spherical mapping \"{other}\" (equalarea, equirectangular)"),
                    ))
                }
            };
            set(&mut s, "mapping", Value::String(mapping.into()), &loc_of(&cam, "mapping"));
        }
        "realistic" => {
            // pbrt-v4's RealisticCamera → neumann's `realistic` sensor (the same tracing).
            s.ty = "realistic".into();
            let file = cam.string("lensfile")?.filter(|f| !f.is_empty());
            let file = file.ok_or_else(|| cam.error("a realistic camera needs its \"string lensfile\""))?;
            set(&mut s, "lens_file", Value::String(file), &loc_of(&cam, "lensfile"));
            let diameter = cam.float("aperturediameter", 1.0)?;
            set(&mut s, "aperture_diameter", Value::Float(diameter as f64), &loc_of(&cam, "aperturediameter"));
            let focus = cam.float("focusdistance", 10.0)?;
            set(&mut s, "focus_distance", Value::Float(focus as f64), &loc_of(&cam, "focusdistance"));
            if let Some(a) = cam.string("aperture")?.filter(|a| !a.is_empty()) {
                set(&mut s, "aperture", Value::String(a), &loc_of(&cam, "aperture"));
            }
            set(&mut s, "film_diagonal", Value::Float(diagonal.0 as f64), &diagonal.1);
        }
        other => return Err(cam.unknown("camera", other, &["orthographic", "perspective", "realistic", "spherical"])),
    }
    // (The realistic camera reads neither: pbrt-v4 reports them unused.)
    let projective = ty != "realistic";
    let frame = if projective { cam.floats("frameaspectratio", &["float"])? } else { None };
    if let Some(a) = frame {
        if (a[0] as f32 - aspect).abs() > 1e-4 {
            return Err(cam.error_at(
                "frameaspectratio",
                "a frame aspect ratio other than the film's is not implemented by neumann",
            ));
        }
    }
    // pbrt's screen window: [-aspect, aspect] × [-1, 1] (wide images), or [-1, 1] × [-1/aspect,
    // 1/aspect]; the orthographic camera scales it into Mitsuba's x ∈ [-1, 1].
    let half = if aspect >= 1.0 { aspect } else { 1.0 };
    let window = if projective { cam.floats("screenwindow", &["float"])? } else { None };
    if let Some(w) = window {
        let default =
            if aspect >= 1.0 { [-aspect, aspect, -1.0, 1.0] } else { [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect] };
        if w.len() != 4 || w.iter().zip(default).any(|(a, b)| (*a as f32 - b).abs() > 1e-4) {
            return Err(cam
                .error_at("screenwindow", "a screen window other than the default is not implemented by neumann yet"));
        }
    }
    // Camera space as Mitsuba's (+x left; the orthographic window's scale), after pbrt's
    // world-from-camera transform: at the start and, for a moving camera, at the end.
    let camera_space = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))
        * if ty == "orthographic" { Mat4::from_scale(Vec3::new(half, half, 1.0)) } else { Mat4::IDENTITY };
    let placed = |world_from_camera: Mat4| {
        crate::math::Transform::from_matrix(world_from_camera * camera_space)
            .ok_or_else(|| cam.error("the camera transform is singular"))
    };
    set(&mut s, "to_world", Value::Transform(placed(world_from_camera)?), &cam.loc);
    if let Some((end, (t0, t1))) = p.camera_motion.take() {
        set(&mut s, "to_world_end", Value::Transform(placed(end)?), &cam.loc);
        set(&mut s, "motion_start", Value::Float(f64::from(t0)), &cam.loc);
        set(&mut s, "motion_end", Value::Float(f64::from(t1)), &cam.loc);
    }
    // The shutter interval (pbrt-v4's default 0 to 1): the times camera rays sample where
    // shapes move (the imaging ratio checks that it is not empty).
    let (open, close) = (cam.float("shutteropen", 0.0)?, cam.float("shutterclose", 1.0)?);
    if open <= close {
        set(&mut s, "shutter_open", Value::Float(open as f64), &cam.loc);
        set(&mut s, "shutter_close", Value::Float(close as f64), &cam.loc);
    }
    cam.string("__type")?;
    cam.check_unused()?;
    let mut film = obj("film", "hdrfilm", loc);
    set(&mut film, "width", Value::Integer(width), loc);
    set(&mut film, "height", Value::Integer(height), loc);
    if sensor != "cie1931" {
        set(&mut film, "sensor", Value::String(sensor), loc);
    }
    if white_balance != 0.0 {
        set(&mut film, "white_balance", Value::Float(white_balance as f64), loc);
    }
    if max_component.is_finite() {
        set(&mut film, "max_component", Value::Float(max_component as f64), loc);
        // pbrt-v4 bounds its sensor's RGB (XYZ for cie1931), before the colour matrix.
        set(&mut film, "max_component_of", Value::String("sensor".into()), loc);
    }
    if let Some([x0, x1, y0, y1]) = crop {
        set(&mut film, "crop_offset_x", Value::Integer(x0), loc);
        set(&mut film, "crop_offset_y", Value::Integer(y0), loc);
        set(&mut film, "crop_width", Value::Integer(x1 - x0), loc);
        set(&mut film, "crop_height", Value::Integer(y1 - y0), loc);
    }
    // Filter (pbrt-v4's default: Gaussian, σ 0.5, radius 1.5).
    let mut rfilter = obj("rfilter", "gaussian", loc);
    if p.filter.is_none() {
        set(&mut rfilter, "radius", Value::Float(1.5), loc);
    }
    if let Some(f) = p.filter.take() {
        let fty = plugin_type(&f);
        rfilter.loc = f.loc.clone();
        match fty.as_str() {
            "gaussian" => {
                set(&mut rfilter, "stddev", Value::Float(f.float("sigma", 0.5)? as f64), &loc_of(&f, "sigma"));
                let r = filter_radius(&f, 1.5)?;
                set(&mut rfilter, "radius", Value::Float(r as f64), &loc_of(&f, "xradius"));
            }
            "box" => {
                rfilter.ty = "box".into();
                let r = filter_radius(&f, 0.5)?;
                set(&mut rfilter, "radius", Value::Float(r as f64), &loc_of(&f, "xradius"));
            }
            "triangle" => {
                rfilter.ty = "tent".into();
                let r = filter_radius(&f, 2.0)?;
                set(&mut rfilter, "radius", Value::Float(r as f64), &loc_of(&f, "xradius"));
            }
            "mitchell" => {
                // pbrt-v4 stretches the cubic to its radius (Mitchell1D(2x / radius)).
                rfilter.ty = "mitchell".into();
                set(&mut rfilter, "B", Value::Float(f.float("B", 1.0 / 3.0)? as f64), &loc_of(&f, "B"));
                set(&mut rfilter, "C", Value::Float(f.float("C", 1.0 / 3.0)? as f64), &loc_of(&f, "C"));
                let r = filter_radius(&f, 2.0)?;
                set(&mut rfilter, "stretch", Value::Float(r as f64), &loc_of(&f, "xradius"));
            }
            "sinc" => {
                rfilter.ty = "sinc".into();
                set(&mut rfilter, "tau", Value::Float(f.float("tau", 3.0)? as f64), &loc_of(&f, "tau"));
                let r = filter_radius(&f, 4.0)?;
                set(&mut rfilter, "radius", Value::Float(r as f64), &loc_of(&f, "xradius"));
            }
            other => return Err(f.unknown("filter", other, &["box", "gaussian", "mitchell", "sinc", "triangle"])),
        }
        f.check_unused()?;
    }
    film.children.push(Rc::new(rfilter));
    // Sampler (pbrt-v4's default: zsobol, 16 samples per pixel).
    let mut sampler = obj("sampler", "ldsampler", loc);
    let mut spp = 16;
    if let Some(sp) = p.sampler.take() {
        let sty = plugin_type(&sp);
        sampler.loc = sp.loc.clone();
        sampler.ty = match sty.as_str() {
            "zsobol" | "sobol" | "paddedsobol" | "halton" => "ldsampler",
            "pmj02bn" => "stratified",
            "independent" => "independent",
            "stratified" => {
                let (x, y) = (sp.int("xsamples", 4)?, sp.int("ysamples", 4)?);
                sp.bool("jitter", true)?;
                spp = x * y;
                "stratified"
            }
            other => return Err(sp.unknown("sampler", other, &["halton", "independent", "paddedsobol", "pmj02bn", "sobol", "stratified", "zsobol"])),
        }
        .into();
        if sty != "stratified" {
            spp = sp.int("pixelsamples", 16)?;
        }
        if let Some(seed) = sp.floats("seed", &["integer"])? {
            set(&mut sampler, "seed", Value::Integer(seed[0] as i64), &loc_of(&sp, "seed"));
        }
        // The randomization changes the noise, not the expected image.
        sp.string("randomization")?;
        sp.check_unused()?;
    }
    let sloc = sampler.loc.clone();
    set(&mut sampler, "sample_count", Value::Integer(spp), &sloc);
    s.children.push(Rc::new(film));
    s.children.push(Rc::new(sampler));
    if let Some(m) = p.camera_medium.take() {
        s.children.push(m);
    }
    Ok(s)
}

#[cfg(test)]
mod tests;

/// pbrt-v4's filter radius: `xradius` and `yradius` (both `default`), which neumann's filters
/// (one radius) need equal.
fn filter_radius(f: &ParamSet, default: f32) -> Result<f32> {
    let (x, y) = (f.float("xradius", default)?, f.float("yradius", default)?);
    if x != y {
        return Err(f.error_at("yradius", format!("neumann's filters have one radius: xradius {x} and yradius {y} differ")));
    }
    if !(x > 0.0 && x.is_finite()) {
        return Err(f.error_at("xradius", format!("a filter radius must be positive, got {x}")));
    }
    Ok(x)
}
