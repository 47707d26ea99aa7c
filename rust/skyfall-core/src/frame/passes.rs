//! The particles of a frame, prepared once for whichever output draws them, and their stage on
//! the float output.

use crate::error::Result;
use crate::particles::composite::{BAND_ROWS, bin_by_bands, composite_band_colour};
use crate::particles::order::far_to_near;
use crate::particles::streak::ScreenStreak;
use crate::rain::far::FarRain;
use crate::rain::streaks::{RainFrame, RainStats};
use crate::scene::camera::Camera;
use crate::snow::streaks::{SnowFrame, SnowStats};
use crate::stage::layers::{Layer, LayerSet};
use crate::stage::{Band, Stage};

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

/// What the particles draw: the rain's layers when it rains, the snow's when it snows.
pub fn layers(rain: bool, snow: bool) -> LayerSet {
    LayerSet::EMPTY
        .with_if(Layer::RainAlpha, rain)
        .with_if(Layer::RainDepth, rain)
        .with_if(Layer::SnowAlpha, snow)
}

impl Particles {
    /// The particles of a `cam` frame with `rain` and `snow`: the drops and flakes made and
    /// drawn into streaks (one list, far to near, each particle carrying its layer); None
    /// when neither falls.
    pub fn prepare(
        cam: &Camera,
        rain: Option<&RainFrame<'_>>,
        snow: Option<&SnowFrame<'_>>,
    ) -> Result<Option<Self>> {
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
                crate::Error::out_of_memory::<ScreenStreak>(
                    "the particles' streaks",
                    p.streaks.len() + flakes.len(),
                )
            })?;
            p.streaks.extend(flakes);
            far_to_near(&mut p.streaks)?;
            p.snow = Some(stats);
        }
        Ok(particles)
    }

    /// What the rain reports: streaks drawn and culled, drops generated (when it rains).
    pub fn rain_report(&self) -> Option<(RainStats, usize)> {
        self.raining.then_some((self.rain, self.rain_drops))
    }

    /// The layers these particles draw.
    pub fn layers(&self) -> LayerSet {
        layers(self.raining, self.snow.is_some())
    }
}

/// The particles as a stage of the float output: each band's streaks (binned once, by bands of
/// [`BAND_ROWS`]) composited far to near after the rain's far shells, with the depth test.
pub struct ParticleStage {
    /// The particles.
    pub particles: Particles,
    /// Per band, the start of its run in `indices`; one more at the end.
    offsets: Vec<u32>,
    /// Streak indices per band.
    indices: Vec<u32>,
}

impl ParticleStage {
    /// `particles` binned to `cam`'s bands.
    pub fn new(particles: Particles, cam: &Camera) -> Result<Self> {
        let (offsets, indices) = bin_by_bands(cam, &particles.streaks)?;
        Ok(ParticleStage {
            particles,
            offsets,
            indices,
        })
    }
}

impl Stage for ParticleStage {
    fn layers(&self) -> LayerSet {
        self.particles.layers()
    }

    fn band(&self, band: &mut Band<'_>) {
        let bi = band.y0 / BAND_ROWS;
        let list = &self.indices[self.offsets[bi] as usize..self.offsets[bi + 1] as usize];
        let [alpha, depth, snow] = band
            .layers
            .0
            .get_disjoint_mut([
                Layer::RainAlpha.index(),
                Layer::RainDepth.index(),
                Layer::SnowAlpha.index(),
            ])
            .unwrap_or_else(|_| unreachable!("three distinct layers"));
        // A layer the frame does not draw is an empty slice (no streak of that effect).
        let mut empty = [[0.0f32; 0]; 3];
        let [e0, e1, e2] = &mut empty;
        composite_band_colour(
            &self.particles.streaks,
            list,
            self.particles.far.as_ref().map(|f| f as _),
            band.y0,
            band.width,
            band.depth_m,
            band.rgb,
            [
                alpha.as_deref_mut().map_or(&mut e0[..], |s| s),
                depth.as_deref_mut().map_or(&mut e1[..], |s| s),
                snow.as_deref_mut().map_or(&mut e2[..], |s| s),
            ],
        );
    }
}
