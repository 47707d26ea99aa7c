//! The wet stage's passes: a photo's (`shaders/wet_photo.wgsl`: after the photo is uploaded,
//! each surface's film darkens it and mirrors what a march through the depth map meets), and
//! the row averaging of the film's grained image (`shaders/wet_grain.wgsl`), which follows it
//! and a box scene's wet stage (the scene pass's second entry point,
//! [`crate::scene_raycast::SceneRaycastPass::encode_wet`], where the mirror rays are cast).

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::pool::Pooled;
use crate::uniforms::{BoxElement, CameraUniform, LightElement, WetPhotoUniform, WetUniform};
use skyfall_core::frame::layers::Layer;
use skyfall_core::scene::boxes::SceneBox;
use skyfall_core::wet::stage::{WetGpu, WetPhotoGpu};
use std::sync::OnceLock;

const SOURCE: &str = include_str!("shaders/wet_photo.wgsl");
const FILM: &str = include_str!("shaders/wet_film.wgsl");
const GRAIN: &str = include_str!("shaders/wet_grain.wgsl");

/// The photo's pass, a box scene's film and the grain's averaging, each compiled at its first
/// use (a renderer that draws no wet frame pays nothing).
#[derive(Debug, Default)]
pub struct WetPass {
    photo: OnceLock<ComputePass>,
    film: OnceLock<ComputePass>,
    grain: OnceLock<ComputePass>,
}

impl WetPass {
    /// A box scene's film (`shaders/wet_film.wgsl`) at each pixel's face in `faces` (the scene
    /// pass's `wet_face`), the rain kept off by `shelter`: rgb darkened, `wetness` and
    /// `puddle_mask` written; returns the mirror rays (three vec4 per pixel) for the scene
    /// pass's `wet_lights` and `MIRROR`.
    pub fn film(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        wet: &WetGpu,
        shelter: &[SceneBox],
        faces: &Pooled,
    ) -> Result<Pooled, GpuError> {
        use Binding::*;
        let pass = self.film.get_or_init(|| {
            ComputePass::new(
                f.ctx,
                "wet_film",
                FILM,
                &[
                    Uniform, Uniform, ReadOnly, ReadOnly, ReadOnly, ReadOnly, ReadWrite, ReadWrite,
                    ReadWrite, ReadWrite,
                ],
            )
        });
        f.ctx.check_buffer(
            "the boxes",
            (shelter.len() * size_of::<BoxElement>()) as u64,
        )?;
        let wet_layer = t.layers.get(Layer::Wetness);
        let puddle_layer = t.layers.get(Layer::PuddleMask);
        let snow = t.layers.get(Layer::SnowDepth);
        let block = WetUniform::new(
            wet,
            shelter.len(),
            wet_layer.is_some(),
            puddle_layer.is_some(),
            snow.is_some(),
        );
        let dummy = f.target("wet_dummy", 1);
        let rays = f.target(
            "wet mirror rays",
            12 * (f.cam.width * f.cam.height) as usize,
        );
        let buffers = [
            f.uniform("camera", &CameraUniform::new(f.cam)),
            f.uniform("wet", &block),
            f.upload("boxes", &BoxElement::list(shelter)),
        ];
        let [cam, info, boxes] = &buffers;
        f.dispatch(
            pass,
            &[
                cam,
                info,
                boxes,
                faces,
                t.depth,
                snow.unwrap_or(&dummy),
                t.rgb,
                &rays,
                wet_layer.unwrap_or(&dummy),
                puddle_layer.unwrap_or(&dummy),
            ],
        );
        f.hold(buffers);
        f.hold([dummy]);
        Ok(rays)
    }

    /// Adds to rgb each pixel's film image averaged along its row over `radius_px` each side
    /// (`skyfall_core::wet::stage::denoise_grain`), from `grain` (w·F·seen and depth per pixel,
    /// depth −1 where none), which it takes.
    pub fn denoise(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        grain: Pooled,
        radius_px: usize,
    ) {
        use Binding::*;
        let pass = self.grain.get_or_init(|| {
            ComputePass::new(f.ctx, "wet_grain", GRAIN, &[Uniform, ReadOnly, ReadWrite])
        });
        let params = f.uniform(
            "wet grain params",
            &[f.cam.width, f.cam.height, radius_px as u32, 0],
        );
        f.dispatch(pass, &[&params, &grain, t.rgb]);
        f.hold([grain, params]);
    }
}

impl FramePass for WetPass {
    /// The film, and the photo's own inputs.
    type Input<'i> = (WetGpu, WetPhotoGpu<'i>);

    fn new(_ctx: &GpuContext) -> Self {
        WetPass::default()
    }

    /// rgb in place and the wetness written, from depth (and the snow cover's depth).
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        (wet, photo): Self::Input<'_>,
    ) -> Result<(), GpuError> {
        use Binding::*;
        let pass = self.photo.get_or_init(|| {
            ComputePass::new(
                f.ctx,
                "wet_photo",
                SOURCE,
                &[
                    Uniform, Uniform, ReadOnly, ReadOnly, ReadWrite, ReadWrite, ReadOnly, ReadOnly,
                    ReadOnly, ReadWrite, ReadWrite,
                ],
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
            relief: crate::uniforms::relief_quantiles(),
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
        f.hold(buffers);
        f.hold([dummy]);
        self.denoise(f, t, grain, wet.grain_radius_px);
        Ok(())
    }
}
