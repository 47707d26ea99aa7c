//! A particle at the frame's time.

use glam::Vec3;

/// A particle (a raindrop, a snowflake) at the end of the frame's exposure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// Position at the end of the exposure relative to the region's centre (a frame's: the
    /// camera's position), m: kept small, so f32 holds it to ~1e-7 m wherever the world is.
    pub position_m: Vec3,
    /// Velocity, m/s.
    pub velocity_m_s: Vec3,
    /// Diameter, m.
    pub diameter_m: f32,
    /// Which voxel and which particle in it: (ix, iy, iz, kind (a diameter bin), index),
    /// stable across frames.
    pub id: [i64; 5],
}

impl super::voxels::Anchored for Particle {
    fn position_m(&self) -> Vec3 {
        self.position_m
    }
}
