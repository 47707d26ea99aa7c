//! The compositor: a band's streaks composited far to near with the depth test, into an
//! [`Accumulator`]: the colour by a [`Blend`], the particle layers by [`Cover`] (one for every
//! output, indexed by [`PARTICLE_LAYERS`]). The float frame blends the colour in place
//! ([`ColourBlend`]); the 8-bit output accumulates each pixel's affine map P·C + Q before the
//! background is decoded (`frame::srgb8`).
//!
//! A fragment deeper than the scene at its pixel is hidden (z ≥ depth, tested as
//! 1 ≥ depth/z without the division); the accumulators receive its coverage as 0, which they
//! must treat as nothing (no branch on it).

use super::binning::bin_by_tiles;
use super::streak::{PARTICLE_LAYERS, ScreenStreak};
use super::walk::{for_each_fragment_in, for_each_fragment_x4};
use crate::error::Result;
use crate::scene::camera::Camera;
use glam::{Vec3, Vec4, Vec4Swizzles};

/// Rows per band of the float frame (a task).
pub const BAND_ROWS: usize = 16;

/// How a band's streaks change its colour: `a` is a fragment's α·coverage after the depth test
/// (0: hidden or missed), `r` the share of its light the streak shows. The float output blends
/// the colour in place ([`ColourBlend`]); the 8-bit output accumulates each pixel's affine map
/// (`frame::srgb8`). The layers are [`Cover`]'s, the same for both.
pub trait Blend {
    /// Per-streak values the blend needs (its light, arranged as it reads it, and r), made
    /// once per streak and band.
    type Light;
    /// The per-streak values of `light`, the streak's received light per channel, and `r`.
    fn light(&self, light: Vec3, r: f32) -> Self::Light;
    /// Four consecutive pixels of a row from `i` (i + 4 ≤ the band's pixels).
    fn blend_x4(&mut self, l: &Self::Light, i: usize, a: Vec4);
    /// One pixel.
    fn blend(&mut self, l: &Self::Light, i: usize, a: f32);
}

/// The particle layers of a band ([`PARTICLE_LAYERS`], indexed by a particle's layer index):
/// per layer the coverage product ∏(1 − a) while compositing (1 − it after
/// [`Cover::finish`]) and, for a layer with a depth, the nearest visible particle's depth
/// (inf: none). A buffer is empty where it is not kept (a layer the frame does not draw).
pub struct Cover<'a> {
    product: [&'a mut [f32]; PARTICLE_LAYERS.len()],
    depth_m: [&'a mut [f32]; PARTICLE_LAYERS.len()],
}

impl<'a> Cover<'a> {
    /// The layers over buffers the caller has started (products at 1, depths at inf, on the
    /// pixels drawn). A layer without a depth in [`PARTICLE_LAYERS`] keeps no depth buffer.
    pub fn new(
        product: [&'a mut [f32]; PARTICLE_LAYERS.len()],
        mut depth_m: [&'a mut [f32]; PARTICLE_LAYERS.len()],
    ) -> Self {
        for (d, l) in depth_m.iter_mut().zip(&PARTICLE_LAYERS) {
            if l.depth.is_none() {
                *d = &mut [];
            }
        }
        Cover { product, depth_m }
    }

    /// [`Self::new`], the buffers started: the coverage products at 1, no depth.
    pub fn started(
        mut product: [&'a mut [f32]; PARTICLE_LAYERS.len()],
        depth_m: [&'a mut [f32]; PARTICLE_LAYERS.len()],
    ) -> Self {
        for p in product.iter_mut() {
            p.fill(1.0);
        }
        let mut cover = Self::new(product, depth_m);
        for d in cover.depth_m.iter_mut() {
            d.fill(f32::INFINITY);
        }
        cover
    }

    /// The products as coverages, 1 − ∏(1 − aᵢ).
    pub fn finish(self) {
        for p in self.product {
            for a in p.iter_mut() {
                *a = 1.0 - *a;
            }
        }
    }

    #[inline(always)]
    fn add_x4(&mut self, layer: usize, i: usize, a: Vec4, inv_z: Vec4) {
        let end = i + 4;
        if let Some(p) = self.product.get_mut(layer).and_then(|p| p.get_mut(i..end)) {
            (Vec4::from_slice(p) * (Vec4::ONE - a)).write_to_slice(p);
        }
        if let Some(d) = self.depth_m.get_mut(layer).and_then(|d| d.get_mut(i..end)) {
            let z = Vec4::select(a.cmpgt(Vec4::ZERO), Vec4::ONE / inv_z, Vec4::INFINITY);
            Vec4::from_slice(d).min(z).write_to_slice(d);
        }
    }

    #[inline(always)]
    fn add(&mut self, layer: usize, i: usize, a: f32, inv_z: f32) {
        if let Some(p) = self.product.get_mut(layer).and_then(|p| p.get_mut(i)) {
            *p *= 1.0 - a;
        }
        if let Some(d) = self.depth_m.get_mut(layer).and_then(|d| d.get_mut(i)) {
            let z = if a > 0.0 { 1.0 / inv_z } else { f32::INFINITY };
            *d = d.min(z);
        }
    }
}

/// What a band's streaks are composited into: the colour by a [`Blend`], the layers by
/// [`Cover`]. `i` indexes the band's pixels; `a` is a fragment's α·coverage after the depth
/// test (0: hidden or missed, which must change nothing: no branch on it), `inv_z` its
/// inverse depth, 1/m.
pub struct Accumulator<'a, B> {
    /// The colour.
    pub colour: B,
    /// The particle layers.
    pub cover: Cover<'a>,
}

impl<B: Blend> Accumulator<'_, B> {
    /// The per-streak values of a streak: its light per channel, `r`, the share of it the
    /// streak shows, and `layer`, the effect whose layers it draws into
    /// ([`super::streak::LAYER_RAIN`], [`super::streak::LAYER_SNOW`]).
    #[inline(always)]
    pub fn streak(&self, light: Vec3, r: f32, layer: u8) -> (B::Light, usize) {
        (self.colour.light(light, r), usize::from(layer))
    }

    /// Four consecutive pixels of a row from `i` (i + 4 ≤ the band's pixels).
    #[inline(always)]
    pub fn add_x4(&mut self, (l, layer): &(B::Light, usize), i: usize, a: Vec4, inv_z: Vec4) {
        self.colour.blend_x4(l, i, a);
        self.cover.add_x4(*layer, i, a, inv_z);
    }

    /// One pixel.
    #[inline(always)]
    pub fn add(&mut self, (l, layer): &(B::Light, usize), i: usize, a: f32, inv_z: f32) {
        self.colour.blend(l, i, a);
        self.cover.add(*layer, i, a, inv_z);
    }
}

/// Composites the streaks `list` (indices into `streaks`, far to near) over a band: rows
/// `y0..y0 + rows` of a `w`-wide frame, only pixels in the columns `cols`; `depth` holds the
/// band's scene depth (at least its pixels). Steep streaks are walked four pixels at a time.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn composite_band<B: Blend>(
    streaks: &[ScreenStreak],
    list: &[u32],
    y0: usize,
    rows: usize,
    w: usize,
    cols: std::ops::Range<usize>,
    depth: &[f32],
    acc: &mut Accumulator<'_, B>,
) {
    let px = rows * w;
    // Cut to the band: one check per four pixels below (i + 4 ≤ px) covers every slice.
    let depth = &depth[..px];
    for (n, s) in list.iter().map(|&k| &streaks[k as usize]).enumerate() {
        // Touch a streak eight ahead: its cache line (the list is larger than L2) is then on
        // its way while this one is drawn.
        if let Some(&ahead) = list.get(n + 8) {
            std::hint::black_box(streaks[ahead as usize].touch());
        }
        let st = acc.streak(s.light(), s.reflectance(), s.layer());
        let walked = for_each_fragment_x4(s, y0, rows, w, cols.clone(), |i, a, inv_z| {
            let Some(end) = i.checked_add(4).filter(|&e| e <= px) else {
                return;
            };
            let d = Vec4::from_slice(&depth[i..end]);
            let a = Vec4::select((d * inv_z).cmple(Vec4::ONE), Vec4::ZERO, a);
            acc.add_x4(&st, i, a, inv_z);
        });
        if walked {
            continue;
        }
        for_each_fragment_in(s, y0, rows, w, cols.clone(), |i, a, inv_z| {
            if !cols.contains(&(i % w)) {
                return;
            }
            let a = if 1.0 >= depth[i] * inv_z { 0.0 } else { a };
            acc.add(&st, i, a, inv_z);
        });
    }
}

/// The float frame's colour, composited in place over a band: C ← C + a·r·(L − C).
pub struct ColourBlend<'a> {
    /// Linear RGB of the band, 3 per pixel.
    pub rgb: &'a mut [f32],
}

/// The float frame's accumulator over a band.
pub type ColourAccumulator<'a> = Accumulator<'a, ColourBlend<'a>>;

impl Blend for ColourBlend<'_> {
    /// The light per channel, and as the three vectors of four pixels' twelve interleaved
    /// colour values: R G B R | G B R G | B R G B; r.
    type Light = ([f32; 3], [Vec4; 3], f32);

    #[inline(always)]
    fn light(&self, light: Vec3, r: f32) -> Self::Light {
        let [lr, lg, lb] = light.to_array();
        (
            [lr, lg, lb],
            [
                Vec4::new(lr, lg, lb, lr),
                Vec4::new(lg, lb, lr, lg),
                Vec4::new(lb, lr, lg, lb),
            ],
            r,
        )
    }

    #[inline(always)]
    fn blend_x4(&mut self, (_, lv, r): &Self::Light, i: usize, a: Vec4) {
        // As `blend`, lane by lane (same bits).
        let ar = a * *r;
        let ars = [ar.xxxy(), ar.yyzz(), ar.zwww()];
        let c = &mut self.rgb[3 * i..3 * (i + 4)];
        for (m, (ar, l)) in ars.iter().zip(lv).enumerate() {
            let cv = Vec4::from_slice(&c[4 * m..4 * m + 4]);
            (cv + *ar * (*l - cv)).write_to_slice(&mut c[4 * m..4 * m + 4]);
        }
    }

    #[inline(always)]
    fn blend(&mut self, (light, _, r): &Self::Light, i: usize, a: f32) {
        let ar = a * r;
        for (c, l) in self.rgb[3 * i..3 * i + 3].iter_mut().zip(light) {
            *c += ar * (l - *c);
        }
    }
}

/// Per-pixel buffers of a whole frame, for [`composite_streaks`] (the tests' whole-frame
/// compositor; the output stages composite band by band).
#[cfg(test)]
pub struct RainTargets<'a> {
    /// Linear RGB, H·W·3, composited in place.
    pub rgb: &'a mut [f32],
    /// Scene depth, H·W (read).
    pub depth_m: &'a [f32],
    /// Streak coverage 1 − ∏(1 − aᵢ), H·W.
    pub alpha: &'a mut [f32],
    /// Nearest visible streak depth, H·W (inf: none).
    pub rain_depth_m: &'a mut [f32],
}

/// Streak lists per band of [`BAND_ROWS`] full-width rows: (offsets, indices) as
/// [`bin_by_tiles`] gives them.
pub fn bin_by_bands(cam: &Camera, streaks: &[ScreenStreak]) -> Result<(Vec<u32>, Vec<u32>)> {
    bin_by_tiles(streaks, cam.width, cam.height, cam.width, BAND_ROWS as u32)
}

/// Composites prepared streaks (far to near, see [`crate::rain::streaks::prepare`]) over a
/// whole frame, bands of rows in parallel; each band draws only the streaks binned to it.
#[cfg(test)]
pub fn composite_streaks(cam: &Camera, streaks: &[ScreenStreak], t: RainTargets<'_>) -> Result<()> {
    composite_streaks_with_snow(cam, streaks, t, &mut [])
}

/// [`composite_streaks`] with the snow's coverage layer too (H·W, or empty when no flakes).
#[cfg(test)]
pub fn composite_streaks_with_snow(
    cam: &Camera,
    streaks: &[ScreenStreak],
    t: RainTargets<'_>,
    snow_alpha: &mut [f32],
) -> Result<()> {
    use rayon::prelude::*;
    let w = cam.width as usize;
    let band = BAND_ROWS * w;
    let (offsets, indices) = bin_by_bands(cam, streaks)?;
    let bands = t.depth_m.len().div_ceil(band);
    let mut snow: Vec<&mut [f32]> = snow_alpha.chunks_mut(band).collect();
    snow.resize_with(bands, Default::default);
    t.rgb
        .par_chunks_mut(3 * band)
        .zip(t.depth_m.par_chunks(band))
        .zip(t.alpha.par_chunks_mut(band))
        .zip(t.rain_depth_m.par_chunks_mut(band))
        .zip(snow.par_iter_mut())
        .enumerate()
        .for_each(|(bi, ((((rgb, depth), alpha), rdepth), snow))| {
            let list = &indices[offsets[bi] as usize..offsets[bi + 1] as usize];
            composite_band_colour(
                streaks,
                list,
                None,
                bi * BAND_ROWS,
                w,
                depth,
                rgb,
                [alpha, rdepth, snow],
            );
        });
    Ok(())
}

/// Particles drawn as a whole into the accumulator before the listed streaks, behind them all
/// (the rain's far level of detail, `rain::far::FarRain`): a trait here so that the
/// compositor need not import the effects that import it.
pub trait Backdrop: Sync {
    /// Composites rows from `y0` (`rows` of them, `w` wide, every column) into `acc`, with the
    /// depth test against `depth`.
    fn composite_colour(
        &self,
        y0: usize,
        rows: usize,
        w: usize,
        depth: &[f32],
        acc: &mut ColourAccumulator<'_>,
    );
}

/// One band of the float frame: rows from `y0` (as many as `depth` holds), every column, the
/// colour `rgb` composited in place (the rain's far layers `far` first, when given), the
/// layers `[rain_alpha, rain_depth_m, snow_alpha]` overwritten (a layer's buffer empty when
/// no particle of its effect is in the list).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub fn composite_band_colour(
    streaks: &[ScreenStreak],
    list: &[u32],
    far: Option<&dyn Backdrop>,
    y0: usize,
    w: usize,
    depth: &[f32],
    rgb: &mut [f32],
    [alpha, rain_depth_m, snow_alpha]: [&mut [f32]; 3],
) {
    let px = depth.len();
    let cut = |b: &mut [f32]| b.len().min(px);
    let (na, nd, ns) = (cut(alpha), cut(rain_depth_m), cut(snow_alpha));
    let mut acc = Accumulator {
        colour: ColourBlend {
            rgb: &mut rgb[..3 * px],
        },
        cover: Cover::started(
            [&mut alpha[..na], &mut snow_alpha[..ns]],
            [&mut rain_depth_m[..nd], &mut []],
        ),
    };
    if let Some(far) = far {
        far.composite_colour(y0, px / w, w, depth, &mut acc);
    }
    composite_band(streaks, list, y0, px / w, w, 0..w, depth, &mut acc);
    acc.cover.finish();
}
