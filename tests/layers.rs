//! The library's layering, enforced: every module of `src/` may use only the modules listed before
//! it (or itself). A `use crate::…` of a later layer — a loader imported by a texture, an
//! integrator by the scene — fails this test with the file and the offending path. Test modules
//! (`#[cfg(test)]` and below) may use anything.

use std::path::Path;

/// The layers, bottom first (as in the crate documentation).
const LAYERS: &[&str] = &[
    "choice",
    "math",
    "props",
    "image",
    "tensor",
    "sampling",
    "testkit",
    "estimators",
    "geometry",
    "bvh",
    "texture",
    "material",
    "light",
    "medium",
    "camera",
    "scene",
    "integrator",
    "film",
    "render",
    "load",
];

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level modules a source text names as `crate::<module>`.
fn crate_paths(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("crate::") {
        rest = &rest[i + "crate::".len()..];
        let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        names.push(name);
    }
    names
}

#[test]
fn no_module_uses_a_later_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        if name == "lib" || name == "bin" {
            continue;
        }
        assert!(LAYERS.contains(&name.as_str()), "module '{name}' has no layer: add it to LAYERS (and the crate docs)");
        if path.is_dir() {
            rust_files(&path, &mut files);
        } else {
            files.push(path);
        }
    }
    let mut violations = Vec::new();
    for file in &files {
        let relative = file.strip_prefix(&src).unwrap();
        let module = relative.components().next().unwrap().as_os_str().to_str().unwrap().trim_end_matches(".rs");
        let rank = LAYERS.iter().position(|l| *l == module).unwrap();
        let text = std::fs::read_to_string(file).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        for used in crate_paths(code) {
            if let Some(r) = LAYERS.iter().position(|l| *l == used) {
                if r > rank {
                    violations
                        .push(format!("src/{}: uses crate::{used} (a later layer than {module})", relative.display()));
                }
            }
        }
    }
    violations.sort();
    violations.dedup();
    assert!(violations.is_empty(), "upward imports:\n{}", violations.join("\n"));
}

#[test]
fn the_scanner_finds_paths() {
    assert_eq!(crate_paths("use crate::math::Rgb; x = crate::render::go();"), ["math", "render"]);
}
