//! `skyfall.snow.accumulate`'s core: the snow cover of a box scene or a photo
//! ([`skyfall_core::snow::cover`]), held as a [`SnowCoverGrid`] that frames draw.

use crate::boxes::box_scene;
use crate::errors::CoreError;
use crate::interrupt::interruptible_core;
use crate::request::{CameraSpec, WeatherSpec};
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use skyfall_core::snow::cover::{CoverParams, Grid, HeightField, SnowCover, accumulate};
use std::sync::Arc;

/// A snow cover: its height field, depth per cell and bookkeeping (see `skyfall.snow`).
#[pyclass(frozen, module = "skyfall._core")]
pub struct SnowCoverGrid {
    /// The core's cover, shared with the frames that draw it.
    pub cover: Arc<SnowCover>,
}

#[pymethods]
impl SnowCoverGrid {
    /// Depth of snow per cell, m, (nz, nx) float64.
    #[getter]
    fn depth_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let g = self.cover.field.grid;
        let a = numpy::ndarray::Array2::from_shape_vec((g.nz, g.nx), self.cover.depth_m.clone())
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        Ok(a.into_pyarray(py))
    }

    /// Height of the surface under the snow per cell, m (NaN: no surface), (nz, nx) float64.
    #[getter]
    fn base_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let g = self.cover.field.grid;
        let a =
            numpy::ndarray::Array2::from_shape_vec((g.nz, g.nx), self.cover.field.base_m.clone())
                .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        Ok(a.into_pyarray(py))
    }

    /// World (x, z) of the grid's corner, m.
    #[getter]
    fn origin_m(&self) -> (f64, f64) {
        let o = self.cover.field.grid.origin_m;
        (o[0], o[1])
    }

    /// Cell side, m.
    #[getter]
    fn spacing_m(&self) -> f64 {
        self.cover.field.grid.spacing_m
    }

    /// (nz, nx).
    #[getter]
    fn shape(&self) -> (usize, usize) {
        let g = self.cover.field.grid;
        (g.nz, g.nx)
    }

    /// (fallen_kg, lying_kg, open_sky_kg, open_depth_m).
    #[getter]
    fn budget(&self) -> (f64, f64, f64, f64) {
        let c = &self.cover;
        (c.fallen_kg, c.lying_kg, c.open_sky_kg, c.open_depth_m)
    }

    /// (steps, dt_s).
    #[getter]
    fn steps(&self) -> (usize, f64) {
        (self.cover.steps, self.cover.dt_s)
    }

    /// The snow's mean fall velocity, m/s.
    #[getter]
    fn fall_velocity_m_s(&self) -> (f64, f64, f64) {
        let v = self.cover.fall_velocity_m_s;
        (v[0], v[1], v[2])
    }

    /// (blown_in_kg, blown_out_kg): snow the wind carried across the grid's edges.
    #[getter]
    fn blown_kg(&self) -> (f64, f64) {
        (self.cover.blown_in_kg, self.cover.blown_out_kg)
    }

    /// (height_m, attenuation, frontal_area_index) of the canopy the wind blew through.
    #[getter]
    fn canopy(&self) -> (f64, f64, f64) {
        let c = self.cover.canopy;
        (c.height_m, c.attenuation, c.frontal_area_index)
    }
}

fn run(
    py: Python<'_>,
    field: HeightField,
    weather: WeatherSpec,
    params: CoverParams,
) -> PyResult<SnowCoverGrid> {
    let w = weather.core()?;
    let cells = field.grid.cells() as u128;
    let steps = (params.duration_s / params.dt_s).ceil().clamp(1.0, 1e9) as u128;
    let cover = interruptible_core(py, cells * steps * 16, move |cancel| {
        accumulate(field, &w, &params, Some(cancel))
    })?;
    Ok(SnowCoverGrid {
        cover: Arc::new(cover),
    })
}

/// The cover of a box scene (its (N, 9) box rows, ground) over x ∈ [lo[0], hi[0]],
/// z ∈ [lo[1], hi[1]] in `resolution_m` cells.
#[pyfunction]
#[pyo3(signature = (boxes, ground, weather, lo_m, hi_m, *, resolution_m, duration_s, dt_s, roughness, seed, turbulence, redistribute))]
#[allow(clippy::too_many_arguments)]
pub fn snow_cover_boxes(
    py: Python<'_>,
    boxes: PyReadonlyArray2<'_, f32>,
    ground: bool,
    weather: WeatherSpec,
    lo_m: [f64; 2],
    hi_m: [f64; 2],
    resolution_m: f64,
    duration_s: f64,
    dt_s: f64,
    roughness: f64,
    seed: u64,
    turbulence: f64,
    redistribute: bool,
) -> PyResult<SnowCoverGrid> {
    let scene = box_scene(&boxes, ground, [0.0; 3])?;
    let grid = Grid::covering(lo_m, hi_m, resolution_m).map_err(CoreError)?;
    let field = HeightField::from_boxes(&scene, grid).map_err(CoreError)?;
    let params = CoverParams {
        duration_s,
        dt_s,
        roughness,
        seed,
        turbulence,
        redistribute,
    };
    run(py, field, weather, params)
}

/// The cover of a photo: its surfaces from `depth_m` through `camera`.
#[pyfunction]
#[pyo3(signature = (camera, depth_m, weather, *, resolution_m, duration_s, dt_s, roughness, seed, turbulence, redistribute))]
#[allow(clippy::too_many_arguments)]
pub fn snow_cover_photo(
    py: Python<'_>,
    camera: CameraSpec,
    depth_m: PyReadonlyArray2<'_, f32>,
    weather: WeatherSpec,
    resolution_m: f64,
    duration_s: f64,
    dt_s: f64,
    roughness: f64,
    seed: u64,
    turbulence: f64,
    redistribute: bool,
) -> PyResult<SnowCoverGrid> {
    let cam = camera.camera;
    let d = depth_m.as_slice()?;
    if d.len() != cam.pixels() {
        return Err(crate::errors::invalid(
            "depth_m",
            None,
            format!("has {} values, the camera {} pixels", d.len(), cam.pixels()),
        ));
    }
    let field = HeightField::from_depth_map(&cam, d, resolution_m).map_err(CoreError)?;
    let params = CoverParams {
        duration_s,
        dt_s,
        roughness,
        seed,
        turbulence,
        redistribute,
    };
    run(py, field, weather, params)
}
