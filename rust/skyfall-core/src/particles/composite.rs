//! The compositor: a band's streaks composited far to near with the depth test, into an
//! [`Accumulator`]. Both CPU outputs use it: the float frame composites the colour in place
//! ([`ColourAccumulator`]); the 8-bit output accumulates each pixel's affine map P·C + Q
//! before the background is decoded (see [`crate::photo8`]).
//!
//! A fragment deeper than the scene at its pixel is hidden (z ≥ depth, tested as
//! 1 ≥ depth/z without the division); the accumulators receive its coverage as 0, which they
//! must treat as nothing (no branch on it).

use super::binning::bin_by_tiles;
use super::streak::{LAYER_SNOW, ScreenStreak};
use super::walk::{for_each_fragment_in, for_each_fragment_x4};
use crate::error::Result;
use crate::scene::camera::Camera;
use glam::{Vec3, Vec4, Vec4Swizzles};

/// Rows per band of the float frame (a task).
pub const BAND_ROWS: usize = 16;

/// What a band's streaks are composited into. `i` indexes the band's pixels; `a` is a
/// fragment's α·coverage after the depth test (0: hidden or missed), `inv_z` its inverse
/// depth, 1/m.
pub trait Accumulator {
    /// Per-streak values the accumulator needs (its light, arranged as the accumulator reads
    /// it), made once per streak and band.
    type Streak;
    /// The per-streak values of `light`, the streak's received light per channel, `r`,
    /// the share of it the streak shows, and `layer`, the effect whose layers it draws into
    /// ([`super::streak::LAYER_RAIN`], [`super::streak::LAYER_SNOW`]).
    fn streak(&self, light: Vec3, r: f32, layer: u8) -> Self::Streak;
    /// Four consecutive pixels of a row from `i` (i + 4 ≤ the band's pixels).
    fn add_x4(&mut self, s: &Self::Streak, i: usize, a: Vec4, inv_z: Vec4);
    /// One pixel.
    fn add(&mut self, s: &Self::Streak, i: usize, a: f32, inv_z: f32);
}

/// Composites the streaks `list` (indices into `streaks`, far to near) over a band: rows
/// `y0..y0 + rows` of a `w`-wide frame, only pixels in the columns `cols`; `depth` holds the
/// band's scene depth (at least its pixels). Steep streaks are walked four pixels at a time.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn composite_band<A: Accumulator>(
    streaks: &[ScreenStreak],
    list: &[u32],
    y0: usize,
    rows: usize,
    w: usize,
    cols: std::ops::Range<usize>,
    depth: &[f32],
    acc: &mut A,
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

/// The float frame's accumulator over a band: the colour composited in place,
/// C ← C + a·r·(I_R − C) (r per streak); per layer, the coverage product ∏(1 − a) (in
/// `alpha` for the rain's particles and `snow_alpha` for the snow's, turned into 1 − it by
/// [`ColourAccumulator::finish`]) and the rain's nearest visible fragment's depth. A layer's
/// buffers may be empty when the list holds no particle of its effect.
pub struct ColourAccumulator<'a> {
    /// Linear RGB of the band, 3 per pixel.
    pub rgb: &'a mut [f32],
    /// ∏(1 − a) of the rain's particles per pixel while compositing.
    pub alpha: &'a mut [f32],
    /// Nearest visible rain particle's depth per pixel, m (inf: none).
    pub rain_depth_m: &'a mut [f32],
    /// ∏(1 − a) of the snow's particles per pixel while compositing.
    pub snow_alpha: &'a mut [f32],
}

impl<'a> ColourAccumulator<'a> {
    /// Starts a band: the coverage products at 1, no depth.
    pub fn new(
        rgb: &'a mut [f32],
        alpha: &'a mut [f32],
        rain_depth_m: &'a mut [f32],
        snow_alpha: &'a mut [f32],
    ) -> Self {
        alpha.fill(1.0);
        rain_depth_m.fill(f32::INFINITY);
        snow_alpha.fill(1.0);
        ColourAccumulator {
            rgb,
            alpha,
            rain_depth_m,
            snow_alpha,
        }
    }

    /// Ends the band: the coverages 1 − ∏(1 − aᵢ).
    pub fn finish(self) {
        for a in self.alpha.iter_mut().chain(self.snow_alpha.iter_mut()) {
            *a = 1.0 - *a;
        }
    }
}

impl Accumulator for ColourAccumulator<'_> {
    /// The light per channel, and as the three vectors of four pixels' twelve interleaved
    /// colour values: R G B R | G B R G | B R G B; r; whether it is the snow's.
    type Streak = ([f32; 3], [Vec4; 3], f32, bool);

    #[inline(always)]
    fn streak(&self, light: Vec3, r: f32, layer: u8) -> Self::Streak {
        let [lr, lg, lb] = light.to_array();
        (
            [lr, lg, lb],
            [
                Vec4::new(lr, lg, lb, lr),
                Vec4::new(lg, lb, lr, lg),
                Vec4::new(lb, lr, lg, lb),
            ],
            r,
            layer == LAYER_SNOW,
        )
    }

    #[inline(always)]
    fn add_x4(&mut self, (_, lv, r, snow): &Self::Streak, i: usize, a: Vec4, inv_z: Vec4) {
        let end = i + 4;
        // As `add`, lane by lane (same bits).
        let ar = a * *r;
        let ars = [ar.xxxy(), ar.yyzz(), ar.zwww()];
        let c = &mut self.rgb[3 * i..3 * end];
        for (m, (ar, l)) in ars.iter().zip(lv).enumerate() {
            let cv = Vec4::from_slice(&c[4 * m..4 * m + 4]);
            (cv + *ar * (*l - cv)).write_to_slice(&mut c[4 * m..4 * m + 4]);
        }
        if *snow {
            let sa = &mut self.snow_alpha[i..end];
            (Vec4::from_slice(sa) * (Vec4::ONE - a)).write_to_slice(sa);
            return;
        }
        let alpha = &mut self.alpha[i..end];
        (Vec4::from_slice(alpha) * (Vec4::ONE - a)).write_to_slice(alpha);
        let z = Vec4::select(a.cmpgt(Vec4::ZERO), Vec4::ONE / inv_z, Vec4::INFINITY);
        let rd = &mut self.rain_depth_m[i..end];
        Vec4::from_slice(rd).min(z).write_to_slice(rd);
    }

    #[inline(always)]
    fn add(&mut self, (light, _, r, snow): &Self::Streak, i: usize, a: f32, inv_z: f32) {
        let ar = a * r;
        for (c, l) in self.rgb[3 * i..3 * i + 3].iter_mut().zip(light) {
            *c += ar * (l - *c);
        }
        if *snow {
            self.snow_alpha[i] *= 1.0 - a;
            return;
        }
        self.alpha[i] *= 1.0 - a;
        let z = if a > 0.0 { 1.0 / inv_z } else { f32::INFINITY };
        self.rain_depth_m[i] = self.rain_depth_m[i].min(z);
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
    let mut acc = ColourAccumulator::new(
        &mut rgb[..3 * px],
        &mut alpha[..na],
        &mut rain_depth_m[..nd],
        &mut snow_alpha[..ns],
    );
    if let Some(far) = far {
        far.composite_colour(y0, px / w, w, depth, &mut acc);
    }
    composite_band(streaks, list, y0, px / w, w, 0..w, depth, &mut acc);
    acc.finish();
}
