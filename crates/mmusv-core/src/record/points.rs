//! Packed point layouts for `foxglove.PointCloud`: field types, and row-interleaving of per-field columns
//! into the little-endian byte buffer the message carries.

use crate::error::{MmusvError, Result};
use foxglove::messages::packed_element_field::NumericType;

/// Numeric type of one packed point field (little-endian in the buffer).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PackedType {
    /// `uint8`.
    U8,
    /// `int8`.
    I8,
    /// `uint16`.
    U16,
    /// `int16`.
    I16,
    /// `uint32`.
    U32,
    /// `int32`.
    I32,
    /// `float32`.
    F32,
    /// `float64`.
    F64,
}

impl PackedType {
    /// Every type with its numpy dtype name.
    pub const ALL: [(PackedType, &'static str); 8] = [
        (Self::U8, "uint8"),
        (Self::I8, "int8"),
        (Self::U16, "uint16"),
        (Self::I16, "int16"),
        (Self::U32, "uint32"),
        (Self::I32, "int32"),
        (Self::F32, "float32"),
        (Self::F64, "float64"),
    ];

    /// Bytes one value takes.
    pub fn size(self) -> u32 {
        match self {
            Self::U8 | Self::I8 => 1,
            Self::U16 | Self::I16 => 2,
            Self::U32 | Self::I32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    /// The numpy dtype name, e.g. `float32`.
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|(t, _)| *t == self).map_or("?", |(_, n)| n)
    }

    /// Parses a numpy dtype name (`uint8` … `float64`); `field` names the argument in the error.
    pub fn parse(name: &str, field: &str) -> Result<Self> {
        Self::ALL.iter().find(|(_, n)| *n == name).map(|(t, _)| *t).ok_or_else(|| {
            let allowed: Vec<&str> = Self::ALL.iter().map(|(_, n)| *n).collect();
            MmusvError::input(field, format!("type {name:?} is not supported; use one of {allowed:?}"))
        })
    }

    /// The Foxglove enum value.
    pub(crate) fn numeric_type(self) -> NumericType {
        match self {
            Self::U8 => NumericType::Uint8,
            Self::I8 => NumericType::Int8,
            Self::U16 => NumericType::Uint16,
            Self::I16 => NumericType::Int16,
            Self::U32 => NumericType::Uint32,
            Self::I32 => NumericType::Int32,
            Self::F32 => NumericType::Float32,
            Self::F64 => NumericType::Float64,
        }
    }
}

/// One per-point column of values, borrowed.
#[derive(Debug, Clone, Copy)]
pub enum Column<'a> {
    /// `uint8` values.
    U8(&'a [u8]),
    /// `int8` values.
    I8(&'a [i8]),
    /// `uint16` values.
    U16(&'a [u16]),
    /// `int16` values.
    I16(&'a [i16]),
    /// `uint32` values.
    U32(&'a [u32]),
    /// `int32` values.
    I32(&'a [i32]),
    /// `float32` values.
    F32(&'a [f32]),
    /// `float64` values.
    F64(&'a [f64]),
}

impl Column<'_> {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Self::U8(v) => v.len(),
            Self::I8(v) => v.len(),
            Self::U16(v) => v.len(),
            Self::I16(v) => v.len(),
            Self::U32(v) => v.len(),
            Self::I32(v) => v.len(),
            Self::F32(v) => v.len(),
            Self::F64(v) => v.len(),
        }
    }

    /// True when the column holds no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The packed type of the values.
    pub fn packed_type(&self) -> PackedType {
        match self {
            Self::U8(_) => PackedType::U8,
            Self::I8(_) => PackedType::I8,
            Self::U16(_) => PackedType::U16,
            Self::I16(_) => PackedType::I16,
            Self::U32(_) => PackedType::U32,
            Self::I32(_) => PackedType::I32,
            Self::F32(_) => PackedType::F32,
            Self::F64(_) => PackedType::F64,
        }
    }

    /// Writes value `i` of this column at `offset` of every `stride`-byte row of `out`.
    fn scatter(&self, out: &mut [u8], stride: usize, offset: usize) {
        fn put<T: Copy, const S: usize>(vals: &[T], le: fn(T) -> [u8; S], out: &mut [u8], stride: usize, at: usize) {
            for (row, v) in out.chunks_exact_mut(stride).zip(vals) {
                row[at..at + S].copy_from_slice(&le(*v));
            }
        }
        match *self {
            Self::U8(v) => put(v, u8::to_le_bytes, out, stride, offset),
            Self::I8(v) => put(v, i8::to_le_bytes, out, stride, offset),
            Self::U16(v) => put(v, u16::to_le_bytes, out, stride, offset),
            Self::I16(v) => put(v, i16::to_le_bytes, out, stride, offset),
            Self::U32(v) => put(v, u32::to_le_bytes, out, stride, offset),
            Self::I32(v) => put(v, i32::to_le_bytes, out, stride, offset),
            Self::F32(v) => put(v, f32::to_le_bytes, out, stride, offset),
            Self::F64(v) => put(v, f64::to_le_bytes, out, stride, offset),
        }
    }
}

/// Points packed row by row: field `i` sits at `offsets[i]` bytes into every `stride`-byte point.
#[derive(Debug, Clone, PartialEq)]
pub struct PackedPoints {
    /// `(name, type)` of every field, in buffer order.
    pub fields: Vec<(String, PackedType)>,
    /// Byte offset of every field inside a point.
    pub offsets: Vec<u32>,
    /// Bytes per point (the fields back to back, no padding).
    pub stride: u32,
    /// `points × stride` bytes, little-endian.
    pub data: Vec<u8>,
}

/// Byte offsets of `fields` packed back to back, and the resulting point size.
pub fn packed_offsets(fields: &[(&str, PackedType)]) -> (Vec<u32>, u32) {
    let mut offsets = Vec::with_capacity(fields.len());
    let mut at = 0u32;
    for (_, t) in fields {
        offsets.push(at);
        at += t.size();
    }
    (offsets, at)
}

/// Interleaves equal-length named columns into one packed buffer (fields in the order given, no padding).
pub fn pack_columns(columns: &[(&str, Column<'_>)]) -> Result<PackedPoints> {
    let Some((_, first)) = columns.first() else {
        return Err(MmusvError::input("columns", "give at least one column (e.g. x, y, z)"));
    };
    let n = first.len();
    for (i, (name, c)) in columns.iter().enumerate() {
        if c.len() != n {
            return Err(MmusvError::input(
                format!("columns[{i}] ({name})"),
                format!("has {} values but the first column has {n}; every column needs one value per point", c.len()),
            ));
        }
    }
    let fields: Vec<(&str, PackedType)> = columns.iter().map(|(n, c)| (*n, c.packed_type())).collect();
    let (offsets, stride) = packed_offsets(&fields);
    let mut data = vec![0u8; n * stride as usize];
    for ((_, c), off) in columns.iter().zip(&offsets) {
        c.scatter(&mut data, stride as usize, *off as usize);
    }
    Ok(PackedPoints { fields: fields.into_iter().map(|(n, t)| (n.to_string(), t)).collect(), offsets, stride, data })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packs_row_interleaved_little_endian() -> Result<()> {
        let x = [1.0f32, 2.0];
        let ring = [7u16, 9];
        let p = pack_columns(&[("x", Column::F32(&x)), ("ring", Column::U16(&ring))])?;
        assert_eq!(p.stride, 6);
        assert_eq!(p.offsets, [0, 4]);
        assert_eq!(&p.data[0..4], &1.0f32.to_le_bytes());
        assert_eq!(&p.data[4..6], &7u16.to_le_bytes());
        assert_eq!(&p.data[6..10], &2.0f32.to_le_bytes());
        assert_eq!(&p.data[10..12], &9u16.to_le_bytes());
        Ok(())
    }

    #[test]
    fn rejects_ragged_columns_and_unknown_types() {
        let err = pack_columns(&[("x", Column::F32(&[1.0])), ("y", Column::F32(&[]))]);
        assert!(matches!(err, Err(MmusvError::InvalidInput { .. })));
        assert!(PackedType::parse("complex64", "fields[0]").is_err());
        assert_eq!(PackedType::parse("uint16", "f").ok(), Some(PackedType::U16));
        assert_eq!(PackedType::F64.name(), "float64");
    }
}
