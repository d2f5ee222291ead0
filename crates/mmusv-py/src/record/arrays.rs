//! The record binding's numpy inputs: a point-cloud column of any supported dtype, an image array, and the check
//! that parallel lists have one entry each.

use crate::errors::InputError;
use crate::native::{c_order, flat};
use mmusv_core::record::{Column, Pixels};
use numpy::PyUntypedArrayMethods;
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

/// One point-cloud column of any supported dtype, borrowed read-only.
pub(super) enum ColumnArray<'py> {
    U8(PyReadonlyArray1<'py, u8>),
    I8(PyReadonlyArray1<'py, i8>),
    U16(PyReadonlyArray1<'py, u16>),
    I16(PyReadonlyArray1<'py, i16>),
    U32(PyReadonlyArray1<'py, u32>),
    I32(PyReadonlyArray1<'py, i32>),
    F32(PyReadonlyArray1<'py, f32>),
    F64(PyReadonlyArray1<'py, f64>),
}

impl<'py> ColumnArray<'py> {
    pub(super) fn from_any(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Self> {
        macro_rules! try_dtype {
            ($t:ty, $v:ident) => {
                if let Ok(a) = obj.cast::<PyArray1<$t>>() {
                    return Ok(Self::$v(a.readonly()));
                }
            };
        }
        try_dtype!(f32, F32);
        try_dtype!(f64, F64);
        try_dtype!(u8, U8);
        try_dtype!(i8, I8);
        try_dtype!(u16, U16);
        try_dtype!(i16, I16);
        try_dtype!(u32, U32);
        try_dtype!(i32, I32);
        Err(PyTypeError::new_err(format!(
            "column {name} must be a 1-D numpy array of uint8, int8, uint16, int16, uint32, int32, float32 or float64"
        )))
    }

    pub(super) fn column(&self, name: &str) -> PyResult<Column<'_>> {
        Ok(match self {
            Self::U8(a) => Column::U8(flat(a, name)?),
            Self::I8(a) => Column::I8(flat(a, name)?),
            Self::U16(a) => Column::U16(flat(a, name)?),
            Self::I16(a) => Column::I16(flat(a, name)?),
            Self::U32(a) => Column::U32(flat(a, name)?),
            Self::I32(a) => Column::I32(flat(a, name)?),
            Self::F32(a) => Column::F32(flat(a, name)?),
            Self::F64(a) => Column::F64(flat(a, name)?),
        })
    }
}

/// An image array: (H, W) or (H, W, 3) uint8, (H, W) uint16, (H, W) float32.
pub(super) enum ImageArray<'py> {
    Mono8(PyReadonlyArray2<'py, u8>),
    Rgb8(PyReadonlyArray3<'py, u8>),
    Mono16(PyReadonlyArray2<'py, u16>),
    Float32(PyReadonlyArray2<'py, f32>),
}

const IMAGE_KINDS: &str = "(H, W) uint8, (H, W, 3) uint8, (H, W) uint16 or (H, W) float32";

impl<'py> ImageArray<'py> {
    pub(super) fn from_any(obj: &Bound<'py, PyAny>) -> PyResult<Self> {
        if let Ok(a) = obj.cast::<PyArray2<u8>>() {
            return Ok(Self::Mono8(a.readonly()));
        }
        if let Ok(a) = obj.cast::<PyArray3<u8>>() {
            return Ok(Self::Rgb8(a.readonly()));
        }
        if let Ok(a) = obj.cast::<PyArray2<u16>>() {
            return Ok(Self::Mono16(a.readonly()));
        }
        if let Ok(a) = obj.cast::<PyArray2<f32>>() {
            return Ok(Self::Float32(a.readonly()));
        }
        Err(PyTypeError::new_err(format!("image must be a numpy array {IMAGE_KINDS}")))
    }

    /// `(width, height, pixels)`.
    pub(super) fn pixels(&self) -> PyResult<(u32, u32, Pixels<'_>)> {
        let (shape, px) = match self {
            Self::Mono8(a) => (a.shape(), Pixels::Mono8(c_order(a, "image")?)),
            Self::Rgb8(a) => {
                if a.shape()[2] != 3 {
                    return Err(InputError::new_err(format!("image must be {IMAGE_KINDS}, got {:?}", a.shape())));
                }
                (a.shape(), Pixels::Rgb8(c_order(a, "image")?))
            }
            Self::Mono16(a) => (a.shape(), Pixels::Mono16(c_order(a, "image")?)),
            Self::Float32(a) => (a.shape(), Pixels::Float32(c_order(a, "image")?)),
        };
        let dim = |v: usize| u32::try_from(v).map_err(|_| InputError::new_err("image is too large"));
        Ok((dim(shape[1])?, dim(shape[0])?, px))
    }
}

/// Checks every `(name, len)` equals `n`.
pub(super) fn same_len(n: usize, what: &str, lens: &[(&str, usize)]) -> PyResult<()> {
    for (name, len) in lens {
        if *len != n {
            return Err(InputError::new_err(format!("{name} has {len} entries for {n} {what}; give one per entry")));
        }
    }
    Ok(())
}
