//! Scenes and cameras: what a frame looks at.
//!
//! Right-handed world, +Y up, metres. A camera looks along its −Z axis with +X right and +Y
//! up; pixel (x, y) has its origin top-left and its centre at (x + 0.5, y + 0.5).

pub mod boxes;
pub mod camera;
pub mod lights;
pub mod raycast;
