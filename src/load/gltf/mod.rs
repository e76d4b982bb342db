//! glTF 2.0 scenes (`.gltf` with external or embedded buffers, binary `.glb`):
//! `neumann render model.gltf`.
//!
//! The file is read with the `gltf` crate (JSON, GLB container, validation of every index), its
//! binary data with bounds-checked accessors (`data`); the loader then translates the default
//! scene into the same located plugin objects a Mitsuba file gives ([`crate::props::Obj`]): each
//! mesh primitive a `mesh` shape whose decoded triangles wait in [`MemoryFiles`], each material a
//! `principled` BSDF with `scale`d textures (`material`), `KHR_lights_punctual` lights as
//! `point`, `spot` and `directional` emitters, the camera as a `perspective` or `orthographic`
//! sensor — and the shared builder makes the scene. Every problem is a [`SceneError`] at the
//! `file:line:col` of the JSON value concerned (in a `.glb`, of its JSON chunk).
//!
//! What neumann does where glTF leaves it to the renderer (documented in the README):
//! - the default scene (`scene`, else the first; without scenes, every root node);
//! - the camera: `--camera NAME|INDEX` (a camera's name or index in `cameras`, or the name of a
//!   node that holds one), else the first camera placed by a node; without cameras, a
//!   perspective camera looking at the scene's bounds from the front (+z), slightly above;
//! - lights: a file with neither `KHR_lights_punctual` lights nor emissive materials gets a
//!   uniform white environment (radiance 1);
//! - units: a punctual light's candela (lm/sr) and a directional light's lux (lm/m²) become W/sr
//!   and W/m² at 683 lm/W, as Blender's importer converts them (its default "standard" mode);
//! - film 960 pixels wide, as tall as the camera's aspect ratio says (16:9 without one),
//!   Gaussian filter, 64 samples per pixel of the independent sampler, the path tracer (volumetric
//!   when a material has `KHR_materials_volume`); `--res`, `--spp`, `--integrator` override.

mod data;
pub mod json;
mod material;
mod mesh;

use crate::load::limits;
use crate::load::memory::MemoryFiles;
use crate::load::overrides::Overrides;
use crate::load::{FileResolver, SceneFile};
use crate::math::{Mat4, Transform, Vec3};
use crate::props::{Loc, Obj, SceneError, SourceFile, Value};
use gltf::Document;
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

type Result<T> = std::result::Result<T, SceneError>;

/// Extensions neumann implements (a file may require them).
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
];

/// The glTF file's JSON text, for locating errors.
pub struct Src {
    file: Arc<SourceFile>,
    index: json::Index,
}

impl Src {
    /// The location of the value at the JSON `path` (`gltf` crate notation).
    pub fn loc(&self, path: &str) -> Loc {
        Loc { file: self.file.clone(), offset: self.index.locate(&self.file.text, &json::parse_path(path)) }
    }

    /// An error at the value at `path`.
    pub fn err(&self, path: &str, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.loc(path), message)
    }
}

/// Loads a glTF 2.0 file (`.gltf` or `.glb`) with settings from outside the file (`settings`:
/// command-line flags) and the camera `camera` chooses (a name or index; `None`: the first).
pub fn load_gltf_file(path: &Path, settings: &Overrides, camera: Option<&str>) -> Result<SceneFile> {
    let bytes = limits::read_bounded(path, limits::MAX_FILE_BYTES).map_err(|e| SceneError::new(e.to_string()))?;
    load_gltf_bytes(path, &bytes, settings, camera)
}

/// [`load_gltf_file`] of the file's bytes (`path` names it and anchors relative URIs).
pub fn load_gltf_bytes(path: &Path, bytes: &[u8], settings: &Overrides, camera: Option<&str>) -> Result<SceneFile> {
    let whole = |m: String| SceneError::new(format!("{}: {m}", path.display()));
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        let (json, bin) =
            data::split_glb(bytes).map_err(|e| whole(format!("not a valid binary glTF (.glb) file: {e}")))?;
        (json.to_vec(), bin.map(<[u8]>::to_vec))
    } else {
        (bytes.to_vec(), None)
    };
    let text = String::from_utf8(json_bytes).map_err(|e| whole(format!("the glTF JSON is not UTF-8: {e}")))?;
    let index = json::Index::new(&text);
    let src = Src { file: Arc::new(SourceFile { path: path.to_path_buf(), text }), index };
    let text = &src.file.text;
    // JSON syntax, with the position serde_json found the problem at.
    let at_line_col = |e: &serde_json::Error, what: &str| {
        let offset: usize = text.split_inclusive('\n').take(e.line().saturating_sub(1)).map(str::len).sum();
        let offset = (offset + e.column().saturating_sub(1)).min(text.len());
        let message = e.to_string();
        let message = message.split(" at line ").next().unwrap_or(&message).to_string();
        SceneError::at(&Loc { file: src.file.clone(), offset }, format!("{what}: {message}"))
    };
    let value: serde_json::Value = serde_json::from_str(text).map_err(|e| at_line_col(&e, "malformed JSON"))?;
    let version = value.pointer("/asset/version").and_then(|v| v.as_str());
    match version {
        Some(v) if v.split('.').next() == Some("2") => {}
        Some(v) => return Err(src.err("asset.version", format!("glTF {v} is not supported (glTF 2.0 is)"))),
        None => return Err(src.err("asset", "the file has no asset.version: is it glTF 2.0?")),
    }
    let mut warnings = Vec::new();
    check_extensions(&src, &value, &mut warnings)?;
    let root: gltf::json::Root =
        serde_json::from_str(text).map_err(|e| at_line_col(&e, "not a valid glTF document"))?;
    check_position_references(&src, &value)?;
    validate(&src, &root)?;
    let doc = Document::from_json_without_validation(root);
    let resolver = FileResolver::for_scene(path);
    let buffers = data::load_buffers(&src, &doc, blob, &resolver)?;
    let mut t = Translator::new(&src, &value, &doc, &buffers, resolver.clone());
    t.warnings = warnings;
    let root = t.translate(camera)?;
    let root = crate::load::overrides::apply(&root, settings);
    let Translator { memory, warnings, .. } = t;
    let mut file = crate::load::build::Builder::with_memory(resolver, memory).build(&root)?;
    file.warnings.extend(warnings);
    Ok(file)
}

/// Required extensions neumann lacks are errors naming them; used ones are warnings (the file
/// says it renders without them).
fn check_extensions(src: &Src, value: &serde_json::Value, warnings: &mut Vec<String>) -> Result<()> {
    let names = |key: &str| -> Vec<String> {
        value
            .get(key)
            .and_then(|v| v.as_array())
            .map_or(Vec::new(), |a| a.iter().filter_map(|s| s.as_str().map(str::to_string)).collect())
    };
    for (i, ext) in names("extensionsRequired").iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(src.err(
                &format!("extensionsRequired[{i}]"),
                format!(
                    "the file requires the extension {ext}, which neumann does not implement (it implements {})",
                    SUPPORTED_EXTENSIONS.join(", ")
                ),
            ));
        }
    }
    for ext in names("extensionsUsed") {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            let what = match ext.as_str() {
                "KHR_materials_unlit" => "unlit materials are rendered as lit metallic-roughness materials",
                "KHR_materials_pbrSpecularGlossiness" => {
                    "materials are rendered from their metallic-roughness parameters"
                }
                "KHR_materials_variants" => "the default material of each primitive is rendered",
                _ => "ignored, as the file allows",
            };
            warnings
                .push(format!("warning: {}: glTF extension {ext} is not implemented: {what}", src.file.path.display()));
        }
    }
    Ok(())
}

/// Each primitive's `POSITION` accessor index must exist before the `gltf` crate's validation
/// reads that accessor (it indexes without checking).
fn check_position_references(src: &Src, value: &serde_json::Value) -> Result<()> {
    let accessors = value.get("accessors").and_then(|a| a.as_array()).map_or(0, Vec::len);
    let meshes = value.get("meshes").and_then(|m| m.as_array()).map_or(&[][..], Vec::as_slice);
    for (m, mesh) in meshes.iter().enumerate() {
        let prims = mesh.get("primitives").and_then(|p| p.as_array()).map_or(&[][..], Vec::as_slice);
        for (p, prim) in prims.iter().enumerate() {
            if let Some(i) = prim.pointer("/attributes/POSITION").and_then(|v| v.as_u64()) {
                if i as usize >= accessors {
                    return Err(src.err(
                        &format!("meshes[{m}].primitives[{p}].attributes[\"POSITION\"]"),
                        format!("index out of range: accessor {i} does not exist (the file has {accessors})"),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The `gltf` crate's validation (indices in range, required values present), located; its
/// refusal of required extensions it lacks is left to [`check_extensions`].
fn validate(src: &Src, root: &gltf::json::Root) -> Result<()> {
    use gltf::json::validation::{Error, Validate};
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| errors.push((path(), error)));
    errors.retain(|(p, e)| !(p.as_str().starts_with("extensionsRequired") && *e == Error::Unsupported));
    // POSITION's min and max, which glTF requires for culling: neumann computes the bounds.
    errors.retain(|(p, _)| !(p.as_str().ends_with("[\"POSITION\"].min") || p.as_str().ends_with("[\"POSITION\"].max")));
    if let Some((path, error)) = errors.first() {
        let what = match error {
            Error::IndexOutOfBounds => "index out of range",
            Error::Invalid => "invalid value",
            Error::Missing => "missing required value",
            Error::Oversize => "size exceeds the system's limits",
            Error::Unsupported => "unsupported value",
        };
        let more = if errors.len() > 1 { format!(" (and {} more problems)", errors.len() - 1) } else { String::new() };
        return Err(src.err(path.as_str(), format!("{}: {what}{more}", path.as_str())));
    }
    Ok(())
}

/// A camera placed by a node.
struct CameraUse {
    camera: usize,
    node: usize,
    to_world: Mat4,
}

/// Builds the plugin objects of a glTF document.
struct Translator<'a> {
    src: &'a Src,
    /// The document as plain JSON (for the extensions the typed API lacks).
    json: &'a serde_json::Value,
    doc: &'a Document,
    buffers: &'a [Vec<u8>],
    resolver: FileResolver,
    memory: MemoryFiles,
    warnings: Vec<String>,
    shapes: Vec<Rc<Obj>>,
    emitters: Vec<Rc<Obj>>,
    cameras: Vec<CameraUse>,
    /// World-space bounds of every mesh (for the default camera).
    bounds: crate::math::Bounds3,
    /// Built BSDFs and area emitters by (material index, uv set, vertex colours).
    materials: HashMap<(Option<usize>, u32, bool), material::Built>,
    /// Whether a material asked for a participating medium (volumetric path tracer).
    has_media: bool,
    /// Whether any material emits.
    has_emission: bool,
    /// The texture-coordinate set of the meshes of the material being built (textures on other
    /// sets read them from mesh attributes).
    primary_uv: u32,
}

impl<'a> Translator<'a> {
    fn new(
        src: &'a Src,
        json: &'a serde_json::Value,
        doc: &'a Document,
        buffers: &'a [Vec<u8>],
        resolver: FileResolver,
    ) -> Translator<'a> {
        Translator {
            src,
            json,
            doc,
            buffers,
            resolver,
            memory: MemoryFiles::default(),
            warnings: Vec::new(),
            shapes: Vec::new(),
            emitters: Vec::new(),
            cameras: Vec::new(),
            bounds: crate::math::Bounds3::EMPTY,
            materials: HashMap::new(),
            has_media: false,
            has_emission: false,
            primary_uv: 0,
        }
    }

    /// A new plugin object located at the JSON `path`.
    fn obj(&self, tag: &str, ty: &str, path: &str) -> Obj {
        Obj::new(tag, ty, self.src.loc(path))
    }

    /// The whole scene as a `<scene>` object.
    fn translate(&mut self, camera: Option<&str>) -> Result<Rc<Obj>> {
        let roots: Vec<usize> = match self.doc.default_scene().or_else(|| self.doc.scenes().next()) {
            Some(s) => s.nodes().map(|n| n.index()).collect(),
            None => {
                let mut is_child = vec![false; self.doc.nodes().len()];
                for n in self.doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                (0..is_child.len()).filter(|&i| !is_child[i]).collect()
            }
        };
        let world = self.world_transforms()?;
        let mut visited = vec![false; self.doc.nodes().len()];
        let nodes: Vec<gltf::Node> = self.doc.nodes().collect();
        // Depth first, in document order.
        let mut stack: Vec<usize> = roots.iter().rev().copied().collect();
        while let Some(i) = stack.pop() {
            if std::mem::replace(&mut visited[i], true) {
                continue;
            }
            let node = nodes[i].clone();
            self.node(&node, &world)?;
            let children: Vec<usize> = node.children().map(|c| c.index()).collect();
            stack.extend(children.into_iter().rev());
        }
        self.cameras.sort_by_key(|c| c.node);
        let mut scene = self.obj("scene", "scene", "");
        scene.children.push(Rc::new(self.integrator()));
        scene.children.push(Rc::new(self.sensor(camera)?));
        if self.emitters.is_empty() && !self.has_emission {
            let mut env = self.obj("emitter", "constant", "");
            self.set(&mut env, "radiance", Value::Float(1.0), "");
            scene.children.push(Rc::new(env));
            self.warnings.push(format!(
                "note: {} has no lights: lit by a uniform white environment (radiance 1)",
                self.src.file.path.display()
            ));
        }
        scene.children.append(&mut self.emitters);
        scene.children.append(&mut self.shapes);
        Ok(Rc::new(scene))
    }

    /// Sets property `name` of `o`, located at the JSON `path`.
    fn set(&self, o: &mut Obj, name: &str, value: Value, path: &str) {
        o.set(name, value, self.src.loc(path));
    }

    /// Every node's world transform (a node reached twice, or a cycle, is an error).
    fn world_transforms(&self) -> Result<Vec<Mat4>> {
        let n = self.doc.nodes().len();
        let mut parent = vec![None; n];
        for node in self.doc.nodes() {
            for c in node.children() {
                if let Some(p) = parent[c.index()] {
                    return Err(self.src.err(
                        &format!("nodes[{}].children", node.index()),
                        format!(
                            "node {} is a child of nodes {p} and {} (glTF's nodes form a tree)",
                            c.index(),
                            node.index()
                        ),
                    ));
                }
                parent[c.index()] = Some(node.index());
            }
        }
        let local: Vec<Mat4> = self.doc.nodes().map(|n| Mat4::from_cols_array_2d(&n.transform().matrix())).collect();
        let mut world: Vec<Option<Mat4>> = vec![None; n];
        for start in 0..n {
            let mut chain = vec![start];
            while let Some(p) = parent[*chain.last().expect("non-empty")] {
                if world[p].is_some() {
                    break;
                }
                if chain.len() > n {
                    return Err(self
                        .src
                        .err(&format!("nodes[{start}]"), "the node is its own ancestor (a cycle of children)"));
                }
                chain.push(p);
            }
            for &i in chain.iter().rev() {
                if world[i].is_none() {
                    let up = parent[i].and_then(|p| world[p]).unwrap_or(Mat4::IDENTITY);
                    world[i] = Some(up * local[i]);
                }
            }
        }
        Ok(world.into_iter().map(|m| m.expect("every node visited")).collect())
    }

    /// A node's mesh, camera and light.
    fn node(&mut self, node: &gltf::Node, world: &[Mat4]) -> Result<()> {
        let path = format!("nodes[{}]", node.index());
        let m = world[node.index()];
        if !m.is_finite() {
            return Err(self.src.err(&path, "the node's transform is not finite"));
        }
        if let Some(camera) = node.camera() {
            self.cameras.push(CameraUse { camera: camera.index(), node: node.index(), to_world: m });
        }
        if let Some(light) = node.light() {
            self.light(&light, &m, &path)?;
        }
        if let Some(mesh) = node.mesh() {
            self.mesh(node, &mesh, world)?;
        }
        Ok(())
    }

    /// A `KHR_lights_punctual` light placed by `m`.
    fn light(&mut self, light: &gltf::khr_lights_punctual::Light, m: &Mat4, node_path: &str) -> Result<()> {
        use gltf::khr_lights_punctual::Kind;
        let path = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
        let [r, g, b] = light.color();
        let intensity = light.intensity();
        if !(intensity >= 0.0 && intensity.is_finite()) || [r, g, b].iter().any(|c| !(*c >= 0.0 && c.is_finite())) {
            return Err(self.src.err(&path, "a light's color and intensity must be finite and ≥ 0"));
        }
        // Blender's importer: W = cd · 4π / 683 for point-like lights (radiant intensity cd / 683
        // W/sr), W/m² = lux / 683 for directional ones.
        let value = Value::Rgb(crate::math::Rgb::new(r, g, b) * (intensity / 683.0));
        let t = Transform::from_matrix(*m);
        let origin = m.transform_point3(Vec3::ZERO);
        // glTF lights shine along their local −z.
        let axis = m.transform_vector3(-Vec3::Z).normalize_or_zero();
        let o = match light.kind() {
            Kind::Point => {
                let mut o = self.obj("emitter", "point", &path);
                self.set(&mut o, "position", Value::Point(origin), node_path);
                self.set(&mut o, "intensity", value, &path);
                o
            }
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                if axis == Vec3::ZERO || t.is_none() {
                    return Err(self.src.err(node_path, "the spot light's transform is singular"));
                }
                if !(0.0..=std::f32::consts::FRAC_PI_2).contains(&outer_cone_angle)
                    || !(0.0..=outer_cone_angle).contains(&inner_cone_angle)
                {
                    return Err(self.src.err(
                        &format!("{path}.spot"),
                        format!("need 0 ≤ innerConeAngle ≤ outerConeAngle ≤ π/2, got {inner_cone_angle} and {outer_cone_angle}"),
                    ));
                }
                let up = if axis.y.abs() > 0.9 { Vec3::X } else { Vec3::Y };
                let frame = Transform::look_at(origin, origin + axis, up).expect("unit axis");
                let mut o = self.obj("emitter", "spot", &path);
                self.set(&mut o, "to_world", Value::Transform(frame), node_path);
                self.set(&mut o, "intensity", value, &path);
                self.set(
                    &mut o,
                    "cutoff_angle",
                    Value::Float(outer_cone_angle.to_degrees().max(1e-3) as f64),
                    &format!("{path}.spot"),
                );
                self.set(
                    &mut o,
                    "beam_width",
                    Value::Float(inner_cone_angle.to_degrees() as f64),
                    &format!("{path}.spot"),
                );
                o
            }
            Kind::Directional => {
                if axis == Vec3::ZERO {
                    return Err(self.src.err(node_path, "the directional light's transform is singular"));
                }
                let mut o = self.obj("emitter", "directional", &path);
                self.set(&mut o, "direction", Value::Vector(axis), node_path);
                self.set(&mut o, "irradiance", value, &path);
                o
            }
        };
        self.emitters.push(Rc::new(o));
        Ok(())
    }

    /// The integrator: the path tracer, volumetric when a material has a medium.
    fn integrator(&self) -> Obj {
        self.obj("integrator", if self.has_media { "volpath" } else { "path" }, "")
    }

    /// The sensor: the chosen camera, or one framing the scene.
    fn sensor(&mut self, choice: Option<&str>) -> Result<Obj> {
        let chosen = match choice {
            None => self.cameras.first(),
            Some(c) => {
                let by_index = c.parse::<usize>().ok();
                let cam = self.cameras.iter().find(|u| {
                    by_index == Some(u.camera)
                        || self.doc.cameras().nth(u.camera).and_then(|k| k.name()) == Some(c)
                        || self.doc.nodes().nth(u.node).and_then(|n| n.name()) == Some(c)
                });
                if cam.is_none() {
                    let names: Vec<String> = self
                        .cameras
                        .iter()
                        .map(|u| {
                            let name = self.doc.cameras().nth(u.camera).and_then(|k| k.name()).unwrap_or("unnamed");
                            format!("{} ('{name}', node {})", u.camera, u.node)
                        })
                        .collect();
                    let list = if names.is_empty() { "none".to_string() } else { names.join(", ") };
                    return Err(SceneError::new(format!(
                        "--camera {c}: {} has no camera of that index or name placed by a node (cameras: {list})",
                        self.src.file.path.display()
                    )));
                }
                cam
            }
        };
        let mut film_size = (960u32, 540u32);
        let mut sensor = match chosen {
            Some(u) => {
                let cam = self.doc.cameras().nth(u.camera).expect("validated");
                let path = format!("cameras[{}]", u.camera);
                let node_path = format!("nodes[{}]", u.node);
                let m = u.to_world;
                let origin = m.transform_point3(Vec3::ZERO);
                let forward = m.transform_vector3(-Vec3::Z).normalize_or_zero();
                let up = m.transform_vector3(Vec3::Y).normalize_or_zero();
                let look = (forward != Vec3::ZERO && up != Vec3::ZERO)
                    .then(|| Transform::look_at(origin, origin + forward, up))
                    .flatten()
                    .ok_or_else(|| self.src.err(&node_path, "the camera's node transform is singular"))?;
                match cam.projection() {
                    gltf::camera::Projection::Perspective(p) => {
                        let mut o = self.obj("sensor", "perspective", &path);
                        if let Some(a) = p.aspect_ratio() {
                            if !(a > 0.0 && a.is_finite()) {
                                return Err(self
                                    .src
                                    .err(&format!("{path}.perspective.aspectRatio"), "must be positive"));
                            }
                            film_size = (960, ((960.0 / a).round() as u32).max(1));
                        }
                        let fov = p.yfov().to_degrees();
                        if !(fov > 0.0 && fov < 180.0) {
                            return Err(self.src.err(
                                &format!("{path}.perspective.yfov"),
                                format!("yfov must lie in (0, π), got {}", p.yfov()),
                            ));
                        }
                        self.set(&mut o, "fov", Value::Float(fov as f64), &format!("{path}.perspective.yfov"));
                        self.set(&mut o, "fov_axis", Value::String("y".into()), &format!("{path}.perspective.yfov"));
                        self.set(&mut o, "to_world", Value::Transform(look), &node_path);
                        self.set(
                            &mut o,
                            "near_clip",
                            Value::Float(p.znear() as f64),
                            &format!("{path}.perspective.znear"),
                        );
                        if let Some(far) = p.zfar() {
                            self.set(&mut o, "far_clip", Value::Float(far as f64), &format!("{path}.perspective.zfar"));
                        }
                        o
                    }
                    gltf::camera::Projection::Orthographic(p) => {
                        let mut o = self.obj("sensor", "orthographic", &path);
                        let (xmag, ymag) = (p.xmag().abs(), p.ymag().abs());
                        if !(xmag > 0.0 && ymag > 0.0 && xmag.is_finite() && ymag.is_finite()) {
                            return Err(self
                                .src
                                .err(&format!("{path}.orthographic"), "xmag and ymag must be non-zero"));
                        }
                        film_size = (960, ((960.0 * ymag / xmag).round() as u32).max(1));
                        let scale = Transform::scale(Vec3::new(xmag, xmag, 1.0)).expect("non-zero");
                        self.set(&mut o, "to_world", Value::Transform(look * scale), &node_path);
                        self.set(
                            &mut o,
                            "near_clip",
                            Value::Float(p.znear().max(1e-6) as f64),
                            &format!("{path}.orthographic.znear"),
                        );
                        self.set(
                            &mut o,
                            "far_clip",
                            Value::Float(p.zfar() as f64),
                            &format!("{path}.orthographic.zfar"),
                        );
                        o
                    }
                }
            }
            None => self.default_camera()?,
        };
        let mut film = self.obj("film", "hdrfilm", "");
        self.set(&mut film, "width", Value::Integer(film_size.0.into()), "");
        self.set(&mut film, "height", Value::Integer(film_size.1.into()), "");
        let mut sampler = self.obj("sampler", "independent", "");
        self.set(&mut sampler, "sample_count", Value::Integer(64), "");
        sensor.children.push(Rc::new(film));
        sensor.children.push(Rc::new(sampler));
        Ok(sensor)
    }

    /// A perspective camera (39.6° along the shorter side, Blender's default lens) looking at the
    /// centre of the scene's bounds from the front (+z) and a little above, at the distance that
    /// fits the bounding sphere in view.
    fn default_camera(&mut self) -> Result<Obj> {
        let b = self.bounds;
        let (center, radius) = if b.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (0.5 * (b.min + b.max), (0.5 * b.diagonal().length()).max(1e-4))
        };
        let fov: f32 = 39.6;
        let distance = radius / (0.5 * fov).to_radians().sin() * 1.05;
        let dir = Vec3::new(0.0, 0.35, 1.0).normalize();
        let origin = center + dir * distance;
        let look = Transform::look_at(origin, center, Vec3::Y).filter(|_| origin.is_finite()).ok_or_else(|| {
            self.src.err(
                "",
                format!("cannot frame the scene with a default camera: its bounds (radius {radius}) are too large"),
            )
        })?;
        let mut o = self.obj("sensor", "perspective", "");
        self.set(&mut o, "fov", Value::Float(fov as f64), "");
        self.set(&mut o, "fov_axis", Value::String("smaller".into()), "");
        self.set(&mut o, "to_world", Value::Transform(look), "");
        self.set(&mut o, "near_clip", Value::Float((distance - radius).max(distance * 1e-3) as f64 * 0.5), "");
        self.set(&mut o, "far_clip", Value::Float(((distance + radius) * 2.0) as f64), "");
        Ok(o)
    }
}

#[cfg(test)]
mod tests;
