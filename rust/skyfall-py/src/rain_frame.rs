//! Rain in frames: drops near the camera, and their streaks composited over a frame.

use crate::errors::CoreError;
use crate::render::camera;
use glam::Vec3;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use skyfall_core::rain::drops::{drops_in_view, drops_near, Drop, RainRegion};
use skyfall_core::rain::splat::{composite, RainShading, RainTargets};
use skyfall_core::scene::lights::Light;

/// (rain_rate_mm_h, diameters_mm, near_m, wind_m_s, time_s, seed) → region.
type RegionArgs<'py> = (f64, PyReadonlyArray1<'py, f64>, f64, [f64; 3], f64, u64);

fn region(args: &RegionArgs<'_>) -> PyResult<RainRegion> {
    let (rate, diams, near, wind, time, seed) = args;
    Ok(RainRegion::new(*rate, diams.as_slice()?, *near, *wind, *time, *seed).map_err(CoreError)?)
}

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

type RainOut<'py> = (Bound<'py, PyArray3<f32>>, Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<f32>>, usize, usize, usize);

/// Composites the region's drops over (rgb, depth_m): returns (rgb, rain_alpha, rain_depth_m,
/// drops in the voxels that reach the view, streaks drawn, drops culled). `lights` is (N, 12):
/// position, colour, intensity (cd), spot axis (zero for a point light), cos outer, cos inner.
#[pyfunction]
#[pyo3(signature = (width, height, camera_params, rgb, depth_m, region_args, *, exposure_s, ground, lights=None, sky_illuminance_lux=10000.0, cull_threshold=None))]
#[allow(clippy::too_many_arguments)]
pub fn rain_composite<'py>(
    py: Python<'py>,
    width: u32,
    height: u32,
    camera_params: [f32; 16],
    rgb: PyReadonlyArray3<'py, f32>,
    depth_m: PyReadonlyArray2<'py, f32>,
    region_args: RegionArgs<'py>,
    exposure_s: f32,
    ground: bool,
    lights: Option<PyReadonlyArray2<'py, f32>>,
    sky_illuminance_lux: f32,
    cull_threshold: Option<f32>,
) -> PyResult<RainOut<'py>> {
    let cam = camera(width, height, camera_params)?;
    let reg = region(&region_args)?;
    if !(exposure_s > 0.0 && exposure_s <= 0.1) {
        return Err(PyValueError::new_err(format!("exposure_s = {exposure_s} is outside the valid range (0, 0.1] s")));
    }
    if !(sky_illuminance_lux > 0.0 && sky_illuminance_lux.is_finite()) {
        return Err(PyValueError::new_err(format!("sky_illuminance_lux = {sky_illuminance_lux} must be positive and finite")));
    }
    if cull_threshold.is_some_and(|t| !(t >= 0.0 && t.is_finite())) {
        return Err(PyValueError::new_err("cull_threshold must be a finite number >= 0, or None"));
    }
    let lights = match &lights {
        None => Vec::new(),
        Some(a) => {
            let a = a.as_array();
            a.rows()
                .into_iter()
                .enumerate()
                .map(|(i, row)| Light::from_row(&row.to_vec(), i))
                .collect::<Result<Vec<_>, _>>()
                .map_err(CoreError)?
        }
    };
    let shading = RainShading { lights, sky_illuminance_lux, cull_threshold, ..RainShading::open_sky() };
    let n = cam.pixels();
    let (src, depth) = (rgb.as_slice()?, depth_m.as_slice()?);
    if src.len() != 3 * n || depth.len() != n {
        return Err(PyValueError::new_err(format!("rgb and depth_m must be {height}x{width}")));
    }
    let (out, alpha, rdepth, n_drops, stats) = py.detach(|| {
        let drops = drops_in_view(&reg, &cam, f64::from(exposure_s), ground);
        let mut out = src.to_vec();
        let mut alpha = vec![0.0f32; n];
        let mut rdepth = vec![0.0f32; n];
        let stats = composite(
            &cam,
            &drops,
            exposure_s,
            &shading,
            RainTargets { rgb: &mut out, depth_m: depth, alpha: &mut alpha, rain_depth_m: &mut rdepth },
        );
        (out, alpha, rdepth, drops.len(), stats)
    });
    let (h, w) = (height as usize, width as usize);
    let err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    Ok((
        Array3::from_shape_vec((h, w, 3), out).map_err(err)?.into_pyarray(py),
        Array2::from_shape_vec((h, w), alpha).map_err(err)?.into_pyarray(py),
        Array2::from_shape_vec((h, w), rdepth).map_err(err)?.into_pyarray(py),
        n_drops,
        stats.streaks,
        stats.culled,
    ))
}
