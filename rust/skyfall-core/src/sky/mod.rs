//! Sky light (Yamamoto & Tadamura §4.2–4.3): CIE sky luminance, rain attenuation along each direction,
//! horizontal (and vertical) illuminance with occlusion, and the ambient-light map.
//!
//! Conventions: directions are unit vectors in the world (+Y up). Azimuth is measured from
//! −Z (north, where a default camera looks) towards +X (east). Luminances are relative to
//! E/π, E the unobstructed horizontal illuminance the user gives; the frame renders in the
//! same units (a white Lambertian surface under the open sky is 1.0).
//!
//! - [`cie`]: Yamamoto & Tadamura's CIE standard overcast sky and the CIE S 011 general skies (types 1–15).
//! - [`Sky`]: a model plus rain attenuation τ(ω) = exp(−σ·H / sin γ) (σ the haze's extinction,
//!   H the cloud base), normalised so the open sky gives E on a horizontal surface *at the
//!   ground*, rain included: E is what a lux meter reads in the rain; the rain reshapes the
//!   sky's angular distribution (the low sky dims most), it does not change E.
//! - [`illuminance`]: E on five axis-aligned normals (up, ±X, ±Z) at points among boxes.
//! - [`ambient`]: those five values on a uniform 3D grid, interpolated trilinearly.
//! - [`horizon`]: what the boxes fix of such a grid (each node's visible sky per azimuth), kept
//!   to light the map again under another sky without the boxes (a sweep over the weather).
//! - [`profile`]: a sky the same at every azimuth read at a few elevations, so that a node's
//!   light is a short dot product of weights the boxes fix with values the sky gives.
//! - [`sun`]: the sun's direct normal illuminance under a clear sky.
//! - [`colour`]: the colour of a sky with a sun (Hosek & Wilkie) and of its sun.

pub mod ambient;
pub mod cie;
pub mod colour;
pub mod horizon;
pub mod illuminance;
mod model;
pub mod profile;
pub mod sun;

pub use model::{AtElevation, Sky, cloud_base_m, light_colour_of, sun_direction};
