//! One typed request per frame, read from the Python objects themselves (`skyfall.Weather`,
//! `skyfall.Camera`, `BoxScene` / `PhotoScene`, the lights): attribute by attribute into the
//! core's [`FrameRequest`], with no packed tuples in between. The core derives the rest
//! ([`skyfall_core::frame::request::FrameSetup`]).

use crate::boxes::{box_rows, box_scene};
use crate::errors::{CoreError, invalid};
use crate::sky::AmbientLightMap;
use glam::{DVec3, Mat3, Vec3};
use numpy::{PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use skyfall_core::frame::request::{FrameRequest, SceneData};
use skyfall_core::rain::drops::RainMethod;
use skyfall_core::scene::boxes::{BoxScene, SceneBox};
use skyfall_core::scene::camera::{Camera, ThinLens};
use skyfall_core::scene::lights::Light;
use skyfall_core::weather::{SkySpec, SnowOpacity, Weather};
use skyfall_core::windshield::stage::Glass;
use std::sync::Arc;

/// `skyfall.Weather`'s fields.
#[derive(FromPyObject)]
pub struct WeatherSpec {
    rain_rate_mm_h: f64,
    snow_rate_mm_h: f64,
    snow_density_kg_m3: f64,
    snow_near_m: f64,
    snow_opacity: String,
    visibility_m: f64,
    sky_illuminance_lux: f64,
    wind_m_s: [f64; 3],
    rain_near_m: f64,
    #[pyo3(default)]
    rain_far_m: Option<f64>,
    rain_diameters_mm: Vec<f64>,
    rain_streaks: bool,
    rain_method: String,
    rain_sheltered: bool,
    #[pyo3(default)]
    rain_duration_s: Option<f64>,
    #[pyo3(default)]
    dry_s: f64,
    sky: SkyArg,
    sun_elevation_deg: Option<f64>,
    sun_azimuth_deg: Option<f64>,
    cloud_base_m: Option<f64>,
    #[pyo3(default)]
    sun_illuminance_lux: Option<f64>,
}

/// `Weather.sky`: `"overcast"` or a CIE general sky type.
#[derive(FromPyObject)]
enum SkyArg {
    Type(i64),
    Name(String),
}

impl WeatherSpec {
    /// The core's weather.
    pub fn core(self) -> PyResult<Weather> {
        let sky = match self.sky {
            SkyArg::Type(t) => SkySpec::from_type(t),
            SkyArg::Name(n) => SkySpec::parse(&n).map_err(CoreError)?,
        };
        let sun_deg = match (self.sun_elevation_deg, self.sun_azimuth_deg) {
            (Some(el), Some(az)) => Some((el, az)),
            (None, None) => None,
            _ => {
                return Err(invalid(
                    "sun_elevation_deg",
                    None,
                    "give both sun_elevation_deg and sun_azimuth_deg, or neither",
                ));
            }
        };
        let w = Weather {
            rain_rate_mm_h: self.rain_rate_mm_h,
            snow_rate_mm_h: self.snow_rate_mm_h,
            snow_density_kg_m3: self.snow_density_kg_m3,
            snow_near_m: self.snow_near_m,
            snow_opacity: SnowOpacity::parse(&self.snow_opacity).map_err(CoreError)?,
            visibility_m: self.visibility_m,
            sky_illuminance_lux: self.sky_illuminance_lux,
            wind_m_s: self.wind_m_s,
            rain_near_m: self.rain_near_m,
            rain_far_m: self.rain_far_m,
            rain_diameters_mm: self.rain_diameters_mm,
            rain_streaks: self.rain_streaks,
            rain_method: RainMethod::parse(&self.rain_method).map_err(CoreError)?,
            rain_sheltered: self.rain_sheltered,
            rain_duration_s: self.rain_duration_s,
            dry_s: self.dry_s,
            sky,
            sun_deg,
            cloud_base_m: self.cloud_base_m,
            sun_illuminance_lux: self.sun_illuminance_lux,
        };
        w.validate().map_err(CoreError)?;
        Ok(w)
    }
}

/// `skyfall.Camera`'s pose, exposure and motion (its intrinsics come from `intrinsics()`).
#[derive(FromPyObject)]
struct CameraAttrs<'py> {
    width: Option<u32>,
    height: Option<u32>,
    position_m: [f64; 3],
    rotation: PyReadonlyArray2<'py, f64>,
    exposure_s: f64,
    velocity_m_s: [f64; 3],
}

/// `skyfall.Camera`'s thin lens (`f_number` None: a pinhole).
#[derive(FromPyObject)]
struct LensAttrs {
    f_number: Option<f64>,
    focus_distance_m: Option<f64>,
    sensor_width_mm: f64,
}

/// A camera with its exposure (s), velocity (m/s) and lens.
pub struct CameraSpec {
    /// The core's camera.
    pub camera: Camera,
    exposure_s: f64,
    velocity_m_s: [f64; 3],
    lens: Option<ThinLens>,
}

impl<'a, 'py> FromPyObject<'a, 'py> for CameraSpec {
    type Error = PyErr;

    fn extract(ob: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let a: CameraAttrs<'py> = ob.extract()?;
        let (Some(width), Some(height)) = (a.width, a.height) else {
            return Err(invalid(
                "camera",
                None,
                "has no resolution: use with_resolution()",
            ));
        };
        let [fx, fy, cx, cy]: [f64; 4] = ob.call_method0("intrinsics")?.extract()?;
        let r = a.rotation.as_array();
        if r.shape() != [3, 3] {
            return Err(invalid(
                "rotation",
                None,
                format!("must be 3 x 3, got {:?}", r.shape()),
            ));
        }
        // world_from_camera: its columns are the camera's right, up and back axes.
        let col = |j: usize| Vec3::new(r[[0, j]] as f32, r[[1, j]] as f32, r[[2, j]] as f32);
        let rot = Mat3::from_cols(col(0), col(1), col(2));
        let camera = Camera::new(
            width,
            height,
            [fx as f32, fy as f32, cx as f32, cy as f32],
            DVec3::from(a.position_m),
            rot,
        )
        .map_err(CoreError)?;
        let l: LensAttrs = ob.extract()?;
        let lens = match l.f_number {
            Some(n) => Some(
                ThinLens::new(
                    n,
                    l.focus_distance_m.unwrap_or(f64::INFINITY),
                    l.sensor_width_mm,
                )
                .map_err(CoreError)?,
            ),
            None => None,
        };
        Ok(CameraSpec {
            camera,
            exposure_s: a.exposure_s,
            velocity_m_s: a.velocity_m_s,
            lens,
        })
    }
}

/// A point light's fields (`skyfall.PointLight`).
#[derive(FromPyObject)]
struct PointAttrs {
    position_m: [f64; 3],
    intensity_cd: f64,
    color: [f64; 3],
}

/// A spot light's fields (`skyfall.SpotLight`; `inner_cone_deg` is set on construction).
#[derive(FromPyObject)]
struct SpotAttrs {
    position_m: [f64; 3],
    direction: [f64; 3],
    intensity_cd: f64,
    cone_deg: f64,
    inner_cone_deg: f64,
    color: [f64; 3],
}

#[derive(FromPyObject)]
enum LightSpec {
    Spot(SpotAttrs),
    Point(PointAttrs),
}

impl LightSpec {
    fn core(&self, index: usize) -> PyResult<Light> {
        let f = |v: [f64; 3]| v.map(|x| x as f32);
        // The core's light row: position, colour, intensity, then the spot's axis and the
        // cosines of its outer and inner half-angles (zero axis: a point light).
        let row: Vec<f32> = match self {
            LightSpec::Point(p) => [
                &f(p.position_m)[..],
                &f(p.color),
                &[p.intensity_cd as f32, 0.0, 0.0, 0.0, -1.0, -1.0],
            ]
            .concat(),
            LightSpec::Spot(s) => [
                &f(s.position_m)[..],
                &f(s.color),
                &[s.intensity_cd as f32],
                &f(s.direction),
                &[
                    s.cone_deg.to_radians().cos() as f32,
                    s.inner_cone_deg.to_radians().cos() as f32,
                ],
            ]
            .concat(),
        };
        Ok(Light::from_row(&row, index).map_err(CoreError)?)
    }
}

/// `BoxScene`'s fields.
#[derive(FromPyObject)]
struct BoxAttrs<'py> {
    boxes: PyReadonlyArray2<'py, f32>,
    ground: bool,
    ground_albedo: [f32; 3],
    lights: Vec<LightSpec>,
}

/// `PhotoScene`'s fields (its pixels are read as each output stage needs them).
#[derive(FromPyObject)]
struct PhotoAttrs<'py> {
    depth_m: PyReadonlyArray2<'py, f32>,
    occluders: PyReadonlyArray2<'py, f32>,
    lights: Vec<LightSpec>,
    /// Linear RGB in the photo's units (estimated or given), or None for a photo in the
    /// renderer's relative units.
    airlight_linear: Option<[f32; 3]>,
}

/// The arrays a request borrows from Python (held while the frame renders).
pub enum SceneArrays<'py> {
    /// A box scene (nothing borrowed).
    Boxes(BoxScene),
    /// A photo's linear RGB (when the float stage draws it) and its depth.
    Photo {
        rgb: Option<PyReadonlyArray3<'py, f32>>,
        depth_m: PyReadonlyArray2<'py, f32>,
        occluders: Vec<SceneBox>,
        airlight: Option<[f32; 3]>,
    },
}

/// A frame request as Python hands it: a dict of the frame's objects.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct RequestArgs<'py> {
    camera: CameraSpec,
    weather: WeatherSpec,
    scene: Bound<'py, PyAny>,
    time_s: f64,
    seed: u64,
    cull_threshold: Option<f64>,
    ambient: Bound<'py, AmbientLightMap>,
    /// The snow cover drawn on the scene (`skyfall.snow.SnowCover`'s core), when given.
    #[pyo3(default)]
    snow_cover: Option<Bound<'py, crate::snow::SnowCoverGrid>>,
    /// The clouds in the sky (`skyfall.clouds`' `_core.CloudField`), when the weather has them.
    #[pyo3(default)]
    clouds: Option<Bound<'py, crate::clouds::CloudField>>,
    /// The windshield the camera looks through: a `_core.Windshield` drawn as it stands, or a
    /// `_core.GlassClock` drawn at the frame's time.
    #[pyo3(default)]
    windshield: Option<GlassArg<'py>>,
}

/// A request's windshield.
#[derive(FromPyObject)]
pub enum GlassArg<'py> {
    /// A windshield as it stands.
    Now(Bound<'py, crate::windshield::Windshield>),
    /// A warmed-up windshield on the frame's clock.
    Clock(Bound<'py, crate::windshield::GlassClock>),
}

/// A request's parts: the Python arrays it borrows, and the rest, owned.
pub struct ParsedRequest<'py> {
    /// The scene's arrays.
    pub arrays: SceneArrays<'py>,
    camera: CameraSpec,
    lights: Vec<Light>,
    weather: Weather,
    time_s: f64,
    seed: u64,
    cull_threshold: Option<f64>,
    ambient: Arc<skyfall_core::sky::ambient::AmbientMap>,
    snow_cover: Option<Arc<skyfall_core::snow::cover::SnowCover>>,
    clouds: Option<Arc<skyfall_core::cloud::frame::CloudField>>,
    glass: Option<Glass>,
}

impl<'py> RequestArgs<'py> {
    /// Reads the scene (`linear`: a photo's linear RGB is wanted, for the float stage) and the
    /// weather into the core's types.
    pub fn parse(self, linear: bool) -> PyResult<ParsedRequest<'py>> {
        let (arrays, lights) = if self.scene.hasattr("boxes")? {
            let b: BoxAttrs<'py> = self.scene.extract()?;
            (
                SceneArrays::Boxes(box_scene(&b.boxes, b.ground, b.ground_albedo)?),
                b.lights,
            )
        } else {
            let p: PhotoAttrs<'py> = self.scene.extract()?;
            let rgb = if linear {
                Some(self.scene.getattr("image")?.extract()?)
            } else {
                None
            };
            (
                SceneArrays::Photo {
                    rgb,
                    depth_m: p.depth_m,
                    occluders: box_rows(&p.occluders)?,
                    airlight: p.airlight_linear,
                },
                p.lights,
            )
        };
        let lights = lights
            .iter()
            .enumerate()
            .map(|(i, l)| l.core(i))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(ParsedRequest {
            arrays,
            camera: self.camera,
            lights,
            weather: self.weather.core()?,
            time_s: self.time_s,
            seed: self.seed,
            cull_threshold: self.cull_threshold,
            ambient: Arc::clone(&self.ambient.get().map),
            snow_cover: self.snow_cover.map(|c| Arc::clone(&c.get().cover)),
            clouds: self.clouds.map(|c| Arc::clone(&c.get().field)),
            glass: match self.windshield {
                None => None,
                Some(GlassArg::Now(w)) => Some(w.get().glass()?),
                Some(GlassArg::Clock(c)) => Some(c.get().glass_at(c.py(), self.time_s)?),
            },
        })
    }
}

impl<'py> ParsedRequest<'py> {
    /// The windshield the camera looks through, at the frame's time.
    pub fn glass(&self) -> Option<&Glass> {
        self.glass.as_ref()
    }

    /// The core's request, borrowing the scene's arrays.
    pub fn request(&self) -> PyResult<FrameRequest<'_>> {
        let scene = match &self.arrays {
            SceneArrays::Boxes(b) => SceneData::Boxes(b),
            SceneArrays::Photo {
                rgb: Some(rgb),
                depth_m,
                occluders,
                airlight,
            } => SceneData::Photo {
                rgb: rgb.as_slice()?,
                depth_m: depth_m.as_slice()?,
                occluders,
                airlight: *airlight,
            },
            SceneArrays::Photo {
                rgb: None,
                depth_m,
                occluders,
                airlight,
            } => SceneData::Photo8 {
                depth_m: depth_m.as_slice()?,
                occluders,
                airlight: *airlight,
            },
        };
        Ok(FrameRequest {
            camera: self.camera.camera,
            exposure_s: self.camera.exposure_s,
            camera_velocity_m_s: self.camera.velocity_m_s,
            lens: self.camera.lens,
            scene,
            lights: &self.lights,
            weather: &self.weather,
            time_s: self.time_s,
            seed: self.seed,
            cull_threshold: self.cull_threshold,
            ambient: Arc::clone(&self.ambient),
            snow_cover: self.snow_cover.as_deref(),
            clouds: self.clouds.as_ref(),
        })
    }
}
