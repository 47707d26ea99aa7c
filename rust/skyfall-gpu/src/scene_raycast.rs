//! The box-scene pass: radiance and depth per pixel (`shaders/scene_raycast.wgsl`).

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::pool::Pooled;
use crate::uniforms::{
    AmbientUniform, BoxElement, CameraUniform, LampUniform, LightElement, SceneUniform, SkyUniform,
    SnowUniform, SunUniform, VolumeUniform,
};
use skyfall_core::frame::layers::Layer;
use skyfall_core::frame::scene::SceneLight;
use skyfall_core::scene::boxes::BoxScene;
use skyfall_core::sky::cie::SkyKind;
use std::sync::OnceLock;

const SOURCE: &str = include_str!("shaders/scene_raycast.wgsl");

/// The compiled pass, twice: with the lights' code (and the sky's colour), and without it
/// (`LIT = false`) for scenes without lights, a sun or a sky in colour, so that an effect
/// switched off costs nothing (on lavapipe the lit pipeline
/// made the unlit street 1.18x slower even though its light loop never ran); and both again
/// with the snow cover's code (`SNOW = true`), for frames with a cover. The wet stage of a box
/// scene takes three more of this shader's pipelines, compiled at the first wet frame, around
/// `shaders/wet_film.wgsl` (`crate::wet`): `wet_face` (each pixel's face), `wet_lights` (the
/// highlights) and `main` with `MIRROR = true` (the mirror rays cast and lit as view rays are),
/// lit and unlit. Fewer, larger pipelines made lavapipe's compiler (Mesa 22.3) write into
/// freed memory (valgrind's memcheck, in vkCreateComputePipelines); these compile cleanly.
#[derive(Debug)]
pub struct SceneRaycastPass {
    lit: ComputePass,
    unlit: ComputePass,
    lit_snow: ComputePass,
    unlit_snow: ComputePass,
    /// `wet_face`, `wet_lights`, then `main` with `MIRROR` lit and unlit.
    wet: OnceLock<[ComputePass; 4]>,
}

/// Which of the pass's pipelines a recording takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    /// The scene (`main`).
    Scene,
    /// Each pixel's face for the wet stage (`wet_face`).
    Face,
    /// The wet surfaces' highlights (`wet_lights`).
    Lights,
    /// The wet stage's mirror rays cast (`main`, `MIRROR`).
    Mirror,
}

/// The pass's bindings, in the order of `shaders/scene_raycast.wgsl`.
const BINDINGS: [Binding; 19] = {
    use Binding::*;
    [
        Uniform, Uniform, ReadOnly, ReadWrite, ReadWrite, Uniform, Uniform, ReadOnly, ReadOnly,
        Uniform, ReadOnly, Uniform, ReadOnly, ReadWrite, Uniform, ReadOnly, ReadWrite, ReadWrite,
        ReadWrite,
    ]
};

/// `main` compiled with its constants.
fn compile(ctx: &GpuContext, lit: bool, snow: bool, mirror: bool) -> ComputePass {
    let b = |v: bool| if v { 1.0 } else { 0.0 };
    ComputePass::with_constants(
        ctx,
        "scene_raycast",
        SOURCE,
        &BINDINGS,
        &[("LIT", b(lit)), ("SNOW", b(snow)), ("MIRROR", b(mirror))],
    )
}

/// The wet stage's entry point `entry` (with the lights' code).
fn compile_wet(ctx: &GpuContext, entry: &str) -> ComputePass {
    ComputePass::with_entry(
        ctx,
        "scene_raycast wet",
        SOURCE,
        &BINDINGS,
        &[("LIT", 1.0)],
        entry,
    )
}

impl FramePass for SceneRaycastPass {
    /// The box scene and its light (sky, ambient-light map, lights).
    type Input<'i> = (&'i BoxScene, &'i SceneLight<'i>);

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
        (scene, light): Self::Input<'_>,
    ) -> Result<(), GpuError> {
        self.record(f, t, scene, light, Stage::Scene, None, None)
    }
}

impl SceneRaycastPass {
    /// The wet stage over the frame [`FramePass::encode`] drew: each pixel's face
    /// (`wet_face`) into a buffer that `film` (`crate::wet::WetPass::film`) makes the mirror
    /// rays of, whose highlights (`wet_lights`, lit frames) and radiance (`main` with
    /// `MIRROR`) are then drawn. Returns the film's grained image per pixel (w·F·seen, depth;
    /// depth −1 where none) for its row averaging.
    pub fn encode_wet(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        (scene, light): (&BoxScene, &SceneLight<'_>),
        film: impl FnOnce(&mut FrameEncoder<'_>, &Pooled) -> Result<Pooled, GpuError>,
    ) -> Result<Pooled, GpuError> {
        let n = (f.cam.width * f.cam.height) as usize;
        let faces = f.target("wet faces", 12 * n);
        self.record(f, t, scene, light, Stage::Face, None, Some(&faces))?;
        let rays = film(f, &faces)?;
        let grain = f.target("wet grain", 4 * n);
        if !(light.lights.is_empty() && light.sun.is_none()) {
            self.record(f, t, scene, light, Stage::Lights, None, Some(&rays))?;
        }
        self.record(f, t, scene, light, Stage::Mirror, Some(&grain), Some(&rays))?;
        f.hold([faces, rays]);
        Ok(grain)
    }

    /// Records `stage`'s pipeline with the wet stage's `grain` and `rays` buffers where given.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        scene: &BoxScene,
        light: &SceneLight<'_>,
        stage: Stage,
        grain: Option<&Pooled>,
        rays: Option<&Pooled>,
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
        let lc = light.sky.light_colour;
        let (colour_sun, model) = match &light.sky.colour {
            Some(c) => {
                let mut m = [0.0f32; 32];
                m[..27].copy_from_slice(&c.params);
                m[27..30].copy_from_slice(&c.radiances);
                m[30] = c.saturation;
                let model: [[f32; 4]; 8] =
                    std::array::from_fn(|i| [m[4 * i], m[4 * i + 1], m[4 * i + 2], m[4 * i + 3]]);
                ([c.sun.x, c.sun.y, c.sun.z, 0.0], model)
            }
            None => ([0.0, 1.0, 0.0, 0.0], [[0.0; 4]; 8]),
        };
        let sky = SkyUniform {
            abcd: [p[0], p[1], p[2], p[3]],
            e_scale: [p[4], scale, kind, 0.0],
            sun: [sun.x, sun.y, sun.z, 0.0],
            colour: [
                lc.x,
                lc.y,
                lc.z,
                f32::from(u8::from(light.sky.colour.is_some())),
            ],
            colour_sun,
            model,
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
                let grid = r.gpu_grid();
                let (g, dims) = (grid.params, grid.dims);
                f.ctx
                    .check_buffer("the snow cover", (grid.base.len() * 16) as u64)?;
                let cells: Vec<[f32; 4]> = grid
                    .base
                    .iter()
                    .zip(grid.depth)
                    .zip(grid.slope)
                    .map(|((&b, &d), &[gx, gz])| [b, d, gx, gz])
                    .collect();
                let info = SnowUniform {
                    grid: [g[0], g[1], g[2], r.open_depth_m()],
                    range: [
                        g[3],
                        g[4],
                        skyfall_core::snow::SNOW_ALBEDO,
                        skyfall_core::snow::cover::look::COVER_FULL_M,
                    ],
                    dims: [dims[0], dims[1], 0, 0],
                    relief: crate::uniforms::relief_quantiles(),
                };
                (info, cells)
            }
            None => (SnowUniform::default(), vec![[0.0f32; 4]]),
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
                colour: [s.colour.x, s.colour.y, s.colour.z, 0.0],
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
        // The wet stage's buffers (four floats: both hold vec4s).
        let wet_dummy = f.target("wet_dummy", 4);
        let grain_out = grain.unwrap_or(&wet_dummy);
        let rays = rays.unwrap_or(&wet_dummy);
        // A sky in colour takes the lit pipelines too (they alone have its code).
        let unlit = light.lights.is_empty() && light.sun.is_none() && light.sky.colour.is_none();
        let wet_pass = |k: usize| {
            let passes = self.wet.get_or_init(|| {
                [
                    compile_wet(f.ctx, "wet_face"),
                    compile_wet(f.ctx, "wet_lights"),
                    compile(f.ctx, true, false, true),
                    compile(f.ctx, false, false, true),
                ]
            });
            &passes[k]
        };
        let pass = match stage {
            Stage::Face => wet_pass(0),
            Stage::Lights => wet_pass(1),
            Stage::Mirror => wet_pass(2 + usize::from(unlit)),
            Stage::Scene => {
                let variant = match (unlit, light.snow.is_some()) {
                    (false, false) => 0,
                    (true, false) => 1,
                    (false, true) => 2,
                    (true, true) => 3,
                };
                [&self.lit, &self.unlit, &self.lit_snow, &self.unlit_snow][variant]
            }
        };
        f.dispatch(
            pass,
            &[
                cam, info, boxes, t.rgb, t.depth, sky, amb, values, solid, lamps, lights, snow,
                cells, snow_out, &sun_info, &sun_gamma, sun_out, grain_out, rays,
            ],
        );
        f.hold(buffers);
        f.hold([snow_dummy, sun_info, sun_gamma, sun_dummy, wet_dummy]);
        Ok(())
    }
}
