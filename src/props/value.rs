//! The property values of a plugin object, with where each was written.

use super::error::Loc;
use crate::math::{Rgb, Transform, Vec3};
use std::cell::Cell;
use std::rc::Rc;

/// A spectrum as written: a constant or (wavelength nm, value) samples (reduced to RGB where it is
/// used, since that depends on whether it is emitted light).
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumValue {
    /// The same value at every wavelength.
    Constant(f32),
    /// Samples sorted by increasing wavelength.
    Samples(Vec<(f32, f32)>),
}

/// A property value.
#[derive(Clone, Debug)]
pub enum Value {
    /// `<float>`.
    Float(f64),
    /// `<integer>`.
    Integer(i64),
    /// `<boolean>`.
    Bool(bool),
    /// `<string>`.
    String(String),
    /// `<rgb>`.
    Rgb(Rgb),
    /// `<spectrum>`.
    Spectrum(SpectrumValue),
    /// `<point>`.
    Point(Vec3),
    /// `<vector>`.
    Vector(Vec3),
    /// `<transform>`.
    Transform(Transform),
    /// A named nested object or named `<ref>`.
    Object(Rc<Obj>),
}

impl Value {
    /// The XML element name of this kind of value (for messages).
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Bool(_) => "boolean",
            Value::String(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) => "spectrum",
            Value::Point(_) => "point",
            Value::Vector(_) => "vector",
            Value::Transform(_) => "transform",
            Value::Object(o) => match o.tag.as_str() {
                "texture" => "texture",
                "bsdf" => "bsdf",
                "emitter" => "emitter",
                "shape" => "shape",
                "volume" => "volume",
                _ => "object",
            },
        }
    }
}

/// A named property with its position; `used` records whether a plugin read it.
#[derive(Debug)]
pub struct Prop {
    /// Parameter name.
    pub name: String,
    /// Value.
    pub value: Value,
    /// Where it was written.
    pub loc: Loc,
    /// Whether a plugin has read it.
    pub used: Cell<bool>,
}

/// A plugin object: `<bsdf type="diffuse" id="white">…</bsdf>`.
#[derive(Debug)]
pub struct Obj {
    /// Element name: `scene`, `bsdf`, `shape`, `emitter`, `sensor`, `film`, `sampler`, …
    pub tag: String,
    /// Plugin type (`type` attribute).
    pub ty: String,
    /// `id` attribute.
    pub id: Option<String>,
    /// Where the element starts.
    pub loc: Loc,
    /// Properties, including named nested objects.
    pub props: Vec<Prop>,
    /// Unnamed nested objects and `<ref>`s, in document order.
    pub children: Vec<Rc<Obj>>,
    /// Whether a plugin was built from it (unused-parameter warnings only concern those).
    pub built: Cell<bool>,
}

impl Prop {
    /// Property `name` = `value`, written at `loc`, not read yet.
    pub fn new(name: &str, value: Value, loc: Loc) -> Prop {
        Prop { name: name.into(), value, loc, used: Cell::new(false) }
    }
}

impl Obj {
    /// A new object `<tag type=ty>` at `loc`, without id, properties or children: how a
    /// format that is not Mitsuba's (pbrt-v4, glTF, command-line overrides) makes the located
    /// objects the plugin registry builds from.
    pub fn new(tag: &str, ty: &str, loc: Loc) -> Obj {
        Obj {
            tag: tag.into(),
            ty: ty.into(),
            id: None,
            loc,
            props: Vec::new(),
            children: Vec::new(),
            built: Cell::new(false),
        }
    }

    /// Adds property `name` = `value`, written at `loc`.
    pub fn set(&mut self, name: &str, value: Value, loc: Loc) {
        self.props.push(Prop::new(name, value, loc));
    }
}

/// The element names that are plugin objects.
pub const OBJECT_TAGS: &[&str] = &[
    "bsdf",
    "shape",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "rfilter",
    "integrator",
    "texture",
    "medium",
    "phase",
    "volume",
];
