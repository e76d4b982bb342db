//! Mitsuba 3 XML to a tree of plugin objects with typed, located properties.
//!
//! Handled here: `<default>` and `$name` substitution (command-line `-D` values win over
//! defaults), `<include>`, `<alias>`, `id` / `<ref>`, nested objects (named: a property; unnamed: a
//! child), and the property elements `float`, `integer`, `boolean`, `string`, `rgb`, `spectrum`,
//! `point`, `vector` and `transform` (with `translate`, `rotate`, `scale`, `matrix`, `lookat`
//! applied in document order, each left-multiplying the ones before, as Mitsuba does).

use crate::load::limits;
use crate::load::FileResolver;
use crate::math::{Mat4, Rgb, Transform, Vec3, Vec4};
use crate::props::{nearest, Loc, Obj, Prop, SceneError, SourceFile, SpectrumValue, Value, OBJECT_TAGS};
use std::cell::Cell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

type Result<T> = std::result::Result<T, SceneError>;

/// The element names that are properties.
const PROPERTY_TAGS: &[&str] =
    &["float", "integer", "boolean", "string", "rgb", "spectrum", "point", "vector", "transform"];

/// Parses scene files.
pub struct Parser {
    /// Parameter values: `-D` overrides, then `<default>`s.
    params: HashMap<String, String>,
    /// Names given on the command line (defaults do not replace them).
    overridden: Vec<String>,
    /// Objects by id.
    ids: HashMap<String, Rc<Obj>>,
    /// Parameter names that a `$name` substituted.
    used_params: std::cell::RefCell<std::collections::HashSet<String>>,
    depth: usize,
    /// Scene files included so far, and the bytes of scene text read (bounded by
    /// [`limits::MAX_INCLUDES`] and [`limits::MAX_SCENE_BYTES`]).
    includes: usize,
    scene_bytes: usize,
    /// Objects open around the one being read (bounded by [`limits::MAX_NESTING`]).
    nesting: usize,
    /// Where relative file names are looked for (Mitsuba's file resolver: `<path>` folders, the
    /// main scene's folder, the working directory).
    pub resolver: FileResolver,
    /// `<alias>`es whose target id was not declared yet: (alias, id, where), bound at the end.
    aliases: Vec<(String, String, Loc)>,
    /// For each document being parsed, whether its `version` is older than 2.0.0 (Mitsuba 0.x),
    /// which Mitsuba upgrades as it reads (see [`Parser::upgraded_name`]).
    legacy: Vec<bool>,
    /// The `name`s of objects placed directly in the scene (its files and the files they
    /// include): Mitsuba's scene takes every nested object whatever its name (the Blender
    /// exporter names them all), so a name there only has to be unique.
    scene_names: HashMap<String, Loc>,
    /// What the file does that Mitsuba reads in a way its author may not expect (formatted
    /// messages, each with its position), for the loaded scene's warnings.
    pub warnings: std::cell::RefCell<Vec<String>>,
}

impl Parser {
    /// A parser with command-line parameter overrides (`-D name=value`).
    pub fn new(overrides: &[(String, String)]) -> Parser {
        Parser {
            params: overrides.iter().cloned().collect(),
            overridden: overrides.iter().map(|(k, _)| k.clone()).collect(),
            ids: HashMap::new(),
            used_params: Default::default(),
            depth: 0,
            includes: 0,
            scene_bytes: 0,
            nesting: 0,
            resolver: FileResolver::default(),
            aliases: Vec::new(),
            legacy: Vec::new(),
            scene_names: HashMap::new(),
            warnings: Default::default(),
        }
    }

    /// The command-line parameters (`-D`) that no `$name` of the scene used, in the order given.
    pub fn unused_overrides(&self) -> Vec<String> {
        let used = self.used_params.borrow();
        self.overridden.iter().filter(|k| !used.contains(*k)).cloned().collect()
    }

    /// Names of all parameters (defaults and overrides).
    pub fn parameter_names(&self) -> Vec<String> {
        let mut v: Vec<String> = self.params.keys().cloned().collect();
        v.sort();
        v
    }

    /// Reads and parses the scene file at `path` into its root `scene` object.
    pub fn parse_file(&mut self, path: &Path) -> Result<Rc<Obj>> {
        let text = limits::read_text(path).map_err(|e| SceneError::new(format!("cannot read scene file: {e}")))?;
        self.parse_text(path.to_path_buf(), text)
    }

    /// Parses scene text (`path` names it in messages and anchors relative paths).
    pub fn parse_text(&mut self, path: PathBuf, text: String) -> Result<Rc<Obj>> {
        if self.depth == 0 {
            self.resolver = FileResolver::for_scene(&path);
        }
        self.scene_bytes += text.len();
        if self.scene_bytes > limits::MAX_SCENE_BYTES {
            return Err(SceneError::new(format!(
                "{}: the scene's files hold more than {} bytes of text together",
                path.display(),
                limits::MAX_SCENE_BYTES
            )));
        }
        if !text.trim_start_matches('\u{feff}').trim_start().starts_with('<') {
            // Said without quoting the file: an include may name any file.
            return Err(SceneError::new(format!("{}: not an XML scene file (it does not start with '<')", path.display())));
        }
        let file = Arc::new(SourceFile { path, text });
        let doc = roxmltree::Document::parse(&file.text).map_err(|e| {
            let pos = e.pos();
            let offset = offset_of(&file.text, pos.row as usize, pos.col as usize);
            SceneError::at(&Loc { file: file.clone(), offset }, format!("malformed XML: {e}"))
        })?;
        let root = doc.root_element();
        let loc = Loc { file: file.clone(), offset: root.range().start };
        if root.tag_name().name() != "scene" {
            return Err(SceneError::at(
                &loc,
                format!("expected a <scene> root element, found <{}>", root.tag_name().name()),
            ));
        }
        self.check_attributes(&file, root, &["version", "type", "id", "name"])?;
        let legacy = match root.attribute("version") {
            None => return Err(SceneError::at(&loc, "<scene> needs a version attribute, e.g. version=\"3.0.0\"")),
            Some(v) => match parse_version(v) {
                Some(version) => version < (2, 0, 0),
                None => {
                    return Err(SceneError::at(
                        &loc,
                        format!("version {v:?} must have three period-separated numbers, e.g. \"3.0.0\""),
                    ))
                }
            },
        };
        let mut scene = Obj {
            tag: "scene".into(),
            ty: "scene".into(),
            id: None,
            loc,
            props: Vec::new(),
            children: Vec::new(),
            built: Cell::new(false),
        };
        self.legacy.push(legacy);
        let filled = self.fill(&file, root, &mut scene, true);
        self.legacy.pop();
        filled?;
        let scene = Rc::new(scene);
        if self.depth > 0 {
            return Ok(scene);
        }
        // The whole document is read (includes too): bind the references to ids declared after
        // them, as Mitsuba does (it instantiates objects only once the file is parsed).
        for (alias, id, loc) in std::mem::take(&mut self.aliases) {
            let target = self.lookup(&loc, &id)?;
            self.ids.insert(alias, target);
        }
        Resolver { ids: &self.ids, parser: self, done: HashMap::new(), stack: Vec::new() }.resolve(&scene)
    }

    /// Reads the children of `node` into `obj`.
    fn fill(&mut self, file: &Arc<SourceFile>, node: roxmltree::Node, obj: &mut Obj, top: bool) -> Result<()> {
        for child in node.children().filter(|c| c.is_element()) {
            let loc = Loc { file: file.clone(), offset: child.range().start };
            let tag = child.tag_name().name();
            match tag {
                "default" if top => {
                    self.check_attributes(file, child, &["name", "value"])?;
                    let name = self.attr(file, child, "name")?;
                    let value = self.raw_attr(file, child, "value")?;
                    if !self.overridden.contains(&name) {
                        self.params.entry(name).or_insert(value);
                    }
                }
                "include" => {
                    self.check_attributes(file, child, &["filename", "name"])?;
                    if self.depth >= 16 {
                        return Err(SceneError::at(&loc, "includes nested more than 16 deep (a cycle?)"));
                    }
                    self.includes += 1;
                    if self.includes > limits::MAX_INCLUDES {
                        return Err(SceneError::at(
                            &loc,
                            format!("more than {} included files in one scene", limits::MAX_INCLUDES),
                        ));
                    }
                    let name = self.attr(file, child, "filename")?;
                    let path = self.resolver.resolve(&name);
                    let included = limits::read_text(&path)
                        .map_err(|e| SceneError::at(&loc, format!("cannot read included file: {e}")))?;
                    self.depth += 1;
                    let inner = self.parse_text(path, included);
                    self.depth -= 1;
                    let inner = inner?;
                    let inner = Rc::try_unwrap(inner).expect("fresh object");
                    obj.props.extend(inner.props);
                    obj.children.extend(inner.children);
                }
                "path" if top => {
                    // Mitsuba's <path value>: a relative folder is looked for beside the file
                    // that names it, then through the search list; it must exist.
                    self.check_attributes(file, child, &["value"])?;
                    let value = self.attr(file, child, "value")?;
                    let mut folder = PathBuf::from(&value);
                    if folder.is_relative() {
                        folder = loc.dir().join(&value);
                        if !folder.exists() {
                            folder = self.resolver.resolve(&value);
                        }
                    }
                    if !folder.is_dir() {
                        return Err(SceneError::at(&loc, format!("<path>: folder \"{value}\" not found")));
                    }
                    self.resolver.prepend(folder);
                }
                "path" => return Err(SceneError::at(&loc, "a <path> must be a child of the <scene>")),
                "alias" => {
                    self.check_attributes(file, child, &["id", "as"])?;
                    let id = self.attr(file, child, "id")?;
                    let alias = self.attr(file, child, "as")?;
                    match self.ids.get(&id) {
                        Some(target) => {
                            self.ids.insert(alias, target.clone());
                        }
                        None => self.aliases.push((alias, id, loc)),
                    }
                }
                "ref" => {
                    self.check_attributes(file, child, &["id", "name"])?;
                    let id = self.attr(file, child, "id")?;
                    // An id declared later (in this file, an included one or the file that
                    // includes this one) is bound once the whole scene is read.
                    let target = match self.ids.get(&id) {
                        Some(t) => t.clone(),
                        None => Rc::new(unbound_reference(id, loc.clone())),
                    };
                    self.place(file, child, obj, target, loc, top)?;
                }
                t if OBJECT_TAGS.contains(&t) => {
                    let nested = Rc::new(self.object(file, child)?);
                    if let Some(id) = &nested.id {
                        if self.ids.contains_key(id) {
                            return Err(SceneError::at(&loc, format!("duplicate id '{id}'")));
                        }
                        self.ids.insert(id.clone(), nested.clone());
                    }
                    self.place(file, child, obj, nested, loc, top)?;
                }
                t if PROPERTY_TAGS.contains(&t) => {
                    let allowed: &[&str] = match t {
                        "point" | "vector" => &["name", "value", "x", "y", "z"],
                        "spectrum" => &["name", "value", "filename", "type", "id"],
                        "transform" => &["name"],
                        _ => &["name", "value"],
                    };
                    self.check_attributes(file, child, allowed)?;
                    // Named properties; a <spectrum type="…"> plugin reduces to a value here.
                    let name = self.upgraded_name(obj, self.attr(file, child, "name")?);
                    let value = self.property(file, child)?;
                    push_prop(obj, name, value, loc)?;
                }
                "default" => return Err(SceneError::at(&loc, "<default> is only allowed directly inside <scene>")),
                other => {
                    let known =
                        OBJECT_TAGS.iter().chain(PROPERTY_TAGS).chain(&["ref", "include", "default", "alias", "path"]);
                    let hint =
                        nearest(other, known.copied()).map(|n| format!(" (did you mean <{n}>?)")).unwrap_or_default();
                    return Err(SceneError::at(&loc, format!("unknown element <{other}>{hint}")));
                }
            }
        }
        Ok(())
    }

    /// Puts the object (or reference) `nested` that element `child` declares into `obj`: a
    /// named property of `obj`, or one of its children when it has no `name` or `obj` is the
    /// scene (which takes its objects whatever their names, as Mitsuba's; see
    /// [`Parser::scene_name`]).
    fn place(
        &mut self,
        file: &Arc<SourceFile>,
        child: roxmltree::Node,
        obj: &mut Obj,
        nested: Rc<Obj>,
        loc: Loc,
        top: bool,
    ) -> Result<()> {
        match child.attribute("name") {
            Some(_) if top => {
                self.scene_name(file, child, &loc)?;
                obj.children.push(nested);
            }
            Some(_) => {
                let name = self.upgraded_name(obj, self.attr(file, child, "name")?);
                push_prop(obj, name, Value::Object(nested), loc)?;
            }
            None => obj.children.push(nested),
        }
        Ok(())
    }

    /// Records the `name` of an object placed directly in the scene. Mitsuba 3.9 keeps only the
    /// last of two scene objects of one name (the earlier vanishes without a word); neumann
    /// says so instead of dropping it.
    fn scene_name(&mut self, file: &Arc<SourceFile>, node: roxmltree::Node, loc: &Loc) -> Result<()> {
        let name = self.attr(file, node, "name")?;
        if let Some(first) = self.scene_names.get(&name) {
            return Err(SceneError::at(
                loc,
                format!(
                    "two objects of the scene are named '{name}' (first at {}): Mitsuba 3 would keep only \
                     the last of them; rename or remove one",
                    first.position()
                ),
            ));
        }
        self.scene_names.insert(name, loc.clone());
        Ok(())
    }

    fn lookup(&self, loc: &Loc, id: &str) -> Result<Rc<Obj>> {
        self.ids.get(id).cloned().ok_or_else(|| self.unknown_id(loc, id))
    }

    fn unknown_id(&self, loc: &Loc, id: &str) -> SceneError {
        let hint = nearest(id, self.ids.keys().map(String::as_str))
            .map(|n| format!(" (did you mean '{n}'?)"))
            .unwrap_or_default();
        SceneError::at(loc, format!("reference to unknown id '{id}'{hint}"))
    }

    fn object(&mut self, file: &Arc<SourceFile>, node: roxmltree::Node) -> Result<Obj> {
        let loc = Loc { file: file.clone(), offset: node.range().start };
        let tag = node.tag_name().name().to_string();
        self.check_attributes(file, node, &["type", "id", "name"])?;
        let ty = match node.attribute("type") {
            Some(_) => self.attr(file, node, "type")?,
            None => return Err(SceneError::at(&loc, format!("<{tag}> needs a type attribute"))),
        };
        let id = match node.attribute("id") {
            Some(_) => Some(self.attr(file, node, "id")?),
            None => None,
        };
        if self.nesting >= limits::MAX_NESTING {
            return Err(SceneError::at(&loc, format!("objects nested more than {} deep", limits::MAX_NESTING)));
        }
        let mut obj = Obj { tag, ty, id, loc, props: Vec::new(), children: Vec::new(), built: Cell::new(false) };
        self.nesting += 1;
        let filled = self.fill(file, node, &mut obj, false);
        self.nesting -= 1;
        filled?;
        if self.is_legacy() {
            upgrade_uv_transform(&mut obj);
        }
        Ok(obj)
    }

    /// Whether the document being parsed is a Mitsuba 0.x scene (version < 2.0.0).
    fn is_legacy(&self) -> bool {
        self.legacy.last().copied().unwrap_or(false)
    }

    /// A parameter name of a child of `parent` as Mitsuba 3.9 reads it from the current
    /// document: in a 0.x scene camelCase becomes snake_case (`toWorld` → `to_world`, `intIOR`
    /// → `int_ior`), and a diffuse BSDF's `diffuse_reflectance` becomes `reflectance` (Mitsuba's
    /// upgrade pass; it renames nothing else: `<lookAt>` stays an error, as in Mitsuba 3.9).
    fn upgraded_name(&self, parent: &Obj, name: String) -> String {
        if !self.is_legacy() {
            return name;
        }
        let name = snake_case(&name);
        if parent.tag == "bsdf" && parent.ty == "diffuse" && name == "diffuse_reflectance" {
            return "reflectance".into();
        }
        name
    }


    /// The attribute's raw text (no `$` substitution), or an error naming it.
    fn raw_attr(&self, file: &Arc<SourceFile>, node: roxmltree::Node, name: &str) -> Result<String> {
        node.attribute(name).map(str::to_string).ok_or_else(|| {
            SceneError::at(
                &Loc { file: file.clone(), offset: node.range().start },
                format!("<{}> needs a '{name}' attribute", node.tag_name().name()),
            )
        })
    }

    /// The attribute with `$name` parameters substituted.
    fn attr(&self, file: &Arc<SourceFile>, node: roxmltree::Node, name: &str) -> Result<String> {
        let raw = self.raw_attr(file, node, name)?;
        let offset = node.attribute_node(name).map_or(node.range().start, |a| a.range_value().start);
        self.substitute(&raw, &Loc { file: file.clone(), offset })
    }

    /// Replaces `$name` (letters, digits, `_`) by the parameter's value.
    fn substitute(&self, s: &str, loc: &Loc) -> Result<String> {
        if !s.contains('$') {
            return Ok(s.to_string());
        }
        let mut out = String::new();
        let mut rest = s;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let key = &after[..len];
            match self.params.get(key) {
                Some(v) if !key.is_empty() => {
                    out.push_str(v);
                    self.used_params.borrow_mut().insert(key.to_string());
                }
                _ => {
                    return Err(SceneError::at(
                        loc,
                        format!(
                            "undefined parameter '${key}': declare it with <default name=\"{key}\" value=\"…\"/> or pass -D {key}=…"
                        ),
                    ))
                }
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    fn property(&self, file: &Arc<SourceFile>, node: roxmltree::Node) -> Result<Value> {
        let tag = node.tag_name().name();
        // A property's value is in its attributes: an element inside one (but a transform's
        // operations and a spectrum plugin's parameters) is an error, as in Mitsuba 3.9.1.
        if tag != "transform" && !(tag == "spectrum" && node.attribute("type").is_some()) {
            if let Some(c) = node.children().find(|c| c.is_element()) {
                return Err(SceneError::at(
                    &Loc { file: file.clone(), offset: c.range().start },
                    format!("<{}> cannot be nested in the property <{tag}>", c.tag_name().name()),
                ));
            }
        }
        let value_loc = |n: &str| Loc {
            file: file.clone(),
            offset: node.attribute_node(n).map_or(node.range().start, |a| a.range_value().start),
        };
        let value = || self.attr(file, node, "value");
        let bad = |what: &str, v: &str| SceneError::at(&value_loc("value"), format!("expected {what}, found {v:?}"));
        Ok(match tag {
            "float" => {
                let v = value()?;
                Value::Float(parse_f64(&v).ok_or_else(|| bad("a number", &v))?)
            }
            "integer" => {
                let v = value()?;
                Value::Integer(v.trim().parse().map_err(|_| bad("an integer", &v))?)
            }
            "boolean" => {
                let v = value()?;
                // As Mitsuba 3.9.1: "true" or "false" in any case, not 1 or 0.
                Value::Bool(match v.trim().to_ascii_lowercase().as_str() {
                    "true" => true,
                    "false" => false,
                    _ => return Err(bad("true or false", &v)),
                })
            }
            "string" => Value::String(value()?),
            "rgb" => {
                let v = value()?;
                let nums = parse_list(&v).ok_or_else(|| bad("one or three numbers", &v))?;
                match nums[..] {
                    [x] => Value::Rgb(Rgb::splat(x as f32)),
                    [r, g, b] => Value::Rgb(Rgb::new(r as f32, g as f32, b as f32)),
                    _ => return Err(bad("one or three numbers", &v)),
                }
            }
            "spectrum" if node.attribute("type").is_some() => self.spectrum_object(file, node)?,
            "spectrum" => {
                if node.attribute("filename").is_some() {
                    let name = self.attr(file, node, "filename")?;
                    let path = self.resolver.resolve(&name);
                    let text = crate::load::limits::read_text(&path).map_err(|e| {
                        SceneError::at(&value_loc("filename"), format!("cannot read spectrum file: {e}"))
                    })?;
                    Value::Spectrum(parse_spd(&text).map_err(|(line, msg)| {
                        SceneError::at(&value_loc("filename"), format!("{}:{line}: {msg}", path.display()))
                    })?)
                } else {
                    let v = value()?;
                    Value::Spectrum(parse_spectrum(&v).map_err(|m| SceneError::at(&value_loc("value"), m))?)
                }
            }
            "point" | "vector" => {
                let p = self.xyz_or_value(file, node, None)?;
                if tag == "point" {
                    Value::Point(p)
                } else {
                    Value::Vector(p)
                }
            }
            "transform" => Value::Transform(self.transform(file, node)?),
            _ => unreachable!("property tags are listed"),
        })
    }

    /// A spectrum plugin, `<spectrum type="…">` with its parameters nested, as Mitsuba's RGB
    /// variants read it: `uniform` (`value`, 1) and `d65` (`scale`, 1) are a grey of that value
    /// (D65 is the RGB white), `srgb` (`color`; in [0, 1] unless `unbounded`) its colour;
    /// `regular` (`wavelength_min`, `wavelength_max`, `values`) and `irregular` (`wavelengths`,
    /// `values`) sampled spectra, reduced to RGB as `<spectrum value="λ:v, …">` is (Mitsuba's RGB
    /// variants cannot render these); `blackbody` is an error, as in Mitsuba's RGB variants.
    fn spectrum_object(&self, file: &Arc<SourceFile>, node: roxmltree::Node) -> Result<Value> {
        let loc = |n: roxmltree::Node| Loc { file: file.clone(), offset: n.range().start };
        let ty = self.attr(file, node, "type")?;
        let allowed: &[&str] = match ty.as_str() {
            "uniform" => &["value"],
            "d65" => &["scale"],
            "srgb" => &["color", "unbounded"],
            "regular" => &["wavelength_min", "wavelength_max", "values"],
            "irregular" => &["wavelengths", "values"],
            "blackbody" => {
                return Err(SceneError::at(
                    &loc(node),
                    "a blackbody spectrum needs spectral rendering: neumann renders in RGB, and Mitsuba's RGB \
                     variants refuse it too",
                ))
            }
            _ => {
                let types = ["uniform", "d65", "srgb", "regular", "irregular", "blackbody"];
                let hint = nearest(&ty, types).map(|n| format!("; the nearest is '{n}'")).unwrap_or_default();
                return Err(SceneError::at(
                    &loc(node),
                    format!("unsupported spectrum type '{ty}' (supported: {}{hint})", types.join(", ")),
                ));
            }
        };
        let mut params: HashMap<String, (Value, roxmltree::Node)> = HashMap::new();
        for c in node.children().filter(|c| c.is_element()) {
            let name = self.attr(file, c, "name")?;
            if !allowed.contains(&name.as_str()) {
                return Err(SceneError::at(
                    &loc(c),
                    format!("spectrum '{ty}' has no parameter '{name}' (its parameters: {})", allowed.join(", ")),
                ));
            }
            if !PROPERTY_TAGS.contains(&c.tag_name().name()) {
                return Err(SceneError::at(&loc(c), format!("parameter '{name}' of spectrum '{ty}' must be a property")));
            }
            params.insert(name, (self.property(file, c)?, c));
        }
        let float = |name: &str, default: Option<f64>| -> Result<f64> {
            match params.get(name) {
                Some((Value::Float(v), _)) => Ok(*v),
                Some((Value::Integer(v), _)) => Ok(*v as f64),
                Some((_, c)) => Err(SceneError::at(&loc(*c), format!("'{name}' of spectrum '{ty}' must be a <float>"))),
                None => default.ok_or_else(|| SceneError::at(&loc(node), format!("spectrum '{ty}' needs '{name}'"))),
            }
        };
        let list = |name: &str| -> Result<Vec<f64>> {
            match params.get(name) {
                Some((Value::String(v), c)) => parse_list(v).ok_or_else(|| {
                    SceneError::at(&loc(*c), format!("'{name}' must be a list of numbers, found {v:?}"))
                }),
                Some((_, c)) => Err(SceneError::at(&loc(*c), format!("'{name}' of spectrum '{ty}' must be a <string>"))),
                None => Err(SceneError::at(&loc(node), format!("spectrum '{ty}' needs '{name}'"))),
            }
        };
        let sampled = |samples: Vec<(f32, f32)>| -> Result<Value> {
            check_increasing(&samples).map_err(|m| SceneError::at(&loc(node), m))?;
            Ok(Value::Spectrum(SpectrumValue::Samples(samples)))
        };
        match ty.as_str() {
            "uniform" => Ok(Value::Float(float("value", Some(1.0))?)),
            "d65" => Ok(Value::Float(float("scale", Some(1.0))?)),
            "srgb" => {
                let unbounded = match params.get("unbounded") {
                    Some((Value::Bool(b), _)) => *b,
                    Some((_, c)) => return Err(SceneError::at(&loc(*c), "'unbounded' must be a <boolean>")),
                    None => false,
                };
                match params.get("color") {
                    Some((Value::Rgb(c), n)) => {
                        if !(unbounded || c.min_element() >= 0.0 && c.max_element() <= 1.0) {
                            return Err(SceneError::at(
                                &loc(*n),
                                format!("an srgb spectrum's colour must lie in [0, 1] unless 'unbounded' is true, got {c}"),
                            ));
                        }
                        Ok(Value::Rgb(*c))
                    }
                    Some((_, n)) => Err(SceneError::at(&loc(*n), "'color' of spectrum 'srgb' must be an <rgb>")),
                    None => Err(SceneError::at(&loc(node), "spectrum 'srgb' needs 'color'")),
                }
            }
            "regular" => {
                let (lo, hi) = (float("wavelength_min", None)?, float("wavelength_max", None)?);
                let values = list("values")?;
                if values.len() < 2 || hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
                    return Err(SceneError::at(
                        &loc(node),
                        "a regular spectrum needs wavelength_min < wavelength_max and at least two values",
                    ));
                }
                let step = (hi - lo) / (values.len() - 1) as f64;
                sampled(values.iter().enumerate().map(|(i, v)| ((lo + step * i as f64) as f32, *v as f32)).collect())
            }
            _ => {
                let (wavelengths, values) = (list("wavelengths")?, list("values")?);
                if wavelengths.len() != values.len() {
                    return Err(SceneError::at(
                        &loc(node),
                        format!("{} wavelengths but {} values", wavelengths.len(), values.len()),
                    ));
                }
                sampled(wavelengths.iter().zip(&values).map(|(l, v)| (*l as f32, *v as f32)).collect())
            }
        }
    }

    /// The `x`, `y`, `z` attributes (each defaulting to `default`).
    fn xyz(&self, file: &Arc<SourceFile>, node: roxmltree::Node, default: f32) -> Result<Vec3> {
        let mut v = [default; 3];
        for (i, k) in ["x", "y", "z"].into_iter().enumerate() {
            if node.attribute(k).is_some() {
                let s = self.attr(file, node, k)?;
                let offset = node.attribute_node(k).map_or(0, |a| a.range_value().start);
                v[i] = parse_f64(&s).ok_or_else(|| {
                    SceneError::at(
                        &Loc { file: file.clone(), offset },
                        format!("expected a number for {k}, found {s:?}"),
                    )
                })? as f32;
            }
        }
        Ok(Vec3::from_array(v))
    }

    /// Mitsuba's `x`/`y`/`z` or `value` (one number for all three, or three) of a `<point>`,
    /// `<vector>`, `<translate>`, `<rotate>` or `<scale>`: never both (Mitsuba refuses the
    /// mix); components left out are `default`, or an error where `default` is `None` (Mitsuba
    /// requires all three on points and vectors).
    fn xyz_or_value(&self, file: &Arc<SourceFile>, node: roxmltree::Node, default: Option<f32>) -> Result<Vec3> {
        let tag = node.tag_name().name();
        let at = |offset: usize| Loc { file: file.clone(), offset };
        if node.attribute("value").is_some() {
            if let Some(a) = ["x", "y", "z"].into_iter().find_map(|k| node.attribute_node(k)) {
                return Err(SceneError::at(
                    &at(a.range().start),
                    format!("<{tag}> cannot mix \"value\" and \"x\"/\"y\"/\"z\" attributes (as in Mitsuba)"),
                ));
            }
            let v = self.attr(file, node, "value")?;
            let offset = node.attribute_node("value").map_or(0, |a| a.range_value().start);
            return match parse_list(&v).as_deref() {
                Some([x]) => Ok(Vec3::splat(*x as f32)),
                Some([x, y, z]) => Ok(Vec3::new(*x as f32, *y as f32, *z as f32)),
                _ => {
                    Err(SceneError::at(&at(offset), format!("<{tag} value> expects one or three numbers, found {v:?}")))
                }
            };
        }
        if default.is_none() {
            if let Some(k) = ["x", "y", "z"].into_iter().find(|k| node.attribute(*k).is_none()) {
                return Err(SceneError::at(
                    &at(node.range().start),
                    format!("<{tag}> needs \"{k}\" (with \"x\", \"y\", \"z\" all three are required, as in Mitsuba), or \"value\""),
                ));
            }
        }
        self.xyz(file, node, default.unwrap_or(0.0))
    }

    /// Refuses attributes of `node` outside `allowed`, as Mitsuba does (a misspelt one would
    /// otherwise be dropped without a word).
    fn check_attributes(&self, file: &Arc<SourceFile>, node: roxmltree::Node, allowed: &[&str]) -> Result<()> {
        match node.attributes().find(|a| !allowed.contains(&a.name())) {
            None => Ok(()),
            Some(a) => {
                let hint = nearest(a.name(), allowed.iter().copied())
                    .map(|n| format!("; did you mean \"{n}\"?"))
                    .unwrap_or_default();
                Err(SceneError::at(
                    &Loc { file: file.clone(), offset: a.range().start },
                    format!(
                        "unexpected attribute \"{}\" in <{}> (its attributes: {}){hint}",
                        a.name(),
                        node.tag_name().name(),
                        allowed.join(", ")
                    ),
                ))
            }
        }
    }

    fn vec3_attr(&self, file: &Arc<SourceFile>, node: roxmltree::Node, name: &str) -> Result<Vec3> {
        let s = self.attr(file, node, name)?;
        let offset = node.attribute_node(name).map_or(0, |a| a.range_value().start);
        match parse_list(&s).as_deref() {
            Some([x, y, z]) => Ok(Vec3::new(*x as f32, *y as f32, *z as f32)),
            _ => Err(SceneError::at(
                &Loc { file: file.clone(), offset },
                format!("expected three numbers for '{name}', found {s:?}"),
            )),
        }
    }

    /// A `<transform>`: its operations in document order, each applied after the previous ones.
    fn transform(&self, file: &Arc<SourceFile>, node: roxmltree::Node) -> Result<Transform> {
        let mut t = Transform::IDENTITY;
        for op in node.children().filter(|c| c.is_element()) {
            let loc = Loc { file: file.clone(), offset: op.range().start };
            let invalid = |what: &str| SceneError::at(&loc, what.to_string());
            // An unknown operation is refused below, by name (not by its attributes).
            let allowed: Option<&[&str]> = match op.tag_name().name() {
                "translate" | "scale" => Some(&["x", "y", "z", "value"]),
                "rotate" => Some(&["x", "y", "z", "value", "angle"]),
                "matrix" => Some(&["value"]),
                "lookat" => Some(&["origin", "target", "up"]),
                _ => None,
            };
            if let Some(allowed) = allowed {
                self.check_attributes(file, op, allowed)?;
            }
            let step = match op.tag_name().name() {
                "translate" => Transform::translate(self.xyz_or_value(file, op, Some(0.0))?),
                "scale" => {
                    let s = self.xyz_or_value(file, op, Some(1.0))?;
                    Transform::scale(s).ok_or_else(|| invalid("scale factors must be non-zero"))?
                }
                "rotate" => {
                    let axis = self.xyz_or_value(file, op, Some(0.0))?;
                    if axis == Vec3::ZERO {
                        return Err(invalid("the rotation axis is zero (give x, y, z or value)"));
                    }
                    let angle = self.attr(file, op, "angle")?;
                    let angle = parse_f64(&angle)
                        .ok_or_else(|| invalid(&format!("expected a number of degrees for angle, found {angle:?}")))?;
                    // As Mitsuba 3: the axis is not normalized (a non-unit one scales too).
                    if (axis.length_squared() - 1.0).abs() > 1e-4 {
                        self.warnings.borrow_mut().push(format!(
                            "warning: {}: the rotation axis ({}, {}, {}) is not a unit vector: Mitsuba 3 does not \
                             normalize it, so this <rotate> scales and shears as well as turns (neumann builds the same \
                             matrix; Mitsuba 3.9.1 also stores that matrix as its own inverse transpose, so its disks, \
                             cylinders, vertex normals and light directions under it differ again); give a unit axis \
                             for a rotation",
                            loc.position(),
                            axis.x,
                            axis.y,
                            axis.z
                        ));
                    }
                    Transform::rotate_unnormalized(axis, angle as f32)
                        .ok_or_else(|| invalid("the rotation is singular (Mitsuba uses the axis as given, not normalized: cos θ I + (1 − cos θ) a aᵀ + sin θ [a]×)"))?
                }
                "matrix" => {
                    let v = self.attr(file, op, "value")?;
                    let m = parse_list(&v).filter(|m| m.len() == 16 || m.len() == 9).ok_or_else(|| {
                        invalid(&format!("<matrix value> expects 16 (or 9) numbers in row-major order, found {v:?}"))
                    })?;
                    let m: Vec<f32> = m.iter().map(|&x| x as f32).collect();
                    let rows = if m.len() == 16 {
                        Mat4::from_cols_array(&m.try_into().expect("16 numbers")).transpose()
                    } else {
                        Mat4::from_cols(
                            Vec4::new(m[0], m[3], m[6], 0.0),
                            Vec4::new(m[1], m[4], m[7], 0.0),
                            Vec4::new(m[2], m[5], m[8], 0.0),
                            Vec4::W,
                        )
                    };
                    Transform::from_matrix(rows).ok_or_else(|| invalid("the matrix is singular or not finite"))?
                }
                "lookat" => {
                    let origin = self.vec3_attr(file, op, "origin")?;
                    let target = self.vec3_attr(file, op, "target")?;
                    // Mitsuba 3.9: without an up vector (or a zero one), the first tangent of the
                    // view direction's coordinate system.
                    let up = if op.attribute("up").is_some() { self.vec3_attr(file, op, "up")? } else { Vec3::ZERO };
                    let up = match (up == Vec3::ZERO, (target - origin).try_normalize()) {
                        (true, Some(dir)) => crate::math::Frame::from_z(dir).s,
                        _ => up,
                    };
                    Transform::look_at(origin, target, up).ok_or_else(|| {
                        invalid("lookat needs origin ≠ target and an up vector not parallel to the view direction")
                    })?
                }
                other => {
                    let hint = nearest(other, ["translate", "rotate", "scale", "matrix", "lookat"])
                        .map(|n| format!(" (did you mean <{n}>?)"))
                        .unwrap_or_default();
                    return Err(invalid(&format!(
                        "unknown transform operation <{other}>{hint}: expected translate, rotate, scale, matrix or lookat"
                    )));
                }
            };
            t = step * t;
            if !(t.matrix().is_finite() && t.inverse_matrix().is_finite()) {
                return Err(invalid("the transform is not finite after this operation (it overflows or is degenerate)"));
            }
        }
        Ok(t)
    }
}

/// `major.minor.patch` of a scene's `version` attribute.
fn parse_version(v: &str) -> Option<(u32, u32, u32)> {
    let parts: Vec<&str> = v.split(['.', ' ']).filter(|p| !p.is_empty()).collect();
    match parts.as_slice() {
        [a, b, c] => Some((a.parse().ok()?, b.parse().ok()?, c.parse().ok()?)),
        _ => None,
    }
}

/// Mitsuba's camelCase → snake_case of 0.x parameter names: an underscore before an upper-case
/// letter that follows a lower-case one, and that run of upper-case letters lowered
/// (`toWorld` → `to_world`, `intIOR` → `int_ior`, `sampleCount` → `sample_count`).
fn snake_case(name: &str) -> String {
    let mut c: Vec<char> = name.chars().collect();
    let mut i = 0;
    while i + 1 < c.len() {
        if c[i].is_ascii_lowercase() && c[i + 1].is_ascii_uppercase() {
            c.insert(i + 1, '_');
            i += 2;
            while i < c.len() && c[i].is_ascii_uppercase() {
                c[i] = c[i].to_ascii_lowercase();
                i += 1;
            }
        } else {
            i += 1;
        }
    }
    c.into_iter().collect()
}

/// Mitsuba's upgrade of 0.x texture offsets and scales: `<float>`s `uoffset`, `voffset`,
/// `uscale`, `vscale` become a `to_uv` transform (the translation first, then the scale).
fn upgrade_uv_transform(obj: &mut Obj) {
    let names = ["uoffset", "voffset", "uscale", "vscale"];
    if !obj.props.iter().any(|p| names.contains(&p.name.as_str()) && matches!(p.value, Value::Float(_))) {
        return;
    }
    let mut v = [0.0f32, 0.0, 1.0, 1.0];
    let mut loc = obj.loc.clone();
    obj.props.retain(|p| match (names.iter().position(|n| *n == p.name), &p.value) {
        (Some(k), Value::Float(f)) => {
            v[k] = *f as f32;
            loc = p.loc.clone();
            false
        }
        _ => true,
    });
    let translate = Transform::translate(Vec3::new(v[0], v[1], 0.0));
    let t = match Transform::scale(Vec3::new(v[2], v[3], 1.0)) {
        Some(scale) => scale * translate,
        None => translate,
    };
    obj.set("to_uv", Value::Transform(t), loc);
}

/// Adds a property, rejecting a second one of the same name.
fn push_prop(obj: &mut Obj, name: String, value: Value, loc: Loc) -> Result<()> {
    if let Some(p) = obj.props.iter().find(|p| p.name == name) {
        return Err(SceneError::at(&loc, format!("parameter '{name}' is given twice (first at {})", p.loc.position())));
    }
    obj.props.push(Prop::new(&name, value, loc));
    Ok(())
}

/// Byte offset of 1-based (row, col).
fn offset_of(text: &str, row: usize, col: usize) -> usize {
    let line_start: usize = text.split_inclusive('\n').take(row.saturating_sub(1)).map(str::len).sum();
    let line = &text[line_start.min(text.len())..];
    line_start + line.chars().take(col.saturating_sub(1)).map(char::len_utf8).sum::<usize>()
}

fn parse_f64(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Numbers separated by commas and/or whitespace.
/// The tag of a placeholder for a `<ref>` to an id not declared yet (no object element has it).
const UNBOUND_REF: &str = "ref";

/// A placeholder for a `<ref id>` met before its id was declared; bound once the scene is read.
fn unbound_reference(id: String, loc: Loc) -> Obj {
    Obj {
        tag: UNBOUND_REF.into(),
        ty: String::new(),
        id: Some(id),
        loc,
        props: Vec::new(),
        children: Vec::new(),
        built: Cell::new(false),
    }
}

/// Binds the placeholders of references to later ids: rebuilds the objects that contain one
/// (directly or below), each once, so that an object referenced from several places stays one
/// shared object; a reference cycle is an error.
struct Resolver<'a> {
    ids: &'a HashMap<String, Rc<Obj>>,
    parser: &'a Parser,
    /// Objects bound already, by address: the same (rebuilt or unchanged) object.
    done: HashMap<*const Obj, Rc<Obj>>,
    /// Objects being bound, by address (a reference back to one is a cycle).
    stack: Vec<*const Obj>,
}

impl Resolver<'_> {
    fn resolve(&mut self, obj: &Rc<Obj>) -> Result<Rc<Obj>> {
        if obj.tag == UNBOUND_REF {
            let id = obj.id.as_deref().unwrap_or_default();
            let target = self.ids.get(id).ok_or_else(|| self.parser.unknown_id(&obj.loc, id))?;
            if self.stack.contains(&Rc::as_ptr(target)) {
                return Err(SceneError::at(&obj.loc, format!("circular reference to '{id}'")));
            }
            return self.resolve(&target.clone());
        }
        let key = Rc::as_ptr(obj);
        if let Some(r) = self.done.get(&key) {
            return Ok(r.clone());
        }
        if self.stack.contains(&key) {
            let what = obj.id.as_ref().map_or_else(|| format!("this <{}>", obj.tag), |id| format!("'{id}'"));
            return Err(SceneError::at(&obj.loc, format!("circular reference to {what}")));
        }
        // Nesting is bounded by the XML's depth, but reference chains are not.
        if self.stack.len() >= 1024 {
            return Err(SceneError::at(&obj.loc, "references chained more than 1024 deep"));
        }
        self.stack.push(key);
        let resolved = self.rebuild(obj);
        self.stack.pop();
        let resolved = resolved?;
        self.done.insert(key, resolved.clone());
        Ok(resolved)
    }

    /// `obj` with its nested objects bound (the same `Rc` if none changed).
    fn rebuild(&mut self, obj: &Rc<Obj>) -> Result<Rc<Obj>> {
        let mut changed = false;
        let mut props = Vec::with_capacity(obj.props.len());
        for p in &obj.props {
            let value = match &p.value {
                Value::Object(o) => {
                    let r = self.resolve(o)?;
                    changed |= !Rc::ptr_eq(&r, o);
                    Value::Object(r)
                }
                v => v.clone(),
            };
            props.push(Prop { name: p.name.clone(), value, loc: p.loc.clone(), used: Cell::new(p.used.get()) });
        }
        let mut children = Vec::with_capacity(obj.children.len());
        for c in &obj.children {
            let r = self.resolve(c)?;
            changed |= !Rc::ptr_eq(&r, c);
            children.push(r);
        }
        if !changed {
            return Ok(obj.clone());
        }
        Ok(Rc::new(Obj {
            tag: obj.tag.clone(),
            ty: obj.ty.clone(),
            id: obj.id.clone(),
            loc: obj.loc.clone(),
            props,
            children,
            built: Cell::new(obj.built.get()),
        }))
    }
}

fn parse_list(s: &str) -> Option<Vec<f64>> {
    let v: Option<Vec<f64>> = s.split([',', ' ', '\t', '\n', '\r']).filter(|t| !t.is_empty()).map(parse_f64).collect();
    v.filter(|v| !v.is_empty())
}

/// `"0.5"` or `"400:0.1, 500:0.6, …"` (wavelengths increasing).
pub fn parse_spectrum(s: &str) -> std::result::Result<SpectrumValue, String> {
    if !s.contains(':') {
        return match parse_list(s).as_deref() {
            Some([v]) => Ok(SpectrumValue::Constant(*v as f32)),
            _ => Err(format!("expected a number or wavelength:value pairs, found {s:?}")),
        };
    }
    let mut samples = Vec::new();
    for pair in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (l, v) = pair.split_once(':').ok_or_else(|| format!("expected wavelength:value, found {pair:?}"))?;
        let (l, v) = (parse_f64(l), parse_f64(v));
        match (l, v) {
            (Some(l), Some(v)) => samples.push((l as f32, v as f32)),
            _ => return Err(format!("expected wavelength:value with numbers, found {pair:?}")),
        }
    }
    check_increasing(&samples)?;
    Ok(SpectrumValue::Samples(samples))
}

/// A `.spd` file: lines of `wavelength value`, `#` comments.
fn parse_spd(text: &str) -> std::result::Result<SpectrumValue, (usize, String)> {
    let mut samples = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        match parse_list(line).as_deref() {
            Some([l, v]) => samples.push((*l as f32, *v as f32)),
            _ => return Err((i + 1, format!("expected 'wavelength value', found {line:?}"))),
        }
    }
    check_increasing(&samples).map_err(|m| (0, m))?;
    Ok(SpectrumValue::Samples(samples))
}

fn check_increasing(samples: &[(f32, f32)]) -> std::result::Result<(), String> {
    if samples.is_empty() {
        return Err("the spectrum has no samples".into());
    }
    if let Some(w) = samples.windows(2).find(|w| w[1].0 <= w[0].0) {
        return Err(format!("wavelengths must increase: {} nm follows {} nm", w[1].0, w[0].0));
    }
    Ok(())
}
