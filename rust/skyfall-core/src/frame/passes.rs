//! A frame's effect passes, prepared once for whichever output stage draws them.

use crate::error::Result;
use crate::haze::Haze;
use crate::particles::streak::ScreenStreak;
use crate::rain::streaks::{RainFrame, RainStats};
use crate::scene::camera::Camera;

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
}

/// The effect passes of a frame, in physical order.
#[derive(Debug, Clone, PartialEq)]
pub struct Passes<'a> {
    /// Haze along the view rays.
    pub haze: Option<&'a Haze>,
    /// The particles (rain), when any effect makes them.
    pub particles: Option<Particles>,
}

impl<'a> Passes<'a> {
    /// The passes of a `cam` frame with `haze` and `rain`: the rain's drops made and drawn into
    /// streaks here, once, for any output stage.
    pub fn prepare(
        cam: &Camera,
        haze: Option<&'a Haze>,
        rain: Option<&RainFrame<'_>>,
    ) -> Result<Self> {
        let particles = match rain {
            Some(rf) => {
                let (streaks, rain, rain_drops) = rf.streaks(cam)?;
                Some(Particles {
                    streaks,
                    rain,
                    rain_drops,
                })
            }
            None => None,
        };
        Ok(Passes { haze, particles })
    }

    /// What the rain reports: streaks drawn and culled, drops generated.
    pub fn rain_report(&self) -> Option<(RainStats, usize)> {
        self.particles.as_ref().map(|p| (p.rain, p.rain_drops))
    }
}
