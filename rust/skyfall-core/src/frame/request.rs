//! One typed request per frame: the camera, the scene, the weather and the options, as the user
//! gave them; [`FrameSetup`] derives from it everything the passes need (the sky, the haze and
//! its airlight, the rain region, the drops' shading, what shelters them), in the core, once.

use super::SceneRef;
use super::scene::{SceneLight, SunLight};
use super::stages::Frame;
use crate::cloud::frame::{CloudField, CloudLight, CloudPass, VolumeView};
use crate::error::Result;
use crate::error::{Error, Param};
use crate::haze::{Haze, clear_air_spectral};
use crate::rain::drops::RainRegion;
use crate::rain::streaks::{RainFrame, RainShading};
use crate::ranges;
use crate::scene::boxes::{BoxScene, SceneBox};
use crate::scene::camera::{Camera, Defocus, ThinLens};
use crate::scene::lights::Light;
use crate::sky::Sky;
use crate::sky::ambient::AmbientMap;
use crate::snow::SNOW_ALBEDO;
use crate::snow::cover::{SnowCover, SnowRender};
use crate::snow::flakes::SnowRegion;
use crate::snow::streaks::{SnowFrame, SnowOpacity};
use crate::weather::Weather;
use crate::windshield::stage::Glass;
use glam::Vec3;
use std::sync::Arc;

/// Rec. 709 luminance weights of linear RGB. They sum to exactly 1 in f32 (tested), so a box
/// scene's units of 1 keep a luminance of 1.
const LUMINANCE_WEIGHTS: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// What a frame shows.
#[derive(Debug, Clone)]
pub enum SceneData<'a> {
    /// The procedural box scene, ray cast.
    Boxes(&'a BoxScene),
    /// A photo (linear RGB, H·W·3) with its depth map (H·W, m, inf = sky), and the boxes in its
    /// world that hide the sky from the drops.
    Photo {
        /// Linear RGB.
        rgb: &'a [f32],
        /// Depth, m.
        depth_m: &'a [f32],
        /// Occluders.
        occluders: &'a [SceneBox],
        /// The photo's airlight, linear RGB in its own units ([`FrameSetup`] puts the rain's
        /// and the lights' radiance in them too); None: the photo is in the renderer's
        /// relative units (E/π = 1) and the sky's airlight is used.
        airlight: Option<[f32; 3]>,
    },
    /// An 8-bit photo's depth map, occluders and airlight (its bytes go to the 8-bit output
    /// stage).
    Photo8 {
        /// Depth, m.
        depth_m: &'a [f32],
        /// Occluders.
        occluders: &'a [SceneBox],
        /// As for [`SceneData::Photo`].
        airlight: Option<[f32; 3]>,
    },
}

/// Everything a frame is made of.
#[derive(Debug, Clone)]
pub struct FrameRequest<'a> {
    /// The camera, at the frame's resolution.
    pub camera: Camera,
    /// Its exposure, s.
    pub exposure_s: f64,
    /// Its velocity, m/s: streaks follow the drops' motion relative to it.
    pub camera_velocity_m_s: [f64; 3],
    /// Its thin lens, which defocuses the streaks; None: a pinhole.
    pub lens: Option<ThinLens>,
    /// What it looks at.
    pub scene: SceneData<'a>,
    /// The scene's lamps and headlights.
    pub lights: &'a [Light],
    /// The weather.
    pub weather: &'a Weather,
    /// The frame's time, s.
    pub time_s: f64,
    /// The rain's seed.
    pub seed: u64,
    /// Drops whose received light is below this are not drawn.
    pub cull_threshold: Option<f64>,
    /// The scene's ambient-light map under this weather's sky (the open sky's light everywhere
    /// where nothing hides it).
    pub ambient: Arc<AmbientMap>,
    /// The snow lying on the scene's surfaces ([`crate::snow::cover::accumulate`]); None: none.
    pub snow_cover: Option<&'a SnowCover>,
    /// The clouds in the sky, made for this weather's sun; None: none.
    pub clouds: Option<&'a Arc<CloudField>>,
}

/// The rain on a frame's surfaces: what it left (the film), the wind that slanted it, and the
/// boxes that kept it off what they cover.
#[derive(Debug, Clone)]
pub struct WetWeather {
    /// The water the rain left.
    pub film: crate::wet::film::Film,
    /// The wind, m/s.
    pub wind_m_s: [f64; 3],
    /// The boxes that keep the rain off (empty without `rain_sheltered`).
    pub shelter: Vec<SceneBox>,
}

/// What a frame's passes need, derived from its request.
#[derive(Debug, Clone)]
pub struct FrameSetup {
    /// The sky through the weather.
    pub sky: Sky,
    /// The haze, when the weather has any.
    pub haze: Option<Haze>,
    ambient: Arc<AmbientMap>,
    lights: Vec<Light>,
    sky_illuminance_lux: f32,
    rain: Option<(RainRegion, RainShading)>,
    snow: Option<(SnowRegion, RainShading, SnowOpacity)>,
    shelter: Vec<SceneBox>,
    exposure_s: f32,
    camera_velocity_m_s: Vec3,
    lens: Option<Defocus>,
    ground: bool,
    snow_cover: Option<SnowRender>,
    clouds: Option<(Arc<CloudField>, CloudLight)>,
    /// The sun on a box scene's surfaces: its direction and normal illuminance over E.
    sun: Option<(Vec3, f32)>,
    eye_m: glam::DVec3,
    wet: Option<WetWeather>,
}

impl FrameRequest<'_> {
    /// Checks the request's own values against their ranges (the weather, the exposure, the
    /// camera's speed, the time, the cull threshold; the lens checks itself when it is made).
    pub fn validate(&self) -> Result<()> {
        self.weather.validate()?;
        ranges::EXPOSURE_S.check(self.exposure_s)?;
        let v = self.camera_velocity_m_s;
        ranges::VELOCITY_M_S.check((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())?;
        ranges::TIME_S.check(self.time_s)?;
        if let Some(t) = self.cull_threshold {
            ranges::CULL_THRESHOLD.check(t)?;
        }
        Ok(())
    }

    /// The scene as the float output stage reads it.
    pub fn scene_ref(&self) -> SceneRef<'_> {
        match &self.scene {
            SceneData::Boxes(b) => SceneRef::Boxes(b),
            SceneData::Photo { rgb, depth_m, .. } => SceneRef::Photo { rgb, depth_m },
            SceneData::Photo8 { depth_m, .. } => SceneRef::Photo { rgb: &[], depth_m },
        }
    }
}

impl FrameSetup {
    /// The sky, the haze (its airlight from the ambient map at the camera), the rain region and
    /// its shading (the lights, the sky light per drop from the map, culling) and the boxes that
    /// shelter the drops, for `req` (validated here).
    ///
    /// A photo with its own airlight A_p sets the frame's units: everything the weather adds
    /// (the airlight, the drops' light from the sky and the lamps) is scaled by A_p / A, A the
    /// sky's airlight in relative units, so the horizon haze has the photo's colour and level
    /// and the rain is lit as brightly relative to it as in a rendered frame.
    pub fn new(req: &FrameRequest<'_>) -> Result<Self> {
        req.validate()?;
        let w = &req.weather;
        let mut sky = w.sky()?;
        // The light of the map's sky (with clouds in it, theirs mixed in) lights the surfaces
        // and the drops; the clouds themselves are lit by the open sky above them.
        let map_light = req.ambient.light_colour.unwrap_or(sky.light_colour);
        // Yamamoto & Tadamura: the airlight Is = ks·E_hv, the sky illuminance at the viewpoint.
        let e_view = req.ambient.sample(req.camera.eye())[0];
        let sky_airlight = sky.airlight as f32;
        let photo_airlight = match &req.scene {
            SceneData::Photo { airlight, .. } | SceneData::Photo8 { airlight, .. } => *airlight,
            SceneData::Boxes(_) => None,
        };
        let units = match photo_airlight {
            Some(a) => {
                for (i, &c) in a.iter().enumerate() {
                    ranges::AIRLIGHT.check_at(Some(i), f64::from(c))?;
                }
                Vec3::from(a) / sky_airlight
            }
            None => Vec3::ONE,
        };
        // A box scene's airlight has the horizon's colour (neutral under an overcast sky); a
        // photo's is its own.
        let tint = match photo_airlight {
            Some(_) => Vec3::ONE,
            None => sky.horizon_colour,
        };
        let airlight = (units * tint * sky_airlight * e_view).to_array();
        // The drops and flakes are lit by the sky light's colour (a photo's: its own units).
        let drops_colour = match photo_airlight {
            Some(_) => Vec3::ONE,
            None => map_light,
        };
        let haze = w.haze(airlight, req.camera.position_m.y)?;
        // Under a sky in colour a box scene's clear air scatters each channel at its own
        // wavelength (Rayleigh and aerosol): distance turns blue-grey. A photo's haze and an
        // overcast sky's stay grey.
        let haze = match haze {
            Some(h) if photo_airlight.is_none() && sky.colour.is_some() => {
                Some(h.with_spectral(clear_air_spectral(w.air_extinction_per_m()))?)
            }
            h => h,
        };
        let rain = match w.rain_region(req.time_s, req.seed)? {
            Some(region) => {
                let shading = RainShading {
                    lights: req.lights.to_vec(),
                    sky_illuminance_lux: w.sky_illuminance_lux as f32,
                    cull_threshold: req.cull_threshold.map(|t| t as f32),
                    ambient: Some(Arc::clone(&req.ambient)),
                    radiance_scale: units,
                    sky_colour: drops_colour,
                    ..RainShading::open_sky()
                };
                Some((region, shading))
            }
            None => None,
        };
        // The flakes are lit as the drops are, as opaque white scatterers (r = 1, their
        // albedo's share of the light).
        let snow = w.snow_region(req.time_s, req.seed)?.map(|region| {
            let shading = RainShading {
                reflectance: 1.0,
                drop_radiance: SNOW_ALBEDO,
                lights: req.lights.to_vec(),
                sky_illuminance_lux: w.sky_illuminance_lux as f32,
                cull_threshold: req.cull_threshold.map(|t| t as f32),
                ambient: Some(Arc::clone(&req.ambient)),
                radiance_scale: units,
                sky_colour: drops_colour,
            };
            (region, shading, w.snow_opacity)
        });
        let (ground, boxes): (bool, &[SceneBox]) = match &req.scene {
            SceneData::Boxes(b) => (b.ground, &b.boxes),
            SceneData::Photo { occluders, .. } | SceneData::Photo8 { occluders, .. } => {
                (false, occluders)
            }
        };
        // The boxes that keep the rain (and the snow) off what they cover, when it rains or
        // snows and they do.
        let shelter = if (rain.is_some() || snow.is_some()) && w.rain_sheltered {
            boxes.to_vec()
        } else {
            Vec::new()
        };
        let film = w.film();
        let wet = film.any().then(|| WetWeather {
            film,
            wind_m_s: w.wind_m_s,
            shelter: if w.rain_sheltered {
                boxes.to_vec()
            } else {
                Vec::new()
            },
        });
        let v = req.camera_velocity_m_s;
        let lens = req
            .lens
            .as_ref()
            .map(|l| l.defocus(&req.camera))
            .transpose()?;
        let snow_cover = match (req.snow_cover, &req.scene) {
            (None, _) => None,
            (Some(c), SceneData::Boxes(_)) => Some(SnowRender::boxes(c)?),
            (Some(c), SceneData::Photo { depth_m, .. } | SceneData::Photo8 { depth_m, .. }) => {
                Some(SnowRender::photo(c, &req.camera, depth_m, units)?)
            }
        };
        let sun = w.sun();
        let clouds = match req.clouds {
            Some(field) => {
                let built_for = field.sun.as_ref().map(|(d, _)| d.as_vec3());
                let wanted = sun.map(|(d, _)| d);
                let same = match (built_for, wanted) {
                    (None, None) => true,
                    (Some(a), Some(b)) => (a - b).length() < 1e-4,
                    _ => false,
                };
                if !same {
                    return Err(Error::Invalid {
                        param: Param {
                            name: "clouds",
                            index: None,
                        },
                        message: "the clouds' volumes were built for another sun than this \
                                  weather's: build them for its sun (skyfall.clouds does)"
                            .into(),
                    });
                }
                let rel = sun.map_or(0.0, |(_, r)| r as f32);
                // A photo's units carry its horizon sky's colour, which the sky's light on the
                // clouds takes; the sun's light keeps only their luminance (Rec. 709 weights):
                // sunlit clouds stay white under a blue sky. A box scene's clouds take the
                // sky's colours: the sun's (orange at sunset) and the sky light's.
                let light = match photo_airlight {
                    Some(_) => CloudLight {
                        sun: Vec3::splat(units.dot(LUMINANCE_WEIGHTS) * rel),
                        sky: units,
                    },
                    None => CloudLight::under(&sky, rel),
                };
                Some((Arc::clone(field), light))
            }
            None => None,
        };
        let sun = match req.scene {
            SceneData::Boxes(_) => sun.map(|(d, r)| (d, r as f32)),
            _ => None,
        };
        sky.light_colour = map_light;
        Ok(FrameSetup {
            wet,
            clouds,
            sun,
            eye_m: req.camera.position_m,
            snow_cover,
            sky,
            haze,
            ambient: Arc::clone(&req.ambient),
            lights: req.lights.to_vec(),
            sky_illuminance_lux: w.sky_illuminance_lux as f32,
            rain,
            snow,
            shelter,
            exposure_s: req.exposure_s as f32,
            camera_velocity_m_s: Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32),
            lens,
            ground,
        })
    }

    /// How the scene is lit: the sky, the ambient-light map, the lights, the sun and the
    /// clouds.
    pub fn light(&self) -> SceneLight<'_> {
        let clouds = self.clouds.as_ref().map(|(field, light)| CloudPass {
            field,
            light: *light,
        });
        let sun = self.sun.map(|(direction, relative)| SunLight {
            direction,
            relative,
            colour: self.sky.sun_colour,
            clouds: self
                .clouds
                .as_ref()
                .and_then(|(f, _)| f.sun.as_ref())
                .map(|(_, v)| VolumeView::new(v, self.eye_m)),
            eye: self.eye_m.as_vec3(),
        });
        SceneLight::new(&self.sky, &self.ambient)
            .with_lights(&self.lights, self.sky_illuminance_lux)
            .with_snow(self.snow_cover.as_ref())
            .with_sky_light(sun, clouds)
    }

    /// The rain on the surfaces, when it wets them.
    pub fn wet(&self) -> Option<&WetWeather> {
        self.wet.as_ref()
    }

    /// The camera's thin lens at the frame's resolution (None: a pinhole).
    pub fn defocus(&self) -> Option<Defocus> {
        self.lens
    }

    /// The rain the frame draws, when it draws streaks.
    pub fn rain(&self) -> Option<RainFrame<'_>> {
        self.rain.as_ref().map(|(region, shading)| RainFrame {
            region,
            exposure_s: self.exposure_s,
            camera_velocity_m_s: self.camera_velocity_m_s,
            lens: self.lens,
            ground: self.ground,
            shelter: &self.shelter,
            shading,
        })
    }

    /// The frame's light and effects, made once ([`Effects::frame`] builds the [`Frame`]
    /// that borrows them).
    pub fn effects(&self) -> Effects<'_> {
        Effects {
            light: self.light(),
            rain: self.rain(),
            snow: self.snow(),
            setup: self,
        }
    }

    /// The snow the frame draws, when it snows.
    pub fn snow(&self) -> Option<SnowFrame<'_>> {
        self.snow
            .as_ref()
            .map(|(region, shading, opacity)| SnowFrame {
                region,
                exposure_s: self.exposure_s,
                camera_velocity_m_s: self.camera_velocity_m_s,
                lens: self.lens,
                ground: self.ground,
                shelter: &self.shelter,
                shading,
                opacity: *opacity,
                haze: self.haze,
            })
    }
}

/// What a [`Frame`] borrows from its [`FrameSetup`]: the light, the rain and the snow (made
/// from it once), with the setup itself for the rest (the haze, the lens, the wet surfaces).
pub struct Effects<'s> {
    /// How the scene is lit.
    pub light: SceneLight<'s>,
    /// The rain, when it rains streaks.
    pub rain: Option<RainFrame<'s>>,
    /// The snowfall, when it snows.
    pub snow: Option<SnowFrame<'s>>,
    setup: &'s FrameSetup,
}

impl Effects<'_> {
    /// The frame of `scene` seen by `cam` (through `glass` when given) with every effect of the
    /// setup: the one place a request's frame is put together, so a new effect's field reaches
    /// every output from here.
    pub fn frame<'a>(
        &'a self,
        scene: SceneRef<'a>,
        cam: &'a Camera,
        glass: Option<&'a Glass>,
    ) -> Frame<'a> {
        Frame::new(scene, cam, &self.light)
            .with_effects(
                self.setup.haze.as_ref(),
                self.rain.as_ref(),
                self.snow.as_ref(),
            )
            .with_windshield(glass, self.setup.defocus())
            .with_wet(self.setup.wet())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luminance_weights_keep_grey_units_exact() {
        assert_eq!(Vec3::ONE.dot(LUMINANCE_WEIGHTS), 1.0);
        let w = LUMINANCE_WEIGHTS;
        assert_eq!((w.z + w.y) + w.x, 1.0);
    }
}
