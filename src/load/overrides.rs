//! Settings from outside the scene file — command-line flags such as `--spp`, `--max-depth`,
//! `--res` — applied as properties of the scene's located objects before the plugins build, so
//! that the plugins validate them like the file's own parameters and report problems the same
//! way (at `command line:1:1`, quoting the flag).
//!
//! Each override names its target object (the integrator, the sensor's sampler or its film) and
//! replaces the property of that name, or adds it; a missing target object is created with
//! Mitsuba's default plugin (`path`, `independent`, `hdrfilm`). `--integrator` replaces the
//! integrator object by one of the requested type that keeps the file's path-length settings
//! (`max_depth`, `rr_depth`, `hide_emitters`) where the new type takes them.

use crate::choice::Choice;
use crate::integrator::aov::AovKind;
use crate::integrator::IntegratorKind;
use crate::props::{Loc, Obj, Prop, SourceFile, Value};
use std::rc::Rc;
use std::sync::Arc;

/// The object an override sets a parameter of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The scene's `<integrator>`.
    Integrator,
    /// The sensor's `<sampler>`.
    Sampler,
    /// The sensor's `<film>`.
    Film,
}

/// One parameter set from outside the file.
#[derive(Clone, Debug)]
pub struct Override {
    /// Which object.
    pub target: Target,
    /// The parameter's name (Mitsuba's).
    pub name: String,
    /// Its value.
    pub value: Value,
    /// Where it came from, as the user wrote it (e.g. `--max-depth 8`), for messages.
    pub source: String,
}

impl Override {
    /// An override of `target`'s parameter `name` by `value`, given as `source`.
    pub fn new(target: Target, name: &str, value: Value, source: impl Into<String>) -> Override {
        Override { target, name: name.to_string(), value, source: source.into() }
    }

    fn loc(&self) -> Loc {
        Loc { file: Arc::new(SourceFile { path: "command line".into(), text: self.source.clone() }), offset: 0 }
    }

    fn prop(&self) -> Prop {
        Prop::new(&self.name, self.value.clone(), self.loc())
    }
}

/// Everything set from outside the file.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// Replace the integrator by one of this kind (`--integrator`).
    pub integrator: Option<(IntegratorKind, String)>,
    /// Parameters.
    pub settings: Vec<Override>,
}

impl Overrides {
    /// Whether nothing is overridden.
    pub fn is_empty(&self) -> bool {
        self.integrator.is_none() && self.settings.is_empty()
    }

    fn for_target(&self, t: Target) -> Vec<&Override> {
        self.settings.iter().filter(|o| o.target == t).collect()
    }
}

/// A copy of `o` (its nested objects shared) whose properties named by `set` are replaced, and
/// the others kept.
fn with_props(o: &Obj, set: &[&Override]) -> Obj {
    let mut props: Vec<Prop> = o
        .props
        .iter()
        .filter(|p| !set.iter().any(|s| s.name == p.name))
        .map(|p| Prop::new(&p.name, p.value.clone(), p.loc.clone()))
        .collect();
    props.extend(set.iter().map(|s| s.prop()));
    Obj { id: o.id.clone(), props, children: o.children.clone(), ..Obj::new(&o.tag, &o.ty, o.loc.clone()) }
}

/// A new object `<tag type=ty>` at `loc` with `props` and `children`.
fn object(tag: &str, ty: &str, loc: &Loc, props: Vec<Prop>, children: Vec<Rc<Obj>>) -> Obj {
    Obj { props, children, ..Obj::new(tag, ty, loc.clone()) }
}

/// The integrator object `--integrator kind` makes of `file` (the file's integrator, if any):
/// the file's `max_depth`, `rr_depth` and `hide_emitters` where the new kind takes them (only
/// `hide_emitters` for `direct`, none for `radiosity` and `depth`); `moment` and `aov` wrap a
/// path tracer with them (`aov` recording every AOV type, each named after it).
fn switched_integrator(kind: IntegratorKind, source: &str, file: Option<&Obj>) -> Obj {
    let loc = Loc { file: Arc::new(SourceFile { path: "command line".into(), text: source.to_string() }), offset: 0 };
    let keep = |names: &[&str]| -> Vec<Prop> {
        let Some(f) = file else { return Vec::new() };
        // A moment or aov file integrator keeps its settings on its first nested integrator.
        let from = if matches!(f.ty.as_str(), "moment" | "aov") {
            f.nested("integrator").first().map(|c| with_props(c, &[])).unwrap_or_else(|| with_props(f, &[]))
        } else {
            with_props(f, &[])
        };
        from.props.into_iter().filter(|p| names.contains(&p.name.as_str())).collect()
    };
    let path_settings = ["max_depth", "rr_depth", "hide_emitters"];
    match kind {
        IntegratorKind::Radiosity => object("integrator", "radiosity", &loc, Vec::new(), Vec::new()),
        IntegratorKind::Direct => object("integrator", "direct", &loc, keep(&["hide_emitters"]), Vec::new()),
        IntegratorKind::Depth => object("integrator", "depth", &loc, Vec::new(), Vec::new()),
        IntegratorKind::Moment | IntegratorKind::Aov => {
            let path = Rc::new(object("integrator", "path", &loc, keep(&path_settings), Vec::new()));
            let mut props = Vec::new();
            if kind == IntegratorKind::Aov {
                let all: Vec<String> = AovKind::CHOICES.iter().map(|c| format!("{0}:{0}", c.1)).collect();
                props.push(Prop::new("aovs", Value::String(all.join(",")), loc.clone()));
            }
            object("integrator", kind.name(), &loc, props, vec![path])
        }
        _ => object("integrator", kind.name(), &loc, keep(&path_settings), Vec::new()),
    }
}

/// `root` (a `<scene>`) with `overrides` applied: its integrator, and its sensor's sampler and
/// film, replaced by overridden copies (or created). The rest of the tree is shared.
pub fn apply(root: &Rc<Obj>, overrides: &Overrides) -> Rc<Obj> {
    if overrides.is_empty() {
        return root.clone();
    }
    let integrator_set = overrides.for_target(Target::Integrator);
    let mut children: Vec<Rc<Obj>> = Vec::with_capacity(root.children.len() + 1);
    let mut had_integrator = false;
    for c in &root.children {
        match c.tag.as_str() {
            "integrator" => {
                had_integrator = true;
                let base = match &overrides.integrator {
                    Some((kind, source)) if kind.name() != c.ty => switched_integrator(*kind, source, Some(c)),
                    _ => with_props(c, &[]),
                };
                children.push(Rc::new(set_integrator(&base, &integrator_set)));
            }
            "sensor" => children.push(Rc::new(sensor(c, overrides))),
            _ => children.push(c.clone()),
        }
    }
    if !had_integrator && (overrides.integrator.is_some() || !integrator_set.is_empty()) {
        let (kind, source) =
            overrides.integrator.clone().unwrap_or((IntegratorKind::Path, integrator_set[0].source.clone()));
        let base = switched_integrator(kind, &source, None);
        children.insert(0, Rc::new(set_integrator(&base, &integrator_set)));
    }
    let mut scene = with_props(root, &[]);
    scene.children = children;
    Rc::new(scene)
}

/// The integrator `o` with `set` applied; `moment` and `aov` pass them to their first nested
/// integrator (whose path settings they render with).
fn set_integrator(o: &Obj, set: &[&Override]) -> Obj {
    if !matches!(o.ty.as_str(), "moment" | "aov") || set.is_empty() {
        return with_props(o, set);
    }
    let mut copy = with_props(o, &[]);
    if let Some(c) = copy.children.iter_mut().find(|c| c.tag == "integrator") {
        *c = Rc::new(set_integrator(c, set));
        return copy;
    }
    if let Some(p) = copy.props.iter_mut().find(|p| matches!(&p.value, Value::Object(v) if v.tag == "integrator")) {
        if let Value::Object(v) = &p.value {
            p.value = Value::Object(Rc::new(set_integrator(v, set)));
        }
        return copy;
    }
    with_props(o, set)
}

/// A sensor with its sampler and film overridden (created when absent and overridden).
fn sensor(s: &Obj, overrides: &Overrides) -> Obj {
    let mut copy = with_props(s, &[]);
    for (target, tag, default_ty) in [(Target::Sampler, "sampler", "independent"), (Target::Film, "film", "hdrfilm")] {
        let set = overrides.for_target(target);
        if set.is_empty() {
            continue;
        }
        let mut found = false;
        for c in copy.children.iter_mut().filter(|c| c.tag == tag) {
            *c = Rc::new(with_props(c, &set));
            found = true;
        }
        for p in copy.props.iter_mut() {
            if let Value::Object(o) = &p.value {
                if o.tag == tag {
                    p.value = Value::Object(Rc::new(with_props(o, &set)));
                    found = true;
                }
            }
        }
        if !found {
            let base = object(tag, default_ty, &set[0].loc(), Vec::new(), Vec::new());
            copy.children.push(Rc::new(with_props(&base, &set)));
        }
    }
    copy
}
