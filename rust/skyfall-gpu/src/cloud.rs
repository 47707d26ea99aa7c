//! The cloud pass: the clouds' splats composited over the frame (`shaders/cloud.wgsl`), after
//! the scene and before the haze. The splats are sorted and binned on the CPU
//! ([`CloudSplats::prepare`], as the particles are), the volumes uploaded as they are.

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::uniforms::{CameraUniform, CloudUniform, VolumeUniform};
use skyfall_core::cloud::frame::{CloudSplats, TILE_PX};
use skyfall_core::frame::layers::Layer;

const SOURCE: &str = include_str!("shaders/cloud.wgsl");

/// The compiled pass.
#[derive(Debug)]
pub struct CloudPass(ComputePass);

impl FramePass for CloudPass {
    /// The frame's splats.
    type Input<'i> = &'i CloudSplats<'i>;

    fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        CloudPass(ComputePass::new(
            ctx,
            "cloud",
            SOURCE,
            &[
                Uniform, Uniform, ReadOnly, ReadOnly, ReadOnly, ReadOnly, ReadWrite, ReadOnly,
                ReadWrite,
            ],
        ))
    }

    /// rgb in place, `cloud_alpha` written when the frame has the layer.
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        s: &CloudSplats<'_>,
    ) -> Result<(), GpuError> {
        f.ctx
            .check_buffer("the clouds' tile lists", (s.indices.len() * 4) as u64)?;
        // Both volumes in one buffer, the zenith's first (the shader reads each from its offset).
        let sun_gamma = s.sun.as_ref().map_or(&[][..], |(_, v)| v.gamma);
        let zenith_len = s.zenith.gamma.len();
        f.ctx.check_buffer(
            "the clouds' volumes",
            ((zenith_len + sun_gamma.len()) * 4) as u64,
        )?;
        let sun_offset = u32::try_from(zenith_len).map_err(|_| GpuError::TooLarge {
            what: "the clouds' zenith volume, as a u32 offset".to_string(),
            bytes: (zenith_len * 4) as u64,
            limit: u64::from(u32::MAX) * 4,
        })?;
        // (each splat's distance from the camera in its second pad: the pass's early end)
        let mut packed: Vec<[f32; 8]> = s
            .splats
            .iter()
            .zip(&s.distances)
            .map(|(p, &dist)| {
                let mut a = p.packed();
                a[6] = dist;
                a
            })
            .collect();
        if packed.is_empty() {
            packed.push([0.0; 8]); // a binding may not be empty; the tile lists are empty
        }
        let mut indices = s.indices.clone();
        if indices.is_empty() {
            indices.push(0);
        }
        let (sun_dir, sun_view) = match &s.sun {
            Some((d, v)) => ([d.x, d.y, d.z, s.g], Some(v)),
            None => ([0.0, 1.0, 0.0, s.g], None),
        };
        let l = s.light;
        let block = CloudUniform {
            counts: [
                s.tiles_x,
                TILE_PX,
                u32::from(sun_view.is_some()),
                u32::from(t.layers.get(Layer::CloudAlpha).is_some()),
            ],
            sun_g: sun_dir,
            sun_light: [l.sun.x, l.sun.y, l.sun.z, if s.diffuse { 1.0 } else { 0.0 }],
            sky_light: [l.sky.x, l.sky.y, l.sky.z, s.reach_m],
            sun_volume: VolumeUniform::new(sun_view, sun_offset),
            zenith_volume: VolumeUniform::new(Some(&s.zenith), 0),
        };
        let dummy = f.target("cloud_dummy", 1);
        let alpha = match t.layers.get(Layer::CloudAlpha) {
            Some(a) => a,
            None => &dummy,
        };
        let buffers = [
            f.uniform("camera", &CameraUniform::new(f.cam)),
            f.uniform("cloud", &block),
            f.upload("cloud_splats", &packed),
            f.upload("cloud_offsets", &s.offsets),
            f.upload("cloud_indices", &indices),
            f.upload_parts("cloud_gammas", &[s.zenith.gamma, sun_gamma]),
        ];
        let [cam, info, splats, offsets, idx, gammas] = &buffers;
        f.dispatch(
            &self.0,
            &[
                cam, info, splats, offsets, idx, gammas, t.rgb, t.depth, alpha,
            ],
        );
        f.hold(buffers);
        f.hold([dummy]);
        Ok(())
    }
}
