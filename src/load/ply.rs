//! Stanford PLY meshes, ASCII and binary (little- and big-endian): `vertex` elements with
//! `x y z`, optional `nx ny nz` and `u v` / `s t` / `texture_u texture_v`, and `face` elements
//! with a `vertex_indices` (or `vertex_index`) list, triangulated as fans. Other properties of
//! vertices and faces become mesh attributes as Mitsuba 3 names them, which `mesh_attribute`
//! textures look up (raw values, integers not rescaled, as Mitsuba reads them): colours `r g b`
//! (or `red green blue`) become `vertex_color` / `face_color`, and each run of properties
//! `NAME_p` whose one-character suffixes follow `x y z`, `r g b`, `0 1 2` or `1 2 3` (one or
//! three of them) becomes `vertex_NAME` / `face_NAME` (`…_color` for `r g b`). Other properties
//! and elements are read and skipped.

use super::LoadError;
use crate::geometry::ellipsoids::PointTable;
use crate::geometry::mesh::MeshAttribute;
use crate::geometry::TriangleMesh;
use crate::math::{Vec2, Vec3};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Scalar,
    /// For lists: the type of the count.
    list_count: Option<Scalar>,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// Loads a PLY file.
pub fn load_ply(path: &Path) -> Result<TriangleMesh, LoadError> {
    let data = super::limits::read_bounded(path, super::limits::MAX_FILE_BYTES)?;
    parse_ply(&data).map_err(|e| LoadError::format(path, e))
}

/// A reader of property values from the body.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    enc: Encoding,
}

impl Body<'_> {
    fn next_token(&mut self) -> Option<&str> {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (start < self.pos).then(|| std::str::from_utf8(&self.data[start..self.pos]).unwrap_or(""))
    }

    fn read(&mut self, kind: Scalar) -> Result<f64, String> {
        if self.enc == Encoding::Ascii {
            let t = self.next_token().ok_or("unexpected end of data")?;
            return t.parse::<f64>().map_err(|_| format!("expected a number in the body, found '{t}'"));
        }
        let n = kind.size();
        if self.pos + n > self.data.len() {
            return Err("unexpected end of binary data".into());
        }
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.pos += n;
        if self.enc == Encoding::Big {
            b[..n].reverse();
        }
        Ok(match kind {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

/// Parses a PLY header: its elements, the body's encoding and where the body starts.
fn parse_header(data: &[u8]) -> Result<(Vec<Element>, Encoding, usize), String> {
    // Header: text lines up to "end_header".
    let mut pos = 0;
    let mut lines = Vec::new();
    loop {
        let end = data[pos..].iter().position(|&c| c == b'\n').ok_or("header has no 'end_header' line")? + pos;
        let line = String::from_utf8_lossy(&data[pos..end]).trim().to_string();
        pos = end + 1;
        if line == "end_header" {
            break;
        }
        lines.push(line);
    }
    if lines.first().map(String::as_str) != Some("ply") {
        return Err("not a PLY file (missing 'ply' magic)".into());
    }
    let mut enc = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(1) {
        let w: Vec<&str> = line.split_whitespace().collect();
        let at = |msg: String| format!("header line {}: {msg}", i + 1);
        match w.first().copied() {
            Some("format") => {
                enc = Some(match w.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::Little,
                    Some("binary_big_endian") => Encoding::Big,
                    other => return Err(at(format!("unknown format {other:?}"))),
                })
            }
            Some("element") => {
                let (Some(name), Some(count)) = (w.get(1), w.get(2).and_then(|c| c.parse().ok())) else {
                    return Err(at("expected 'element NAME COUNT'".into()));
                };
                elements.push(Element { name: name.to_string(), count, props: Vec::new() });
            }
            Some("property") => {
                let el = elements.last_mut().ok_or_else(|| at("property before any element".into()))?;
                let prop = if w.get(1) == Some(&"list") {
                    let (Some(c), Some(k), Some(name)) =
                        (w.get(2).and_then(|s| Scalar::parse(s)), w.get(3).and_then(|s| Scalar::parse(s)), w.get(4))
                    else {
                        return Err(at("expected 'property list COUNT_TYPE ITEM_TYPE NAME'".into()));
                    };
                    Property { name: name.to_string(), kind: k, list_count: Some(c) }
                } else {
                    let (Some(k), Some(name)) = (w.get(1).and_then(|s| Scalar::parse(s)), w.get(2)) else {
                        return Err(at(format!("expected 'property TYPE NAME', found '{line}'")));
                    };
                    Property { name: name.to_string(), kind: k, list_count: None }
                };
                el.props.push(prop);
            }
            Some("comment") | Some("obj_info") | None => {}
            Some(other) => return Err(at(format!("unknown header keyword '{other}'"))),
        }
    }
    let enc = enc.ok_or("header has no 'format' line")?;
    Ok((elements, enc, pos))
}

/// Parses a PLY file's bytes.
pub fn parse_ply(data: &[u8]) -> Result<TriangleMesh, String> {
    let (elements, enc, pos) = parse_header(data)?;
    let mut body = Body { data, pos, enc };
    let (mut positions, mut normals, mut uvs, mut indices) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // Mitsuba's mesh attributes of vertices and of faces (one value per triangle of a face's
    // fan): (name, the properties holding its 1 or 3 channels, values).
    let mut attributes: Vec<(MeshAttribute, Vec<usize>)> = Vec::new();
    for el in &elements {
        let find = |names: &[&str]| el.props.iter().position(|p| names.contains(&p.name.as_str()));
        let (ix, iy, iz) = (find(&["x"]), find(&["y"]), find(&["z"]));
        let (inx, iny, inz) = (find(&["nx"]), find(&["ny"]), find(&["nz"]));
        let (iu, iv) = (find(&["u", "s", "texture_u", "texture_s"]), find(&["v", "t", "texture_v", "texture_t"]));
        let iface = find(&["vertex_indices", "vertex_index"]);
        let first_attribute = attributes.len();
        let kind = match el.name.as_str() {
            "vertex" => Some(false),
            "face" if iface.is_some() => Some(true),
            _ => None,
        };
        if let Some(per_face) = kind {
            let uv_names: &[&str] = if iu.is_some() && iv.is_some() { &["u", "v", "s", "t", "texture_u", "texture_v", "texture_s", "texture_t"] } else { &[] };
            for (name, channels) in attribute_groups(&el.props, uv_names) {
                let name = format!("{}_{name}", if per_face { "face" } else { "vertex" });
                attributes.push((MeshAttribute { name, per_face, values: Vec::new() }, channels));
            }
        }
        if el.props.is_empty() {
            // No data per item, whatever the count.
            continue;
        }
        let mut vals = vec![0.0f64; el.props.len()];
        let mut list: Vec<u32> = Vec::new();
        for item in 0..el.count {
            for (k, p) in el.props.iter().enumerate() {
                match p.list_count {
                    None => vals[k] = body.read(p.kind).map_err(|e| format!("{} {item}: {e}", el.name))?,
                    Some(ct) => {
                        let n = body.read(ct).map_err(|e| format!("{} {item}: {e}", el.name))? as usize;
                        let keep = Some(k) == iface;
                        if keep {
                            list.clear();
                        }
                        for _ in 0..n {
                            let x = body.read(p.kind).map_err(|e| format!("{} {item}: {e}", el.name))?;
                            if keep {
                                if !(x >= 0.0 && x <= u32::MAX as f64 && x.fract() == 0.0) {
                                    return Err(format!("{} {item}: vertex index {x} is not a non-negative integer", el.name));
                                }
                                list.push(x as u32);
                            }
                        }
                    }
                }
            }
            if el.name == "vertex" {
                let (Some(x), Some(y), Some(z)) = (ix, iy, iz) else {
                    return Err("vertex element lacks x, y or z".into());
                };
                positions.push(Vec3::new(vals[x] as f32, vals[y] as f32, vals[z] as f32));
                if let (Some(a), Some(b), Some(c)) = (inx, iny, inz) {
                    normals.push(Vec3::new(vals[a] as f32, vals[b] as f32, vals[c] as f32));
                }
                if let (Some(a), Some(b)) = (iu, iv) {
                    uvs.push(Vec2::new(vals[a] as f32, vals[b] as f32));
                }
                for (a, channels) in &mut attributes[first_attribute..] {
                    a.values.push(attribute_value(&vals, channels));
                }
            } else if el.name == "face" && iface.is_some() {
                if list.len() < 3 {
                    return Err(format!("face {item} has {} vertices (need at least 3)", list.len()));
                }
                for k in 1..list.len() - 1 {
                    indices.push([list[0], list[k], list[k + 1]]);
                    for (a, channels) in &mut attributes[first_attribute..] {
                        a.values.push(attribute_value(&vals, channels));
                    }
                }
            }
        }
    }
    let mut mesh = TriangleMesh::new(positions, normals, uvs, indices).map_err(|e| e.to_string())?;
    mesh.attributes = attributes.into_iter().map(|(a, _)| a).collect();
    Ok(mesh)
}

/// Loads the first element of a PLY file as a table (see [`parse_ply_table`]).
pub fn load_ply_table(path: &Path) -> Result<PointTable, LoadError> {
    let data = super::limits::read_bounded(path, super::limits::MAX_FILE_BYTES)?;
    parse_ply_table(&data).map_err(|e| LoadError::format(path, e))
}

/// The first element of a PLY file as a table of single-precision values, one row per item and
/// one column per property, whatever the properties' types — as Mitsuba's `ellipsoids` read
/// their file (Mitsuba reads the bytes as floats, so its files hold `float` properties only).
/// List properties are refused; later elements are not read.
pub fn parse_ply_table(data: &[u8]) -> Result<PointTable, String> {
    let (elements, enc, pos) = parse_header(data)?;
    let el = elements.first().ok_or("the header declares no element")?;
    if let Some(p) = el.props.iter().find(|p| p.list_count.is_some()) {
        return Err(format!("element '{}' has a list property '{}' (a table has one number per column)", el.name, p.name));
    }
    let names: Vec<String> = el.props.iter().map(|p| p.name.clone()).collect();
    let mut body = Body { data, pos, enc };
    // Every item takes at least a byte (binary) or a character (ASCII) per property: a count
    // beyond what the body can hold is refused before anything is allocated for it.
    if el.count.saturating_mul(names.len()) > data.len().saturating_sub(pos) {
        return Err(format!("element '{}' declares {} items, more than the file holds", el.name, el.count));
    }
    let mut values = Vec::with_capacity(el.count * names.len());
    for item in 0..el.count {
        for p in &el.props {
            values.push(body.read(p.kind).map_err(|e| format!("{} {item}: {e}", el.name))? as f32);
        }
    }
    Ok(PointTable { names, values })
}

/// A mesh attribute's value from the item's property values: three channels, or one (grey).
fn attribute_value(vals: &[f64], channels: &[usize]) -> Vec3 {
    match channels {
        [r, g, b] => Vec3::new(vals[*r] as f32, vals[*g] as f32, vals[*b] as f32),
        [v] => Vec3::splat(vals[*v] as f32),
        _ => unreachable!("attributes have one or three channels"),
    }
}

/// The mesh attributes among an element's properties, as Mitsuba 3's PLY loader finds them
/// (names without the `vertex_` / `face_` prefix): `color` from `r g b` or `red green blue`;
/// then each run of consecutive properties `NAME_p` (the same NAME) whose one-character
/// suffixes follow one of the sequences `x y z w`, `r g b a`, `0 1 2 3`, `1 2 3 4` from its
/// start, and has one or three members (`NAME`, or `NAME_color` for `r g b`). Positions,
/// normals, the texture coordinates `uv_names` (when the element has them), lists and
/// properties that fit no run are not attributes (Mitsuba warns and skips those).
fn attribute_groups(props: &[Property], uv_names: &[&str]) -> Vec<(String, Vec<usize>)> {
    let index = |n: &str| props.iter().position(|p| p.name == n && p.list_count.is_none());
    let mut groups = Vec::new();
    let mut reserved: Vec<&str> = vec!["x", "y", "z", "nx", "ny", "nz", "r", "g", "b", "a"];
    reserved.extend(uv_names);
    let rgb = match (index("r"), index("g"), index("b")) {
        (Some(r), Some(g), Some(b)) => Some([r, g, b]),
        _ => match (index("red"), index("green"), index("blue")) {
            (Some(r), Some(g), Some(b)) => {
                reserved.extend(["red", "green", "blue", "alpha"]);
                Some([r, g, b])
            }
            _ => None,
        },
    };
    if let Some(c) = rgb {
        groups.push(("color".to_string(), c.to_vec()));
    }
    const SEQUENCES: [&[u8; 4]; 4] = [b"xyzw", b"rgba", b"0123", b"1234"];
    let mut seen: Vec<&str> = Vec::new();
    let mut k = 0;
    while k < props.len() {
        let p = &props[k];
        let split = p.name.rsplit_once('_').filter(|(_, s)| s.len() == 1);
        let Some((prefix, suffix)) = split.filter(|_| p.list_count.is_none() && !reserved.contains(&p.name.as_str()))
        else {
            k += 1;
            continue;
        };
        // The run of consecutive properties with this prefix.
        let mut run = vec![(k, suffix.as_bytes()[0])];
        let mut j = k + 1;
        while let Some((pre, suf)) = props.get(j).filter(|q| q.list_count.is_none()).and_then(|q| q.name.rsplit_once('_')) {
            if pre != prefix || suf.len() != 1 {
                break;
            }
            run.push((j, suf.as_bytes()[0]));
            j += 1;
        }
        k = j;
        if seen.contains(&prefix) {
            continue;
        }
        seen.push(prefix);
        let Some(seq) = SEQUENCES.iter().position(|s| s[0] == run[0].1) else { continue };
        let follows = run.len() <= 4 && run.iter().enumerate().all(|(level, &(_, c))| SEQUENCES[seq][level] == c);
        if follows && (run.len() == 1 || run.len() == 3) {
            let name = if seq == 1 { format!("{prefix}_color") } else { prefix.to_string() };
            groups.push((name, run.iter().map(|&(i, _)| i).collect()));
        }
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0\n2 0 0 1 0\n2 2 0 1 1\n0 2 0 0 1\n4 0 1 2 3\n";

    /// The first element as a table, whatever its types and encoding; lists and counts the
    /// body cannot hold are refused.
    #[test]
    fn point_tables() {
        let ascii = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty uchar k\nproperty double w\n\
                     element face 0\nproperty list uchar int vertex_indices\nend_header\n1.5 7 -2\n0 255 1e-3\n";
        let t = parse_ply_table(ascii.as_bytes()).unwrap();
        assert_eq!(t.names, ["x", "k", "w"]);
        assert_eq!(t.values, [1.5, 7.0, -2.0, 0.0, 255.0, 1e-3]);
        let mut binary = b"ply\nformat binary_big_endian 1.0\nelement point 1\nproperty float a\nproperty short b\nend_header\n".to_vec();
        binary.extend(2.5f32.to_be_bytes());
        binary.extend((-3i16).to_be_bytes());
        let t = parse_ply_table(&binary).unwrap();
        assert_eq!((t.names.as_slice(), t.values.as_slice()), (["a".to_string(), "b".to_string()].as_slice(), [2.5, -3.0].as_slice()));
        let faces = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n3 0 1 2\n";
        let e = parse_ply_table(faces.as_bytes()).unwrap_err();
        assert!(e.contains("element 'face' has a list property 'vertex_indices'"), "{e}");
        let e = parse_ply_table(b"ply\nformat binary_little_endian 1.0\nelement v 1000000000000\nproperty float x\nend_header\n").unwrap_err();
        assert!(e.contains("more than the file holds"), "{e}");
        let e = parse_ply_table(&binary[..binary.len() - 1]).unwrap_err();
        assert!(e.contains("point 0: unexpected end"), "{e}");
    }

    #[test]
    fn ascii_quad() {
        let m = parse_ply(ASCII.as_bytes()).unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(m.uvs.len(), 4);
        assert!((m.area() - 4.0).abs() < 1e-6);
    }

    /// Vertex and face colours become Mitsuba's `vertex_color` and `face_color` attributes (raw
    /// values; a face's colour on every triangle of its fan), which a mesh point interpolates.
    #[test]
    fn colours_become_mesh_attributes() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
            property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n\
            property list uchar int vertex_indices\nproperty float r\nproperty float g\nproperty float b\nend_header\n\
            0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 10 20 30\n4 0 1 2 3 0.25 0.5 0.75\n";
        let m = parse_ply(text.as_bytes()).unwrap();
        let names: Vec<&str> = m.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["vertex_color", "face_color"]);
        assert_eq!(m.attributes[1].values, vec![Vec3::new(0.25, 0.5, 0.75); 2]);
        let point = |tri, b1, b2| crate::geometry::mesh::MeshPoint { mesh: &m, tri, bary: Vec2::new(b1, b2) };
        assert_eq!(point(0, 0.0, 0.0).attribute("vertex_color"), Some(Vec3::new(255.0, 0.0, 0.0)));
        let mid = point(0, 0.5, 0.5).attribute("vertex_color").unwrap();
        assert!((mid - Vec3::new(0.0, 127.5, 127.5)).length() < 1e-4, "{mid}");
        assert_eq!(point(1, 0.3, 0.3).attribute("face_color"), Some(Vec3::new(0.25, 0.5, 0.75)));
        assert_eq!(point(1, 0.3, 0.3).attribute("vertex_weight"), None);
    }

    /// Other properties group into attributes as Mitsuba 3.9.1 groups them (its attribute list
    /// for this very file: face_area 1, vertex_color 3, face_k 3, vertex_tint_color 3,
    /// vertex_weight 1, vertex_dir 3; `lone`, without a suffix, is skipped).
    #[test]
    fn named_properties_become_mesh_attributes() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
            property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float weight_x\n\
            property float dir_x\nproperty float dir_y\nproperty float dir_z\nproperty float tint_r\n\
            property float tint_g\nproperty float tint_b\nproperty float lone\nproperty float bad_x\nproperty float bad_z\n\
            element face 1\nproperty list uchar int vertex_indices\nproperty float area_0\nproperty float k_1\n\
            property float k_2\nproperty float k_3\nend_header\n\
            0 0 0 255 0 128 0.5 1 2 3 0.1 0.2 0.3 7 0 0\n1 0 0 0 255 0 0.25 4 5 6 0.4 0.5 0.6 8 0 0\n\
            0 1 0 0 0 255 0.125 7 8 9 0.7 0.8 0.9 9 0 0\n3 0 1 2 42 1 2 3\n";
        let m = parse_ply(text.as_bytes()).unwrap();
        let mut names: Vec<&str> = m.attributes.iter().map(|a| a.name.as_str()).collect();
        names.sort();
        assert_eq!(names, ["face_area", "face_k", "vertex_color", "vertex_dir", "vertex_tint_color", "vertex_weight"]);
        let get = |n: &str| &m.attributes.iter().find(|a| a.name == n).unwrap().values;
        assert_eq!(get("vertex_color")[0], Vec3::new(255.0, 0.0, 128.0));
        assert_eq!(get("vertex_weight")[1], Vec3::splat(0.25));
        assert_eq!(get("vertex_dir")[2], Vec3::new(7.0, 8.0, 9.0));
        assert_eq!(get("vertex_tint_color")[1], Vec3::new(0.4, 0.5, 0.6));
        assert_eq!(get("face_area")[0], Vec3::splat(42.0));
        assert_eq!(get("face_k")[0], Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn binary_both_endians_match_ascii() {
        for (fmt, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            let mut d = format!(
                "ply\nformat {fmt} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty double nx\nproperty double ny\nproperty double nz\nelement extra 1\nproperty short junk\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
            )
            .into_bytes();
            let f32b = |x: f32| if big { x.to_be_bytes().to_vec() } else { x.to_le_bytes().to_vec() };
            let f64b = |x: f64| if big { x.to_be_bytes().to_vec() } else { x.to_le_bytes().to_vec() };
            for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
                for c in p {
                    d.extend(f32b(c));
                }
                for c in [0.0, 0.0, 1.0] {
                    d.extend(f64b(c));
                }
            }
            d.extend([7u8, 0]); // the skipped 'extra' element
            d.push(3);
            for i in [0u32, 1, 2] {
                d.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
            }
            let m = parse_ply(&d).unwrap();
            assert_eq!(m.len(), 1, "{fmt}");
            assert!((m.area() - 0.5).abs() < 1e-6);
            assert_eq!(m.normals.len(), 3);
        }
    }

    #[test]
    fn clear_errors() {
        assert!(parse_ply(b"plx\nend_header\n").unwrap_err().contains("magic"));
        assert!(parse_ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty floot x\nend_header\n")
            .unwrap_err()
            .contains("header line 4"));
        let truncated = ASCII.replace("4 0 1 2 3\n", "4 0 1\n");
        assert!(parse_ply(truncated.as_bytes()).unwrap_err().contains("end of data"));
        let bad_index = ASCII.replace("4 0 1 2 3", "3 0 1 9");
        assert!(parse_ply(bad_index.as_bytes()).unwrap_err().contains("vertex"));
    }
}
