//! pbrt-v4 directives, executed in order over the graphics state (transform stack, attributes,
//! named coordinate systems, materials, textures, objects), each scene object translated at its
//! directive into neumann's plugin objects (Mitsuba's names, [`crate::props::Obj`]).

use super::lexer::{tokenize, Kind, Token};
use super::params::{PVal, Param, ParamSet};
use super::translate;
use crate::load::limits;
use crate::load::memory::MemoryFiles;
use crate::load::FileResolver;
use crate::math::{Mat4, Transform, Vec3};
use crate::props::{Loc, Obj, SceneError, SourceFile, Value};
use std::cell::Cell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

type Result<T> = std::result::Result<T, SceneError>;

/// The material a shape gets.
#[derive(Clone, Debug)]
pub enum MaterialRef {
    /// pbrt's default (`diffuse` 0.5) or one from `Material`.
    Object(Rc<Obj>),
    /// `NamedMaterial`.
    Named(String, Loc),
}

/// The attributes `AttributeBegin` saves.
#[derive(Clone, Debug)]
pub struct Graphics {
    /// The current transform (object to world) at the start of the transform interval.
    pub ctm: Mat4,
    /// The current transform at its end: another than `ctm` where `ActiveTransform` animated
    /// it (the shapes that follow move: motion blur).
    pub ctm_end: Mat4,
    /// Which of the two the transform directives change (`ActiveTransform`): bit 0 the start,
    /// bit 1 the end.
    active: u8,
    /// `TransformTimes`: the times of the start and end transforms (0, 1).
    pub times: (f32, f32),
    /// `ReverseOrientation`.
    pub reverse: bool,
    /// The material.
    pub material: MaterialRef,
    /// `AreaLightSource` (its translated emitter properties).
    pub area_light: Option<Rc<ParamSet>>,
    /// `Attribute` defaults by target (`shape`, `light`, `material`, `medium`, `texture`): parameters the
    /// target's directives get when they do not give them.
    attributes: Rc<Vec<(String, Param)>>,
    /// `MediumInterface`: the media inside and outside the shapes that follow (the outside one
    /// at `Camera` is the camera's).
    pub inside: Option<String>,
    /// See `inside`.
    pub outside: Option<String>,
    /// Whether the transform block is a `TransformBegin` (only the transform is restored).
    transform_only: bool,
}

impl Graphics {
    /// Post-multiplies the active transforms by `m`.
    fn concat(&mut self, m: Mat4) {
        if self.active & 1 != 0 {
            self.ctm *= m;
        }
        if self.active & 2 != 0 {
            self.ctm_end *= m;
        }
    }

    /// Sets the active transforms to `m`.
    fn set(&mut self, m: Mat4) {
        if self.active & 1 != 0 {
            self.ctm = m;
        }
        if self.active & 2 != 0 {
            self.ctm_end = m;
        }
    }

    /// Whether the current transform moves (its start and end differ).
    pub fn moving(&self) -> bool {
        self.ctm != self.ctm_end
    }
}

/// The state of a pbrt-v4 file being read.
pub struct Parser {
    /// Where relative file names resolve (the main file's folder).
    pub resolver: FileResolver,
    /// Decoded meshes (`trianglemesh`, PLY files).
    pub memory: MemoryFiles,
    /// Warnings (things that cannot change the image).
    pub warnings: Vec<String>,
    pub(super) gs: Graphics,
    stack: Vec<Graphics>,
    named_coords: HashMap<String, (Mat4, Mat4)>,
    pub(super) named_materials: HashMap<String, Rc<Obj>>,
    /// How deeply each named material's objects nest (by the address of the material, which
    /// `named_materials` keeps alive): a mix of mixes of … is refused past
    /// [`MAX_MATERIAL_DEPTH`], before anything walks it recursively.
    material_depth: HashMap<*const Obj, usize>,
    pub(super) float_textures: HashMap<String, Rc<Obj>>,
    /// Named media (`MakeNamedMedium`).
    pub(super) media: HashMap<String, Rc<Obj>>,
    /// Whether a `subsurface` material was declared (its scattering needs `volpath`, pbrt-v4's
    /// default integrator, which neumann otherwise replaces by `path` where nothing differs).
    pub(super) subsurface: bool,
    /// The camera's medium (the outside medium at `Camera`).
    pub(super) camera_medium: Option<Rc<Obj>>,
    pub(super) spectrum_textures: HashMap<String, Rc<Obj>>,
    objects: HashMap<String, Vec<Rc<Obj>>>,
    current_object: Option<(String, Vec<Rc<Obj>>)>,
    pub(super) camera: Option<(ParamSet, Mat4)>,
    /// A moving camera's world-from-camera transform at the end, and the transform times.
    pub(super) camera_motion: Option<(Mat4, (f32, f32))>,
    pub(super) film: Option<ParamSet>,
    pub(super) sampler: Option<ParamSet>,
    pub(super) filter: Option<ParamSet>,
    pub(super) integrator: Option<ParamSet>,
    /// Parameters that follow an `Include` being parsed, for the included file's last
    /// parameter list (see `Cursor::tail`).
    include_tail: Option<Vec<Param>>,
    pub(super) shapes: Vec<Rc<Obj>>,
    pub(super) emitters: Vec<Rc<Obj>>,
    world: bool,
    files: usize,
    bytes: usize,
    pub(super) mesh_count: usize,
    /// Curve primitives made so far (each curve times 2^splitdepth), bounded by
    /// [`super::translate::MAX_CURVE_PIECES`].
    pub(super) curve_pieces: usize,
}

/// How deeply a material's objects may nest (mixes of mixes, maps of mixes): deeper ones are
/// a located error, as a hostile file could otherwise exhaust the stack of the recursive
/// walks that build them.
const MAX_MATERIAL_DEPTH: usize = 64;

/// The plugin type of a stand-in for a named material defined later in the file.
const NAMED_LATER: &str = "pbrt named material";

/// Objects already resolved by [`Parser::resolve_named`], by address: the object (kept alive)
/// and its result.
type ResolvedMemo = HashMap<*const Obj, (Rc<Obj>, Rc<Obj>)>;

/// A token cursor over one file.
struct Cursor<'a> {
    tokens: &'a [Token],
    pos: usize,
    file: Arc<SourceFile>,
    /// Parameters that follow this (included) file's `Include` in the files that include it:
    /// pbrt reads one stream of tokens across an `Include`, so a parameter list that ends this
    /// file goes on with them (pbrt-v4-scenes' smoke-plume gives its medium's coefficients
    /// after including the file that declares the medium). Taken by the parameter list that
    /// ends the file; `None` once taken or where there are none.
    tail: Option<Vec<Param>>,
}

impl Cursor<'_> {
    fn loc_at(&self, offset: usize) -> Loc {
        Loc { file: self.file.clone(), offset }
    }

    fn here(&self) -> Loc {
        self.loc_at(self.tokens.get(self.pos).map_or(self.file.text.len(), |t| t.offset))
    }

    fn err(&self, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.here(), message)
    }

    fn string(&mut self, what: &str) -> Result<String> {
        match self.tokens.get(self.pos) {
            Some(Token { kind: Kind::Str(s), .. }) => {
                self.pos += 1;
                Ok(s.clone())
            }
            Some(t) => Err(self.err(format!("expected {what} (a quoted string), found {}", t.kind.describe()))),
            None => Err(self.err(format!("expected {what} (a quoted string), found the end of the file"))),
        }
    }

    fn number(&mut self, what: &str) -> Result<f64> {
        match self.tokens.get(self.pos) {
            Some(Token { kind: Kind::Num(n), .. }) => {
                self.pos += 1;
                Ok(*n)
            }
            Some(t) => Err(self.err(format!("expected {what} (a number), found {}", t.kind.describe()))),
            None => Err(self.err(format!("expected {what} (a number), found the end of the file"))),
        }
    }

    /// `n` numbers, optionally in brackets.
    fn numbers(&mut self, n: usize, what: &str) -> Result<Vec<f64>> {
        let bracket = matches!(self.tokens.get(self.pos), Some(Token { kind: Kind::Open, .. }));
        if bracket {
            self.pos += 1;
        }
        let v = (0..n).map(|_| self.number(what)).collect::<Result<Vec<_>>>()?;
        if bracket {
            match self.tokens.get(self.pos) {
                Some(Token { kind: Kind::Close, .. }) => self.pos += 1,
                _ => return Err(self.err(format!("expected ']' after the {n} numbers of {what}"))),
            }
        }
        Ok(v)
    }

    /// The parameter list that follows a directive.
    fn params(&mut self, what: String, loc: Loc) -> Result<ParamSet> {
        let mut params: Vec<Param> = Vec::new();
        while let Some(Token { kind: Kind::Str(decl), offset }) = self.tokens.get(self.pos) {
            let ploc = self.loc_at(*offset);
            let mut words = decl.split_whitespace();
            let (Some(ty), Some(name), None) = (words.next(), words.next(), words.next()) else {
                return Err(SceneError::at(
                    &ploc,
                    format!("expected a parameter declaration \"type name\", found \"{decl}\""),
                ));
            };
            const TYPES: &[&str] = &[
                "integer",
                "float",
                "point2",
                "vector2",
                "point3",
                "vector3",
                "normal3",
                "point",
                "vector",
                "normal",
                "rgb",
                "color",
                "spectrum",
                "blackbody",
                "bool",
                "string",
                "texture",
            ];
            if !TYPES.contains(&ty) {
                let hint = crate::choice::nearest(ty, TYPES.iter().copied())
                    .map(|n| format!("; the nearest is '{n}'"))
                    .unwrap_or_default();
                return Err(SceneError::at(
                    &ploc,
                    format!("unknown parameter type '{ty}' (types: {}{hint})", TYPES.join(", ")),
                ));
            }
            if params.iter().any(|p| p.name == name) {
                return Err(SceneError::at(&ploc, format!("parameter '{name}' is given twice")));
            }
            self.pos += 1;
            let mut values = Vec::new();
            let value = |t: &Token| -> Option<PVal> {
                match &t.kind {
                    Kind::Num(n) => Some(PVal::Num(*n)),
                    Kind::Str(s) => Some(PVal::Str(s.clone())),
                    Kind::Ident(b) if b == "true" || b == "false" => Some(PVal::Bool(b == "true")),
                    _ => None,
                }
            };
            match self.tokens.get(self.pos) {
                Some(Token { kind: Kind::Open, .. }) => {
                    self.pos += 1;
                    loop {
                        match self.tokens.get(self.pos) {
                            Some(Token { kind: Kind::Close, .. }) => {
                                self.pos += 1;
                                break;
                            }
                            Some(t) => match value(t) {
                                Some(v) => {
                                    values.push(v);
                                    self.pos += 1;
                                }
                                None => {
                                    return Err(
                                        self.err(format!("expected a value or ']', found {}", t.kind.describe()))
                                    )
                                }
                            },
                            None => return Err(self.err("expected ']' before the end of the file")),
                        }
                    }
                }
                Some(t) => match value(t) {
                    Some(v) => {
                        values.push(v);
                        self.pos += 1;
                    }
                    None => {
                        return Err(self.err(format!("expected the value of \"{decl}\", found {}", t.kind.describe())))
                    }
                },
                None => return Err(self.err(format!("expected the value of \"{decl}\""))),
            }
            let mixed =
                values.iter().any(|v| matches!(v, PVal::Num(_))) && values.iter().any(|v| !matches!(v, PVal::Num(_)));
            if values.is_empty() || mixed {
                return Err(SceneError::at(&ploc, format!("\"{decl}\" needs values of one kind")));
            }
            params.push(Param { ty: ty.into(), name: name.into(), values, loc: ploc, used: Cell::new(false) });
        }
        if self.pos == self.tokens.len() {
            for p in self.tail.take().unwrap_or_default() {
                if params.iter().any(|q| q.name == p.name) {
                    return Err(SceneError::at(&p.loc, format!("parameter '{}' is given twice", p.name)));
                }
                params.push(p);
            }
        }
        Ok(ParamSet { params, loc, what })
    }
}

impl Parser {
    /// Reads the spectrum files a parameter list names: a `spectrum` parameter whose value is
    /// one string that is not one of pbrt-v4's named spectra names a file of `wavelength value`
    /// pairs (whitespace-separated, `#` comments; pbrt-v4's `PiecewiseLinearSpectrum::Read`),
    /// looked for as other files are, and becomes those pairs, as if written inline.
    fn spectrum_files(&self, mut ps: ParamSet) -> Result<ParamSet> {
        for p in ps.params.iter_mut().filter(|p| p.ty == "spectrum") {
            let [PVal::Str(name)] = &p.values[..] else { continue };
            if translate::is_named_spectrum(name) {
                continue;
            }
            let path = self.resolver.resolve(name);
            let text = crate::load::limits::read_text(&path).map_err(|e| {
                SceneError::at(
                    &p.loc,
                    format!("\"spectrum {}\": \"{name}\" is neither one of pbrt-v4's named spectra nor a readable spectrum file: {e}", p.name),
                )
            })?;
            let samples = parse_spectrum_file(&text)
                .map_err(|m| SceneError::at(&p.loc, format!("spectrum file {}: {m}", path.display())))?;
            p.values = samples.into_iter().flat_map(|(l, v)| [PVal::Num(l), PVal::Num(v)]).collect();
        }
        Ok(ps)
    }

    /// A parser for the scene file `path`.
    pub fn new(path: &Path) -> Parser {
        let default_material = Rc::new(translate::default_material());
        Parser {
            resolver: FileResolver::for_scene(path),
            memory: MemoryFiles::default(),
            warnings: Vec::new(),
            gs: Graphics {
                ctm: Mat4::IDENTITY,
                ctm_end: Mat4::IDENTITY,
                active: 0b11,
                times: (0.0, 1.0),
                reverse: false,
                material: MaterialRef::Object(default_material),
                area_light: None,
                attributes: Rc::new(Vec::new()),
                inside: None,
                outside: None,
                transform_only: false,
            },
            stack: Vec::new(),
            named_coords: HashMap::new(),
            named_materials: HashMap::new(),
            material_depth: HashMap::new(),
            float_textures: HashMap::new(),
            media: HashMap::new(),
            subsurface: false,
            camera_medium: None,
            spectrum_textures: HashMap::new(),
            objects: HashMap::new(),
            current_object: None,
            camera: None,
            camera_motion: None,
            film: None,
            sampler: None,
            filter: None,
            integrator: None,
            include_tail: None,
            shapes: Vec::new(),
            emitters: Vec::new(),
            world: false,
            files: 0,
            bytes: 0,
            mesh_count: 0,
            curve_pieces: 0,
        }
    }

    /// Reads and executes the file `path` (and what it includes).
    pub fn parse_file(&mut self, path: &Path, from: Option<&Loc>) -> Result<()> {
        self.files += 1;
        if self.files > limits::MAX_INCLUDES {
            return Err(SceneError::new(format!(
                "{}: more than {} included files",
                path.display(),
                limits::MAX_INCLUDES
            )));
        }
        let located = |m: String| match from {
            Some(l) => SceneError::at(l, m),
            None => SceneError::new(m),
        };
        let bytes = limits::read_bounded(path, limits::MAX_FILE_BYTES).map_err(|e| located(e.to_string()))?;
        let bytes = super::mesh::gunzip_if_compressed(path, bytes, limits::MAX_SCENE_BYTES as u64).map_err(located)?;
        self.bytes += bytes.len();
        if self.bytes > limits::MAX_SCENE_BYTES {
            return Err(located(format!(
                "{}: the scene's files exceed {} bytes",
                path.display(),
                limits::MAX_SCENE_BYTES
            )));
        }
        let text = String::from_utf8(bytes).map_err(|e| located(format!("{}: not UTF-8 text: {e}", path.display())))?;
        self.parse_text(path.to_path_buf(), text)
    }

    /// Executes the directives of `text` (named `path` in messages).
    pub fn parse_text(&mut self, path: PathBuf, text: String) -> Result<()> {
        let file = Arc::new(SourceFile { path, text });
        let tokens =
            tokenize(&file.text).map_err(|(offset, m)| SceneError::at(&Loc { file: file.clone(), offset }, m))?;
        let mut c = Cursor { tokens: &tokens, pos: 0, file: file.clone(), tail: self.include_tail.take() };
        while c.pos < tokens.len() {
            self.directive(&mut c)?;
        }
        match c.tail.and_then(|t| t.into_iter().next()) {
            // pbrt would read them as the next directive: the file does not end with one that
            // takes parameters.
            Some(p) => Err(SceneError::at(
                &p.loc,
                format!(
                    "expected a directive, found the parameter \"{} {}\" (the included file {} does not end with a directive that takes parameters)",
                    p.ty,
                    p.name,
                    file.path.display()
                ),
            )),
            None => Ok(()),
        }
    }

    fn directive(&mut self, c: &mut Cursor) -> Result<()> {
        let t = &c.tokens[c.pos];
        let loc = c.loc_at(t.offset);
        let Kind::Ident(name) = &t.kind else {
            return Err(c.err(format!("expected a directive, found {}", t.kind.describe())));
        };
        let name = name.clone();
        c.pos += 1;
        match name.as_str() {
            "Translate" => {
                let v = c.numbers(3, "Translate's x y z")?;
                self.gs.concat(Mat4::from_translation(vec3(&v)));
            }
            "Scale" => {
                let v = c.numbers(3, "Scale's x y z")?;
                self.gs.concat(Mat4::from_scale(vec3(&v)));
            }
            "Rotate" => {
                let v = c.numbers(4, "Rotate's angle x y z")?;
                let axis = vec3(&v[1..]);
                if axis.length_squared() == 0.0 {
                    return Err(SceneError::at(&loc, "Rotate: the axis is zero"));
                }
                self.gs.concat(Mat4::from_axis_angle(axis.normalize(), (v[0] as f32).to_radians()));
            }
            "LookAt" => {
                let v = c.numbers(9, "LookAt's eye, look and up points")?;
                let (eye, look, up) = (vec3(&v[0..3]), vec3(&v[3..6]), vec3(&v[6..9]));
                // pbrt's LookAt: the camera-from-world transform whose camera looks down +z.
                let t = Transform::look_at(eye, look, up).ok_or_else(|| {
                    SceneError::at(&loc, "LookAt: the eye and look points coincide, or up is parallel to the view")
                })?;
                self.gs.concat(*t.inverse_matrix());
            }
            "Transform" | "ConcatTransform" => {
                let v = c.numbers(16, &format!("{name}'s 16 matrix entries"))?;
                let m: [f32; 16] = std::array::from_fn(|i| v[i] as f32);
                // pbrt lists the matrix by columns (it transposes what it reads).
                let m = Mat4::from_cols_array(&m);
                if !m.is_finite() {
                    return Err(SceneError::at(&loc, format!("{name}: the matrix is not finite")));
                }
                if name == "Transform" {
                    self.gs.set(m);
                } else {
                    self.gs.concat(m);
                }
            }
            "CoordinateSystem" => {
                let n = c.string("the coordinate system's name")?;
                self.named_coords.insert(n, (self.gs.ctm, self.gs.ctm_end));
            }
            "CoordSysTransform" => {
                let n = c.string("the coordinate system's name")?;
                match self.named_coords.get(&n) {
                    Some(&(start, end)) => (self.gs.ctm, self.gs.ctm_end) = (start, end),
                    None => {
                        let names: Vec<&str> = self.named_coords.keys().map(String::as_str).collect();
                        return Err(SceneError::at(
                            &loc,
                            format!(
                                "CoordSysTransform: no coordinate system named \"{n}\" (defined: {})",
                                if names.is_empty() { "none".into() } else { names.join(", ") }
                            ),
                        ));
                    }
                }
            }
            "ReverseOrientation" => self.gs.reverse = !self.gs.reverse,
            "Identity" => self.gs.set(Mat4::IDENTITY),
            "ActiveTransform" => {
                let Some(Token { kind: Kind::Ident(which), .. }) = c.tokens.get(c.pos) else {
                    return Err(c.err("expected StartTime, EndTime or All after ActiveTransform"));
                };
                c.pos += 1;
                self.gs.active = match which.as_str() {
                    "All" => 0b11,
                    "StartTime" => 0b01,
                    "EndTime" => 0b10,
                    other => return Err(SceneError::at(&loc, format!("ActiveTransform {other}: expected StartTime, EndTime or All"))),
                };
            }
            "TransformTimes" => {
                let v = c.numbers(2, "TransformTimes' start and end")?;
                let (t0, t1) = (v[0] as f32, v[1] as f32);
                if !(t0 <= t1 && t0.is_finite() && t1.is_finite()) {
                    return Err(SceneError::at(&loc, format!("TransformTimes: need start ≤ end, got {t0} and {t1}")));
                }
                self.gs.times = (t0, t1);
            }
            "AttributeBegin" | "TransformBegin" => {
                if self.stack.len() >= limits::MAX_NESTING * 8 {
                    return Err(SceneError::at(&loc, "attribute blocks nest too deeply"));
                }
                let mut saved = self.gs.clone();
                saved.transform_only = name == "TransformBegin";
                self.stack.push(saved);
            }
            "AttributeEnd" | "TransformEnd" => {
                let Some(saved) = self.stack.pop() else {
                    return Err(SceneError::at(
                        &loc,
                        format!("{name} without a matching {}", name.replace("End", "Begin")),
                    ));
                };
                if saved.transform_only != (name == "TransformEnd") {
                    return Err(SceneError::at(
                        &loc,
                        format!("{name} closes a block opened by the other kind of Begin"),
                    ));
                }
                if saved.transform_only {
                    (self.gs.ctm, self.gs.ctm_end, self.gs.active) = (saved.ctm, saved.ctm_end, saved.active);
                } else {
                    self.gs = saved;
                }
            }
            "Option" => {
                let ps = c.params("Option".into(), loc)?;
                translate::option(self, &ps)?;
            }
            "ColorSpace" => {
                let n = c.string("the color space's name")?;
                if n != "srgb" {
                    return Err(SceneError::at(
                        &loc,
                        format!("ColorSpace \"{n}\": neumann renders in linear sRGB only (\"srgb\")"),
                    ));
                }
            }
            "Camera" => {
                let ty = c.string("the camera type")?;
                let ps = c.params(format!("Camera \"{ty}\""), loc.clone())?;
                if self.world {
                    return Err(SceneError::at(&loc, "Camera must come before WorldBegin"));
                }
                // pbrt names the camera's space "camera". A moving transform (ActiveTransform)
                // moves the camera: pbrt-v4 interpolates its world-from-camera transform.
                let world_from_camera = self.gs.ctm.inverse();
                let world_from_camera_end = self.gs.ctm_end.inverse();
                if !(world_from_camera.is_finite() && world_from_camera_end.is_finite()) {
                    return Err(SceneError::at(&loc, "Camera: the current transform is singular"));
                }
                self.named_coords.insert("camera".into(), (world_from_camera, world_from_camera_end));
                self.camera_motion = self.gs.moving().then_some((world_from_camera_end, self.gs.times));
                let mut ps = ps;
                ps.params.push(type_param(&ty, &loc));
                self.camera = Some((ps, world_from_camera));
                self.camera_medium = self.gs.outside.as_ref().and_then(|n| self.media.get(n).cloned());
            }
            "Film" | "Sampler" | "PixelFilter" | "Integrator" | "Accelerator" => {
                let ty = c.string(&format!("the {name} type"))?;
                let mut ps = c.params(format!("{name} \"{ty}\""), loc.clone())?;
                if self.world {
                    return Err(SceneError::at(&loc, format!("{name} must come before WorldBegin")));
                }
                ps.params.push(type_param(&ty, &loc));
                match name.as_str() {
                    "Film" => self.film = Some(ps),
                    "Sampler" => self.sampler = Some(ps),
                    "PixelFilter" => self.filter = Some(ps),
                    "Integrator" => self.integrator = Some(ps),
                    // The acceleration structure cannot change the image.
                    _ => {
                        for p in &ps.params {
                            p.used.set(true);
                        }
                    }
                }
            }
            "WorldBegin" => {
                if self.world {
                    return Err(SceneError::at(&loc, "WorldBegin appears twice"));
                }
                self.world = true;
                (self.gs.ctm, self.gs.ctm_end, self.gs.active) = (Mat4::IDENTITY, Mat4::IDENTITY, 0b11);
                self.named_coords.insert("world".into(), (Mat4::IDENTITY, Mat4::IDENTITY));
            }
            "WorldEnd" => {}
            "MakeNamedMedium" => {
                let medium = c.string("the medium's name")?;
                let mut ps = self.spectrum_files(c.params(format!("MakeNamedMedium \"{medium}\""), loc.clone())?)?;
                self.with_attributes(&mut ps, "medium");
                let obj = translate::medium(self, &ps)?;
                ps.check_unused()?;
                self.media.insert(medium, Rc::new(obj));
            }
            "MediumInterface" => {
                let inside = c.string("the inside medium's name")?;
                // One name: the same medium on both sides.
                let outside = match c.tokens.get(c.pos) {
                    Some(Token { kind: Kind::Str(_), .. }) => c.string("the outside medium's name")?,
                    _ => inside.clone(),
                };
                for n in [&inside, &outside] {
                    if !n.is_empty() && !self.media.contains_key(n) {
                        return Err(SceneError::at(
                            &loc,
                            format!("MediumInterface: no medium named \"{n}\" (MakeNamedMedium defines them)"),
                        ));
                    }
                }
                self.gs.inside = (!inside.is_empty()).then_some(inside);
                self.gs.outside = (!outside.is_empty()).then_some(outside);
            }
            "Attribute" => {
                let target = c.string("the attribute's target (shape, light, material, medium, texture)")?;
                let ps = self.spectrum_files(c.params(format!("Attribute \"{target}\""), loc.clone())?)?;
                const TARGETS: &[&str] = &["shape", "light", "material", "medium", "texture"];
                if !TARGETS.contains(&target.as_str()) {
                    return Err(ps.unknown("attribute target", &target, TARGETS));
                }
                let mut list: Vec<(String, Param)> =
                    self.gs.attributes.iter().map(|(t, p)| (t.clone(), p.clone())).collect();
                for p in ps.params {
                    list.retain(|(t, q)| !(*t == target && q.name == p.name));
                    list.push((target.clone(), p));
                }
                self.gs.attributes = Rc::new(list);
            }
            "Texture" => {
                let tex_name = c.string("the texture's name")?;
                let class = c.string("the texture's type (\"spectrum\" or \"float\")")?;
                let ty = c.string("the texture's class (imagemap, checkerboard, …)")?;
                let mut ps = self
                    .spectrum_files(c.params(format!("Texture \"{tex_name}\" \"{class}\" \"{ty}\""), loc.clone())?)?;
                self.with_attributes(&mut ps, "texture");
                let obj = translate::texture(self, &ty, &class, &ps)?;
                ps.check_unused()?;
                match class.as_str() {
                    "float" => self.float_textures.insert(tex_name, Rc::new(obj)),
                    "spectrum" | "color" => self.spectrum_textures.insert(tex_name, Rc::new(obj)),
                    other => {
                        return Err(SceneError::at(
                            &loc,
                            format!("Texture type \"{other}\": expected \"spectrum\" or \"float\""),
                        ))
                    }
                };
            }
            "Material" => {
                let ty = c.string("the material type")?;
                let mut ps = self.spectrum_files(c.params(format!("Material \"{ty}\""), loc.clone())?)?;
                self.with_attributes(&mut ps, "material");
                let obj = translate::material(self, &ty, &ps)?;
                ps.check_unused()?;
                self.material_depth_of(&obj, &loc)?;
                self.gs.material = MaterialRef::Object(Rc::new(obj));
            }
            "MakeNamedMaterial" => {
                let mat = c.string("the material's name")?;
                let mut ps = self.spectrum_files(c.params(format!("MakeNamedMaterial \"{mat}\""), loc.clone())?)?;
                self.with_attributes(&mut ps, "material");
                let ty = ps.string("type")?.ok_or_else(|| ps.error("needs its \"string type\""))?;
                if self.named_materials.contains_key(&mat) {
                    // pbrt-v4 refuses a second definition too ("named material redefined").
                    return Err(SceneError::at(&loc, format!("MakeNamedMaterial: \"{mat}\" is defined twice")));
                }
                let obj = translate::material(self, &ty, &ps)?;
                ps.check_unused()?;
                let depth = self.material_depth_of(&obj, &loc)?;
                let obj = Rc::new(obj);
                self.material_depth.insert(Rc::as_ptr(&obj), depth);
                self.named_materials.insert(mat, obj);
            }
            "NamedMaterial" => {
                let mat = c.string("the material's name")?;
                self.gs.material = MaterialRef::Named(mat, loc);
            }
            "LightSource" => {
                let ty = c.string("the light type")?;
                let mut ps = self.spectrum_files(c.params(format!("LightSource \"{ty}\""), loc.clone())?)?;
                self.with_attributes(&mut ps, "light");
                let obj = translate::light(self, &ty, &ps)?;
                ps.check_unused()?;
                self.emitters.push(Rc::new(obj));
            }
            "AreaLightSource" => {
                let ty = c.string("the area light type")?;
                let ps = self.spectrum_files(c.params(format!("AreaLightSource \"{ty}\""), loc.clone())?)?;
                if ty != "diffuse" {
                    return Err(ps.error("the only area light is \"diffuse\""));
                }
                self.gs.area_light = Some(Rc::new(ps));
            }
            "Shape" => {
                let ty = c.string("the shape type")?;
                let mut ps = self.spectrum_files(c.params(format!("Shape \"{ty}\""), loc.clone())?)?;
                self.with_attributes(&mut ps, "shape");
                let shapes = translate::shape(self, &ty, &ps)?;
                ps.check_unused()?;
                if let Some(al) = &self.gs.area_light {
                    al.check_unused()?;
                }
                match &mut self.current_object {
                    Some((_, list)) => list.extend(shapes),
                    None => self.shapes.extend(shapes),
                }
            }
            "ObjectBegin" => {
                let n = c.string("the object's name")?;
                if self.current_object.is_some() {
                    return Err(SceneError::at(&loc, "ObjectBegin inside another object"));
                }
                self.stack.push(Graphics { transform_only: false, ..self.gs.clone() });
                self.current_object = Some((n, Vec::new()));
            }
            "ObjectEnd" => {
                let Some((n, list)) = self.current_object.take() else {
                    return Err(SceneError::at(&loc, "ObjectEnd without ObjectBegin"));
                };
                self.objects.insert(n, list);
                if let Some(saved) = self.stack.pop() {
                    self.gs = saved;
                }
            }
            "ObjectInstance" => {
                let n = c.string("the object's name")?;
                let Some(list) = self.objects.get(&n) else {
                    return Err(SceneError::at(
                        &loc,
                        format!("ObjectInstance: no object named \"{n}\" (ObjectBegin defines them)"),
                    ));
                };
                if self.gs.moving() {
                    // pbrt-v4's animated instance: the object's shapes, each placed in the
                    // instance's space by its own transform, moved together by the instance's
                    // transform interpolated at each ray's time (an `instance` of a
                    // `shapegroup` with `to_world_end`, as the XML builder reads it).
                    let placed = |m: Mat4| {
                        Transform::from_matrix(m)
                            .ok_or_else(|| SceneError::at(&loc, "ObjectInstance: the current transform is singular"))
                    };
                    let (start, end) = (placed(self.gs.ctm)?, placed(self.gs.ctm_end)?);
                    let mut group = Obj::new("shape", "shapegroup", loc.clone());
                    group.children = list.clone();
                    let mut instance = Obj::new("shape", "instance", loc.clone());
                    let (t0, t1) = self.gs.times;
                    instance.set("to_world", Value::Transform(start), loc.clone());
                    instance.set("to_world_end", Value::Transform(end), loc.clone());
                    instance.set("motion_start", Value::Float(f64::from(t0)), loc.clone());
                    instance.set("motion_end", Value::Float(f64::from(t1)), loc.clone());
                    instance.children.push(Rc::new(group));
                    self.shapes.push(Rc::new(instance));
                } else {
                    let instance = self.gs.ctm;
                    let copies: Vec<Rc<Obj>> = list.iter().map(|o| Rc::new(translate::placed(o, &instance))).collect();
                    self.shapes.extend(copies);
                }
            }
            "Include" | "Import" => {
                let f = c.string("the file name")?;
                let path = self.resolver.resolve(&f);
                // Parameters after the file name continue the included file's last parameter
                // list (pbrt's one token stream); where this file ends there too, so do the
                // parameters that follow it in its own includer.
                // (An imported file is parsed apart in pbrt-v4: nothing runs on from it.)
                let tail = c.params(format!("{name} \"{f}\""), loc.clone())?.params;
                if name == "Import" {
                    if let Some(p) = tail.first() {
                        return Err(SceneError::at(&p.loc, "Import takes no parameters (an imported file is parsed apart)"));
                    }
                }
                self.include_tail = (!tail.is_empty()).then_some(tail);
                // An imported file adds shapes and named things but cannot change the
                // importer's graphics state (pbrt-v4 parses it apart); an included one can.
                let saved = (name == "Import").then(|| self.gs.clone());
                let parsed = self.parse_file(&path, Some(&loc));
                self.include_tail = None;
                parsed?;
                if let Some(gs) = saved {
                    self.gs = gs;
                }
            }
            "MakeNamedCamera" | "CameraBegin" => {
                return Err(SceneError::at(&loc, format!("{name} is not a pbrt-v4 directive")));
            }
            other => {
                const DIRECTIVES: &[&str] = &[
                    "Translate",
                    "Scale",
                    "Rotate",
                    "LookAt",
                    "Transform",
                    "ConcatTransform",
                    "CoordinateSystem",
                    "CoordSysTransform",
                    "ReverseOrientation",
                    "Identity",
                    "ActiveTransform",
                    "TransformTimes",
                    "AttributeBegin",
                    "AttributeEnd",
                    "TransformBegin",
                    "TransformEnd",
                    "Option",
                    "ColorSpace",
                    "Camera",
                    "Film",
                    "Sampler",
                    "PixelFilter",
                    "Integrator",
                    "Accelerator",
                    "WorldBegin",
                    "MakeNamedMedium",
                    "MediumInterface",
                    "Attribute",
                    "Texture",
                    "Material",
                    "MakeNamedMaterial",
                    "NamedMaterial",
                    "LightSource",
                    "AreaLightSource",
                    "Shape",
                    "ObjectBegin",
                    "ObjectEnd",
                    "ObjectInstance",
                    "Include",
                    "Import",
                ];
                let hint = crate::choice::nearest(other, DIRECTIVES.iter().copied())
                    .map(|n| format!(" (the nearest is '{n}')"))
                    .unwrap_or_default();
                return Err(SceneError::at(&loc, format!("unknown directive '{other}'{hint}")));
            }
        }
        Ok(())
    }

    /// Adds the `Attribute` defaults of `target` that `ps` does not give (they are read by the
    /// plugins that take them and ignored by the others).
    fn with_attributes(&self, ps: &mut ParamSet, target: &str) {
        for (t, p) in self.gs.attributes.iter() {
            if t == target && !ps.has(&p.name) {
                // A default for every shape (say) need not apply to each: never "unused".
                let p = p.clone();
                p.used.set(true);
                ps.params.push(p);
            }
        }
    }

    /// The material object shapes get now.
    pub(super) fn current_material(&self) -> Rc<Obj> {
        match &self.gs.material {
            MaterialRef::Object(o) => o.clone(),
            MaterialRef::Named(n, loc) => self.named_material(n, loc),
        }
    }

    /// How deeply `o`'s objects nest (1 for a plugin without nested ones), the named materials
    /// in it counted as recorded; an error at `loc` past [`MAX_MATERIAL_DEPTH`].
    fn material_depth_of(&self, o: &Obj, loc: &Loc) -> Result<usize> {
        fn depth(p: &Parser, o: &Obj) -> usize {
            1 + o
                .children
                .iter()
                .map(|c| p.material_depth.get(&Rc::as_ptr(c)).copied().unwrap_or_else(|| depth(p, c)))
                .max()
                .unwrap_or(0)
        }
        let d = depth(self, o);
        if d > MAX_MATERIAL_DEPTH {
            return Err(SceneError::at(
                loc,
                format!("this material nests {d} deep (mixes of mixes …), more than {MAX_MATERIAL_DEPTH}"),
            ));
        }
        Ok(d)
    }

    /// The named material `name`, or, where it is not defined yet, a stand-in that
    /// [`Parser::resolve_named`] replaces once the whole file is read: pbrt-v4 creates named
    /// materials after parsing, so `NamedMaterial` (and a `mix`) may name one defined further
    /// on (pbrt-v4-scenes' `contemporary-bathroom` uses its materials before including them).
    pub(super) fn named_material(&self, name: &str, loc: &Loc) -> Rc<Obj> {
        match self.named_materials.get(name) {
            Some(m) => m.clone(),
            None => {
                let mut o = Obj::new("bsdf", NAMED_LATER, loc.clone());
                o.set("name", crate::props::Value::String(name.into()), loc.clone());
                Rc::new(o)
            }
        }
    }

    /// Replaces the stand-ins inside the named materials themselves (a `mix` of materials
    /// defined after it) by [`Parser::resolve_named`], then those in `shapes`.
    pub(super) fn resolve_named_materials(&mut self, shapes: Vec<Rc<Obj>>) -> Result<Vec<Rc<Obj>>> {
        let mut memo = ResolvedMemo::new();
        let mut names: Vec<String> = self.named_materials.keys().cloned().collect();
        names.sort();
        for n in names {
            let m = self.named_materials[&n].clone();
            let resolved = self.resolve_named(&m, 0, &mut memo)?;
            self.named_materials.insert(n, resolved);
        }
        shapes.iter().map(|s| self.resolve_named(s, 0, &mut memo)).collect()
    }

    /// `o` with every stand-in of [`Parser::named_material`] replaced by the material of that
    /// name (the object itself where it holds none); an error names the first that is
    /// defined nowhere, or a cycle of mixes. Each object is resolved once (`memo`): materials
    /// shared by many shapes and mixes stay shared, and nested mixes cost their number, not
    /// the paths through them.
    fn resolve_named(&self, o: &Rc<Obj>, depth: usize, memo: &mut ResolvedMemo) -> Result<Rc<Obj>> {
        if let Some((_, r)) = memo.get(&Rc::as_ptr(o)) {
            return Ok(r.clone());
        }
        let resolved = if o.ty == NAMED_LATER && o.tag == "bsdf" {
            let name = match o.props.first().map(|p| &p.value) {
                Some(crate::props::Value::String(n)) => n.clone(),
                _ => unreachable!("a stand-in holds its name"),
            };
            let Some(m) = self.named_materials.get(&name) else {
                return Err(SceneError::at(
                    &o.loc,
                    format!("no material named \"{name}\" (MakeNamedMaterial defines them)"),
                ));
            };
            if depth > MAX_MATERIAL_DEPTH {
                return Err(SceneError::at(
                    &o.loc,
                    format!(
                        "the named material \"{name}\" contains itself, or nests more than {MAX_MATERIAL_DEPTH} deep"
                    ),
                ));
            }
            self.resolve_named(&m.clone(), depth + 1, memo)?
        } else {
            let mut children = Vec::with_capacity(o.children.len());
            let mut changed = false;
            for c in &o.children {
                let r = self.resolve_named(c, depth, memo)?;
                changed |= !Rc::ptr_eq(&r, c);
                children.push(r);
            }
            if changed {
                let props =
                    o.props.iter().map(|p| crate::props::Prop::new(&p.name, p.value.clone(), p.loc.clone())).collect();
                Rc::new(Obj { props, children, id: o.id.clone(), ..Obj::new(&o.tag, &o.ty, o.loc.clone()) })
            } else {
                o.clone()
            }
        };
        // The input is kept alive beside its result, so that its address names it alone.
        memo.insert(Rc::as_ptr(o), (o.clone(), resolved.clone()));
        Ok(resolved)
    }

    /// Checks the end state: balanced blocks, a camera.
    pub(super) fn finish_checks(&self, file: &Arc<SourceFile>) -> Result<()> {
        let end = Loc { file: file.clone(), offset: file.text.len() };
        if self.current_object.is_some() {
            return Err(SceneError::at(&end, "ObjectBegin without ObjectEnd"));
        }
        if !self.world {
            return Err(SceneError::at(&end, "the file has no WorldBegin"));
        }
        Ok(())
    }
}

fn vec3(v: &[f64]) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// The directive's plugin type as a parameter (read by the translator).
fn type_param(ty: &str, loc: &Loc) -> Param {
    Param {
        ty: "string".into(),
        name: "__type".into(),
        values: vec![PVal::Str(ty.into())],
        loc: loc.clone(),
        used: Cell::new(false),
    }
}

/// The (wavelength, value) pairs of a spectrum file: numbers separated by white space, `#`
/// comments to the end of a line, an even count, wavelengths increasing (pbrt-v4's rules).
fn parse_spectrum_file(text: &str) -> std::result::Result<Vec<(f64, f64)>, String> {
    let mut nums = Vec::new();
    for (i, line) in text.lines().enumerate() {
        for word in line.split('#').next().unwrap_or("").split_whitespace() {
            match word.parse::<f64>() {
                Ok(x) if x.is_finite() => nums.push(x),
                _ => return Err(format!("line {}: expected a number, found {word:?}", i + 1)),
            }
        }
    }
    if nums.is_empty() || nums.len() % 2 != 0 {
        return Err(format!("expected (wavelength, value) pairs, found {} numbers", nums.len()));
    }
    let pairs: Vec<(f64, f64)> = nums.chunks(2).map(|c| (c[0], c[1])).collect();
    if let Some(w) = pairs.windows(2).find(|w| w[1].0 <= w[0].0) {
        return Err(format!("wavelengths must increase: {} nm follows {} nm", w[1].0, w[0].0));
    }
    Ok(pairs)
}
