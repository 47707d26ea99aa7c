//! The GPU frame: passes chained on the device, one readback per output.

use crate::context::{AdapterChoice, GpuContext, GpuError};
use crate::haze::HazePass;
use crate::pass::{storage, storage_init};
use crate::rain::{RainPass, RainTargets};
use crate::readback::read_f32_into;
use crate::scene_raycast::SceneRaycastPass;
use skyfall_core::frame::{
    FrameBuffers, FrameOut, RainReport, SceneRef, check_frame_size, check_photo,
};
use skyfall_core::haze::Haze;
use skyfall_core::rain::streaks::RainFrame;
use skyfall_core::scene::boxes::SceneLight;
use skyfall_core::scene::camera::Camera;

/// A device with every pass compiled, reused across frames.
#[derive(Debug)]
pub struct GpuRenderer {
    /// The context.
    pub ctx: GpuContext,
    raycast: SceneRaycastPass,
    haze: HazePass,
    rain: RainPass,
}

impl GpuRenderer {
    /// Creates the device and compiles the passes.
    pub fn new(choice: AdapterChoice) -> Result<Self, GpuError> {
        let ctx = GpuContext::new(choice)?;
        let (raycast, haze, rain) = ctx.scoped(|| {
            Ok((
                SceneRaycastPass::new(&ctx),
                HazePass::new(&ctx),
                RainPass::new(&ctx),
            ))
        })?;
        Ok(GpuRenderer {
            ctx,
            raycast,
            haze,
            rain,
        })
    }

    /// Renders a frame: the scene (ray cast under `light`, or the photo uploaded), haze, rain,
    /// then readback.
    pub fn render(
        &self,
        scene: SceneRef<'_>,
        cam: &Camera,
        light: &SceneLight<'_>,
        haze: Option<&Haze>,
        rain: Option<&RainFrame<'_>>,
    ) -> Result<FrameBuffers, GpuError> {
        FrameBuffers::filled(cam, haze.is_some(), rain.is_some(), |out| {
            self.render_into(scene, cam, light, haze, rain, out)
        })
    }

    /// [`Self::render`] read back into the caller's buffers (see [`FrameOut`]); the rain's
    /// report when it rains.
    pub fn render_into(
        &self,
        scene: SceneRef<'_>,
        cam: &Camera,
        light: &SceneLight<'_>,
        haze: Option<&Haze>,
        rain: Option<&RainFrame<'_>>,
        out: FrameOut<'_>,
    ) -> Result<Option<RainReport>, GpuError> {
        check_frame_size(cam)?;
        out.check(cam, haze.is_some(), rain.is_some())?;
        let n = cam.pixels();
        self.ctx.check_buffer(
            &format!("a {}x{} RGB frame", cam.width, cam.height),
            (3 * n * 4) as u64,
        )?;
        let ctx = &self.ctx;
        ctx.scoped(|| {
            let mut enc = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("frame"),
                });
            let (rgb, depth) = match scene {
                SceneRef::Boxes(b) => {
                    ctx.check_buffer(
                        "the ambient-light map",
                        (light.ambient.values.len() * 4) as u64,
                    )?;
                    let rgb = storage(ctx, "rgb", 3 * n);
                    let depth = storage(ctx, "depth", n);
                    self.raycast
                        .encode(ctx, &mut enc, b, cam, light, &rgb, &depth);
                    (rgb, depth)
                }
                SceneRef::Photo { rgb, depth_m } => {
                    check_photo(cam, rgb, depth_m)?;
                    (
                        storage_init(ctx, "rgb", rgb),
                        storage_init(ctx, "depth", depth_m),
                    )
                }
            };
            let trans = haze.map(|h| {
                let t = storage(ctx, "transmittance", n);
                self.haze.encode(ctx, &mut enc, h, cam, [&rgb, &depth, &t]);
                t
            });
            let rain_out = rain.map(|rf| {
                let (streaks, stats, drops) = rf.streaks(cam)?;
                let alpha = storage(ctx, "rain_alpha", n);
                let rain_depth = storage(ctx, "rain_depth", n);
                let targets = RainTargets {
                    rgb: &rgb,
                    depth: &depth,
                    alpha: &alpha,
                    rain_depth: &rain_depth,
                };
                self.rain.encode(
                    ctx,
                    &mut enc,
                    cam,
                    &streaks,
                    rf.shading.reflectance,
                    targets,
                )?;
                Ok::<_, GpuError>((alpha, rain_depth, stats, drops))
            });
            let rain_out = rain_out.transpose()?;
            ctx.queue.submit([enc.finish()]);
            let FrameOut {
                rgb: rgb_out,
                depth_m: depth_out,
                transmittance: trans_out,
                rain: layers_out,
            } = out;
            read_f32_into(ctx, &rgb, rgb_out)?;
            read_f32_into(ctx, &depth, depth_out)?;
            if let (Some(t), Some(t_out)) = (&trans, trans_out) {
                read_f32_into(ctx, t, t_out)?;
            }
            match (rain_out, layers_out) {
                (Some((alpha, rd, stats, drops)), Some((a_out, d_out))) => {
                    read_f32_into(ctx, &alpha, a_out)?;
                    read_f32_into(ctx, &rd, d_out)?;
                    Ok(Some((stats, drops)))
                }
                _ => Ok(None),
            }
        })
    }
}
