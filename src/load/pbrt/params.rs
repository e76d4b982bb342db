//! pbrt-v4 parameter lists (`"float radius" [ 2 ]`): typed, located, marked when read, so that
//! parameters no plugin reads are errors (pbrt-v4 stops on them too).

use crate::math::{Rgb, Vec3};
use crate::props::{Loc, SceneError};
use std::cell::Cell;

type Result<T> = std::result::Result<T, SceneError>;

/// One value of a parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum PVal {
    /// A number.
    Num(f64),
    /// A string.
    Str(String),
    /// `true` / `false`.
    Bool(bool),
}

/// A parameter: `"type name" values`.
#[derive(Clone, Debug)]
pub struct Param {
    /// The declared type (`float`, `integer`, `point3`, `rgb`, `spectrum`, `texture`, …).
    pub ty: String,
    /// The name.
    pub name: String,
    /// The values.
    pub values: Vec<PVal>,
    /// Where it was written.
    pub loc: Loc,
    /// Whether the translator read it.
    pub used: Cell<bool>,
}

/// A spectrum as written for a parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumParam {
    /// `rgb` values.
    Rgb(Rgb),
    /// A constant (`float` given for a spectrum, or a one-value `spectrum`).
    Constant(f32),
    /// (wavelength, value) pairs.
    Samples(Vec<(f32, f32)>),
    /// A named spectrum (`"metal-Au-eta"`, `"stdillum-D65"`, …) or an `.spd` file name.
    Named(String),
    /// `blackbody` temperature in kelvin.
    Blackbody(f32),
}

/// The parameters of one directive, with the directive's position.
#[derive(Debug)]
pub struct ParamSet {
    /// The parameters in order.
    pub params: Vec<Param>,
    /// Where the directive starts.
    pub loc: Loc,
    /// What they belong to, for messages (`Shape "sphere"`).
    pub what: String,
}

impl ParamSet {
    fn find(&self, name: &str) -> Option<&Param> {
        let p = self.params.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// Whether a parameter `name` is present (not marked read).
    pub fn has(&self, name: &str) -> bool {
        self.params.iter().any(|p| p.name == name)
    }

    /// An error at parameter `name` (or the directive).
    pub fn error_at(&self, name: &str, message: impl Into<String>) -> SceneError {
        let loc = self.params.iter().find(|p| p.name == name).map_or(&self.loc, |p| &p.loc);
        SceneError::at(loc, format!("{}: {}", self.what, message.into()))
    }

    /// The error for a plugin name pbrt-v4 does not have: pbrt-v4's `names` of that `kind`,
    /// and the nearest of them.
    pub fn unknown(&self, kind: &str, name: &str, names: &[&str]) -> SceneError {
        let hint = crate::choice::nearest(name, names.iter().copied())
            .map(|n| format!("; the nearest is '{n}'"))
            .unwrap_or_default();
        self.error(format!("unknown {kind} \"{name}\" (pbrt-v4's: {}{hint})", names.join(", ")))
    }

    /// An error at the directive.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.loc, format!("{}: {}", self.what, message.into()))
    }

    fn numbers(&self, p: &Param, types: &[&str]) -> Result<Vec<f64>> {
        if !types.contains(&p.ty.as_str()) {
            return Err(SceneError::at(
                &p.loc,
                format!("{}: \"{} {}\" must be of type {}", self.what, p.ty, p.name, types.join(" or ")),
            ));
        }
        p.values
            .iter()
            .map(|v| match v {
                PVal::Num(n) => Ok(*n),
                _ => Err(SceneError::at(&p.loc, format!("{}: \"{} {}\" takes numbers", self.what, p.ty, p.name))),
            })
            .collect()
    }

    /// Every number of a numeric parameter of one of `types`.
    pub fn floats(&self, name: &str, types: &[&str]) -> Result<Option<Vec<f64>>> {
        match self.find(name) {
            None => Ok(None),
            Some(p) => self.numbers(p, types).map(Some),
        }
    }

    /// A parameter of 3-vectors (`point3`, `normal3`, … as `types` says), read as triples; an
    /// error at the parameter unless its numbers come in threes.
    pub fn vec3s(&self, name: &str, types: &[&str]) -> Result<Option<Vec<Vec3>>> {
        let Some(v) = self.floats(name, types)? else { return Ok(None) };
        if !v.len().is_multiple_of(3) {
            return Err(self.error_at(name, format!("\"{name}\" needs a multiple of 3 numbers, has {}", v.len())));
        }
        Ok(Some(v.chunks(3).map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)).collect()))
    }

    /// A single `float` (default if absent).
    pub fn float(&self, name: &str, default: f32) -> Result<f32> {
        match self.find(name) {
            None => Ok(default),
            Some(p) => {
                let v = self.numbers(p, &["float"])?;
                match v[..] {
                    [x] if x.is_finite() => Ok(x as f32),
                    _ => Err(SceneError::at(&p.loc, format!("{}: \"float {name}\" takes one finite value", self.what))),
                }
            }
        }
    }

    /// A single `integer`.
    pub fn int(&self, name: &str, default: i64) -> Result<i64> {
        match self.find(name) {
            None => Ok(default),
            Some(p) => {
                let v = self.numbers(p, &["integer"])?;
                match v[..] {
                    [x] if x.fract() == 0.0 && x.abs() < 1e15 => Ok(x as i64),
                    _ => Err(SceneError::at(&p.loc, format!("{}: \"integer {name}\" takes one integer", self.what))),
                }
            }
        }
    }

    /// A single `bool`.
    pub fn bool(&self, name: &str, default: bool) -> Result<bool> {
        match self.find(name) {
            None => Ok(default),
            Some(p) => match (&p.ty[..], &p.values[..]) {
                ("bool", [PVal::Bool(b)]) => Ok(*b),
                ("bool", [PVal::Str(s)]) if s == "true" || s == "false" => Ok(s == "true"),
                _ => Err(SceneError::at(&p.loc, format!("{}: \"bool {name}\" takes one true or false", self.what))),
            },
        }
    }

    /// A single `string` (or `texture` name when `ty` says so).
    pub fn string_of(&self, name: &str, ty: &str) -> Result<Option<String>> {
        match self.find(name) {
            None => Ok(None),
            Some(p) => match (&p.ty[..] == ty, &p.values[..]) {
                (true, [PVal::Str(s)]) => Ok(Some(s.clone())),
                _ => Err(SceneError::at(&p.loc, format!("{}: \"{ty} {name}\" takes one string", self.what))),
            },
        }
    }

    /// A single `string`.
    pub fn string(&self, name: &str) -> Result<Option<String>> {
        self.string_of(name, "string")
    }

    /// A `point3` (or `point`).
    pub fn point(&self, name: &str, default: Vec3) -> Result<Vec3> {
        match self.floats(name, &["point3", "point", "vector3", "vector", "normal3", "normal"])? {
            None => Ok(default),
            Some(v) if v.len() == 3 => Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)),
            Some(_) => Err(self.error_at(name, format!("\"{name}\" takes three numbers"))),
        }
    }

    /// The type a parameter was declared with (`None` if absent; not marked read).
    pub fn type_of(&self, name: &str) -> Option<&str> {
        self.params.iter().find(|p| p.name == name).map(|p| p.ty.as_str())
    }

    /// A spectrum-valued parameter (`rgb`, `spectrum`, `blackbody`, or a `float` constant).
    pub fn spectrum(&self, name: &str) -> Result<Option<SpectrumParam>> {
        let Some(p) = self.find(name) else { return Ok(None) };
        let bad = |m: &str| SceneError::at(&p.loc, format!("{}: \"{} {name}\": {m}", self.what, p.ty));
        let nums = || self.numbers(p, &[p.ty.as_str()]);
        Ok(Some(match p.ty.as_str() {
            "rgb" | "color" => match nums()?[..] {
                [r, g, b] => Rgb::new(r as f32, g as f32, b as f32),
                _ => return Err(bad("takes three values")),
            }
            .into_spectrum(),
            "float" => match nums()?[..] {
                [v] => SpectrumParam::Constant(v as f32),
                _ => return Err(bad("takes one value")),
            },
            "blackbody" => match nums()?[..] {
                [t] if t > 0.0 => SpectrumParam::Blackbody(t as f32),
                _ => return Err(bad("takes one positive temperature")),
            },
            "spectrum" => match &p.values[..] {
                [PVal::Str(s)] => SpectrumParam::Named(s.clone()),
                _ => {
                    let v = nums()?;
                    match v.len() {
                        1 => SpectrumParam::Constant(v[0] as f32),
                        n if n >= 2 && n % 2 == 0 => {
                            SpectrumParam::Samples(v.chunks(2).map(|c| (c[0] as f32, c[1] as f32)).collect())
                        }
                        _ => return Err(bad("takes (wavelength, value) pairs, a named spectrum or a file")),
                    }
                }
            },
            _ => return Err(bad("must be an rgb, spectrum, blackbody or float")),
        }))
    }

    /// The parameters no one read.
    pub fn unused(&self) -> Vec<&Param> {
        self.params.iter().filter(|p| !p.used.get()).collect()
    }

    /// An error if a parameter was not read: pbrt-v4 stops on unused parameters too, and in
    /// neumann an unread parameter is a feature it does not implement.
    pub fn check_unused(&self) -> Result<()> {
        let unused = self.unused();
        if let Some(p) = unused.first() {
            let all: Vec<String> = unused.iter().map(|p| format!("\"{} {}\"", p.ty, p.name)).collect();
            return Err(SceneError::at(
                &p.loc,
                format!(
                    "{}: unused parameter{} {} (a misspelt name, or a feature neumann does not implement)",
                    self.what,
                    if all.len() > 1 { "s" } else { "" },
                    all.join(", ")
                ),
            ));
        }
        Ok(())
    }
}

trait IntoSpectrum {
    fn into_spectrum(self) -> SpectrumParam;
}

impl IntoSpectrum for Rgb {
    fn into_spectrum(self) -> SpectrumParam {
        SpectrumParam::Rgb(self)
    }
}
