//! The windshield pass: the metaball field, then the frame refracted through the drops
//! (`shaders/windshield_field.wgsl`, `shaders/windshield_refract.wgsl`), against the CPU's
//! `skyfall_core::windshield::render` (tested in `tests/windshield_gpu.rs`). The metaballs are
//! binned into 16 × 16 tiles on the CPU, in their index order (the order the CPU sums them in).
//! In a frame ([`WindshieldPass::encode`]) the drop layer is box blurred when the camera's lens
//! defocuses the drops (`shaders/windshield_blur.wgsl`) and laid over the frame with the wipers'
//! blades (`shaders/windshield_over.wgsl`): the whole stage on the device.

use crate::context::{GpuContext, GpuError};
use crate::pass::{Binding, ComputePass, FrameEncoder, FrameTargets};
use crate::pool::{BufferPool, Pooled};
use crate::readback::read_f32_into;
use bytemuck::Zeroable;
use skyfall_core::error::{Error, Param};
use skyfall_core::frame::layers::Layer;
use skyfall_core::windshield::render::{self, CUTOFF, RefractMode, Refraction};
use skyfall_core::windshield::stage::{BLADE_ALBEDO, BladePx, WindshieldStage};

const FIELD: &str = include_str!("shaders/windshield_field.wgsl");
const REFRACT: &str = include_str!("shaders/windshield_refract.wgsl");
const LOOKUP: &str = include_str!("shaders/windshield_lookup.wgsl");
const BLUR: &str = include_str!("shaders/windshield_blur.wgsl");
const OVER: &str = include_str!("shaders/windshield_over.wgsl");
const TILE: usize = 16;

/// What the pass gives back: the field (H·W), the frame through the drops (H·W·3) and the
/// drops' coverage (H·W).
#[derive(Debug, Clone, PartialEq)]
pub struct WindshieldOut {
    /// The (compressed) metaball field.
    pub field: Vec<f32>,
    /// Linear RGB.
    pub rgb: Vec<f32>,
    /// Coverage.
    pub mask: Vec<f32>,
}

/// The metaballs binned into [`TILE`]² tiles, each in every tile its 4R square reaches, in index
/// order (the order the CPU sums them in): (tiles across, balls (x, y, R, 0), offsets, items).
fn tiles(
    centres_px: &[[f32; 2]],
    radii_px: &[f32],
    width: usize,
    height: usize,
) -> (usize, Vec<[f32; 4]>, Vec<u32>, Vec<u32>) {
    let (tx, ty) = (width.div_ceil(TILE), height.div_ceil(TILE));
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); tx * ty];
    let mut balls: Vec<[f32; 4]> = Vec::with_capacity(centres_px.len());
    for (i, (c, &rad)) in centres_px.iter().zip(radii_px).enumerate() {
        balls.push([c[0], c[1], rad, 0.0]);
        let reach = CUTOFF * rad;
        let (x0, x1) = (c[0] - reach, c[0] + reach);
        let (y0, y1) = (c[1] - reach, c[1] + reach);
        if x1 < 0.0 || y1 < 0.0 || x0 > width as f32 || y0 > height as f32 {
            continue;
        }
        let t = |v: f32, n: usize| ((v.max(0.0) as usize) / TILE).min(n - 1);
        for tj in t(y0, ty)..=t(y1, ty) {
            for ti in t(x0, tx)..=t(x1, tx) {
                lists[tj * tx + ti].push(i as u32);
            }
        }
    }
    let mut offsets = Vec::with_capacity(tx * ty + 1);
    let mut items = Vec::new();
    offsets.push(0u32);
    for l in &lists {
        items.extend_from_slice(l);
        offsets.push(items.len() as u32);
    }
    if balls.is_empty() {
        balls.push([0.0; 4]);
    }
    if items.is_empty() {
        items.push(0);
    }
    (tx, balls, offsets, items)
}

/// The compiled pipelines.
#[derive(Debug)]
pub struct WindshieldPass {
    field: ComputePass,
    refract: ComputePass,
    lookup: ComputePass,
    blur: ComputePass,
    over: ComputePass,
    pool: BufferPool,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct OverParams {
    dims: [u32; 4],
    albedo: [f32; 4],
}

/// A blade as `windshield_over.wgsl` reads it (see its `WsBlade`).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BladeGpu {
    pivot: [f32; 4],
    axis: [f32; 4],
    edge: [f32; 4],
    bounds: [i32; 4],
}

impl BladeGpu {
    fn of(b: &BladePx) -> Self {
        let f = |v: f64| v as f32;
        BladeGpu {
            pivot: [
                f(b.pivot_px[0]),
                f(b.pivot_px[1]),
                f(b.mm_per_px[0]),
                f(b.mm_per_px[1]),
            ],
            axis: [
                f(b.cos_sin[0]),
                f(b.cos_sin[1]),
                f(b.half_width_mm),
                f(b.length_mm),
            ],
            edge: [f(b.px_across), f(b.px_per_mm), 0.0, 0.0],
            bounds: b.bounds.map(|v| v.clamp(0, i64::from(i32::MAX)) as i32),
        }
    }
}

/// The blades' buffer and the over pass's parameters for a `width` × `height` frame (at least one
/// blade in the buffer: a binding may not be empty; the count says how many are read).
fn over_input(blades: &[BladePx], width: usize, height: usize) -> (OverParams, Vec<BladeGpu>) {
    let mut list: Vec<BladeGpu> = blades.iter().map(BladeGpu::of).collect();
    let count = list.len() as u32;
    if list.is_empty() {
        list.push(BladeGpu::zeroed());
    }
    (
        OverParams {
            dims: [width as u32, height as u32, count, 0],
            albedo: [BLADE_ALBEDO, 0.0, 0.0, 0.0],
        },
        list,
    )
}

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FieldParams {
    dims: [u32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RefractParams {
    dims: [u32; 4],
    opts: [u32; 4],
    lens: [f32; 4],
    more: [f32; 4],
}

impl RefractParams {
    /// The refraction `r` over a `dims` = (width, height, lookup width, lookup height) frame
    /// whose lookup copy is `scale` times smaller.
    fn new(r: &Refraction, dims: [usize; 4], scale: usize) -> Self {
        RefractParams {
            dims: dims.map(|d| d as u32),
            opts: [
                scale as u32,
                match r.mode {
                    RefractMode::Offset => 0,
                    RefractMode::Snell => 1,
                },
                0,
                0,
            ],
            lens: [
                r.focal_px as f32,
                r.principal_px[0] as f32,
                r.principal_px[1] as f32,
                r.index as f32,
            ],
            more: [r.slope_px as f32, 0.0, 0.0, 0.0],
        }
    }
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

impl WindshieldPass {
    /// Compiles the pass.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        use Binding::*;
        ctx.scoped(|| {
            Ok(WindshieldPass {
                field: ComputePass::new(
                    ctx,
                    "windshield_field",
                    FIELD,
                    &[Uniform, ReadOnly, ReadOnly, ReadOnly, ReadWrite],
                ),
                refract: ComputePass::new(
                    ctx,
                    "windshield_refract",
                    REFRACT,
                    &[Uniform, ReadOnly, ReadOnly, ReadWrite, ReadWrite, ReadWrite],
                ),
                lookup: ComputePass::new(
                    ctx,
                    "windshield_lookup",
                    LOOKUP,
                    &[Uniform, ReadOnly, ReadWrite],
                ),
                blur: ComputePass::new(
                    ctx,
                    "windshield_blur",
                    BLUR,
                    &[Uniform, ReadOnly, ReadWrite],
                ),
                over: ComputePass::new(
                    ctx,
                    "windshield_over",
                    OVER,
                    &[Uniform, ReadOnly, ReadOnly, ReadWrite],
                ),
                pool: BufferPool::default(),
            })
        })
    }

    /// Records the windshield stage into the frame's encoder, over its `rgb` target in place:
    /// the field, the box-averaged lookup copy (`windshield_lookup.wgsl`, the CPU's
    /// `render::lookup_copy` in the same order of sums), the refraction into the drop layer,
    /// `drop_mask` and `drop_height`; the drop layer box blurred along rows then columns when
    /// the lens defocuses the drops; then laid over the frame, and the blades over it.
    pub fn encode(
        &self,
        f: &mut FrameEncoder<'_>,
        t: &FrameTargets<'_>,
        ws: &WindshieldStage,
    ) -> Result<(), GpuError> {
        let r = ws.refraction();
        let (width, height) = (f.cam.width as usize, f.cam.height as usize);
        let n = width * height;
        let (centres, radii) = ws.metaballs_px();
        let (tx, balls, offsets, items) = tiles(centres, radii, width, height);
        let s = width
            .min(height)
            .checked_div(r.lookup_px)
            .map_or(1, |s| s.max(1));
        let (lw, lh) = (width.div_ceil(s), height.div_ceil(s));
        let fp = FieldParams {
            dims: [width as u32, height as u32, tx as u32, 1],
        };
        let rp = RefractParams::new(r, [width, height, lw, lh], s);
        let lp = FieldParams {
            dims: [width as u32, height as u32, lw as u32, s as u32],
        };
        let mask = t.layer(Layer::DropMask)?;
        let height_layer = t.layer(Layer::DropHeight)?;
        let fpu = f.uniform("windshield field params", &fp);
        let rpu = f.uniform("windshield refract params", &rp);
        let lpu = f.uniform("windshield lookup params", &lp);
        let bb = f.upload("metaballs", &balls);
        let ob = f.upload("tile offsets", &offsets);
        let ib = f.upload("tile items", &items);
        let field = f.target("field", n);
        let look = f.target("lookup", lw * lh * 3);
        let layer = f.target("drop layer", 4 * n);
        f.dispatch(&self.field, &[&fpu, &bb, &ob, &ib, &field]);
        f.dispatch(&self.lookup, &[&lpu, t.rgb, &look]);
        f.dispatch(
            &self.refract,
            &[&rpu, &field, &look, &layer, mask, height_layer],
        );
        let radius = r.blur_radius_px();
        if radius > 0 {
            let [w, h, rad] = [width, height, radius].map(|v| v as u32);
            let rows = f.uniform(
                "windshield blur rows",
                &FieldParams {
                    dims: [w, h, rad, 0],
                },
            );
            let cols = f.uniform(
                "windshield blur columns",
                &FieldParams {
                    dims: [w, h, rad, 1],
                },
            );
            let along_rows = f.target("drop layer blurred along rows", 4 * n);
            f.dispatch(&self.blur, &[&rows, &layer, &along_rows]);
            f.dispatch(&self.blur, &[&cols, &along_rows, &layer]);
            f.hold([rows, cols, along_rows]);
        }
        let (op, blades) = over_input(&ws.blades_px(), width, height);
        let opu = f.uniform("windshield over params", &op);
        let blb = f.upload("blades", &blades);
        f.dispatch(&self.over, &[&opu, &layer, &blb, t.rgb]);
        f.hold([fpu, rpu, lpu, bb, ob, ib, field, look, layer, opu, blb]);
        Ok(())
    }

    fn upload<T: bytemuck::Pod>(
        &self,
        ctx: &GpuContext,
        label: &str,
        values: &[T],
        usage: wgpu::BufferUsages,
    ) -> Pooled {
        let bytes: &[u8] = bytemuck::cast_slice(values);
        let b = self
            .pool
            .take(ctx, label, (bytes.len() as u64).max(16), usage);
        if !bytes.is_empty() {
            ctx.queue.write_buffer(&b.buffer, 0, bytes);
        }
        b
    }

    /// The field of the metaballs (`centres_px`, `radii_px`) over a `width` × `height` frame,
    /// and `frame` (H·W·3) refracted through it by `r` (its `blur_px` must be 0; no blades): the
    /// pass alone, for comparisons with `render::refract_frame`.
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &self,
        ctx: &GpuContext,
        centres_px: &[[f32; 2]],
        radii_px: &[f32],
        width: usize,
        height: usize,
        compress: bool,
        frame: &[f32],
        r: &Refraction,
    ) -> Result<WindshieldOut, GpuError> {
        // the CPU's checks, on an empty map (sizes, radii, the lens)
        render::height_map(centres_px, radii_px, 1, 1, false).map_err(GpuError::Core)?;
        skyfall_core::ranges::WIDTH
            .check(width as f64)
            .map_err(GpuError::Core)?;
        skyfall_core::ranges::HEIGHT
            .check(height as f64)
            .map_err(GpuError::Core)?;
        r.validate().map_err(GpuError::Core)?;
        let n = width * height;
        if frame.len() != n * 3 {
            return Err(GpuError::Core(Error::Length {
                param: Param {
                    name: "frame",
                    index: None,
                },
                len: frame.len(),
                expected: n * 3,
            }));
        }
        if r.blur_px != 0.0 {
            return Err(GpuError::Core(Error::Unusable {
                param: Param {
                    name: "blur_px",
                    index: None,
                },
                value: r.blur_px,
                message: "is not drawn by this pass alone (in focus: 0); a frame's windshield stage blurs on the device".into(),
            }));
        }
        ctx.check_buffer("the windshield's frame", (n * 12) as u64)?;
        let (tx, balls, offsets, items) = tiles(centres_px, radii_px, width, height);
        let (look, lw, lh, scale) = render::lookup_copy(frame, width, height, r.lookup_px)?;
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let fp = FieldParams {
            dims: [width as u32, height as u32, tx as u32, u32::from(compress)],
        };
        let rp = RefractParams::new(r, [width, height, lw, lh], scale);
        let bufs = ctx.scoped(|| {
            let fpu = self.upload(ctx, "windshield field params", &[fp], uniform);
            let rpu = self.upload(ctx, "windshield refract params", &[rp], uniform);
            let bb = self.upload(ctx, "metaballs", &balls, STORAGE);
            let ob = self.upload(ctx, "tile offsets", &offsets, STORAGE);
            let ib = self.upload(ctx, "tile items", &items, STORAGE);
            let lb = self.upload(ctx, "lookup", &look, STORAGE);
            // the frame behind the glass, the drops laid over it in place
            let rgb = self.upload(ctx, "rgb", frame, STORAGE);
            let (op, blades) = over_input(&[], width, height);
            let opu = self.upload(ctx, "windshield over params", &[op], uniform);
            let blb = self.upload(ctx, "blades", &blades, STORAGE);
            let layer = self.pool.take(ctx, "drop layer", (n * 16) as u64, STORAGE);
            let field = self.pool.take(ctx, "field", (n * 4) as u64, STORAGE);
            let height_layer = self.pool.take(ctx, "drop height", (n * 4) as u64, STORAGE);
            let mask = self.pool.take(ctx, "mask", (n * 4) as u64, STORAGE);
            let total = (n * 20) as u64;
            let staging = self.pool.take(
                ctx,
                "windshield readback",
                total,
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            );
            let mut enc = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("windshield"),
                });
            let (w, h) = (width as u32, height as u32);
            self.field
                .dispatch(ctx, &mut enc, &[&fpu, &bb, &ob, &ib, &field], w, h);
            self.refract.dispatch(
                ctx,
                &mut enc,
                &[&rpu, &field, &lb, &layer, &mask, &height_layer],
                w,
                h,
            );
            self.over
                .dispatch(ctx, &mut enc, &[&opu, &layer, &blb, &rgb], w, h);
            let mut at = 0;
            for (b, bytes) in [(&field, n * 4), (&rgb, n * 12), (&mask, n * 4)] {
                enc.copy_buffer_to_buffer(&b.buffer, 0, &staging.buffer, at, bytes as u64);
                at += bytes as u64;
            }
            ctx.queue.submit([enc.finish()]);
            Ok((
                [
                    fpu,
                    rpu,
                    bb,
                    ob,
                    ib,
                    lb,
                    height_layer,
                    field,
                    rgb,
                    mask,
                    opu,
                    blb,
                    layer,
                ],
                staging,
                total,
            ))
        })?;
        let (held, staging, total) = bufs;
        let mut out = WindshieldOut {
            field: vec![0.0; n],
            rgb: vec![0.0; n * 3],
            mask: vec![0.0; n],
        };
        let read = read_f32_into(
            ctx,
            &staging.buffer,
            total,
            &mut [&mut out.field[..], &mut out.rgb[..], &mut out.mask[..]],
        );
        self.pool
            .give_back(held.into_iter().chain(std::iter::once(staging)));
        read?;
        Ok(out)
    }
}
