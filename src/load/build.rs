//! Scene assembly from properties, shared by every scene format: a format's loader maps its
//! syntax to a tree of located objects ([`crate::props::Obj`], Mitsuba's plugin names and
//! parameters), and this builds the scene from it.
//!
//! The scene's structure, from the parsed objects: which objects are built and where they go
//! (shapes with their BSDF, area emitter and media; ids shared by reference; shapegroups and
//! instances; the default BSDFs), and the loader's services to plugins (textures, nested BSDFs,
//! image and mesh files). Each plugin builds itself from its properties (`from_props` beside it)
//! and is found by name in its layer's registry (`BSDF_PLUGINS`, `TEXTURE_PLUGINS`,
//! `EMITTER_PLUGINS`, `SHAPE_PLUGINS`, `MEDIUM_PLUGINS`, `INTEGRATOR_PLUGINS`), so that every
//! scene format shares them.

use super::SceneFile;
use crate::camera::{look_along, require_one_pixel, Camera, DistantTarget};
use crate::choice::Choice;
use crate::film::FilmSettings;
use crate::geometry::{shape_plugin, Geometry, MeshFile, MeshSource, SHAPE_PLUGINS};
use crate::image::{GridVolume, Image, ImageSource, VolumeSource};
use crate::integrator::{integrator_from_props, AnyIntegrator};
use crate::light::LightSamplerKind;
use crate::math::AnimatedTransform;
use crate::light::{area_opacity_from_props, area_radiance_from_props, emitter_plugin, ShapeEmission, EMITTER_PLUGINS};
use crate::load::image::load_image;
use crate::load::memory::MemoryFiles;
use crate::load::FileResolver;
use crate::material::{bsdf_plugin, Bsdf, BsdfBuilder, Diffuse, BSDF_PLUGINS};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Rgb, Transform, Vec3};
use crate::medium::MEDIUM_PLUGINS;
use crate::props::SceneError;
use crate::props::{Obj, Value};
use crate::sampling::sampler::{SamplerKind, SamplerSettings};
use crate::scene::SceneBuilder;
use crate::texture::{texture_plugin, Texture, TextureAttributes, TextureSource, TEXTURE_PLUGINS};
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::Arc;

type Result<T> = std::result::Result<T, SceneError>;

/// What the sensor with its film and sampler asks for.
struct SensorSettings {
    camera: Camera,
    spp: u32,
    sampler: SamplerKind,
    seed: u64,
    film: FilmSettings,
}

/// Builds the scene from the parsed root object.
pub struct Builder {
    sb: SceneBuilder,
    bsdf_index: HashMap<*const Obj, u32>,
    shared_bsdfs: HashMap<*const Obj, Arc<Bsdf>>,
    /// How many BSDF evaluations one evaluation of each built BSDF may make (itself included).
    bsdf_sizes: HashMap<*const Obj, u64>,
    /// Plausible mistakes that change the image (a reflectance above 1), with their position.
    warnings: Vec<String>,
    images: HashMap<(PathBuf, bool), Arc<Image>>,
    volumes: HashMap<PathBuf, Arc<GridVolume>>,
    /// NanoVDB grids read so far, by file and grid name (`None`: the file has no such grid).
    nano_grids: HashMap<(PathBuf, String), Option<Arc<crate::image::nanovdb::NanoGrid>>>,
    tensors: HashMap<PathBuf, Arc<crate::tensor::TensorFile>>,
    /// The default BSDFs (diffuse 0.5 for plain shapes, black for emitters), once created.
    default_bsdf: [Option<u32>; 2],
    medium_index: HashMap<*const Obj, u32>,
    /// The integrator's `light_sampler` (neumann's own parameter; default the light BVH).
    light_sampler: LightSamplerKind,
    /// The integrator's `timeout` (Mitsuba: seconds, ≤ 0 for none).
    time_limit: Option<std::time::Duration>,
    /// Where plugins' relative file names are looked for.
    resolver: FileResolver,
    /// Meshes and images the scene's format decoded itself (glTF's).
    memory: MemoryFiles,
    /// A sensor nested in a shape (an irradiance meter) with that shape's world geometry.
    shape_sensor: Option<(Rc<Obj>, Geometry)>,
    /// The scene's sensor's `shutter_open` and `shutter_close` (0, 0 without one).
    shutter: (f32, f32),
    /// Mesh files read before the build, in parallel ([`Builder::prefetch_meshes`]): per file,
    /// the uses left and what reading it gave.
    prefetched: HashMap<MeshKey, (usize, std::result::Result<MeshFile, crate::load::LoadError>)>,
}

impl Builder {
    /// A builder whose plugins find their files through `resolver`.
    pub fn new(resolver: FileResolver) -> Builder {
        Builder {
            sb: SceneBuilder::new(),
            bsdf_index: HashMap::new(),
            shared_bsdfs: HashMap::new(),
            bsdf_sizes: HashMap::new(),
            warnings: Vec::new(),
            images: HashMap::new(),
            volumes: HashMap::new(),
            nano_grids: HashMap::new(),
            tensors: HashMap::new(),
            default_bsdf: [None; 2],
            medium_index: HashMap::new(),
            light_sampler: LightSamplerKind::default(),
            time_limit: None,
            resolver,
            memory: MemoryFiles::default(),
            shape_sensor: None,
            shutter: (0.0, 0.0),
            prefetched: HashMap::new(),
        }
    }

    /// A builder whose plugins also find the meshes and images in `memory` (by name, before
    /// files on disk).
    pub fn with_memory(resolver: FileResolver, memory: MemoryFiles) -> Builder {
        Builder { memory, ..Builder::new(resolver) }
    }

    /// Builds everything under `root` (a `<scene>`).
    pub fn build(mut self, root: &Obj) -> Result<SceneFile> {
        root.built.set(true);
        self.prefetch_meshes(root);
        // The sensor's shutter (the time of its rays), for the emitters that depend on time.
        if let Some(sensor) = root.children.iter().find(|c| c.tag == "sensor") {
            self.shutter = (sensor.float("shutter_open", 0.0)?, sensor.float("shutter_close", 0.0)?);
        }
        self.sb.set_shutter(self.shutter.0, self.shutter.1);
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
                "shape" => self.shape(c, &Transform::IDENTITY, None)?,
                // An area emitter with an id is attached to the shapes that <ref> it.
                "emitter" if is_shape_emitter(&c.ty) && c.id.is_some() => {}
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
        // An area emitter declared apart must light some shape: dropping it would change the image.
        if let Some(e) = root.children.iter().find(|c| c.tag == "emitter" && is_shape_emitter(&c.ty) && !c.built.get())
        {
            return Err(e.error(format!(
                "no shape references this {} emitter (add <ref id=\"{}\"/> to the shape that emits)",
                e.ty,
                e.id.as_deref().unwrap_or("")
            )));
        }
        let meter = self.shape_sensor.take();
        if let (Some(_), Some((nested, _))) = (&sensor, &meter) {
            return Err(SceneError::at(&nested.loc, "the scene has more than one <sensor> (one is supported)"));
        }
        let (sensor, meter_shape) = match (sensor, meter) {
            (Some(s), None) => (s, None),
            (None, Some((s, shape))) => (s, Some(shape)),
            _ => return Err(SceneError::at(&root.loc, "the scene has no <sensor> (camera)")),
        };
        let SensorSettings { camera, spp, sampler, seed, film } = self.sensor(&sensor, meter_shape.as_ref())?;
        self.sb.set_camera(camera);
        let mut scene =
            self.sb.build().map_err(|e| SceneError::at(&root.loc, format!("cannot build the scene: {e}")))?;
        if self.light_sampler != LightSamplerKind::default() {
            scene
                .set_light_sampler(self.light_sampler)
                .map_err(|e| SceneError::at(&root.loc, format!("cannot build the light sampler: {e}")))?;
        }
        if scene.lights_are_off() {
            self.warnings.push(format!(
                "warning: {}: every emitter of the scene emits nothing: only black can be rendered",
                root.loc.position()
            ));
        }
        // Subsurface scattering is `volpath`'s alone (pbrt-v4's too): elsewhere such surfaces
        // are their dielectric boundary, which changes the image.
        let name = integrator.as_ref().map_or_else(|| AnyIntegrator::default().name(), |i| i.name());
        if name != "volpath" && scene.bsdfs().iter().any(|b| b.subsurface().is_some()) {
            self.warnings.push(format!(
                "warning: {}: the `{name}` integrator renders subsurface materials as their dielectric boundary: only `volpath` renders their subsurface scattering (as in pbrt-v4)",
                root.loc.position(),
            ));
        }
        // Mitsuba 3 rejects parameters that no plugin reads ("unreferenced property"), and so
        // does neumann: such a parameter is a typo or a feature neumann does not implement.
        root.check_unused(&mut Vec::new())?;
        let warnings = std::mem::take(&mut self.warnings);
        Ok(SceneFile {
            scene,
            integrator: integrator.unwrap_or_default(),
            spp,
            sampler,
            seed,
            filter: film.filter,
            window: film.window,
            alpha: film.alpha,
            colors: film.colors,
            component: film.component,
            sample_border: film.sample_border,
            transform: film.transform,
            time_limit: self.time_limit,
            warnings,
        })
    }

    fn integrator(&mut self, o: &Obj) -> Result<AnyIntegrator> {
        if !matches!(o.ty.as_str(), "moment" | "aov") {
            o.check_children(&[])?;
        }
        self.read_loader_params(o, true)?;
        integrator_from_props(o)
    }

    /// What the loader itself reads of an integrator and of those nested in it (`moment`,
    /// `aov`): the `light_sampler` of the integrators that sample lights, the `timeout` of the
    /// `top` one (seconds; the render stops at it or at the sample count, whichever comes
    /// first, as Mitsuba's does; nested integrators' are read and unused, as in Mitsuba), and
    /// Mitsuba's rendering-loop parameters that cannot change the image (`block_size`,
    /// `samples_per_pass`).
    fn read_loader_params(&mut self, o: &Obj, top: bool) -> Result<()> {
        let timeout = o.float_checked("timeout", -1.0, f32::is_finite, "a number of seconds (≤ 0: none)")?;
        if top && timeout > 0.0 {
            self.time_limit = Some(std::time::Duration::from_secs_f32(timeout));
        }
        if o.ty.parse::<crate::integrator::IntegratorKind>().is_ok_and(|k| k.samples_lights()) {
            self.light_sampler =
                o.choice("light_sampler", &LightSamplerKind::names())?.parse().map_err(|e: String| o.error(e))?;
        }
        o.int("block_size", 0)?;
        o.int("samples_per_pass", -1)?;
        for c in o.nested("integrator") {
            self.read_loader_params(&c, false)?;
        }
        Ok(())
    }

    /// The sensor `o`; `meter_shape` is the world geometry of the shape it is nested in (an
    /// irradiance meter's).
    fn sensor(&mut self, o: &Obj, meter_shape: Option<&Geometry>) -> Result<SensorSettings> {
        o.built.set(true);
        if o.ty == "batch" {
            o.check_children(&["film", "sampler", "medium", "sensor"])?;
        } else {
            o.check_children(&["film", "sampler", "medium"])?;
        }
        let media = o.nested("medium");
        if media.len() > 1 {
            return Err(SceneError::at(&media[1].loc, "a sensor sits in one <medium>"));
        }
        if let Some(m) = media.first() {
            let i = self.medium_index(m)?;
            self.sb.set_camera_medium(Some(i));
        }
        let films = o.nested("film");
        let film = match films.first() {
            Some(f) => FilmSettings::from_props(f)?,
            None => FilmSettings::default(),
        };
        let sampler = match o.nested("sampler").first() {
            Some(s) => SamplerSettings::from_props(s)?,
            None => SamplerSettings::default(),
        };
        let camera = match meter_shape {
            Some(shape) => {
                require_one_pixel(o, film.width, film.height)?;
                Camera::irradiancemeter(shape).map_err(|e| o.error(e.to_string()))?
            }
            None if o.ty == "batch" => batch_from_props(o, film.width, film.height)?,
            None if o.ty == "distant" => self.distant_from_props(o, film.width, film.height)?,
            None if o.ty == "realistic" => self.realistic_from_props(o, film.width, film.height)?,
            None => Camera::from_props(o, film.width, film.height)?,
        };
        // neumann's moving camera (pbrt-v4's animated camera transform): `to_world` at
        // `motion_start` (0), `to_world_end` at `motion_end` (1), over the sensor's shutter.
        let camera = match o.get("to_world_end") {
            Some(_) => {
                let end = o.transform("to_world_end")?;
                let (t0, t1) = (o.float("motion_start", 0.0)?, o.float("motion_end", 1.0)?);
                camera.with_motion(end, t0, t1, self.shutter).map_err(|e| o.error_at("to_world_end", e.to_string()))?
            }
            None => camera,
        };
        let SamplerSettings { kind, spp, seed } = sampler;
        Ok(SensorSettings { camera, spp, sampler: kind, seed, film })
    }

    /// neumann's `realistic` sensor, pbrt-v4's realistic camera (see [`crate::camera::realistic`]):
    /// `to_world`, `lens_file` (a lens description: per element its curvature radius, thickness,
    /// index of refraction and aperture diameter in millimetres, front to rear, `#` comments),
    /// `aperture_diameter` (1 mm; clamped to the stop's, with a warning), `focus_distance` (10,
    /// scene units from the film), `film_diagonal` (35 mm), `aperture` (none: a disk; `gaussian`,
    /// `square`, `pentagon`, `star`, or an image file, its colour averaged), `shutter_open`,
    /// `shutter_close`.
    fn realistic_from_props(&mut self, o: &Obj, width: u32, height: u32) -> Result<Camera> {
        use crate::camera::realistic::{parse_lens_file, ApertureImage, BUILTIN_APERTURES};
        let to_world = o.transform("to_world")?;
        crate::camera::check_shutter(o)?;
        let path = self.resolver.resolve(&o.string("lens_file")?);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| o.error_at("lens_file", format!("cannot read the lens file '{}': {e}", path.display())))?;
        let values =
            parse_lens_file(&text).map_err(|e| o.error_at("lens_file", format!("'{}': {e}", path.display())))?;
        let aperture = match o.string_opt("aperture")?.as_deref() {
            None | Some("") => None,
            Some(name) if BUILTIN_APERTURES.contains(&name) => ApertureImage::builtin(name),
            Some(_) => {
                let image = ImageSource::image(self, o, "aperture", false)?;
                Some(ApertureImage::from_image(&image).map_err(|e| o.error_at("aperture", e))?)
            }
        };
        let positive = |v: f32| v > 0.0 && v.is_finite();
        let diameter = o.float_checked("aperture_diameter", 1.0, positive, "a positive diameter (mm)")?;
        let focus = o.float_checked("focus_distance", 10.0, positive, "a positive distance")?;
        let diagonal = o.float_checked("film_diagonal", 35.0, positive, "a positive diagonal (mm)")?;
        let (lens, warning) = crate::camera::LensSystem::new(&values, diameter, focus, diagonal, aperture)
            .map_err(|e| o.error_at("lens_file", e))?;
        if let Some(w) = warning {
            let at = o.props.iter().find(|p| p.name == "aperture_diameter").map_or(&o.loc, |p| &p.loc);
            self.warnings.push(format!("warning: {}: {w}", at.position()));
        }
        Camera::realistic(to_world, lens, width, height).map_err(|e| o.error(e.to_string()))
    }

    /// Mitsuba's `distant` sensor: `direction` or `to_world` (not both; it looks along
    /// `to_world`'s +z), `target` (a `<point>`, or a `<shape name="target">` sampled by area and
    /// not part of the scene; none: the scene's bounding sphere), a 1 × 1 film.
    fn distant_from_props(&mut self, o: &Obj, width: u32, height: u32) -> Result<Camera> {
        require_one_pixel(o, width, height)?;
        let to_world = match o.point_opt("direction")? {
            Some(_) if o.get("to_world").is_some() => {
                return Err(o.error_at("direction", "give 'direction' or 'to_world', not both (as in Mitsuba)"))
            }
            Some(d) => look_along(o, Vec3::ZERO, d)?,
            None => o.transform("to_world")?,
        };
        let target = match o.get("target").map(|p| &p.value) {
            None => DistantTarget::Scene,
            Some(Value::Object(shape)) if shape.tag == "shape" => {
                shape.built.set(true);
                shape.check_children(&[])?;
                DistantTarget::Shape(std::sync::Arc::new(self.geometry(shape, &Transform::IDENTITY, &[])?))
            }
            Some(_) => DistantTarget::Point(o.point_opt("target")?.expect("present")),
        };
        Camera::distant(to_world, target).map_err(|e| o.error_at("target", e.to_string()))
    }

    // ---------------------------------------------------------------- shapes

    /// The world geometry of the shape plugin `o` (`to_world` and `flip_normals` read), placed
    /// by `outer` after its own `to_world`; an unknown type names the shape plugins and `more`.
    fn geometry(&mut self, o: &Obj, outer: &Transform, more: &[&str]) -> Result<Geometry> {
        let to_world = *outer * o.transform("to_world")?;
        self.geometry_placed(o, &to_world, more)
    }

    /// [`Builder::geometry`] placed by `to_world` (the identity for a moving shape's own space).
    fn geometry_placed(&mut self, o: &Obj, to_world: &Transform, more: &[&str]) -> Result<Geometry> {
        let flip = o.bool("flip_normals", false)?;
        let plugin = shape_plugin(&o.ty).ok_or_else(|| {
            let mut names: Vec<&str> = SHAPE_PLUGINS.iter().map(|p| p.0).collect();
            names.extend(more);
            o.unknown_plugin(&names)
        })?;
        let geometry = plugin(o, to_world, flip, self)?;
        check_finite_geometry(o, &geometry)?;
        Ok(geometry)
    }

    /// Adds the shape `o`, placed by `outer` after its own `to_world` (instances); or, in an
    /// instance that moves, placed by its own `to_world` in the instance's space and moved by
    /// `outer_motion` (the instance's transform over the shutter).
    fn shape(&mut self, o: &Rc<Obj>, outer: &Transform, outer_motion: Option<&AnimatedTransform>) -> Result<()> {
        o.built.set(true);
        match o.ty.as_str() {
            "shapegroup" => {
                // Its shapes appear through instances only.
                o.check_children(&["shape"])?;
                return Ok(());
            }
            "merge" => {
                // Mitsuba merges the nested meshes that share a BSDF into one mesh to save
                // memory: the same surfaces, the same image. neumann adds them one by one.
                o.check_children(&["shape"])?;
                for s in o.children.iter().filter(|c| c.tag == "shape") {
                    self.shape(s, outer, outer_motion)?;
                }
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
                // An instance with `to_world_end` moves its shapes (pbrt-v4's animated object
                // instances): each placed in the instance's space by its own `to_world`, the
                // instance's transform interpolated at each ray's time.
                let motion = shape_motion(o, outer)?;
                if let (Some(_), Some(_)) = (&motion, outer_motion) {
                    return Err(o.error_at("to_world_end", "an instance inside a moving instance cannot move"));
                }
                for s in group.children.iter().filter(|c| c.tag == "shape") {
                    if s.ty == "shapegroup" || s.ty == "instance" {
                        return Err(SceneError::at(&s.loc, "shapegroups cannot contain shapegroups or instances"));
                    }
                    self.shape(s, &t, motion.as_ref())?;
                }
                return Ok(());
            }
            _ => {}
        }
        o.check_children(&["bsdf", "emitter", "sensor"])?;
        let interior = o.object_opt("interior", "medium")?.map(|m| self.medium_index(&m)).transpose()?;
        let exterior = o.object_opt("exterior", "medium")?.map(|m| self.medium_index(&m)).transpose()?;
        let more = ["shapegroup", "instance", "merge"];
        // A moving shape's geometry in its own space (or, in a moving instance, in the
        // instance's), placed at each ray's time by `motion`.
        let (motion, own_space) = match (shape_motion(o, outer)?, outer_motion) {
            (Some(_), Some(_)) => {
                return Err(o.error_at("to_world_end", "a shape inside a moving instance cannot move by itself as well"))
            }
            (Some(m), None) => (Some(m), Transform::IDENTITY),
            (None, Some(m)) => (Some(*m), o.transform("to_world")?),
            (None, None) => (None, Transform::IDENTITY),
        };
        // Errors of a moving shape: at its `to_world_end`, or at the shape where the instance
        // it is in moves it.
        let motion_error = |message: String| match outer_motion {
            Some(_) => o.error(format!("{message} (it moves with the instance it is in)")),
            None => o.error_at("to_world_end", message),
        };
        let geometry = match &motion {
            Some(m) => {
                let g = self.geometry_placed(o, &own_space, &more)?;
                let b = match &g {
                    Geometry::Mesh(mesh) => m.motion_bounds(&mesh.positions),
                    // Every other shape is traced in its own space, the ray moved there.
                    _ => {
                        if m.start().swaps_handedness() {
                            return Err(motion_error(format!("a moving {} whose transform mirrors is not implemented", o.ty)));
                        }
                        // A sphere moved by a transform that scales unevenly would be an
                        // ellipsoid, which a sphere at rest is not (Mitsuba's rule keeps it round).
                        let similar = |t: &Transform| {
                            crate::geometry::is_similarity(&[Vec3::X, Vec3::Y, Vec3::Z].map(|a| t.apply_vector(a)))
                        };
                        if matches!(g, Geometry::Sphere(_)) && !(similar(m.start()) && similar(m.end())) {
                            return Err(motion_error(
                                "a moving sphere whose transform scales unevenly or shears (an ellipsoid) is not implemented".into(),
                            ));
                        }
                        let b = g.bounds();
                        m.motion_bounds(&std::array::from_fn::<Vec3, 8, _>(|k| b.corner(k)))
                    }
                };
                // (A mesh without triangles has no bounds, and is nothing: no error.)
                let empty = matches!(&g, Geometry::Mesh(mesh) if mesh.is_empty());
                let finite = b.min.is_finite() && b.max.is_finite();
                if !(empty || finite) {
                    return Err(motion_error("the moving shape's coordinates are not finite over its motion".into()));
                }
                g
            }
            None => self.geometry(o, outer, &more)?,
        };
        let textures = self.texture_attributes(o, &geometry)?;
        for sensor in o.nested("sensor") {
            if motion.is_some() {
                return Err(sensor.error("an irradiancemeter cannot measure a moving shape"));
            }
            if sensor.ty != "irradiancemeter" {
                return Err(sensor.error("only an irradiancemeter can be nested in a <shape> (it measures that shape)"));
            }
            if let Some((first, _)) = &self.shape_sensor {
                let at = if Rc::ptr_eq(first, &sensor) { &o.loc } else { &sensor.loc };
                return Err(SceneError::at(at, "the scene has more than one <sensor> (one is supported)"));
            }
            self.shape_sensor = Some((sensor, geometry.clone()));
        }
        let emitters = o.nested("emitter");
        if emitters.len() > 1 {
            return Err(SceneError::at(&emitters[1].loc, "a shape takes one <emitter>"));
        }
        if let Some(e) = emitters.first().filter(|e| is_shape_emitter(&e.ty)) {
            // Shapes without an area to sample, as their renderers have them.
            let refusal = match geometry {
                Geometry::SdfGrid(_) => Some(("an sdfgrid".to_string(), "Mitsuba: it has")),
                Geometry::LinearCurves(_) | Geometry::BSplineCurves(_) => {
                    Some((format!("a {}", o.ty), "Mitsuba: it has"))
                }
                Geometry::Curves(_) => Some(("curves".to_string(), "pbrt-v4: they have")),
                Geometry::Ellipsoids(_) => Some(("ellipsoids".to_string(), "Mitsuba: they have")),
                Geometry::Cylinder(c) if c.is_elliptic() => {
                    return Err(e.error(format!(
                    "an elliptic cylinder (a to_world that scales unevenly across its axis or shears) cannot be {}: \
                         its area has no closed form and uniform (φ, z) points are not uniform in area (Mitsuba \
                         samples it as if they were, a biased estimate)",
                    emitter_name(&e.ty)
                )))
                }
                // Mitsuba's ellipsoid shells skip the mesh's area table.
                Geometry::Mesh(_) if o.ty == "ellipsoidsmesh" => {
                    Some(("an ellipsoidsmesh".to_string(), "Mitsuba: its shells have"))
                }
                _ => None,
            };
            if let Some((what, source)) = refusal {
                return Err(
                    e.error(format!("{what} cannot be {} (as in {source} no area to sample)", emitter_name(&e.ty)))
                );
            }
        }
        let emission = match emitters.first() {
            None => None,
            Some(e) if e.ty == "directionalarea" => {
                e.built.set(true);
                e.check_children(&[])?;
                read_sampling_weight(e)?;
                let radiance = area_radiance_from_props(e, self)?;
                check_emitted_power(e, &geometry, &radiance, 1.0)?;
                Some(ShapeEmission::DirectionalArea { radiance })
            }
            Some(e) if e.ty == "area" => {
                e.built.set(true);
                e.check_children(&[])?;
                read_sampling_weight(e)?;
                let mut radiance = area_radiance_from_props(e, self)?;
                let two_sided = e.bool("two_sided", false)?;
                let sides = if two_sided { 2.0 } else { 1.0 };
                if let Some(p) = e.float_opt("power")? {
                    // pbrt-v4's `power`: radiance × power / (π · area · sides).
                    let k = std::f32::consts::PI * geometry.area() * sides;
                    match &mut radiance {
                        Texture::Constant(c) if p > 0.0 && p.is_finite() && k > 0.0 => *c *= p / k,
                        Texture::Constant(_) => {
                            return Err(e.error_at(
                                "power",
                                format!("needs a positive power and shape area, got {p} and {}", geometry.area()),
                            ))
                        }
                        // An image (pbrt-v4's image area lights): normalised by the luminance of
                        // its texel average, as pbrt's k_e.
                        t if p > 0.0 && p.is_finite() && k > 0.0 && t.mean_is_exact() => {
                            let lum = crate::math::luminance(t.mean());
                            if lum.is_nan() || lum <= 0.0 {
                                return Err(
                                    e.error_at("power", "the radiance image is black: no power can be given to it")
                                );
                            }
                            let factor = Texture::Constant(Rgb::splat(p / (k * lum)));
                            *t = Texture::Scale(Box::new([t.clone(), factor]));
                        }
                        _ => {
                            return Err(e.error_at(
                                "power",
                                "a power needs a positive number, a shape with area, and a constant or image radiance",
                            ))
                        }
                    }
                }
                // neumann's `opacity` (pbrt-v4's alpha on an area light): no emission where the
                // shape is cut out, after `power` (which pbrt computes without the alpha).
                if let Some(opacity) = area_opacity_from_props(e, self)? {
                    radiance = radiance.times(opacity);
                }
                check_emitted_power(e, &geometry, &radiance, std::f32::consts::PI * sides)?;
                Some(ShapeEmission::Area { radiance, two_sided })
            }
            Some(e) => return Err(e.error("only an 'area' or 'directionalarea' emitter can be attached to a shape")),
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
        // Mitsuba: a mesh_attribute texture on a shape without that attribute is an error.
        for name in self.sb.bsdf(bsdf).mesh_attributes() {
            if !has_attribute(&geometry, &textures, name) {
                return Err(o.error(format!(
                    "the shape's BSDF reads the mesh attribute '{name}', which this {} does not have \
                     (a PLY file's vertex and face properties give them: r g b → vertex_color / face_color, NAME_x NAME_y NAME_z → vertex_NAME, …; \
                     a <texture name=\"{name}\"> nested in the shape gives it on any shape)",
                    o.ty
                )));
            }
        }
        if emission.as_ref().is_some_and(|e| !e.radiance().mesh_attributes().is_empty()) {
            return Err(o.error("a mesh_attribute texture as an area emitter's radiance is not implemented by neumann"));
        }
        if let (Some(_), Some(e)) = (&motion, emitters.first()) {
            return Err(e.error("a moving shape cannot emit (moving area lights are not implemented)"));
        }
        let index = self.sb.add_emitting_shape(geometry, bsdf, emission);
        if let Some(m) = motion {
            self.sb.set_shape_motion(index, m);
        }
        if !textures.is_empty() {
            self.sb.set_shape_textures(index, textures);
        }
        self.sb.set_shape_media(index, interior, exterior);
        let id = o.id.as_deref().map_or(String::new(), |id| format!(" '{id}'"));
        self.sb.set_shape_label(index, format!("the {} shape{id}", o.ty), Some(o.loc.clone()));
        Ok(())
    }

    /// Mitsuba's texture attributes of the shape `o`: every texture nested in it by name (the
    /// `mesh_attribute` textures of its BSDF read them where `geometry`, a mesh, has no
    /// attribute of that name). Each attribute's own `mesh_attribute` reads must be answered by
    /// the mesh or another attribute, without a cycle.
    fn texture_attributes(&mut self, o: &Obj, geometry: &Geometry) -> Result<TextureAttributes> {
        let mut textures = TextureAttributes::default();
        let mut locs = Vec::new();
        for p in &o.props {
            let Value::Object(t) = &p.value else { continue };
            if t.tag != "texture" {
                continue;
            }
            p.used.set(true);
            if locs.len() == crate::load::limits::MAX_TEXTURE_ATTRIBUTES {
                return Err(SceneError::at(
                    &p.loc,
                    format!(
                        "a shape takes at most {} texture attributes (neumann's limit: each may read another)",
                        crate::load::limits::MAX_TEXTURE_ATTRIBUTES
                    ),
                ));
            }
            let texture = self.texture_obj(t)?;
            textures.insert(p.name.clone(), texture);
            locs.push((p.name.as_str(), &p.loc));
        }
        for (name, loc) in &locs {
            let texture = textures.get(name).expect("inserted");
            if let Some(missing) =
                texture.mesh_attributes().into_iter().find(|n| !has_attribute(geometry, &textures, n))
            {
                return Err(SceneError::at(
                    loc,
                    format!(
                        "the texture attribute '{name}' reads the attribute '{missing}', which this {} does not have",
                        o.ty
                    ),
                ));
            }
        }
        if let Some(name) = textures.cycle(|n| mesh_has(geometry, n)) {
            let loc = locs.iter().find(|(n, _)| *n == name).map(|(_, l)| *l).unwrap_or(&o.loc);
            return Err(SceneError::at(
                loc,
                format!(
                    "the texture attribute '{name}' reads itself (through mesh_attribute textures): it has no value"
                ),
            ));
        }
        Ok(textures)
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
        let plugin = MEDIUM_PLUGINS
            .iter()
            .find(|(n, _)| *n == o.ty)
            .map(|(_, f)| *f)
            .ok_or_else(|| o.unknown_plugin(&MEDIUM_PLUGINS.iter().map(|p| p.0).collect::<Vec<_>>()))?;
        let medium = plugin(o, self)?;
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

    fn nested_bsdfs(&mut self, o: &Obj, range: std::ops::RangeInclusive<usize>) -> Result<Vec<Arc<Bsdf>>> {
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
        nested.iter().map(|b| self.shared_bsdf(b)).collect()
    }

    /// The BSDF of `o`, built once and shared however often it is referenced (a chain of
    /// blends that each name the previous one twice stays linear, not exponential).
    fn shared_bsdf(&mut self, o: &Rc<Obj>) -> Result<Arc<Bsdf>> {
        let key = Rc::as_ptr(o);
        if let Some(b) = self.shared_bsdfs.get(&key) {
            return Ok(b.clone());
        }
        let b = Arc::new(self.bsdf(o)?);
        self.shared_bsdfs.insert(key, b.clone());
        Ok(b)
    }

    fn bsdf(&mut self, o: &Rc<Obj>) -> Result<Bsdf> {
        o.built.set(true);
        o.check_children(&["bsdf", "texture"])?;
        let plugin = bsdf_plugin(&o.ty)
            .ok_or_else(|| o.unknown_plugin(&BSDF_PLUGINS.iter().map(|p| p.0).collect::<Vec<_>>()))?;
        let bsdf = plugin(o, self)?;
        // The BSDFs an evaluation may visit: each nested one as often as it is named (a blend of
        // two references to one BSDF evaluates it twice). Bounded, so that a chain of blends
        // naming the previous one twice cannot make every shading point cost 2⁴⁰ evaluations.
        let size =
            1 + o.nested("bsdf").iter().map(|c| self.bsdf_sizes.get(&Rc::as_ptr(c)).copied().unwrap_or(1)).sum::<u64>();
        if size > MAX_BSDF_EVALUATIONS {
            return Err(o.error(format!(
                "this BSDF nests {size} BSDF evaluations (shared BSDFs count once per use), more than {MAX_BSDF_EVALUATIONS}"
            )));
        }
        self.bsdf_sizes.insert(Rc::as_ptr(o), size);
        // Reflectances and transmittance scales above 1 create energy: allowed (as in Mitsuba,
        // for a <float> or <spectrum>), but said, as Mitsuba and pbrt warn.
        let scales: Vec<(&str, &Texture)> = match &bsdf {
            Bsdf::Diffuse(d) => vec![("reflectance", &d.reflectance)],
            Bsdf::Plastic(p) => vec![("diffuse_reflectance", &p.diffuse_reflectance)],
            Bsdf::RoughPlastic(p) => vec![("diffuse_reflectance", &p.diffuse_reflectance)],
            Bsdf::Conductor(c) => vec![("specular_reflectance", &c.specular_reflectance)],
            Bsdf::RoughConductor(c) => vec![("specular_reflectance", &c.specular_reflectance)],
            Bsdf::Dielectric(d) => {
                vec![
                    ("specular_reflectance", &d.specular_reflectance),
                    ("specular_transmittance", &d.specular_transmittance),
                ]
            }
            Bsdf::ThinDielectric(d) => {
                vec![
                    ("specular_reflectance", &d.specular_reflectance),
                    ("specular_transmittance", &d.specular_transmittance),
                ]
            }
            Bsdf::RoughDielectric(d) => {
                vec![
                    ("specular_reflectance", &d.specular_reflectance),
                    ("specular_transmittance", &d.specular_transmittance),
                ]
            }
            _ => Vec::new(),
        };
        for (name, t) in scales {
            if let Texture::Constant(c) = t {
                if c.max_element() > 1.0 {
                    let at = o.get(name).map_or_else(|| o.loc.position(), |p| p.loc.position());
                    self.warnings.push(format!(
                        "warning: {at}: {name} {c} exceeds 1: the surface sends out more light than it receives"
                    ));
                }
            }
        }
        Ok(bsdf)
    }

    // ---------------------------------------------------------------- textures

    /// A texturable parameter: a nested/referenced `<texture>`, or a constant colour.
    fn texture(&mut self, o: &Obj, name: &str, default: Rgb, kind: SpectrumKind) -> Result<Texture> {
        if let Some(t) = o.object_opt(name, "texture").ok().flatten() {
            return self.texture_obj(&t);
        }
        let c = o.rgb(name, default, kind)?;
        Ok(Texture::Constant(c))
    }

    fn texture_obj(&mut self, o: &Obj) -> Result<Texture> {
        o.built.set(true);
        o.check_children(&[])?;
        let plugin = texture_plugin(&o.ty)
            .ok_or_else(|| o.unknown_plugin(&TEXTURE_PLUGINS.iter().map(|p| p.0).collect::<Vec<_>>()))?;
        plugin(o, self)
    }

    // ---------------------------------------------------------------- emitters

    fn emitter(&mut self, o: &Obj) -> Result<()> {
        o.built.set(true);
        o.check_children(&["texture"])?;
        if is_shape_emitter(&o.ty) {
            return Err(o.error(format!(
                "{} must be nested in the <shape> that emits, or given an id and referenced from it",
                emitter_name(&o.ty)
            )));
        }
        read_sampling_weight(o)?;
        let light = if o.ty == "timed_sunsky" {
            // Mitsuba's rays carry the sensor's time; neumann renders the one moment a sensor
            // whose shutter does not open over an interval (Mitsuba's default) gives them all.
            let (open, close) = self.shutter;
            if close != open {
                return Err(o.error(format!(
                    "the sensor's shutter is open from {open} to {close}: the timed_sunsky would change over it (a sky \
                     averaged over days and hours), which neumann's rays, without a time, cannot render; a sensor \
                     with shutter_open = shutter_close renders the sky of that moment"
                )));
            }
            crate::light::timed_sunsky(o, self, open)?
        } else {
            let plugin = emitter_plugin(&o.ty).ok_or_else(|| {
                let mut names: Vec<&str> = EMITTER_PLUGINS.iter().map(|p| p.0).collect();
                names.extend(["area", "directionalarea", "timed_sunsky"]);
                o.unknown_plugin(&names)
            })?;
            plugin(o, self)?
        };
        if let crate::light::Light::SunSky { sky, .. } = &light {
            if !sky.is_lit() {
                self.warnings.push(format!(
                    "warning: {}: the sun is below the horizon: the sunsky emits nothing (as in Mitsuba)",
                    o.loc.position()
                ));
            }
        }
        self.sb.add_light(light);
        Ok(())
    }
}

/// Whether `geometry` is a mesh with the vertex or face attribute `name`.
fn mesh_has(geometry: &Geometry, name: &str) -> bool {
    matches!(geometry, Geometry::Mesh(m) if m.attributes.iter().any(|a| a.name == name))
}

/// Whether a `mesh_attribute` texture of the shape `geometry` with texture attributes `textures`
/// finds the attribute `name` (the mesh's own, or a texture attribute).
fn has_attribute(geometry: &Geometry, textures: &TextureAttributes, name: &str) -> bool {
    mesh_has(geometry, name) || textures.get(name).is_some()
}

/// Whether an emitter of plugin `ty` belongs to the shape it is nested in (or that references it).
fn is_shape_emitter(ty: &str) -> bool {
    matches!(ty, "area" | "directionalarea")
}

/// Refuses a shape emitter `e` whose power, `factor` × the shape's area × the radiance's largest
/// mean channel (`factor`: π · sides for Lambertian emission, 1 along the normal), overflows.
fn check_emitted_power(e: &Obj, geometry: &Geometry, radiance: &Texture, factor: f32) -> Result<()> {
    if !(factor * geometry.area() * radiance.mean().max_element()).is_finite() {
        return Err(e.error(format!(
            "the emitted power overflows (area {} × radiance {}): scale the shape or the radiance down",
            geometry.area(),
            radiance.mean()
        )));
    }
    Ok(())
}

/// "an area emitter", "a directionalarea emitter": an emitter plugin named in a message.
fn emitter_name(ty: &str) -> String {
    let article = if ty.starts_with(['a', 'e', 'i', 'o', 'u']) { "an" } else { "a" };
    format!("{article} {ty} emitter")
}

/// Mitsuba's `sampling_weight` of an emitter (default 1): it only steers which light Mitsuba's
/// uniform light selection picks, never the expected image, and neumann's light samplers choose
/// by their own rule; read and checked, not used.
fn read_sampling_weight(o: &Obj) -> Result<()> {
    o.float_checked("sampling_weight", 1.0, |w| w >= 0.0 && w.is_finite(), "non-negative")?;
    Ok(())
}

impl TextureSource for Builder {
    fn texture_of(&mut self, o: &Obj, name: &str, default: Rgb, kind: SpectrumKind) -> Result<Texture> {
        Builder::texture(self, o, name, default, kind)
    }
}

impl BsdfBuilder for Builder {
    fn nested_bsdfs(&mut self, o: &Obj, count: std::ops::RangeInclusive<usize>) -> Result<Vec<Arc<Bsdf>>> {
        Builder::nested_bsdfs(self, o, count)
    }

    fn nested_textures(&mut self, o: &Obj) -> Result<Vec<Texture>> {
        o.nested("texture").iter().map(|t| self.texture_obj(t)).collect()
    }

    fn tensor_file(&mut self, o: &Obj, name: &str) -> Result<Arc<crate::tensor::TensorFile>> {
        let path = self.resolver.resolve(&o.string(name)?);
        if let Some(t) = self.tensors.get(&path) {
            return Ok(t.clone());
        }
        let t =
            Arc::new(crate::load::tensor_file::load_tensor_file(&path).map_err(|e| o.error_at(name, e.to_string()))?);
        self.tensors.insert(path, t.clone());
        Ok(t)
    }
}

impl ImageSource for Builder {
    fn image(&mut self, o: &Obj, name: &str, raw: bool) -> Result<Arc<Image>> {
        let file = o.string(name)?;
        if !self.memory.images.is_empty() {
            let key = (PathBuf::from(format!("#memory/{file}")), raw);
            if let Some(i) = self.images.get(&key) {
                return Ok(i.clone());
            }
            if let Some(img) = self.memory.image(&file, raw) {
                let img = Arc::new(img);
                self.images.insert(key, img.clone());
                return Ok(img);
            }
        }
        let path = self.resolver.resolve(&file);
        let key = (path.clone(), raw);
        if let Some(i) = self.images.get(&key) {
            return Ok(i.clone());
        }
        let img = Arc::new(load_image(&path, raw).map_err(|e| o.error_at(name, e.to_string()))?);
        self.images.insert(key, img.clone());
        Ok(img)
    }

    fn pbrt_scalar_image(&mut self, o: &Obj, name: &str, raw: bool, gamma: Option<f32>) -> Result<Arc<Image>> {
        let file = o.string(name)?;
        let path = self.resolver.resolve(&file);
        // Cached apart from the colour images of the same file (a suffix no file name has).
        let tag = match (raw, gamma) {
            (true, _) => "linear".to_string(),
            (_, Some(g)) => format!("gamma {g}"),
            _ => "sRGB".to_string(),
        };
        let key = (PathBuf::from(format!("{}\0pbrt-scalar {tag}", path.display())), raw);
        if let Some(i) = self.images.get(&key) {
            return Ok(i.clone());
        }
        let decode = |v: f32| match (raw, gamma) {
            (true, _) => v,
            (_, Some(g)) => v.max(0.0).powf(g),
            _ => crate::math::color::srgb_decode(v),
        };
        let img = Arc::new(
            crate::load::image::load_pbrt_scalar(&path, &decode).map_err(|e| o.error_at(name, e.to_string()))?,
        );
        self.images.insert(key, img.clone());
        Ok(img)
    }
}

impl VolumeSource for Builder {
    fn grid_volume(&mut self, o: &Obj, name: &str) -> Result<Arc<GridVolume>> {
        let file = o.string(name)?;
        if let Some(v) = self.memory.volumes.get(&file) {
            return Ok(v.clone());
        }
        let path = self.resolver.resolve(&file);
        if let Some(v) = self.volumes.get(&path) {
            return Ok(v.clone());
        }
        let v = Arc::new(crate::load::volume::load_grid_volume(&path).map_err(|e| o.error_at(name, e.to_string()))?);
        self.volumes.insert(path, v.clone());
        Ok(v)
    }

    fn nanovdb_grid(
        &mut self,
        o: &Obj,
        name: &str,
        grid: &str,
    ) -> Result<Option<Arc<crate::image::nanovdb::NanoGrid>>> {
        let path = self.resolver.resolve(&o.string(name)?);
        let key = (path, grid.to_string());
        if let Some(g) = self.nano_grids.get(&key) {
            return Ok(g.clone());
        }
        let g = crate::load::nanovdb::load_nanovdb(&key.0, grid).map_err(|e| o.error_at(name, e.to_string()))?;
        let g = g.map(Arc::new);
        self.nano_grids.insert(key, g.clone());
        Ok(g)
    }

    fn warn(&mut self, line: String) {
        self.warnings.push(line);
    }
}

impl MeshSource for Builder {
    fn point_table(&mut self, o: &Obj, name: &str) -> Result<crate::geometry::ellipsoids::PointTable> {
        let path = self.resolver.resolve(&o.string(name)?);
        crate::load::ply::load_ply_table(&path).map_err(|e| o.error_at(name, e.to_string()))
    }

    fn curve_file(&mut self, o: &Obj, name: &str) -> Result<Vec<Vec<crate::geometry::roundcurve::ControlPoint>>> {
        let path = self.resolver.resolve(&o.string(name)?);
        crate::load::curve_file::load_curve_file(&path).map_err(|e| o.error_at(name, e.to_string()))
    }

    fn curves(&mut self, o: &Obj, name: &str) -> Result<crate::geometry::CurveSet> {
        let file = o.string(name)?;
        self.memory.curves.get(&file).cloned().ok_or_else(|| {
            o.error_at(
                name,
                format!("no decoded curves named '{file}' (the 'curve' shape holds the curves of pbrt-v4 scenes)"),
            )
        })
    }

    fn mesh(&mut self, o: &Obj, name: &str) -> Result<MeshFile> {
        if o.ty == "mesh" {
            let file = o.string(name)?;
            let mesh = self.memory.meshes.get(&file).cloned().ok_or_else(|| {
                o.error_at(name, format!("no decoded mesh named '{file}' (the 'mesh' shape holds meshes a scene format decoded itself, such as glTF's)"))
            })?;
            return Ok(MeshFile { mesh, face_normals: false });
        }
        let path = self.resolver.resolve(&o.string(name)?);
        let index = match o.ty.as_str() {
            "obj" | "ply" => 0,
            _ => {
                let index = o.int("shape_index", 0)?;
                usize::try_from(index)
                    .map_err(|_| o.error_at("shape_index", format!("shape_index must be ≥ 0, got {index}")))?
            }
        };
        let key = (path, o.ty.clone(), index);
        let read = match self.prefetched.remove(&key) {
            Some((uses, Ok(file))) if uses > 1 => {
                self.prefetched.insert(key, (uses - 1, Ok(file.clone())));
                Ok(file)
            }
            Some((_, read)) => read,
            None => read_mesh_file(&key),
        };
        read.map_err(|e| o.error_at(name, e.to_string()))
    }
}

/// A mesh file as the shapes name it: its path, the shape's type (`obj`, `ply` or
/// `serialized`) and, in a serialized file, the mesh's index.
type MeshKey = (PathBuf, String, usize);

/// Reads the mesh file `key` names.
fn read_mesh_file((path, ty, index): &MeshKey) -> std::result::Result<MeshFile, crate::load::LoadError> {
    match ty.as_str() {
        "obj" => Ok(MeshFile { mesh: crate::load::obj::load_obj(path)?, face_normals: false }),
        "ply" => Ok(MeshFile { mesh: crate::load::ply::load_ply(path)?, face_normals: false }),
        _ => {
            let s = crate::load::serialized::load_serialized(path, *index)?;
            let mut mesh = s.mesh;
            if !s.colors.is_empty() {
                // Mitsuba names a serialized mesh's vertex colours `vertex_color`.
                let values = s.colors;
                mesh.attributes.push(crate::geometry::mesh::MeshAttribute {
                    name: "vertex_color".into(),
                    per_face: false,
                    values,
                });
            }
            Ok(MeshFile { mesh, face_normals: s.face_normals })
        }
    }
}

impl Builder {
    /// Reads every mesh file the scene's shapes name (OBJ, PLY, serialized), in parallel, before
    /// the build takes them one by one in document order: a scene of many meshes loads on every
    /// core, as Mitsuba's loads them. A file named by several shapes is read once and copied
    /// for all but its last use. Nothing here can fail: a shape whose file or index cannot be
    /// read is left to its own build, which reports it where it is.
    fn prefetch_meshes(&mut self, root: &Obj) {
        // Every object once (references make a graph of the tree), without recursion (a chain of
        // references is as long as the file makes it).
        let mut uses: HashMap<MeshKey, usize> = HashMap::new();
        let (mut seen, mut todo) = (std::collections::HashSet::new(), vec![root]);
        while let Some(o) = todo.pop() {
            let nested = o.children.iter().chain(o.props.iter().filter_map(|p| match &p.value {
                Value::Object(c) => Some(c),
                _ => None,
            }));
            for c in nested.filter(|c| seen.insert(Rc::as_ptr(c))) {
                todo.push(c);
                if c.tag != "shape" || !matches!(c.ty.as_str(), "obj" | "ply" | "serialized") {
                    continue;
                }
                let value = |name: &str| c.props.iter().find(|p| p.name == name).map(|p| &p.value);
                let Some(Value::String(file)) = value("filename") else { continue };
                let index = match value("shape_index") {
                    _ if c.ty != "serialized" => 0,
                    None => 0,
                    Some(Value::Integer(i)) if *i >= 0 => *i as usize,
                    Some(_) => continue,
                };
                *uses.entry((self.resolver.resolve(file), c.ty.clone(), index)).or_default() += 1;
            }
        }
        if uses.len() < 2 {
            return; // (One file or none: read where it is used.)
        }
        let keys: Vec<MeshKey> = uses.keys().cloned().collect();
        let read: Vec<_> = keys.par_iter().map(read_mesh_file).collect();
        self.prefetched = keys
            .into_iter()
            .zip(read)
            .map(|(k, r)| {
                let n = uses[&k];
                (k, (n, r))
            })
            .collect();
    }
}

/// The most BSDF evaluations one BSDF's evaluation may make (nested blends, twosided, masks).
const MAX_BSDF_EVALUATIONS: u64 = 4096;

/// A shape's motion (neumann's properties for pbrt-v4's animated transforms): `to_world` at
/// time `motion_start` (0) and `to_world_end` at `motion_end` (1), both placed by `outer`; `None`
/// without `to_world_end` or where the two transforms are the same.
fn shape_motion(o: &Obj, outer: &Transform) -> Result<Option<crate::math::AnimatedTransform>> {
    if o.get("to_world_end").is_none() {
        return Ok(None);
    }
    let start = *outer * o.transform("to_world")?;
    let end = *outer * o.transform("to_world_end")?;
    let (t0, t1) = (o.float("motion_start", 0.0)?, o.float("motion_end", 1.0)?);
    let motion = crate::math::AnimatedTransform::new(start, t0, end, t1).map_err(|e| o.error_at("to_world_end", e))?;
    Ok(motion.is_animated().then_some(motion))
}

/// Rejects geometry whose coordinates are not finite, or so large that their differences
/// overflow (a NaN or overflowing `to_world`, huge mesh coordinates): such shapes would be
/// invisible or poison the image.
fn check_finite_geometry(o: &Obj, geometry: &Geometry) -> Result<()> {
    for i in 0..geometry.primitive_count() {
        let b = geometry.primitive_bounds(i);
        if !(b.min.is_finite() && b.max.is_finite() && (b.max - b.min).is_finite()) {
            return Err(o.error(format!(
                "the shape's coordinates are not finite after its to_world (primitive {i} spans {} to {}): \
                 check the transform and the file's coordinates",
                b.min, b.max
            )));
        }
    }
    Ok(())
}

/// Mitsuba's `batch` sensor: its nested sensors side by side on its `width × height` film (the
/// width a multiple of their number). The nested sensors' own films and samplers are read and
/// replaced, as in Mitsuba.
fn batch_from_props(o: &Obj, width: u32, height: u32) -> Result<Camera> {
    let nested = o.nested("sensor");
    let columns = Camera::batch_column_width(width, nested.len()).map_err(|e| o.error(e.to_string()))?;
    let mut cameras = Vec::with_capacity(nested.len());
    for s in &nested {
        s.built.set(true);
        s.check_children(&["film", "sampler"])?;
        if matches!(s.ty.as_str(), "batch" | "irradiancemeter" | "radiancemeter" | "distant") {
            return Err(s.error(format!("a {} cannot be part of a batch", s.ty)));
        }
        for f in s.nested("film") {
            f.built.set(true);
            FilmSettings::from_props(&f)?;
        }
        for m in s.nested("sampler") {
            m.built.set(true);
            SamplerSettings::from_props(&m)?;
        }
        cameras.push(Camera::from_props(s, columns, height)?);
    }
    Camera::batch(cameras, width, height).map_err(|e| o.error(e.to_string()))
}
