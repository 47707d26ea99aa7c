//! Scenes and cameras: what a frame looks at.
//!
//! Right-handed world, +Y up, metres. A camera looks along its −Z axis with +X right and +Y
//! up; pixel (x, y) has its origin top-left and its centre at (x + 0.5, y + 0.5).

pub mod boxes;
pub mod camera;
pub mod lights;
pub mod raycast;

use glam::Vec3;

/// How a frame lights a surface, as the effects that draw surfaces of their own (the snow
/// cover) see it: the frame's `SceneLight` implements it, so they need not import the frame.
pub trait SurfaceLight {
    /// Radiance (relative to E/π) of a Lambertian face of albedo `a` and normal `n` at `p`,
    /// with the shadows of `boxes`, and the share of the sun's direct light it receives.
    fn surface_radiance_sun(
        &self,
        boxes: &[boxes::SceneBox],
        p: Vec3,
        n: Vec3,
        a: Vec3,
    ) -> (Vec3, f32);

    /// The sky's radiance seen along the unit direction `dir` (relative, linear RGB).
    fn sky_pixel(&self, dir: Vec3) -> Vec3;

    /// The sun as a mirror sees it (the snow's glints): the unit direction towards it and
    /// its colour times its normal illuminance over E; None without a sun.
    fn sun_glint(&self) -> Option<(Vec3, Vec3)>;
}
