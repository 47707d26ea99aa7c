//! The rain pass: streaks composited over the frame (`shaders/rain.wgsl`). Streaks are
//! projected, lit, culled, sorted and binned into 2 × 4-pixel tiles on the CPU
//! (`skyfall_core::particles`); each pixel walks its tile's list, and skips a streak whose
//! reach it is beyond before reading the rest of it.
//!
//! Tile size, measured on lavapipe (2 cores; 200 × 120 frame with 30 k streaks / 1920 × 1080
//! street photo with 18 k), with the skip: 16 × 16 tiles 474 / 1100 ms per frame (600 / 1330
//! without it), 8 × 8 191 / 680, 4 × 4 107 / 515, 2 × 8 99 / 447, 2 × 4 83 / 441. Most streaks are steep and under two pixels
//! wide, so narrow tiles keep most of them out of most lists. The 8 × 8 workgroup then spans
//! several tiles; on a real GPU that costs some divergence, which is unmeasured here.

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::pool::Pooled;
use crate::uniforms::{CameraUniform, RainUniform};
use skyfall_core::particles::binning::bin_by_tiles;
use skyfall_core::particles::streak::{PARTICLE_LAYERS, ScreenStreak};

const SOURCE: &str = include_str!("shaders/rain.wgsl");
/// Tile width, px (see the module's note on tile size).
pub const TILE_W: u32 = 2;
/// Tile height, px.
pub const TILE_H: u32 = 4;

/// The compiled pass.
#[derive(Debug)]
pub struct RainPass(ComputePass);

impl FramePass for RainPass {
    /// The prepared streaks, far to near (each with its light and r); whether the far pass
    /// drew the rain's far shells before them (the rain's coverage plane and the depth then
    /// hold theirs, which the streaks continue); and the particle layers' coverage planes
    /// ([`PARTICLE_LAYERS`] in order, W·H each), which the caller copies to the frame's layers.
    type Input<'i> = (&'i [ScreenStreak], bool, &'i Pooled);

    fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        RainPass(ComputePass::new(
            ctx,
            "rain",
            SOURCE,
            &[
                Uniform, Uniform, ReadOnly, ReadOnly, ReadOnly, ReadWrite, ReadOnly, ReadWrite,
                ReadWrite,
            ],
        ))
    }

    /// rgb composited in place, every particle layer's coverage plane written, and the nearest
    /// depth of the layers that have one (when the frame draws it);
    /// [`GpuError::TooLarge`] when the streaks or the tiles' lists of them do not fit one of
    /// the device's storage buffers.
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        (streaks, after_far, coverage): Self::Input<'_>,
    ) -> Result<(), GpuError> {
        let cam = f.cam;
        // A frame without the depth layer binds a one-value stand-in, never written
        // (`params.layers`).
        let unused = f.target("unused layer", 1);
        let depth_layer = PARTICLE_LAYERS.iter().find_map(|l| l.depth);
        let rain_depth = depth_layer.and_then(|l| t.layers.get(l));
        let depth_layers = PARTICLE_LAYERS
            .iter()
            .enumerate()
            .filter(|(_, l)| l.depth.is_some())
            .fold(0u32, |m, (k, _)| m | 1 << k);
        let (offsets, mut indices) = bin_by_tiles(streaks, cam.width, cam.height, TILE_W, TILE_H)?;
        // rain_near_m, snow_near_m and the rates set how many streaks there are (a region's
        // volume goes as its radius cubed).
        let mut packed: Vec<f32> = streaks.iter().flat_map(|s| s.packed()).collect();
        let why = "(fewer with a smaller rain_near_m, snow_near_m or rate)";
        f.ctx.check_buffer(
            &format!("the particles' {} streaks {why}", streaks.len()),
            (packed.len() * 4) as u64,
        )?;
        f.ctx.check_buffer(
            &format!(
                "the particles' tile lists ({} entries) {why}",
                indices.len()
            ),
            (indices.len() * 4) as u64,
        )?;
        // Bindings may not be empty; the offsets keep padding unread.
        if packed.is_empty() {
            packed.resize(16, 0.0);
        }
        if indices.is_empty() {
            indices.push(0);
        }
        let params = RainUniform {
            streak_count: streaks.len() as u32,
            tiles_x: cam.width.div_ceil(TILE_W),
            tile_w: TILE_W,
            tile_h: TILE_H,
            layers: u32::from(rain_depth.is_some()) | (u32::from(after_far) << 2),
            depth_layers,
            planes: PARTICLE_LAYERS
                .iter()
                .enumerate()
                .filter(|(_, l)| t.layers.get(l.coverage).is_some())
                .fold(0u32, |m, (k, _)| m | 1 << k),
            pad: 0,
        };
        let cam_buf = f.uniform("camera", &CameraUniform::new(cam));
        let params_buf = f.uniform("rain", &params);
        let streak_buf = f.upload("streaks", &packed);
        let offsets_buf = f.upload("tile offsets", &offsets);
        let indices_buf = f.upload("tile indices", &indices);
        f.dispatch(
            &self.0,
            &[
                &cam_buf,
                &params_buf,
                &streak_buf,
                &offsets_buf,
                &indices_buf,
                t.rgb,
                t.depth,
                coverage,
                rain_depth.unwrap_or(&unused),
            ],
        );
        f.hold([
            cam_buf,
            params_buf,
            streak_buf,
            offsets_buf,
            indices_buf,
            unused,
        ]);
        Ok(())
    }
}
