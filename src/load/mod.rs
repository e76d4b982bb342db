//! Loading files, the top layer: scene formats (Mitsuba 3 XML, [`mitsuba`]; glTF 2.0, [`gltf`]), which construct
//! scenes, integrators and render settings, and the files they name: Wavefront OBJ, Stanford
//! PLY and Mitsuba serialized meshes, images, grid volumes and tensor files. Errors name the
//! file, the line (for text formats) and what was expected.

pub mod build;
pub mod curve_file;
mod error;
pub mod gltf;
pub mod image;
pub mod limits;
pub mod memory;
pub mod nanovdb;
pub mod mitsuba;
pub mod obj;
pub mod overrides;
pub mod pbrt;
pub mod ply;
mod resolver;
#[cfg(test)]
pub(crate) mod test_support;
pub mod serialized;
pub mod tensor_file;
pub mod volume;

pub use error::LoadError;
pub use resolver::FileResolver;

use crate::film::filter::Filter;
use crate::geometry::TriangleMesh;
use crate::integrator::AnyIntegrator;
use crate::sampling::sampler::SamplerKind;
use crate::scene::Scene;
use std::path::Path;

/// A loaded scene file, whatever its format: the scene and the render settings it asks for.
#[derive(Debug)]
pub struct SceneFile {
    /// The scene (camera included).
    pub scene: Scene,
    /// The integrator (`path` or `direct`; `path` when the file names none).
    pub integrator: AnyIntegrator,
    /// Samples per pixel (the sampler's `sample_count`).
    pub spp: u32,
    /// Sampler kind (`independent`; `stratified`, `multijitter`, `orthogonal` → stratified;
    /// `ldsampler` → Sobol).
    pub sampler: SamplerKind,
    /// Sampler seed.
    pub seed: u64,
    /// Reconstruction filter (Mitsuba's default is a Gaussian of σ = 0.5).
    pub filter: Filter,
    /// Crop window `[x, y, w, h]`, if the film has one.
    pub window: Option<[u32; 4]>,
    /// Whether the film asks for an alpha channel (`pixel_format` `rgba`, `luminance_alpha`,
    /// `xyza`).
    pub alpha: bool,
    /// What the written image's colour channels hold (the rest of `pixel_format`).
    pub colors: crate::film::output::ColorChannels,
    /// The number type of the written EXR's channels (the film's `component_format`).
    pub component: crate::film::output::ComponentFormat,
    /// Whether the pixels just outside the film (or crop window) within the filter's reach are
    /// sampled too (the film's `sample_border`).
    pub sample_border: bool,
    /// What each sample becomes before the film (white balance, clamp): the film's.
    pub transform: crate::film::sensor::SampleTransform,
    /// The longest the render may take (Mitsuba's integrator `timeout`): it stops there or at
    /// `spp`, whichever comes first, with whole passes.
    pub time_limit: Option<std::time::Duration>,
    /// Warnings: things that cannot change the image (`-D` parameters the scene never uses).
    pub warnings: Vec<String>,
}

/// What kind of scene file `path` is, by its extension: glTF (`.gltf`, `.glb`) or Mitsuba 3 XML
/// (anything else).
pub fn is_gltf(path: &Path) -> bool {
    matches!(path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref(), Some("gltf" | "glb"))
}

/// Loads a scene file of any format neumann reads (by extension: pbrt-v4 `.pbrt` (or
/// `.pbrt.gz`), glTF 2.0 `.gltf` / `.glb`, else Mitsuba 3 XML), with `-D` parameters (`defines`, Mitsuba only), settings from the command
/// line, and the glTF camera to render (`camera`: a name or index).
pub fn load_scene(
    path: &Path,
    defines: &[(String, String)],
    settings: &overrides::Overrides,
    camera: Option<&str>,
) -> Result<SceneFile, crate::props::SceneError> {
    use crate::props::SceneError;
    let pbrt = matches!(path.extension().and_then(|e| e.to_str()), Some("pbrt"))
        || path.to_str().is_some_and(|p| p.ends_with(".pbrt.gz"));
    if pbrt {
        if let Some((name, _)) = defines.first() {
            return Err(SceneError::new(format!("-D {name}: a pbrt file has no parameters to set (-D is for Mitsuba scenes)")));
        }
        if let Some(c) = camera {
            return Err(SceneError::new(format!("--camera {c}: choosing a camera is for glTF files (a pbrt scene has one)")));
        }
        return pbrt::load_pbrt_file(path, settings);
    }
    if is_gltf(path) {
        if let Some((name, _)) = defines.first() {
            return Err(SceneError::new(format!("-D {name}: a glTF file has no parameters to set (-D is for Mitsuba scenes)")));
        }
        return gltf::load_gltf_file(path, settings, camera);
    }
    if let Some(c) = camera {
        return Err(SceneError::new(format!(
            "--camera {c}: choosing a camera is for glTF files (a Mitsuba scene has one sensor)"
        )));
    }
    mitsuba::load_scene_file_with(path, defines, settings)
}

/// Loads a triangle mesh from an `.obj` or `.ply` file (by extension).
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, LoadError> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("obj") => obj::load_obj(path),
        Some("ply") => ply::load_ply(path),
        _ => Err(LoadError::Unsupported {
            path: path.to_path_buf(),
            message: "unknown mesh format (expected .obj or .ply)".into(),
        }),
    }
}
