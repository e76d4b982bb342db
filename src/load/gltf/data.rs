//! glTF's binary data: buffers (the `.glb` file's BIN chunk, `data:` URIs, external `.bin`
//! files) and accessors (typed, strided, possibly normalized or sparse views of them), read
//! with every offset and length checked against the data that exists.

use super::Src;
use crate::load::limits;
use crate::load::FileResolver;
use crate::props::SceneError;
use gltf::accessor::{DataType, Dimensions};
use gltf::Document;

type Result<T> = std::result::Result<T, SceneError>;

/// The JSON chunk and the optional BIN chunk of a binary glTF file (header: `glTF`, version 2,
/// total length; then chunks of length, type and data), every length checked.
pub fn split_glb(bytes: &[u8]) -> std::result::Result<(&[u8], Option<&[u8]>), String> {
    let word = |at: usize| -> Option<u32> { Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?)) };
    let (version, length) = (word(4).ok_or("truncated header")?, word(8).ok_or("truncated header")?);
    if version != 2 {
        return Err(format!("container version {version} (glTF 2.0 files have 2)"));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(format!("the header says {length} bytes but the file has {}", bytes.len()));
    }
    let chunk = |at: usize| -> std::result::Result<(u32, &[u8], usize), String> {
        let len = word(at).ok_or("truncated chunk header")? as usize;
        let kind = word(at + 4).ok_or("truncated chunk header")?;
        let data =
            bytes.get(at + 8..(at + 8).checked_add(len).filter(|&e| e <= length).ok_or("a chunk runs past the end")?);
        Ok((kind, data.ok_or("a chunk runs past the end")?, at + 8 + len))
    };
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    let (kind, json, next) = chunk(12)?;
    if kind != JSON {
        return Err("the first chunk is not JSON".into());
    }
    let bin = if next + 8 <= length {
        let (kind, bin, _) = chunk(next)?;
        (kind == BIN).then_some(bin)
    } else {
        None
    };
    Ok((json, bin))
}

/// The bytes of every buffer, in the document's order.
pub fn load_buffers(src: &Src, doc: &Document, blob: Option<Vec<u8>>, resolver: &FileResolver) -> Result<Vec<Vec<u8>>> {
    let mut blob = blob;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let path = format!("buffers[{}]", b.index());
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                src.err(&path, "the buffer has no 'uri', but the file has no binary chunk (only the first buffer of a .glb may omit it)")
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(src, &format!("{path}.uri"), uri, resolver)?,
        };
        if data.len() < b.length() {
            return Err(src.err(
                &format!("{path}.byteLength"),
                format!("the buffer declares {} bytes but its data holds {}", b.length(), data.len()),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes a URI names: a `data:` URI's base64 payload, or a file relative to the glTF file.
pub fn read_uri(src: &Src, path: &str, uri: &str, resolver: &FileResolver) -> Result<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or_else(|| src.err(path, "a data: URI must be base64-encoded ('data:…;base64,…')"))?;
        return super::json::base64_decode(payload).map_err(|e| src.err(path, format!("bad data: URI: {e}")));
    }
    if uri.contains("://") {
        return Err(
            src.err(path, format!("'{uri}': only relative file names and data: URIs are read (no network access)"))
        );
    }
    let file = resolver.resolve(&super::json::percent_decode(uri));
    limits::read_bounded(&file, limits::MAX_FILE_BYTES).map_err(|e| src.err(path, e.to_string()))
}

/// Size in bytes of one component.
fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// Component `i` of `bytes` (little-endian) as a number: normalized integers mapped to [0, 1]
/// or [-1, 1] as glTF says, others as their value.
fn component(bytes: &[u8], t: DataType, normalized: bool) -> f64 {
    let v = match t {
        DataType::I8 => bytes[0] as i8 as f64,
        DataType::U8 => bytes[0] as f64,
        DataType::I16 => i16::from_le_bytes([bytes[0], bytes[1]]) as f64,
        DataType::U16 => u16::from_le_bytes([bytes[0], bytes[1]]) as f64,
        DataType::U32 => u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as f64,
        DataType::F32 => return f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as f64,
    };
    if !normalized {
        return v;
    }
    match t {
        DataType::I8 => (v / 127.0).max(-1.0),
        DataType::U8 => v / 255.0,
        DataType::I16 => (v / 32767.0).max(-1.0),
        DataType::U16 => v / 65535.0,
        _ => v,
    }
}

/// Columns × rows and the byte size of one element, with the column padding glTF requires for
/// 1- and 2-byte matrices.
fn layout(dims: Dimensions, t: DataType) -> (usize, usize, usize) {
    let c = component_size(t);
    let (cols, rows) = match dims {
        Dimensions::Scalar => (1, 1),
        Dimensions::Vec2 => (1, 2),
        Dimensions::Vec3 => (1, 3),
        Dimensions::Vec4 => (1, 4),
        Dimensions::Mat2 => (2, 2),
        Dimensions::Mat3 => (3, 3),
        Dimensions::Mat4 => (4, 4),
    };
    let column_bytes = if cols > 1 { (rows * c).next_multiple_of(4) } else { rows * c };
    (cols, rows, cols * column_bytes)
}

/// The bytes of a buffer view, checked against its buffer.
pub fn view_bytes<'a>(src: &Src, buffers: &'a [Vec<u8>], view: &gltf::buffer::View) -> Result<&'a [u8]> {
    let buffer = &buffers[view.buffer().index()];
    let (start, len) = (view.offset(), view.length());
    start.checked_add(len).and_then(|end| buffer.get(start..end)).ok_or_else(|| {
        src.err(
            &format!("bufferViews[{}]", view.index()),
            format!(
                "the view's bytes {start}..{} lie outside its buffer ({} bytes)",
                start.saturating_add(len),
                buffer.len()
            ),
        )
    })
}

/// Where elements lie in a buffer view: the first's byte offset, the byte stride (`None`:
/// packed), how many.
struct Span {
    offset: usize,
    stride: Option<usize>,
    count: usize,
}

/// Reads the elements of `span` (of the given layout) from `bytes`, calling `f` with each
/// element's index and its components (column-major).
fn read_elements(
    src: &Src,
    path: &str,
    bytes: &[u8],
    Span { offset, stride, count }: Span,
    (dims, t, normalized): (Dimensions, DataType, bool),
    mut f: impl FnMut(usize, &[f64]),
) -> Result<()> {
    let (cols, rows, elem) = layout(dims, t);
    let stride = stride.unwrap_or(elem);
    if stride < elem && count > 1 {
        return Err(src.err(path, format!("the byte stride {stride} is less than an element's {elem} bytes")));
    }
    let needed =
        if count == 0 { Some(0) } else { (count - 1).checked_mul(stride).and_then(|n| n.checked_add(offset + elem)) };
    let needed = needed.ok_or_else(|| src.err(path, "the accessor's size overflows"))?;
    if offset > bytes.len() || needed > bytes.len() {
        return Err(src.err(
            path,
            format!(
                "the accessor needs bytes {offset}..{needed} of its buffer view, which holds {} (out of range)",
                bytes.len()
            ),
        ));
    }
    let c = component_size(t);
    let column_bytes = if cols > 1 { (rows * c).next_multiple_of(4) } else { rows * c };
    let mut values = vec![0.0; cols * rows];
    for i in 0..count {
        let base = offset + i * stride;
        for col in 0..cols {
            for row in 0..rows {
                let at = base + col * column_bytes + row * c;
                values[col * rows + row] = component(&bytes[at..at + c], t, normalized);
            }
        }
        f(i, &values);
    }
    Ok(())
}

/// An accessor's elements, flattened: `count × components` numbers (matrices column-major),
/// sparse substitutions applied.
pub fn read_accessor(src: &Src, buffers: &[Vec<u8>], a: &gltf::Accessor) -> Result<Vec<f64>> {
    let path = format!("accessors[{}]", a.index());
    let (dims, t) = (a.dimensions(), a.data_type());
    let n = dims.multiplicity();
    let total = a.count().checked_mul(n).filter(|&t| t <= limits::MAX_ACCESSOR_VALUES).ok_or_else(|| {
        src.err(&format!("{path}.count"), format!("{} elements is more than neumann reads", a.count()))
    })?;
    let mut out = vec![0.0; total];
    if let Some(view) = a.view() {
        let bytes = view_bytes(src, buffers, &view)?;
        let span = Span { offset: a.offset(), stride: view.stride(), count: a.count() };
        read_elements(src, &path, bytes, span, (dims, t, a.normalized()), |i, v| {
            out[i * n..(i + 1) * n].copy_from_slice(v)
        })?;
    }
    if let Some(sparse) = a.sparse() {
        let sp = format!("{path}.sparse");
        let count = sparse.count();
        let indices = sparse.indices();
        let index_type = match indices.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let mut targets = Vec::with_capacity(count.min(a.count()));
        let ibytes = view_bytes(src, buffers, &indices.view())?;
        read_elements(
            src,
            &format!("{sp}.indices"),
            ibytes,
            Span { offset: indices.offset(), stride: None, count },
            (Dimensions::Scalar, index_type, false),
            |_, v| targets.push(v[0] as usize),
        )?;
        if let Some(&bad) = targets.iter().find(|&&i| i >= a.count()) {
            return Err(src.err(
                &format!("{sp}.indices"),
                format!("sparse index {bad} is out of range (the accessor has {} elements)", a.count()),
            ));
        }
        let values = sparse.values();
        let vbytes = view_bytes(src, buffers, &values.view())?;
        read_elements(
            src,
            &format!("{sp}.values"),
            vbytes,
            Span { offset: values.offset(), stride: None, count },
            (dims, t, a.normalized()),
            |i, v| {
                let at = targets[i] * n;
                out[at..at + n].copy_from_slice(v)
            },
        )?;
    }
    if let Some(bad) = out.iter().position(|v| !v.is_finite()) {
        return Err(src.err(&path, format!("element {} holds a value that is not finite", bad / n)));
    }
    Ok(out)
}

/// An accessor of integers (indices, joints) as `u32`, checked to be one of `types`.
pub fn read_integers(src: &Src, buffers: &[Vec<u8>], a: &gltf::Accessor, what: &str) -> Result<Vec<u32>> {
    if a.data_type() == DataType::F32 || a.normalized() {
        return Err(src.err(
            &format!("accessors[{}].componentType", a.index()),
            format!(
                "{what} must be unsigned integers (not {:?}{})",
                a.data_type(),
                if a.normalized() { ", normalized" } else { "" }
            ),
        ));
    }
    Ok(read_accessor(src, buffers, a)?.into_iter().map(|v| v as u32).collect())
}

/// An accessor's elements as `N`-vectors (checked to have `N` components).
pub fn read_vectors<const N: usize>(
    src: &Src,
    buffers: &[Vec<u8>],
    a: &gltf::Accessor,
    what: &str,
) -> Result<Vec<[f32; N]>> {
    if a.dimensions().multiplicity() != N {
        return Err(src.err(
            &format!("accessors[{}].type", a.index()),
            format!("{what} must have {N} components, the accessor has {:?}", a.dimensions()),
        ));
    }
    let flat = read_accessor(src, buffers, a)?;
    Ok(flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i] as f32)).collect())
}
