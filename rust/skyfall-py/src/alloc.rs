//! Output arrays allocated fallibly: through `numpy.zeros`, so a refused allocation is
//! numpy's own `MemoryError`. (rust-numpy's `PyArray::zeros`, `from_vec` and `into_pyarray`
//! panic on the NULL numpy returns then; a Rust `Vec` that cannot grow aborts the process.)

use numpy::ndarray::Dimension;
use numpy::{Element, PyArray, PyArrayMethods, dtype};
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::errors::SkyfallError;

/// A new C-ordered array of zeros of `shape` (numpy's calloc: untouched pages cost nothing).
pub fn zeros<'py, T: Element, D: Dimension>(
    py: Python<'py>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArray<T, D>>> {
    let np = py.import(intern!(py, "numpy"))?;
    let a = np
        .getattr(intern!(py, "zeros"))?
        .call1((PyTuple::new(py, shape)?, dtype::<T>(py)))?;
    Ok(a.cast_into::<PyArray<T, D>>()?)
}

/// A new array of `shape` whose values `fill` writes (given the zeroed C-ordered buffer).
pub fn filled<'py, T: Element, D: Dimension>(
    py: Python<'py>,
    shape: &[usize],
    fill: impl FnOnce(&mut [T]) -> PyResult<()>,
) -> PyResult<Bound<'py, PyArray<T, D>>> {
    let a = zeros::<T, D>(py, shape)?;
    {
        let mut w = a.try_readwrite().map_err(|e| {
            SkyfallError::new_err(format!("internal: a new array is borrowed: {e}"))
        })?;
        fill(w.as_slice_mut()?)?;
    }
    Ok(a)
}

/// A new array of `shape` holding `values` (row-major; their length must be the shape's).
pub fn from_slice<'py, T: Element + Copy, D: Dimension>(
    py: Python<'py>,
    shape: &[usize],
    values: &[T],
) -> PyResult<Bound<'py, PyArray<T, D>>> {
    filled(py, shape, |out| {
        if out.len() != values.len() {
            return Err(SkyfallError::new_err(format!(
                "internal: {} values for shape {shape:?}",
                values.len()
            )));
        }
        out.copy_from_slice(values);
        Ok(())
    })
}
