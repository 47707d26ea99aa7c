//! A frame as the list of its stages. [`Frame`] is what one frame draws (the scene, the camera,
//! its light, the effects); [`Frame::plan`] declares its stages in physical order (the scene,
//! the clouds, the haze, the lights' glows, the particles), each with its layers and the
//! outputs that draw it, so which layers a frame carries and which outputs can draw it are
//! decided once, here; [`Frame::prepare`] makes the stages for a frame, which the float output
//! draws through [`crate::stage::draw_bands`] and the GPU records as its passes.
//!
//! A new effect is a [`Stage`] in its own folder, one declaration in [`Frame::plan`] and one
//! entry in [`Prepared`] (see ARCHITECTURE.md, "Adding an effect").

use super::SceneRef;
use super::passes::{self, ParticleStage, Particles};
use super::scene::{SceneLight, SceneStage};
use crate::cloud::frame::CloudSplats;
use crate::cloud::stage::CloudStage;
use crate::error::Result;
use crate::glow::Glow;
use crate::glow::stage::GlowStage;
use crate::haze::Haze;
use crate::haze::stage::HazeStage;
use crate::rain::streaks::{RainFrame, RainStats};
use crate::scene::boxes::BoxScene;
use crate::scene::camera::Camera;
use crate::scene::camera::Defocus;
use crate::snow::streaks::{SnowFrame, SnowStats};
use crate::stage::layers::{Layer, LayerSet};
use crate::stage::{Declared, Kind, Output, Plan, Stage};
use crate::wet::stage::{Surfaces, WetFrame, WetStage};
use crate::windshield::stage::{Glass, WindshieldStage};

/// What one frame draws: the scene seen by the camera under its light, and the effects.
#[derive(Clone, Copy)]
pub struct Frame<'a> {
    /// The photo or the box scene.
    pub scene: SceneRef<'a>,
    /// The camera, at the frame's resolution.
    pub cam: &'a Camera,
    /// How the scene is lit (the sky, the map, the lights, the sun, the clouds, the snow cover).
    pub light: &'a SceneLight<'a>,
    /// The haze, when the weather has any.
    pub haze: Option<&'a Haze>,
    /// The rain, when it rains streaks.
    pub rain: Option<&'a RainFrame<'a>>,
    /// The snowfall, when it snows.
    pub snow: Option<&'a SnowFrame<'a>>,
    /// The windshield in front of the camera, and the camera's thin lens that blurs its drops.
    pub windshield: Option<(&'a Glass, Option<Defocus>)>,
    /// The rain the surfaces received, when it wets them.
    pub wet: Option<&'a super::request::WetWeather>,
}

impl<'a> Frame<'a> {
    /// `scene` seen by `cam` under `light`, with no effect.
    pub fn new(scene: SceneRef<'a>, cam: &'a Camera, light: &'a SceneLight<'a>) -> Self {
        Frame {
            scene,
            cam,
            light,
            haze: None,
            rain: None,
            snow: None,
            windshield: None,
            wet: None,
        }
    }

    /// The same with the rain `wet` on its surfaces (None, or a film that wets nothing: dry).
    pub fn with_wet(self, wet: Option<&'a super::request::WetWeather>) -> Self {
        Frame {
            wet: wet.filter(|w| w.film.any()),
            ..self
        }
    }

    /// The same seen through `glass` (its drops blurred by the camera's thin lens `defocus`).
    pub fn with_windshield(self, glass: Option<&'a Glass>, defocus: Option<Defocus>) -> Self {
        Frame {
            windshield: glass.map(|g| (g, defocus)),
            ..self
        }
    }

    /// The same with `haze`, `rain` and `snow`.
    pub fn with_effects(
        self,
        haze: Option<&'a Haze>,
        rain: Option<&'a RainFrame<'a>>,
        snow: Option<&'a SnowFrame<'a>>,
    ) -> Self {
        Frame {
            haze,
            rain,
            snow,
            ..self
        }
    }

    /// The box scene, when the frame shows one.
    fn boxes(&self) -> Option<&'a BoxScene> {
        match self.scene {
            SceneRef::Boxes(b) => Some(b),
            SceneRef::Photo { .. } => None,
        }
    }

    /// The frame's stages as declared, in drawing order.
    pub fn plan(&self) -> Plan {
        let light = self.light;
        let photo = self.boxes().is_none();
        let mut plan = vec![Declared {
            kind: Kind::Scene,
            layers: LayerSet::EMPTY
                .with_if(Layer::SnowDepth, light.snow.is_some())
                .with_if(Layer::SunTransmittance, light.sun.is_some()),
            srgb8: photo && light.snow.is_none(),
            gpu: true,
            param: if photo { "snow_cover" } else { "scene" },
            why_not: if photo {
                "a photo under a snow cover is drawn by the banded 8-bit output (frame::encoded)"
            } else {
                "it draws 8-bit photos; a box scene is drawn by the banded 8-bit output (frame::encoded)"
            },
        }];
        if self.wet.is_some() {
            plan.push(Declared {
                kind: Kind::Wet,
                layers: crate::wet::stage::LAYERS,
                srgb8: false,
                // On the GPU a photo's in a pass of its own, a box scene's in the scene pass's
                // second entry point (its mirror ray needs the scene's ray cast and lighting).
                gpu: true,
                param: "rain_duration_s",
                why_not: "wet surfaces are drawn by the banded 8-bit output (frame::encoded)",
            });
        }
        if light.clouds.is_some() {
            plan.push(Declared {
                kind: Kind::Clouds,
                layers: crate::cloud::stage::LAYERS,
                srgb8: false,
                gpu: true,
                param: "clouds",
                why_not: "clouds are drawn by the banded 8-bit output (frame::encoded)",
            });
        }
        if self.haze.is_some() {
            plan.push(Declared {
                kind: Kind::Haze,
                layers: crate::haze::stage::LAYERS,
                srgb8: true,
                gpu: true,
                param: "visibility_m",
                why_not: "",
            });
        }
        if !photo && !light.lights.is_empty() {
            plan.push(Declared {
                kind: Kind::Glow,
                layers: LayerSet::EMPTY,
                srgb8: false,
                gpu: true,
                param: "lights",
                why_not: "the lights' glows are drawn by the banded 8-bit output (frame::encoded)",
            });
        }
        if self.rain.is_some() || self.snow.is_some() {
            plan.push(Declared {
                kind: Kind::Particles,
                layers: passes::layers(self.rain.is_some(), self.snow.is_some()),
                srgb8: true,
                gpu: true,
                param: "rain_far_m",
                why_not: "",
            });
        }
        if self.windshield.is_some() {
            plan.push(Declared {
                kind: Kind::Windshield,
                layers: crate::windshield::stage::LAYERS,
                srgb8: false,
                gpu: true,
                param: "windshield",
                why_not: "the windshield is drawn by the banded 8-bit output (frame::encoded)",
            });
        }
        Plan(plan)
    }

    /// Every layer the frame's stages draw.
    pub fn layers(&self) -> LayerSet {
        self.plan().layers()
    }

    /// The frame's stages, made for `output` (checked to draw them all): the clouds' splats
    /// sorted and binned, the glows' sources in view found, the particles made, lit, projected
    /// and sorted far to near (binned by bands for the float output).
    pub fn prepare(&self, output: Output) -> Result<Prepared<'a>> {
        self.prepare_planned(&self.plan(), output)
    }

    /// [`Self::prepare`] with the frame's [`Self::plan`] already made (an output that checked
    /// its buffers against the plan's layers first makes it once).
    pub fn prepare_planned(&self, plan: &Plan, output: Output) -> Result<Prepared<'a>> {
        plan.check(output)?;
        let cam = self.cam;
        let light = self.light;
        let clouds = light
            .clouds
            .as_ref()
            .map(|c| CloudSplats::prepare(c, cam).map(|splats| CloudStage { splats, cam }))
            .transpose()?;
        let haze = self.haze.map(|h| HazeStage::new(h, cam));
        let glow = self.boxes().and_then(|scene| {
            if light.lights.is_empty() {
                return None;
            }
            let tau = |d: f32| self.haze.map_or(0.0, |h| h.optical_depth(d));
            Glow::prepare(cam, scene, light.lights, tau, light.sky_illuminance_lux)
        });
        let particles = match Particles::prepare(cam, self.rain, self.snow)? {
            Some(p) if output == Output::Float => {
                Some(PreparedParticles::Binned(ParticleStage::new(p, cam)?))
            }
            Some(p) => Some(PreparedParticles::Listed(p)),
            None => None,
        };
        let wet = self.wet.and_then(|w| {
            WetStage::new(WetFrame {
                surfaces: match self.scene {
                    SceneRef::Boxes(b) => Surfaces::Boxes(b),
                    SceneRef::Photo { rgb, depth_m } => Surfaces::Photo { rgb, depth_m },
                },
                cam,
                film: w.film,
                wind_m_s: w.wind_m_s,
                shelter: &w.shelter,
                light,
                lamps: light.lights,
                sky_illuminance_lux: light.sky_illuminance_lux,
                sun: light.sun.map(|s| (s.direction, s.colour * s.relative)),
            })
        });
        let windshield = self
            .windshield
            .map(|(glass, defocus)| WindshieldStage::new(glass, cam, defocus.as_ref()))
            .transpose()?;
        Ok(Prepared {
            plan: plan.clone(),
            scene: SceneStage {
                scene: self.scene,
                cam,
                light,
            },
            wet,
            clouds,
            haze,
            glow: glow.map(|glow| GlowStage { glow, cam }),
            particles,
            windshield,
        })
    }
}

/// The particles as an output needs them: binned by bands for the float output's stage, or the
/// list alone.
pub enum PreparedParticles {
    /// The float output's stage.
    Binned(ParticleStage),
    /// The list, for an output with its own binning.
    Listed(Particles),
}

/// A frame's stages, made for it, in drawing order.
pub struct Prepared<'a> {
    /// The frame's plan: its stages' declarations, in drawing order.
    pub plan: Plan,
    /// The scene: the box scene ray cast (with its snow cover and the sun), or the photo.
    pub scene: SceneStage<'a>,
    /// The wet surfaces, when the rain wets them.
    pub wet: Option<WetStage<'a>>,
    /// The clouds, when the sky has them.
    pub clouds: Option<CloudStage<'a>>,
    /// The haze, when the weather has any.
    pub haze: Option<HazeStage<'a>>,
    /// The lights' glows, when a box scene's lights are in view.
    pub glow: Option<GlowStage<'a>>,
    /// The particles (rain and snow), when any effect makes them.
    pub particles: Option<PreparedParticles>,
    /// The windshield, when the camera looks through one (a whole-frame stage, last).
    pub windshield: Option<WindshieldStage>,
}

impl Prepared<'_> {
    /// The stages, in the plan's order (the particles when binned for the float output).
    pub fn stages(&self) -> Vec<&dyn Stage> {
        let mut list: Vec<&dyn Stage> = Vec::with_capacity(self.plan.0.len());
        for d in &self.plan.0 {
            let stage: Option<&dyn Stage> = match d.kind {
                Kind::Scene => Some(&self.scene),
                Kind::Wet => self.wet.as_ref().map(|s| s as &dyn Stage),
                Kind::Clouds => self.clouds.as_ref().map(|s| s as &dyn Stage),
                Kind::Haze => self.haze.as_ref().map(|s| s as &dyn Stage),
                Kind::Glow => self.glow.as_ref().map(|s| s as &dyn Stage),
                Kind::Particles => match &self.particles {
                    Some(PreparedParticles::Binned(s)) => Some(s),
                    _ => None,
                },
                Kind::Windshield => self.windshield.as_ref().map(|s| s as &dyn Stage),
            };
            list.extend(stage);
        }
        list
    }

    /// The particles, sorted far to near.
    pub fn particles(&self) -> Option<&Particles> {
        self.particles.as_ref().map(|d| match d {
            PreparedParticles::Binned(s) => &s.particles,
            PreparedParticles::Listed(p) => p,
        })
    }

    /// What the rain reports: streaks drawn and culled, drops generated (when it rains).
    pub fn rain_report(&self) -> Option<(RainStats, usize)> {
        self.particles().and_then(Particles::rain_report)
    }

    /// What the snow reports: flakes generated and streaks drawn (when it snows).
    pub fn snow_report(&self) -> Option<SnowStats> {
        self.particles().and_then(|p| p.snow)
    }
}
