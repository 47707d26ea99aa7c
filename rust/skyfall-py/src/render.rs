//! Frame rendering: the CPU backend as a function, the GPU backend as a device object. Both
//! take the same arguments, parsed once into a [`Request`].

use crate::errors::{CoreError, gpu_error, in_use, invalid};
use crate::sky::{AmbientLightMap, SkyModel};
use glam::{DVec3, Mat3, Vec3};
use numpy::ndarray::{Ix2, Ix3};
use numpy::{
    PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyReadwriteArray2, PyReadwriteArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use skyfall_core::frame::scene::SceneLight;
use skyfall_core::frame::srgb8::{Photo8, Photo8Out, render_photo8 as render_photo8_core};
use skyfall_core::frame::{FrameOut, SceneRef, check_frame_size, render_into};
use skyfall_core::haze::Haze;
use skyfall_core::rain::drops::{RainMethod, RainRegion};
use skyfall_core::rain::streaks::{RainFrame, RainShading};
use skyfall_core::ranges;
use skyfall_core::scene::boxes::{BoxScene, SceneBox};
use skyfall_core::scene::camera::Camera;
use skyfall_core::scene::lights::Light;
use skyfall_core::sky::Sky;
use skyfall_core::sky::ambient::AmbientMap;
use skyfall_core::sky::cie::SkyKind;
use skyfall_core::sky::illuminance::{SkyTable, irradiance};
use skyfall_gpu::AdapterChoice;
use skyfall_gpu::frame::GpuRenderer;
use std::sync::Arc;

type F2<'py> = Bound<'py, PyArray2<f32>>;
/// (rain_alpha, rain_depth_m, drops generated, streaks drawn, drops culled).
type RainTuple<'py> = (F2<'py>, F2<'py>, usize, usize, usize);
/// (rgb (H, W, 3), depth_m (H, W), transmittance or None, rain or None).
type FrameTuple<'py> = (
    Bound<'py, PyArray3<f32>>,
    F2<'py>,
    Option<F2<'py>>,
    Option<RainTuple<'py>>,
);
/// (rain_rate_mm_h, diameters_mm, near_m, wind_m_s, time_s, seed, method).
pub(crate) type RegionArgs<'py> = (
    f64,
    PyReadonlyArray1<'py, f64>,
    f64,
    [f64; 3],
    f64,
    u64,
    String,
);

/// Camera from (width, height, [fx, fy, cx, cy, px, py, pz, r00, r01, …, r22]) with the
/// world_from_camera rotation row-major. The position stays f64 (the core draws particles
/// relative to it); the rest is f32.
pub(crate) fn camera(width: u32, height: u32, p: [f64; 16]) -> Result<Camera, CoreError> {
    let f = |i: usize| p[i] as f32;
    let rot = Mat3::from_cols_array(&[f(7), f(10), f(13), f(8), f(11), f(14), f(9), f(12), f(15)]);
    Ok(Camera::new(
        width,
        height,
        [f(0), f(1), f(2), f(3)],
        DVec3::new(p[4], p[5], p[6]),
        rot,
    )?)
}

/// A rain region from Python's argument tuple.
pub(crate) fn region(args: &RegionArgs<'_>) -> PyResult<RainRegion> {
    let (rate, diams, near, wind, time, seed, method) = args;
    let mut region =
        RainRegion::new(*rate, diams.as_slice()?, *near, *wind, *time, *seed).map_err(CoreError)?;
    region.method = RainMethod::parse(method).map_err(CoreError)?;
    Ok(region)
}

/// Box scene from an (N, 9) array: min xyz, max xyz, albedo rgb per row.
pub(crate) fn box_scene(
    boxes: &PyReadonlyArray2<'_, f32>,
    ground: bool,
    ground_albedo: [f32; 3],
) -> PyResult<BoxScene> {
    let a = boxes.as_array();
    if a.ncols() != 9 {
        return Err(invalid(
            "boxes",
            None,
            format!("must have shape (N, 9), got {:?}", a.shape()),
        ));
    }
    let rows = a
        .rows()
        .into_iter()
        .map(|r| SceneBox {
            min_m: Vec3::new(r[0], r[1], r[2]),
            max_m: Vec3::new(r[3], r[4], r[5]),
            albedo: Vec3::new(r[6], r[7], r[8]),
        })
        .collect();
    Ok(BoxScene::new(rows, ground, Vec3::from(ground_albedo)).map_err(CoreError)?)
}

/// Every input of a frame, validated.
struct Request<'a> {
    cam: Camera,
    boxes: Option<BoxScene>,
    photo: Option<(&'a [f32], &'a [f32])>,
    haze: Option<Haze>,
    rain: Option<(RainRegion, f32, Vec3, bool, RainShading)>,
    shelter: Vec<SceneBox>,
}

/// The rain arguments: one dict from Python with every key (None where a type allows it).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct RainArgs<'py> {
    region: RegionArgs<'py>,
    exposure_s: f64,
    camera_velocity_m_s: [f64; 3],
    ground: bool,
    lights: Option<PyReadonlyArray2<'py, f32>>,
    sky_illuminance_lux: f64,
    cull_threshold: Option<f64>,
    /// Boxes that shelter the rain besides a box scene's own (a photo's occluders), and
    /// whether boxes shelter it at all.
    occluders: Option<PyReadonlyArray2<'py, f32>>,
    shelter: bool,
}

impl<'a> Request<'a> {
    #[allow(clippy::too_many_arguments)]
    fn parse<'py>(
        width: u32,
        height: u32,
        camera_params: [f64; 16],
        boxes: Option<&PyReadonlyArray2<'py, f32>>,
        ground: bool,
        ground_albedo: [f32; 3],
        photo: Option<(
            &'a PyReadonlyArray3<'py, f32>,
            &'a PyReadonlyArray2<'py, f32>,
        )>,
        haze_params: Option<(f32, [f32; 3])>,
        rain: Option<&RainArgs<'py>>,
        ambient: &Arc<AmbientMap>,
    ) -> PyResult<Self> {
        let cam = camera(width, height, camera_params)?;
        let (boxes, photo) = match (boxes, photo) {
            (Some(b), None) => (Some(box_scene(b, ground, ground_albedo)?), None),
            (None, Some((rgb, depth))) => (None, Some((rgb.as_slice()?, depth.as_slice()?))),
            (None, None) => (None, None),
            _ => {
                return Err(invalid(
                    "boxes",
                    None,
                    "give either boxes, or photo_rgb and photo_depth_m",
                ));
            }
        };
        let haze = haze_params
            .map(|(sigma, air)| Haze::new(sigma, air))
            .transpose()
            .map_err(CoreError)?;
        let (shelter_wanted, occluders) = (
            rain.is_some_and(|r| r.shelter),
            rain.and_then(|r| r.occluders.as_ref()),
        );
        let rain = match rain {
            None => None,
            Some(rain) => {
                // Checked in f64, before the f32 the passes use rounds a value into range.
                ranges::EXPOSURE_S
                    .check(rain.exposure_s)
                    .map_err(CoreError)?;
                ranges::SKY_ILLUMINANCE_LUX
                    .check(rain.sky_illuminance_lux)
                    .map_err(CoreError)?;
                if let Some(t) = rain.cull_threshold {
                    ranges::CULL_THRESHOLD.check(t).map_err(CoreError)?;
                }
                let v = DVec3::from(rain.camera_velocity_m_s);
                ranges::VELOCITY_M_S.check(v.length()).map_err(CoreError)?;
                let lights = match &rain.lights {
                    None => Vec::new(),
                    Some(a) => a
                        .as_array()
                        .rows()
                        .into_iter()
                        .enumerate()
                        .map(|(i, row)| Light::from_row(&row.to_vec(), i))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(CoreError)?,
                };
                let shading = RainShading {
                    lights,
                    sky_illuminance_lux: rain.sky_illuminance_lux as f32,
                    cull_threshold: rain.cull_threshold.map(|t| t as f32),
                    ambient: Some(Arc::clone(ambient)),
                    ..RainShading::open_sky()
                };
                Some((
                    region(&rain.region)?,
                    rain.exposure_s as f32,
                    v.as_vec3(),
                    rain.ground,
                    shading,
                ))
            }
        };
        let mut shelter = Vec::new();
        if shelter_wanted {
            if let Some(b) = &boxes {
                shelter.extend_from_slice(&b.boxes);
            }
            if let Some(o) = occluders {
                shelter.extend_from_slice(&box_scene(o, false, [0.0; 3])?.boxes);
            }
        }
        Ok(Request {
            cam,
            boxes,
            photo,
            haze,
            rain,
            shelter,
        })
    }

    fn scene(&self) -> SceneRef<'_> {
        match (&self.boxes, self.photo) {
            (Some(b), _) => SceneRef::Boxes(b),
            (None, Some((rgb, depth_m))) => SceneRef::Photo { rgb, depth_m },
            (None, None) => SceneRef::Photo {
                rgb: &[],
                depth_m: &[],
            },
        }
    }

    fn rain_frame(&self) -> Option<RainFrame<'_>> {
        self.rain.as_ref().map(
            |(region, exposure_s, camera_velocity_m_s, ground, shading)| RainFrame {
                region,
                exposure_s: *exposure_s,
                camera_velocity_m_s: *camera_velocity_m_s,
                ground: *ground,
                shelter: &self.shelter,
                shading,
            },
        )
    }
}

/// A previous frame's arrays to render into (`out=`), each optional: the frame's own arrays
/// where one is missing or its layer is not drawn this time.
#[derive(FromPyObject, Default)]
#[pyo3(from_item_all)]
pub struct OutArrays<'py> {
    rgb: Option<Bound<'py, PyArray3<f32>>>,
    depth_m: Option<F2<'py>>,
    transmittance: Option<F2<'py>>,
    rain_alpha: Option<F2<'py>>,
    rain_depth_m: Option<F2<'py>>,
}

/// Renders a frame on `device` (the GPU backend), or on the CPU backend when it is None.
#[pyfunction]
#[pyo3(signature = (
    width, height, camera_params, *, device=None, boxes=None, ground=true, ground_albedo=[0.0; 3], photo_rgb=None,
    photo_depth_m=None, haze_params=None, rain=None, sky=None, ambient=None, out=None
))]
#[allow(clippy::too_many_arguments)]
pub fn render_frame<'py>(
    py: Python<'py>,
    width: u32,
    height: u32,
    camera_params: [f64; 16],
    device: Option<Bound<'py, GpuDevice>>,
    boxes: Option<PyReadonlyArray2<'py, f32>>,
    ground: bool,
    ground_albedo: [f32; 3],
    photo_rgb: Option<PyReadonlyArray3<'py, f32>>,
    photo_depth_m: Option<PyReadonlyArray2<'py, f32>>,
    haze_params: Option<(f32, [f32; 3])>,
    rain: Option<RainArgs<'py>>,
    sky: Option<Bound<'py, SkyModel>>,
    ambient: Option<Bound<'py, AmbientLightMap>>,
    out: Option<OutArrays<'py>>,
) -> PyResult<FrameTuple<'py>> {
    let lit = Lighting::new(sky.as_ref(), ambient.as_ref())?;
    let light = SceneLight {
        sky: &lit.sky,
        ambient: &lit.ambient,
    };
    if boxes.is_none() && (photo_rgb.is_none() || photo_depth_m.is_none()) {
        return Err(invalid(
            "boxes",
            None,
            "give either boxes, or photo_rgb and photo_depth_m",
        ));
    }
    let photo = photo_rgb.as_ref().zip(photo_depth_m.as_ref());
    let req = Request::parse(
        width,
        height,
        camera_params,
        boxes.as_ref(),
        ground,
        ground_albedo,
        photo,
        haze_params,
        rain.as_ref(),
        &lit.ambient,
    )?;
    let (scene, cam, haze, rain) = (req.scene(), &req.cam, req.haze.as_ref(), req.rain_frame());
    // Into numpy's arrays (see `FrameOut`): the caller's (`out`) where given, else new ones,
    // sized once the frame is known to fit.
    check_frame_size(cam).map_err(CoreError)?;
    let (h, w) = (cam.height as usize, cam.width as usize);
    let plane = || crate::alloc::zeros::<f32, Ix2>(py, &[h, w]);
    let out = out.unwrap_or_default();
    let rgb = match out.rgb {
        Some(a) => a,
        None => crate::alloc::zeros::<f32, Ix3>(py, &[h, w, 3])?,
    };
    let depth = out.depth_m.map_or_else(plane, Ok)?;
    let trans = match haze {
        Some(_) => Some(out.transmittance.map_or_else(plane, Ok)?),
        None => None,
    };
    let layers = match rain {
        Some(_) => Some((
            out.rain_alpha.map_or_else(plane, Ok)?,
            out.rain_depth_m.map_or_else(plane, Ok)?,
        )),
        None => None,
    };
    let report = {
        // A given array may also be an input (a photo rendered over itself): name it.
        fn busy(name: &'static str) -> impl Fn(numpy::BorrowError) -> PyErr {
            move |_| in_use(name)
        }
        let (mut rgb_w, mut depth_w) = (
            rgb.try_readwrite().map_err(busy("rgb"))?,
            depth.try_readwrite().map_err(busy("depth_m"))?,
        );
        let mut trans_w = trans
            .as_ref()
            .map(|t| t.try_readwrite().map_err(busy("transmittance")))
            .transpose()?;
        let mut layers_w = match layers.as_ref() {
            Some((a, d)) => Some((
                a.try_readwrite().map_err(busy("rain_alpha"))?,
                d.try_readwrite().map_err(busy("rain_depth_m"))?,
            )),
            None => None,
        };
        let out = FrameOut {
            rgb: rgb_w.as_slice_mut()?,
            depth_m: depth_w.as_slice_mut()?,
            transmittance: trans_w.as_mut().map(|t| t.as_slice_mut()).transpose()?,
            rain: match layers_w.as_mut() {
                Some((a, d)) => Some((a.as_slice_mut()?, d.as_slice_mut()?)),
                None => None,
            },
        };
        match device.as_ref().map(|d| &d.get().inner) {
            Some(gpu) => py
                .detach(|| gpu.render_into(scene, cam, &light, haze, rain.as_ref(), out))
                .map_err(gpu_error)?,
            None => py
                .detach(|| render_into(scene, cam, &light, haze, rain.as_ref(), out))
                .map_err(CoreError)?,
        }
    };
    let rain = layers
        .zip(report)
        .map(|((a, d), (stats, drops))| (a, d, drops, stats.streaks, stats.culled));
    Ok((rgb, depth, trans, rain))
}

/// The sky and its ambient-light map for a frame: the given ones, or the overcast sky and its
/// open-sky light everywhere.
struct Lighting {
    sky: Sky,
    ambient: Arc<AmbientMap>,
}

impl Lighting {
    fn new(
        sky: Option<&Bound<'_, SkyModel>>,
        ambient: Option<&Bound<'_, AmbientLightMap>>,
    ) -> PyResult<Self> {
        let sky: Sky = match sky {
            Some(s) => s.get().sky,
            None => Sky::new(SkyKind::Overcast, 0.0, 1000.0).map_err(CoreError)?,
        };
        let ambient: Arc<AmbientMap> = match ambient {
            Some(a) => Arc::clone(&a.get().map),
            None => Arc::new(AmbientMap::uniform(irradiance(
                &[],
                &SkyTable::new(&sky, 64).map_err(CoreError)?,
                Vec3::ZERO,
            ))),
        };
        Ok(Lighting { sky, ambient })
    }
}

/// Renders haze and rain over an 8-bit sRGB photo into `out_srgb8` on the CPU, fused (see
/// `skyfall_core::photo8`); fills `rain_alpha_out` when given. Returns (drops generated,
/// streaks drawn, drops culled) when it rains.
#[pyfunction]
#[pyo3(signature = (
    width, height, camera_params, photo_srgb8, photo_depth_m, decode_table, out_srgb8, *, rain_alpha_out=None,
    haze_params=None, rain=None, sky=None, ambient=None
))]
#[allow(clippy::too_many_arguments)]
pub fn render_photo8<'py>(
    py: Python<'py>,
    width: u32,
    height: u32,
    camera_params: [f64; 16],
    photo_srgb8: PyReadonlyArray3<'py, u8>,
    photo_depth_m: PyReadonlyArray2<'py, f32>,
    decode_table: PyReadonlyArray1<'py, f32>,
    mut out_srgb8: PyReadwriteArray3<'py, u8>,
    rain_alpha_out: Option<PyReadwriteArray2<'py, f32>>,
    haze_params: Option<(f32, [f32; 3])>,
    rain: Option<RainArgs<'py>>,
    sky: Option<Bound<'py, SkyModel>>,
    ambient: Option<Bound<'py, AmbientLightMap>>,
) -> PyResult<Option<(usize, usize, usize)>> {
    let lit = Lighting::new(sky.as_ref(), ambient.as_ref())?;
    let req = Request::parse(
        width,
        height,
        camera_params,
        None,
        false,
        [0.0; 3],
        None,
        haze_params,
        rain.as_ref(),
        &lit.ambient,
    )?;
    let decode: &[f32; 256] = decode_table.as_slice()?.try_into().map_err(|_| {
        invalid(
            "decode_table",
            None,
            format!("must have 256 entries, got {}", decode_table.len()),
        )
    })?;
    let photo = Photo8 {
        srgb: photo_srgb8.as_slice()?,
        depth_m: photo_depth_m.as_slice()?,
        decode,
    };
    let mut alpha = rain_alpha_out;
    let out = Photo8Out {
        srgb: out_srgb8.as_slice_mut()?,
        rain_alpha: alpha.as_mut().map(|a| a.as_slice_mut()).transpose()?,
    };
    let (cam, haze, rain) = (&req.cam, req.haze.as_ref(), req.rain_frame());
    let stats = py
        .detach(|| render_photo8_core(cam, &photo, haze, rain.as_ref(), out))
        .map_err(CoreError)?;
    Ok(stats.map(|s| (s.drops, s.rain.streaks, s.rain.culled)))
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
