//! Skies, sky illuminance with occlusion and the ambient-light map.

use crate::alloc::{filled, from_slice};
use crate::boxes::box_scene;
use crate::clouds::CloudDome;
use crate::errors::{CoreError, invalid};
use crate::interrupt::interruptible_core;
use glam::Vec3;
use numpy::ndarray::{Ix1, Ix2, Ix3, Ix4};
use numpy::{PyArray1, PyArray2, PyArray3, PyArray4, PyReadonlyArray2};
use pyo3::prelude::*;
use rayon::prelude::*;
use skyfall_core::error::{Error, check_cancel};
use skyfall_core::ranges;
use skyfall_core::scene::boxes::BoxScene;
use skyfall_core::sky::ambient::AmbientMap;
use skyfall_core::sky::cie::SkyKind;
use skyfall_core::sky::horizon::Horizon;
use skyfall_core::sky::illuminance::{CHANNELS, SkyTable, boxes_above, irradiance};
use skyfall_core::sky::{Sky, cloud_base_m as base_for_rate, sun_direction};
use std::sync::Arc;
use std::sync::atomic::Ordering;

/// Rows of an (N, 3) float32 array as points.
fn points(a: &PyReadonlyArray2<'_, f32>, name: &'static str) -> PyResult<Vec<Vec3>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(invalid(
            name,
            None,
            format!("must have shape (N, 3), got {:?}", v.shape()),
        ));
    }
    let mut pts: Vec<Vec3> = Vec::new();
    pts.try_reserve_exact(v.nrows())
        .map_err(|_| CoreError(Error::out_of_memory::<Vec3>(name.to_string(), v.nrows())))?;
    pts.extend(v.rows().into_iter().map(|r| Vec3::new(r[0], r[1], r[2])));
    if let Some(i) = pts.iter().position(|p| !p.is_finite()) {
        return Err(invalid(name, Some(i), "must be finite"));
    }
    Ok(pts)
}

/// A normalised sky with rain attenuation.
#[pyclass(frozen, module = "skyfall._core")]
pub struct SkyModel {
    pub(crate) sky: Sky,
}

#[pymethods]
impl SkyModel {
    /// `sky_type` 0 is Yamamoto & Tadamura's overcast sky, 1–15 the CIE general skies.
    #[new]
    #[pyo3(signature = (sky_type, sun_elevation_deg, sun_azimuth_deg, extinction_per_m, cloud_base_m))]
    fn new(
        sky_type: i64,
        sun_elevation_deg: Option<f64>,
        sun_azimuth_deg: Option<f64>,
        extinction_per_m: f64,
        cloud_base_m: f64,
    ) -> PyResult<Self> {
        let sun = match (sun_elevation_deg, sun_azimuth_deg) {
            (Some(el), Some(az)) => {
                ranges::SUN_ELEVATION_DEG.check(el).map_err(CoreError)?;
                ranges::SUN_AZIMUTH_DEG.check(az).map_err(CoreError)?;
                Some(sun_direction(el, az))
            }
            (None, None) => None,
            (el, _) => {
                return Err(invalid(
                    if el.is_some() {
                        "sun_azimuth_deg"
                    } else {
                        "sun_elevation_deg"
                    },
                    None,
                    "give both sun_elevation_deg and sun_azimuth_deg, or neither",
                ));
            }
        };
        let kind = if sky_type == 0 {
            SkyKind::Overcast
        } else {
            SkyKind::general(sky_type, sun).map_err(CoreError)?
        };
        Ok(SkyModel {
            sky: Sky::new(kind, extinction_per_m, cloud_base_m).map_err(CoreError)?,
        })
    }

    /// π / ∫ (L/Lz) τ cos θ dω: L/Lz times this is the luminance relative to E/π.
    #[getter]
    fn scale(&self) -> f64 {
        self.sky.scale
    }

    /// Luminance relative to E/π along unit directions (N, 3): emitted by the cloud base, or
    /// `received` at the ground through the rain.
    #[pyo3(signature = (dirs, *, received))]
    fn luminance_relative<'py>(
        &self,
        py: Python<'py>,
        dirs: PyReadonlyArray2<'py, f32>,
        received: bool,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let d = points(&dirs, "directions")?;
        filled::<f64, Ix1>(py, &[d.len()], |out| {
            for (o, v) in out.iter_mut().zip(&d) {
                let u = v.normalize_or_zero();
                *o = if received {
                    self.sky.received(u)
                } else {
                    self.sky.emitted(u)
                };
            }
            Ok(())
        })
    }

    /// [`Self::luminance_relative`] in colour: linear Rec. 709 RGB (N, 3) whose luminance
    /// (0.2126 R + 0.7152 G + 0.0722 B) is the luminance there.
    #[pyo3(signature = (dirs, *, received))]
    fn rgb_relative<'py>(
        &self,
        py: Python<'py>,
        dirs: PyReadonlyArray2<'py, f32>,
        received: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = points(&dirs, "directions")?;
        filled::<f64, Ix2>(py, &[d.len(), 3], |out| {
            for (o, v) in out.chunks_exact_mut(3).zip(&d) {
                let u = v.normalize_or_zero();
                let c = if received {
                    self.sky.received_rgb(u)
                } else {
                    self.sky.sky_pixel_rgb(u)
                };
                o.copy_from_slice(&c.to_array().map(f64::from));
            }
            Ok(())
        })
    }

    /// The colour of the horizon (the airlight's), of the light the open sky gives a
    /// horizontal surface, and of the sun's direct light: linear Rec. 709 RGB of luminance 1
    /// each, (1, 1, 1) for an overcast sky.
    #[getter]
    fn colours(&self) -> ([f32; 3], [f32; 3], [f32; 3]) {
        (
            self.sky.horizon_colour.to_array(),
            self.sky.light_colour.to_array(),
            self.sky.sun_colour.to_array(),
        )
    }

    /// Illuminance relative to E on the five normals (up, +X, −X, +Z, −Z) at points (N, 3)
    /// among boxes (M, 9), points in parallel.
    #[pyo3(signature = (points_m, boxes, *, samples))]
    fn illuminance<'py>(
        &self,
        py: Python<'py>,
        points_m: PyReadonlyArray2<'py, f32>,
        boxes: PyReadonlyArray2<'py, f32>,
        samples: usize,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let pts = points(&points_m, "points_m")?;
        let scene = box_scene(&boxes, true, [0.0; 3])?;
        let sky = &self.sky;
        // (the sky table itself costs about as much as 512 points)
        let steps = (pts.len() as u128 + 512) * samples as u128;
        filled::<f32, Ix2>(py, &[pts.len(), CHANNELS], |out| {
            interruptible_core(py, steps, |cancel| {
                let s = SkyTable::new_cancellable(sky, samples, cancel)?;
                out.par_chunks_mut(CHANNELS)
                    .zip(pts.par_iter())
                    .for_each(|(o, &p)| {
                        if !cancel.load(Ordering::Relaxed) {
                            o.copy_from_slice(&irradiance(&boxes_above(&scene, p.y), &s, p));
                        }
                    });
                check_cancel(cancel, "the illuminance")
            })
        })
    }

    /// The ambient-light map of boxes (M, 9) over `bounds_min_m`..`bounds_max_m`;
    /// `per_azimuth`: the sky tabulated along every azimuth at 512 elevations even when it is
    /// the same at every azimuth (the reference the fast reading is tested against).
    /// `dome`: clouds in the sky (`CloudDome`), which the map's light then includes (its
    /// colour too: `AmbientLightMap.light_colour`).
    #[pyo3(signature = (boxes, *, bounds_min_m, bounds_max_m, spacing_m, samples, spacing_name=None, per_azimuth=false, dome=None))]
    #[allow(clippy::too_many_arguments)]
    fn ambient_map(
        &self,
        py: Python<'_>,
        boxes: PyReadonlyArray2<'_, f32>,
        bounds_min_m: [f32; 3],
        bounds_max_m: [f32; 3],
        spacing_m: f64,
        samples: usize,
        spacing_name: Option<String>,
        per_azimuth: bool,
        dome: Option<&CloudDome>,
    ) -> PyResult<AmbientLightMap> {
        let (scene, lo, hi, nodes) =
            map_grid(&boxes, bounds_min_m, bounds_max_m, spacing_m, spacing_name)?;
        let sky = &self.sky;
        let steps = (if scene.boxes.is_empty() { 0 } else { nodes } + 512) * samples as u128;
        let dome = dome.map(|d| Arc::clone(&d.dome));
        let map = interruptible_core(py, steps, |cancel| {
            let (s, colour) = table(sky, dome.as_deref(), samples, per_azimuth, cancel)?;
            let mut map = if scene.boxes.is_empty() {
                // (the bounds and spacing were checked above)
                AmbientMap::uniform(irradiance(&[], &s, Vec3::ZERO))
            } else {
                AmbientMap::build_cancellable(&scene, &s, lo, hi, spacing_m, cancel)?
            };
            map.light_colour = colour;
            Ok(map)
        })?;
        Ok(AmbientLightMap { map: Arc::new(map) })
    }

    /// The ambient-light map under this sky from `horizon` (`ambient_horizon`): the map
    /// `ambient_map` builds over the same boxes, bounds, spacing and samples, bit for bit,
    /// from the sky's tables alone (what the boxes hide was found once, in the horizon; for a
    /// sky the same at every azimuth, each node's weights, made at the first such sky).
    /// `dome`: clouds in the sky, as `ambient_map` takes them.
    #[pyo3(signature = (horizon, *, dome=None))]
    fn light_map(
        &self,
        py: Python<'_>,
        horizon: &AmbientHorizon,
        dome: Option<&CloudDome>,
    ) -> PyResult<AmbientLightMap> {
        let h = Arc::clone(&horizon.inner);
        let sky = &self.sky;
        let [nx, ny, nz] = h.dims();
        let steps = (nx * ny * nz + 512) as u128 * h.azimuths() as u128 / 8;
        let dome = dome.map(|d| Arc::clone(&d.dome));
        let map = interruptible_core(py, steps, |cancel| {
            let (t, colour) = table(sky, dome.as_deref(), h.azimuths(), false, cancel)?;
            let mut map = h.light(&t, cancel)?;
            map.light_colour = colour;
            Ok(map)
        })?;
        Ok(AmbientLightMap { map: Arc::new(map) })
    }
}

/// The sky's table on `samples` azimuths (`per_azimuth`: along every one even for a symmetric
/// sky), with `dome`'s clouds in it and the colour of their light when given (and any cloud
/// shows in the sky: a clear dome leaves the sky's own table, bit for bit).
fn table(
    sky: &Sky,
    dome: Option<&skyfall_core::cloud::dome::CloudDome>,
    samples: usize,
    per_azimuth: bool,
    cancel: &std::sync::atomic::AtomicBool,
) -> Result<(SkyTable, Option<Vec3>), Error> {
    Ok(match dome {
        Some(d) if !d.is_clear() => {
            let (t, c) = skyfall_core::cloud::dome::clouded_light(sky, d, samples, cancel)?;
            (t, Some(c))
        }
        _ if per_azimuth => (SkyTable::per_azimuth(sky, samples, cancel)?, None),
        _ => (SkyTable::new_cancellable(sky, samples, cancel)?, None),
    })
}

/// What a scene fixes of its ambient-light map (see skyfall_core::sky::horizon): each open
/// node's visible sky per azimuth, found once and lit under any sky by `SkyModel.light_map`.
#[pyclass(frozen, module = "skyfall._core")]
pub struct AmbientHorizon {
    pub(crate) inner: Arc<Horizon>,
}

#[pymethods]
impl AmbientHorizon {
    /// Nodes along X, Y, Z.
    #[getter]
    fn dims(&self) -> [usize; 3] {
        self.inner.dims()
    }

    /// Azimuths per node.
    #[getter]
    fn samples(&self) -> usize {
        self.inner.azimuths()
    }

    /// Bytes it holds.
    #[getter]
    fn nbytes(&self) -> usize {
        self.inner.bytes()
    }
}

/// A map's boxes (N, 6) as a scene, its bounds, and its node count, the bounds and the
/// spacing checked (errors name the spacing `spacing_name`, the caller's own parameter).
fn map_grid(
    boxes: &PyReadonlyArray2<'_, f32>,
    bounds_min_m: [f32; 3],
    bounds_max_m: [f32; 3],
    spacing_m: f64,
    spacing_name: Option<String>,
) -> PyResult<(BoxScene, Vec3, Vec3, u128)> {
    let scene: BoxScene = box_scene(boxes, true, [0.0; 3])?;
    let (lo, hi) = (Vec3::from(bounds_min_m), Vec3::from(bounds_max_m));
    let name = spacing_name
        .and_then(|n| skyfall_core::ranges::find(&n))
        .map_or("spacing_m", |l| l.name);
    let nodes = AmbientMap::grid_dims_for(lo, hi, spacing_m, name)
        .map_err(CoreError)?
        .iter()
        .map(|&d| d as u128)
        .product::<u128>();
    Ok((scene, lo, hi, nodes))
}

/// The horizon of the boxes (N, 6) over the grid `ambient_map` builds for these bounds,
/// spacing and samples (azimuths); MemoryError past `HORIZON_MAX_PAIRS` node-azimuth pairs.
#[pyfunction]
#[pyo3(signature = (boxes, *, bounds_min_m, bounds_max_m, spacing_m, samples, spacing_name=None))]
pub fn ambient_horizon(
    py: Python<'_>,
    boxes: PyReadonlyArray2<'_, f32>,
    bounds_min_m: [f32; 3],
    bounds_max_m: [f32; 3],
    spacing_m: f64,
    samples: usize,
    spacing_name: Option<String>,
) -> PyResult<AmbientHorizon> {
    let (scene, lo, hi, nodes) =
        map_grid(&boxes, bounds_min_m, bounds_max_m, spacing_m, spacing_name)?;
    let horizon = interruptible_core(py, (nodes + 512) * samples as u128, |cancel| {
        Horizon::build_cancellable(&scene, samples, lo, hi, spacing_m, cancel)
    })?;
    Ok(AmbientHorizon {
        inner: Arc::new(horizon),
    })
}

/// Sky illuminance relative to E on five normals over a grid (see skyfall_core::sky::ambient).
#[pyclass(frozen, module = "skyfall._core")]
pub struct AmbientLightMap {
    pub(crate) map: Arc<AmbientMap>,
}

#[pymethods]
impl AmbientLightMap {
    /// Node (0, 0, 0), m.
    #[getter]
    fn origin_m(&self) -> [f32; 3] {
        self.map.origin_m.to_array()
    }

    /// Node spacing, m.
    #[getter]
    fn spacing_m(&self) -> f32 {
        self.map.spacing_m
    }

    /// Nodes along X, Y, Z.
    #[getter]
    fn dims(&self) -> [usize; 3] {
        self.map.dims
    }

    /// The grid, (nx, ny, nz, 5), relative to E.
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray4<f32>>> {
        let [nx, ny, nz] = self.map.dims;
        from_slice::<f32, Ix4>(py, &[nx, ny, nz, CHANNELS], &self.map.values)
    }

    /// Nodes inside a box, (nx, ny, nz).
    #[getter]
    fn solid<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<bool>>> {
        let [nx, ny, nz] = self.map.dims;
        filled::<bool, Ix3>(py, &[nx, ny, nz], |out| {
            for (o, &s) in out.iter_mut().zip(&self.map.solid) {
                *o = s != 0;
            }
            Ok(())
        })
    }

    /// The colour of the light of the map's sky on a horizontal surface (linear RGB of
    /// luminance 1) when the map has clouds in its sky; None: its sky's own colour.
    #[getter]
    fn light_colour(&self) -> Option<[f32; 3]> {
        self.map.light_colour.map(|c| c.to_array())
    }

    /// Trilinear samples at points (N, 3): (N, 5) relative to E.
    fn sample<'py>(
        &self,
        py: Python<'py>,
        points_m: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let pts = points(&points_m, "points_m")?;
        filled::<f32, Ix2>(py, &[pts.len(), CHANNELS], |out| {
            for (o, &p) in out.chunks_exact_mut(CHANNELS).zip(&pts) {
                o.copy_from_slice(&self.map.sample(p));
            }
            Ok(())
        })
    }
}

/// Cloud base height for a rain rate, m (see skyfall_core::sky::cloud_base_m).
#[pyfunction]
pub fn cloud_base_m(rain_rate_mm_h: f64) -> PyResult<f64> {
    ranges::RAIN_RATE_MM_H
        .check(rain_rate_mm_h)
        .map_err(CoreError)?;
    Ok(base_for_rate(rain_rate_mm_h))
}
