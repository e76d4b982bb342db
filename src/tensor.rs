//! Tensor files in memory: named n-dimensional arrays, as Mitsuba's `TensorFile` holds them
//! (the data of measured BSDFs). Decoding the file format is the job of `load::tensor_file`.

use std::collections::BTreeMap;

/// The element type of a tensor field (Mitsuba's `Struct::Type` codes 1–11 in the file).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TensorType {
    /// 8-bit unsigned integers.
    U8,
    /// 8-bit signed integers.
    I8,
    /// 16-bit unsigned integers.
    U16,
    /// 16-bit signed integers.
    I16,
    /// 32-bit unsigned integers.
    U32,
    /// 32-bit signed integers.
    I32,
    /// 64-bit unsigned integers.
    U64,
    /// 64-bit signed integers.
    I64,
    /// IEEE half-precision floats.
    F16,
    /// IEEE single-precision floats.
    F32,
    /// IEEE double-precision floats.
    F64,
}

impl TensorType {
    /// Every type, in the order of the file format's codes (1 = `U8` … 11 = `F64`).
    pub const ALL: [TensorType; 11] = [
        TensorType::U8,
        TensorType::I8,
        TensorType::U16,
        TensorType::I16,
        TensorType::U32,
        TensorType::I32,
        TensorType::U64,
        TensorType::I64,
        TensorType::F16,
        TensorType::F32,
        TensorType::F64,
    ];

    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            TensorType::U8 | TensorType::I8 => 1,
            TensorType::U16 | TensorType::I16 | TensorType::F16 => 2,
            TensorType::U32 | TensorType::I32 | TensorType::F32 => 4,
            TensorType::U64 | TensorType::I64 | TensorType::F64 => 8,
        }
    }

    /// The type's name in messages (NumPy's).
    pub fn name(self) -> &'static str {
        match self {
            TensorType::U8 => "uint8",
            TensorType::I8 => "int8",
            TensorType::U16 => "uint16",
            TensorType::I16 => "int16",
            TensorType::U32 => "uint32",
            TensorType::I32 => "int32",
            TensorType::U64 => "uint64",
            TensorType::I64 => "int64",
            TensorType::F16 => "float16",
            TensorType::F32 => "float32",
            TensorType::F64 => "float64",
        }
    }
}

/// One field of a tensor file: an array of `shape.iter().product()` elements, the last index
/// varying fastest (C order, as NumPy writes them), little-endian bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct TensorField {
    /// Element type.
    pub dtype: TensorType,
    /// Extent of each dimension, outermost first.
    pub shape: Vec<usize>,
    /// The elements' bytes (`size() · dtype.size()` of them).
    pub bytes: Vec<u8>,
}

impl TensorField {
    /// A `float32` field of `shape` holding `values` (for tests and tools).
    pub fn from_f32(shape: &[usize], values: &[f32]) -> TensorField {
        assert_eq!(shape.iter().product::<usize>(), values.len(), "shape and values disagree");
        TensorField {
            dtype: TensorType::F32,
            shape: shape.to_vec(),
            bytes: values.iter().flat_map(|v| v.to_le_bytes()).collect(),
        }
    }

    /// A `uint8` field of `shape` holding `values` (text, flags).
    pub fn from_u8(shape: &[usize], values: &[u8]) -> TensorField {
        assert_eq!(shape.iter().product::<usize>(), values.len(), "shape and values disagree");
        TensorField { dtype: TensorType::U8, shape: shape.to_vec(), bytes: values.to_vec() }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether the field has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The elements of a `float32` field; `None` for any other type.
    pub fn f32s(&self) -> Option<Vec<f32>> {
        (self.dtype == TensorType::F32)
            .then(|| self.bytes.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect())
    }

    /// The elements of a `uint8` field; `None` for any other type.
    pub fn u8s(&self) -> Option<&[u8]> {
        (self.dtype == TensorType::U8).then_some(&self.bytes[..])
    }

    /// `float32[3, 4]`-style description for messages.
    pub fn describe(&self) -> String {
        let dims: Vec<String> = self.shape.iter().map(|d| d.to_string()).collect();
        format!("{}[{}]", self.dtype.name(), dims.join(", "))
    }
}

/// A tensor file: its fields by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TensorFile {
    /// The fields, by name.
    pub fields: BTreeMap<String, TensorField>,
}

impl TensorFile {
    /// The field `name`, if the file has it.
    pub fn field(&self, name: &str) -> Option<&TensorField> {
        self.fields.get(name)
    }
}
