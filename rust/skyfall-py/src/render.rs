//! Frame rendering: the CPU backend as a function, the GPU backend as a device object. Both
//! take one typed request per frame ([`RequestArgs`]: the Python objects of the frame), from
//! which the core derives everything else ([`FrameSetup`]).

use crate::errors::{CoreError, gpu_error, in_use, invalid};
use crate::request::{ParsedRequest, RequestArgs};
use numpy::ndarray::{Ix2, Ix3};
use numpy::{PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use skyfall_core::frame::encoded::draw_srgb8;
use skyfall_core::frame::float::draw;
use skyfall_core::frame::layers::{Layer, Layers};
use skyfall_core::frame::request::FrameSetup;
use skyfall_core::frame::srgb8::{Photo8, Photo8Out, render_photo8 as render_photo8_core};
use skyfall_core::frame::{FrameOut, RainReport, check_frame_size};
use skyfall_core::rain::streaks::RainStats;
use skyfall_core::snow::streaks::SnowStats;
use skyfall_core::stage::Output;
use skyfall_gpu::AdapterChoice;
use skyfall_gpu::frame::GpuRenderer;

type F2<'py> = Bound<'py, PyArray2<f32>>;
/// (rgb (H, W, 3), depth_m (H, W), the drawn layers by name, the passes' counters by name).
type FrameTuple<'py> = (
    Bound<'py, PyArray3<f32>>,
    F2<'py>,
    Bound<'py, PyDict>,
    Bound<'py, PyDict>,
);

/// The passes' counters by name: drops generated, streaks drawn, drops culled; flakes
/// generated and their streaks drawn.
fn stats<'py>(
    py: Python<'py>,
    report: Option<RainReport>,
    snow: Option<SnowStats>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if let Some((RainStats { streaks, culled }, drops)) = report {
        d.set_item("rain_drops", drops)?;
        d.set_item("rain_streaks", streaks)?;
        d.set_item("rain_culled", culled)?;
    }
    if let Some(SnowStats { flakes, streaks }) = snow {
        d.set_item("snow_flakes", flakes)?;
        d.set_item("snow_streaks", streaks)?;
    }
    Ok(d)
}

/// A previous frame's arrays to render into (`out=`): `rgb`, `depth_m` and layers by name
/// ([`Layer::name`]), each optional; the frame's own arrays where one is missing.
#[derive(FromPyObject, Default)]
pub struct OutArrays<'py>(std::collections::HashMap<String, Option<Bound<'py, PyAny>>>);

impl<'py> OutArrays<'py> {
    fn take<T: numpy::Element, D: numpy::ndarray::Dimension>(
        &mut self,
        name: &str,
    ) -> PyResult<Option<Bound<'py, numpy::PyArray<T, D>>>> {
        match self.0.remove(name).flatten() {
            Some(a) => Ok(Some(a.cast_into::<numpy::PyArray<T, D>>()?)),
            None => Ok(None),
        }
    }
}

/// Renders the frame of `request` on `device` (the GPU backend), or on the CPU backend when
/// it is None, into `out`'s arrays where given. With `cpu_fallback` (`backend="auto"`), a frame
/// with a stage the core's plan declares the GPU does not draw is drawn on the CPU instead
/// (without it, the GPU refuses it by name).
#[pyfunction]
#[pyo3(signature = (request, *, device=None, cpu_fallback=false, out=None))]
pub fn render_frame<'py>(
    py: Python<'py>,
    request: RequestArgs<'py>,
    device: Option<Bound<'py, GpuDevice>>,
    cpu_fallback: bool,
    out: Option<OutArrays<'py>>,
) -> PyResult<FrameTuple<'py>> {
    let parsed: ParsedRequest<'py> = request.parse(true)?;
    let req = parsed.request()?;
    let setup = FrameSetup::new(&req).map_err(CoreError)?;
    let (cam, effects) = (&req.camera, setup.effects());
    let frame = effects.frame(req.scene_ref(), cam, parsed.glass());
    let device = device.filter(|_| !(cpu_fallback && frame.plan().check(Output::Gpu).is_err()));
    // Into numpy's arrays (see `FrameOut`): the caller's (`out`) where given, else new ones,
    // sized once the frame is known to fit.
    check_frame_size(cam).map_err(CoreError)?;
    let (h, w) = (cam.height as usize, cam.width as usize);
    let plane = || crate::alloc::zeros::<f32, Ix2>(py, &[h, w]);
    let mut out = out.unwrap_or_default();
    let rgb = match out.take::<f32, Ix3>("rgb")? {
        Some(a) => a,
        None => crate::alloc::zeros::<f32, Ix3>(py, &[h, w, 3])?,
    };
    let depth = out.take::<f32, Ix2>("depth_m")?.map_or_else(plane, Ok)?;
    // The layers this frame draws, in the order they are declared.
    let mut layers: Vec<(Layer, F2<'py>)> = Vec::new();
    for layer in frame.layers().iter() {
        layers.push((
            layer,
            out.take::<f32, Ix2>(layer.name())?.map_or_else(plane, Ok)?,
        ));
    }
    let (report, snow_report) = {
        fn busy(name: &'static str) -> impl Fn(numpy::BorrowError) -> PyErr {
            move |_| in_use(&format!("out {name}"))
        }
        let mut rgb_w = rgb.try_readwrite().map_err(busy("rgb"))?;
        let mut depth_w = depth.try_readwrite().map_err(busy("depth_m"))?;
        let mut layers_w = layers
            .iter()
            .map(|(l, a)| a.try_readwrite().map_err(busy(l.name())).map(|w| (*l, w)))
            .collect::<PyResult<Vec<_>>>()?;
        let slices = layers_w
            .iter_mut()
            .map(|(l, w)| w.as_slice_mut().map(|s| (*l, s)))
            .collect::<Result<Vec<_>, _>>()?;
        let out = FrameOut::from_layers(rgb_w.as_slice_mut()?, depth_w.as_slice_mut()?, slices);
        match device.as_ref().map(|d| &d.get().inner) {
            Some(gpu) => py.detach(|| gpu.draw(&frame, out)).map_err(gpu_error)?,
            None => py.detach(|| draw(&frame, out)).map_err(CoreError)?,
        }
    };
    let named = PyDict::new(py);
    for (l, a) in layers {
        named.set_item(l.name(), a)?;
    }
    Ok((rgb, depth, named, stats(py, report, snow_report)?))
}

/// A stage as `frame_plan` returns it: its name, whether the fused 8-bit output draws it,
/// whether the GPU does, and its layers' names.
type DeclaredStage = (&'static str, bool, bool, Vec<&'static str>);

/// The stages the frame of `request` draws, as the core declares them
/// (`skyfall_core::frame::stages::Frame::plan`), in drawing order: each stage's name, whether
/// the fused 8-bit output draws it, whether the GPU backend does, and the names of its layers.
/// Outputs decide what they can draw from this list alone (`Renderer.srgb8_path`).
#[pyfunction]
#[pyo3(signature = (request))]
pub fn frame_plan<'py>(request: RequestArgs<'py>) -> PyResult<Vec<DeclaredStage>> {
    let parsed: ParsedRequest<'py> = request.parse(true)?;
    let req = parsed.request()?;
    let setup = FrameSetup::new(&req).map_err(CoreError)?;
    let effects = setup.effects();
    let frame = effects.frame(req.scene_ref(), &req.camera, parsed.glass());
    Ok(frame
        .plan()
        .0
        .iter()
        .map(|d| {
            (
                d.name(),
                d.srgb8,
                d.gpu,
                d.layers.iter().map(Layer::name).collect(),
            )
        })
        .collect())
}

/// Renders the frame of `request` as 8-bit sRGB into `out_srgb8` on the CPU, any frame (the
/// stages band by band, each band encoded as it is finished: the float frame's bytes, see
/// `skyfall_core::frame::encoded`), filling the arrays of `layers` (name to (H, W) float32)
/// with the frame's layers (their neutral value where no stage draws one). Returns the passes'
/// counters.
#[pyfunction]
#[pyo3(signature = (request, out_srgb8, *, layers=None))]
pub fn render_frame8<'py>(
    py: Python<'py>,
    request: RequestArgs<'py>,
    out_srgb8: Bound<'py, PyArray3<u8>>,
    layers: Option<OutArrays<'py>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut out_w = out_srgb8.try_readwrite().map_err(|_| in_use("out"))?;
    let mut given = layers.unwrap_or_default();
    let mut arrays: Vec<(Layer, F2<'py>)> = Vec::new();
    for layer in Layer::ALL {
        if let Some(a) = given.take::<f32, Ix2>(layer.name())? {
            arrays.push((layer, a));
        }
    }
    if let Some(name) = given.0.keys().next() {
        return Err(invalid(
            "layers",
            None,
            format!(
                "names no layer {name:?}; the layers are {:?}",
                Layer::ALL.map(Layer::name)
            ),
        ));
    }
    let mut writers = arrays
        .iter()
        .map(|(l, a)| {
            a.try_readwrite()
                .map_err(|_| in_use(l.name()))
                .map(|w| (*l, w))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let mut slices: Layers<&mut [f32]> = Layers::default();
    for (l, w) in writers.iter_mut() {
        slices.set(*l, w.as_slice_mut()?);
    }
    let parsed: ParsedRequest<'py> = request.parse(true)?;
    let req = parsed.request()?;
    let setup = FrameSetup::new(&req).map_err(CoreError)?;
    let effects = setup.effects();
    let frame = effects.frame(req.scene_ref(), &req.camera, parsed.glass());
    let out = out_w.as_slice_mut()?;
    let (report, snow_report) = py
        .detach(|| draw_srgb8(&frame, out, slices))
        .map_err(CoreError)?;
    stats(py, report, snow_report)
}

/// Renders the frame of `request` over its 8-bit sRGB photo `photo_srgb8` into `out_srgb8` on
/// the CPU, fused (see `skyfall_core::frame::srgb8`); fills `rain_alpha_out` and
/// `snow_alpha_out` when given. A frame with a stage the fused output does not draw (the
/// core's plan decides) is drawn by the banded 8-bit output instead, in the same call.
/// Returns the passes' counters.
#[pyfunction]
#[pyo3(signature = (request, photo_srgb8, decode_table, out_srgb8, *, rain_alpha_out=None, snow_alpha_out=None))]
#[allow(clippy::too_many_arguments)]
pub fn render_photo8<'py>(
    py: Python<'py>,
    request: Bound<'py, PyAny>,
    photo_srgb8: Bound<'py, PyArray3<u8>>,
    decode_table: PyReadonlyArray1<'py, f32>,
    out_srgb8: Bound<'py, PyArray3<u8>>,
    rain_alpha_out: Option<F2<'py>>,
    snow_alpha_out: Option<F2<'py>>,
) -> PyResult<Bound<'py, PyDict>> {
    // Borrowed here rather than at the call's conversion, so an array another render (on
    // another thread) holds is refused as a `ValueError` naming it, not pyo3's TypeError.
    let photo_srgb8 = photo_srgb8
        .try_readonly()
        .map_err(|_| in_use("the photo (scene.srgb8)"))?;
    let args: RequestArgs<'py> = request.extract()?;
    let parsed: ParsedRequest<'py> = args.parse(false)?;
    let req = parsed.request()?;
    let setup = FrameSetup::new(&req).map_err(CoreError)?;
    // Which stages the fused 8-bit output draws is the stages' own declaration. A stage it does
    // not draw (wet surfaces, clouds, a snow cover, a windshield): the banded 8-bit output
    // draws the frame, in this one call, the same bytes as `render_frame8`.
    let effects = setup.effects();
    let (rain, snow) = (&effects.rain, &effects.snow);
    let frame = effects.frame(req.scene_ref(), &req.camera, parsed.glass());
    if frame.plan().check(Output::Srgb8).is_err() {
        let layers = PyDict::new(py);
        layers.set_item("rain_alpha", rain_alpha_out)?;
        layers.set_item("snow_alpha", snow_alpha_out)?;
        return render_frame8(py, request.extract()?, out_srgb8, Some(layers.extract()?));
    }
    let mut out_srgb8 = out_srgb8.try_readwrite().map_err(|_| in_use("out"))?;
    let rain_alpha_out = rain_alpha_out
        .map(|a| a.try_readwrite().map_err(|_| in_use("rain_alpha_out")))
        .transpose()?;
    let snow_alpha_out = snow_alpha_out
        .map(|a| a.try_readwrite().map_err(|_| in_use("snow_alpha_out")))
        .transpose()?;
    let decode: &[f32; 256] = decode_table.as_slice()?.try_into().map_err(|_| {
        invalid(
            "decode_table",
            None,
            format!("must have 256 entries, got {}", decode_table.len()),
        )
    })?;
    let depth_m = match req.scene_ref() {
        skyfall_core::frame::SceneRef::Photo { depth_m, .. } => depth_m,
        skyfall_core::frame::SceneRef::Boxes(_) => {
            return Err(invalid(
                "scene",
                None,
                "the 8-bit output stage draws photos only",
            ));
        }
    };
    let photo = Photo8 {
        srgb: photo_srgb8.as_slice()?,
        depth_m,
        decode,
    };
    let (mut alpha, mut snow_alpha) = (rain_alpha_out, snow_alpha_out);
    let out = Photo8Out {
        srgb: out_srgb8.as_slice_mut()?,
        rain_alpha: alpha.as_mut().map(|a| a.as_slice_mut()).transpose()?,
        snow_alpha: snow_alpha.as_mut().map(|a| a.as_slice_mut()).transpose()?,
    };
    let (cam, haze) = (&req.camera, setup.haze.as_ref());
    let report = py
        .detach(|| render_photo8_core(cam, &photo, haze, rain.as_ref(), snow.as_ref(), out))
        .map_err(CoreError)?;
    let raining = rain.is_some();
    stats(
        py,
        report.filter(|_| raining).map(|s| (s.rain, s.drops)),
        report.and_then(|s| s.snow),
    )
}

/// A wgpu device with every pass compiled, reused across frames.
#[pyclass(frozen, module = "skyfall._core")]
pub struct GpuDevice {
    pub(crate) inner: GpuRenderer,
}

#[pymethods]
impl GpuDevice {
    /// Opens the GPU; `require_hardware` refuses software adapters (lavapipe).
    #[new]
    #[pyo3(signature = (*, require_hardware))]
    fn new(py: Python<'_>, require_hardware: bool) -> PyResult<Self> {
        let choice = if require_hardware {
            AdapterChoice::HardwareOnly
        } else {
            AdapterChoice::Any
        };
        let inner = py.detach(|| GpuRenderer::new(choice)).map_err(gpu_error)?;
        Ok(GpuDevice { inner })
    }

    /// Adapter name, backend, device type and driver.
    #[getter]
    fn adapter_info(&self) -> (String, String, String, String) {
        let a = &self.inner.ctx.adapter;
        (
            a.name.clone(),
            a.backend.clone(),
            a.device_type.clone(),
            a.driver.clone(),
        )
    }
}
