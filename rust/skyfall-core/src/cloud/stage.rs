//! The clouds as a stage of a frame: each row's splats composited over what lies behind them,
//! their coverage into the `cloud_alpha` layer.

use super::frame::CloudSplats;
use crate::scene::camera::Camera;
use crate::stage::layers::{Layer, LayerSet};
use crate::stage::{Row, Stage};

/// A frame's clouds: their splats, sorted and binned for `cam`.
pub struct CloudStage<'a> {
    /// The splats.
    pub splats: CloudSplats<'a>,
    /// The frame's camera.
    pub cam: &'a Camera,
}

/// What the clouds draw.
pub const LAYERS: LayerSet = LayerSet::of(&[Layer::CloudAlpha]);

impl Stage for CloudStage<'_> {
    fn layers(&self) -> LayerSet {
        LAYERS
    }

    fn row(&self, row: &mut Row<'_>) {
        let alpha = row.layers.get_mut(Layer::CloudAlpha).map(|a| &mut **a);
        self.splats
            .apply_row(self.cam, row.y, row.rgb, row.depth_m, alpha);
    }
}
