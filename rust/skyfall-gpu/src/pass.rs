//! What every compute pass shares: WGSL assembly, pipeline creation, dispatch over 8 × 8
//! tiles, the [`FramePass`] trait every pass implements, and the [`FrameEncoder`] a frame's
//! passes record into (pooled buffers, one submission, one readback).

use crate::context::{GpuContext, GpuError};
use crate::pool::{BufferPool, Pooled};
use crate::readback::read_f32_into;
use skyfall_core::frame::layers::{Layer, Layers};
use skyfall_core::scene::camera::Camera;

/// The WGSL every pass is prepended with (camera block and rays).
pub const COMMON_WGSL: &str = include_str!("shaders/common.wgsl");

/// The constants the shaders share with the core, generated from the core's own values (so a
/// change there reaches the GPU): WGSL `const` declarations.
pub fn shared_constants() -> String {
    use skyfall_core::frame::scene::{SHADOW_OFFSET_M, SKIP_LEVELS, SUN_RAY_M};
    let f = |name: &str, v: f32| format!("const {name}: f32 = {v:?};\n");
    let u = |name: &str, v: usize| format!("const {name}: u32 = {v}u;\n");
    [
        f("PI", std::f32::consts::PI),
        f("HALF_PI", std::f32::consts::FRAC_PI_2),
        f("STREAM_WIDTH", skyfall_core::cloud::frame::STREAM_WIDTH),
        f("PHASE_SHARE", skyfall_core::cloud::frame::PHASE_SHARE),
        f("K_THROUGH", skyfall_core::cloud::frame::K_THROUGH),
        f("K_BACK", skyfall_core::cloud::frame::K_BACK),
        f("STREAM_DEPTH", skyfall_core::cloud::frame::STREAM_DEPTH),
        f("LUMA_R", skyfall_core::sky::colour::LUMA.x),
        f("LUMA_G", skyfall_core::sky::colour::LUMA.y),
        f("LUMA_B", skyfall_core::sky::colour::LUMA.z),
        f("CUTOFF_RADII", skyfall_core::cloud::CUTOFF_RADII as f32),
        f(
            "MIN_TRANSMITTANCE",
            skyfall_core::cloud::frame::MIN_TRANSMITTANCE,
        ),
        u("CHANNELS", skyfall_core::sky::illuminance::CHANNELS),
        f(
            "WINDOW_ALBEDO_FACTOR",
            skyfall_core::scene::boxes::WINDOW_ALBEDO_FACTOR,
        ),
        f("T_MIN", skyfall_core::scene::raycast::T_MIN),
        u("SKIP_LEVELS", SKIP_LEVELS),
        f("SHADOW_OFFSET_M", SHADOW_OFFSET_M),
        f("SUN_RAY_M", SUN_RAY_M),
        u(
            "PARTICLE_LAYERS",
            skyfall_core::particles::streak::PARTICLE_LAYERS.len(),
        ),
        u(
            "LAYER_RAIN",
            usize::from(skyfall_core::particles::streak::LAYER_RAIN),
        ),
        f("WET_OFFSET_M", skyfall_core::wet::stage::OFFSET_M),
        f("SHELTER_RAY_M", skyfall_core::wet::stage::SHELTER_RAY_M),
        f("MIN_EXPOSURE", skyfall_core::wet::film::MIN_EXPOSURE as f32),
        f("STORAGE_MM", skyfall_core::wet::film::STORAGE_MM as f32),
        f("WET_FILM_MM", skyfall_core::wet::film::WET_FILM_MM as f32),
        f("WATER_INDEX", skyfall_core::wet::optics::WATER_INDEX as f32),
        f("FILM_ROUGHNESS", skyfall_core::wet::optics::FILM_ROUGHNESS),
        f(
            "PUDDLE_ROUGHNESS",
            skyfall_core::wet::optics::PUDDLE_ROUGHNESS,
        ),
        u("MARCH_STEPS", skyfall_core::wet::stage::MARCH_STEPS),
        f("RELIEF_MM", skyfall_core::wet::puddles::RELIEF_MM as f32),
        f("RELIEF_SCALE_M", skyfall_core::wet::puddles::RELIEF_SCALE_M),
        f("LEVEL_MIN_UP", skyfall_core::wet::puddles::LEVEL_MIN_UP),
        f("GRAIN_CELL_M", skyfall_core::wet::puddles::GRAIN_CELL_M),
        u(
            "RELIEF_QUANTILES",
            skyfall_core::wet::puddles::RELIEF_QUANTILES,
        ),
        f(
            "SNOW_PATCH_M",
            skyfall_core::snow::cover::look::SNOW_PATCH_M,
        ),
        f(
            "SNOW_SHARP_BELOW",
            skyfall_core::snow::cover::look::SHARP_BELOW,
        ),
        f(
            "SNOW_BLEND_FROM",
            skyfall_core::snow::cover::look::BLEND_FROM,
        ),
        f(
            "SNOW_PATCH_OFFSET",
            skyfall_core::snow::cover::look::PATCH_OFFSET,
        ),
        f("FACET_M", skyfall_core::snow::cover::sparkle::FACET_M),
        f("ICE_INDEX", skyfall_core::snow::cover::sparkle::ICE_INDEX),
        f(
            "SUN_RADIUS_RAD",
            skyfall_core::snow::cover::sparkle::SUN_RADIUS_RAD,
        ),
        f(
            "GLINT_CELL_M",
            skyfall_core::snow::cover::sparkle::GLINT_CELL_M,
        ),
    ]
    .concat()
}

/// A pass's whole WGSL: [`COMMON_WGSL`], the [`shared_constants`], then its `source`.
pub fn assemble(source: &str) -> String {
    format!("{COMMON_WGSL}\n{}\n{source}", shared_constants())
}

/// One compute pipeline with its bind-group layout (bindings in order, all in group 0).
#[derive(Debug)]
pub struct ComputePass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    label: &'static str,
}

/// How a binding is used by the shader.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binding {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    ReadOnly,
    /// `var<storage, read_write>`.
    ReadWrite,
}

impl ComputePass {
    /// Compiles [`assemble`]`(source)` with entry point `main`.
    pub fn new(ctx: &GpuContext, label: &'static str, source: &str, bindings: &[Binding]) -> Self {
        Self::with_constants(ctx, label, source, bindings, &[])
    }

    /// [`ComputePass::new`] with values for the shader's pipeline-overridable constants
    /// (`override NAME: T`), by name: a specialised pipeline, whose branches on them the shader
    /// compiler removes.
    pub fn with_constants(
        ctx: &GpuContext,
        label: &'static str,
        source: &str,
        bindings: &[Binding],
        constants: &[(&str, f64)],
    ) -> Self {
        Self::with_entry(ctx, label, source, bindings, constants, "main")
    }

    /// [`ComputePass::with_constants`] with the entry point `entry` (a second stage in one
    /// shader's file: the box scene's wet stage, `wet_main`).
    pub fn with_entry(
        ctx: &GpuContext,
        label: &'static str,
        source: &str,
        bindings: &[Binding],
        constants: &[(&str, f64)],
        entry: &str,
    ) -> Self {
        let code = assemble(source);
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(code.into()),
            });
        let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupLayoutEntry {
                binding: i as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: match b {
                    Binding::Uniform => wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    Binding::ReadOnly | Binding::ReadWrite => wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage {
                            read_only: *b == Binding::ReadOnly,
                        },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                },
                count: None,
            })
            .collect();
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            });
        let pipeline_layout = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
        let pipeline = ctx
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            });
        ComputePass {
            pipeline,
            layout,
            label,
        }
    }

    /// Records one dispatch covering `width × height` pixels in 8 × 8 workgroups with
    /// `buffers` bound in order.
    pub fn dispatch(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        buffers: &[&Pooled],
        width: u32,
        height: u32,
    ) {
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.binding(),
            })
            .collect();
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.layout,
            entries: &entries,
        });
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.label),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
    }
}

/// A frame's buffers on the device, as the passes read and write them: one f32 per channel.
#[derive(Debug, Clone, Copy)]
pub struct FrameTargets<'a> {
    /// Linear RGB, H·W·3.
    pub rgb: &'a Pooled,
    /// Depth along the optical axis, m, H·W.
    pub depth: &'a Pooled,
    /// The layers the frame's passes draw, H·W each.
    pub layers: &'a Layers<Pooled>,
}

impl FrameTargets<'_> {
    /// A layer's buffer: an error when the frame does not draw it (a pass asked for a layer
    /// its frame has not made).
    pub fn layer(&self, layer: Layer) -> Result<&Pooled, GpuError> {
        self.layers
            .get(layer)
            .ok_or_else(|| GpuError::Readback(format!("the frame has no {} buffer", layer.name())))
    }
}

/// What a frame's passes record into: the device, the frame's one command encoder, the
/// buffer pool and the camera. Buffers a pass takes are held until the frame is read back,
/// then given back to the pool.
pub struct FrameEncoder<'a> {
    /// The device.
    pub ctx: &'a GpuContext,
    /// The frame's commands (submitted once, with the readback's copies).
    pub enc: wgpu::CommandEncoder,
    /// The frame's camera.
    pub cam: &'a Camera,
    pool: &'a BufferPool,
    held: Vec<Pooled>,
}

const TARGET: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

impl<'a> FrameEncoder<'a> {
    /// Starts a frame.
    pub fn new(ctx: &'a GpuContext, pool: &'a BufferPool, cam: &'a Camera) -> Self {
        let enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        FrameEncoder {
            ctx,
            enc,
            cam,
            pool,
            held: Vec::new(),
        }
    }

    /// A uniform buffer holding `value`.
    pub fn uniform<T: bytemuck::Pod>(&self, label: &str, value: &T) -> Pooled {
        let b = self.pool.take(
            self.ctx,
            label,
            size_of::<T>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        self.ctx
            .queue
            .write_buffer(&b.buffer, 0, bytemuck::bytes_of(value));
        b
    }

    /// A storage buffer holding `values` (at least one value: a binding may not be empty).
    pub fn upload<T: bytemuck::Pod>(&self, label: &str, values: &[T]) -> Pooled {
        let bytes: &[u8] = bytemuck::cast_slice(values);
        let b = self.pool.take(self.ctx, label, bytes.len() as u64, TARGET);
        if !bytes.is_empty() {
            self.ctx.queue.write_buffer(&b.buffer, 0, bytes);
        }
        b
    }

    /// One storage buffer holding `parts` one after another (a shader reads each from its
    /// offset: the sum of the lengths before it).
    pub fn upload_parts(&self, label: &str, parts: &[&[f32]]) -> Pooled {
        let len: usize = parts.iter().map(|p| p.len()).sum();
        let b = self
            .pool
            .take(self.ctx, label, (len.max(1) * 4) as u64, TARGET);
        let mut at = 0u64;
        for part in parts {
            let bytes: &[u8] = bytemuck::cast_slice(part);
            if !bytes.is_empty() {
                self.ctx.queue.write_buffer(&b.buffer, at, bytes);
            }
            at += bytes.len() as u64;
        }
        b
    }

    /// A storage buffer of `len` f32 values that a pass writes in full.
    pub fn target(&self, label: &str, len: usize) -> Pooled {
        self.pool
            .take(self.ctx, label, (len.max(1) * 4) as u64, TARGET)
    }

    /// Records `pass` over the frame's pixels with `buffers` bound in order.
    pub fn dispatch(&mut self, pass: &ComputePass, buffers: &[&Pooled]) {
        pass.dispatch(
            self.ctx,
            &mut self.enc,
            buffers,
            self.cam.width,
            self.cam.height,
        );
    }

    /// Holds `buffers` until the frame is read back (they are in its commands).
    pub fn hold(&mut self, buffers: impl IntoIterator<Item = Pooled>) {
        self.held.extend(buffers);
    }

    /// Submits the frame and reads `outputs` back into the caller's slices, in one staging
    /// buffer mapped once; every buffer then goes back to the pool.
    pub fn read_back(mut self, outputs: Vec<(Pooled, &mut [f32])>) -> Result<(), GpuError> {
        let total: u64 = outputs.iter().map(|(_, o)| (o.len() * 4) as u64).sum();
        let staging = self.pool.take(
            self.ctx,
            "readback",
            total.max(4),
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let mut offset = 0;
        for (b, out) in &outputs {
            let bytes = (out.len() * 4) as u64;
            if bytes > b.size {
                return Err(GpuError::Readback(format!(
                    "{} values asked of a buffer of {} bytes",
                    out.len(),
                    b.size
                )));
            }
            self.enc
                .copy_buffer_to_buffer(&b.buffer, 0, &staging.buffer, offset, bytes);
            offset += bytes;
        }
        self.ctx.queue.submit([self.enc.finish()]);
        let mut outs: Vec<&mut [f32]> = Vec::with_capacity(outputs.len());
        let mut done = Vec::with_capacity(outputs.len() + 1);
        for (b, out) in outputs {
            outs.push(out);
            done.push(b);
        }
        read_f32_into(self.ctx, &staging.buffer, total, &mut outs)?;
        done.push(staging);
        self.pool.give_back(done.into_iter().chain(self.held));
        Ok(())
    }
}

/// A pass of the GPU frame: compiled once per device, then recorded into each frame's
/// encoder over the frame's buffers with what it draws (`Input`).
pub trait FramePass: Sized {
    /// What the pass draws, besides the frame's buffers.
    type Input<'i>;
    /// Compiles the pass.
    fn new(ctx: &GpuContext) -> Self;
    /// Records the pass.
    fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        targets: &FrameTargets<'_>,
        input: Self::Input<'_>,
    ) -> Result<(), GpuError>;
}
