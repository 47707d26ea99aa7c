//! skyfall-core: the CPU half of skyfall.
//!
//! Physics in SI inside, the field's customary units at the edges (drop diameters in mm,
//! rain rates in mm/h), every kernel a pure function over slices. No pyo3, no wgpu.
//!
//! - [`physics`]: air, sphere drag, terminal velocity (rigid sphere, Beard 1976, Atlas 1973),
//!   the Marshall–Palmer drop-size distribution, rain extinction.
//! - [`rain`]: precomputed rain-streak textures (Yoshida, Dobashi & Yamamoto).
//! - [`scene`]: cameras and the procedural box scene (ray cast).
//! - [`haze`]: rain haze along view rays (Yamamoto & Tadamura).
//! - [`sky`]: CIE skies, sky illuminance with occlusion, the ambient-light map (Yamamoto & Tadamura).
//! - [`frame`]: the frame pipeline (scene stage, effect passes, output stage) and the CPU
//!   backend's two output stages: float32 frames and 8-bit sRGB photos.
//! - [`particles`]: the particle toolkit shared by rain and (next) snow.
//! - [`cloud`]: particle clouds, Harris' illumination and the attenuation volume (Shimada,
//!   Shinya, Shiraishi & Harada).
//! - [`simd`]: the 8-bit output stage's kernels vectorised (AVX2), chosen at run time; the
//!   one module allowed `unsafe`.
//! - [`windshield`]: drops on a windshield, wipers, and their refraction (Gotou, Tanaka & Sagawa).

#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used))]

pub mod cloud;
pub mod color;
pub mod error;
pub mod frame;
pub mod glow;
pub mod haze;
pub mod particles;
pub mod physics;
pub mod rain;
pub mod ranges;
pub mod scene;
mod seed;
pub mod simd;
pub mod sky;
pub mod snow;
pub mod stage;
pub mod weather;
pub mod wet;
pub mod windshield;

pub use error::{Error, Result};
