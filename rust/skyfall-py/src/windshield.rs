//! The windshield: its simulation (`Windshield`), the metaball height map, the normals and the
//! refraction, GIL released for the work.

use crate::alloc::from_slice;
use crate::errors::{CoreError, invalid};
use numpy::ndarray::{Ix1, Ix2, Ix3};
use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use skyfall_core::ranges;
use skyfall_core::windshield::clock;
use skyfall_core::windshield::furmidge::Wetting;
use skyfall_core::windshield::render::{self, RefractMode, Refraction};
use skyfall_core::windshield::sim::{MeshDrop, ParticleDrop};
use skyfall_core::windshield::stage::Glass;
use skyfall_core::windshield::steady;
use skyfall_core::windshield::{Windshield as Sim, WindshieldConfig, WindshieldState};
use std::sync::Mutex;

/// (positions or centres (N, 2), radii (N,)).
type Balls<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<f64>>);
/// (rgb (H, W, 3), coverage (H, W)).
type Refracted<'py> = (Bound<'py, PyArray3<f32>>, Bound<'py, PyArray2<f32>>);

/// Columns of a saved mesh drop: x, y, mass, budget, trail, age, sub-metaball angle.
const DROP_COLUMNS: usize = 7;

fn state_from_dict(d: &Bound<'_, PyDict>) -> PyResult<WindshieldState> {
    let get = |k: &'static str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(k)?
            .ok_or_else(|| invalid("state", None, format!("has no {k:?}")))
    };
    let drops: PyReadonlyArray2<'_, f64> = get("drops")?.extract()?;
    let particles: PyReadonlyArray2<'_, f64> = get("particles")?.extract()?;
    let dv = drops.as_array();
    let pv = particles.as_array();
    if dv.ncols() != DROP_COLUMNS || pv.ncols() != 3 {
        return Err(invalid(
            "state",
            None,
            format!(
                "drops must be (N, {DROP_COLUMNS}) and particles (M, 3), got {:?} and {:?}",
                dv.shape(),
                pv.shape()
            ),
        ));
    }
    Ok(WindshieldState {
        t_s: get("t_s")?.extract()?,
        steps: get("steps")?.extract()?,
        drops: dv
            .rows()
            .into_iter()
            .map(|r| MeshDrop {
                x_mm: r[0],
                y_mm: r[1],
                mass_kg: r[2],
                budget_mm: r[3],
                trail: r[4] != 0.0,
                age_s: r[5],
                sub_angle_rad: r[6],
            })
            .collect(),
        particles: pv
            .rows()
            .into_iter()
            .map(|r| ParticleDrop {
                x_mm: r[0],
                y_mm: r[1],
                mass_kg: r[2],
            })
            .collect(),
        arrived_kg: get("arrived_kg")?.extract()?,
        swept_off_kg: get("swept_off_kg")?.extract()?,
        evaporated_kg: get("evaporated_kg")?.extract()?,
    })
}

/// A simulated windshield (the Python class `skyfall.windshield.Windshield` wraps it).
#[pyclass(module = "skyfall._core", frozen)]
pub struct Windshield {
    sim: Mutex<Sim>,
}

impl Windshield {
    fn wrap(sim: Sim) -> Self {
        Windshield {
            sim: Mutex::new(sim),
        }
    }

    /// The glass as a frame draws it now.
    pub fn glass(&self) -> PyResult<Glass> {
        self.with(|s| Glass::of(s))
    }

    fn with<T>(&self, f: impl FnOnce(&mut Sim) -> T) -> PyResult<T> {
        let mut g = self.sim.lock().map_err(|_| {
            crate::errors::SkyfallError::new_err("the windshield's lock is poisoned")
        })?;
        Ok(f(&mut g))
    }
}

#[pymethods]
impl Windshield {
    #[new]
    #[pyo3(signature = (*, glass_width_mm, glass_height_mm, glass_tilt_deg, car_speed_m_s, rain_rate_mm_h, wipers, wiper_period_s, wiper_angles_deg, advancing_deg, receding_deg, cell_mm, particle_radius_mm, seed, state=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        glass_width_mm: f64,
        glass_height_mm: f64,
        glass_tilt_deg: f64,
        car_speed_m_s: f64,
        rain_rate_mm_h: f64,
        wipers: i64,
        wiper_period_s: f64,
        wiper_angles_deg: (f64, f64),
        advancing_deg: f64,
        receding_deg: f64,
        cell_mm: f64,
        particle_radius_mm: f64,
        seed: u64,
        state: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        ranges::WIPERS.check(wipers as f64).map_err(CoreError)?;
        // the grid's size is checked before anything is built from it
        ranges::GLASS_WIDTH_MM
            .check(glass_width_mm)
            .map_err(CoreError)?;
        ranges::GLASS_HEIGHT_MM
            .check(glass_height_mm)
            .map_err(CoreError)?;
        let mut c = WindshieldConfig::car(glass_width_mm, glass_height_mm, wipers as usize);
        c.tilt_deg = glass_tilt_deg;
        c.car_speed_m_s = car_speed_m_s;
        c.rain_rate_mm_h = rain_rate_mm_h;
        c.wiper_period_s = wiper_period_s;
        c.wiper_angles_deg = [wiper_angles_deg.0, wiper_angles_deg.1];
        c.advancing_deg = advancing_deg;
        c.receding_deg = receding_deg;
        c.cell_mm = cell_mm;
        c.particle_radius_mm = particle_radius_mm;
        c.seed = seed;
        let st = match state {
            Some(d) => state_from_dict(d)?,
            None => WindshieldState::default(),
        };
        let sim = Sim::from_state(c, st).map_err(CoreError)?;
        Ok(Windshield {
            sim: Mutex::new(sim),
        })
    }

    /// Advances by `dt_s`, GIL released.
    fn step(&self, py: Python<'_>, dt_s: f64) -> PyResult<()> {
        let mut g = self.sim.lock().map_err(|_| {
            crate::errors::SkyfallError::new_err("the windshield's lock is poisoned")
        })?;
        let sim: &mut Sim = &mut g;
        py.detach(|| sim.step(dt_s)).map_err(CoreError)?;
        Ok(())
    }

    /// A new windshield of this one's configuration in the steady state the table describes
    /// (`skyfall_core::windshield::steady`), at `t_s`, GIL released; with (drops left out, their
    /// water kg, drops placed).
    #[pyo3(signature = (*, cell_mm, block, mass_edges_kg, counts, mass_weights, t_s))]
    #[allow(clippy::too_many_arguments)]
    fn drawn_steady(
        &self,
        py: Python<'_>,
        cell_mm: f64,
        block: usize,
        mass_edges_kg: PyReadonlyArray1<'_, f64>,
        counts: PyReadonlyArray3<'_, f64>,
        mass_weights: PyReadonlyArray1<'_, f64>,
        t_s: f64,
    ) -> PyResult<(Self, (usize, f64, usize))> {
        let shape = counts.shape();
        if shape[0] != steady::KINDS {
            return Err(invalid(
                "counts",
                None,
                format!("must be ({}, ny, nx), got {shape:?}", steady::KINDS),
            ));
        }
        let table = steady::SteadyTable {
            cell_mm,
            nx: shape[2],
            ny: shape[1],
            block,
            mass_edges_kg: mass_edges_kg.as_array().iter().copied().collect(),
            counts: counts.as_array().iter().copied().collect(),
            mass_weights: mass_weights.as_array().iter().copied().collect(),
        };
        let config = self.with(|s| s.config().clone())?;
        let (sim, r) = py
            .detach(|| Sim::drawn_steady(config, &table, t_s))
            .map_err(CoreError)?;
        Ok((Windshield::wrap(sim), (r.left_out, r.left_out_kg, r.placed)))
    }

    /// (positions (N, 2) mm, base radii (N,) mm, kinds (N,) uint8: 0 mesh, 1 trail, 2 particle).
    #[allow(clippy::type_complexity)]
    fn drops<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<u8>>,
    )> {
        let d = self.with(|s| s.drops())?;
        let xy: Vec<f64> = d.iter().flat_map(|t| [t.0, t.1]).collect();
        let r: Vec<f64> = d.iter().map(|t| t.2).collect();
        let k: Vec<u8> = d.iter().map(|t| t.3 as u8).collect();
        Ok((
            from_slice::<f64, Ix2>(py, &[d.len(), 2], &xy)?,
            from_slice::<f64, Ix1>(py, &[d.len()], &r)?,
            from_slice::<u8, Ix1>(py, &[d.len()], &k)?,
        ))
    }

    /// (centres (N, 2) mm, radii (N,) mm) of every metaball, sub-metaballs included.
    fn metaballs<'py>(&self, py: Python<'py>) -> PyResult<Balls<'py>> {
        let m = self.with(|s| s.metaballs())?;
        let xy: Vec<f64> = m.iter().flat_map(|b| [b.x_mm, b.y_mm]).collect();
        let r: Vec<f64> = m.iter().map(|b| b.radius_mm).collect();
        Ok((
            from_slice::<f64, Ix2>(py, &[m.len(), 2], &xy)?,
            from_slice::<f64, Ix1>(py, &[m.len()], &r)?,
        ))
    }

    /// The blades now: a list of (pivot (x, y) mm, angle rad, length mm, width mm).
    #[allow(clippy::type_complexity)]
    fn blades(&self) -> PyResult<Vec<((f64, f64), f64, f64, f64)>> {
        self.with(|s| {
            let a = s.wiper_angle_rad();
            s.config()
                .wipers
                .iter()
                .map(|w| ((w.pivot_mm[0], w.pivot_mm[1]), a, w.length_mm, w.width_mm))
                .collect()
        })
    }

    /// Water balance, kg: (on the glass, arrived, swept off or run off, evaporated).
    fn water_kg(&self) -> PyResult<(f64, f64, f64, f64)> {
        self.with(|s| {
            let st = s.state();
            (
                s.on_glass_kg(),
                st.arrived_kg,
                st.swept_off_kg,
                st.evaporated_kg,
            )
        })
    }

    /// Simulated time, s.
    #[getter]
    fn t_s(&self) -> PyResult<f64> {
        self.with(|s| s.state().t_s)
    }

    /// Expected arrival, kg/s, on the whole glass.
    fn arrival_kg_per_s(&self) -> PyResult<f64> {
        self.with(|s| s.config().arrival_kg_per_s())
    }

    /// The state as a dict of arrays and numbers (resume with `state=`).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let st = self.with(|s| s.state().clone())?;
        let d = PyDict::new(py);
        d.set_item("t_s", st.t_s)?;
        d.set_item("steps", st.steps)?;
        let drops: Vec<f64> = st
            .drops
            .iter()
            .flat_map(|m| {
                [
                    m.x_mm,
                    m.y_mm,
                    m.mass_kg,
                    m.budget_mm,
                    f64::from(u8::from(m.trail)),
                    m.age_s,
                    m.sub_angle_rad,
                ]
            })
            .collect();
        d.set_item(
            "drops",
            from_slice::<f64, Ix2>(py, &[st.drops.len(), DROP_COLUMNS], &drops)?,
        )?;
        let ps: Vec<f64> = st
            .particles
            .iter()
            .flat_map(|p| [p.x_mm, p.y_mm, p.mass_kg])
            .collect();
        d.set_item(
            "particles",
            from_slice::<f64, Ix2>(py, &[st.particles.len(), 3], &ps)?,
        )?;
        d.set_item("arrived_kg", st.arrived_kg)?;
        d.set_item("swept_off_kg", st.swept_off_kg)?;
        d.set_item("evaporated_kg", st.evaporated_kg)?;
        Ok(d)
    }
}

/// Furmidge's critical base radius (m) and volume (m³) on glass tilted `glass_tilt_deg`.
#[pyfunction]
pub fn furmidge_critical(
    advancing_deg: f64,
    receding_deg: f64,
    glass_tilt_deg: f64,
) -> PyResult<(f64, f64)> {
    ranges::ADVANCING_DEG
        .check(advancing_deg)
        .map_err(CoreError)?;
    ranges::RECEDING_DEG
        .check(receding_deg)
        .map_err(CoreError)?;
    ranges::GLASS_TILT_DEG
        .check(glass_tilt_deg)
        .map_err(CoreError)?;
    let w = Wetting::from_deg(advancing_deg, receding_deg);
    let a = w.critical_base_radius_m(glass_tilt_deg.to_radians());
    Ok((a, w.volume_m3(a)))
}

/// The metaballs' summed (compressed) field, (height, width) float32.
#[pyfunction]
#[pyo3(signature = (centers_px, radii_px, width, height, compress))]
pub fn metaball_height_map<'py>(
    py: Python<'py>,
    centers_px: PyReadonlyArray2<'py, f32>,
    radii_px: PyReadonlyArray1<'py, f32>,
    width: usize,
    height: usize,
    compress: bool,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let c = centers_px.as_array();
    if c.ncols() != 2 {
        return Err(invalid(
            "centers_px",
            None,
            format!("must have shape (N, 2), got {:?}", c.shape()),
        ));
    }
    let centres: Vec<[f32; 2]> = c.rows().into_iter().map(|r| [r[0], r[1]]).collect();
    let radii = radii_px.as_array().to_vec();
    let field = py
        .detach(|| render::height_map(&centres, &radii, width, height, compress))
        .map_err(CoreError)?;
    from_slice::<f32, Ix2>(py, &[height, width], &field)
}

/// The field's unit normals, (height, width, 3) float32.
#[pyfunction]
pub fn metaball_normals<'py>(
    py: Python<'py>,
    height_map: PyReadonlyArray2<'py, f32>,
    slope_px: f32,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (h, w) = (height_map.shape()[0], height_map.shape()[1]);
    let f = height_map.as_slice()?;
    let n = py
        .detach(|| render::normals(f, w, h, slope_px))
        .map_err(CoreError)?;
    from_slice::<f32, Ix3>(py, &[h, w, 3], &n)
}

/// `frame` (H, W, 3) float32 seen through the drops of `height_map`: (rgb, coverage).
#[pyfunction]
#[pyo3(signature = (frame, height_map, *, refraction, focal_px, principal_px, index, slope_px, lookup_px, blur_px))]
#[allow(clippy::too_many_arguments)]
pub fn refract_through_drops<'py>(
    py: Python<'py>,
    frame: PyReadonlyArray3<'py, f32>,
    height_map: PyReadonlyArray2<'py, f32>,
    refraction: &str,
    focal_px: f64,
    principal_px: (f64, f64),
    index: f64,
    slope_px: f64,
    lookup_px: usize,
    blur_px: f64,
) -> PyResult<Refracted<'py>> {
    let shape = frame.shape().to_vec();
    if shape[2] != 3 || height_map.shape() != [shape[0], shape[1]] {
        return Err(invalid(
            "height_map",
            None,
            format!(
                "must be (H, W) for a frame (H, W, 3); got {:?} and {:?}",
                height_map.shape(),
                shape
            ),
        ));
    }
    let (h, w) = (shape[0], shape[1]);
    let r = Refraction {
        mode: RefractMode::parse(refraction).map_err(CoreError)?,
        focal_px,
        principal_px: [principal_px.0, principal_px.1],
        index,
        slope_px,
        lookup_px,
        blur_px,
    };
    let src = frame.as_slice()?;
    let field = height_map.as_slice()?;
    let rgb = crate::alloc::zeros::<f32, Ix3>(py, &[h, w, 3])?;
    let mask = crate::alloc::zeros::<f32, Ix2>(py, &[h, w])?;
    {
        let mut ro = rgb
            .try_readwrite()
            .map_err(|_| crate::errors::in_use("out rgb"))?;
        let mut mo = mask
            .try_readwrite()
            .map_err(|_| crate::errors::in_use("out mask"))?;
        let (ro, mo) = (ro.as_slice_mut()?, mo.as_slice_mut()?);
        py.detach(|| render::refract_frame(src, w, h, field, &r, ro, mo))
            .map_err(CoreError)?;
    }
    Ok((rgb, mask))
}

/// The GPU pass on `device`: (field (H, W), rgb (H, W, 3), coverage (H, W)) of the metaballs
/// over `frame`, in focus (`blur_px` is the CPU's).
#[pyfunction]
#[pyo3(signature = (device, centers_px, radii_px, frame, *, compress, refraction, focal_px, principal_px, index, slope_px, lookup_px))]
#[allow(clippy::too_many_arguments)]
pub fn windshield_gpu<'py>(
    py: Python<'py>,
    device: Bound<'py, crate::render::GpuDevice>,
    centers_px: PyReadonlyArray2<'py, f32>,
    radii_px: PyReadonlyArray1<'py, f32>,
    frame: PyReadonlyArray3<'py, f32>,
    compress: bool,
    refraction: &str,
    focal_px: f64,
    principal_px: (f64, f64),
    index: f64,
    slope_px: f64,
    lookup_px: usize,
) -> PyResult<(Bound<'py, PyArray2<f32>>, Refracted<'py>)> {
    let c = centers_px.as_array();
    let shape = frame.shape().to_vec();
    if c.ncols() != 2 || shape[2] != 3 {
        return Err(invalid(
            "centers_px",
            None,
            format!(
                "centers_px must be (N, 2) and frame (H, W, 3), got {:?} and {:?}",
                c.shape(),
                shape
            ),
        ));
    }
    let centres: Vec<[f32; 2]> = c.rows().into_iter().map(|r| [r[0], r[1]]).collect();
    let radii = radii_px.as_array().to_vec();
    let (h, w) = (shape[0], shape[1]);
    let r = Refraction {
        mode: RefractMode::parse(refraction).map_err(CoreError)?,
        focal_px,
        principal_px: [principal_px.0, principal_px.1],
        index,
        slope_px,
        lookup_px,
        blur_px: 0.0,
    };
    let src = frame.as_slice()?;
    let gpu = &device.get().inner;
    let out = py
        .detach(|| {
            let pass = skyfall_gpu::windshield::WindshieldPass::new(&gpu.ctx)?;
            pass.draw(&gpu.ctx, &centres, &radii, w, h, compress, src, &r)
        })
        .map_err(crate::errors::gpu_error)?;
    Ok((
        from_slice::<f32, Ix2>(py, &[h, w], &out.field)?,
        (
            from_slice::<f32, Ix3>(py, &[h, w, 3], &out.rgb)?,
            from_slice::<f32, Ix2>(py, &[h, w], &out.mask)?,
        ),
    ))
}

/// A warmed-up windshield on a frame's clock (`skyfall_core::windshield::clock`): the glass at
/// any frame time, the same bits whatever frames came before.
#[pyclass(module = "skyfall._core", frozen)]
pub struct GlassClock {
    clock: Mutex<clock::GlassClock>,
}

impl GlassClock {
    /// The glass at frame time `t_s`, GIL released.
    pub fn glass_at(&self, py: Python<'_>, t_s: f64) -> PyResult<Glass> {
        self.sim_at(py, t_s).map(|s| Glass::of(&s))
    }

    fn sim_at(&self, py: Python<'_>, t_s: f64) -> PyResult<Sim> {
        let mut g = self.clock.lock().map_err(|_| {
            crate::errors::SkyfallError::new_err("the windshield clock's lock is poisoned")
        })?;
        let c: &mut clock::GlassClock = &mut g;
        Ok(py.detach(|| c.at(t_s)).map_err(CoreError)?)
    }
}

#[pymethods]
impl GlassClock {
    /// The clock of `warm` (a copy of its state now, a whole number of `period_s` into the
    /// rain), whose frames repeat every `epoch_periods` periods.
    #[new]
    #[pyo3(signature = (warm, period_s, epoch_periods))]
    fn new(warm: &Windshield, period_s: f64, epoch_periods: usize) -> PyResult<Self> {
        let sim = warm.with(|s| s.clone())?;
        let c = clock::GlassClock::new(sim, period_s, epoch_periods).map_err(CoreError)?;
        Ok(GlassClock {
            clock: Mutex::new(c),
        })
    }

    /// The windshield at frame time `t_s` (a new one), GIL released.
    fn at(&self, py: Python<'_>, t_s: f64) -> PyResult<Windshield> {
        self.sim_at(py, t_s).map(Windshield::wrap)
    }

    /// The epoch, s: frames this far apart show the same glass.
    #[getter]
    fn epoch_s(&self) -> PyResult<f64> {
        let g = self.clock.lock().map_err(|_| {
            crate::errors::SkyfallError::new_err("the windshield clock's lock is poisoned")
        })?;
        Ok(g.epoch_s())
    }
}
