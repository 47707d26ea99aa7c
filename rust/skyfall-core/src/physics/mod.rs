//! Physics of falling rain and snow: air and water properties, sphere drag, terminal velocity,
//! the Marshall–Palmer drop-size distribution, rain extinction, and snowflakes (`snow`).
//!
//! Units are in every name. Diameters are millimetres and rain rates mm/h at the API;
//! everything inside is SI.

pub mod air;
pub mod drag;
pub mod dsd;
pub mod extinction;
pub mod fall_speed;
pub(crate) mod quadrature;
pub mod snow;

/// Standard gravity, m/s² (CGPM 1901).
pub const GRAVITY_M_S2: f64 = 9.80665;
