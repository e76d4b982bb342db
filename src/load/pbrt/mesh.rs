//! pbrt-v4's meshes: `trianglemesh` (`indices`, `P`, `N`, `uv`; the indices may be left out
//! for a single triangle) and `bilinearmesh` (each patch of four vertices split into two
//! triangles: exact for planar patches), and PLY files (gzip-compressed too: `.ply.gz`).
//! `loopsubdiv` control meshes are subdivided here (`geometry::subdivision`).
//! pbrt's uv (0, 0) is an image's bottom-left; neumann's bitmaps flip it where they look images
//! up (the texture's `to_uv`), so the mesh's uv stay as written.

use super::params::ParamSet;
use crate::geometry::TriangleMesh;
use crate::load::limits;
use crate::math::{Vec2, Vec3};
use crate::props::SceneError;
use std::path::Path;

type Result<T> = std::result::Result<T, SceneError>;

/// A `trianglemesh` or `bilinearmesh` from its parameters.
pub fn from_params(ps: &ParamSet, bilinear: bool) -> Result<TriangleMesh> {
    let positions =
        ps.vec3s("P", &["point3", "point"])?.ok_or_else(|| ps.error("needs its vertex positions \"point3 P\""))?;
    if positions.is_empty() {
        return Err(ps.error_at("P", "\"P\" needs a multiple of 3 numbers, has 0"));
    }
    let n_vertices = positions.len();
    let normals: Vec<Vec3> = match ps.floats("N", &["normal3", "normal"])? {
        None => Vec::new(),
        Some(n) if n.len() == 3 * n_vertices => {
            n.chunks(3).map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)).collect()
        }
        Some(n) => {
            return Err(ps.error_at(
                "N",
                format!("\"N\" has {} numbers, \"P\" {}: one normal per vertex is needed", n.len(), 3 * n_vertices),
            ))
        }
    };
    let uvs: Vec<Vec2> = match ps.floats("uv", &["point2", "float"])? {
        None => Vec::new(),
        Some(t) if t.len() == 2 * n_vertices => t.chunks(2).map(|c| Vec2::new(c[0] as f32, c[1] as f32)).collect(),
        Some(t) => {
            return Err(
                ps.error_at("uv", format!("\"uv\" has {} numbers for {n_vertices} vertices (two per vertex)", t.len()))
            )
        }
    };
    for tangents in ["S", "faceIndices"] {
        if ps.has(tangents) {
            // Tangents and face indices (for ptex) cannot change an image without them.
            ps.floats(tangents, &["vector3", "vector", "integer"])?;
        }
    }
    let idx: Vec<f64> = match ps.floats("indices", &["integer"])? {
        Some(i) => i,
        None if !bilinear && n_vertices == 3 => vec![0.0, 1.0, 2.0],
        None if bilinear && n_vertices == 4 => vec![0.0, 1.0, 2.0, 3.0],
        None => return Err(ps.error("needs its \"integer indices\"")),
    };
    let per = if bilinear { 4 } else { 3 };
    if !idx.len().is_multiple_of(per) {
        return Err(ps.error_at("indices", format!("\"indices\" needs a multiple of {per} values, has {}", idx.len())));
    }
    let mut index = Vec::with_capacity(idx.len());
    for &i in &idx {
        if !(i >= 0.0 && i.fract() == 0.0 && (i as usize) < n_vertices) {
            return Err(
                ps.error_at("indices", format!("index {i} is out of range: the mesh has {n_vertices} vertices"))
            );
        }
        index.push(i as u32);
    }
    let indices: Vec<[u32; 3]> = if bilinear {
        // pbrt's patch (p00, p10, p01, p11): triangles (p00, p10, p11) and (p00, p11, p01).
        index.chunks(4).flat_map(|q| [[q[0], q[1], q[3]], [q[0], q[3], q[2]]]).collect()
    } else {
        index.chunks(3).map(|t| [t[0], t[1], t[2]]).collect()
    };
    TriangleMesh::new(positions, normals, uvs, indices).map_err(|e| ps.error(e.to_string()))
}

/// pbrt-v4's `loopsubdiv`: the control mesh `P`, `indices` subdivided `levels` (3) times and
/// pushed to the limit surface, with the limit normals (no uv, as in pbrt).
pub fn loop_subdivision(ps: &ParamSet) -> Result<TriangleMesh> {
    let levels = ps.int("levels", 3)?;
    if !(0..=12).contains(&levels) {
        return Err(ps.error_at("levels", format!("\"levels\" must be 0–12, got {levels}")));
    }
    let positions =
        ps.vec3s("P", &["point3", "point"])?.ok_or_else(|| ps.error("needs its control points \"point3 P\""))?;
    if positions.is_empty() {
        return Err(ps.error_at("P", "\"P\" needs a multiple of 3 numbers, has 0"));
    }
    let idx = ps.floats("indices", &["integer"])?.ok_or_else(|| ps.error("needs its \"integer indices\""))?;
    if idx.is_empty() || !idx.len().is_multiple_of(3) {
        return Err(ps.error_at("indices", format!("\"indices\" needs a multiple of 3 values, has {}", idx.len())));
    }
    let n = positions.len();
    let mut indices = Vec::with_capacity(idx.len() / 3);
    for t in idx.chunks(3) {
        let mut tri = [0u32; 3];
        for (k, &i) in t.iter().enumerate() {
            if !(i >= 0.0 && i.fract() == 0.0 && (i as usize) < n) {
                return Err(ps.error_at("indices", format!("index {i} is out of range: the mesh has {n} vertices")));
            }
            tri[k] = i as u32;
        }
        indices.push(tri);
    }
    let s = crate::geometry::subdivision::loop_subdivide(&positions, &indices, levels as u32)
        .map_err(|e| ps.error(format!("Loop subdivision: {e}")))?;
    TriangleMesh::new(s.positions, s.normals, Vec::new(), s.indices).map_err(|e| ps.error(e.to_string()))
}

/// A PLY file (`.ply` or gzip-compressed `.ply.gz`), normals and uv as stored.
pub fn read_ply(path: &Path) -> std::result::Result<TriangleMesh, String> {
    let data = limits::read_bounded(path, limits::MAX_FILE_BYTES).map_err(|e| e.to_string())?;
    let data = gunzip_if_compressed(path, data, limits::MAX_FILE_BYTES)?;
    crate::load::ply::parse_ply(&data).map_err(|e| format!("{}: {e}", path.display()))
}

/// `data` decompressed if it is gzip data (at most `limit` + 1 bytes, so that a size check after
/// it sees any excess), else as it is.
pub fn gunzip_if_compressed(path: &Path, data: Vec<u8>, limit: u64) -> std::result::Result<Vec<u8>, String> {
    if !data.starts_with(&[0x1f, 0x8b]) {
        return Ok(data);
    }
    use std::io::Read;
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(&data[..])
        .take(limit + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("{}: corrupt gzip data: {e}", path.display()))?;
    Ok(out)
}
