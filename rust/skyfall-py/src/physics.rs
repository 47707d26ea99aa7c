//! Wrappers of `skyfall_core::physics`: numpy in, numpy out, GIL released.

use crate::errors::CoreError;
use numpy::ndarray::Ix1;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use skyfall_core::error::{at, broadcast_len};
use skyfall_core::physics::air::{Air, TEMPERATURE_C, air_viscosity_pa_s};
use skyfall_core::physics::fall_speed::{AirArrays, FallSpeedModel, terminal_velocity_many};
use skyfall_core::physics::{dsd, extinction};

type Arr<'py> = PyReadonlyArray1<'py, f64>;
type Out<'py> = PyResult<Bound<'py, PyArray1<f64>>>;

fn done<'py>(py: Python<'py>, r: Result<Vec<f64>, skyfall_core::Error>) -> Out<'py> {
    let v = r.map_err(CoreError)?;
    crate::alloc::from_slice::<f64, Ix1>(py, &[v.len()], &v)
}

/// Moist-air density, kg/m³ (arrays of length 1 or n).
#[pyfunction]
pub fn air_density_kg_m3<'py>(
    py: Python<'py>,
    temperature_c: Arr<'py>,
    pressure_hpa: Arr<'py>,
    relative_humidity: Arr<'py>,
) -> Out<'py> {
    let (t, p, rh) = (
        temperature_c.as_slice()?,
        pressure_hpa.as_slice()?,
        relative_humidity.as_slice()?,
    );
    let r = py.detach(|| {
        let n = broadcast_len(&[
            ("temperature_c", t.len()),
            ("pressure_hpa", p.len()),
            ("relative_humidity", rh.len()),
        ])?;
        (0..n)
            .map(|i| {
                let idx = (n > 1).then_some(i);
                Ok(Air::checked(at(t, i), at(p, i), at(rh, i), idx)?.density_kg_m3())
            })
            .collect()
    });
    done(py, r)
}

/// Dynamic viscosity of air, Pa·s.
#[pyfunction]
pub fn air_viscosity<'py>(py: Python<'py>, temperature_c: Arr<'py>) -> Out<'py> {
    let t = temperature_c.as_slice()?;
    let r = py.detach(|| {
        TEMPERATURE_C.check_all("temperature_c", t)?;
        Ok(t.iter().map(|&x| air_viscosity_pa_s(x)).collect())
    });
    done(py, r)
}

/// Terminal velocity, m/s.
#[pyfunction]
pub fn terminal_velocity_m_s<'py>(
    py: Python<'py>,
    diameter_mm: Arr<'py>,
    model: &str,
    temperature_c: Arr<'py>,
    pressure_hpa: Arr<'py>,
    relative_humidity: Arr<'py>,
) -> Out<'py> {
    let model = FallSpeedModel::parse(model).map_err(CoreError)?;
    let d = diameter_mm.as_slice()?;
    let air = AirArrays {
        temperature_c: temperature_c.as_slice()?,
        pressure_hpa: pressure_hpa.as_slice()?,
        relative_humidity: relative_humidity.as_slice()?,
    };
    let r = py.detach(|| terminal_velocity_many(d, model, air));
    done(py, r)
}

/// Marshall–Palmer N(D), m⁻³ mm⁻¹.
#[pyfunction]
pub fn marshall_palmer<'py>(
    py: Python<'py>,
    diameter_mm: Arr<'py>,
    rain_rate_mm_h: Arr<'py>,
) -> Out<'py> {
    let (d, r) = (diameter_mm.as_slice()?, rain_rate_mm_h.as_slice()?);
    let res = py.detach(|| dsd::marshall_palmer_many(d, r));
    done(py, res)
}

/// Drops per m³ in a diameter interval.
#[pyfunction]
pub fn drops_per_m3<'py>(
    py: Python<'py>,
    rain_rate_mm_h: Arr<'py>,
    d_min_mm: Arr<'py>,
    d_max_mm: Arr<'py>,
) -> Out<'py> {
    let (r, lo, hi) = (
        rain_rate_mm_h.as_slice()?,
        d_min_mm.as_slice()?,
        d_max_mm.as_slice()?,
    );
    let res = py.detach(|| dsd::drops_per_m3_many(r, lo, hi));
    done(py, res)
}

/// Rain rate carried by the distribution, mm/h.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn rain_rate_from_dsd<'py>(
    py: Python<'py>,
    rain_rate_mm_h: Arr<'py>,
    model: &str,
    temperature_c: Arr<'py>,
    pressure_hpa: Arr<'py>,
    relative_humidity: Arr<'py>,
    d_min_mm: Arr<'py>,
    d_max_mm: Arr<'py>,
) -> Out<'py> {
    let model = FallSpeedModel::parse(model).map_err(CoreError)?;
    let r = rain_rate_mm_h.as_slice()?;
    let air = AirArrays {
        temperature_c: temperature_c.as_slice()?,
        pressure_hpa: pressure_hpa.as_slice()?,
        relative_humidity: relative_humidity.as_slice()?,
    };
    let (lo, hi) = (d_min_mm.as_slice()?, d_max_mm.as_slice()?);
    let res = py.detach(|| dsd::rain_rate_from_dsd_many(r, model, air, lo, hi));
    done(py, res)
}

/// Rain extinction coefficient, 1/m.
#[pyfunction]
pub fn rain_extinction_per_m<'py>(py: Python<'py>, rain_rate_mm_h: Arr<'py>) -> Out<'py> {
    let r = rain_rate_mm_h.as_slice()?;
    let res = py.detach(|| extinction::rain_extinction_many(r));
    done(py, res)
}
