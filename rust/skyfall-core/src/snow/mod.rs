//! Snow after Koitabashi, Matsubara, Moriya & Takahashi, *Snowfall and snow-cover scenes with
//! wind*: the flakes falling with the wind (drawn through the particle toolkit) and the cover
//! they lay where the wind lets them. The flakes' sizes, masses and speeds are
//! [`crate::physics::snow`].
//!
//! - [`flakes`]: the flakes near the camera, world-anchored in 1 m voxels and seeded, falling
//!   with the wind plus a seeded, smooth sway, wrapping at the ground;
//! - [`streaks`]: a frame's flakes lit, faded with distance, given their sprites and projected
//!   into the particle list.

pub mod cover;
pub mod flakes;
pub mod streaks;
