//! The lights' glows as a stage of a frame: each row's emitter discs and glows added to the
//! hazed colour. It draws no layer.

use super::Glow;
use crate::scene::camera::Camera;
use crate::stage::layers::LayerSet;
use crate::stage::{Row, Stage};

/// A frame's glows: the sources in view, found once.
pub struct GlowStage<'a> {
    /// The sources.
    pub glow: Glow,
    /// The frame's camera.
    pub cam: &'a Camera,
}

impl Stage for GlowStage<'_> {
    fn layers(&self) -> LayerSet {
        LayerSet::EMPTY
    }

    fn row(&self, row: &mut Row<'_>) {
        self.glow.apply_row(self.cam, row.y, row.rgb);
    }
}
