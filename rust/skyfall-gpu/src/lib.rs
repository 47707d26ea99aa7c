//! skyfall-gpu: the wgpu backend.
//!
//! - [`context`]: instance, adapter choice (Vulkan first; lavapipe when it is the only one),
//!   one device reused across frames, errors captured instead of panicking.
//! - [`pass`]: the [`pass::FramePass`] trait every pass implements and the
//!   [`pass::FrameEncoder`] a frame records into; [`uniforms`]: the passes' uniform blocks as
//!   Pod structs; [`pool`]: buffers pooled across frames; [`readback`]: one mapped copy back.
//! - One pass per file, its WGSL in `shaders/`: [`scene_raycast`] (with the sun's direct
//!   light through the clouds, and a box scene's wet surfaces), [`wet`] (a photo's wet
//!   surfaces), [`cloud`] (the clouds' splats), [`haze`], [`glow`], [`rain`], [`rain_far`];
//!   [`windshield`] (the drops on the glass).
//! - [`frame`]: the passes in physical order on one encoder, one submission, one readback.
//!
//! Passes read and write storage buffers (one f32 per channel), so readback is a plain
//! buffer copy with no texture row padding.
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used))]

pub mod cloud;
pub mod context;
pub mod frame;
pub mod glow;
pub mod haze;
pub mod pass;
pub mod pool;
pub mod rain;
pub mod rain_far;
pub mod readback;
pub mod scene_raycast;
pub mod uniforms;
pub mod wet;
pub mod windshield;

pub use context::{AdapterChoice, GpuContext, GpuError};
