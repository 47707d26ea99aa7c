//! skyfall-gpu: the wgpu backend.
//!
//! - [`context`]: instance, adapter choice (Vulkan first; lavapipe when it is the only one),
//!   one device reused across frames, errors captured instead of panicking.
//! - [`readback`]: copies a storage buffer back to the CPU.
//! - One pass per file, its WGSL in `shaders/`: [`scene_raycast`], [`haze`], [`rain`].
//! - [`frame`]: chains the passes on the GPU and reads the frame back once.
//!
//! Passes read and write storage buffers (one f32 per channel), so readback is a plain
//! buffer copy with no texture row padding.
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used))]

pub mod camera;
pub mod context;
pub mod frame;
pub mod haze;
pub mod pass;
pub mod rain;
pub mod readback;
pub mod scene_raycast;

pub use context::{AdapterChoice, GpuContext, GpuError};
