//! A frame is one list of stages (the [`crate::stage::Stage`] seam) in physical order: the
//! scene stage (a photo and its depth, or the box scene ray cast), then the clouds, the haze,
//! the lights' glows and the particles. [`stages::Frame`] declares the list ([`stages::Frame::plan`]:
//! each stage's layers and the outputs that draw it) and makes it once per frame
//! ([`stages::Frame::prepare`]; the particles of every effect in one far-to-near list,
//! [`passes::Particles`]); an output draws it:
//!
//! - [`float`]: the linear float32 frame with its layers, through the one generic loop
//!   [`crate::stage::draw_bands`]: band by band (16 rows) while the band is in cache;
//! - [`encoded`]: 8-bit sRGB of any frame, the same loop with each band encoded as it is
//!   finished (the float frame's bytes, no frame-sized float buffer);
//! - [`srgb8`]: 8-bit sRGB for 8-bit photos, fused, in tiles: the particles into each pixel's affine
//!   map first, then each pixel decoded, hazed, mapped and encoded once (the stages that
//!   declare it: the photo, the haze, the particles);
//! - the GPU backend (`skyfall-gpu`), each stage a pass recorded into one encoder.
//!
//! The layers a frame can carry are declared once, in [`layers`] (`crate::stage::layers`).

use crate::error::{Error, Param, Result, try_filled_par};
use crate::haze::check_depth;
use crate::rain::streaks::RainStats;
use crate::scene::boxes::BoxScene;
use crate::scene::camera::Camera;
pub use crate::stage::layers;
use layers::{Layer, LayerSet, Layers};

pub mod encoded;
pub mod float;
pub mod passes;
pub mod request;
pub mod scene;
pub mod srgb8;
pub mod stages;

pub use float::{draw, render_frame};

/// Largest frame (rgb + depth + layers, float32) the renderers allocate: 8 GiB, the
/// documented largest frame (16384 × 16384, [`crate::ranges::SIDE_PX`]) with every value per
/// pixel, so every size within the width and height ranges is allowed (the budget was 4 GiB,
/// which refused sizes the ranges accept); what the machine cannot give is a `MemoryError`.
pub const FRAME_BUDGET_BYTES: u64 = 8 << 30;
/// float32 values per pixel a frame may hold: rgb, depth and up to four layers.
const VALUES_PER_PIXEL: u64 = 8;

/// What the frame shows.
#[derive(Debug, Clone, Copy)]
pub enum SceneRef<'a> {
    /// The procedural box scene, ray cast.
    Boxes(&'a BoxScene),
    /// A photo (linear RGB, H·W·3) with its depth map (H·W, metres along the axis, inf = sky).
    Photo {
        /// Linear RGB.
        rgb: &'a [f32],
        /// Depth, m.
        depth_m: &'a [f32],
    },
}

/// A rendered frame's buffers.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameBuffers {
    /// Linear RGB, H·W·3.
    pub rgb: Vec<f32>,
    /// Depth along the optical axis, m (inf for sky), H·W.
    pub depth_m: Vec<f32>,
    /// The layers the frame's passes drew, H·W each ([`Layer`]).
    pub layers: Layers<Vec<f32>>,
    /// The rain's streaks drawn and culled and drops generated, when it rained.
    pub rain: Option<RainReport>,
}

impl FrameBuffers {
    /// A layer, when the frame drew it.
    pub fn layer(&self, layer: Layer) -> Option<&[f32]> {
        self.layers.get(layer).map(Vec::as_slice)
    }
}

/// Refuses frames over [`FRAME_BUDGET_BYTES`] before allocating (none within the ranges).
pub fn check_frame_size(cam: &Camera) -> Result<()> {
    let bytes = cam.pixels() as u128 * u128::from(VALUES_PER_PIXEL) * 4;
    if bytes > u128::from(FRAME_BUDGET_BYTES) {
        let what = format!("a {}x{} frame", cam.width, cam.height);
        return Err(Error::too_large(what, bytes, FRAME_BUDGET_BYTES));
    }
    Ok(())
}

/// Checks a photo scene's arrays against the camera.
pub fn check_photo(cam: &Camera, rgb: &[f32], depth_m: &[f32]) -> Result<()> {
    let n = cam.pixels();
    if rgb.len() != 3 * n {
        return Err(Error::Length {
            param: Param {
                name: "image",
                index: None,
            },
            len: rgb.len(),
            expected: 3 * n,
        });
    }
    if depth_m.len() != n {
        return Err(Error::Length {
            param: Param {
                name: "depth_m",
                index: None,
            },
            len: depth_m.len(),
            expected: n,
        });
    }
    check_depth(depth_m)
}

/// Where [`draw`] writes a frame: buffers the caller owns, every value overwritten
/// (the Python binding passes numpy's arrays, so a frame's megabytes come from numpy's
/// allocator, which asks for huge pages: a fresh frame then costs a few dozen page faults
/// instead of one per 4 KiB).
pub struct FrameOut<'a> {
    /// Linear RGB, H·W·3.
    pub rgb: &'a mut [f32],
    /// Depth along the optical axis, m, H·W.
    pub depth_m: &'a mut [f32],
    /// The layers, H·W each: given exactly when the frame's stages draw them
    /// ([`stages::Frame::layers`]).
    pub layers: Layers<&'a mut [f32]>,
}

/// What [`draw`] reports of the rain: streaks drawn and culled, drops generated.
pub type RainReport = (RainStats, usize);

impl<'a> FrameOut<'a> {
    /// The buffers `rgb`, `depth_m` and the layers given.
    pub fn from_layers(
        rgb: &'a mut [f32],
        depth_m: &'a mut [f32],
        layers: impl IntoIterator<Item = (Layer, &'a mut [f32])>,
    ) -> Self {
        let mut out = FrameOut {
            rgb,
            depth_m,
            layers: Layers::default(),
        };
        for (l, buf) in layers {
            out.layers.set(l, buf);
        }
        out
    }

    /// Checks the buffers against a `cam` frame drawing the layers `drawn`: every length, and
    /// the layers given exactly when they are drawn.
    pub fn check(&self, cam: &Camera, drawn: LayerSet) -> Result<()> {
        let n = cam.pixels();
        let length = |name: &'static str, len: usize, expected: usize| Error::Length {
            param: Param { name, index: None },
            len,
            expected,
        };
        if self.rgb.len() != 3 * n {
            return Err(length("rgb", self.rgb.len(), 3 * n));
        }
        if self.depth_m.len() != n {
            return Err(length("depth_m", self.depth_m.len(), n));
        }
        for l in Layer::ALL {
            let drawn = drawn.contains(l);
            let want = if drawn { n } else { 0 };
            let got = self.layers.get(l).map_or(0, |b| b.len());
            if got != want || self.layers.get(l).is_some() != drawn {
                return Err(length(l.name(), got, want));
            }
        }
        Ok(())
    }
}

impl FrameBuffers {
    /// A `cam` frame's buffers (with each layer of `drawn`), sized after the frame
    /// is checked to fit, filled by a backend's `draw`.
    pub fn filled<E: From<Error>>(
        cam: &Camera,
        drawn: LayerSet,
        draw: impl FnOnce(FrameOut<'_>) -> std::result::Result<Option<RainReport>, E>,
    ) -> std::result::Result<Self, E> {
        check_frame_size(cam)?;
        let n = cam.pixels();
        // Reserved fallibly: out of memory is an error, never an abort.
        let (mut rgb, mut depth) = (
            try_filled_par("rgb", 3 * n, 0.0f32)?,
            try_filled_par("depth_m", n, 0.0f32)?,
        );
        let mut layers: Layers<Vec<f32>> = Layers::default();
        for l in Layer::ALL {
            if drawn.contains(l) {
                layers.set(l, try_filled_par(l.name(), n, 0.0f32)?);
            }
        }
        let slices = layers
            .0
            .iter_mut()
            .zip(Layer::ALL)
            .filter_map(|(b, l)| b.as_mut().map(|b| (l, b.as_mut_slice())));
        let out = FrameOut::from_layers(&mut rgb, &mut depth, slices);
        let rain = draw(out)?;
        Ok(FrameBuffers {
            rgb,
            depth_m: depth,
            layers,
            rain,
        })
    }
}

/// The frame the output stages' tests draw: one box in front of a level camera `width` ×
/// `height` px, under an overcast sky with a uniform ambient map, and a haze.
#[cfg(test)]
pub(crate) mod fixture {
    use crate::haze::Haze;
    use crate::scene::boxes::{BoxScene, SceneBox};
    use crate::scene::camera::Camera;
    use crate::sky::ambient::AmbientMap;
    use crate::sky::{Sky, cie::SkyKind};
    use glam::{Mat3, Vec3};

    /// (camera, scene, haze, sky, ambient map).
    #[allow(clippy::unwrap_used)]
    pub(crate) fn one_box(width: u32, height: u32) -> (Camera, BoxScene, Haze, Sky, AmbientMap) {
        let (cx, cy) = (width as f32 / 2.0, height as f32 / 2.0);
        let cam = Camera::new(
            width,
            height,
            [30.0, 30.0, cx, cy],
            Vec3::new(0.0, 1.6, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let b = SceneBox {
            min_m: Vec3::new(-3.0, 0.0, -12.0),
            max_m: Vec3::new(3.0, 6.0, -8.0),
            albedo: Vec3::new(0.6, 0.5, 0.4),
        };
        let scene = BoxScene::new(vec![b], true, Vec3::splat(0.1)).unwrap();
        let h = Haze::new(0.02, [0.43; 3], 700.0).unwrap();
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0, 0.4, 0.4, 0.4, 0.4]);
        (cam, scene, h, sky, amb)
    }
}
