//! The drops near a camera, as arrays: ground truth for stereo and video.

use crate::alloc::filled;
use crate::boxes::box_rows;
use crate::errors::CoreError;
use crate::request::WeatherSpec;
use glam::DVec3;
use numpy::ndarray::{Ix1, Ix2};
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use skyfall_core::particles::Particle;
use skyfall_core::rain::drops::{Drop, drops_near};
use skyfall_core::rain::shelter::remove_sheltered;

/// Particles as numpy arrays: positions, velocities, diameters, ids.
pub type ParticleArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray2<i64>>,
);

/// Every drop of `weather` (a `skyfall.Weather`) at `time_s` with `seed` within its region
/// around `center_m`, less those `shelter` boxes (N, 9) keep
/// dry: world positions (N, 3, f64: exact far from the origin), velocities (N, 3), diameters
/// (N,) in m, ids (N, 5).
#[pyfunction]
#[pyo3(signature = (center_m, weather, *, time_s, seed, ground, shelter=None))]
pub fn rain_drops<'py>(
    py: Python<'py>,
    center_m: [f64; 3],
    weather: WeatherSpec,
    time_s: f64,
    seed: u64,
    ground: bool,
    shelter: Option<PyReadonlyArray2<'py, f32>>,
) -> PyResult<ParticleArrays<'py>> {
    skyfall_core::ranges::TIME_S
        .check(time_s)
        .map_err(CoreError)?;
    let reg = weather.core()?.region(time_s, seed).map_err(CoreError)?;
    let boxes = match &shelter {
        Some(b) => box_rows(b)?,
        None => Vec::new(),
    };
    let c = DVec3::from(center_m);
    reg.check_budget(1.0).map_err(CoreError)?;
    let drops: Vec<Drop> = py
        .detach(|| {
            let mut d = drops_near(&reg, c, ground)?;
            remove_sheltered(&mut d, &boxes, c.as_vec3(), reg.near_m as f32);
            Ok::<_, skyfall_core::Error>(d)
        })
        .map_err(CoreError)?;
    particle_arrays(py, c, &drops)
}

/// Particles kept relative to `c` as arrays: world positions (N, 3, f64), velocities
/// (N, 3), diameters (N,) in m, ids (N, 5). The drops' and the flakes' ground truth alike.
pub fn particle_arrays<'py>(
    py: Python<'py>,
    c: DVec3,
    particles: &[Particle],
) -> PyResult<ParticleArrays<'py>> {
    let n = particles.len();
    let pos = filled::<f64, Ix2>(py, &[n, 3], |out| {
        // The core keeps particles relative to the centre; these are world positions.
        for (o, d) in out.chunks_exact_mut(3).zip(particles) {
            o.copy_from_slice(&(c + d.position_m.as_dvec3()).to_array());
        }
        Ok(())
    })?;
    let vel = filled::<f32, Ix2>(py, &[n, 3], |out| {
        for (o, d) in out.chunks_exact_mut(3).zip(particles) {
            o.copy_from_slice(&d.velocity_m_s.to_array());
        }
        Ok(())
    })?;
    let diam = filled::<f32, Ix1>(py, &[n], |out| {
        for (o, d) in out.iter_mut().zip(particles) {
            *o = d.diameter_m;
        }
        Ok(())
    })?;
    let ids = filled::<i64, Ix2>(py, &[n, 5], |out| {
        for (o, d) in out.chunks_exact_mut(5).zip(particles) {
            o.copy_from_slice(&d.id);
        }
        Ok(())
    })?;
    Ok((pos, vel, diam, ids))
}
