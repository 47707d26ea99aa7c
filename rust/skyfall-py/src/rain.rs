//! Wrappers of `skyfall_core::rain`.

use crate::alloc::{filled, from_slice};
use crate::errors::CoreError;
use numpy::ndarray::{Ix1, Ix4};
use numpy::{PyArray1, PyArray4, PyReadonlyArray1};
use pyo3::prelude::*;
use skyfall_core::rain::bins::diameter_bins;
use skyfall_core::rain::texture::{TextureRequest, render_textures_into};

/// Rain textures, float32 (n_rates, n_diameters, size_px, size_px).
#[pyfunction]
pub fn rain_textures<'py>(
    py: Python<'py>,
    rain_rates_mm_h: PyReadonlyArray1<'py, f64>,
    diameters_mm: PyReadonlyArray1<'py, f64>,
    size_px: usize,
    exposure_s: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyArray4<f32>>> {
    let req = TextureRequest {
        rain_rates_mm_h: rain_rates_mm_h.as_slice()?,
        diameters_mm: diameters_mm.as_slice()?,
        size_px,
        exposure_s,
        seed,
    };
    let shape = (
        req.rain_rates_mm_h.len(),
        req.diameters_mm.len(),
        size_px,
        size_px,
    );
    // Checked (the texture budget included) before numpy allocates the textures, then drawn
    // straight into numpy's array.
    req.validate().map_err(CoreError)?;
    filled::<f32, Ix4>(py, &[shape.0, shape.1, shape.2, shape.3], |out| {
        py.detach(|| render_textures_into(&req, out))
            .map_err(|e| CoreError(e).into())
    })
}

type BinEdges<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// Diameter bin edges (lower, upper), mm, for texture diameters.
#[pyfunction]
pub fn rain_diameter_bins<'py>(
    py: Python<'py>,
    diameters_mm: PyReadonlyArray1<'py, f64>,
) -> PyResult<BinEdges<'py>> {
    let bins = diameter_bins(diameters_mm.as_slice()?).map_err(CoreError)?;
    let (lo, hi): (Vec<f64>, Vec<f64>) = bins.into_iter().unzip();
    Ok((
        from_slice::<f64, Ix1>(py, &[lo.len()], &lo)?,
        from_slice::<f64, Ix1>(py, &[hi.len()], &hi)?,
    ))
}
