//! Snow after Koitabashi, Matsubara, Moriya & Takahashi, *Snowfall and snow-cover scenes with
//! wind*: the flakes falling with the wind (drawn through the particle toolkit) and the cover
//! they lay where the wind lets them. The flakes' sizes, masses and speeds are
//! [`crate::physics::snow`].
//!
//! - [`flakes`]: the flakes near the camera, world-anchored in 1 m voxels and seeded, falling
//!   with the wind plus a seeded, smooth sway, wrapping at the ground;
//! - [`streaks`]: a frame's flakes lit, faded with distance, given their sprites and projected
//!   into the particle list.

/// Albedo of fresh snow in the visible, 0.85, for the falling flakes and the cover alike: fresh
/// dry snow reflects 0.80–0.90 of the visible sunlight (Cuffey & Paterson, *The Physics of
/// Glaciers*, 4th ed., 2010, Table 5.2, fresh dry snow 0.75–0.98; Warren, *Optical properties
/// of snow*, Rev. Geophys. 1982: above 0.9 at 0.4–0.7 µm for deep fine-grained snow, less for
/// the broadband and older snow).
pub const SNOW_ALBEDO: f32 = 0.85;

pub mod cover;
pub mod flakes;
pub mod streaks;
