//! The haze pass: attenuation and airlight along view rays (`shaders/haze.wgsl`).

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::uniforms::{CameraUniform, HazeUniform};
use skyfall_core::frame::layers::Layer;
use skyfall_core::haze::Haze;

const SOURCE: &str = include_str!("shaders/haze.wgsl");

/// The compiled pass.
#[derive(Debug)]
pub struct HazePass(ComputePass);

impl FramePass for HazePass {
    /// The haze: extinction (per channel) and airlight.
    type Input<'i> = &'i Haze;

    fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        HazePass(ComputePass::new(
            ctx,
            "haze",
            SOURCE,
            &[Uniform, Uniform, ReadWrite, ReadOnly, ReadWrite],
        ))
    }

    /// rgb in place and the transmittance written, from depth.
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        haze: &Haze,
    ) -> Result<(), GpuError> {
        let transmittance = t.layer(Layer::Transmittance)?;
        let a = haze.airlight;
        let block = HazeUniform {
            params: [
                haze.extinction_per_m,
                haze.sky_ceiling_m,
                haze.spectral[0],
                haze.spectral[1],
            ],
            airlight: [a[0], a[1], a[2], 0.0],
            drawn: [
                haze.drawn[0].radius_m,
                haze.drawn[0].extinction_per_m,
                haze.drawn[1].radius_m,
                haze.drawn[1].extinction_per_m,
            ],
        };
        let cam = f.uniform("camera", &CameraUniform::new(f.cam));
        let params = f.uniform("haze", &block);
        f.dispatch(&self.0, &[&cam, &params, t.rgb, t.depth, transmittance]);
        f.hold([cam, params]);
        Ok(())
    }
}
