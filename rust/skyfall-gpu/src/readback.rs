//! Reading storage buffers back to the CPU.

use crate::context::{GpuContext, GpuError};

/// Copies the first `out.len()` f32 values of `buffer` into `out` through a mappable staging
/// buffer (the caller's memory: numpy's arrays, from the Python binding).
pub fn read_f32_into(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    out: &mut [f32],
) -> Result<(), GpuError> {
    let bytes = (out.len() * 4) as u64;
    if bytes > buffer.size() {
        return Err(GpuError::Readback(format!(
            "{} values asked of a buffer of {} bytes",
            out.len(),
            buffer.size()
        )));
    }
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
    ctx.queue.submit([enc.finish()]);
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    {
        let view = slice
            .get_mapped_range()
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        // The mapped range is 4-byte aligned in practice; value by value if it is not.
        match bytemuck::try_cast_slice::<u8, f32>(&view) {
            Ok(values) if values.len() == out.len() => out.copy_from_slice(values),
            _ => {
                for (o, b) in out.iter_mut().zip(view.chunks_exact(4)) {
                    *o = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                }
            }
        }
    }
    staging.unmap();
    Ok(())
}
