//! The haze as a stage of a frame: each row's transmittance e^(−τ) along its view rays into the
//! `transmittance` layer, and the colour blended towards the airlight, C·t + A·(1 − t).

use super::{Haze, ViewRays, apply_row};
use crate::scene::camera::Camera;
use crate::stage::layers::{Layer, LayerSet};
use crate::stage::{Row, Stage};

/// The haze of a frame, with its view rays.
pub struct HazeStage<'a> {
    haze: &'a Haze,
    rays: ViewRays,
}

impl<'a> HazeStage<'a> {
    /// `haze` seen by `cam`.
    pub fn new(haze: &'a Haze, cam: &Camera) -> Self {
        HazeStage {
            haze,
            rays: ViewRays::new(cam),
        }
    }

    /// The haze.
    pub fn haze(&self) -> &'a Haze {
        self.haze
    }
}

/// What the haze draws.
pub const LAYERS: LayerSet = LayerSet::of(&[Layer::Transmittance]);

impl Stage for HazeStage<'_> {
    fn layers(&self) -> LayerSet {
        LAYERS
    }

    fn row(&self, row: &mut Row<'_>) {
        let w = row.depth_m.len();
        if let Some(t) = row.layers.get_mut(Layer::Transmittance) {
            apply_row(
                self.haze,
                &self.rays.row(row.y, 0..w),
                row.rgb,
                row.depth_m,
                t,
            );
        }
    }
}
