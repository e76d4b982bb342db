//! Mitsuba's tensor files (`mi.tensor_io`; the `.bsdf` files of the RGL material database).
//! Layout (little-endian): the 12 bytes `tensor_file\0`; the version 1, 0 (two bytes); the
//! field count (u32); per field its name (u16 length, then UTF-8), its dimension count (u16),
//! its type (u8: 1 = uint8, 2 = int8, 3 = uint16, 4 = int16, 5 = uint32, 6 = int32, 7 = uint64,
//! 8 = int64, 9 = float16, 10 = float32, 11 = float64), the byte offset of its data (u64) and
//! its extents (u64 each, outermost first); then the data, each field's elements contiguous in
//! C order at its offset.

use super::LoadError;
pub use crate::tensor::{TensorField, TensorFile, TensorType};
use std::path::Path;

const MAGIC: &[u8; 12] = b"tensor_file\0";

/// Reads the tensor file at `path`.
pub fn load_tensor_file(path: &Path) -> Result<TensorFile, LoadError> {
    let bytes = super::limits::read_bounded(path, super::limits::MAX_FILE_BYTES)?;
    parse_tensor_file(&bytes).map_err(|m| LoadError::format(path, m))
}

/// A cursor over the header that turns running off the end into an error naming what was read.
struct Header<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Header<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], String> {
        let end =
            self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or_else(|| {
                format!("the file ends at byte {} inside the header, reading {what}", self.bytes.len())
            })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u16(&mut self, what: &str) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.take(2, what)?.try_into().expect("2 bytes")))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8, what)?.try_into().expect("8 bytes")))
    }
}

/// Parses the bytes of a tensor file.
pub fn parse_tensor_file(bytes: &[u8]) -> Result<TensorFile, String> {
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err("not a tensor file (it does not start with \"tensor_file\\0\")".into());
    }
    let mut h = Header { bytes, at: MAGIC.len() };
    let version = h.take(2, "the version")?;
    if version != [1, 0] {
        return Err(format!("tensor file version {}.{} (only 1.0 exists)", version[0], version[1]));
    }
    let count = u32::from_le_bytes(h.take(4, "the field count")?.try_into().expect("4 bytes"));
    let mut file = TensorFile::default();
    for k in 0..count {
        let len = h.u16("a field name's length")? as usize;
        let name = String::from_utf8(h.take(len, "a field name")?.to_vec())
            .map_err(|_| format!("the name of field {k} is not UTF-8"))?;
        let ndim = h.u16("a field's dimension count")? as usize;
        let code = h.take(1, "a field's type")?[0];
        let dtype = code
            .checked_sub(1)
            .and_then(|i| TensorType::ALL.get(i as usize))
            .copied()
            .ok_or_else(|| format!("field '{name}' has type code {code} (1–11 exist)"))?;
        let offset = h.u64("a field's offset")?;
        let mut shape = Vec::with_capacity(ndim.min(64));
        for _ in 0..ndim {
            shape
                .push(usize::try_from(h.u64("a field's extent")?).map_err(|_| format!("field '{name}' is too large"))?);
        }
        let size = shape
            .iter()
            .try_fold(dtype.size(), |a, &d| a.checked_mul(d))
            .ok_or_else(|| format!("field '{name}' is too large"))?;
        let start = usize::try_from(offset).ok().filter(|&s| s <= bytes.len());
        let data = start.and_then(|s| bytes.get(s..s.checked_add(size)?)).ok_or_else(|| {
            format!(
                "field '{name}' ({} elements of {}) at byte {offset} runs past the end of the file ({} bytes)",
                size / dtype.size(),
                dtype.name(),
                bytes.len()
            )
        })?;
        if file.fields.insert(name.clone(), TensorField { dtype, shape, bytes: data.to_vec() }).is_some() {
            return Err(format!("field '{name}' appears twice"));
        }
    }
    Ok(file)
}

/// The bytes of a tensor file holding `file`'s fields (in name order, data aligned to 8 bytes,
/// as `mi.tensor_io.write` aligns it), for tests and tools.
pub fn tensor_file_bytes(file: &TensorFile) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    out.extend([1, 0]);
    out.extend((file.fields.len() as u32).to_le_bytes());
    let mut offset_at = Vec::new();
    for (name, f) in &file.fields {
        out.extend((name.len() as u16).to_le_bytes());
        out.extend(name.as_bytes());
        out.extend((f.shape.len() as u16).to_le_bytes());
        let code = TensorType::ALL.iter().position(|&t| t == f.dtype).expect("listed") as u8 + 1;
        out.push(code);
        offset_at.push(out.len());
        out.extend(0u64.to_le_bytes());
        for &d in &f.shape {
            out.extend((d as u64).to_le_bytes());
        }
    }
    for (f, at) in file.fields.values().zip(offset_at) {
        out.resize(out.len().div_ceil(8) * 8, 0);
        let offset = out.len() as u64;
        out[at..at + 8].copy_from_slice(&offset.to_le_bytes());
        out.extend(&f.bytes);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> TensorFile {
        let mut t = TensorFile::default();
        t.fields.insert("data".into(), TensorField::from_f32(&[2, 3], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.5]));
        t.fields.insert("description".into(), TensorField::from_u8(&[5], b"hello"));
        t.fields.insert("flag".into(), TensorField::from_u8(&[1], &[1]));
        t
    }

    #[test]
    fn round_trip() {
        let t = sample();
        let parsed = parse_tensor_file(&tensor_file_bytes(&t)).unwrap();
        assert_eq!(parsed, t);
        assert_eq!(parsed.field("data").unwrap().f32s().unwrap()[5], 6.5);
        assert_eq!(parsed.field("data").unwrap().describe(), "float32[2, 3]");
        assert!(parsed.field("description").unwrap().f32s().is_none());
    }

    /// Bytes written by Mitsuba 3.9.1's `mi.tensor_io.write(f, a=np.arange(6, dtype=np.float32)
    /// .reshape(2, 3), b=np.array([7], dtype=np.uint8))`.
    #[test]
    fn reads_what_mitsuba_writes() {
        let bytes: [u8; 97] = [
            0x74, 0x65, 0x6e, 0x73, 0x6f, 0x72, 0x5f, 0x66, 0x69, 0x6c, 0x65, 0x00, 0x01, 0x00, 0x02, 0x00, 0x00, 0x00,
            0x01, 0x00, 0x61, 0x02, 0x00, 0x0a, 0x48, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x62, 0x01, 0x00, 0x01,
            0x60, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0x40, 0x00, 0x00, 0x40, 0x40, 0x00, 0x00,
            0x80, 0x40, 0x00, 0x00, 0xa0, 0x40, 0x07,
        ];
        let t = parse_tensor_file(&bytes).unwrap();
        assert_eq!(t.field("a").unwrap().shape, [2, 3]);
        assert_eq!(t.field("a").unwrap().f32s().unwrap(), [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(t.field("b").unwrap().u8s().unwrap(), [7]);
        assert_eq!(tensor_file_bytes(&t), bytes, "written as Mitsuba writes it");
    }

    #[test]
    fn hostile_input_is_an_error() {
        let good = tensor_file_bytes(&sample());
        for n in 0..good.len() {
            assert!(parse_tensor_file(&good[..n]).is_err(), "truncated to {n} bytes");
        }
        let mut bad = good.clone();
        bad[12] = 2;
        assert!(parse_tensor_file(&bad).unwrap_err().contains("version 2.0"));
        // An extent of 2⁶³ elements must not overflow or allocate.
        let mut huge = good.clone();
        let at = 12 + 2 + 4 + 2 + 4 + 2 + 1 + 8;
        huge[at..at + 8].copy_from_slice(&(1u64 << 63).to_le_bytes());
        assert!(parse_tensor_file(&huge).unwrap_err().contains("too large"));
        let mut code = good;
        code[12 + 2 + 4 + 2 + 4 + 2] = 12;
        assert!(parse_tensor_file(&code).unwrap_err().contains("type code 12"));
    }
}
