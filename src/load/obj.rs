//! Wavefront OBJ: `v`, `vt`, `vn` and `f` records (polygons are triangulated as fans; negative
//! indices count from the end); other records (groups, materials, smoothing) are ignored.
//! Vertices are unified per distinct (position, uv, normal) triple.

use super::LoadError;
use crate::geometry::TriangleMesh;
use crate::math::{Vec2, Vec3};
use std::path::Path;

/// Loads an OBJ file.
pub fn load_obj(path: &Path) -> Result<TriangleMesh, LoadError> {
    let text = super::limits::read_text(path)?;
    parse_obj(&text).map_err(|(line, message)| LoadError::Format {
        path: path.to_path_buf(),
        line: Some(line),
        message,
    })
}

/// The vertices a mesh gets: one per distinct (position, texture, normal) triple of the
/// faces, numbered in order of first use. Found without hashing: each position lists the
/// vertices made from it (most positions have one, a seam's a few).
#[derive(Default)]
struct Unified {
    /// Per position: its most recent vertex, or [`NONE`].
    head: Vec<u32>,
    /// Per vertex: its texture and normal indices (or [`NONE`]) and the position's previous
    /// vertex (or [`NONE`]).
    keys: Vec<[u32; 3]>,
}

/// No index.
const NONE: u32 = u32::MAX;

impl Unified {
    /// The vertex of (`p`, `t`, `n`), if there is one already.
    fn find(&self, p: u32, t: u32, n: u32) -> Option<u32> {
        let mut k = self.head.get(p as usize).copied().unwrap_or(NONE);
        while k != NONE {
            let [kt, kn, next] = self.keys[k as usize];
            if (kt, kn) == (t, n) {
                return Some(k);
            }
            k = next;
        }
        None
    }

    /// Adds the vertex of (`p`, `t`, `n`) (not there yet) as the next one; returns its number.
    fn add(&mut self, p: u32, t: u32, n: u32) -> u32 {
        if p as usize >= self.head.len() {
            self.head.resize(p as usize + 1, NONE);
        }
        let id = self.keys.len() as u32;
        self.keys.push([t, n, self.head[p as usize]]);
        self.head[p as usize] = id;
        id
    }
}

/// Parses OBJ text; errors carry the 1-based line number.
pub fn parse_obj(text: &str) -> Result<TriangleMesh, (usize, String)> {
    let (mut v, mut vt, mut vn) = (Vec::new(), Vec::new(), Vec::new());
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    let mut unified = Unified::default();
    let mut corner = Vec::new();
    let (mut any_uv, mut any_n) = (false, false);
    for (ln, raw) in text.lines().enumerate() {
        let line_no = ln + 1;
        let line = raw.split_once('#').map_or(raw, |(before, _)| before).trim();
        let mut it = line.split_whitespace();
        let Some(tag) = it.next() else { continue };
        // The first `n` (at most 3) numbers of a record.
        let floats = |it: std::str::SplitWhitespace, n: usize, what: &str| -> Result<[f32; 3], (usize, String)> {
            let mut vals = [0.0; 3];
            let mut found = 0;
            for s in it.take(n) {
                vals[found] =
                    s.parse::<f32>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                        (line_no, format!("expected a finite number in '{what}' record, found '{s}'"))
                    })?;
                found += 1;
            }
            if found < n {
                return Err((line_no, format!("'{what}' record needs {n} numbers, found {found}")));
            }
            Ok(vals)
        };
        match tag {
            "v" => {
                let f = floats(it, 3, "v")?;
                v.push(Vec3::new(f[0], f[1], f[2]));
            }
            "vt" => {
                let f = floats(it, 2, "vt")?;
                vt.push(Vec2::new(f[0], f[1]));
            }
            "vn" => {
                let f = floats(it, 3, "vn")?;
                vn.push(Vec3::new(f[0], f[1], f[2]));
            }
            "f" => {
                corner.clear();
                for tok in it {
                    let mut parts = tok.split('/');
                    let resolve = |s: Option<&str>, len: usize, what: &str| -> Result<Option<usize>, (usize, String)> {
                        match s {
                            None | Some("") => Ok(None),
                            Some(s) => {
                                let i: i64 =
                                    s.parse().map_err(|_| (line_no, format!("bad {what} index '{s}' in face")))?;
                                let idx = if i > 0 { i - 1 } else { len as i64 + i };
                                if i == 0 || idx < 0 || idx >= len as i64 {
                                    return Err((line_no, format!("{what} index {i} out of range (have {len})")));
                                }
                                Ok(Some(idx as usize))
                            }
                        }
                    };
                    let p = resolve(parts.next(), v.len(), "vertex")?
                        .ok_or((line_no, "face corner without a vertex index".to_string()))?;
                    let t = resolve(parts.next(), vt.len(), "texture")?;
                    let n = resolve(parts.next(), vn.len(), "normal")?;
                    any_uv |= t.is_some();
                    any_n |= n.is_some();
                    // (Indices below u32::MAX: a file of 4 billion records is refused below.)
                    let small =
                        |i: Option<usize>| i.map_or(Some(NONE), |i| u32::try_from(i).ok().filter(|&i| i != NONE));
                    let (Some(pk), Some(tk), Some(nk)) = (small(Some(p)), small(t), small(n)) else {
                        return Err((line_no, "more than 4 billion vertices, texture coordinates or normals".into()));
                    };
                    let id = match unified.find(pk, tk, nk) {
                        Some(id) => id,
                        None => {
                            positions.push(v[p]);
                            uvs.push(t.map_or(Vec2::ZERO, |t| vt[t]));
                            normals.push(n.map_or(Vec3::ZERO, |n| vn[n]));
                            unified.add(pk, tk, nk)
                        }
                    };
                    corner.push(id);
                }
                if corner.len() < 3 {
                    return Err((line_no, format!("face with {} vertices (need at least 3)", corner.len())));
                }
                for k in 1..corner.len() - 1 {
                    indices.push([corner[0], corner[k], corner[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if !any_uv {
        uvs.clear();
    }
    if !any_n || normals.contains(&Vec3::ZERO) {
        normals.clear();
    }
    TriangleMesh::new(positions, normals, uvs, indices).map_err(|e| (0, e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_quads_negative_indices_and_attributes() {
        let text = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 -1/-1/-1\n";
        let m = parse_obj(text).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.uvs.len(), 4);
        assert_eq!(m.normals.len(), 4);
        assert!((m.area() - 1.0).abs() < 1e-6);
    }

    /// One vertex per distinct (position, uv, normal) triple, numbered in order of first use: a
    /// position met again with another uv (a seam) or another normal is a new vertex, the same
    /// triple met again is the same one, whichever records come between.
    #[test]
    fn vertices_are_unified_per_triple_in_order_of_first_use() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\nvn 0 0 1\nvn 0 0 -1\n\
                    f 1/1/1 2/2/1 3/3/1\nf 2/4/1 4/2/1 3/3/1\nf 3/3/2 2/2/1 1/1/1\nf 1/1/1 2/2/1 3/3/1\n";
        let m = parse_obj(text).unwrap();
        assert_eq!(m.indices, vec![[0, 1, 2], [3, 4, 2], [5, 1, 0], [0, 1, 2]]);
        assert_eq!(
            m.positions,
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ]
        );
        assert_eq!(m.uvs[3], Vec2::new(0.5, 0.5));
        assert_eq!(m.normals[5], Vec3::new(0.0, 0.0, -1.0));
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse_obj("v 0 0 0\nv 1 0\n").unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("3 numbers"), "{}", e.1);
        let e = parse_obj("v 0 0 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("out of range"));
        let e = parse_obj("v 0 0 x\n").unwrap_err();
        assert!(e.1.contains("'x'"));
    }

    /// Errors from a file name the file and the line.
    #[test]
    fn file_errors_are_located() {
        let dir = std::env::temp_dir().join(format!("neumann-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
        let e = load_obj(&path).unwrap_err();
        assert!(matches!(e, LoadError::Format { line: Some(4), .. }), "{e:?}");
        assert!(e.to_string().starts_with(&format!("{}:4: ", path.display())), "{e}");
        assert!(matches!(load_obj(&dir.join("none.obj")).unwrap_err(), LoadError::Io { .. }));
        std::fs::remove_dir_all(&dir).ok();
    }
}
