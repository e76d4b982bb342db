//! Mitsuba 3 plugins to neumann objects: sensor, film, sampler, integrator, shapes, BSDFs,
//! textures and emitters. Parameter names, defaults and semantics are Mitsuba's; each plugin's
//! parameters are listed in the README's scene-format table.

use super::error::{nearest, SceneError};
use super::parse::{resolve, Obj, Value};
use super::SceneFile;
use crate::camera::{Camera, FovAxis};
use crate::choice::Choice;
use crate::film::filter::Filter;
use crate::geometry::{Cylinder, Disk, Geometry, Sphere, TriangleMesh};
use crate::integrator::{
    radiosity, AnyIntegrator, DirectIntegrator, LightTracer, PathIntegrator, PathSettings, VolPathIntegrator,
};
use crate::light::LightSamplerKind;
use crate::light::{EnvMap, Light};
use crate::load::image::{load_image, Image};
use crate::material::fresnel::lookup_ior;
use crate::material::microfacet::{Microfacet, MicrofacetType};
use crate::material::{
    conductor_names, named_conductor, Bsdf, Conductor, ConductorIor, Dielectric, Diffuse, Plastic, RoughConductor,
    RoughDielectric, RoughPlastic, ThinDielectric,
};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Frame, Mat3, Rgb, Transform, Vec3};
use crate::medium::{Medium, PhaseFunction};
use crate::sampling::sampler::SamplerKind;
use crate::scene::SceneBuilder;
use crate::texture::{Bitmap, Filter as TexFilter, Texture, Wrap};
use std::collections::HashMap;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::Arc;

type Result<T> = std::result::Result<T, SceneError>;

const SHAPES: &[&str] = &["obj", "ply", "rectangle", "disk", "cube", "sphere", "cylinder", "shapegroup", "instance"];
const BSDFS: &[&str] = &[
    "diffuse",
    "conductor",
    "roughconductor",
    "dielectric",
    "thindielectric",
    "roughdielectric",
    "plastic",
    "roughplastic",
    "twosided",
    "blendbsdf",
    "mask",
    "null",
];
const EMITTERS: &[&str] = &["area", "point", "spot", "directional", "constant", "envmap"];
const INTEGRATORS: &[&str] = &["path", "direct", "ptracer", "radiosity", "volpath"];
const SAMPLERS: &[&str] = &["independent", "stratified", "multijitter", "orthogonal", "ldsampler"];
const FILTERS: &[&str] = &["box", "tent", "gaussian"];
const TEXTURES: &[&str] = &["bitmap", "checkerboard"];

/// Error for an unknown plugin type, naming the nearest supported one.
fn unknown(o: &Obj, supported: &[&str]) -> SceneError {
    let hint = nearest(&o.ty, supported.iter().copied()).map(|n| format!("; the nearest is '{n}'")).unwrap_or_default();
    o.error(format!("unsupported {} plugin (supported: {}{hint})", o.tag, supported.join(", ")))
}

/// What the sensor with its film and sampler asks for.
struct SensorSettings {
    camera: Camera,
    spp: u32,
    sampler: SamplerKind,
    seed: u64,
    filter: Filter,
    window: Option<[u32; 4]>,
    alpha: bool,
}

/// Builds the scene from the parsed root object.
pub struct Builder {
    sb: SceneBuilder,
    bsdf_index: HashMap<*const Obj, u32>,
    images: HashMap<(PathBuf, bool), Arc<Image>>,
    /// The default BSDFs (diffuse 0.5 for plain shapes, black for emitters), once created.
    default_bsdf: [Option<u32>; 2],
    medium_index: HashMap<*const Obj, u32>,
    /// The integrator's `light_sampler` (neumann's own parameter; default the light BVH).
    light_sampler: LightSamplerKind,
}

impl Builder {
    pub fn new() -> Builder {
        Builder {
            sb: SceneBuilder::new(),
            bsdf_index: HashMap::new(),
            images: HashMap::new(),
            default_bsdf: [None; 2],
            medium_index: HashMap::new(),
            light_sampler: LightSamplerKind::default(),
        }
    }

    /// Builds everything under `root` (a `<scene>`).
    pub fn build(mut self, root: &Obj) -> Result<SceneFile> {
        root.built.set(true);
        let mut integrator = None;
        let mut sensor = None;
        for c in &root.children {
            match c.tag.as_str() {
                "integrator" => {
                    if integrator.is_some() {
                        return Err(SceneError::at(&c.loc, "the scene has more than one <integrator>"));
                    }
                    integrator = Some(self.integrator(c)?);
                }
                "sensor" => {
                    if sensor.is_some() {
                        return Err(SceneError::at(&c.loc, "the scene has more than one <sensor> (one is supported)"));
                    }
                    sensor = Some(c.clone());
                }
                "shape" => self.shape(c, &Transform::IDENTITY)?,
                "emitter" => self.emitter(c)?,
                "bsdf" => {
                    self.bsdf_index(c)?;
                }
                "texture" => {
                    self.texture_obj(c)?;
                }
                "medium" => {
                    self.medium_index(c)?;
                }
                "phase" => return Err(c.error("a <phase> must be nested in a <medium>")),
                other => {
                    return Err(SceneError::at(
                        &c.loc,
                        format!("a <{other}> must be nested in a <sensor>, not placed directly in the <scene>"),
                    ))
                }
            }
        }
        let sensor = sensor.ok_or_else(|| SceneError::at(&root.loc, "the scene has no <sensor> (camera)"))?;
        let SensorSettings { camera, spp, sampler, seed, filter, window, alpha } = self.sensor(&sensor)?;
        self.sb.set_camera(camera);
        let mut scene =
            self.sb.build().map_err(|e| SceneError::at(&root.loc, format!("cannot build the scene: {e}")))?;
        if self.light_sampler != LightSamplerKind::default() {
            scene
                .set_light_sampler(self.light_sampler)
                .map_err(|e| SceneError::at(&root.loc, format!("cannot build the light sampler: {e}")))?;
        }
        let mut warnings = Vec::new();
        root.unused_warnings(&mut warnings, &mut Vec::new());
        Ok(SceneFile {
            scene,
            integrator: integrator.unwrap_or_default(),
            spp,
            sampler,
            seed,
            filter,
            window,
            alpha,
            warnings,
        })
    }

    fn integrator(&mut self, o: &Obj) -> Result<AnyIntegrator> {
        o.built.set(true);
        o.check_children(&[])?;
        if matches!(o.ty.as_str(), "path" | "volpath" | "direct") {
            self.light_sampler =
                o.choice("light_sampler", &LightSamplerKind::names())?.parse().map_err(|e: String| o.error(e))?;
        }
        match o.ty.as_str() {
            "path" | "ptracer" | "volpath" => {
                let settings =
                    PathSettings::new(o.int("max_depth", -1)?, o.int("rr_depth", 5)?, o.bool("hide_emitters", false)?)
                        .map_err(|(name, message)| o.error_at(name, message))?;
                Ok(match o.ty.as_str() {
                    "path" => AnyIntegrator::Path(PathIntegrator { settings, ..Default::default() }),
                    "volpath" => AnyIntegrator::VolPath(VolPathIntegrator { settings }),
                    _ => AnyIntegrator::Ptracer(LightTracer { settings }),
                })
            }
            "radiosity" => {
                let d = radiosity::Options::default();
                let patch_size =
                    o.float_checked("patch_size", d.patch_size, |v| v > 0.0 && v.is_finite(), "a positive length")?;
                let rays = o.int("rays_per_patch", d.rays_per_patch as i64)?;
                if !(1..=1 << 24).contains(&rays) {
                    return Err(
                        o.error_at("rays_per_patch", format!("rays_per_patch must be between 1 and 2^24, got {rays}"))
                    );
                }
                let tolerance =
                    o.float_checked("tolerance", d.tolerance as f32, |v| v > 0.0 && v < 1.0, "a number in (0, 1)")?;
                let max_iterations = o.int("max_iterations", d.max_iterations as i64)?;
                if !(1..=1_000_000).contains(&max_iterations) {
                    return Err(o.error_at(
                        "max_iterations",
                        format!("max_iterations must be between 1 and 10⁶, got {max_iterations}"),
                    ));
                }
                let method = match o.choice("method", &["gauss_seidel", "jacobi", "shooting"])?.as_str() {
                    "jacobi" => radiosity::Method::Jacobi,
                    "shooting" => radiosity::Method::Shooting,
                    _ => radiosity::Method::GaussSeidel,
                };
                Ok(AnyIntegrator::Radiosity(radiosity::Options {
                    patch_size,
                    rays_per_patch: rays as u32,
                    method,
                    tolerance: tolerance as f64,
                    max_iterations: max_iterations as usize,
                    smooth: o.bool("smooth", false)?,
                    seed: o.int("seed", 0)?.max(0) as u64,
                }))
            }
            "direct" => {
                let count = |name: &str, default: i64| -> Result<u32> {
                    let v = o.int(name, default)?;
                    if (0..=1024).contains(&v) {
                        Ok(v as u32)
                    } else {
                        Err(o.error_at(name, format!("'{name}' must be between 0 and 1024, got {v}")))
                    }
                };
                let shading = count("shading_samples", 1)?;
                let d = DirectIntegrator {
                    emitter_samples: count("emitter_samples", shading as i64)?,
                    bsdf_samples: count("bsdf_samples", shading as i64)?,
                    hide_emitters: o.bool("hide_emitters", false)?,
                };
                if d.emitter_samples + d.bsdf_samples == 0 {
                    return Err(o.error("needs at least one emitter or BSDF sample"));
                }
                Ok(AnyIntegrator::Direct(d))
            }
            _ => Err(unknown(o, INTEGRATORS)),
        }
    }

    fn sensor(&mut self, o: &Obj) -> Result<SensorSettings> {
        o.built.set(true);
        o.check_children(&["film", "sampler", "medium"])?;
        let media = o.nested("medium");
        if media.len() > 1 {
            return Err(SceneError::at(&media[1].loc, "a sensor sits in one <medium>"));
        }
        if let Some(m) = media.first() {
            let i = self.medium_index(m)?;
            self.sb.set_camera_medium(Some(i));
        }
        if !matches!(o.ty.as_str(), "perspective" | "thinlens") {
            return Err(unknown(o, &["perspective", "thinlens"]));
        }
        // Film.
        let films = o.nested("film");
        let film = films.first();
        let (mut width, mut height, mut filter, mut window) = (768u32, 576u32, Filter::gaussian(0.5).unwrap(), None);
        let mut alpha = false;
        if let Some(f) = film {
            f.built.set(true);
            f.check_children(&["rfilter"])?;
            if f.ty != "hdrfilm" {
                return Err(unknown(f, &["hdrfilm"]));
            }
            let dim = |name: &str, default: i64| -> Result<u32> {
                let v = f.int(name, default)?;
                if (1..=16384).contains(&v) {
                    Ok(v as u32)
                } else {
                    Err(f.error_at(name, format!("'{name}' must be between 1 and 16384, got {v}")))
                }
            };
            width = dim("width", 768)?;
            height = dim("height", 576)?;
            if (width as u64) * (height as u64) > 1 << 26 {
                return Err(f.error(format!("film {width}x{height} is too large (at most 67 million pixels)")));
            }
            alpha = f.choice("pixel_format", &["rgb", "rgba"])? == "rgba";
            f.choice("component_format", &["float16", "float32", "uint32"])?;
            f.choice("file_format", &["openexr", "pfm", "png"])?;
            f.bool("sample_border", false)?;
            if f.has("crop_width") || f.has("crop_height") || f.has("crop_offset_x") || f.has("crop_offset_y") {
                let ox = f.int("crop_offset_x", 0)?;
                let oy = f.int("crop_offset_y", 0)?;
                let cw = f.int("crop_width", width as i64 - ox)?;
                let ch = f.int("crop_height", height as i64 - oy)?;
                if ox < 0 || oy < 0 || cw < 1 || ch < 1 || ox + cw > width as i64 || oy + ch > height as i64 {
                    return Err(f.error(format!(
                        "crop window {cw}x{ch} at ({ox}, {oy}) does not fit in the {width}x{height} film"
                    )));
                }
                window = Some([ox as u32, oy as u32, cw as u32, ch as u32]);
            }
            let filters = f.nested("rfilter");
            if filters.len() > 1 {
                return Err(SceneError::at(&filters[1].loc, "the film has more than one <rfilter>"));
            }
            if let Some(r) = filters.first() {
                r.built.set(true);
                filter = match r.ty.as_str() {
                    "box" => Filter::Box,
                    "tent" => {
                        let radius = r.float("radius", 1.0)?;
                        Filter::tent(radius)
                            .ok_or_else(|| r.error_at("radius", "radius must be positive and at most 16.5 pixels"))?
                    }
                    "gaussian" => {
                        let s = r.float("stddev", 0.5)?;
                        Filter::gaussian(s).ok_or_else(|| {
                            r.error_at("stddev", "stddev must be positive and at most 4.125 pixels (radius 4 stddev)")
                        })?
                    }
                    _ => return Err(unknown(r, FILTERS)),
                };
            }
        }
        // Sampler.
        let (mut spp, mut kind, mut seed) = (4u32, SamplerKind::Independent, 0u64);
        if let Some(s) = o.nested("sampler").first() {
            s.built.set(true);
            kind = match s.ty.as_str() {
                "independent" => SamplerKind::Independent,
                "stratified" | "multijitter" | "orthogonal" => {
                    s.bool("jitter", true)?;
                    SamplerKind::Stratified
                }
                "ldsampler" => SamplerKind::Sobol,
                _ => return Err(unknown(s, SAMPLERS)),
            };
            let n = s.int("sample_count", 4)?;
            if !(1..=1 << 24).contains(&n) {
                return Err(s.error_at("sample_count", format!("sample_count must be between 1 and 2^24, got {n}")));
            }
            spp = n as u32;
            let sd = s.int("seed", 0)?;
            seed = sd as u64;
        }
        // Camera.
        let to_world = o.transform("to_world")?;
        let (fov, axis) = match (o.float_opt("fov")?, o.get("focal_length")) {
            (Some(_), Some(p)) => {
                return Err(SceneError::at(&p.loc, "give either 'fov' or 'focal_length', not both"));
            }
            (Some(fov), None) => {
                let axis = match o.choice("fov_axis", &["x", "y", "diagonal", "smaller", "larger"])?.as_str() {
                    "x" => FovAxis::X,
                    "y" => FovAxis::Y,
                    "diagonal" => FovAxis::Diagonal,
                    "smaller" => FovAxis::Smaller,
                    _ => FovAxis::Larger,
                };
                (fov, axis)
            }
            (None, p) => {
                // Mitsuba: a 35 mm focal length gives the diagonal field of view of a 36 × 24 mm frame.
                let mm = match p.map(|p| &p.value) {
                    None => 50.0,
                    Some(Value::String(s)) => {
                        s.trim().trim_end_matches("mm").trim().parse::<f32>().ok().filter(|f| *f > 0.0).ok_or_else(
                            || o.error_at("focal_length", format!("focal_length must be like \"50mm\", got {s:?}")),
                        )?
                    }
                    Some(Value::Float(f)) if *f > 0.0 => *f as f32,
                    Some(_) => return Err(o.error_at("focal_length", "focal_length must be a string like \"50mm\"")),
                };
                (2.0 * ((36.0f32.hypot(24.0)) / (2.0 * mm)).atan().to_degrees(), FovAxis::Diagonal)
            }
        };
        let mut camera = Camera::perspective(to_world, fov, axis, width, height).map_err(|e| o.error_at("fov", e))?;
        let near = o.float("near_clip", 0.01)?;
        let far = o.float("far_clip", 10000.0)?;
        camera = camera.with_clip(near, far).map_err(|e| o.error_at("near_clip", e))?;
        if o.ty == "thinlens" {
            let r = o.float_opt("aperture_radius")?.ok_or_else(|| o.error("'aperture_radius' is required"))?;
            let d = o.float_opt("focus_distance")?.ok_or_else(|| o.error("'focus_distance' is required"))?;
            camera = camera.with_thin_lens(r, d).map_err(|e| o.error_at("aperture_radius", e))?;
        }
        Ok(SensorSettings { camera, spp, sampler: kind, seed, filter, window, alpha })
    }

    // ---------------------------------------------------------------- shapes

    /// Adds the shape `o`, placed by `outer` after its own `to_world` (instances).
    fn shape(&mut self, o: &Rc<Obj>, outer: &Transform) -> Result<()> {
        o.built.set(true);
        match o.ty.as_str() {
            "shapegroup" => {
                // Its shapes appear through instances only.
                o.check_children(&["shape"])?;
                return Ok(());
            }
            "instance" => {
                o.check_children(&["shape"])?;
                let groups: Vec<_> = o.children.iter().filter(|c| c.ty == "shapegroup").collect();
                let [group] = groups[..] else {
                    return Err(o.error("an instance needs exactly one <ref> to a shapegroup"));
                };
                group.built.set(true);
                let t = *outer * o.transform("to_world")?;
                for s in group.children.iter().filter(|c| c.tag == "shape") {
                    if s.ty == "shapegroup" || s.ty == "instance" {
                        return Err(SceneError::at(&s.loc, "shapegroups cannot contain shapegroups or instances"));
                    }
                    self.shape(s, &t)?;
                }
                return Ok(());
            }
            _ => {}
        }
        o.check_children(&["bsdf", "emitter"])?;
        let interior = o.object_opt("interior", "medium")?.map(|m| self.medium_index(&m)).transpose()?;
        let exterior = o.object_opt("exterior", "medium")?.map(|m| self.medium_index(&m)).transpose()?;
        let to_world = *outer * o.transform("to_world")?;
        let flip = o.bool("flip_normals", false)?;
        let geometry = match o.ty.as_str() {
            "obj" | "ply" => {
                let name = o.string("filename")?;
                let path = resolve(&o.loc, &name);
                let mut mesh = crate::load::load_mesh(&path).map_err(|e| o.error_at("filename", e))?;
                if o.bool("face_normals", false)? {
                    mesh.normals.clear();
                }
                if o.ty == "obj" && o.bool("flip_tex_coords", true)? {
                    for uv in &mut mesh.uvs {
                        uv.y = 1.0 - uv.y;
                    }
                }
                mesh.transform(&to_world);
                mesh.flip_normals ^= flip;
                Geometry::Mesh(mesh)
            }
            "rectangle" | "cube" => {
                let mut mesh = if o.ty == "cube" { TriangleMesh::cube() } else { TriangleMesh::rectangle() };
                mesh.transform(&to_world);
                mesh.flip_normals ^= flip;
                Geometry::Mesh(mesh)
            }
            "disk" => Geometry::Disk(
                Disk::new(to_world, flip).ok_or_else(|| o.error_at("to_world", "the transform flattens the disk"))?,
            ),
            "sphere" => {
                let center = o.point_opt("center")?.unwrap_or(Vec3::ZERO);
                let radius = o.float_checked("radius", 1.0, |r| r > 0.0 && r.is_finite(), "positive")?;
                let t = to_world * Transform::translate(center) * Transform::scale(Vec3::splat(radius)).expect("r > 0");
                let (c, r) = similarity(&t).ok_or_else(|| {
                    o.error_at("to_world", "a sphere's to_world may only translate, rotate and scale uniformly")
                })?;
                Geometry::Sphere(Sphere { center: c, radius: r, flip })
            }
            "cylinder" => {
                let p0 = o.point_opt("p0")?.unwrap_or(Vec3::ZERO);
                let p1 = o.point_opt("p1")?.unwrap_or(Vec3::Z);
                let radius = o.float_checked("radius", 1.0, |r| r > 0.0 && r.is_finite(), "positive")?;
                Geometry::Cylinder(Cylinder::new(p0, p1, radius, to_world, flip).ok_or_else(|| {
                    o.error_at(
                        "to_world",
                        "degenerate cylinder (p0 = p1), or a to_world that does not scale uniformly across the axis",
                    )
                })?)
            }
            _ => return Err(unknown(o, SHAPES)),
        };
        let emitters = o.nested("emitter");
        if emitters.len() > 1 {
            return Err(SceneError::at(&emitters[1].loc, "a shape takes one <emitter>"));
        }
        let emission = match emitters.first() {
            None => None,
            Some(e) if e.ty == "area" => {
                e.built.set(true);
                e.check_children(&[])?;
                Some(e.rgb("radiance", Rgb::ONE, SpectrumKind::Illuminant)?)
            }
            Some(e) => return Err(e.error("only an 'area' emitter can be attached to a shape")),
        };
        // BSDF: nested or referenced. Mitsuba's default is diffuse with reflectance 0.5, except on
        // emitters, which are black (they only emit).
        let bsdfs = o.nested("bsdf");
        if bsdfs.len() > 1 {
            return Err(SceneError::at(&bsdfs[1].loc, "a shape takes one <bsdf>"));
        }
        let bsdf = match bsdfs.first() {
            Some(b) => self.bsdf_index(b)?,
            None => {
                let black = emission.is_some();
                match self.default_bsdf[usize::from(black)] {
                    Some(i) => i,
                    None => {
                        let albedo = if black { 0.0 } else { 0.5 };
                        let i = self.sb.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(albedo))));
                        self.default_bsdf[usize::from(black)] = Some(i);
                        i
                    }
                }
            }
        };
        let index = self.sb.add_shape(geometry, bsdf, emission);
        self.sb.set_shape_media(index, interior, exterior);
        Ok(())
    }

    // ---------------------------------------------------------------- media

    /// Mitsuba's `homogeneous` medium: `sigma_t` (m⁻¹, default 1) × `scale` (default 1),
    /// `albedo` (default 0.75), and a nested `<phase>` (`isotropic`, the default, or `hg` with
    /// `g`, default 0.8).
    fn medium_index(&mut self, o: &Rc<Obj>) -> Result<u32> {
        let key = Rc::as_ptr(o);
        if let Some(&i) = self.medium_index.get(&key) {
            return Ok(i);
        }
        o.built.set(true);
        o.check_children(&["phase"])?;
        if o.ty != "homogeneous" {
            return Err(unknown(o, &["homogeneous"]));
        }
        let scale = o.float_checked("scale", 1.0, |s| s >= 0.0 && s.is_finite(), "a non-negative number")?;
        let sigma_t = o.rgb("sigma_t", Rgb::ONE, SpectrumKind::Illuminant)? * scale;
        if !(0..3).all(|c| sigma_t[c] >= 0.0 && sigma_t[c].is_finite()) {
            return Err(o.error_at("sigma_t", format!("sigma_t must be non-negative, got {sigma_t}")));
        }
        let albedo = o.rgb("albedo", Rgb::splat(0.75), SpectrumKind::Reflectance)?;
        if !(0..3).all(|c| (0.0..=1.0).contains(&albedo[c])) {
            return Err(o.error_at("albedo", format!("albedo must lie in [0, 1], got {albedo}")));
        }
        let phases = o.nested("phase");
        if phases.len() > 1 {
            return Err(SceneError::at(&phases[1].loc, "a medium takes one <phase>"));
        }
        let phase = match phases.first() {
            None => PhaseFunction::Isotropic,
            Some(p) => {
                p.built.set(true);
                p.check_children(&[])?;
                match p.ty.as_str() {
                    "isotropic" => PhaseFunction::Isotropic,
                    "hg" => {
                        let g = p.float_checked("g", 0.8, |g| g > -1.0 && g < 1.0, "a number in (-1, 1)")?;
                        PhaseFunction::HenyeyGreenstein { g }
                    }
                    _ => return Err(unknown(p, &["isotropic", "hg"])),
                }
            }
        };
        let medium = Medium::new(sigma_t, albedo, phase).ok_or_else(|| o.error("invalid medium parameters"))?;
        let i = self.sb.add_medium(medium);
        self.medium_index.insert(key, i);
        Ok(i)
    }

    // ---------------------------------------------------------------- BSDFs

    fn bsdf_index(&mut self, o: &Rc<Obj>) -> Result<u32> {
        let key = Rc::as_ptr(o);
        if let Some(&i) = self.bsdf_index.get(&key) {
            return Ok(i);
        }
        let b = self.bsdf(o)?;
        let i = self.sb.add_bsdf(b);
        self.bsdf_index.insert(key, i);
        Ok(i)
    }

    fn ior(&self, o: &Obj, name: &str, default: f32) -> Result<f32> {
        let v = match o.get(name).map(|p| &p.value) {
            None => default,
            Some(Value::Float(f)) => *f as f32,
            Some(Value::Integer(i)) => *i as f32,
            Some(Value::String(s)) => lookup_ior(s).ok_or_else(|| {
                let names = crate::material::fresnel::NAMED_IORS.iter().map(|n| n.0);
                let hint = nearest(s, names).map(|n| format!(" (did you mean '{n}'?)")).unwrap_or_default();
                o.error_at(name, format!("unknown index of refraction '{s}'{hint}"))
            })?,
            Some(_) => return Err(o.error_at(name, format!("'{name}' must be a number or a material name"))),
        };
        if !(v > 0.0 && v.is_finite()) {
            return Err(o.error_at(name, format!("'{name}' must be positive, got {v}")));
        }
        Ok(v)
    }

    /// Relative IOR `int_ior / ext_ior` with Mitsuba's defaults (`default_int`, air outside).
    fn eta(&self, o: &Obj, default_int: f32) -> Result<f32> {
        Ok(self.ior(o, "int_ior", default_int)? / self.ior(o, "ext_ior", 1.000277)?)
    }

    fn microfacet(&self, o: &Obj, anisotropic: bool) -> Result<Microfacet> {
        let kind = match o.choice("distribution", &["beckmann", "ggx", "phong"])?.as_str() {
            "beckmann" => MicrofacetType::Beckmann,
            "ggx" => MicrofacetType::Ggx,
            _ => {
                // Blinn–Phong (Mitsuba 0.6's "phong"): exponent given, or from alpha by n = 2/α² - 2.
                let n = match o.float_opt("exponent")? {
                    Some(n) => n,
                    None => {
                        let a = o.float_checked("alpha", 0.1, |a| a > 0.0, "positive")?;
                        2.0 / (a * a) - 2.0
                    }
                };
                if !(n >= 0.0 && n.is_finite()) {
                    return Err(o.error_at("exponent", format!("the Phong exponent must be ≥ 0, got {n}")));
                }
                return Ok(Microfacet::blinn_phong(n));
            }
        };
        let rough = |name: &str, default: f32| o.float_checked(name, default, |a| a >= 0.0 && a.is_finite(), "≥ 0");
        let (au, av) = if anisotropic && (o.has("alpha_u") || o.has("alpha_v")) {
            if o.has("alpha") {
                return Err(o.error_at("alpha", "give either 'alpha' or 'alpha_u'/'alpha_v'"));
            }
            (rough("alpha_u", 0.1)?, rough("alpha_v", 0.1)?)
        } else {
            let a = rough("alpha", 0.1)?;
            (a, a)
        };
        o.bool("sample_visible", true)?;
        Ok(Microfacet::new(kind, au, av))
    }

    fn conductor_ior(&self, o: &Obj) -> Result<Option<ConductorIor>> {
        if o.has("eta") || o.has("k") {
            if o.has("material") {
                return Err(o.error_at("material", "give either 'material' or 'eta'/'k'"));
            }
            let eta = o.rgb("eta", Rgb::ZERO, SpectrumKind::Reflectance)?;
            let k = o.rgb("k", Rgb::ONE, SpectrumKind::Reflectance)?;
            return Ok(Some(ConductorIor { eta, k }));
        }
        let name = o.string_opt("material")?.unwrap_or_else(|| "none".into());
        named_conductor(&name).ok_or_else(|| {
            let hint = nearest(&name, conductor_names()).map(|n| format!(" (did you mean '{n}'?)")).unwrap_or_default();
            o.error_at("material", format!("unknown conductor material '{name}'{hint}"))
        })
    }

    fn nested_bsdfs(&mut self, o: &Obj, range: std::ops::RangeInclusive<usize>) -> Result<Vec<Bsdf>> {
        let nested = o.nested("bsdf");
        if !range.contains(&nested.len()) {
            return Err(o.error(format!(
                "expects {} nested <bsdf>, found {}",
                if range.start() == range.end() {
                    range.start().to_string()
                } else {
                    format!("{} or {}", range.start(), range.end())
                },
                nested.len()
            )));
        }
        nested.iter().map(|b| self.bsdf(b)).collect()
    }

    fn bsdf(&mut self, o: &Rc<Obj>) -> Result<Bsdf> {
        o.built.set(true);
        o.check_children(&["bsdf", "texture"])?;
        let refl = SpectrumKind::Reflectance;
        let spec_r = |o: &Obj| o.rgb("specular_reflectance", Rgb::ONE, refl);
        Ok(match o.ty.as_str() {
            "diffuse" => {
                let reflectance = self.texture(o, "reflectance", Rgb::splat(0.5))?;
                Bsdf::Diffuse(Diffuse { reflectance })
            }
            "conductor" => Bsdf::Conductor(Conductor { ior: self.conductor_ior(o)?, specular_reflectance: spec_r(o)? }),
            "roughconductor" => Bsdf::RoughConductor(RoughConductor {
                distribution: self.microfacet(o, true)?,
                ior: self.conductor_ior(o)?,
                specular_reflectance: spec_r(o)?,
            }),
            "dielectric" | "thindielectric" | "roughdielectric" => {
                let eta = self.eta(o, 1.5046)?;
                let specular_reflectance = spec_r(o)?;
                let specular_transmittance = o.rgb("specular_transmittance", Rgb::ONE, refl)?;
                match o.ty.as_str() {
                    "dielectric" => Bsdf::Dielectric(Dielectric { eta, specular_reflectance, specular_transmittance }),
                    "thindielectric" => {
                        Bsdf::ThinDielectric(ThinDielectric { eta, specular_reflectance, specular_transmittance })
                    }
                    _ => Bsdf::RoughDielectric(RoughDielectric {
                        distribution: self.microfacet(o, true)?,
                        eta,
                        specular_reflectance,
                        specular_transmittance,
                    }),
                }
            }
            "plastic" | "roughplastic" => {
                let diffuse = o.rgb("diffuse_reflectance", Rgb::splat(0.5), refl)?;
                let eta = self.eta(o, 1.49)?;
                let nonlinear = o.bool("nonlinear", false)?;
                if o.ty == "plastic" {
                    Bsdf::Plastic(Plastic::new(diffuse, spec_r(o)?, eta, nonlinear))
                } else {
                    Bsdf::RoughPlastic(RoughPlastic::new(
                        self.microfacet(o, false)?,
                        diffuse,
                        spec_r(o)?,
                        eta,
                        nonlinear,
                    ))
                }
            }
            "twosided" => {
                let mut b = self.nested_bsdfs(o, 1..=2)?;
                let back = if b.len() == 2 { b.pop().expect("two") } else { b[0].clone() };
                Bsdf::TwoSided(Box::new([b.pop().expect("one"), back]))
            }
            "blendbsdf" => {
                let weight = self.texture(o, "weight", Rgb::splat(0.5))?;
                let b = self.nested_bsdfs(o, 2..=2)?;
                let [a, c]: [Bsdf; 2] = b.try_into().expect("two");
                Bsdf::Blend { weight, bsdfs: Box::new([a, c]) }
            }
            "null" => Bsdf::Null,
            "mask" => {
                let opacity = self.texture(o, "opacity", Rgb::splat(0.5))?;
                let mut b = self.nested_bsdfs(o, 1..=1)?;
                Bsdf::Mask { opacity, bsdf: Box::new(b.pop().expect("one")) }
            }
            _ => return Err(unknown(o, BSDFS)),
        })
    }

    // ---------------------------------------------------------------- textures

    /// A texturable parameter: a nested/referenced `<texture>`, or a constant colour.
    fn texture(&mut self, o: &Obj, name: &str, default: Rgb) -> Result<Texture> {
        if let Some(t) = o.object_opt(name, "texture").ok().flatten() {
            return self.texture_obj(&t);
        }
        let c = o.rgb(name, default, SpectrumKind::Reflectance)?;
        Ok(Texture::Constant(c))
    }

    fn to_uv(o: &Obj) -> Result<Mat3> {
        let m = *o.transform("to_uv")?.matrix();
        Ok(Mat3::from_cols(
            Vec3::new(m.x_axis.x, m.x_axis.y, 0.0),
            Vec3::new(m.y_axis.x, m.y_axis.y, 0.0),
            Vec3::new(m.w_axis.x, m.w_axis.y, 1.0),
        ))
    }

    fn texture_obj(&mut self, o: &Obj) -> Result<Texture> {
        o.built.set(true);
        o.check_children(&[])?;
        let refl = SpectrumKind::Reflectance;
        match o.ty.as_str() {
            "bitmap" => {
                let name = o.string("filename")?;
                let raw = o.bool("raw", false)?;
                let path = resolve(&o.loc, &name);
                let image = self.image(&path, raw).map_err(|e| o.error_at("filename", e))?;
                let filter = match o.choice("filter_type", &["bilinear", "nearest"])?.as_str() {
                    "bilinear" => TexFilter::Bilinear,
                    _ => TexFilter::Nearest,
                };
                let wrap = match o.choice("wrap_mode", &["repeat", "mirror", "clamp"])?.as_str() {
                    "repeat" => Wrap::Repeat,
                    "mirror" => Wrap::Mirror,
                    _ => Wrap::Clamp,
                };
                Ok(Texture::Bitmap { bitmap: Bitmap { image, filter, wrap }, to_uv: Self::to_uv(o)? })
            }
            "checkerboard" => Ok(Texture::Checkerboard {
                color0: o.rgb("color0", Rgb::splat(0.4), refl)?,
                color1: o.rgb("color1", Rgb::splat(0.2), refl)?,
                to_uv: Self::to_uv(o)?,
            }),
            _ => Err(unknown(o, TEXTURES)),
        }
    }

    fn image(&mut self, path: &std::path::Path, raw: bool) -> std::result::Result<Arc<Image>, String> {
        let key = (path.to_path_buf(), raw);
        if let Some(i) = self.images.get(&key) {
            return Ok(i.clone());
        }
        let img = Arc::new(load_image(path, raw)?);
        self.images.insert(key, img.clone());
        Ok(img)
    }

    // ---------------------------------------------------------------- emitters

    fn emitter(&mut self, o: &Obj) -> Result<()> {
        o.built.set(true);
        o.check_children(&["texture"])?;
        let illum = SpectrumKind::Illuminant;
        let to_world = o.transform("to_world")?;
        let light = match o.ty.as_str() {
            "point" => {
                let position = match o.point_opt("position")? {
                    Some(p) => {
                        if o.has("to_world") {
                            return Err(o.error_at("position", "give either 'position' or 'to_world'"));
                        }
                        p
                    }
                    None => to_world.apply_point(Vec3::ZERO),
                };
                Light::Point { position, intensity: o.rgb("intensity", Rgb::ONE, illum)? }
            }
            "spot" => {
                let cutoff = o.float_checked("cutoff_angle", 20.0, |c| c > 0.0 && c <= 180.0, "in (0, 180] degrees")?;
                let beam =
                    o.float_checked("beam_width", cutoff * 0.75, |b| b >= 0.0 && b <= cutoff, "in [0, cutoff_angle]")?;
                let axis = to_world.apply_vector(Vec3::Z).normalize();
                Light::Spot {
                    position: to_world.apply_point(Vec3::ZERO),
                    frame: Frame::from_z(axis),
                    intensity: o.rgb("intensity", Rgb::ONE, illum)?,
                    cutoff: cutoff.to_radians(),
                    beam: beam.to_radians(),
                }
            }
            "directional" => {
                let d = match o.point_opt("direction")? {
                    Some(d) => d,
                    None => to_world.apply_vector(Vec3::Z),
                };
                if !(d.length() > 0.0 && d.is_finite()) {
                    return Err(o.error_at("direction", "the direction must be a non-zero vector"));
                }
                Light::Directional {
                    direction: d.normalize(),
                    irradiance: o.rgb("irradiance", Rgb::ONE, illum)?,
                    center: Vec3::ZERO,
                    radius: 0.0,
                }
            }
            "constant" => {
                Light::Constant { radiance: o.rgb("radiance", Rgb::ONE, illum)?, center: Vec3::ZERO, radius: 0.0 }
            }
            "envmap" => {
                let name = o.string("filename")?;
                let path = resolve(&o.loc, &name);
                let image = load_image(&path, false).map_err(|e| o.error_at("filename", e))?;
                let scale = o.float("scale", 1.0)?;
                let map = EnvMap::new(image, scale, to_world).map_err(|e| o.error(e))?;
                Light::EnvMap { map: Box::new(map), center: Vec3::ZERO, radius: 0.0 }
            }
            "area" => return Err(o.error("an area emitter must be nested in the <shape> that emits")),
            _ => return Err(unknown(o, EMITTERS)),
        };
        self.sb.add_light(light);
        Ok(())
    }
}

/// Centre and radius of the unit sphere under `t`, if `t` is a similarity (uniform scale).
fn similarity(t: &Transform) -> Option<(Vec3, f32)> {
    let cols = [t.apply_vector(Vec3::X), t.apply_vector(Vec3::Y), t.apply_vector(Vec3::Z)];
    let r = cols[0].length();
    let uniform = cols.iter().all(|c| (c.length() - r).abs() <= 1e-4 * r);
    let orthogonal = (cols[0].dot(cols[1])).abs() <= 1e-4 * r * r
        && (cols[0].dot(cols[2])).abs() <= 1e-4 * r * r
        && (cols[1].dot(cols[2])).abs() <= 1e-4 * r * r;
    (uniform && orthogonal && r > 0.0).then(|| (t.apply_point(Vec3::ZERO), r))
}
