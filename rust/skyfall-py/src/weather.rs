//! What a `skyfall.Weather` implies, computed by the core (one definition of the haze model).

use crate::errors::CoreError;
use crate::request::WeatherSpec;
use pyo3::prelude::*;

/// (air extinction, rain extinction, total extinction σ, all 1/m; the cloud base in use, m;
/// the sky's airlight relative to E/π; snow extinction, 1/m) of `weather`, a
/// `skyfall.Weather`.
#[pyfunction]
pub fn weather_optics(weather: WeatherSpec) -> PyResult<(f64, f64, f64, f64, f64, f64)> {
    let w = weather.core()?;
    let sky = w.sky().map_err(CoreError)?;
    Ok((
        w.air_extinction_per_m(),
        w.rain_extinction_per_m(),
        w.extinction_per_m(),
        w.cloud_base_height_m(),
        sky.airlight,
        w.snow_extinction_per_m(),
    ))
}

/// The sun's direct light of `weather`: (its unit direction, towards it; its normal
/// illuminance at the ground over E, through the haze below the cloud base), or None when the
/// weather has no sun.
#[pyfunction]
pub fn weather_sun(weather: WeatherSpec) -> PyResult<Option<([f32; 3], f64)>> {
    let w = weather.core()?;
    Ok(w.sun().map(|(d, r)| (d.to_array(), r)))
}
