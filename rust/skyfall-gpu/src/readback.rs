//! Reading a frame's storage buffers back to the CPU.

use crate::context::{GpuContext, GpuError};

/// Maps the first `bytes` of `staging` (filled by the frame's copies, already submitted) once
/// and splits them into `outs` in order (the caller's memory: numpy's arrays, from the Python
/// binding).
pub fn read_f32_into(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    bytes: u64,
    outs: &mut [&mut [f32]],
) -> Result<(), GpuError> {
    let want: u64 = outs.iter().map(|o| (o.len() * 4) as u64).sum();
    if want > bytes || bytes > staging.size() {
        return Err(GpuError::Readback(format!(
            "{want} bytes asked of a staging buffer of {} ({bytes} copied)",
            staging.size()
        )));
    }
    let slice = staging.slice(..bytes.max(4));
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
        let mut at = 0;
        for out in outs.iter_mut() {
            let part = &view[at..at + out.len() * 4];
            at += out.len() * 4;
            // The mapped range is 4-byte aligned in practice; value by value if it is not.
            match bytemuck::try_cast_slice::<u8, f32>(part) {
                Ok(values) => out.copy_from_slice(values),
                Err(_) => {
                    for (o, b) in out.iter_mut().zip(part.chunks_exact(4)) {
                        *o = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                    }
                }
            }
        }
    }
    staging.unmap();
    Ok(())
}
