//! The box-scene pass: radiance and depth per pixel (`shaders/scene_raycast.wgsl`).

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::uniforms::{
    AmbientUniform, BoxElement, CameraUniform, LampUniform, LightElement, SceneUniform, SkyUniform,
    SnowUniform, SunUniform, VolumeUniform, WetUniform,
};
use skyfall_core::frame::layers::Layer;
use skyfall_core::frame::scene::SceneLight;
use skyfall_core::scene::boxes::BoxScene;
use skyfall_core::sky::cie::SkyKind;
use skyfall_core::wet::stage::WetGpu;
use std::sync::OnceLock;

const SOURCE: &str = include_str!("shaders/scene_raycast.wgsl");

/// The compiled pass, twice: with the lights' code, and without it (`LIT = false`) for scenes
/// without lights, so that an effect switched off costs nothing (on lavapipe the lit pipeline
/// made the unlit street 1.18x slower even though its light loop never ran); and both again
/// with the snow cover's code (`SNOW = true`), for frames with a cover; the four again with
/// the wet stage's code (`WET = true`), compiled at the first wet frame.
#[derive(Debug)]
pub struct SceneRaycastPass {
    lit: ComputePass,
    unlit: ComputePass,
    lit_snow: ComputePass,
    unlit_snow: ComputePass,
    /// lit, unlit, lit_snow, unlit_snow with `WET = true`.
    wet: OnceLock<[ComputePass; 4]>,
}

/// The pass's bindings, in the order of `shaders/scene_raycast.wgsl`.
const BINDINGS: [Binding; 19] = {
    use Binding::*;
    [
        Uniform, Uniform, ReadOnly, ReadWrite, ReadWrite, Uniform, Uniform, ReadOnly, ReadOnly,
        Uniform, ReadOnly, Uniform, ReadOnly, ReadWrite, Uniform, ReadOnly, ReadWrite, Uniform,
        ReadWrite,
    ]
};

/// The pass compiled with its constants.
fn compile(ctx: &GpuContext, lit: bool, snow: bool, wet: bool) -> ComputePass {
    let b = |v: bool| if v { 1.0 } else { 0.0 };
    ComputePass::with_constants(
        ctx,
        "scene_raycast",
        SOURCE,
        &BINDINGS,
        &[("LIT", b(lit)), ("SNOW", b(snow)), ("WET", b(wet))],
    )
}

impl FramePass for SceneRaycastPass {
    /// The box scene, its light (sky, ambient-light map, lights) and its wet surfaces.
    type Input<'i> = (&'i BoxScene, &'i SceneLight<'i>, Option<WetGpu>);

    fn new(ctx: &GpuContext) -> Self {
        SceneRaycastPass {
            lit: compile(ctx, true, false, false),
            unlit: compile(ctx, false, false, false),
            lit_snow: compile(ctx, true, true, false),
            unlit_snow: compile(ctx, false, true, false),
            wet: OnceLock::new(),
        }
    }

    /// Writes rgb (H·W·3) and depth (H·W).
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        (scene, light, wet): Self::Input<'_>,
    ) -> Result<(), GpuError> {
        f.ctx.check_buffer(
            "the ambient-light map",
            (light.ambient.values.len() * 4) as u64,
        )?;
        let g = scene.ground_albedo;
        let info = SceneUniform {
            ground_albedo: [g.x, g.y, g.z, 0.0],
            counts: [scene.boxes.len() as u32, u32::from(scene.ground), 0, 0],
        };
        let boxes = BoxElement::list(&scene.boxes);
        let (p, sun) = light.sky.kind.params();
        let kind = if matches!(light.sky.kind, SkyKind::Overcast) {
            0.0
        } else {
            1.0
        };
        let p = if kind == 0.0 { [0.0; 5] } else { p };
        let scale = light.sky.scale as f32;
        let sky = SkyUniform {
            abcd: [p[0], p[1], p[2], p[3]],
            e_scale: [p[4], scale, kind, 0.0],
            sun: [sun.x, sun.y, sun.z, 0.0],
        };
        let m = light.ambient;
        let o = m.origin_m;
        let amb = AmbientUniform {
            origin_spacing: [o.x, o.y, o.z, m.spacing_m],
            dims: [m.dims[0] as u32, m.dims[1] as u32, m.dims[2] as u32, 0],
        };
        let lamps = LampUniform {
            params: [
                1.0 / light.sky_illuminance_lux,
                skyfall_core::frame::scene::SHADOW_SKIP_RELATIVE,
                0.0,
                0.0,
            ],
            counts: [light.lights.len() as u32, 0, 0, 0],
        };
        f.ctx.check_buffer(
            "the lights",
            (light.lights.len() * size_of::<LightElement>()) as u64,
        )?;
        let lights = LightElement::list(light.lights);
        // The snow cover's grid (a cell of none where the frame has no cover: its pipeline
        // does not read them).
        let (snow_info, cells) = match light.snow {
            Some(r) => {
                let (g, dims, base, depth) = r.gpu_grid();
                f.ctx
                    .check_buffer("the snow cover", (base.len() * 8) as u64)?;
                let cells: Vec<[f32; 2]> = base.iter().zip(depth).map(|(&b, &d)| [b, d]).collect();
                let info = SnowUniform {
                    grid: [g[0], g[1], g[2], r.open_depth_m()],
                    range: [
                        g[3],
                        g[4],
                        skyfall_core::snow::SNOW_ALBEDO,
                        skyfall_core::snow::cover::render::COVER_EFOLD_M,
                    ],
                    dims: [dims[0], dims[1], 0, 0],
                };
                (info, cells)
            }
            None => (SnowUniform::default(), vec![[0.0f32; 2]]),
        };
        let snow_dummy = f.target("snow_dummy", 1);
        let snow_out = match light.snow {
            Some(_) => t.layer(Layer::SnowDepth)?,
            None => &snow_dummy,
        };
        // The sun (its code is in the lit pipelines, which a frame with a sun takes).
        let sun_block = match &light.sun {
            Some(s) => SunUniform {
                dir: [s.direction.x, s.direction.y, s.direction.z, s.relative],
                flags: [
                    1,
                    u32::from(s.clouds.is_some()),
                    u32::from(t.layers.get(Layer::SunTransmittance).is_some()),
                    0,
                ],
                volume: VolumeUniform::new(s.clouds.as_ref(), 0),
            },
            None => SunUniform::default(),
        };
        let sun_gamma = match light.sun.as_ref().and_then(|s| s.clouds.as_ref()) {
            Some(v) => {
                f.ctx
                    .check_buffer("the clouds' volume", (v.gamma.len() * 4) as u64)?;
                f.upload("sun_gamma", v.gamma)
            }
            None => f.upload("sun_gamma", &[1.0f32]),
        };
        let sun_dummy = f.target("sun_dummy", 1);
        let sun_out = match t.layers.get(Layer::SunTransmittance) {
            Some(b) => b,
            None => &sun_dummy,
        };
        let sun_info = f.uniform("sun", &sun_block);
        let buffers = [
            f.uniform("camera", &CameraUniform::new(f.cam)),
            f.uniform("scene", &info),
            f.upload("boxes", &boxes),
            f.uniform("sky", &sky),
            f.uniform("ambient", &amb),
            f.upload("ambient_values", &m.values),
            f.upload("ambient_solid", &m.solid),
            f.uniform("lamps", &lamps),
            f.upload("lights", &lights),
            f.uniform("snow", &snow_info),
            f.upload("snow_cells", &cells),
        ];
        let [
            cam,
            info,
            boxes,
            sky,
            amb,
            values,
            solid,
            lamps,
            lights,
            snow,
            cells,
        ] = &buffers;
        // The wet stage (its code in the WET pipelines, which a wet frame takes).
        let wet_layer = t.layers.get(Layer::Wetness);
        let wet_info = f.uniform(
            "wet",
            &wet.map_or(WetUniform::default(), |w| {
                WetUniform::new(&w, wet_layer.is_some())
            }),
        );
        let wet_dummy = f.target("wet_dummy", 1);
        let wet_out = wet_layer.unwrap_or(&wet_dummy);
        let unlit = light.lights.is_empty() && light.sun.is_none();
        let variant = match (unlit, light.snow.is_some()) {
            (false, false) => 0,
            (true, false) => 1,
            (false, true) => 2,
            (true, true) => 3,
        };
        let pass = match wet {
            Some(_) => {
                let passes = self.wet.get_or_init(|| {
                    [
                        compile(f.ctx, true, false, true),
                        compile(f.ctx, false, false, true),
                        compile(f.ctx, true, true, true),
                        compile(f.ctx, false, true, true),
                    ]
                });
                &passes[variant]
            }
            None => [&self.lit, &self.unlit, &self.lit_snow, &self.unlit_snow][variant],
        };
        f.dispatch(
            pass,
            &[
                cam, info, boxes, t.rgb, t.depth, sky, amb, values, solid, lamps, lights, snow,
                cells, snow_out, &sun_info, &sun_gamma, sun_out, &wet_info, wet_out,
            ],
        );
        f.hold(buffers);
        f.hold([
            snow_dummy, sun_info, sun_gamma, sun_dummy, wet_info, wet_dummy,
        ]);
        Ok(())
    }
}
