//! Typed access to an object's properties, as Mitsuba's `Properties`: each getter marks the
//! property as read (for the unused-parameter warnings) and reports a wrong type at the
//! property's position.

use super::error::{nearest, SceneError};
use super::value::{Obj, Prop, SpectrumValue, Value};
use crate::math::spectrum::{spectrum_to_rgb, SpectrumKind};
use crate::math::{Rgb, Transform, Vec3};
use std::rc::Rc;

use super::Result;

impl Obj {
    /// The property `name`, marked as read.
    pub fn get(&self, name: &str) -> Option<&Prop> {
        let p = self.props.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// Whether the property is present (does not mark it read).
    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name)
    }

    fn wrong(&self, p: &Prop, expected: &str) -> SceneError {
        SceneError::at(
            &p.loc,
            format!(
                "parameter '{}' of {} '{}' must be {expected}, found <{}>",
                p.name,
                self.tag,
                self.ty,
                p.value.kind()
            ),
        )
    }

    /// An error at the property `name` (or at the object if it is absent).
    pub fn error_at(&self, name: &str, message: impl Into<String>) -> SceneError {
        let loc = self.props.iter().find(|p| p.name == name).map_or(&self.loc, |p| &p.loc);
        SceneError::at(loc, format!("{} '{}': {}", self.tag, self.ty, message.into()))
    }

    /// The error for a plugin type that is not among `supported`, naming the nearest one.
    pub fn unknown_plugin(&self, supported: &[&str]) -> SceneError {
        let hint =
            nearest(&self.ty, supported.iter().copied()).map(|n| format!("; the nearest is '{n}'")).unwrap_or_default();
        self.error(format!("unsupported {} plugin (supported: {}{hint})", self.tag, supported.join(", ")))
    }

    /// An error at the object.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::at(&self.loc, format!("{} '{}': {}", self.tag, self.ty, message.into()))
    }

    /// A float (integers are accepted).
    pub fn float(&self, name: &str, default: f32) -> Result<f32> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    /// A float if present.
    pub fn float_opt(&self, name: &str) -> Result<Option<f32>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Float(v) => Ok(Some(*v as f32)),
                Value::Integer(v) => Ok(Some(*v as f32)),
                _ => Err(self.wrong(p, "a <float>")),
            },
        }
    }

    /// A float that must satisfy `ok` (described by `what`).
    pub fn float_checked(&self, name: &str, default: f32, ok: impl Fn(f32) -> bool, what: &str) -> Result<f32> {
        let v = self.float(name, default)?;
        if ok(v) {
            Ok(v)
        } else {
            Err(self.error_at(name, format!("'{name}' must be {what}, got {v}")))
        }
    }

    /// An integer.
    pub fn int(&self, name: &str, default: i64) -> Result<i64> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match &p.value {
                Value::Integer(v) => Ok(*v),
                _ => Err(self.wrong(p, "an <integer>")),
            },
        }
    }

    /// A boolean.
    pub fn bool(&self, name: &str, default: bool) -> Result<bool> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match &p.value {
                Value::Bool(v) => Ok(*v),
                _ => Err(self.wrong(p, "a <boolean>")),
            },
        }
    }

    /// A string if present.
    pub fn string_opt(&self, name: &str) -> Result<Option<String>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::String(v) => Ok(Some(v.clone())),
                _ => Err(self.wrong(p, "a <string>")),
            },
        }
    }

    /// A required string.
    pub fn string(&self, name: &str) -> Result<String> {
        self.string_opt(name)?.ok_or_else(|| self.error(format!("the parameter '{name}' (a <string>) is required")))
    }

    /// A string that must be one of `choices` (the first is the default).
    pub fn choice(&self, name: &str, choices: &[&str]) -> Result<String> {
        match self.string_opt(name)? {
            None => Ok(choices[0].to_string()),
            Some(v) if choices.contains(&v.as_str()) => Ok(v),
            Some(v) => {
                let hint =
                    nearest(&v, choices.iter().copied()).map(|n| format!(" (did you mean '{n}'?)")).unwrap_or_default();
                Err(self.error_at(name, format!("'{name}' must be one of {}, got '{v}'{hint}", choices.join(", "))))
            }
        }
    }

    /// A colour: `<rgb>`, `<spectrum>` (reduced to RGB as `kind`), or a `<float>` (grey).
    pub fn rgb_opt(&self, name: &str, kind: SpectrumKind) -> Result<Option<Rgb>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Rgb(c) => {
                    if kind == SpectrumKind::Reflectance && !(c.min_element() >= 0.0 && c.max_element() <= 1.0) {
                        // As Mitsuba's srgb reflectance spectrum; a <float> or <spectrum> is not
                        // range-checked.
                        return Err(SceneError::at(
                            &p.loc,
                            format!(
                                "'{name}' is a reflectance: an <rgb> value must lie in [0, 1], got {c} (as in Mitsuba; \
                                 a <float> or <spectrum> may exceed 1)"
                            ),
                        ));
                    }
                    Ok(Some(*c))
                }
                Value::Float(v) => Ok(Some(Rgb::splat(*v as f32))),
                Value::Integer(v) => Ok(Some(Rgb::splat(*v as f32))),
                Value::Spectrum(SpectrumValue::Constant(v)) => Ok(Some(match kind {
                    SpectrumKind::Reflectance | SpectrumKind::Unbounded => Rgb::splat(*v),
                    // Mitsuba: a constant emission spectrum is illuminant E times the value.
                    SpectrumKind::Illuminant => spectrum_to_rgb(&[(360.0, *v), (830.0, *v)], kind),
                })),
                Value::Spectrum(SpectrumValue::Samples(s)) => Ok(Some(spectrum_to_rgb(s, kind))),
                Value::Object(o) if o.tag == "texture" => Err(self.wrong(
                    p,
                    "a constant colour here (<rgb>, <spectrum> or <float>); textures are not supported for it",
                )),
                _ => Err(self.wrong(p, "a colour (<rgb>, <spectrum> or <float>)")),
            },
        }
    }

    /// A colour with a default.
    pub fn rgb(&self, name: &str, default: Rgb, kind: SpectrumKind) -> Result<Rgb> {
        let c = self.rgb_opt(name, kind)?.unwrap_or(default);
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(self.error_at(name, format!("'{name}' must be non-negative, got {c}")));
        }
        Ok(c)
    }

    /// A point (`<point>`), if present.
    pub fn point_opt(&self, name: &str) -> Result<Option<Vec3>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Point(v) | Value::Vector(v) => Ok(Some(*v)),
                _ => Err(self.wrong(p, "a <point>")),
            },
        }
    }

    /// A transform (identity if absent).
    pub fn transform(&self, name: &str) -> Result<Transform> {
        match self.get(name) {
            None => Ok(Transform::IDENTITY),
            Some(p) => match &p.value {
                Value::Transform(t) => Ok(*t),
                _ => Err(self.wrong(p, "a <transform>")),
            },
        }
    }

    /// A named nested object of element `tag`, if present.
    pub fn object_opt(&self, name: &str, tag: &str) -> Result<Option<Rc<Obj>>> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Object(o) if o.tag == tag => Ok(Some(o.clone())),
                _ => Err(self.wrong(p, &format!("a <{tag}>"))),
            },
        }
    }

    /// Nested objects of element `tag`: unnamed children and named properties, in order.
    pub fn nested(&self, tag: &str) -> Vec<Rc<Obj>> {
        let mut v: Vec<Rc<Obj>> = self.children.iter().filter(|c| c.tag == tag).cloned().collect();
        for p in &self.props {
            if let Value::Object(o) = &p.value {
                if o.tag == tag {
                    p.used.set(true);
                    v.push(o.clone());
                }
            }
        }
        v
    }

    /// Rejects nested objects of element kinds the plugin does not take.
    pub fn check_children(&self, allowed: &[&str]) -> Result<()> {
        for c in &self.children {
            if !allowed.contains(&c.tag.as_str()) {
                return Err(SceneError::at(
                    &c.loc,
                    format!("a <{}> cannot be nested in {} '{}'", c.tag, self.tag, self.ty),
                ));
            }
        }
        Ok(())
    }

    /// An error at the first parameter that no plugin read, in objects that were built
    /// (recursively), listing every such parameter of that object: Mitsuba 3's "unreferenced
    /// property" check (a misspelt name, a parameter of another plugin, or a feature neumann
    /// does not implement).
    pub fn check_unused(&self, seen: &mut Vec<*const Obj>) -> Result<()> {
        if seen.contains(&(self as *const Obj)) {
            return Ok(());
        }
        seen.push(self as *const Obj);
        if self.built.get() {
            let unused: Vec<&Prop> = self.props.iter().filter(|p| !p.used.get()).collect();
            if let Some(first) = unused.first() {
                let list: Vec<String> = unused.iter().map(|p| format!("{} '{}'", p.value.kind(), p.name)).collect();
                let s = if unused.len() == 1 { "" } else { "s" };
                return Err(SceneError::at(
                    &first.loc,
                    format!(
                        "{} '{}' does not take the parameter{s} {} (Mitsuba 3 also rejects unreferenced parameters; \
                         a misspelt name, or a parameter neumann does not implement)",
                        self.tag,
                        self.ty,
                        list.join(", ")
                    ),
                ));
            }
        }
        for p in &self.props {
            if let Value::Object(o) = &p.value {
                o.check_unused(seen)?;
            }
        }
        for c in &self.children {
            c.check_unused(seen)?;
        }
        Ok(())
    }
}
