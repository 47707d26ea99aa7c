//! Wrappers of `skyfall_core::cloud`: a cloud's arrays in, numpy out, GIL released.

use crate::errors::{CoreError, invalid};
use numpy::PyUntypedArrayMethods;
use numpy::ndarray::{Ix1, Ix2, Ix3};
use numpy::{PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use skyfall_core::cloud::generate::{Kind, particles};
use skyfall_core::cloud::harris::harris_illumination as harris;
use skyfall_core::cloud::volume::{AttenuationVolume, VolumeBox, sample};
use skyfall_core::cloud::{Cloud, sun_direction as sun_direction_of};

/// The rows of an (N, 3) float64 array `a` (named `name` in errors) as points, each finite.
fn points3(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> PyResult<Vec<glam::DVec3>> {
    let shape = a.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(invalid(
            name,
            None,
            format!("must have shape (N, 3), got {shape:?}"),
        ));
    }
    let p: Vec<glam::DVec3> = a
        .as_slice()?
        .chunks_exact(3)
        .map(|c| glam::DVec3::new(c[0], c[1], c[2]))
        .collect();
    if let Some(i) = p.iter().position(|v| !v.is_finite()) {
        return Err(invalid(name, Some(i), "must be finite"));
    }
    Ok(p)
}

/// A cloud's four arrays as the core's checked [`Cloud`].
fn cloud_of(
    positions_m: &PyReadonlyArray2<'_, f64>,
    radii_m: &PyReadonlyArray1<'_, f64>,
    optical_depths: &PyReadonlyArray1<'_, f64>,
    albedos: &PyReadonlyArray1<'_, f64>,
    asymmetry_g: f64,
) -> PyResult<Cloud> {
    let positions = points3(positions_m, "positions_m")?
        .iter()
        .map(|p| p.to_array())
        .collect();
    Ok(Cloud::new(
        positions,
        radii_m.as_slice()?.to_vec(),
        optical_depths.as_slice()?.to_vec(),
        albedos.as_slice()?.to_vec(),
        asymmetry_g,
    )
    .map_err(CoreError)?)
}

type CloudArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    f64,
);

/// A generated cloud: (positions_m (N, 3), radii_m, optical_depths, albedos, asymmetry_g).
#[pyfunction]
pub fn cloud_particles<'py>(
    py: Python<'py>,
    kind: &str,
    n_particles: usize,
    extent_m: f64,
    altitude_m: f64,
    seed: u64,
) -> PyResult<CloudArrays<'py>> {
    let kind = Kind::parse(kind).map_err(CoreError)?;
    let c = py
        .detach(|| particles(kind, n_particles, extent_m, altitude_m, seed))
        .map_err(CoreError)?;
    let flat: Vec<f64> = c.positions_m.iter().flatten().copied().collect();
    let n = c.len();
    Ok((
        crate::alloc::from_slice::<f64, Ix2>(py, &[n, 3], &flat)?,
        crate::alloc::from_slice::<f64, Ix1>(py, &[n], &c.radii_m)?,
        crate::alloc::from_slice::<f64, Ix1>(py, &[n], &c.optical_depths)?,
        crate::alloc::from_slice::<f64, Ix1>(py, &[n], &c.albedos)?,
        c.asymmetry_g,
    ))
}

/// Harris' per-particle sunlight, in the unit of `sun_radiance`.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn harris_illumination<'py>(
    py: Python<'py>,
    positions_m: PyReadonlyArray2<'py, f64>,
    radii_m: PyReadonlyArray1<'py, f64>,
    optical_depths: PyReadonlyArray1<'py, f64>,
    albedos: PyReadonlyArray1<'py, f64>,
    asymmetry_g: f64,
    sun_direction: [f64; 3],
    sun_radiance: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let c = cloud_of(
        &positions_m,
        &radii_m,
        &optical_depths,
        &albedos,
        asymmetry_g,
    )?;
    let light = py
        .detach(|| harris(&c, sun_direction, sun_radiance))
        .map_err(CoreError)?;
    crate::alloc::from_slice::<f64, Ix1>(py, &[light.len()], &light)
}

type VolumeArrays<'py> = (Bound<'py, PyArray3<f32>>, Bound<'py, PyArray2<f64>>);

/// The attenuation volume: (Γ (R, R, R) float32, world_from_volume (4, 4)).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn attenuation_volume<'py>(
    py: Python<'py>,
    positions_m: PyReadonlyArray2<'py, f64>,
    radii_m: PyReadonlyArray1<'py, f64>,
    optical_depths: PyReadonlyArray1<'py, f64>,
    albedos: PyReadonlyArray1<'py, f64>,
    asymmetry_g: f64,
    sun_direction: [f64; 3],
    resolution: usize,
) -> PyResult<VolumeArrays<'py>> {
    let c = cloud_of(
        &positions_m,
        &radii_m,
        &optical_depths,
        &albedos,
        asymmetry_g,
    )?;
    sun_direction_of(sun_direction).map_err(CoreError)?;
    skyfall_core::ranges::RESOLUTION
        .check(resolution as f64)
        .map_err(CoreError)?;
    let n = resolution;
    let mut grid = None;
    // Built straight into numpy's array (zeroed pages, first touched by the build's threads).
    let gamma = crate::alloc::filled::<f32, Ix3>(py, &[n, n, n], |out| {
        let g = py
            .detach(|| AttenuationVolume::build_into(&c, sun_direction, n, out))
            .map_err(CoreError)?;
        grid = Some(g);
        Ok(())
    })?;
    let grid = grid.ok_or_else(|| invalid("gamma", None, "internal: the volume was not built"))?;
    Ok((
        gamma,
        crate::alloc::from_slice::<f64, Ix2>(py, &[4, 4], &grid.matrix())?,
    ))
}

/// Trilinear Γ at world points (M, 3).
#[pyfunction]
pub fn sample_attenuation<'py>(
    py: Python<'py>,
    gamma: PyReadonlyArray3<'py, f32>,
    world_from_volume: PyReadonlyArray2<'py, f64>,
    points_m: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    let s = gamma.shape();
    if s[0] != s[1] || s[1] != s[2] || s[0] == 0 {
        return Err(invalid(
            "gamma",
            None,
            format!("must be a non-empty cube, got {s:?}"),
        ));
    }
    let n = s[0];
    let grid = VolumeBox::from_matrix(world_from_volume.as_slice()?).map_err(CoreError)?;
    let g = gamma.as_slice()?;
    let p = points3(&points_m, "points_m")?;
    let out: Vec<f32> = py.detach(|| p.iter().map(|&q| sample(g, n, &grid, q)).collect());
    crate::alloc::from_slice::<f32, Ix1>(py, &[out.len()], &out)
}

/// Checks a sun direction (towards the sun): finite and non-zero; returns it normalised.
#[pyfunction]
pub fn check_sun_direction(sun_direction: [f64; 3]) -> PyResult<[f64; 3]> {
    Ok(sun_direction_of(sun_direction)
        .map_err(CoreError)?
        .to_array())
}

/// A cloud made ready for frames under one sky (`skyfall_core::cloud::frame::CloudField`):
/// its attenuation volumes for the sun (when there is one) and for the zenith, built once
/// and shared by every frame that draws it.
#[pyclass(frozen, module = "skyfall._core")]
pub struct CloudField {
    pub(crate) field: std::sync::Arc<skyfall_core::cloud::frame::CloudField>,
}

#[pymethods]
impl CloudField {
    /// Builds the field of a cloud's arrays under a sun towards `sun_direction` (None: no sun)
    /// at `resolution`³ voxels, the GIL released.
    #[new]
    #[pyo3(signature = (positions_m, radii_m, optical_depths, albedos, asymmetry_g, sun_direction, resolution, *, diffuse=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        positions_m: PyReadonlyArray2<'_, f64>,
        radii_m: PyReadonlyArray1<'_, f64>,
        optical_depths: PyReadonlyArray1<'_, f64>,
        albedos: PyReadonlyArray1<'_, f64>,
        asymmetry_g: f64,
        sun_direction: Option<[f64; 3]>,
        resolution: usize,
        diffuse: bool,
    ) -> PyResult<Self> {
        let cloud = cloud_of(
            &positions_m,
            &radii_m,
            &optical_depths,
            &albedos,
            asymmetry_g,
        )?;
        let mut field = py
            .detach(|| {
                skyfall_core::cloud::frame::CloudField::new(cloud, sun_direction, resolution)
            })
            .map_err(CoreError)?;
        field.diffuse = diffuse;
        Ok(CloudField {
            field: std::sync::Arc::new(field),
        })
    }

    /// Number of particles.
    #[getter]
    fn n_particles(&self) -> usize {
        self.field.cloud.len()
    }

    /// Whether the field has a sun.
    #[getter]
    fn has_sun(&self) -> bool {
        self.field.sun.is_some()
    }

    /// The clouds' share of the sun's light Γ at world points `points_m` (N, 3): 1 without a
    /// sun.
    fn sun_share<'py>(
        &self,
        py: Python<'py>,
        points_m: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let out: Vec<f32> = points3(&points_m, "points_m")?
            .iter()
            .map(|&q| self.field.sun.as_ref().map_or(1.0, |(_, v)| v.sample(q)))
            .collect();
        crate::alloc::from_slice::<f32, Ix1>(py, &[out.len()], &out)
    }
}

/// Three per-direction arrays.
type Three<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// The Monte Carlo reference (`skyfall_core::cloud::reference::path_trace`): (radiance of
/// every order, single scattering alone, one standard error) per direction, relative units.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn cloud_path_traced<'py>(
    py: Python<'py>,
    positions_m: PyReadonlyArray2<'py, f64>,
    radii_m: PyReadonlyArray1<'py, f64>,
    optical_depths: PyReadonlyArray1<'py, f64>,
    albedos: PyReadonlyArray1<'py, f64>,
    asymmetry_g: f64,
    sun_direction: [f64; 3],
    sun_relative: f64,
    eye_m: [f64; 3],
    directions: PyReadonlyArray2<'py, f64>,
    paths: usize,
    max_orders: usize,
    seed: u64,
) -> PyResult<Three<'py>> {
    let cloud = cloud_of(
        &positions_m,
        &radii_m,
        &optical_depths,
        &albedos,
        asymmetry_g,
    )?;
    let dirs = points3(&directions, "directions")?;
    if !(sun_relative.is_finite() && sun_relative >= 0.0) {
        return Err(invalid(
            "sun_relative",
            None,
            format!("= {sun_relative} must be finite and at least 0"),
        ));
    }
    if let Some(i) = dirs.iter().position(|d| d.length() < 1e-12) {
        return Err(invalid("directions", Some(i), "must be non-zero"));
    }
    let eye = glam::DVec3::from_array(eye_m);
    let r = py
        .detach(|| {
            skyfall_core::cloud::reference::path_trace(
                &cloud,
                sun_direction,
                sun_relative,
                eye,
                &dirs,
                paths,
                max_orders,
                seed,
            )
        })
        .map_err(CoreError)?;
    let n = dirs.len();
    Ok((
        crate::alloc::from_slice::<f64, Ix1>(py, &[n], &r.radiance)?,
        crate::alloc::from_slice::<f64, Ix1>(py, &[n], &r.single)?,
        crate::alloc::from_slice::<f64, Ix1>(py, &[n], &r.std_err)?,
    ))
}

/// A dome's transmittance (N,) and light (N, 3) along N directions.
type Sampled<'py> = (Bound<'py, PyArray1<f32>>, Bound<'py, PyArray2<f32>>);

/// The clouds of a `CloudField` over a point, seen along every direction above its horizon
/// (`skyfall_core::cloud::dome::CloudDome`): what they hide of the sky and the light they send
/// down, which an ambient-light map built with it (`SkyModel.ambient_map(..., dome=)`) takes.
#[pyclass(frozen, module = "skyfall._core")]
pub struct CloudDome {
    pub(crate) dome: std::sync::Arc<skyfall_core::cloud::dome::CloudDome>,
    /// The sky it was built under.
    sky: skyfall_core::sky::Sky,
}

#[pymethods]
impl CloudDome {
    /// The clouds of `field` under `sky` (its sun at `sun_relative`, the sun's normal
    /// illuminance over E; 0 without a sun) seen from `eye_m` on faces `face_px` wide, the GIL
    /// released.
    #[new]
    /// (`face_px`'s default is the core's `FACE_PX`, checked below; the signature needs a literal.)
    #[pyo3(signature = (field, sky, eye_m, sun_relative, face_px=32))]
    fn new(
        py: Python<'_>,
        field: &CloudField,
        sky: &crate::sky::SkyModel,
        eye_m: [f64; 3],
        sun_relative: f64,
        face_px: u32,
    ) -> PyResult<Self> {
        for (i, v) in eye_m.iter().enumerate() {
            skyfall_core::ranges::POSITION_M
                .range
                .check("eye_m", Some(i), *v)
                .map_err(CoreError)?;
        }
        skyfall_core::error::Range::closed(0.0, 1e6, "")
            .check("sun_relative", None, sun_relative)
            .map_err(CoreError)?;
        let f = std::sync::Arc::clone(&field.field);
        let light = skyfall_core::cloud::frame::CloudLight::under(&sky.sky, sun_relative as f32);
        let dome = py
            .detach(|| {
                skyfall_core::cloud::dome::CloudDome::build(
                    &f,
                    light,
                    glam::DVec3::from_array(eye_m),
                    face_px,
                )
            })
            .map_err(CoreError)?;
        Ok(CloudDome {
            dome: std::sync::Arc::new(dome),
            sky: sky.sky,
        })
    }

    /// The sky with these clouds in it along unit directions `dirs` (N, 3): the linear RGB
    /// reaching the ground, relative to E/π (what the ambient-light map integrates; the sky's
    /// own `rgb_relative(received=True)` where no cloud is).
    fn sky_rgb<'py>(
        &self,
        py: Python<'py>,
        dirs: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let d = points3(&dirs, "dirs")?;
        let n = d.len();
        let mut out = Vec::with_capacity(3 * n);
        for q in d {
            let v = q.as_vec3().normalize_or_zero();
            let (t, s) = self.dome.sample(v);
            let rgb = if v.y > 0.0 {
                skyfall_core::cloud::dome::clouded_rgb(&self.sky, v, t, s)
            } else {
                glam::Vec3::ZERO
            };
            out.extend_from_slice(&rgb.to_array());
        }
        crate::alloc::from_slice::<f32, Ix2>(py, &[n, 3], &out)
    }

    /// The clouds' transmittance (N,) and light (N, 3) along unit directions `dirs` (N, 3).
    fn sample<'py>(
        &self,
        py: Python<'py>,
        dirs: PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Sampled<'py>> {
        let d = points3(&dirs, "dirs")?;
        let mut t = Vec::with_capacity(d.len());
        let mut s = Vec::with_capacity(3 * d.len());
        for q in d {
            let (a, b) = self.dome.sample(q.as_vec3().normalize_or_zero());
            t.push(a);
            s.extend_from_slice(&b.to_array());
        }
        Ok((
            crate::alloc::from_slice::<f32, Ix1>(py, &[t.len()], &t)?,
            crate::alloc::from_slice::<f32, Ix2>(py, &[t.len(), 3], &s)?,
        ))
    }
}

const _: () = assert!(skyfall_core::cloud::dome::FACE_PX == 32);
