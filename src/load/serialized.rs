//! Mitsuba's `serialized` meshes: a file of zlib-compressed triangle meshes, one chosen by its
//! index. Layout (little-endian): each mesh starts with the format tag `0x041C` (u16) and a
//! version (u16: 3 or 4), followed by a zlib stream holding: flags (u32; `0x0001` vertex normals,
//! `0x0002` texture coordinates, `0x0008` vertex colours, `0x0010` face normals, `0x1000`
//! single / `0x2000` double precision), in version 4 the mesh's name (NUL-terminated UTF-8), the
//! vertex and triangle counts (u64 each), positions, then normals, uvs and colours as the flags
//! say (3, 2, 3 scalars per vertex), then the triangles' vertex indices (u32, or u64 past 2³²
//! vertices). The file ends with the byte offset of every mesh (u64 in version 4, u32 in
//! version 3) and their count (u32).

use super::LoadError;
use crate::geometry::TriangleMesh;
use crate::math::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

const FORMAT_TAG: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const FACE_NORMALS: u32 = 0x0010;
const SINGLE_PRECISION: u32 = 0x1000;
const DOUBLE_PRECISION: u32 = 0x2000;

/// A mesh read from a serialized file, with what the file says about its shading.
#[derive(Debug)]
pub struct SerializedMesh {
    /// The mesh (normals and uvs if the file has them).
    pub mesh: TriangleMesh,
    /// The file asks for flat shading (`face normals` flag).
    pub face_normals: bool,
    /// The mesh's name (version 4), if any.
    pub name: String,
    /// Per-vertex colours, if the file has them (linear RGB).
    pub colors: Vec<Vec3>,
}

/// Reads mesh `index` (0-based) of the serialized file at `path`.
pub fn load_serialized(path: &Path, index: usize) -> Result<SerializedMesh, LoadError> {
    let bytes = super::limits::read_bounded(path, super::limits::MAX_FILE_BYTES)?;
    let fail = |m: String| LoadError::format(path, m);
    if bytes.len() < 8 {
        return Err(fail("too short for a serialized mesh file".into()));
    }
    let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]);
    if u16_at(0) != FORMAT_TAG {
        return Err(fail(format!("not a Mitsuba serialized mesh (format tag {:#06x}, expected 0x041c)", u16_at(0))));
    }
    let version = u16_at(2);
    if version != 3 && version != 4 {
        return Err(fail(format!("serialized mesh version {version} (neumann reads versions 3 and 4)")));
    }
    let count = u32::from_le_bytes(bytes[bytes.len() - 4..].try_into().expect("4 bytes")) as usize;
    if index >= count {
        return Err(fail(format!("shape_index {index} is out of range: the file holds {count} meshes")));
    }
    let offset_size = if version == 4 { 8 } else { 4 };
    let table = bytes
        .len()
        .checked_sub(4 + count.checked_mul(offset_size).ok_or_else(|| fail("corrupt mesh count".into()))?)
        .ok_or_else(|| fail(format!("the file is too short for its table of {count} meshes")))?;
    let at = table + index * offset_size;
    let start = if version == 4 {
        u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes")) as usize
    } else {
        u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize
    };
    if start + 4 > table || u16_at(start) != FORMAT_TAG || u16_at(start + 2) != version {
        return Err(fail(format!("mesh {index} does not start with the format tag at byte {start}")));
    }
    // A hostile stream could inflate without bound: stop at 16 GiB (a billion-triangle mesh).
    const MAX_INFLATED: u64 = 16 << 30;
    let mut data = Vec::new();
    flate2::read::ZlibDecoder::new(&bytes[start + 4..table])
        .take(MAX_INFLATED + 1)
        .read_to_end(&mut data)
        .map_err(|e| fail(format!("mesh {index}: corrupt compressed data: {e}")))?;
    if data.len() as u64 > MAX_INFLATED {
        return Err(fail(format!("mesh {index} inflates to more than 16 GiB")));
    }
    parse(&data, version, index).map_err(fail)
}

/// A cursor over the decompressed mesh data.
struct Reader<'a> {
    data: &'a [u8],
    at: usize,
    double: bool,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len()).ok_or("the mesh data ends early")?;
        let s = &self.data[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }
    /// `n` scalars in the file's precision.
    fn floats(&mut self, n: usize) -> Result<Vec<f32>, String> {
        let double = self.double;
        let size = if double { 8 } else { 4 };
        let raw = self.take(n.checked_mul(size).ok_or("corrupt count")?)?;
        Ok(if double {
            raw.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")) as f32).collect()
        } else {
            raw.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect()
        })
    }
}

fn parse(data: &[u8], version: u16, index: usize) -> Result<SerializedMesh, String> {
    let mut r = Reader { data, at: 0, double: false };
    let flags = r.u32()?;
    r.double = match (flags & SINGLE_PRECISION != 0, flags & DOUBLE_PRECISION != 0) {
        (true, false) => false,
        (false, true) => true,
        _ => return Err(format!("mesh {index}: flags {flags:#x} name neither single nor double precision")),
    };
    let mut name = String::new();
    if version == 4 {
        let end = data[r.at..].iter().position(|&b| b == 0).ok_or("the mesh name is not terminated")?;
        name = String::from_utf8_lossy(&data[r.at..r.at + end]).into_owned();
        r.at += end + 1;
    }
    let vertices = usize::try_from(r.u64()?).map_err(|_| "vertex count too large")?;
    let triangles = usize::try_from(r.u64()?).map_err(|_| "triangle count too large")?;
    let vec3s = |v: Vec<f32>| v.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>();
    let positions = vec3s(r.floats(vertices.checked_mul(3).ok_or("corrupt vertex count")?)?);
    let normals = if flags & HAS_NORMALS != 0 { vec3s(r.floats(vertices * 3)?) } else { Vec::new() };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        r.floats(vertices * 2)?.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect()
    } else {
        Vec::new()
    };
    let colors = if flags & HAS_COLORS != 0 { vec3s(r.floats(vertices * 3)?) } else { Vec::new() };
    let wide = vertices > u32::MAX as usize;
    // Capacity from the counts in the file only as far as the data can hold them.
    let index_size = if wide { 24 } else { 12 };
    let mut indices = Vec::with_capacity(triangles.min((data.len() - r.at) / index_size));
    for _ in 0..triangles {
        let mut t = [0u32; 3];
        for v in &mut t {
            let i = if wide { r.u64()? } else { r.u32()? as u64 };
            if i as usize >= vertices {
                return Err(format!("mesh {index}: vertex index {i} out of range ({vertices} vertices)"));
            }
            *v = i as u32;
        }
        indices.push(t);
    }
    let mesh = TriangleMesh::new(positions, normals, uvs, indices).map_err(|e| format!("mesh {index}: {e}"))?;
    Ok(SerializedMesh { mesh, face_normals: flags & FACE_NORMALS != 0, name, colors })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::io::Write;

    /// Writes meshes in the serialized format (version 4, single precision; normals and uvs if
    /// given): what Mitsuba's `mtsutil` and exporters write.
    pub(crate) fn write_serialized(meshes: &[(&TriangleMesh, bool)]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for (m, face_normals) in meshes {
            offsets.push(out.len() as u64);
            out.extend_from_slice(&FORMAT_TAG.to_le_bytes());
            out.extend_from_slice(&4u16.to_le_bytes());
            let mut raw = Vec::new();
            let mut flags = SINGLE_PRECISION;
            if !m.normals.is_empty() {
                flags |= HAS_NORMALS;
            }
            if !m.uvs.is_empty() {
                flags |= HAS_TEXCOORDS;
            }
            if *face_normals {
                flags |= FACE_NORMALS;
            }
            raw.extend_from_slice(&flags.to_le_bytes());
            raw.extend_from_slice(b"part\0");
            raw.extend_from_slice(&(m.positions.len() as u64).to_le_bytes());
            raw.extend_from_slice(&(m.indices.len() as u64).to_le_bytes());
            let mut put = |v: &[f32]| v.iter().for_each(|x| raw.extend_from_slice(&x.to_le_bytes()));
            put(&m.positions.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
            put(&m.normals.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
            put(&m.uvs.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
            for t in &m.indices {
                t.iter().for_each(|i| raw.extend_from_slice(&i.to_le_bytes()));
            }
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(&raw).unwrap();
            out.extend_from_slice(&z.finish().unwrap());
        }
        for o in &offsets {
            out.extend_from_slice(&o.to_le_bytes());
        }
        out.extend_from_slice(&(offsets.len() as u32).to_le_bytes());
        out
    }

    #[test]
    fn reads_the_chosen_mesh_and_rejects_bad_files() {
        let dir = std::env::temp_dir().join(format!("neumann-serialized-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let quad = TriangleMesh::rectangle();
        let cube = TriangleMesh::cube();
        let path = dir.join("two.serialized");
        std::fs::write(&path, write_serialized(&[(&quad, false), (&cube, true)])).unwrap();
        let a = load_serialized(&path, 0).unwrap();
        assert_eq!((a.mesh.positions.clone(), a.mesh.indices.clone()), (quad.positions.clone(), quad.indices.clone()));
        assert_eq!(a.mesh.uvs, quad.uvs);
        assert!(!a.face_normals);
        assert_eq!(a.name, "part");
        let b = load_serialized(&path, 1).unwrap();
        assert_eq!(b.mesh.len(), cube.len());
        assert!(b.face_normals);
        let e = load_serialized(&path, 2).unwrap_err().to_string();
        assert!(e.contains("shape_index 2 is out of range: the file holds 2"), "{e}");
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[10] ^= 0xff; // inside the first compressed stream
        std::fs::write(&path, &bytes).unwrap();
        assert!(load_serialized(&path, 0).is_err());
        // A header that claims 2⁴⁰ triangles over a few bytes of data: an error, not an abort.
        let mut raw = Vec::new();
        raw.extend_from_slice(&SINGLE_PRECISION.to_le_bytes());
        raw.extend_from_slice(b"x\0");
        raw.extend_from_slice(&3u64.to_le_bytes());
        raw.extend_from_slice(&(1u64 << 40).to_le_bytes());
        raw.extend_from_slice(&[0u8; 9 * 4 + 3 * 4]);
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&raw).unwrap();
        let mut file = [FORMAT_TAG.to_le_bytes(), 4u16.to_le_bytes()].concat();
        file.extend_from_slice(&z.finish().unwrap());
        file.extend_from_slice(&0u64.to_le_bytes());
        file.extend_from_slice(&1u32.to_le_bytes());
        std::fs::write(&path, &file).unwrap();
        assert!(load_serialized(&path, 0).unwrap_err().to_string().contains("ends early"));
        std::fs::write(&path, b"not a mesh").unwrap();
        assert!(load_serialized(&path, 0).unwrap_err().to_string().contains("format tag"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
