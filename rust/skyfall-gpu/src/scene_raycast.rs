//! The box-scene pass: radiance and depth per pixel (`shaders/scene_raycast.wgsl`).

use crate::camera::camera_words;
use crate::context::GpuContext;
use crate::pass::{Binding, ComputePass, storage_init, uniform};
use skyfall_core::scene::boxes::{BoxScene, SceneLight};
use skyfall_core::scene::camera::Camera;
use skyfall_core::sky::cie::SkyKind;

const SOURCE: &str = include_str!("shaders/scene_raycast.wgsl");

/// The compiled pass.
#[derive(Debug)]
pub struct SceneRaycastPass(ComputePass);

impl SceneRaycastPass {
    /// Compiles the pass.
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        SceneRaycastPass(ComputePass::new(
            ctx,
            "scene_raycast",
            SOURCE,
            &[
                Uniform, Uniform, ReadOnly, ReadWrite, ReadWrite, Uniform, Uniform, ReadOnly,
                ReadOnly,
            ],
        ))
    }

    /// Records the pass writing `rgb` (H·W·3) and `depth` (H·W).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        scene: &BoxScene,
        cam: &Camera,
        light: &SceneLight<'_>,
        rgb: &wgpu::Buffer,
        depth: &wgpu::Buffer,
    ) {
        let g = scene.ground_albedo;
        let mut info = [g.x.to_bits(), g.y.to_bits(), g.z.to_bits(), 0, 0, 0, 0, 0];
        info[4] = scene.boxes.len() as u32;
        info[5] = u32::from(scene.ground);
        let mut boxes: Vec<f32> = Vec::with_capacity(12 * scene.boxes.len().max(1));
        for b in &scene.boxes {
            for v in [b.min_m, b.max_m, b.albedo] {
                boxes.extend_from_slice(&[v.x, v.y, v.z, 0.0]);
            }
        }
        if boxes.is_empty() {
            boxes.resize(12, 0.0); // a binding may not be empty; counts.x = 0 keeps it unread
        }
        let (p, sun) = light.sky.kind.params();
        let kind = if matches!(light.sky.kind, SkyKind::Overcast) {
            0.0
        } else {
            1.0
        };
        let p = if kind == 0.0 { [0.0; 5] } else { p };
        let sky: [f32; 12] = [
            p[0],
            p[1],
            p[2],
            p[3],
            p[4],
            light.sky.scale.min(skyfall_core::sky::SKY_PIXEL_MAX) as f32,
            kind,
            0.0,
            sun.x,
            sun.y,
            sun.z,
            0.0,
        ];
        let m = light.ambient;
        let o = m.origin_m;
        let mut amb = [
            o.x.to_bits(),
            o.y.to_bits(),
            o.z.to_bits(),
            m.spacing_m.to_bits(),
            0,
            0,
            0,
            0,
        ];
        for k in 0..3 {
            amb[4 + k] = m.dims[k] as u32;
        }
        let sky_buf = uniform(ctx, "sky", &sky.map(f32::to_bits));
        let amb_buf = uniform(ctx, "ambient", &amb);
        let amb_values = storage_init(ctx, "ambient_values", &m.values);
        let amb_solid = storage_init(ctx, "ambient_solid", &m.solid);
        let cam_buf = uniform(ctx, "camera", &camera_words(cam));
        let info_buf = uniform(ctx, "scene", &info);
        let box_buf = storage_init(ctx, "boxes", &boxes);
        self.0.encode(
            ctx,
            enc,
            &[
                &cam_buf,
                &info_buf,
                &box_buf,
                rgb,
                depth,
                &sky_buf,
                &amb_buf,
                &amb_values,
                &amb_solid,
            ],
            cam.width,
            cam.height,
        );
    }
}
