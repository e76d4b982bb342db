//! Mitsuba 3 XML scene files: `neumann render scene.xml`.
//!
//! [`load_scene_file`] parses the file ([`parse`]: defaults, `$` substitution, includes, ids and
//! references, transforms, typed properties with positions) into located objects, which the
//! format-neutral [`crate::load::build`] turns into the scene.
//! Every problem is a [`SceneError`] naming `file:line:col` with the source line, parameters that
//! no plugin reads included (Mitsuba 3 rejects unreferenced properties too); `-D` parameters the
//! scene never uses come back as warnings.

pub mod parse;

pub use crate::props::SceneError;

use crate::load::overrides::Overrides;
use std::path::Path;

pub use super::SceneFile;

/// Loads a Mitsuba 3 XML scene. `overrides` are `-D name=value` parameters; one that no `$name`
/// of the scene uses is reported in the warnings (as Mitsuba reports unused parameters).
pub fn load_scene_file(path: &Path, overrides: &[(String, String)]) -> Result<SceneFile, SceneError> {
    load_scene_file_with(path, overrides, &Overrides::default())
}

/// [`load_scene_file`] with settings from outside the file (`settings`: command-line flags),
/// applied to the scene's objects before the plugins build ([`crate::load::overrides`]).
pub fn load_scene_file_with(
    path: &Path,
    defines: &[(String, String)],
    settings: &Overrides,
) -> Result<SceneFile, SceneError> {
    let mut parser = parse::Parser::new(defines);
    let root = parser.parse_file(path)?;
    finish(parser, crate::load::overrides::apply(&root, settings))
}

/// Loads a scene from XML text (`path` names it in messages and anchors relative paths).
pub fn load_scene_text(path: &Path, text: &str, overrides: &[(String, String)]) -> Result<SceneFile, SceneError> {
    let mut parser = parse::Parser::new(overrides);
    let root = parser.parse_text(path.to_path_buf(), text.to_string())?;
    finish(parser, root)
}

fn finish(parser: parse::Parser, root: std::rc::Rc<crate::props::Obj>) -> Result<SceneFile, SceneError> {
    let mut file = crate::load::build::Builder::new(parser.resolver.clone()).build(&root)?;
    file.warnings.extend(parser.warnings.take());
    for name in parser.unused_overrides() {
        file.warnings.push(format!("warning: -D {name}: the scene has no ${name} to substitute"));
    }
    Ok(file)
}

#[cfg(test)]
mod tests;
