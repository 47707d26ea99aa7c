//! Buffers pooled across frames: a frame takes its storage, uniform and staging buffers from
//! the pool and gives them back once it has been read back, so a sequence of frames of one
//! size allocates device memory once instead of per frame.
//!
//! Buffers are kept by usage and size class (the size rounded up to 1, 1.25, 1.5 or 1.75
//! times a power of two, so that per-frame lists of varying length find a buffer again), and
//! bound with the size asked for, so a shader sees the same array as with a fresh buffer.
//! Every pass overwrites what it writes, so a reused buffer's old contents are never read.
//! At most [`POOL_BYTES`] stay pooled; the oldest go first.

use crate::context::GpuContext;
use std::sync::Mutex;

/// The most device memory the pool keeps between frames, bytes.
pub const POOL_BYTES: u64 = 1 << 30;

/// A buffer of the pool, with the size it was taken for.
#[derive(Debug)]
pub struct Pooled {
    /// The buffer (its size is the size class).
    pub buffer: wgpu::Buffer,
    /// Bytes asked for.
    pub size: u64,
}

impl Pooled {
    /// The binding of the bytes asked for.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: 0,
            size: wgpu::BufferSize::new(self.size),
        })
    }
}

/// The free buffers.
#[derive(Debug, Default)]
pub struct BufferPool {
    free: Mutex<Vec<wgpu::Buffer>>,
}

/// `size` rounded up to its class: 4 × (1, 1.25, 1.5 or 1.75) × 2^k bytes, at least 16.
pub fn size_class(size: u64) -> u64 {
    let size = size.max(16);
    let p = size.next_power_of_two();
    if p == size {
        return size;
    }
    let base = p / 2;
    (1..=4)
        .map(|q| base + q * base / 4)
        .find(|&c| c >= size)
        .unwrap_or(p)
        .next_multiple_of(4)
}

impl BufferPool {
    /// A buffer of at least `size` bytes with exactly `usage`: a free one of its class, or a
    /// new one.
    pub fn take(
        &self,
        ctx: &GpuContext,
        label: &str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> Pooled {
        let class = size_class(size);
        let found = self.free.lock().ok().and_then(|mut free| {
            let i = free
                .iter()
                .position(|b| b.size() == class && b.usage() == usage)?;
            Some(free.swap_remove(i))
        });
        let buffer = found.unwrap_or_else(|| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: class,
                usage,
                mapped_at_creation: false,
            })
        });
        Pooled {
            buffer,
            size: size.max(4),
        }
    }

    /// Returns a frame's buffers (after its readback), dropping the oldest beyond
    /// [`POOL_BYTES`].
    pub fn give_back(&self, buffers: impl IntoIterator<Item = Pooled>) {
        let Ok(mut free) = self.free.lock() else {
            return;
        };
        free.extend(buffers.into_iter().map(|p| p.buffer));
        let mut total: u64 = free.iter().map(wgpu::Buffer::size).sum();
        let mut drop = 0;
        while total > POOL_BYTES && drop < free.len() {
            total -= free[drop].size();
            drop += 1;
        }
        free.drain(..drop);
    }

    /// Bytes held by free buffers.
    pub fn pooled_bytes(&self) -> u64 {
        self.free
            .lock()
            .map_or(0, |f| f.iter().map(wgpu::Buffer::size).sum())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn size_classes_hold_the_size_within_a_quarter() {
        for size in (0..5000u64).chain([24_883_200, 8_294_400, 1 << 30, (1 << 30) + 1]) {
            let c = size_class(size);
            assert!(c >= size.max(16) && c.is_multiple_of(4), "{size} -> {c}");
            assert!(
                c as f64 <= (size.max(16) as f64 * 1.25).max(16.0) + 4.0,
                "{size} -> {c}"
            );
        }
        assert_eq!(size_class(4096), 4096);
        assert_eq!(size_class(4097), 5120);
    }
}
