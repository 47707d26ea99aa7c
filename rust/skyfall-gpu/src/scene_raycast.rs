//! The box-scene pass: radiance and depth per pixel (`shaders/scene_raycast.wgsl`).

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FramePass, FrameTargets};
use crate::uniforms::{
    AmbientUniform, BoxElement, CameraUniform, LampUniform, LightElement, SceneUniform, SkyUniform,
};
use skyfall_core::frame::scene::SceneLight;
use skyfall_core::scene::boxes::BoxScene;
use skyfall_core::sky::cie::SkyKind;

const SOURCE: &str = include_str!("shaders/scene_raycast.wgsl");

/// The compiled pass, twice: with the lights' code, and without it (`LIT = false`) for scenes
/// without lights, so that an effect switched off costs nothing (on lavapipe the lit pipeline
/// made the unlit street 1.18x slower even though its light loop never ran).
#[derive(Debug)]
pub struct SceneRaycastPass {
    lit: ComputePass,
    unlit: ComputePass,
}

impl FramePass for SceneRaycastPass {
    /// The box scene and its light (sky, ambient-light map, lights).
    type Input<'i> = (&'i BoxScene, &'i SceneLight<'i>);

    fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        let bindings = [
            Uniform, Uniform, ReadOnly, ReadWrite, ReadWrite, Uniform, Uniform, ReadOnly, ReadOnly,
            Uniform, ReadOnly,
        ];
        let pass = |lit: f64| {
            ComputePass::with_constants(ctx, "scene_raycast", SOURCE, &bindings, &[("LIT", lit)])
        };
        SceneRaycastPass {
            lit: pass(1.0),
            unlit: pass(0.0),
        }
    }

    /// Writes rgb (H·W·3) and depth (H·W).
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        (scene, light): Self::Input<'_>,
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
        let v = |a: glam::Vec3| [a.x, a.y, a.z, 0.0];
        let mut boxes: Vec<BoxElement> = scene
            .boxes
            .iter()
            .map(|b| BoxElement {
                min_m: v(b.min_m),
                max_m: v(b.max_m),
                albedo: v(b.albedo),
            })
            .collect();
        if boxes.is_empty() {
            boxes.push(BoxElement::default()); // a binding may not be empty; counts.x = 0 keeps it unread
        }
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
        let mut lights: Vec<LightElement> = light.lights.iter().map(LightElement::new).collect();
        if lights.is_empty() {
            lights.push(LightElement::default()); // counts.x = 0 keeps it unread
        }
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
        ];
        let [cam, info, boxes, sky, amb, values, solid, lamps, lights] = &buffers;
        f.dispatch(
            if light.lights.is_empty() {
                &self.unlit
            } else {
                &self.lit
            },
            &[
                cam, info, boxes, t.rgb, t.depth, sky, amb, values, solid, lamps, lights,
            ],
        );
        f.hold(buffers);
        Ok(())
    }
}
