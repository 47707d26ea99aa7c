//! The haze pass: attenuation and airlight along view rays (`shaders/haze.wgsl`).

use crate::camera::camera_words;
use crate::context::GpuContext;
use crate::pass::{Binding, ComputePass, uniform};
use skyfall_core::haze::Haze;
use skyfall_core::scene::camera::Camera;

const SOURCE: &str = include_str!("shaders/haze.wgsl");

/// The compiled pass.
#[derive(Debug)]
pub struct HazePass(ComputePass);

impl HazePass {
    /// Compiles the pass.
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        HazePass(ComputePass::new(
            ctx,
            "haze",
            SOURCE,
            &[Uniform, Uniform, ReadWrite, ReadOnly, ReadWrite],
        ))
    }

    /// Records the pass over `[rgb, depth, transmittance]`: rgb in place, transmittance
    /// written, from depth.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        haze: &Haze,
        cam: &Camera,
        targets: [&wgpu::Buffer; 3],
    ) {
        let [rgb, depth, transmittance] = targets;
        let a = haze.airlight;
        let words = [
            haze.extinction_per_m.to_bits(),
            0,
            0,
            0,
            a[0].to_bits(),
            a[1].to_bits(),
            a[2].to_bits(),
            0,
        ];
        let cam_buf = uniform(ctx, "camera", &camera_words(cam));
        let haze_buf = uniform(ctx, "haze", &words);
        self.0.encode(
            ctx,
            enc,
            &[&cam_buf, &haze_buf, rgb, depth, transmittance],
            cam.width,
            cam.height,
        );
    }
}
