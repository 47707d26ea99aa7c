//! Output encoding.

use numpy::{PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// Linear float32 (any shape) to 8-bit sRGB of the same shape, GIL released.
#[pyfunction]
pub fn encode_srgb8<'py>(py: Python<'py>, linear: PyReadonlyArrayDyn<'py, f32>) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
    let src = linear.as_slice()?;
    let shape = linear.shape().to_vec();
    let mut out = vec![0u8; src.len()];
    py.detach(|| skyfall_core::color::encode_srgb8(src, &mut out));
    let arr = numpy::PyArray1::from_vec(py, out);
    arr.reshape(shape)
}
