//! `skyfall._core.RANGES` and `check_range`: the core's table of valid ranges
//! (`skyfall_core::ranges`) for Python's own checks and their messages.

use crate::errors::CoreError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `{name: (lo, hi, lo_inclusive, hi_inclusive, unit)}` for every declared parameter.
pub fn table(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for l in skyfall_core::ranges::ALL {
        let r = l.range;
        d.set_item(l.name, (r.lo, r.hi, !r.lo_open, !r.hi_open, r.unit))?;
    }
    Ok(d)
}

/// `{name: meaning}`: one line on each declared parameter.
pub fn meanings(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for l in skyfall_core::ranges::ALL {
        d.set_item(l.name, l.meaning)?;
    }
    Ok(d)
}

/// Returns `value` when it lies in the declared range of `name`, else raises the core's
/// ValueError naming the parameter (element `index` of an array), the value and the range.
#[pyfunction]
#[pyo3(signature = (name, value, index=None))]
pub fn check_range(name: &str, value: f64, index: Option<usize>) -> PyResult<f64> {
    Ok(skyfall_core::ranges::check_named(name, index, value).map_err(CoreError)?)
}
