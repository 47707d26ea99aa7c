//! The box-scene pass: radiance and depth per pixel (`shaders/scene_raycast.wgsl`).

use crate::camera::camera_words;
use crate::context::GpuContext;
use crate::pass::{storage_init, uniform, Binding, ComputePass};
use skyfall_core::scene::boxes::BoxScene;
use skyfall_core::scene::camera::Camera;

const SOURCE: &str = include_str!("shaders/scene_raycast.wgsl");

/// The compiled pass.
#[derive(Debug)]
pub struct SceneRaycastPass(ComputePass);

impl SceneRaycastPass {
    /// Compiles the pass.
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        SceneRaycastPass(ComputePass::new(ctx, "scene_raycast", SOURCE, &[Uniform, Uniform, ReadOnly, ReadWrite, ReadWrite]))
    }

    /// Records the pass writing `rgb` (H·W·3) and `depth` (H·W).
    pub fn encode(&self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, scene: &BoxScene, cam: &Camera, rgb: &wgpu::Buffer, depth: &wgpu::Buffer) {
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
        let cam_buf = uniform(ctx, "camera", &camera_words(cam));
        let info_buf = uniform(ctx, "scene", &info);
        let box_buf = storage_init(ctx, "boxes", &boxes);
        self.0.encode(ctx, enc, &[&cam_buf, &info_buf, &box_buf, rgb, depth], cam.width, cam.height);
    }
}
