//! Loading files, the top layer: scene formats (Mitsuba 3 XML, [`mitsuba`]), which construct
//! scenes, integrators and render settings, and the files they name: Wavefront OBJ and Stanford
//! PLY meshes, PNG and OpenEXR images. Errors name the file, the line (for text formats) and what
//! was expected.

pub mod image;
pub mod mitsuba;
pub mod obj;
pub mod ply;

use crate::geometry::TriangleMesh;
use std::path::Path;

/// Loads a triangle mesh from an `.obj` or `.ply` file (by extension).
pub fn load_mesh(path: &Path) -> Result<TriangleMesh, String> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("obj") => obj::load_obj(path),
        Some("ply") => ply::load_ply(path),
        _ => Err(format!("{}: unknown mesh format (expected .obj or .ply)", path.display())),
    }
}
