//! The 8-bit output stage, for 8-bit photos: sRGB bytes in, sRGB bytes out, the frame's
//! stages that declare it (the photo, the haze and the particles, [`super::passes::Particles`];
//! [`super::stages::Frame::plan`]) drawn in one pass: bands of rows in
//! parallel, each cut into tiles of 128 columns drawn one after the other.
//!
//! The rain is composited far to near as in [`crate::particles::composite::composite_streaks`], but
//! into a per-pixel affine map instead of the colour: each streak does C ← (1 − a r) C + a r L,
//! so the whole ordered stack is C ↦ P·C + Q with P = ∏(1 − a r) and Q accumulated as
//! Q ← (1 − a r) Q + a r L. P and Q depend only on the streaks and the depth test, not on the
//! background, so a tile's streaks are rasterised into P and Q first (a tile's share of a
//! band-sized scratch, in L1 while the tile is drawn; no frame-sized float buffers; Q is one
//! value when every light is grey), then each of its pixels is decoded, hazed, mapped and
//! encoded once, four at a time. The result equals the float frame encoded to 8 bits up to the
//! rounding of the reassociated sums (tests: every byte within 1 code, nearly all identical).

use super::check_frame_size;
use super::passes::Particles;
use crate::color::Srgb8Encoder;
use crate::error::{Error, Param, Result};
use crate::haze::{Haze, ViewRays, blend};
use crate::particles::binning::bin_by_tiles;
use crate::particles::composite::{Accumulator, Blend, Cover, composite_band};
use crate::particles::streak::{PARTICLE_LAYERS, ScreenStreak};
use crate::rain::streaks::{RainFrame, RainStats};
use crate::scene::camera::Camera;
use crate::simd::{self, Dispatch, Level};
use crate::snow::streaks::{SnowFrame, SnowStats};
use crate::stage::layers::Layer;
use glam::{Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use std::cell::RefCell;

/// Rows per band (a task): a band's scratch is 8 B per pixel, 16 with coloured lights.
const BAND_ROWS: usize = 16;
/// Columns per tile: a tile's scratch (P, Q, depth: 16 rows × 128 × 12 B) fits a core's L1.
const TILE_W: usize = 128;

/// An 8-bit sRGB photo with its depth.
#[derive(Debug, Clone, Copy)]
pub struct Photo8<'a> {
    /// sRGB bytes, H·W·3.
    pub srgb: &'a [u8],
    /// Depth along the optical axis, m (inf = sky), H·W.
    pub depth_m: &'a [f32],
    /// The 8-bit decoding table (byte → linear).
    pub decode: &'a [f32; 256],
}

/// What the pass writes.
pub struct Photo8Out<'a> {
    /// sRGB bytes, H·W·3.
    pub srgb: &'a mut [u8],
    /// The rain's coverage 1 − ∏(1 − aᵢ), H·W, when wanted.
    pub rain_alpha: Option<&'a mut [f32]>,
    /// The snow's coverage 1 − ∏(1 − aᵢ), H·W, when wanted.
    pub snow_alpha: Option<&'a mut [f32]>,
}

/// What the rain did: streak counts and drops generated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Photo8Stats {
    /// Streaks drawn and culled.
    pub rain: RainStats,
    /// Drops generated (in the voxels that can reach the view, less the sheltered ones).
    pub drops: usize,
    /// The snow's flakes and streaks, when it snows.
    pub snow: Option<SnowStats>,
}

fn length_error(name: &'static str, len: usize, expected: usize) -> Error {
    Error::Length {
        param: Param { name, index: None },
        len,
        expected,
    }
}

/// Per-thread band scratch, reused across bands and frames.
#[derive(Default)]
struct Scratch {
    /// The rain's P per pixel.
    p: Vec<f32>,
    /// The rain's Q: one plane when every streak's light is grey, three (one per channel)
    /// with coloured lights.
    q: Vec<f32>,
    /// The particle layers' coverage products ∏(1 − a) ([`PARTICLE_LAYERS`]' order), each
    /// when its layer is wanted.
    covers: [Vec<f32>; PARTICLE_LAYERS.len()],
    /// A row's transmittance.
    t_row: Vec<f32>,
}

thread_local! {
    /// Borrowed once per band; nothing inside the borrow calls into rayon, so a thread never
    /// re-enters it through work stealing.
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Renders haze, rain and snow over an 8-bit photo into `out` (same size), on the CPU.
/// Returns the particles' counts when `rain` or `snow` is given. The per-pixel kernels run at
/// the best SIMD level of the CPU ([`Dispatch::detect`]); the bytes are the scalar code's.
pub fn render_photo8(
    cam: &Camera,
    photo: &Photo8<'_>,
    haze: Option<&Haze>,
    rain: Option<&RainFrame<'_>>,
    snow: Option<&SnowFrame<'_>>,
    out: Photo8Out<'_>,
) -> Result<Option<Photo8Stats>> {
    render_photo8_with(cam, photo, haze, rain, snow, out, Dispatch::detect())
}

/// [`render_photo8`] with its per-pixel kernels at the levels of `dispatch` (the same bytes
/// at every level: [`Dispatch::scalar`] is the reference).
pub fn render_photo8_with(
    cam: &Camera,
    photo: &Photo8<'_>,
    haze: Option<&Haze>,
    rain: Option<&RainFrame<'_>>,
    snow: Option<&SnowFrame<'_>>,
    out: Photo8Out<'_>,
    dispatch: Dispatch,
) -> Result<Option<Photo8Stats>> {
    check_frame_size(cam)?;
    let (w, n) = (cam.width as usize, cam.pixels());
    if photo.srgb.len() != 3 * n {
        return Err(length_error("image", photo.srgb.len(), 3 * n));
    }
    if photo.depth_m.len() != n {
        return Err(length_error("depth_m", photo.depth_m.len(), n));
    }
    if out.srgb.len() != 3 * n {
        return Err(length_error("out", out.srgb.len(), 3 * n));
    }
    let Photo8Out {
        srgb: out_srgb,
        rain_alpha,
        snow_alpha,
    } = out;
    // The coverages in PARTICLE_LAYERS' order.
    let (mut rain_alpha, mut snow_alpha) = (rain_alpha, snow_alpha);
    let coverages = PARTICLE_LAYERS.map(|l| match l.coverage {
        Layer::RainAlpha => rain_alpha.take(),
        Layer::SnowAlpha => snow_alpha.take(),
        _ => None,
    });
    for (c, l) in coverages.iter().zip(&PARTICLE_LAYERS) {
        if let Some(a) = c
            && a.len() != n
        {
            return Err(length_error(l.coverage.name(), a.len(), n));
        }
    }
    crate::haze::check_depth(photo.depth_m)?;

    let particles = Particles::prepare(cam, rain, snow)?;
    let stats = particles.as_ref().map(|p| {
        let (rain, drops) = p.rain_report().unwrap_or_default();
        Photo8Stats {
            rain,
            drops,
            snow: p.snow,
        }
    });
    let streaks: &[ScreenStreak] = particles.as_ref().map_or(&[], |p| &p.streaks);
    let far = particles.as_ref().and_then(|p| p.far.as_ref());
    if haze.is_none() && streaks.is_empty() && far.is_none() {
        // Nothing to draw: encode(decode(b)) = b for every byte (tested), so the bytes as they are.
        out_srgb.copy_from_slice(photo.srgb);
        for (c, l) in coverages.into_iter().zip(&PARTICLE_LAYERS) {
            if let Some(a) = c {
                a.fill(l.coverage.neutral());
            }
        }
        return Ok(stats);
    }
    // Each band of rows is cut into tiles of TILE_W columns, rasterised and shaded one after
    // the other: a tile's scratch and depth stay in the core's L1.
    let tiles_x = w.div_ceil(TILE_W);
    let (offsets, indices) = bin_by_tiles(
        streaks,
        cam.width,
        cam.height,
        TILE_W as u32,
        BAND_ROWS as u32,
    )?;
    let rays = ViewRays::new(cam);
    let enc = Srgb8Encoder::new();
    let band = BAND_ROWS * w;
    // Each band's coverage layers, in PARTICLE_LAYERS' order.
    let mut chunks = coverages.map(|c| c.map(|a| a.chunks_mut(band)));
    let mut layer_bands: Vec<[Option<&mut [f32]>; PARTICLE_LAYERS.len()]> = (0..n.div_ceil(band))
        .map(|_| std::array::from_fn(|k| chunks[k].as_mut().and_then(Iterator::next)))
        .collect();
    let air = haze.map_or([0.0; 3], |h| h.airlight);
    // (a photo's haze is grey: only a box scene's clear air has a colour, and box scenes take
    // the banded path)
    debug_assert!(haze.is_none_or(|h| h.spectral == [0.0; 2]));
    // Grey light everywhere (the sky's; coloured lamps aside): Q's three channels are equal.
    let grey = streaks.iter().all(|s| {
        let l = s.light();
        l.x == l.y && l.y == l.z
    }) && far.is_none_or(|f| f.grey());
    let k = if grey { 1 } else { 3 };
    out_srgb
        .par_chunks_mut(3 * band)
        .zip(layer_bands.par_iter_mut())
        .enumerate()
        .for_each(|(bi, (out_band, layers))| {
            let y0 = bi * BAND_ROWS;
            let rows = out_band.len() / (3 * w);
            let px = rows * w;
            let depth = &photo.depth_m[y0 * w..y0 * w + px];
            let src = &photo.srgb[3 * y0 * w..3 * (y0 * w + px)];
            SCRATCH.with(|cell| {
                let mut guard = cell.borrow_mut();
                let Scratch {
                    p,
                    q,
                    covers,
                    t_row,
                } = &mut *guard;
                // Sized for the band; a tile initialises its own columns before drawing (a tile's
                // windows may spill a few columns into a neighbour's: they write those back
                // unchanged, a = 0).
                p.resize(px, 1.0);
                q.resize(k * px, 0.0);
                for (c, l) in covers.iter_mut().zip(layers.iter()) {
                    c.resize(if l.is_some() { px } else { 0 }, 1.0);
                }
                t_row.clear();
                t_row.resize(w, 1.0);
                for tx in 0..tiles_x {
                    let t = bi * tiles_x + tx;
                    let mine = &indices[offsets[t] as usize..offsets[t + 1] as usize];
                    let cols = tx * TILE_W..((tx + 1) * TILE_W).min(w);
                    let rained = !mine.is_empty() || far.is_some();
                    if rained {
                        for row in 0..rows {
                            let seg = row * w + cols.start..row * w + cols.end;
                            p[seg.clone()].fill(1.0);
                            for c in 0..k {
                                q[c * px + seg.start..c * px + seg.end].fill(0.0);
                            }
                            for c in covers.iter_mut() {
                                if let Some(c) = c.get_mut(seg.clone()) {
                                    c.fill(1.0);
                                }
                            }
                        }
                        // One Q plane when every light is grey, three otherwise.
                        let raster = if grey {
                            raster_tile::<1>
                        } else {
                            raster_tile::<3>
                        };
                        raster(
                            streaks,
                            mine,
                            far,
                            (y0, rows, w),
                            cols.clone(),
                            depth,
                            p,
                            q,
                            covers.each_mut().map(Vec::as_mut_slice),
                        );
                    }
                    let t_seg = &mut t_row[..cols.len()];
                    for row in 0..rows {
                        let seg = row * w + cols.start..row * w + cols.end;
                        if let Some(h) = haze {
                            simd::transmittance_row(
                                dispatch.transmittance(),
                                h,
                                &rays.row((y0 + row) as u32, cols.clone()),
                                &depth[seg.clone()],
                                t_seg,
                            );
                        }
                        let (src_row, out_row) = (
                            &src[3 * seg.start..3 * seg.end],
                            &mut out_band[3 * seg.start..3 * seg.end],
                        );
                        let maps = || Some((&p[seg.clone()], &q[seg.start..], px));
                        match (rained, grey) {
                            (false, _) => shade_row_at::<1>(
                                dispatch.shade(),
                                photo.decode,
                                enc,
                                air,
                                t_seg,
                                None,
                                src_row,
                                out_row,
                            ),
                            (true, true) => shade_row_at::<1>(
                                dispatch.shade(),
                                photo.decode,
                                enc,
                                air,
                                t_seg,
                                maps(),
                                src_row,
                                out_row,
                            ),
                            (true, false) => shade_row_at::<3>(
                                dispatch.shade(),
                                photo.decode,
                                enc,
                                air,
                                t_seg,
                                maps(),
                                src_row,
                                out_row,
                            ),
                        }
                        for (layer, cov) in layers.iter_mut().zip(covers.iter()) {
                            if let Some(a) = layer {
                                let a = &mut a[seg.clone()];
                                if rained {
                                    for (o, c) in a.iter_mut().zip(&cov[seg.clone()]) {
                                        *o = 1.0 - c;
                                    }
                                } else {
                                    a.fill(0.0);
                                }
                            }
                        }
                    }
                }
            });
        });
    Ok(stats)
}

/// The 8-bit output's colour over a band: each pixel's affine map C ↦ P·C + Q of the streaks
/// composited over it (C ← (1 − a r) C + a r L gives P ← (1 − a r) P and
/// Q ← (1 − a r) Q + a r L), P in `p`, Q in `K` planes of `q` (one when every light is grey).
/// Band-sized buffers, indexed as the band; the layers are the accumulator's [`Cover`].
struct AffineBlend<'a, const K: usize> {
    p: &'a mut [f32],
    q: [&'a mut [f32]; K],
}

impl<const K: usize> Blend for AffineBlend<'_, K> {
    /// The light per channel, and r.
    type Light = ([f32; 3], f32);

    #[inline(always)]
    fn light(&self, light: Vec3, r: f32) -> Self::Light {
        (light.to_array(), r)
    }

    #[inline(always)]
    fn blend_x4(&mut self, (l, r): &Self::Light, i: usize, a: Vec4) {
        let end = i + 4;
        let ar = a * *r;
        let keep = Vec4::ONE - ar;
        (Vec4::from_slice(&self.p[i..end]) * keep).write_to_slice(&mut self.p[i..end]);
        for (q, &lc) in self.q.iter_mut().zip(l) {
            (Vec4::from_slice(&q[i..end]) * keep + ar * lc).write_to_slice(&mut q[i..end]);
        }
    }

    #[inline(always)]
    fn blend(&mut self, (l, r): &Self::Light, i: usize, a: f32) {
        let ar = a * r;
        let keep = 1.0 - ar;
        self.p[i] *= keep;
        for (q, &lc) in self.q.iter_mut().zip(l) {
            q[i] = q[i] * keep + ar * lc;
        }
    }
}

/// Composites a tile's streaks (`mine`, indices into `streaks`, far to near, after the rain's
/// far layers `far` when given; the tile: the band's rows, columns `cols`) into the band's
/// affine maps (see [`AffineBlend`]: P in `p`, Q in `q`'s `K` planes) and the particle layers'
/// coverage products `covers` ([`PARTICLE_LAYERS`]' order, each empty when not kept).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn raster_tile<const K: usize>(
    streaks: &[ScreenStreak],
    mine: &[u32],
    far: Option<&crate::rain::far::FarRain>,
    (y0, rows, w): (usize, usize, usize),
    cols: std::ops::Range<usize>,
    depth: &[f32],
    p: &mut [f32],
    q: &mut [f32],
    covers: [&mut [f32]; PARTICLE_LAYERS.len()],
) {
    let px = p.len();
    let mut planes = q.chunks_exact_mut(px);
    let q: [&mut [f32]; K] = std::array::from_fn(|_| planes.next().unwrap_or_default());
    let covers = covers.map(|c| {
        let n = c.len().min(px);
        &mut c[..n]
    });
    let mut acc = Accumulator {
        colour: AffineBlend::<K> { p, q },
        // the 8-bit output keeps no particle's depth
        cover: Cover::new(covers, std::array::from_fn(|_| <&mut [f32]>::default())),
    };
    if let Some(far) = far {
        far.composite(y0, rows, w, cols.clone(), depth, &mut acc);
    }
    composite_band(streaks, mine, y0, rows, w, cols, depth, &mut acc);
}

/// The first four values of `s` as a vector, in one unaligned load (glam's `from_slice`
/// assembles it from four scalars); zeros if `s` is shorter (callers pass four or more).
#[inline(always)]
fn load4(s: &[f32]) -> Vec4 {
    s.first_chunk::<4>().map_or(Vec4::ZERO, |a| Vec4::from(*a))
}

/// [`shade_row`] with its whole groups of pixels at `level` ([`simd`]'s twin, the same bits),
/// the rest by [`shade_row`] itself.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn shade_row_at<const K: usize>(
    level: Level,
    decode: &[f32; 256],
    enc: Srgb8Encoder,
    air: [f32; 3],
    t: &[f32],
    pq: Option<(&[f32], &[f32], usize)>,
    src: &[u8],
    out: &mut [u8],
) {
    let done = simd::shade_row::<K>(level, decode, enc.thresholds(), air, t, pq, src, out);
    if done == 0 {
        return shade_row::<K>(decode, enc, air, t, pq, src, out);
    }
    let rest = pq.map(|(p, q, stride)| (&p[done..], &q[done..], stride));
    shade_row::<K>(
        decode,
        enc,
        air,
        &t[done..],
        rest,
        &src[3 * done..],
        &mut out[3 * done..],
    );
}

/// A row's bytes: decoded, hazed (eq. 2; t = 1 without haze), mapped by the rain's P·C + Q
/// (`p`, and `q` with `K` planes `stride` apart, see [`raster_tile`]), encoded.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn shade_row<const K: usize>(
    decode: &[f32; 256],
    enc: Srgb8Encoder,
    air: [f32; 3],
    t: &[f32],
    pq: Option<(&[f32], &[f32], usize)>,
    src: &[u8],
    out: &mut [u8],
) {
    if K == 1 {
        // Four pixels at a time: their twelve values in three vectors (R G B R | G B R G |
        // B R G B), the arithmetic and the clamp vectorised, the same operations in the same
        // order as one by one below (same bits); the tail pixels one by one.
        let n4 = t.len() / 4 * 4;
        let (t4, t_tail) = t.split_at(n4);
        let (src4, src_tail) = src.split_at(3 * n4);
        let (out4, out_tail) = out.split_at_mut(3 * n4);
        let air4 = [
            Vec4::new(air[0], air[1], air[2], air[0]),
            Vec4::new(air[1], air[2], air[0], air[1]),
            Vec4::new(air[2], air[0], air[1], air[2]),
        ];
        let groups = out4
            .chunks_exact_mut(12)
            .zip(src4.chunks_exact(12))
            .zip(t4.chunks_exact(4));
        let maps = pq.map(|(p, q, _)| (p.split_at(n4), q.split_at(n4)));
        match maps {
            None => groups.for_each(|((o, s), tc)| shade4(decode, enc, &air4, o, s, tc, None)),
            Some(((p4, _), (q4, _))) => {
                groups
                    .zip(p4.chunks_exact(4).zip(q4.chunks_exact(4)))
                    .for_each(|(((o, s), tc), (p, q))| {
                        shade4(decode, enc, &air4, o, s, tc, Some((p, q)))
                    });
            }
        }
        let tail = maps.map(|((_, p), (_, q))| (p, q, 0));
        return shade_row_x1::<K>(decode, enc, air, t_tail, tail, src_tail, out_tail);
    }
    shade_row_x1::<K>(decode, enc, air, t, pq, src, out);
}

/// Four pixels of [`shade_row`] (`K` = 1): twelve bytes of `s` into `o`, `tc` their
/// transmittances, `map` their P and Q.
#[inline(always)]
fn shade4(
    decode: &[f32; 256],
    enc: Srgb8Encoder,
    air4: &[Vec4; 3],
    o: &mut [u8],
    s: &[u8],
    tc: &[f32],
    map: Option<(&[f32], &[f32])>,
) {
    let d = |k: usize| decode[usize::from(s[k])];
    let v = [
        Vec4::new(d(0), d(1), d(2), d(3)),
        Vec4::new(d(4), d(5), d(6), d(7)),
        Vec4::new(d(8), d(9), d(10), d(11)),
    ];
    let tv = load4(tc);
    let ts = [tv.xxxy(), tv.yyzz(), tv.zwww()];
    let pqs = map.map(|(p, q)| {
        let (p, q) = (load4(p), load4(q));
        (
            [p.xxxy(), p.yyzz(), p.zwww()],
            [q.xxxy(), q.yyzz(), q.zwww()],
        )
    });
    for m in 0..3 {
        let mut h = blend(v[m], ts[m], air4[m], Vec4::ONE);
        if let Some((ps, qs)) = &pqs {
            h = h * ps[m] + qs[m];
        }
        // The encoder's clamp: NaN and x ≤ 0 to 0 (maxps keeps its second operand then),
        // above 1 to 1.
        let h = h.max(Vec4::ZERO).min(Vec4::ONE).to_array();
        for (b, x) in o[4 * m..4 * m + 4].iter_mut().zip(h) {
            *b = enc.encode_unit(x);
        }
    }
}

/// [`shade_row`] one pixel at a time.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn shade_row_x1<const K: usize>(
    decode: &[f32; 256],
    enc: Srgb8Encoder,
    air: [f32; 3],
    t: &[f32],
    pq: Option<(&[f32], &[f32], usize)>,
    src: &[u8],
    out: &mut [u8],
) {
    // Zipped iterators, one loop per case: no bounds check and no branch per pixel.
    let pixels = out.chunks_exact_mut(3).zip(src.chunks_exact(3)).zip(t);
    let hazed = |s: &[u8], t: f32| -> [f32; 3] {
        std::array::from_fn(|ch| blend(decode[usize::from(s[ch])], t, air[ch], 1.0))
    };
    match pq {
        None => {
            for ((o, s), &t) in pixels {
                let v = hazed(s, t);
                for ch in 0..3 {
                    o[ch] = enc.encode(v[ch]);
                }
            }
        }
        Some((p, q, _)) if K == 1 => {
            for ((((o, s), &t), &p), &q) in pixels.zip(p).zip(q) {
                let v = hazed(s, t);
                for ch in 0..3 {
                    o[ch] = enc.encode(v[ch] * p + q);
                }
            }
        }
        Some((p, q, stride)) => {
            let (qr, qg, qb) = (
                &q[..p.len()],
                &q[stride..stride + p.len()],
                &q[2 * stride..2 * stride + p.len()],
            );
            for (((((o, s), &t), &p), &r), (&g, &b)) in pixels.zip(p).zip(qr).zip(qg.iter().zip(qb))
            {
                let v = hazed(s, t);
                let q = [r, g, b];
                for ch in 0..3 {
                    o[ch] = enc.encode(v[ch] * p + q[ch]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::{encode_srgb8, encode_srgb8_formula};
    use crate::frame::scene::SceneLight;
    use crate::frame::stages::Frame;
    use crate::frame::{SceneRef, render_frame};
    use crate::rain::drops::RainRegion;
    use crate::rain::streaks::RainShading;
    use crate::scene::lights::Light;
    use crate::sky::ambient::AmbientMap;
    use crate::sky::{Sky, cie::SkyKind};
    use glam::{Mat3, Vec3};

    /// The SIMD levels this CPU has; AVX2 at least wherever it has AVX2 and FMA (asserted, so
    /// the comparisons are not the scalar code against itself on such a CPU).
    fn simd_levels() -> Vec<Level> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            assert!(simd::best_level() >= Level::Avx2);
        }
        simd::levels()
            .into_iter()
            .filter(|&l| l != Level::Scalar)
            .collect()
    }

    fn decode_table() -> [f32; 256] {
        std::array::from_fn(|k| {
            let v = k as f32 / 255.0;
            if v <= 0.040_45 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        })
    }

    /// A photo with a near wall on the left, a far street and sky, and bytes that sweep
    /// 0..255. The tests use 61 rows (the last band is short) and 300 columns (three tiles,
    /// the last narrow).
    fn photo(w: usize, h: usize) -> (Vec<u8>, Vec<f32>) {
        let srgb = (0..w * h * 3)
            .map(|i| ((i * 37 + i / 7) % 256) as u8)
            .collect();
        let depth = (0..w * h)
            .map(|i| match (i % w, i / w) {
                (x, _) if x < w / 4 => 0.6,
                (_, y) if y < h / 3 => f32::INFINITY,
                (x, y) => 2.0 + 0.3 * x as f32 + 0.5 * y as f32,
            })
            .collect();
        (srgb, depth)
    }

    /// The fused frame against the float frame encoded: bytes within 1 code and nearly all
    /// equal, the same counts and the same coverage layer (returned), through `lens`.
    fn check_against_the_float_frame(
        shading: &RainShading,
        lens: Option<crate::scene::camera::ThinLens>,
    ) -> Vec<f32> {
        let (w, h) = (300usize, 61usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [60.0, 60.0, 150.0, 30.5],
            Vec3::new(0.0, 1.6, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let (srgb, depth) = photo(w, h);
        let dec = decode_table();
        let linear: Vec<f32> = srgb.iter().map(|&b| dec[usize::from(b)]).collect();
        let haze = Haze::new(0.03, [0.4, 0.42, 0.45], 600.0).unwrap();
        let region =
            RainRegion::new(60.0, &[1.0, 1.5, 2.0, 3.0], 4.0, [1.5, 0.0, 0.0], 0.3, 5).unwrap();
        let rf = RainFrame {
            region: &region,
            exposure_s: 1.0 / 30.0,
            camera_velocity_m_s: Vec3::ZERO,
            lens: lens.map(|l| l.defocus(&cam).unwrap()),
            ground: false,
            shelter: &[],
            shading,
        };
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0, 0.4, 0.4, 0.4, 0.4]);
        let light = SceneLight::new(&sky, &amb);
        let reference = render_frame(
            &Frame::new(
                SceneRef::Photo {
                    rgb: &linear,
                    depth_m: &depth,
                },
                &cam,
                &light,
            )
            .with_effects(Some(&haze), Some(&rf), None),
        )
        .unwrap();
        let mut expected = vec![0u8; srgb.len()];
        encode_srgb8(&reference.rgb, &mut expected);
        let mut out = vec![0u8; srgb.len()];
        let mut alpha = vec![0.0f32; w * h];
        let photo = Photo8 {
            srgb: &srgb,
            depth_m: &depth,
            decode: &dec,
        };
        let stats = render_photo8(
            &cam,
            &photo,
            Some(&haze),
            Some(&rf),
            None,
            Photo8Out {
                srgb: &mut out,
                rain_alpha: Some(&mut alpha),
                snow_alpha: None,
            },
        )
        .unwrap()
        .unwrap();
        assert_eq!(reference.rain, Some((stats.rain, stats.drops)));
        let ref_alpha = reference
            .layer(crate::frame::layers::Layer::RainAlpha)
            .unwrap();
        assert!(stats.rain.streaks > 50, "{stats:?}");
        // P·C + Q reassociates the float frame's sums: bytes within 1 code, nearly all equal.
        let diff: Vec<i32> = out
            .iter()
            .zip(&expected)
            .map(|(a, b)| (i32::from(*a) - i32::from(*b)).abs())
            .collect();
        assert!(diff.iter().all(|&d| d <= 1));
        assert!(
            diff.iter().filter(|&&d| d > 0).count() * 1000 <= diff.len(),
            "{} differ",
            diff.iter().filter(|&&d| d > 0).count()
        );
        let alpha_err = alpha
            .iter()
            .zip(ref_alpha)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(
            alpha_err < 1e-6 && ref_alpha.iter().any(|&a| a > 0.01),
            "{alpha_err}"
        );
        ref_alpha.to_vec()
    }

    #[test]
    fn the_fused_8_bit_path_is_the_float_frame_encoded() {
        // Grey light (Q one value per pixel) and a warm lamp by the camera (Q per channel).
        check_against_the_float_frame(&RainShading::open_sky(), None);
        let lamp = Light {
            position_m: Vec3::new(0.5, 1.8, -1.5),
            intensity_cd: 3e4,
            color: Vec3::new(1.0, 0.7, 0.4),
            spot: None,
        };
        let lit = RainShading {
            lights: vec![lamp],
            ..RainShading::open_sky()
        };
        assert!(
            lit.drop_light(Vec3::new(0.5, 1.5, -1.5)).x
                > 2.0 * lit.drop_light(Vec3::new(0.5, 1.5, -1.5)).z
        );
        check_against_the_float_frame(&lit, None);
    }

    #[test]
    fn the_8_bit_path_is_the_float_frame_through_a_lens_too() {
        // A wide aperture focused at 8 m (f = 60 px · 300 mm / 300 px = 60 mm at f/0.7): the
        // near drops' blur circles are several pixels wide, and the frame changes.
        let lens = crate::scene::camera::ThinLens::new(0.7, 8.0, 300.0).unwrap();
        let pinhole = check_against_the_float_frame(&RainShading::open_sky(), None);
        let blurred = check_against_the_float_frame(&RainShading::open_sky(), Some(lens));
        let changed = pinhole
            .iter()
            .zip(&blurred)
            .filter(|(a, b)| (*a - *b).abs() > 1e-3)
            .count();
        assert!(changed * 10 > pinhole.len(), "{changed} pixels changed");
        // the blur spreads the drops' opacity: more pixels covered, the densest less dense
        let covered = |a: &[f32]| a.iter().filter(|&&v| v > 1e-4).count();
        let densest = |a: &[f32]| a.iter().fold(0.0f32, |m, &v| m.max(v));
        assert!(covered(&blurred) > covered(&pinhole) && densest(&blurred) < densest(&pinhole));
    }

    #[test]
    fn four_pixels_at_a_time_give_the_one_by_one_bits() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(21);
        let dec = decode_table();
        let enc = Srgb8Encoder::new();
        for n in (0..=13).chain([128, 131]) {
            let src: Vec<u8> = (0..3 * n).map(|_| rng.random()).collect();
            let t: Vec<f32> = (0..n)
                .map(|_| {
                    if rng.random_bool(0.2) {
                        1.0
                    } else {
                        rng.random()
                    }
                })
                .collect();
            let p: Vec<f32> = (0..n).map(|_| rng.random()).collect();
            let q: Vec<f32> = (0..n).map(|_| rng.random_range(0.0..2.0)).collect();
            for air in [[0.3, 1.5, 0.0], [0.0; 3]] {
                for maps in [None, Some((&p[..], &q[..], n))] {
                    let (mut a, mut b) = (vec![0u8; 3 * n], vec![0u8; 3 * n]);
                    shade_row::<1>(&dec, enc, air, &t, maps, &src, &mut a);
                    shade_row_x1::<1>(&dec, enc, air, &t, maps, &src, &mut b);
                    assert_eq!(a, b, "n = {n}");
                }
            }
        }
    }

    #[test]
    fn the_simd_shading_gives_the_scalar_bits_on_every_code() {
        // Every code in every channel over a grid of transmittances and maps, each row length
        // past whole groups (every lane remainder 0..16) and unaligned starts, for one Q plane
        // and three, at every SIMD level the CPU has, against the one-by-one reference.
        let levels = simd_levels();
        let dec = decode_table();
        let enc = Srgb8Encoder::new();
        let ts = [0.0, 1e-7, 0.003, 0.1, 0.37, 0.5, 0.81, 0.999_999, 1.0];
        let pqs: [Option<(f32, [f32; 3])>; 6] = [
            None,
            Some((1.0, [0.0; 3])),
            Some((0.0, [0.2, 0.5, 1.2])),
            Some((0.62, [0.013, 0.0, 0.4])),
            Some((0.97, [0.05, 0.9, 0.002])),
            Some((0.3, [1.0, 2.0, 0.7])),
        ];
        let mut rows = 0;
        for air in [[0.4, 0.42, 0.45], [0.3, 1.5, 0.0]] {
            for (j, &tj) in ts.iter().enumerate() {
                for pq in pqs {
                    for rem in 0..16 {
                        for start in [0usize, 1, 3, 6] {
                            let n = 256 + rem;
                            let total = start + n;
                            // pixel i: codes i, 255 − i and i + 85 (mod 256), so each channel
                            // sees all 256; t varies along the row around the grid's value
                            let src: Vec<u8> = (0..total)
                                .flat_map(|i| {
                                    let k = (i - start.min(i)) % 256;
                                    [k as u8, (255 - k) as u8, ((k + 85) % 256) as u8]
                                })
                                .collect();
                            let t: Vec<f32> = (0..total)
                                .map(|i| {
                                    if i % 3 == 0 {
                                        tj
                                    } else {
                                        ts[(i + j) % ts.len()]
                                    }
                                })
                                .collect();
                            let stride = total + 5;
                            let (p0, q0) = pq.unwrap_or((1.0, [0.0; 3]));
                            let p: Vec<f32> = (0..total)
                                .map(|i| if i % 2 == 0 { p0 } else { p0 * 0.5 })
                                .collect();
                            let q: Vec<f32> = (0..3 * stride)
                                .map(|i| q0[i / stride] * (1.0 + (i % 7) as f32 * 0.01))
                                .collect();
                            let maps = pq.map(|_| (&p[start..], &q[start..], stride));
                            for (k, &level) in [1, 3]
                                .iter()
                                .flat_map(|k| levels.iter().map(move |l| (*k, l)))
                            {
                                let (mut a, mut b) = (vec![0u8; 3 * n], vec![0u8; 3 * n]);
                                let (s, tt) = (&src[3 * start..], &t[start..]);
                                if k == 1 {
                                    shade_row_at::<1>(level, &dec, enc, air, tt, maps, s, &mut a);
                                    shade_row_x1::<1>(&dec, enc, air, tt, maps, s, &mut b);
                                } else {
                                    shade_row_at::<3>(level, &dec, enc, air, tt, maps, s, &mut a);
                                    shade_row_x1::<3>(&dec, enc, air, tt, maps, s, &mut b);
                                }
                                assert_eq!(
                                    a, b,
                                    "{level:?} K {k} t {tj} maps {pq:?} n {n} start {start}"
                                );
                                rows += 1;
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(rows, 2 * 9 * 6 * 16 * 4 * 2 * levels.len());
    }

    #[test]
    fn the_simd_shading_rounds_as_the_scalar_code_at_the_thresholds() {
        // Values that land within a few ulp of the encoder's thresholds, where one rounding
        // done otherwise (a fused multiply-add, another order) changes the byte: t chosen so
        // the hazed value meets a threshold (no maps), or Q so the mapped one does.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        let dec = decode_table();
        let enc = Srgb8Encoder::new();
        let thr = enc.thresholds();
        let air = [0.4f32, 0.42, 0.45];
        let near = |x: f32, rng: &mut rand_pcg::Pcg64Mcg| {
            f32::from_bits((x.to_bits() as i64 + rng.random_range(-3..=3)).max(0) as u32)
        };
        for k in [1usize, 3] {
            for mapped in [false, true] {
                let n = 40_000;
                let src: Vec<u8> = (0..3 * n).map(|_| rng.random()).collect();
                let code = |rng: &mut rand_pcg::Pcg64Mcg| thr[rng.random_range(1..255)];
                let mut t = vec![0.0f32; n];
                let p: Vec<f32> = (0..n).map(|_| rng.random_range(0.05..1.0)).collect();
                let mut q = vec![0.0f32; 3 * n];
                for i in 0..n {
                    let ch = i % 3; // the channel aimed at
                    let v = dec[usize::from(src[3 * i + ch])];
                    if mapped {
                        t[i] = rng.random();
                        let hv = v * t[i] + air[ch] * (1.0 - t[i]);
                        for c in 0..3 {
                            let aim = if c == ch || k == 1 { ch } else { c };
                            let hc =
                                dec[usize::from(src[3 * i + aim])] * t[i] + air[aim] * (1.0 - t[i]);
                            let target = code(&mut rng);
                            let qv = near(
                                (target - if c == ch { hv } else { hc } * p[i]).max(0.0),
                                &mut rng,
                            );
                            q[c * n + i] = qv;
                        }
                    } else {
                        let target = code(&mut rng);
                        let d = v - air[ch];
                        t[i] = if d.abs() > 1e-3 {
                            near(((target - air[ch]) / d).clamp(0.0, 1.0), &mut rng)
                        } else {
                            rng.random()
                        };
                    }
                }
                let maps = mapped.then_some((&p[..], &q[..], n));
                for level in simd_levels() {
                    let (mut a, mut b) = (vec![0u8; 3 * n], vec![0u8; 3 * n]);
                    if k == 1 {
                        shade_row_at::<1>(level, &dec, enc, air, &t, maps, &src, &mut a);
                        shade_row_x1::<1>(&dec, enc, air, &t, maps, &src, &mut b);
                    } else {
                        shade_row_at::<3>(level, &dec, enc, air, &t, maps, &src, &mut a);
                        shade_row_x1::<3>(&dec, enc, air, &t, maps, &src, &mut b);
                    }
                    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
                    assert_eq!(differ, 0, "{level:?} K {k} mapped {mapped}");
                }
            }
        }
    }

    #[test]
    fn the_whole_fused_frame_is_the_same_bytes_at_every_simd_level() {
        // render_photo8 with every kernel scalar against each SIMD level the CPU has: haze
        // alone, and haze with rain in grey and in coloured light, on widths whose tiles end
        // past whole groups of eight (300 = 2·128 + 44, 301) and a short last band.
        let lamp = Light {
            position_m: Vec3::new(0.5, 1.8, -1.5),
            intensity_cd: 3e4,
            color: Vec3::new(1.0, 0.7, 0.4),
            spot: None,
        };
        let lit = RainShading {
            lights: vec![lamp],
            ..RainShading::open_sky()
        };
        let dec = decode_table();
        let haze = Haze::new(0.03, [0.4, 0.42, 0.45], 600.0).unwrap();
        let region =
            RainRegion::new(60.0, &[1.0, 1.5, 2.0, 3.0], 4.0, [1.5, 0.0, 0.0], 0.3, 5).unwrap();
        let mut drawn = 0;
        for w in [300usize, 301] {
            let h = 61usize;
            let cam = Camera::new(
                w as u32,
                h as u32,
                [60.0, 60.0, w as f32 / 2.0, 30.5],
                Vec3::new(0.0, 1.6, 0.0),
                Mat3::IDENTITY,
            )
            .unwrap();
            let (srgb, depth) = photo(w, h);
            let photo = Photo8 {
                srgb: &srgb,
                depth_m: &depth,
                decode: &dec,
            };
            for shading in [None, Some(RainShading::open_sky()), Some(lit.clone())] {
                let rf = shading.as_ref().map(|shading| RainFrame {
                    region: &region,
                    exposure_s: 1.0 / 30.0,
                    camera_velocity_m_s: Vec3::ZERO,
                    lens: None,
                    ground: false,
                    shelter: &[],
                    shading,
                });
                let run = |d: Dispatch| {
                    let mut out = vec![0u8; srgb.len()];
                    let mut alpha = vec![0.0f32; w * h];
                    let stats = render_photo8_with(
                        &cam,
                        &photo,
                        Some(&haze),
                        rf.as_ref(),
                        None,
                        Photo8Out {
                            srgb: &mut out,
                            rain_alpha: Some(&mut alpha),
                            snow_alpha: None,
                        },
                        d,
                    )
                    .unwrap();
                    (out, alpha, stats)
                };
                let scalar = run(Dispatch::scalar());
                assert_ne!(scalar.0, srgb);
                for level in simd_levels() {
                    let simd = run(Dispatch::best().capped(level));
                    assert!(scalar.0 == simd.0, "{level:?} w {w}: the bytes differ");
                    assert_eq!(scalar.1, simd.1);
                    assert_eq!(scalar.2, simd.2);
                }
                drawn += scalar.2.map_or(0, |s| s.rain.streaks);
            }
        }
        assert!(drawn > 100, "{drawn}");
    }

    #[test]
    fn without_haze_and_rain_the_bytes_come_back_unchanged() {
        // encode(decode(b)) = b for every byte, and no scratch state leaks from a hazy frame.
        let (w, h) = (96usize, 61usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [60.0, 60.0, 48.0, 30.5],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let (srgb, depth) = photo(w, h);
        let dec = decode_table();
        assert!((0..=255u8).all(|b| encode_srgb8_formula(dec[usize::from(b)]) == b));
        let photo = Photo8 {
            srgb: &srgb,
            depth_m: &depth,
            decode: &dec,
        };
        let mut out = vec![0u8; srgb.len()];
        let haze = Haze::new(0.5, [0.4; 3], 900.0).unwrap();
        render_photo8(
            &cam,
            &photo,
            Some(&haze),
            None,
            None,
            Photo8Out {
                srgb: &mut out,
                rain_alpha: None,
                snow_alpha: None,
            },
        )
        .unwrap();
        assert_ne!(out, srgb);
        let mut alpha = vec![1.0f32; w * h];
        let stats = render_photo8(
            &cam,
            &photo,
            None,
            None,
            None,
            Photo8Out {
                srgb: &mut out,
                rain_alpha: Some(&mut alpha),
                snow_alpha: None,
            },
        )
        .unwrap();
        assert_eq!(stats, None);
        assert_eq!(out, srgb);
        assert!(alpha.iter().all(|&a| a == 0.0));
    }

    #[test]
    fn bad_inputs_name_the_parameter() {
        let cam = Camera::new(4, 2, [4.0, 4.0, 2.0, 1.0], Vec3::ZERO, Mat3::IDENTITY).unwrap();
        let dec = decode_table();
        let srgb = vec![0u8; 24];
        let mut depth = vec![1.0f32; 8];
        let mut out = vec![0u8; 24];
        let short = Photo8 {
            srgb: &srgb[..23],
            depth_m: &depth,
            decode: &dec,
        };
        let e = render_photo8(
            &cam,
            &short,
            None,
            None,
            None,
            Photo8Out {
                srgb: &mut out,
                rain_alpha: None,
                snow_alpha: None,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("image"), "{e}");
        depth[5] = f32::NAN;
        let bad = Photo8 {
            srgb: &srgb,
            depth_m: &depth,
            decode: &dec,
        };
        let e = render_photo8(
            &cam,
            &bad,
            None,
            None,
            None,
            Photo8Out {
                srgb: &mut out,
                rain_alpha: None,
                snow_alpha: None,
            },
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("depth_m") && e.to_string().contains('5'),
            "{e}"
        );
        let ok = Photo8 {
            srgb: &srgb,
            depth_m: &[1.0; 8],
            decode: &dec,
        };
        let e = render_photo8(
            &cam,
            &ok,
            None,
            None,
            None,
            Photo8Out {
                srgb: &mut out[..3],
                rain_alpha: None,
                snow_alpha: None,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("out"), "{e}");
    }
}
