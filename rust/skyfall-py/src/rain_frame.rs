//! The drops near a camera, as arrays: ground truth for stereo and video.

use crate::render::{region, RegionArgs};
use glam::Vec3;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use skyfall_core::rain::drops::{drops_near, Drop};

type DropArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<f32>>, Bound<'py, PyArray1<f32>>, Bound<'py, PyArray2<i64>>);

/// Every drop within the region around `center_m`: positions (N, 3), velocities (N, 3),
/// diameters (N,) in m, ids (N, 5).
#[pyfunction]
#[pyo3(signature = (center_m, region_args, *, ground))]
pub fn rain_drops<'py>(py: Python<'py>, center_m: [f32; 3], region_args: RegionArgs<'py>, ground: bool) -> PyResult<DropArrays<'py>> {
    let reg = region(&region_args)?;
    let drops: Vec<Drop> = py.detach(|| drops_near(&reg, Vec3::from(center_m), ground));
    let n = drops.len();
    let err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let pos = Array2::from_shape_vec((n, 3), drops.iter().flat_map(|d| d.position_m.to_array()).collect()).map_err(err)?;
    let vel = Array2::from_shape_vec((n, 3), drops.iter().flat_map(|d| d.velocity_m_s.to_array()).collect()).map_err(err)?;
    let diam: Vec<f32> = drops.iter().map(|d| d.diameter_m).collect();
    let ids = Array2::from_shape_vec((n, 5), drops.iter().flat_map(|d| d.id).collect()).map_err(err)?;
    Ok((pos.into_pyarray(py), vel.into_pyarray(py), diam.into_pyarray(py), ids.into_pyarray(py)))
}
