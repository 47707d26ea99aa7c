//! A photo's wet stage (`shaders/wet_photo.wgsl`): after the photo is uploaded, each surface's
//! film darkens it and mirrors what a march through the depth map meets. A box scene's wet
//! stage is drawn in its scene pass ([`crate::scene_raycast`]), where its mirror rays are cast.

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::uniforms::{BoxElement, CameraUniform, LightElement, WetPhotoUniform};
use skyfall_core::frame::layers::Layer;
use skyfall_core::wet::stage::{WetGpu, WetPhotoGpu};
use std::sync::OnceLock;

const SOURCE: &str = include_str!("shaders/wet_photo.wgsl");
const GRAIN: &str = include_str!("shaders/wet_grain.wgsl");

/// The pass and its grain's denoising (`shaders/wet_grain.wgsl`), compiled at the first wet
/// photo (a renderer that draws none pays nothing).
#[derive(Debug, Default)]
pub struct WetPhotoPass(OnceLock<(ComputePass, ComputePass)>);

impl FramePass for WetPhotoPass {
    /// The film, and the photo's own inputs.
    type Input<'i> = (WetGpu, WetPhotoGpu<'i>);

    fn new(_ctx: &GpuContext) -> Self {
        WetPhotoPass(OnceLock::new())
    }

    /// rgb in place and the wetness written, from depth (and the snow cover's depth).
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        (wet, photo): Self::Input<'_>,
    ) -> Result<(), GpuError> {
        use Binding::*;
        let (pass, grain_pass) = self.0.get_or_init(|| {
            (
                ComputePass::new(
                    f.ctx,
                    "wet_photo",
                    SOURCE,
                    &[
                        Uniform, Uniform, ReadOnly, ReadOnly, ReadWrite, ReadWrite, ReadOnly,
                        ReadOnly, ReadOnly, ReadWrite, ReadWrite,
                    ],
                ),
                ComputePass::new(f.ctx, "wet_grain", GRAIN, &[Uniform, ReadOnly, ReadWrite]),
            )
        });
        f.ctx
            .check_buffer("the photo", (photo.rgb.len() * 4) as u64)?;
        let v = |a: glam::Vec3| [a.x, a.y, a.z, 0.0];
        let boxes = BoxElement::list(photo.shelter);
        let lights = LightElement::list(photo.lamps);
        let wet_layer = t.layers.get(Layer::Wetness);
        let snow = t.layers.get(Layer::SnowDepth);
        let puddle_layer = t.layers.get(Layer::PuddleMask);
        let mut relief = [[0.0f32; 4]; 9];
        for (k, q) in skyfall_core::wet::puddles::relief_quantiles()
            .iter()
            .enumerate()
        {
            relief[k / 4][k % 4] = *q;
        }
        let block = WetPhotoUniform {
            dirs: wet.directions.map(v),
            film: [wet.mm_per_exposure.unwrap_or(-1.0), wet.dried_mm, 0.0, 0.0],
            optics: [
                wet.darkening_numerator,
                wet.internal_reflectance,
                photo.inv_sky_lux,
                0.0,
            ],
            sky: v(photo.sky),
            counts: [
                if wet.sheltered {
                    photo.shelter.len() as u32
                } else {
                    0
                },
                photo.lamps.len() as u32,
                u32::from(snow.is_some()),
                u32::from(wet_layer.is_some()),
            ],
            flags: [u32::from(puddle_layer.is_some()), 0, 0, 0],
            relief,
        };
        let dummy = f.target("wet_dummy", 1);
        let grain = f.target("wet grain", 4 * (f.cam.width * f.cam.height) as usize);
        let buffers = [
            f.uniform("camera", &CameraUniform::new(f.cam)),
            f.uniform("wet_photo", &block),
            f.upload("photo", photo.rgb),
            f.upload("occluders", &boxes),
            f.upload("lights", &lights),
        ];
        let [cam, info, rgb, occluders, lights] = &buffers;
        f.dispatch(
            pass,
            &[
                cam,
                info,
                rgb,
                t.depth,
                t.rgb,
                wet_layer.unwrap_or(&dummy),
                occluders,
                lights,
                snow.unwrap_or(&dummy),
                puddle_layer.unwrap_or(&dummy),
                &grain,
            ],
        );
        let params = f.uniform(
            "wet grain params",
            &[f.cam.width, f.cam.height, wet.grain_radius_px as u32, 0],
        );
        f.dispatch(grain_pass, &[&params, &grain, t.rgb]);
        f.hold(buffers);
        f.hold([dummy, grain, params]);
        Ok(())
    }
}
