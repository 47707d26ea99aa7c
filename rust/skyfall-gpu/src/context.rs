//! The wgpu context: instance, adapter, device and queue, created once and reused.

use std::sync::{Arc, Mutex};
use wgpu::{Backends, DeviceType};

/// Errors of the GPU backend.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all on the requested backends.
    #[error(
        "no GPU adapter found on backends {backends}; for a software GPU install Mesa's Vulkan driver \
         (Debian/Ubuntu: apt-get install mesa-vulkan-drivers libvulkan1), or use backend=\"cpu\""
    )]
    NoAdapter {
        /// Backends searched.
        backends: String,
    },
    /// Only software adapters when a hardware one was required.
    #[error("no hardware GPU adapter; found only: {found}")]
    NoHardwareAdapter {
        /// What was found.
        found: String,
    },
    /// Device creation failed.
    #[error("GPU device request failed: {0}")]
    Device(String),
    /// A wgpu validation or out-of-memory error during a frame.
    #[error("GPU error: {0}")]
    Wgpu(String),
    /// Mapping a readback buffer failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
    /// A request beyond the device's limits.
    #[error(
        "{what} needs a {bytes}-byte buffer, over this GPU's limit of {limit} bytes; use backend=\"cpu\" or a smaller frame"
    )]
    TooLarge {
        /// What was requested.
        what: String,
        /// Bytes needed.
        bytes: u64,
        /// The device limit.
        limit: u64,
    },
    /// Bad input, from the core's validation.
    #[error(transparent)]
    Core(#[from] skyfall_core::Error),
}

/// Which adapters are acceptable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AdapterChoice {
    /// Hardware GPUs only (what `backend="auto"` wants).
    HardwareOnly,
    /// Hardware preferred, a software adapter (lavapipe) accepted.
    Any,
}

/// Adapter description for users.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AdapterDescription {
    /// Adapter name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub name: String,
    /// Backend, e.g. `Vulkan`.
    pub backend: String,
    /// Device type, e.g. `Cpu`, `DiscreteGpu`.
    pub device_type: String,
    /// Driver name and info.
    pub driver: String,
}

/// Instance, adapter, device and queue.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What was chosen.
    pub adapter: AdapterDescription,
    /// The device's limits.
    pub limits: wgpu::Limits,
    uncaptured: Arc<Mutex<Option<String>>>,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.adapter)
            .finish()
    }
}

fn rank(t: DeviceType) -> u8 {
    match t {
        DeviceType::DiscreteGpu => 0,
        DeviceType::IntegratedGpu => 1,
        DeviceType::VirtualGpu => 2,
        DeviceType::Other => 3,
        DeviceType::Cpu => 4,
    }
}

impl GpuContext {
    /// Creates the context. Backends default to Vulkan; `WGPU_BACKEND` overrides.
    pub fn new(choice: AdapterChoice) -> Result<Self, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = Backends::VULKAN.with_env();
        let backends = desc.backends;
        let instance = wgpu::Instance::new(desc);
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        adapters.sort_by_key(|a| rank(a.get_info().device_type));
        let Some(adapter) = adapters.into_iter().next() else {
            return Err(GpuError::NoAdapter {
                backends: format!("{backends:?}"),
            });
        };
        let info = adapter.get_info();
        if choice == AdapterChoice::HardwareOnly && info.device_type == DeviceType::Cpu {
            return Err(GpuError::NoHardwareAdapter {
                found: format!("{} ({:?})", info.name, info.backend),
            });
        }
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("skyfall"),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let uncaptured = Arc::new(Mutex::new(None));
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut slot) = sink.lock() {
                slot.get_or_insert_with(|| e.to_string());
            }
        }));
        Ok(GpuContext {
            device,
            queue,
            adapter: AdapterDescription {
                name: info.name,
                backend: format!("{:?}", info.backend),
                device_type: format!("{:?}", info.device_type),
                driver: format!("{} {}", info.driver, info.driver_info)
                    .trim()
                    .to_string(),
            },
            limits,
            uncaptured,
        })
    }

    /// Runs `f` inside validation and out-of-memory error scopes; a captured error becomes
    /// [`GpuError::Wgpu`] instead of a panic.
    pub fn scoped<T>(&self, f: impl FnOnce() -> Result<T, GpuError>) -> Result<T, GpuError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = v.or(o) {
            return Err(GpuError::Wgpu(e.to_string()));
        }
        if let Ok(mut slot) = self.uncaptured.lock()
            && let Some(e) = slot.take()
        {
            return Err(GpuError::Wgpu(e));
        }
        out
    }

    /// Checks that a storage buffer of `bytes` fits the device's limits.
    pub fn check_buffer(&self, what: &str, bytes: u64) -> Result<(), GpuError> {
        let limit = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        if bytes > limit {
            return Err(GpuError::TooLarge {
                what: what.to_string(),
                bytes,
                limit,
            });
        }
        Ok(())
    }
}
