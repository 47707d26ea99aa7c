//! The snowflakes near a point, as arrays: ground truth, and the flux the notebooks count.

use crate::errors::CoreError;
use crate::rain_frame::{ParticleArrays, particle_arrays};
use crate::request::WeatherSpec;
use glam::DVec3;
use pyo3::prelude::*;
use skyfall_core::snow::flakes::{Flake, SnowRegion, flakes_near};

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
) -> PyResult<ParticleArrays<'py>> {
    let w = weather.core()?;
    let reg = SnowRegion::new(w.snow_rate_mm_h, w.snow_near_m, w.wind_m_s, time_s, seed)
        .map_err(CoreError)?;
    reg.check_budget(1.0).map_err(CoreError)?;
    let c = DVec3::from(center_m);
    let flakes: Vec<Flake> = py
        .detach(|| flakes_near(&reg, c, ground))
        .map_err(CoreError)?;
    particle_arrays(py, c, &flakes)
}
