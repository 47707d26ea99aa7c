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

use crate::camera::camera_words;
use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, storage_init, uniform};
use skyfall_core::particles::binning::bin_by_tiles;
use skyfall_core::particles::streak::ScreenStreak;
use skyfall_core::scene::camera::Camera;

const SOURCE: &str = include_str!("shaders/rain.wgsl");
/// Tile width, px (see the module's note on tile size).
pub const TILE_W: u32 = 2;
/// Tile height, px.
pub const TILE_H: u32 = 4;

/// The compiled pass.
#[derive(Debug)]
pub struct RainPass(ComputePass);

/// The frame buffers the pass reads and writes: rgb (in place), depth (read), alpha and
/// rain depth (written).
pub struct RainTargets<'a> {
    /// Linear RGB.
    pub rgb: &'a wgpu::Buffer,
    /// Scene depth.
    pub depth: &'a wgpu::Buffer,
    /// Streak coverage.
    pub alpha: &'a wgpu::Buffer,
    /// Nearest streak depth.
    pub rain_depth: &'a wgpu::Buffer,
}

impl RainPass {
    /// Compiles the pass.
    pub fn new(ctx: &GpuContext) -> Self {
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

    /// Records the pass over prepared `streaks` (far to near); [`GpuError::TooLarge`] when the
    /// streaks or the tiles' lists of them do not fit one of the device's storage buffers.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        cam: &Camera,
        streaks: &[ScreenStreak],
        reflectance: f32,
        t: RainTargets<'_>,
    ) -> Result<(), GpuError> {
        let (offsets, mut indices) = bin_by_tiles(streaks, cam.width, cam.height, TILE_W, TILE_H);
        // rain_near_m and the rain rate set how many streaks there are (the region's volume
        // goes as rain_near_m³).
        let mut packed: Vec<f32> = streaks.iter().flat_map(|s| s.packed()).collect();
        let why = "(fewer with a smaller rain_near_m or rain rate)";
        ctx.check_buffer(
            &format!("the rain's {} streaks {why}", streaks.len()),
            (packed.len() * 4) as u64,
        )?;
        ctx.check_buffer(
            &format!("the rain's tile lists ({} entries) {why}", indices.len()),
            (indices.len() * 4) as u64,
        )?;
        // Bindings may not be empty; the offsets keep padding unread.
        if packed.is_empty() {
            packed.resize(16, 0.0);
        }
        if indices.is_empty() {
            indices.push(0);
        }
        let params = [
            reflectance.to_bits(),
            cam.width.div_ceil(TILE_W),
            TILE_W,
            TILE_H,
        ];
        let cam_buf = uniform(ctx, "camera", &camera_words(cam));
        let params_buf = uniform(ctx, "rain", &params);
        let streak_buf = storage_init(ctx, "streaks", &packed);
        let offsets_buf = storage_init(ctx, "tile offsets", &offsets);
        let indices_buf = storage_init(ctx, "tile indices", &indices);
        self.0.encode(
            ctx,
            enc,
            &[
                &cam_buf,
                &params_buf,
                &streak_buf,
                &offsets_buf,
                &indices_buf,
                t.rgb,
                t.depth,
                t.alpha,
                t.rain_depth,
            ],
            cam.width,
            cam.height,
        );
        Ok(())
    }
}
