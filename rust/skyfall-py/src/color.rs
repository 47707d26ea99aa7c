//! Output encoding.

use numpy::{
    PyArrayDyn, PyArrayMethods, PyReadonlyArray1, PyReadonlyArrayDyn, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Linear float32 (any shape) to 8-bit sRGB of the same shape, GIL released.
#[pyfunction]
pub fn encode_srgb8<'py>(
    py: Python<'py>,
    linear: PyReadonlyArrayDyn<'py, f32>,
) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
    let src = linear.as_slice()?;
    let shape = linear.shape().to_vec();
    let mut out = vec![0u8; src.len()];
    py.detach(|| skyfall_core::color::encode_srgb8(src, &mut out));
    let arr = numpy::PyArray1::from_vec(py, out);
    arr.reshape(shape)
}

/// Bytes (any shape) through a 256-entry float32 table, same shape, GIL released.
#[pyfunction]
pub fn apply_lut8<'py>(
    py: Python<'py>,
    encoded: PyReadonlyArrayDyn<'py, u8>,
    table: PyReadonlyArray1<'py, f32>,
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let t: &[f32; 256] = table.as_slice()?.try_into().map_err(|_| {
        PyValueError::new_err(format!("table must have 256 entries, got {}", table.len()))
    })?;
    let src = encoded.as_slice()?;
    let shape = encoded.shape().to_vec();
    let mut out = vec![0.0f32; src.len()];
    py.detach(|| skyfall_core::color::apply_lut8(src, t, &mut out));
    numpy::PyArray1::from_vec(py, out).reshape(shape)
}
