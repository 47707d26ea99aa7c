//! The glow pass: the lights' emitter discs and glows added to the hazed frame
//! (`shaders/glow.wgsl`; CPU reference `skyfall_core::glow`).

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::uniforms::{CameraUniform, GlowElement, GlowUniform};
use skyfall_core::glow::{Glow, ORDERS};

const SOURCE: &str = include_str!("shaders/glow.wgsl");

/// The compiled pass.
#[derive(Debug)]
pub struct GlowPass(ComputePass);

impl FramePass for GlowPass {
    /// The frame's visible sources.
    type Input<'i> = &'i Glow;

    fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        GlowPass(ComputePass::new(
            ctx,
            "glow",
            SOURCE,
            &[Uniform, Uniform, ReadOnly, ReadWrite],
        ))
    }

    /// rgb in place.
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        glow: &Glow,
    ) -> Result<(), GpuError> {
        const _: () = assert!(ORDERS == 6, "GlowElement packs six orders");
        f.ctx.check_buffer(
            "the lights in view",
            (glow.sources.len() * size_of::<GlowElement>()) as u64,
        )?;
        let sources: Vec<GlowElement> = glow
            .sources
            .iter()
            .map(|s| {
                let (w, g): (Vec<f32>, Vec<f32>) = s.orders.iter().copied().unzip();
                GlowElement {
                    dir_cut: [s.dir.x, s.dir.y, s.dir.z, s.cut_chord],
                    flux_radius: [s.flux.x, s.flux.y, s.flux.z, s.disc_radius],
                    disc: [s.disc.x, s.disc.y, s.disc.z, 0.0],
                    weights_a: [w[0], w[1], w[2], w[3]],
                    weights_b: [w[4], w[5], 0.0, 0.0],
                    asym_a: [g[0], g[1], g[2], g[3]],
                    asym_b: [g[4], g[5], 0.0, 0.0],
                }
            })
            .collect();
        let block = GlowUniform {
            params: [glow.pixel_rad, 0.0, 0.0, 0.0],
            counts: [sources.len() as u32, 0, 0, 0],
        };
        let buffers = [
            f.uniform("camera", &CameraUniform::new(f.cam)),
            f.uniform("glow", &block),
            f.upload("glow_sources", &sources),
        ];
        let [cam, params, list] = &buffers;
        f.dispatch(&self.0, &[cam, params, list, t.rgb]);
        f.hold(buffers);
        Ok(())
    }
}
