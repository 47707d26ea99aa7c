//! A frame's effect passes, prepared once for whichever output stage draws them.

use super::scene::SceneLight;
use crate::error::Result;
use crate::glow::Glow;
use crate::haze::Haze;
use crate::particles::order::far_to_near;
use crate::particles::streak::ScreenStreak;
use crate::rain::far::FarRain;
use crate::rain::streaks::{RainFrame, RainStats};
use crate::scene::boxes::BoxScene;
use crate::scene::camera::Camera;
use crate::snow::streaks::{SnowFrame, SnowStats};

/// The particles of a frame: every effect's, lit, projected and sorted far to near in one list
/// (each carries its own light and r), so they composite in depth order whatever effect made
/// them.
#[derive(Debug, Clone, PartialEq)]
pub struct Particles {
    /// Far to near.
    pub streaks: Vec<ScreenStreak>,
    /// The rain's streaks drawn and culled.
    pub rain: RainStats,
    /// Rain drops generated (in the voxels that can reach the view, less the sheltered ones).
    pub rain_drops: usize,
    /// Whether it rains (the list holds the rain's particles).
    pub raining: bool,
    /// The snow's flakes and streaks, when it snows.
    pub snow: Option<SnowStats>,
    /// The rain's far level of detail, when the rain has one: composited before `streaks`.
    pub far: Option<FarRain>,
}

/// The effect passes of a frame, in physical order.
#[derive(Debug, Clone, PartialEq)]
pub struct Passes<'a> {
    /// Haze along the view rays.
    pub haze: Option<&'a Haze>,
    /// The lights seen by the camera, their discs and glows (after the haze, before the
    /// particles), when a box scene has lights in view.
    pub glow: Option<Glow>,
    /// The particles (rain and snow), when any effect makes them.
    pub particles: Option<Particles>,
}

impl<'a> Passes<'a> {
    /// The passes of a `cam` frame with `haze`, `rain` and `snow` and, for a box scene, its
    /// lights (`lit`: the scene and how it is lit): the drops and flakes made and drawn into
    /// streaks (one list, far to near, each particle carrying its layer) and the glows' sources
    /// found here, once, for any output stage.
    pub fn prepare(
        cam: &Camera,
        lit: Option<(&BoxScene, &SceneLight<'_>)>,
        haze: Option<&'a Haze>,
        rain: Option<&RainFrame<'_>>,
        snow: Option<&SnowFrame<'_>>,
    ) -> Result<Self> {
        let mut particles = match rain {
            Some(rf) => {
                let (streaks, rain, rain_drops) = rf.streaks(cam)?;
                Some(Particles {
                    streaks,
                    rain,
                    rain_drops,
                    raining: true,
                    snow: None,
                    far: rf.far(cam)?,
                })
            }
            None => None,
        };
        if let Some(sf) = snow {
            let (flakes, stats) = sf.streaks(cam)?;
            let p = particles.get_or_insert_with(|| Particles {
                streaks: Vec::new(),
                rain: RainStats::default(),
                rain_drops: 0,
                raining: false,
                snow: None,
                far: None,
            });
            // One list: the rain's (sorted) then the flakes, sorted together far to near
            // (ties in that order).
            p.streaks.try_reserve(flakes.len()).map_err(|_| {
                crate::Error::out_of_memory::<crate::particles::streak::ScreenStreak>(
                    "the particles' streaks",
                    p.streaks.len() + flakes.len(),
                )
            })?;
            p.streaks.extend(flakes);
            far_to_near(&mut p.streaks)?;
            p.snow = Some(stats);
        }
        let glow = lit.and_then(|(scene, light)| {
            if light.lights.is_empty() {
                return None;
            }
            let tau = |d: f32| haze.map_or(0.0, |h| h.optical_depth(d));
            Glow::prepare(cam, scene, light.lights, tau, light.sky_illuminance_lux)
        });
        Ok(Passes {
            haze,
            glow,
            particles,
        })
    }

    /// What the rain reports: streaks drawn and culled, drops generated (when it rains).
    pub fn rain_report(&self) -> Option<(RainStats, usize)> {
        self.particles
            .as_ref()
            .filter(|p| p.raining)
            .map(|p| (p.rain, p.rain_drops))
    }

    /// The rain's far layers, when the frame draws them.
    pub fn far(&self) -> Option<&FarRain> {
        self.particles.as_ref().and_then(|p| p.far.as_ref())
    }

    /// What the snow reports: flakes generated and streaks drawn (when it snows).
    pub fn snow_report(&self) -> Option<SnowStats> {
        self.particles.as_ref().and_then(|p| p.snow)
    }
}
