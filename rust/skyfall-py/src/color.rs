//! Output encoding.

use crate::errors::invalid;
use numpy::ndarray::IxDyn;
use numpy::{PyArrayDyn, PyReadonlyArray1, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// Linear float32 (any shape) to 8-bit sRGB of the same shape, GIL released.
#[pyfunction]
pub fn encode_srgb8<'py>(
    py: Python<'py>,
    linear: PyReadonlyArrayDyn<'py, f32>,
) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
    let src = linear.as_slice()?;
    // 8-bit sRGB has no NaN: refused as `io.write_image` refuses it, not encoded as 0.
    let nan = py.detach(|| src.iter().filter(|v| v.is_nan()).count());
    if nan > 0 {
        return Err(invalid(
            "linear",
            None,
            format!(
                "holds {nan} NaN values, which 8-bit sRGB cannot store: replace them (np.nan_to_num)"
            ),
        ));
    }
    crate::alloc::filled::<u8, IxDyn>(py, linear.shape(), |out| {
        py.detach(|| skyfall_core::color::encode_srgb8(src, out));
        Ok(())
    })
}

/// Bytes (any shape) through a 256-entry float32 table, same shape, GIL released.
#[pyfunction]
pub fn apply_lut8<'py>(
    py: Python<'py>,
    encoded: PyReadonlyArrayDyn<'py, u8>,
    table: PyReadonlyArray1<'py, f32>,
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let t: &[f32; 256] = table.as_slice()?.try_into().map_err(|_| {
        invalid(
            "table",
            None,
            format!("must have 256 entries, got {}", table.len()),
        )
    })?;
    let src = encoded.as_slice()?;
    crate::alloc::filled::<f32, IxDyn>(py, encoded.shape(), |out| {
        py.detach(|| skyfall_core::color::apply_lut8(src, t, out));
        Ok(())
    })
}
