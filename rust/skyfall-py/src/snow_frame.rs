//! The snowflakes near a point, as arrays: ground truth, and the flux the notebooks count.

use crate::alloc::filled;
use crate::errors::CoreError;
use crate::request::WeatherSpec;
use glam::DVec3;
use numpy::ndarray::{Ix1, Ix2};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use skyfall_core::snow::flakes::{Flake, SnowRegion, flakes_near};

type FlakeArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray2<i64>>,
);

/// Every flake of `weather` (a `skyfall.Weather`) at `time_s` with `seed` within its
/// `snow_near_m` of `center_m` (only voxels above the ground when `ground`): world positions
/// (N, 3, f64), velocities (N, 3), sizes S (maximum dimension, N) in m, ids (N, 5).
#[pyfunction]
#[pyo3(signature = (center_m, weather, *, time_s, seed, ground))]
pub fn snowflakes<'py>(
    py: Python<'py>,
    center_m: [f64; 3],
    weather: WeatherSpec,
    time_s: f64,
    seed: u64,
    ground: bool,
) -> PyResult<FlakeArrays<'py>> {
    let w = weather.core()?;
    let reg = SnowRegion::new(w.snow_rate_mm_h, w.snow_near_m, w.wind_m_s, time_s, seed)
        .map_err(CoreError)?;
    reg.check_budget(1.0).map_err(CoreError)?;
    let c = DVec3::from(center_m);
    let flakes: Vec<Flake> = py.detach(|| flakes_near(&reg, c, ground));
    let n = flakes.len();
    let pos = filled::<f64, Ix2>(py, &[n, 3], |out| {
        for (o, f) in out.chunks_exact_mut(3).zip(&flakes) {
            o.copy_from_slice(&(c + f.position_m.as_dvec3()).to_array());
        }
        Ok(())
    })?;
    let vel = filled::<f32, Ix2>(py, &[n, 3], |out| {
        for (o, f) in out.chunks_exact_mut(3).zip(&flakes) {
            o.copy_from_slice(&f.velocity_m_s.to_array());
        }
        Ok(())
    })?;
    let size = filled::<f32, Ix1>(py, &[n], |out| {
        for (o, f) in out.iter_mut().zip(&flakes) {
            *o = f.diameter_m;
        }
        Ok(())
    })?;
    let ids = filled::<i64, Ix2>(py, &[n, 5], |out| {
        for (o, f) in out.chunks_exact_mut(5).zip(&flakes) {
            o.copy_from_slice(&f.id);
        }
        Ok(())
    })?;
    Ok((pos, vel, size, ids))
}
