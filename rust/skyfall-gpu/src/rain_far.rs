//! The rain's far level of detail on the GPU (`shaders/rain_far.wgsl`): the shells' textures
//! (`skyfall_core::rain::far`) looked up per pixel and composited before the near streaks,
//! which the rain pass then composites over the coverage and depth written here.

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::pool::Pooled;
use crate::uniforms::CameraUniform;
use skyfall_core::frame::layers::Layer;
use skyfall_core::rain::far::{BLOCK_PX, FAR_MAX_TAN, FarRain, TEXTURE_SIZE};

const SOURCE: &str = include_str!("shaders/rain_far.wgsl");

/// The compiled pass.
#[derive(Debug)]
pub struct FarPass(ComputePass);

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FarUniform {
    dims: [u32; 4],
    misc: [f32; 4],
    shear: [f32; 4],
    extra: [f32; 4],
}

impl FramePass for FarPass {
    /// The frame's far rain, and the particle layers' coverage planes (the rain's is written).
    type Input<'i> = (&'i FarRain, &'i Pooled);

    fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        FarPass(ComputePass::new(
            ctx,
            "rain_far",
            SOURCE,
            &[
                Uniform, Uniform, ReadOnly, ReadOnly, ReadOnly, ReadOnly, ReadWrite, ReadOnly,
                ReadWrite, ReadWrite,
            ],
        ))
    }

    /// rgb composited in place, the rain's coverage plane and `rain_depth_m` written (which the
    /// rain pass continues); [`GpuError::TooLarge`] when the textures do not fit one of the
    /// device's storage buffers.
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        (far, coverage): Self::Input<'_>,
    ) -> Result<(), GpuError> {
        let Some(rain_depth) = t.layers.get(Layer::RainDepth) else {
            // a frame with far rain draws the rain's layers (its plan declares them)
            return Ok(());
        };
        let a = far.arrays();
        f.ctx.check_buffer(
            &format!(
                "the far rain's {} textures of {TEXTURE_SIZE}² (fewer shells: rain_far_m nearer rain_near_m)",
                a.radii.len()
            ),
            (a.textures.len() * 4) as u64,
        )?;
        let turn = std::f32::consts::TAU * a.inv_delta;
        let params = FarUniform {
            dims: [
                a.radii.len() as u32,
                TEXTURE_SIZE as u32,
                a.blocks_x as u32,
                BLOCK_PX as u32,
            ],
            misc: [a.inv_delta, a.spacing_m, a.near_m, a.reflectance],
            shear: [a.shear[0], a.shear[1], FAR_MAX_TAN, turn],
            extra: [a.opacity_scale, 0.0, 0.0, 0.0],
        };
        let cam_buf = f.uniform("camera", &CameraUniform::new(f.cam));
        let params_buf = f.uniform("far rain", &params);
        let radii = f.upload("far radii", a.radii);
        let offsets = f.upload("far offsets", a.offsets);
        let textures = f.upload("far textures", a.textures);
        let lights = f.upload("far lights", &a.lights);
        f.dispatch(
            &self.0,
            &[
                &cam_buf,
                &params_buf,
                &radii,
                &offsets,
                &textures,
                &lights,
                t.rgb,
                t.depth,
                coverage,
                rain_depth,
            ],
        );
        f.hold([cam_buf, params_buf, radii, offsets, textures, lights]);
        Ok(())
    }
}
