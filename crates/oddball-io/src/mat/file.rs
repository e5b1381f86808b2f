//! The contents of a MAT file: header, variables and their arrays, values kept in the type they
//! are stored in.

use serde::{Deserialize, Serialize};

/// The 128-byte header of a MAT file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MatHeader {
    /// The descriptive text, e.g. `MATLAB 5.0 MAT-file, Platform: PCWIN, Created on: …`.
    pub text: String,
    /// 0x0100 for v5/v7.
    pub version: u16,
    /// `MI` instead of `IM`: the file was written big-endian.
    pub big_endian: bool,
    /// Byte offset of the subsystem data (MATLAB objects), 0 when there is none.
    pub subsys_offset: u64,
}

/// A whole MAT file: header and variables in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct MatFile {
    pub header: MatHeader,
    pub variables: Vec<MatVariable>,
}

impl MatFile {
    /// The variable called `name`, if any (the first, should a file repeat a name).
    pub fn get(&self, name: &str) -> Option<&MatVariable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// The names of the variables in file order.
    pub fn names(&self) -> Vec<String> {
        self.variables.iter().map(|v| v.name.clone()).collect()
    }
}

/// One top-level variable.
#[derive(Debug, Clone, PartialEq)]
pub struct MatVariable {
    pub name: String,
    pub array: MatArray,
    /// Byte offset of the variable's element tag in the file.
    pub offset: u64,
    /// Stored in a `miCOMPRESSED` (zlib) element.
    pub compressed: bool,
    /// MATLAB's global flag.
    pub global: bool,
}

/// An array: its dimensions (at least two) and its values, column-major.
#[derive(Debug, Clone, PartialEq)]
pub struct MatArray {
    pub dims: Vec<usize>,
    pub value: MatValue,
}

impl MatArray {
    /// The number of elements, the product of the dimensions.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The real part of a numeric or logical array.
    pub fn numbers(&self) -> Option<&MatNumbers> {
        match &self.value {
            MatValue::Numeric { real, .. } => Some(real),
            _ => None,
        }
    }

    /// The rows of a char array as strings (a `1 × n` array is one string).
    pub fn char_rows(&self) -> Option<Vec<String>> {
        match &self.value {
            MatValue::Char(chars) => {
                let m = self.dims.first().copied().unwrap_or(0);
                if m == 0 {
                    return Some(Vec::new());
                }
                let n = chars.len() / m;
                Some(
                    (0..m)
                        .map(|i| (0..n).map(|j| chars[i + j * m]).collect())
                        .collect(),
                )
            }
            _ => None,
        }
    }
}

/// The values of an array.
#[derive(Debug, Clone, PartialEq)]
pub enum MatValue {
    /// A numeric or logical array; `class` is MATLAB's class, `real` (and `imag` for complex
    /// arrays) the numbers in the type they were stored in.
    Numeric {
        class: MatClass,
        real: MatNumbers,
        imag: Option<MatNumbers>,
    },
    /// A char array's characters, column-major.
    Char(Vec<char>),
    /// A cell array's cells, column-major.
    Cell(Vec<MatArray>),
    /// A struct array: its field names and, for each element (column-major) in turn, one value
    /// per field (`values[element * fields.len() + field]`).
    Struct {
        fields: Vec<String>,
        values: Vec<MatArray>,
    },
    /// A class this reader does not decode (sparse, object, function handle, opaque): the
    /// class number of the array flags.
    Unsupported { class: u8 },
}

/// MATLAB's array class (`mxCLASS`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MatClass {
    Cell,
    Struct,
    Object,
    Char,
    Sparse,
    Double,
    Single,
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    /// uint8 storage with MATLAB's logical flag.
    Logical,
}

impl MatClass {
    pub(super) fn from_byte(b: u8) -> Option<Self> {
        Some(match b {
            1 => Self::Cell,
            2 => Self::Struct,
            3 => Self::Object,
            4 => Self::Char,
            5 => Self::Sparse,
            6 => Self::Double,
            7 => Self::Single,
            8 => Self::Int8,
            9 => Self::UInt8,
            10 => Self::Int16,
            11 => Self::UInt16,
            12 => Self::Int32,
            13 => Self::UInt32,
            14 => Self::Int64,
            15 => Self::UInt64,
            _ => return None,
        })
    }

    pub(super) fn is_numeric(self) -> bool {
        matches!(
            self,
            Self::Double
                | Self::Single
                | Self::Int8
                | Self::UInt8
                | Self::Int16
                | Self::UInt16
                | Self::Int32
                | Self::UInt32
                | Self::Int64
                | Self::UInt64
        )
    }
}

/// A numeric data type of the file (`miINT8` … `miDOUBLE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MatType {
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Single,
    Double,
    Int64,
    UInt64,
}

impl MatType {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Self::Int8 | Self::UInt8 => 1,
            Self::Int16 | Self::UInt16 => 2,
            Self::Int32 | Self::UInt32 | Self::Single => 4,
            Self::Double | Self::Int64 | Self::UInt64 => 8,
        }
    }
}

/// Numbers in the type the file stores them in.
#[derive(Debug, Clone, PartialEq)]
pub enum MatNumbers {
    I8(Vec<i8>),
    U8(Vec<u8>),
    I16(Vec<i16>),
    U16(Vec<u16>),
    I32(Vec<i32>),
    U32(Vec<u32>),
    F32(Vec<f32>),
    F64(Vec<f64>),
    I64(Vec<i64>),
    U64(Vec<u64>),
}

/// Applies `$body` to the vector inside any [`MatNumbers`].
macro_rules! each {
    ($n:expr, $v:ident => $body:expr) => {
        match $n {
            MatNumbers::I8($v) => $body,
            MatNumbers::U8($v) => $body,
            MatNumbers::I16($v) => $body,
            MatNumbers::U16($v) => $body,
            MatNumbers::I32($v) => $body,
            MatNumbers::U32($v) => $body,
            MatNumbers::F32($v) => $body,
            MatNumbers::F64($v) => $body,
            MatNumbers::I64($v) => $body,
            MatNumbers::U64($v) => $body,
        }
    };
}

impl MatNumbers {
    /// Decodes `d` (a whole number of values) as `t` in the given byte order.
    pub(super) fn decode(t: MatType, d: &[u8], big_endian: bool) -> Self {
        macro_rules! dec {
            ($ty:ty, $var:ident) => {{
                const N: usize = std::mem::size_of::<$ty>();
                MatNumbers::$var(
                    d.chunks_exact(N)
                        .map(|c| {
                            let a: [u8; N] = c.try_into().unwrap_or([0; N]);
                            if big_endian {
                                <$ty>::from_be_bytes(a)
                            } else {
                                <$ty>::from_le_bytes(a)
                            }
                        })
                        .collect(),
                )
            }};
        }
        match t {
            MatType::Int8 => dec!(i8, I8),
            MatType::UInt8 => dec!(u8, U8),
            MatType::Int16 => dec!(i16, I16),
            MatType::UInt16 => dec!(u16, U16),
            MatType::Int32 => dec!(i32, I32),
            MatType::UInt32 => dec!(u32, U32),
            MatType::Single => dec!(f32, F32),
            MatType::Double => dec!(f64, F64),
            MatType::Int64 => dec!(i64, I64),
            MatType::UInt64 => dec!(u64, U64),
        }
    }

    /// The type the numbers are stored in.
    pub fn stored_type(&self) -> MatType {
        match self {
            Self::I8(_) => MatType::Int8,
            Self::U8(_) => MatType::UInt8,
            Self::I16(_) => MatType::Int16,
            Self::U16(_) => MatType::UInt16,
            Self::I32(_) => MatType::Int32,
            Self::U32(_) => MatType::UInt32,
            Self::F32(_) => MatType::Single,
            Self::F64(_) => MatType::Double,
            Self::I64(_) => MatType::Int64,
            Self::U64(_) => MatType::UInt64,
        }
    }

    pub fn len(&self) -> usize {
        each!(self, v => v.len())
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` as `f64` (exact except for 64-bit integers beyond 2⁵³).
    #[allow(clippy::unnecessary_cast)] // `as f64` is a no-op for the F64 arm only
    pub fn get_f64(&self, i: usize) -> Option<f64> {
        each!(self, v => v.get(i).map(|&x| x as f64))
    }

    /// All values as `f64` (exact except for 64-bit integers beyond 2⁵³).
    #[allow(clippy::unnecessary_cast)] // `as f64` is a no-op for the F64 arm only
    pub fn to_f64(&self) -> Vec<f64> {
        each!(self, v => v.iter().map(|&x| x as f64).collect())
    }

    /// All values as `i64`: floats truncated toward zero (saturating), `u64` above `i64::MAX`
    /// saturated.
    pub fn to_i64(&self) -> Vec<i64> {
        match self {
            Self::F32(v) => v.iter().map(|&x| x as i64).collect(),
            Self::F64(v) => v.iter().map(|&x| x as i64).collect(),
            Self::U64(v) => v
                .iter()
                .map(|&x| i64::try_from(x).unwrap_or(i64::MAX))
                .collect(),
            Self::I8(v) => v.iter().map(|&x| i64::from(x)).collect(),
            Self::U8(v) => v.iter().map(|&x| i64::from(x)).collect(),
            Self::I16(v) => v.iter().map(|&x| i64::from(x)).collect(),
            Self::U16(v) => v.iter().map(|&x| i64::from(x)).collect(),
            Self::I32(v) => v.iter().map(|&x| i64::from(x)).collect(),
            Self::U32(v) => v.iter().map(|&x| i64::from(x)).collect(),
            Self::I64(v) => v.clone(),
        }
    }
}
