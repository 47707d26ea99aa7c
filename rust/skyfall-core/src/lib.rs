//! skyfall-core: the CPU half of skyfall.
//!
//! Physics in SI inside, the field's customary units at the edges (drop diameters in mm,
//! rain rates in mm/h), every kernel a pure function over slices. No pyo3, no wgpu.
//!
//! - [`physics`]: air, sphere drag, terminal velocity (rigid sphere, Beard 1976, Atlas 1973),
//!   the Marshall–Palmer drop-size distribution, rain extinction.
//! - [`rain`]: precomputed rain-streak textures (seed 000).

pub mod error;
pub mod physics;
pub mod rain;
mod seed;

pub use error::{Error, Result};
