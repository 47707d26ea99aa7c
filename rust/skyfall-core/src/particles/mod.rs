//! The particle toolkit, shared by every effect drawn as particles (rain now, snowflakes next):
//!
//! - [`Particle`]: a particle at the frame's time (a raindrop, a flake), relative to the camera;
//! - [`streak`]: a particle's exposure-long path in screen space ([`streak::ScreenStreak`]),
//!   its per-pixel coverage and the GPU packing contract;
//! - [`order`]: far-to-near order, deterministic;
//! - [`binning`]: streak lists per tile of pixels;
//! - [`walk`]: the pixels a streak covers in a band of rows, four at a time where it is steep;
//! - [`composite`]: the compositor over a band, with the depth test, into an accumulator
//!   (the float frame's colour, or the 8-bit output's affine map);
//! - [`voxels`]: world-anchored 1 m voxels (wrap, visibility from the camera, per-voxel seeds).

mod particle;
pub use particle::Particle;

pub mod binning;
pub mod composite;
pub(crate) mod num;
pub mod order;
pub mod streak;
pub mod voxels;
pub mod walk;
