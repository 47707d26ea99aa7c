//! Frame rendering: the CPU backend as a function, the GPU backend as a device object.

use crate::errors::{gpu_error, CoreError};
use glam::{Mat3, Vec3};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use skyfall_core::frame::{render, FrameBuffers, SceneRef};
use skyfall_core::haze::Haze;
use skyfall_core::scene::boxes::{BoxScene, SceneBox};
use skyfall_core::scene::camera::Camera;
use skyfall_gpu::frame::GpuRenderer;
use skyfall_gpu::AdapterChoice;

/// (rgb (H, W, 3), depth_m (H, W), transmittance (H, W) or None).
type FrameTuple<'py> = (Bound<'py, PyArray3<f32>>, Bound<'py, PyArray2<f32>>, Option<Bound<'py, PyArray2<f32>>>);

/// Camera from (width, height, [fx, fy, cx, cy, px, py, pz, r00, r01, …, r22]) with the
/// world_from_camera rotation row-major.
pub(crate) fn camera(width: u32, height: u32, p: [f32; 16]) -> Result<Camera, CoreError> {
    let rot = Mat3::from_cols_array(&[p[7], p[10], p[13], p[8], p[11], p[14], p[9], p[12], p[15]]);
    Ok(Camera::new(width, height, [p[0], p[1], p[2], p[3]], Vec3::new(p[4], p[5], p[6]), rot)?)
}

/// Box scene from an (N, 9) array: min xyz, max xyz, albedo rgb per row.
fn box_scene(boxes: &PyReadonlyArray2<'_, f32>, ground: bool, ground_albedo: [f32; 3]) -> PyResult<BoxScene> {
    let a = boxes.as_array();
    if a.ncols() != 9 {
        return Err(PyValueError::new_err(format!("boxes must have shape (N, 9), got {:?}", a.shape())));
    }
    let rows = a
        .rows()
        .into_iter()
        .map(|r| SceneBox { min_m: Vec3::new(r[0], r[1], r[2]), max_m: Vec3::new(r[3], r[4], r[5]), albedo: Vec3::new(r[6], r[7], r[8]) })
        .collect();
    Ok(BoxScene::new(rows, ground, Vec3::from(ground_albedo)).map_err(CoreError)?)
}

fn haze(h: Option<(f32, [f32; 3])>) -> Result<Option<Haze>, CoreError> {
    Ok(h.map(|(sigma, air)| Haze::new(sigma, air)).transpose()?)
}

fn to_py<'py>(py: Python<'py>, cam: &Camera, f: FrameBuffers) -> PyResult<FrameTuple<'py>> {
    let (h, w) = (cam.height as usize, cam.width as usize);
    let err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let rgb = Array3::from_shape_vec((h, w, 3), f.rgb).map_err(err)?.into_pyarray(py);
    let depth = Array2::from_shape_vec((h, w), f.depth_m).map_err(err)?.into_pyarray(py);
    let t = f.transmittance.map(|t| Array2::from_shape_vec((h, w), t).map(|a| a.into_pyarray(py))).transpose().map_err(err)?;
    Ok((rgb, depth, t))
}

/// Scene arguments as received from Python.
struct SceneArgs<'a, 'py> {
    boxes: Option<&'a PyReadonlyArray2<'py, f32>>,
    ground: bool,
    ground_albedo: [f32; 3],
    photo_rgb: Option<&'a PyReadonlyArray3<'py, f32>>,
    photo_depth_m: Option<&'a PyReadonlyArray2<'py, f32>>,
}

/// Either an owned box scene or the photo's slices.
enum Scene<'a> {
    Boxes(BoxScene),
    Photo(&'a [f32], &'a [f32]),
}

impl<'a> Scene<'a> {
    fn parse(args: &'a SceneArgs<'a, '_>) -> PyResult<Self> {
        match (args.boxes, args.photo_rgb, args.photo_depth_m) {
            (Some(b), None, None) => Ok(Scene::Boxes(box_scene(b, args.ground, args.ground_albedo)?)),
            (None, Some(rgb), Some(depth)) => Ok(Scene::Photo(rgb.as_slice()?, depth.as_slice()?)),
            _ => Err(PyValueError::new_err("give either boxes, or photo_rgb and photo_depth_m")),
        }
    }

    fn as_ref(&self) -> SceneRef<'_> {
        match self {
            Scene::Boxes(b) => SceneRef::Boxes(b),
            Scene::Photo(rgb, depth_m) => SceneRef::Photo { rgb, depth_m },
        }
    }
}

/// Renders a frame on the CPU backend.
#[pyfunction]
#[pyo3(signature = (width, height, camera_params, *, boxes=None, ground=true, ground_albedo=[0.0; 3], photo_rgb=None, photo_depth_m=None, haze_params=None))]
#[allow(clippy::too_many_arguments)]
pub fn render_cpu<'py>(
    py: Python<'py>,
    width: u32,
    height: u32,
    camera_params: [f32; 16],
    boxes: Option<PyReadonlyArray2<'py, f32>>,
    ground: bool,
    ground_albedo: [f32; 3],
    photo_rgb: Option<PyReadonlyArray3<'py, f32>>,
    photo_depth_m: Option<PyReadonlyArray2<'py, f32>>,
    haze_params: Option<(f32, [f32; 3])>,
) -> PyResult<FrameTuple<'py>> {
    let cam = camera(width, height, camera_params)?;
    let args = SceneArgs { boxes: boxes.as_ref(), ground, ground_albedo, photo_rgb: photo_rgb.as_ref(), photo_depth_m: photo_depth_m.as_ref() };
    let scene = Scene::parse(&args)?;
    let h = haze(haze_params)?;
    let frame = py.detach(|| render(scene.as_ref(), &cam, h.as_ref())).map_err(CoreError)?;
    to_py(py, &cam, frame)
}

/// A wgpu device with every pass compiled, reused across frames.
#[pyclass(frozen, module = "skyfall._core")]
pub struct GpuDevice {
    inner: GpuRenderer,
}

#[pymethods]
impl GpuDevice {
    /// Opens the GPU; `require_hardware` refuses software adapters (lavapipe).
    #[new]
    #[pyo3(signature = (*, require_hardware))]
    fn new(py: Python<'_>, require_hardware: bool) -> PyResult<Self> {
        let choice = if require_hardware { AdapterChoice::HardwareOnly } else { AdapterChoice::Any };
        let inner = py.detach(|| GpuRenderer::new(choice)).map_err(gpu_error)?;
        Ok(GpuDevice { inner })
    }

    /// Adapter name, backend, device type and driver.
    #[getter]
    fn adapter_info(&self) -> (String, String, String, String) {
        let a = &self.inner.ctx.adapter;
        (a.name.clone(), a.backend.clone(), a.device_type.clone(), a.driver.clone())
    }

    /// Renders a frame on this device (same arguments as `render_cpu`).
    #[pyo3(signature = (width, height, camera_params, *, boxes=None, ground=true, ground_albedo=[0.0; 3], photo_rgb=None, photo_depth_m=None, haze_params=None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        width: u32,
        height: u32,
        camera_params: [f32; 16],
        boxes: Option<PyReadonlyArray2<'py, f32>>,
        ground: bool,
        ground_albedo: [f32; 3],
        photo_rgb: Option<PyReadonlyArray3<'py, f32>>,
        photo_depth_m: Option<PyReadonlyArray2<'py, f32>>,
        haze_params: Option<(f32, [f32; 3])>,
    ) -> PyResult<FrameTuple<'py>> {
        let cam = camera(width, height, camera_params)?;
        let args = SceneArgs { boxes: boxes.as_ref(), ground, ground_albedo, photo_rgb: photo_rgb.as_ref(), photo_depth_m: photo_depth_m.as_ref() };
        let scene = Scene::parse(&args)?;
        let h = haze(haze_params)?;
        let frame = py.detach(|| self.inner.render(scene.as_ref(), &cam, h.as_ref())).map_err(gpu_error)?;
        to_py(py, &cam, frame)
    }
}
