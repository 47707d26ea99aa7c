//! Drawing drops as perspective-correct, anti-aliased streaks over a frame, with a depth test.
//!
//! A drop of diameter D moving at velocity u during the exposure T sweeps the segment from
//! p − u·T to p. Both ends are projected (clipped at [`NEAR_CLIP_M`]); the streak is a band
//! whose width is the drop's projected diameter w = D·f/z, interpolated along it. A pixel on
//! the path is covered for the fraction α = w / max(L, w) of the exposure (L: the streak's
//! length in pixels; the screen-space form of seed 000's D / (v T)), times the pixel's
//! coverage of the band, box-filtered: across, clamp(w/2 + ½ − dist, 0, 1) for w ≥ 1 px and
//! w·clamp(1 − dist, 0, 1) below (a drop narrower than a pixel covers it partially); along, a
//! one-pixel ramp at each end. Each streak so adds α·w·L = w² of opacity-area, as in the
//! textures.
//!
//! Brightness (seed 002, eq. 7): a drop shows I_v = r·I_R + (1 − r)·I_T, I_T the background
//! behind it, I_R = k·E_R the light it receives: the sky's horizontal illuminance at the drop
//! (relative 1.0 in the open; read from the ambient-light map when there is one, so drops
//! under a roof are dimmer) plus, per point or spot light, k·I·cone/d² (inverse square; E in
//! lux over the sky's E). Compositing
//! a = α·coverage of it over C gives C + a·r·(I_R − C); streaks are composited far to near.
//! Drops whose I_R is below an optional cull threshold are not drawn (the seed's culling).
//! The `rain_alpha` layer is 1 − ∏(1 − aᵢ), the streaks' coverage; `rain_depth_m` is the
//! nearest visible streak's depth (inf: none). Streak fragments deeper than the scene at that
//! pixel are hidden.

use super::drops::Drop;
use crate::error::Result;
use crate::scene::camera::Camera;
use crate::scene::lights::Light;
use crate::sky::ambient::AmbientMap;
use glam::{Vec2, Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use std::sync::Arc;

/// Streak ends nearer than this (m along the axis) are clipped.
pub const NEAR_CLIP_M: f32 = 0.05;
/// Rows per band processed by one task.
const BAND_ROWS: usize = 16;

/// How streaks are lit: I_v = r·I_R + (1 − r)·I_T.
#[derive(Debug, Clone, PartialEq)]
pub struct RainShading {
    /// r, the share of the drop's own light, in [0, 1].
    pub reflectance: f32,
    /// I_R from the sky (relative units, E/π = 1).
    pub drop_radiance: f32,
    /// Point and spot lights.
    pub lights: Vec<Light>,
    /// The sky's horizontal illuminance E, lux: a light's illuminance E_L adds
    /// drop_radiance · E_L / E to I_R.
    pub sky_illuminance_lux: f32,
    /// Drops whose I_R (brightest channel) is below this are not drawn; None draws all.
    pub cull_threshold: Option<f32>,
    /// Sky illuminance relative to E per position (its "up" channel); None: the open sky, 1.
    pub ambient: Option<Arc<AmbientMap>>,
}

impl RainShading {
    /// Seed 002's constant r (0.5 here), an open-sky drop light I_R = E/π (relative 1.0), no
    /// lights, no culling. The ambient-light map will lower I_R where drops see less sky.
    pub fn open_sky() -> Self {
        RainShading {
            reflectance: 0.5,
            drop_radiance: 1.0,
            lights: Vec::new(),
            sky_illuminance_lux: 10_000.0,
            cull_threshold: None,
            ambient: None,
        }
    }

    /// I_R of a drop at `p`, per channel.
    pub fn drop_light(&self, p: Vec3) -> Vec3 {
        let lit = self
            .lights
            .iter()
            .fold(Vec3::ZERO, |acc, l| acc + l.illuminance_lux(p));
        let sky = self.ambient.as_ref().map_or(1.0, |m| m.sample(p)[0]);
        Vec3::splat(self.drop_radiance * sky)
            + lit * (self.drop_radiance / self.sky_illuminance_lux)
    }
}

/// What the rain pass did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RainStats {
    /// Streaks drawn (on screen, not culled).
    pub streaks: usize,
    /// Drops on screen skipped by the cull threshold.
    pub culled: usize,
}

/// A streak in screen space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScreenStreak {
    a: Vec2,
    b: Vec2,
    inv_za: f32,
    inv_zb: f32,
    wa: f32,
    wb: f32,
    alpha: f32,
    min: Vec2,
    max: Vec2,
    light: Vec3,
    /// Unit direction a → b (+y for a dot) and length, px: per streak, not per pixel.
    dir: Vec2,
    len: f32,
    /// 1/len (0 for a dot), dx/dy and the half-width of a row's window, px, for steep streaks
    /// (see [`for_each_fragment`]): per streak, not per band of rows.
    inv_len: f32,
    slope: f32,
    half: f32,
}

fn to_camera(cam: &Camera, p: glam::Vec3) -> glam::Vec3 {
    cam.rotation.transpose() * (p - cam.position_m)
}

fn project(cam: &Camera, pc: glam::Vec3) -> Vec2 {
    let z = -pc.z;
    Vec2::new(cam.cx + cam.fx * pc.x / z, cam.cy - cam.fy * pc.y / z)
}

/// The distance from a streak's axis beyond which a pixel gets no coverage, px: its widest
/// half-width plus half a pixel, at least one pixel (see [`ScreenStreak::fragment`]).
#[inline]
fn reach(wa: f32, wb: f32) -> f32 {
    (0.5 * wa.max(wb) + 0.5).max(1.0)
}

/// Projects a drop's exposure-long path relative to a camera moving at `camera_velocity_m_s`
/// (the camera's pose is the one at the end of the exposure); None when it is behind.
pub fn screen_streak(
    cam: &Camera,
    d: &Drop,
    exposure_s: f32,
    camera_velocity_m_s: Vec3,
) -> Option<ScreenStreak> {
    let mut pa = to_camera(
        cam,
        d.position_m - (d.velocity_m_s - camera_velocity_m_s) * exposure_s,
    );
    let mut pb = to_camera(cam, d.position_m);
    let (za, zb) = (-pa.z, -pb.z);
    if za < NEAR_CLIP_M && zb < NEAR_CLIP_M {
        return None;
    }
    if za < NEAR_CLIP_M {
        pa = pa + (pb - pa) * ((NEAR_CLIP_M - za) / (zb - za));
    } else if zb < NEAR_CLIP_M {
        pb = pb + (pa - pb) * ((NEAR_CLIP_M - zb) / (za - zb));
    }
    let (za, zb) = (-pa.z, -pb.z);
    let f = 0.5 * (cam.fx + cam.fy);
    let (mut a, mut b) = (project(cam, pa), project(cam, pb));
    let (wa, wb) = (d.diameter_m * f / za, d.diameter_m * f / zb);
    let mut len = a.distance(b);
    let w_mid = 0.5 * (wa + wb);
    // Every streak carries w² of opacity-area, whatever the exposure: its pixels' coverage
    // sums to α·w·L for L ≥ 1 px, wherever it falls on the pixel grid (the anti-aliased ends
    // are one pixel long), so α = w / L. A path shorter than a pixel or than the drop is wide
    // (a near drop in a short exposure, a drop moving with the camera) is lengthened about its
    // middle to max(w, 1 px): opaque when w ≥ 1 px, as the drop's disc is.
    let l = len.max(w_mid).max(1.0);
    if l > len {
        let dir = if len > 1e-6 { (b - a) / len } else { Vec2::Y };
        let grow = 0.5 * (l - len);
        (a, b) = (a - dir * grow, b + dir * grow);
        len = l;
    }
    let alpha = w_mid / l;
    let r = 0.5 * wa.max(wb) + 1.0;
    let min = a.min(b) - Vec2::splat(r);
    let max = a.max(b) + Vec2::splat(r);
    let on_screen =
        min.x < cam.width as f32 && min.y < cam.height as f32 && max.x > 0.0 && max.y > 0.0;
    if !on_screen || !alpha.is_finite() {
        return None;
    }
    let dir = if len > 1e-6 { (b - a) / len } else { Vec2::Y };
    let inv_len = if len > 1e-6 { 1.0 / len } else { 0.0 };
    // Pixels farther than `reach` from the axis get no coverage; on a steep streak a row's
    // window is the pixels whose centre lies within `half` of the axis' crossing.
    let reach = reach(wa, wb);
    let (slope, half) = if dir.y.abs() > 0.5 {
        (dir.x / dir.y, reach / dir.y.abs())
    } else {
        (0.0, 0.0)
    };
    Some(ScreenStreak {
        a,
        b,
        inv_za: 1.0 / za,
        inv_zb: 1.0 / zb,
        wa,
        wb,
        alpha,
        min,
        max,
        light: Vec3::ONE,
        dir,
        len,
        inv_len,
        slope,
        half,
    })
}

/// Per-pixel buffers the rain pass writes.
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

/// Projects, lights and culls the drops, sorted far to near (stable: ties keep the drops'
/// deterministic order). The GPU backend draws the same list.
pub fn prepare(
    cam: &Camera,
    drops: &[Drop],
    exposure_s: f32,
    camera_velocity_m_s: Vec3,
    shading: &RainShading,
) -> (Vec<ScreenStreak>, RainStats) {
    // Projected and lit in parallel, in the drops' order (rayon's collect keeps it).
    let mut streaks: Vec<ScreenStreak> = drops
        .par_iter()
        .with_min_len(1024)
        .filter_map(|d| {
            screen_streak(cam, d, exposure_s, camera_velocity_m_s).map(|mut s| {
                s.light = shading.drop_light(d.position_m);
                s
            })
        })
        .collect();
    let mut stats = RainStats::default();
    if let Some(th) = shading.cull_threshold {
        let before = streaks.len();
        streaks.retain(|s| s.light.max_element() >= th);
        stats.culled = before - streaks.len();
    }
    // Far to near, ties in the drops' order: (key, index) pairs are a total order, so the
    // unstable sort of the small pairs gives the stable sort's order, the same in every
    // process, without moving the streaks around.
    let mut order: Vec<(f32, u32)> = streaks
        .iter()
        .enumerate()
        .map(|(i, s)| (s.inv_za + s.inv_zb, i as u32))
        .collect();
    order.par_sort_unstable_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
    permute_in_place(&mut streaks, order.into_iter().map(|(_, i)| i).collect());
    stats.streaks = streaks.len();
    (streaks, stats)
}

/// Reorders `v` so that `v[j]` becomes the old `v[from[j]]` (`from` a permutation of the
/// indices), cycle by cycle, without a second buffer: a frame's streak list is megabytes, and
/// a fresh copy of it per frame costs as many page faults when the allocator hands the memory
/// back to the system between frames.
fn permute_in_place<T: Copy>(v: &mut [T], mut from: Vec<u32>) {
    const DONE: u32 = u32::MAX;
    for start in 0..from.len() {
        if from[start] == DONE {
            continue;
        }
        let first = v[start];
        let mut j = start;
        loop {
            let k = from[j] as usize;
            from[j] = DONE;
            if k == start {
                v[j] = first;
                break;
            }
            v[j] = v[k];
            j = k;
        }
    }
}

impl ScreenStreak {
    /// One value of the streak (to pull its cache line in ahead of use).
    #[inline(always)]
    pub fn touch(&self) -> f32 {
        self.half
    }

    /// The drop's received light I_R, per channel (relative units).
    pub fn light(&self) -> Vec3 {
        self.light
    }

    /// The streak as 16 floats for the GPU pass: a.xy, the unit direction | length, reach
    /// (the distance from the axis beyond which a pixel gets no coverage), w_a, w_b | 1/z_a,
    /// 1/z_b, α, 0 | light rgb, 0. Direction, length and reach are the values
    /// [`Self::fragment`] uses, so the shader does not compute its own.
    pub fn packed(&self) -> [f32; 16] {
        [
            self.a.x,
            self.a.y,
            self.dir.x,
            self.dir.y,
            self.len,
            reach(self.wa, self.wb),
            self.wa,
            self.wb,
            self.inv_za,
            self.inv_zb,
            self.alpha,
            0.0,
            self.light.x,
            self.light.y,
            self.light.z,
            0.0,
        ]
    }

    /// The streak's opacity-area inside a `width` × `height` frame, px²: α times the length of
    /// its axis inside the frame times its mean width there, the sum of its pixels' α·coverage
    /// up to the anti-aliased ends. Over the whole axis it is w² (streaks are at least a pixel
    /// long, see [`screen_streak`]), which goes as 1/z² with the drop's depth z.
    pub fn opacity_area_in(&self, width: f32, height: f32) -> f32 {
        let inside = |p: Vec2| p.x >= 0.0 && p.y >= 0.0 && p.x <= width && p.y <= height;
        if self.len <= 1e-6 {
            let w = 0.5 * (self.wa + self.wb);
            return if inside(self.a) {
                self.alpha * w * w
            } else {
                0.0
            };
        }
        // Liang–Barsky: the part t ∈ [t0, t1] of a + t·(b − a) inside the frame.
        let d = self.b - self.a;
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for (p, q) in [
            (-d.x, self.a.x),
            (d.x, width - self.a.x),
            (-d.y, self.a.y),
            (d.y, height - self.a.y),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return 0.0;
                }
            } else if p < 0.0 {
                t0 = t0.max(q / p);
            } else {
                t1 = t1.min(q / p);
            }
        }
        if t1 <= t0 {
            return 0.0;
        }
        // The width is linear along the axis: its mean over [t0, t1] is its value midway.
        let w = self.wa + (self.wb - self.wa) * (0.5 * (t0 + t1));
        self.alpha * w * self.len * (t1 - t0)
    }

    /// Pixel rows and columns the streak may touch: (x0, x1, y0, y1), end-exclusive, clipped
    /// to a `width` × `height` frame.
    pub fn pixel_bounds(&self, width: u32, height: u32) -> (u32, u32, u32, u32) {
        // Clamped first, so truncation is the floor (no libm floor/ceil on SSE2 targets).
        let lo = |v: f32, hi: u32| floor_nonneg(v.clamp(0.0, hi as f32)) as u32;
        let up = |v: f32, hi: u32| ceil_nonneg(v.clamp(0.0, hi as f32)) as u32;
        (
            lo(self.min.x, width),
            up(self.max.x, width),
            lo(self.min.y, height),
            up(self.max.y, height),
        )
    }

    /// Pixel columns (x0, x1), end-exclusive, that the streak may touch within pixel rows
    /// `rows`, inside its box's columns `bx0..bx1` ([`Self::pixel_bounds`]): a covered pixel's centre lies less
    /// than ½ px beyond either end and less than the reach (½·w + ½, at least 1) across, so
    /// within r = ½·max(w) + 1.5 of the axis segment; the segment's part within r of the rows'
    /// centres, widened by r and a pixel for rounding, holds every column it covers there. A
    /// slanted streak then meets far fewer tiles than its bounding box does.
    fn columns_in_rows(
        &self,
        rows: std::ops::Range<u32>,
        (bx0, bx1): (u32, u32),
        width: u32,
    ) -> (u32, u32) {
        let r = 0.5 * self.wa.max(self.wb) + 1.5;
        let (ylo, yhi) = (
            idx_f32(rows.start as usize) + 0.5 - r,
            idx_f32(rows.end as usize) - 0.5 + r,
        );
        let dy = self.b.y - self.a.y;
        let (t0, t1) = if dy.abs() > 1e-6 {
            let (ta, tb) = ((ylo - self.a.y) / dy, (yhi - self.a.y) / dy);
            (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
        } else {
            (0.0, 1.0)
        };
        // (false for NaN too)
        if t0
            .partial_cmp(&t1)
            .is_none_or(|o| o == std::cmp::Ordering::Greater)
        {
            return (bx0, bx0);
        }
        let (xa, xb) = (
            self.a.x + (self.b.x - self.a.x) * t0,
            self.a.x + (self.b.x - self.a.x) * t1,
        );
        let pad = r + 1.0;
        let lo = |v: f32| floor_nonneg(v.clamp(0.0, width as f32)) as u32;
        let up = |v: f32| ceil_nonneg(v.clamp(0.0, width as f32)) as u32;
        let (x0, x1) = (lo(xa.min(xb) - pad).max(bx0), up(xa.max(xb) + pad).min(bx1));
        (x0, x1.max(x0))
    }

    /// Coverage of the pixel centred at `p` and the depth there: (α·coverage, depth m), or
    /// None when the pixel is off the streak. Mirrored line for line in `rain.wgsl`.
    #[inline]
    pub fn fragment(&self, p: Vec2) -> Option<(f32, f32)> {
        let (dir, len) = (self.dir, self.len);
        let q = p - self.a;
        let along = q.dot(dir);
        let across = q.perp_dot(dir).abs();
        let k = if len > 1e-6 {
            (along / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let width = self.wa + (self.wb - self.wa) * k;
        let cov_across = if width >= 1.0 {
            (0.5 * width + 0.5 - across).clamp(0.0, 1.0)
        } else {
            width * (1.0 - across).clamp(0.0, 1.0)
        };
        let cov_along = (along + 0.5)
            .clamp(0.0, 1.0)
            .min((len - along + 0.5).clamp(0.0, 1.0));
        let cov = cov_across * cov_along;
        if cov <= 0.0 {
            return None;
        }
        Some((
            self.alpha * cov,
            1.0 / (self.inv_za + (self.inv_zb - self.inv_za) * k),
        ))
    }

    /// [`Self::fragment`]'s coverage and inverse depth (0 off the streak) at the point
    /// `along` px along the axis from `a` and `across` px off it, for the walk of
    /// [`for_each_fragment`]: a product by 1/L for the division by L, compare-selects for the
    /// clamps. `THIN`: the streak is under a pixel wide all along (the coverage across is
    /// w·(1 − d)).
    #[inline(always)]
    fn coverage<const THIN: bool>(&self, along: f32, across: f32) -> (f32, f32) {
        let k = clamp01(along * self.inv_len);
        let width = self.wa + (self.wb - self.wa) * k;
        let cov_across = if THIN {
            width * pos(1.0 - across)
        } else if width >= 1.0 {
            clamp01(0.5 * width + 0.5 - across)
        } else {
            width * clamp01(1.0 - across)
        };
        let cov_along = clamp01(least(along, self.len - along) + 0.5);
        (
            self.alpha * cov_across * cov_along,
            self.inv_za + (self.inv_zb - self.inv_za) * k,
        )
    }
}

impl ScreenStreak {
    /// [`Self::coverage`] for four pixels, lane for lane the same bits.
    #[inline(always)]
    fn coverage_x4<const THIN: bool>(&self, along: Vec4, across: Vec4) -> (Vec4, Vec4) {
        let (zero, one, half) = (Vec4::ZERO, Vec4::ONE, Vec4::splat(0.5));
        let clamp01 = |x: Vec4| x.max(zero).min(one);
        let k = clamp01(along * self.inv_len);
        let width = Vec4::splat(self.wa) + Vec4::splat(self.wb - self.wa) * k;
        let cov_across = if THIN {
            width * (one - across).max(zero)
        } else {
            let wide = clamp01(half * width + half - across);
            let thin = width * clamp01(one - across);
            Vec4::select(width.cmpge(one), wide, thin)
        };
        let cov_along = clamp01(along.min(Vec4::splat(self.len) - along) + half);
        (
            Vec4::splat(self.alpha) * cov_across * cov_along,
            Vec4::splat(self.inv_za) + Vec4::splat(self.inv_zb - self.inv_za) * k,
        )
    }
}

/// Per row of `tile_w` × `tile_h` tiles that a streak may touch, `f(row, first column, end
/// column)` (end-exclusive), rows in order: its bounding box's columns when the box is a single
/// column of tiles, else per row the columns it can reach there (see
/// [`ScreenStreak::columns_in_rows`]: a slanted streak meets far fewer tiles than its box).
#[inline]
fn tile_spans(
    s: &ScreenStreak,
    width: u32,
    height: u32,
    tile_w: u32,
    tile_h: u32,
    mut f: impl FnMut(u32, u32, u32),
) {
    let (x0, x1, y0, y1) = s.pixel_bounds(width, height);
    let (i0, i1) = (x0 / tile_w, x1.div_ceil(tile_w));
    if i1 <= i0 + 1 {
        for j in y0 / tile_h..y1.div_ceil(tile_h) {
            f(j, i0, i1);
        }
        return;
    }
    for j in y0 / tile_h..y1.div_ceil(tile_h) {
        let rows = (j * tile_h).max(y0)..((j + 1) * tile_h).min(y1);
        let (c0, c1) = s.columns_in_rows(rows, (x0, x1), width);
        if c1 > c0 {
            f(j, c0 / tile_w, c1.div_ceil(tile_w));
        }
    }
}

/// Streak indices per `tile` × `tile` pixel tile, in list order (see [`bin_by_tiles`]). For the
/// GPU pass.
pub fn bin_by_tile(
    streaks: &[ScreenStreak],
    width: u32,
    height: u32,
    tile: u32,
) -> (Vec<u32>, Vec<u32>) {
    bin_by_tiles(streaks, width, height, tile, tile)
}

/// Streak indices per `tile_w` × `tile_h` pixel tile (row-major tiles), in list order:
/// (offsets, indices) with the tile t's streaks at `indices[offsets[t]..offsets[t + 1]]`.
/// The two halves of the list are binned in parallel and joined tile by tile.
pub fn bin_by_tiles(
    streaks: &[ScreenStreak],
    width: u32,
    height: u32,
    tile_w: u32,
    tile_h: u32,
) -> (Vec<u32>, Vec<u32>) {
    let tx = width.div_ceil(tile_w);
    let tiles = (tx * height.div_ceil(tile_h)) as usize;
    let half = streaks.len() / 2;
    let bin = |first: usize, part: &[ScreenStreak]| {
        let mut counts = vec![0u32; tiles + 1];
        for s in part {
            tile_spans(s, width, height, tile_w, tile_h, |j, i0, i1| {
                for i in i0..i1 {
                    counts[(j * tx + i) as usize + 1] += 1;
                }
            });
        }
        for t in 1..counts.len() {
            counts[t] += counts[t - 1];
        }
        let mut fill = counts.clone();
        let mut indices = vec![0u32; counts[tiles] as usize];
        for (k, s) in part.iter().enumerate() {
            tile_spans(s, width, height, tile_w, tile_h, |j, i0, i1| {
                for i in i0..i1 {
                    let t = (j * tx + i) as usize;
                    indices[fill[t] as usize] = (first + k) as u32;
                    fill[t] += 1;
                }
            });
        }
        (counts, indices)
    };
    let ((oa, ia), (ob, ib)) =
        rayon::join(|| bin(0, &streaks[..half]), || bin(half, &streaks[half..]));
    // Tile t: the first half's streaks, then the second's (list order).
    let mut offsets = Vec::with_capacity(tiles + 1);
    let mut indices = Vec::with_capacity(ia.len() + ib.len());
    offsets.push(0u32);
    for t in 0..tiles {
        indices.extend_from_slice(&ia[oa[t] as usize..oa[t + 1] as usize]);
        indices.extend_from_slice(&ib[ob[t] as usize..ob[t + 1] as usize]);
        offsets.push(indices.len() as u32);
    }
    (offsets, indices)
}

/// The rain a frame draws.
#[derive(Debug, Clone, Copy)]
pub struct RainFrame<'a> {
    /// Which drops.
    pub region: &'a super::drops::RainRegion,
    /// The camera's exposure, s.
    pub exposure_s: f32,
    /// The camera's velocity, m/s: streaks follow the drops' motion relative to it.
    pub camera_velocity_m_s: Vec3,
    /// Whether the ground bounds the rain.
    pub ground: bool,
    /// Boxes that shelter the rain (see [`super::shelter`]); empty: none.
    pub shelter: &'a [crate::scene::boxes::SceneBox],
    /// How drops are lit and culled.
    pub shading: &'a RainShading,
}

impl RainFrame<'_> {
    /// The frame's streaks (see [`prepare`]), its stats, and how many drops there were (those
    /// of the voxels that can reach the view, less the sheltered ones).
    pub fn streaks(&self, cam: &Camera) -> Result<(Vec<ScreenStreak>, RainStats, usize)> {
        self.region
            .check_budget(cam.view_solid_angle_sr() / (4.0 * std::f64::consts::PI))?;
        let (t, v) = (
            f64::from(self.exposure_s),
            f64::from(self.camera_velocity_m_s.length()),
        );
        let mut drops = match self.region.method {
            super::drops::RainMethod::Drops => {
                super::drops::drops_in_view(self.region, cam, t, v, self.ground)
            }
            super::drops::RainMethod::Billboards => super::billboards::billboards_in_view(
                self.region,
                cam,
                t,
                self.camera_velocity_m_s,
                self.ground,
            ),
        };
        super::shelter::remove_sheltered(
            &mut drops,
            self.shelter,
            cam.position_m,
            self.region.near_m as f32,
        );
        let (streaks, stats) = prepare(
            cam,
            &drops,
            self.exposure_s,
            self.camera_velocity_m_s,
            self.shading,
        );
        Ok((streaks, stats, drops.len()))
    }
}

/// Composites the drops' streaks over the frame, far to near, for a camera at rest.
pub fn composite(
    cam: &Camera,
    drops: &[Drop],
    exposure_s: f32,
    shading: &RainShading,
    t: RainTargets<'_>,
) -> RainStats {
    let (streaks, stats) = prepare(cam, drops, exposure_s, Vec3::ZERO, shading);
    composite_streaks(cam, &streaks, shading.reflectance, t);
    stats
}

/// ⌊v⌋ for v ≥ 0 (as an index; no libm call on targets without a rounding instruction).
#[inline]
fn floor_nonneg(v: f32) -> usize {
    // Through i32: one truncating conversion (f32 → u64 has no instruction before AVX-512).
    v as i32 as usize
}

/// A pixel index as f32 (exact below 2²⁴): through u32, one conversion instruction where
/// usize → f32 takes a branchy sequence.
#[inline(always)]
fn idx_f32(v: usize) -> f32 {
    v as u32 as f32
}

/// ⌈v⌉ for v ≥ 0.
#[inline]
fn ceil_nonneg(v: f32) -> usize {
    let t = floor_nonneg(v);
    t + usize::from(idx_f32(t) < v)
}

/// Calls `f(i, a, inv_z)` for the pixels of rows `y0..y0 + rows` (a band of a `w`-wide
/// frame) that the streak may cover: `i` the index within the band, `a` = α·coverage (0 where
/// it misses the pixel: `f` must treat a = 0 as nothing) and `inv_z` the streak's inverse depth
/// there (1/m), as [`ScreenStreak::fragment`] computes them (up to rounding: a product by 1/L
/// for the division by L). Far to near order is the caller's.
///
/// On a steep streak each row visits a window of the same width around the axis, so the
/// loops have fixed trip counts and the coverage no branch: the branches of a data-dependent
/// span mispredict on nearly every row of a thin streak.
#[inline]
pub fn for_each_fragment(
    s: &ScreenStreak,
    y0: usize,
    rows: usize,
    w: usize,
    f: impl FnMut(usize, f32, f32),
) {
    for_each_fragment_in(s, y0, rows, w, 0..w, f);
}

/// [`for_each_fragment`], the shallow streaks' rows walked only within the columns `cols`
/// (steep streaks' windows are a few pixels: the caller filters those by column).
pub fn for_each_fragment_in(
    s: &ScreenStreak,
    y0: usize,
    rows: usize,
    w: usize,
    cols: std::ops::Range<usize>,
    mut f: impl FnMut(usize, f32, f32),
) {
    if s.max.y <= idx_f32(y0)
        || s.min.y >= idx_f32(y0 + rows)
        || s.max.x <= 0.0
        || s.min.x >= idx_f32(w)
    {
        return;
    }
    let (ya, yb) = (
        floor_nonneg(s.min.y.max(idx_f32(y0))),
        ceil_nonneg(s.max.y.min(idx_f32(y0 + rows))),
    );
    let steep = s.half > 0.0;
    if steep {
        let (slope, half) = (s.slope, s.half);
        // A pixel is covered only if its centre lies strictly within `half` of the axis'
        // crossing: an open interval of 2·half holds at most ⌈2·half⌉ pixel centres, the first
        // at ⌊xc − half + ½⌋.
        let span = ceil_nonneg(2.0 * half).clamp(1, w);
        let rows_of = SteepRows {
            s,
            y0,
            w,
            slope,
            half,
        };
        // Thin (w < 1 px all along): the coverage across is w·(1 − d). The drawing paths walk
        // steep streaks with for_each_fragment_x4; this walk is their fallback and reference.
        if s.wa.max(s.wb) < 1.0 {
            rows_of.run::<true>(ya..yb, span, &mut f);
        } else {
            rows_of.run::<false>(ya..yb, span, &mut f);
        }
    } else {
        let (dx, dy) = (s.dir.x, s.dir.y);
        // Within the bounds and `cols`, and on each row within the window where the pixel
        // centre can be covered: −½ < along < len + ½ and across < reach (both linear in the
        // column; |dx| ≥ √¾ for a shallow streak), widened by a pixel for rounding. The other
        // pixels of the row have no coverage.
        let (bx0, bx1) = (
            s.min.x.max(0.0).max(idx_f32(cols.start)),
            s.max.x.min(idx_f32(w)).min(idx_f32(cols.end.min(w))),
        );
        if bx1 <= bx0 {
            return;
        }
        let reach = reach(s.wa, s.wb);
        for y in ya..yb {
            let qy = idx_f32(y) + 0.5 - s.a.y;
            // along = qy·dy + qx·dx and across = qx·dy − qy·dx, with qx = x + ½ − a.x
            let (l0, l1) = ((-0.5 - qy * dy) / dx, (s.len + 0.5 - qy * dy) / dx);
            let (mut lo, mut hi) = (l0.min(l1), l0.max(l1));
            if dy.abs() > 1e-3 {
                let (c0, c1) = ((qy * dx - reach) / dy, (qy * dx + reach) / dy);
                lo = lo.max(c0.min(c1));
                hi = hi.min(c0.max(c1));
            }
            let (lo, hi) = (
                (lo + s.a.x - 0.5 - 1.0).max(bx0),
                (hi + s.a.x - 0.5 + 1.0).min(bx1),
            );
            if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
                continue;
            }
            for x in floor_nonneg(lo)..ceil_nonneg(hi) {
                let qx = idx_f32(x) + 0.5 - s.a.x;
                let (a, inv_z) = s.coverage::<false>(qy * dy + qx * dx, (qx * dy - qy * dx).abs());
                f((y - y0) * w + x, a, inv_z);
            }
        }
    }
}

/// [`for_each_fragment`] four pixels at a time, within the columns `cols`: calls
/// `f(i, a, inv_z)` with `i` the band index of the first of four consecutive pixels of a row
/// and `a`, `inv_z` theirs, the same values lane for lane (a = 0 where the streak misses a
/// pixel or the pixel is outside `cols`; `f` must treat it as nothing). Every pixel in `cols`
/// the streak covers is in exactly one call; the four pixels may reach up to three columns
/// past `cols` (always within the row). For steep streaks in frames at
/// least a window wide, which are nearly all of them; returns false, having called nothing,
/// for the others (walk those with [`for_each_fragment`]).
#[inline]
pub fn for_each_fragment_x4(
    s: &ScreenStreak,
    y0: usize,
    rows: usize,
    w: usize,
    cols: std::ops::Range<usize>,
    mut f: impl FnMut(usize, Vec4, Vec4),
) -> bool {
    if s.half <= 0.0 {
        return false;
    }
    // Windows of ⌈2·half⌉ pixels (see for_each_fragment), in chunks of four.
    let chunks = ceil_nonneg(2.0 * s.half).max(1).div_ceil(4);
    if 4 * chunks > w {
        return false;
    }
    let cols = cols.start..cols.end.min(w);
    if s.max.y <= idx_f32(y0)
        || s.min.y >= idx_f32(y0 + rows)
        || s.max.x <= idx_f32(cols.start)
        || s.min.x >= idx_f32(cols.end)
    {
        return true;
    }
    let (ya, yb) = (
        floor_nonneg(s.min.y.max(idx_f32(y0))),
        ceil_nonneg(s.max.y.min(idx_f32(y0 + rows))),
    );
    let thin = s.wa.max(s.wb) < 1.0;
    let c = (idx_f32(cols.start), idx_f32(cols.end));
    match (thin, chunks) {
        (true, 1) => steep_x4::<true, 1>(s, ya..yb, y0, w, c, &mut f),
        (false, 1) => steep_x4::<false, 1>(s, ya..yb, y0, w, c, &mut f),
        (false, 2) => steep_x4::<false, 2>(s, ya..yb, y0, w, c, &mut f),
        (_, _) => steep_x4::<false, 0>(s, ya..yb, y0, w, c, &mut f),
    }
    true
}

/// The rows `ys` of a steep streak, `f` per chunk of four pixels of each row's window
/// (`CHUNKS` chunks; 0: as many as the window needs), lanes outside the columns
/// [`cols.0`, `cols.1`) zeroed. `THIN`: under a pixel wide all along.
#[inline(always)]
fn steep_x4<const THIN: bool, const CHUNKS: usize>(
    s: &ScreenStreak,
    ys: std::ops::Range<usize>,
    y0: usize,
    w: usize,
    cols: (f32, f32),
    f: &mut impl FnMut(usize, Vec4, Vec4),
) {
    let (c0, c1) = (Vec4::splat(cols.0), Vec4::splat(cols.1));
    let inside = |x: Vec4, a: Vec4| Vec4::select(x.cmpge(c0) & x.cmplt(c1), a, Vec4::ZERO);
    let chunks = if CHUNKS > 0 {
        CHUNKS
    } else {
        ceil_nonneg(2.0 * s.half).max(1).div_ceil(4)
    };
    let (dx, dy) = (s.dir.x, s.dir.y);
    let last = w - 4 * chunks;
    let lanes = Vec4::new(0.0, 1.0, 2.0, 3.0);
    let mut ys = ys;
    if CHUNKS == 1 {
        // Windows of up to four pixels (nearly every streak): four rows at a time, one per
        // lane. The rows' windows and coverages are computed side by side (a row alone is a
        // chain of dependent steps, float to integer and back, that leaves the core mostly
        // waiting), then transposed to four pixels per row.
        let (ax, ay) = (Vec4::splat(s.a.x), Vec4::splat(s.a.y));
        let lastf = idx_f32(last);
        while ys.len() >= 4 {
            let y = ys.start;
            let qy = Vec4::splat(idx_f32(y)) + lanes + Vec4::splat(0.5) - ay;
            let xc = ax + qy * s.slope;
            let x0 = (xc - Vec4::splat(s.half) + Vec4::splat(0.5))
                .max(Vec4::ZERO)
                .floor()
                .min(Vec4::splat(lastf));
            let qx0 = x0 + Vec4::splat(0.5) - ax;
            let (along0, across0) = (qy * dy + qx0 * dx, qx0 * dy - qy * dx);
            let mut cov = [Vec4::ZERO; 4];
            let mut inv = [Vec4::ZERO; 4];
            for j in 0..4 {
                let jf = idx_f32(j);
                (cov[j], inv[j]) = s.coverage_x4::<THIN>(
                    along0 + Vec4::splat(jf * dx),
                    (across0 + Vec4::splat(jf * dy)).abs(),
                );
            }
            // (pixel j, row l) → (row l, pixel j)
            let cov = glam::Mat4::from_cols(cov[0], cov[1], cov[2], cov[3]).transpose();
            let inv = glam::Mat4::from_cols(inv[0], inv[1], inv[2], inv[3]).transpose();
            // x0 holds whole numbers in [0, 2²³): adding 2²³ puts each in the low mantissa
            // bits, read without a float-to-integer conversion.
            let x0f = x0;
            let x0 = (x0 + Vec4::splat(8_388_608.0)).to_array();
            for l in 0..4 {
                let x = Vec4::splat(x0f[l]) + lanes;
                f(
                    (y + l - y0) * w + (x0[l].to_bits() - 0x4B00_0000) as usize,
                    inside(x, cov.col(l)),
                    inv.col(l),
                );
            }
            ys.start += 4;
        }
    }
    for y in ys {
        let qy = idx_f32(y) + 0.5 - s.a.y;
        let xc = s.a.x + qy * s.slope;
        let x0 = floor_nonneg((xc - s.half + 0.5).max(0.0)).min(last);
        let qx0 = idx_f32(x0) + 0.5 - s.a.x;
        let (along0, across0) = (qy * dy + qx0 * dx, qx0 * dy - qy * dx);
        let row = (y - y0) * w + x0;
        for c in 0..chunks {
            // j·dx and j·dy as the scalar walk forms them (same bits).
            let j = lanes + Vec4::splat(idx_f32(4 * c));
            let along = Vec4::splat(along0) + j * dx;
            let across = (Vec4::splat(across0) + j * dy).abs();
            let (a, inv_z) = s.coverage_x4::<THIN>(along, across);
            f(
                row + 4 * c,
                inside(Vec4::splat(idx_f32(x0 + 4 * c)) + lanes, a),
                inv_z,
            );
        }
    }
}

/// A steep streak's rows (see [`for_each_fragment`]).
struct SteepRows<'a> {
    s: &'a ScreenStreak,
    y0: usize,
    w: usize,
    slope: f32,
    half: f32,
}

impl SteepRows<'_> {
    /// Visits the window of `span` pixels on each row of `ys`; `THIN`: the streak is under a
    /// pixel wide all along.
    #[inline(always)]
    fn run<const THIN: bool>(
        &self,
        ys: std::ops::Range<usize>,
        span: usize,
        f: &mut impl FnMut(usize, f32, f32),
    ) {
        let s = self.s;
        let (dx, dy) = (s.dir.x, s.dir.y);
        for y in ys {
            let qy = idx_f32(y) + 0.5 - s.a.y;
            let xc = s.a.x + qy * self.slope;
            let x0 = floor_nonneg((xc - self.half + 0.5).max(0.0)).min(self.w - span);
            let qx0 = idx_f32(x0) + 0.5 - s.a.x;
            let (along0, across0) = (qy * dy + qx0 * dx, qx0 * dy - qy * dx);
            let row = (y - self.y0) * self.w + x0;
            for j in 0..span {
                let jf = idx_f32(j);
                let (a, inv_z) = s.coverage::<THIN>(along0 + jf * dx, (across0 + jf * dy).abs());
                f(row + j, a, inv_z);
            }
        }
    }
}

/// max(x, 0) as one compare-select (`f32::max` also handles NaN, which costs instructions;
/// no NaN reaches here).
#[inline(always)]
fn pos(x: f32) -> f32 {
    if x > 0.0 { x } else { 0.0 }
}

/// x clamped to [0, 1] (see [`pos`]).
#[inline(always)]
fn clamp01(x: f32) -> f32 {
    let x = pos(x);
    if x < 1.0 { x } else { 1.0 }
}

/// min(a, b) as one compare-select.
#[inline(always)]
fn least(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// Composites prepared streaks (see [`prepare`]) over the frame, rows in parallel bands; each
/// band draws only the streaks binned to it (see [`bin_by_tiles`]), steep ones four pixels at
/// a time.
pub fn composite_streaks(
    cam: &Camera,
    streaks: &[ScreenStreak],
    reflectance: f32,
    t: RainTargets<'_>,
) {
    let w = cam.width as usize;
    let band = BAND_ROWS * w;
    let r = reflectance;
    let (offsets, indices) =
        bin_by_tiles(streaks, cam.width, cam.height, cam.width, BAND_ROWS as u32);
    t.rgb
        .par_chunks_mut(3 * band)
        .zip(t.depth_m.par_chunks(band))
        .zip(t.alpha.par_chunks_mut(band))
        .zip(t.rain_depth_m.par_chunks_mut(band))
        .enumerate()
        .for_each(|(bi, (((rgb, depth), alpha), rdepth))| {
            let y0 = bi * BAND_ROWS;
            let px = depth.len();
            let rows = px / w;
            // Cut to the band's pixels: one check per four pixels below covers every slice.
            let (rgb, alpha, rdepth) = (&mut rgb[..3 * px], &mut alpha[..px], &mut rdepth[..px]);
            // ∏(1 − a) per pixel in `alpha` (1 − it at the end); colour composited in place.
            alpha.fill(1.0);
            rdepth.fill(f32::INFINITY);
            for &k in &indices[offsets[bi] as usize..offsets[bi + 1] as usize] {
                let s = &streaks[k as usize];
                let light = s.light.to_array();
                // Four pixels' twelve colour values are three vectors: R G B R | G B R G | B R G B.
                let [lr, lg, lb] = light;
                let lv = [
                    Vec4::new(lr, lg, lb, lr),
                    Vec4::new(lg, lb, lr, lg),
                    Vec4::new(lb, lr, lg, lb),
                ];
                let walked = for_each_fragment_x4(s, y0, rows, w, 0..w, |i, a, inv_z| {
                    let Some(end) = i.checked_add(4).filter(|&e| e <= px) else {
                        return;
                    };
                    // As the one-pixel closure below, lane by lane (same bits).
                    let a = Vec4::select(
                        (Vec4::from_slice(&depth[i..end]) * inv_z).cmple(Vec4::ONE),
                        Vec4::ZERO,
                        a,
                    );
                    let ar = a * r;
                    let ars = [ar.xxxy(), ar.yyzz(), ar.zwww()];
                    let c = &mut rgb[3 * i..3 * end];
                    for (m, (ar, l)) in ars.iter().zip(&lv).enumerate() {
                        let cv = Vec4::from_slice(&c[4 * m..4 * m + 4]);
                        (cv + *ar * (*l - cv)).write_to_slice(&mut c[4 * m..4 * m + 4]);
                    }
                    (Vec4::from_slice(&alpha[i..end]) * (Vec4::ONE - a))
                        .write_to_slice(&mut alpha[i..end]);
                    let z = Vec4::select(a.cmpgt(Vec4::ZERO), Vec4::ONE / inv_z, Vec4::INFINITY);
                    Vec4::from_slice(&rdepth[i..end])
                        .min(z)
                        .write_to_slice(&mut rdepth[i..end]);
                });
                if walked {
                    continue;
                }
                for_each_fragment(s, y0, rows, w, |i, a, inv_z| {
                    // Hidden where z ≥ depth (1 ≥ depth/z, without the division); a = 0
                    // leaves the pixel as it is, so there is no branch on it.
                    let a = if 1.0 >= depth[i] * inv_z { 0.0 } else { a };
                    let ar = a * r;
                    for (c, l) in rgb[3 * i..3 * i + 3].iter_mut().zip(light) {
                        *c += ar * (l - *c);
                    }
                    alpha[i] *= 1.0 - a;
                    let z = if a > 0.0 { 1.0 / inv_z } else { f32::INFINITY };
                    rdepth[i] = rdepth[i].min(z);
                });
            }
            for a in alpha.iter_mut() {
                *a = 1.0 - *a;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat3, Vec3};

    #[test]
    fn permuting_in_place_is_the_gathered_copy() {
        use rand::SeedableRng;
        use rand::seq::SliceRandom;
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        for n in [0usize, 1, 2, 7, 1000] {
            let v: Vec<u64> = (0..n as u64).map(|k| k * 7919 % 1009).collect();
            let mut from: Vec<u32> = (0..n as u32).collect();
            from.shuffle(&mut rng);
            let want: Vec<u64> = from.iter().map(|&i| v[i as usize]).collect();
            let mut got = v.clone();
            permute_in_place(&mut got, from);
            assert_eq!(got, want);
        }
    }

    #[test]
    fn opacity_area_is_the_sum_of_the_pixels_coverage() {
        // Against ScreenStreak::fragment summed over every pixel of the frame, for random drops
        // near and far, thin and wide, many leaving the frame: the analytic α·w·(length inside)
        // that the billboards' opacity balance integrates.
        use rand::{Rng, SeedableRng};
        let (w, h) = (96usize, 64usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [60.0, 60.0, 48.0, 32.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(17);
        let (mut checked, mut clipped) = (0, 0);
        for _ in 0..600 {
            let z: f32 = rng.random_range(0.2..6.0);
            let p = Vec3::new(
                rng.random_range(-1.2..1.2) * z,
                rng.random_range(-1.0..1.0) * z,
                -z,
            );
            let v = Vec3::new(
                rng.random_range(-4.0..4.0),
                rng.random_range(-9.0..-2.0),
                rng.random_range(-2.0..2.0),
            );
            let d = Drop {
                position_m: p,
                velocity_m_s: v,
                diameter_m: rng.random_range(0.5e-3..4e-3),
                id: [0; 5],
            };
            let Some(s) = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::ZERO) else {
                continue;
            };
            let sum: f32 = (0..w * h)
                .filter_map(|i| s.fragment(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5)))
                .map(|f| f.0)
                .sum();
            let area = s.opacity_area_in(w as f32, h as f32);
            // The pixel grid samples the streak: its anti-aliased ends and the frame's edges
            // are off by at most about a pixel of length.
            let slack = 2.0 * s.alpha * (s.wa.max(s.wb) + 1.0);
            assert!(
                (sum - area).abs() <= 0.03 * area + slack,
                "{sum} vs {area} ({s:?})"
            );
            checked += 1;
            clipped += usize::from(
                s.min.x < 0.0 || s.min.y < 0.0 || s.max.x > w as f32 || s.max.y > h as f32,
            );
        }
        assert!(
            checked > 200 && clipped > 50,
            "{checked} streaks, {clipped} clipped"
        );
        // off the frame entirely: nothing
        let off = Drop {
            position_m: Vec3::new(5.0, 0.0, -1.0),
            velocity_m_s: Vec3::new(0.0, -6.0, 0.0),
            diameter_m: 2e-3,
            id: [0; 5],
        };
        assert!(
            screen_streak(&cam, &off, 1.0 / 30.0, Vec3::ZERO)
                .is_none_or(|s| s.opacity_area_in(w as f32, h as f32) == 0.0)
        );
    }

    #[test]
    fn the_windowed_walk_visits_every_covered_pixel_with_its_coverage() {
        // Against ScreenStreak::fragment at every pixel (the per-pixel definition rain.wgsl
        // mirrors): random drops near and far, thin and wide, steep and slanted, dots, and
        // streaks leaving the frame; walked in bands of 7 rows.
        use rand::{Rng, SeedableRng};
        let (w, h) = (64usize, 45usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [40.0, 40.0, 32.0, 22.5],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
        let mut checked = 0;
        for _ in 0..400 {
            let z: f32 = rng.random_range(0.1..6.0);
            let p = Vec3::new(
                rng.random_range(-1.0..1.0) * z,
                rng.random_range(-0.8..0.8) * z,
                -z,
            );
            let v = Vec3::new(
                rng.random_range(-6.0..6.0),
                rng.random_range(-9.0..1.0),
                rng.random_range(-3.0..3.0),
            );
            let d = Drop {
                position_m: p,
                velocity_m_s: v,
                diameter_m: rng.random_range(0.5e-3..6e-3),
                id: [0; 5],
            };
            let exposure = if rng.random_bool(0.1) {
                1e-5
            } else {
                1.0 / 30.0
            };
            let Some(s) = screen_streak(&cam, &d, exposure, Vec3::ZERO) else {
                continue;
            };
            let mut walked = vec![0.0f32; w * h];
            for y0 in (0..h).step_by(7) {
                let rows = 7.min(h - y0);
                for_each_fragment(&s, y0, rows, w, |i, a, inv_z| {
                    walked[y0 * w + i] += a;
                    if a > 0.0 {
                        let (_, z) = s
                            .fragment(Vec2::new((i % w) as f32 + 0.5, (y0 + i / w) as f32 + 0.5))
                            .unwrap_or((0.0, f32::NAN));
                        assert!(
                            (1.0 / inv_z - z).abs() <= 1e-4 * z,
                            "{} vs {z}",
                            1.0 / inv_z
                        );
                    }
                });
            }
            for (i, got) in walked.iter().enumerate() {
                let want = s
                    .fragment(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5))
                    .map_or(0.0, |f| f.0);
                // rounding only (the walk steps from the streak's start): nothing missed, nothing extra
                assert!(
                    (got - want).abs() <= 2e-4 * s.alpha,
                    "pixel {i}: {got} vs {want} ({s:?})"
                );
            }
            checked += 1;
        }
        assert!(checked > 100, "{checked}");
    }

    #[test]
    fn the_four_wide_walk_visits_every_covered_pixel_of_its_columns_once() {
        // Against ScreenStreak::fragment at every pixel, walked in bands of 7 rows and tiles
        // of 13 columns (so windows cross tile edges and the frame's right edge): every pixel
        // gets its coverage from exactly one tile, lanes outside a tile carry a = 0.
        use rand::{Rng, SeedableRng};
        let (w, h) = (64usize, 45usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [40.0, 40.0, 32.0, 22.5],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
        let (mut checked, mut thin) = (0, 0);
        for _ in 0..600 {
            let z: f32 = rng.random_range(0.1..6.0);
            let p = Vec3::new(
                rng.random_range(-1.0..1.0) * z,
                rng.random_range(-0.8..0.8) * z,
                -z,
            );
            let v = Vec3::new(
                rng.random_range(-4.0..4.0),
                rng.random_range(-9.0..1.0),
                rng.random_range(-3.0..3.0),
            );
            let d = Drop {
                position_m: p,
                velocity_m_s: v,
                diameter_m: rng.random_range(0.5e-3..6e-3),
                id: [0; 5],
            };
            let Some(s) = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::ZERO) else {
                continue;
            };
            let mut walked = vec![0.0f32; w * h];
            let mut all = true;
            for y0 in (0..h).step_by(7) {
                let rows = 7.min(h - y0);
                for c0 in (0..w).step_by(13) {
                    let cols = c0..(c0 + 13).min(w);
                    all &= for_each_fragment_x4(&s, y0, rows, w, cols.clone(), |i, a, inv_z| {
                        let (row, x) = (i / w, i % w);
                        assert!(row < rows && x + 4 <= w, "{i}");
                        for l in 0..4 {
                            if a[l] > 0.0 {
                                assert!(
                                    cols.contains(&(x + l)),
                                    "lane {l} at x = {} outside {cols:?}",
                                    x + l
                                );
                                let (_, z) = s
                                    .fragment(Vec2::new(
                                        (x + l) as f32 + 0.5,
                                        (y0 + row) as f32 + 0.5,
                                    ))
                                    .unwrap_or((0.0, f32::NAN));
                                assert!(
                                    (1.0 / inv_z[l] - z).abs() <= 1e-4 * z,
                                    "{} vs {z}",
                                    1.0 / inv_z[l]
                                );
                            }
                            walked[(y0 + row) * w + x + l] += a[l];
                        }
                    });
                }
            }
            if !all {
                continue; // not steep: the scalar walk's case
            }
            for (i, got) in walked.iter().enumerate() {
                let want = s
                    .fragment(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5))
                    .map_or(0.0, |f| f.0);
                assert!(
                    (got - want).abs() <= 2e-4 * s.alpha,
                    "pixel {i}: {got} vs {want} ({s:?})"
                );
            }
            checked += 1;
            thin += usize::from(s.wa.max(s.wb) < 1.0);
        }
        assert!(checked > 200 && thin > 50, "{checked} {thin}");
    }

    #[test]
    fn composite_matches_a_per_pixel_reference() {
        // Random streaks (near, far, thin, wide, slanted, crossing band and frame edges) over a
        // random frame and depth, against the definition: every pixel, every streak in order,
        // ScreenStreak::fragment.
        use rand::{Rng, SeedableRng};
        let (w, h) = (300usize, 45usize); // three column tiles, the last narrow
        let cam = Camera::new(
            w as u32,
            h as u32,
            [40.0, 40.0, 150.0, 22.5],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let drops: Vec<Drop> = (0..600)
            .map(|k| {
                let z: f32 = rng.random_range(0.2..6.0);
                let p = Vec3::new(
                    rng.random_range(-4.0..4.0) * z,
                    rng.random_range(-0.8..0.8) * z,
                    -z,
                );
                let v = Vec3::new(
                    rng.random_range(-4.0..4.0),
                    rng.random_range(-9.0..1.0),
                    rng.random_range(-3.0..3.0),
                );
                Drop {
                    position_m: p,
                    velocity_m_s: v,
                    diameter_m: rng.random_range(0.5e-3..5e-3),
                    id: [k, 0, 0, 0, 0],
                }
            })
            .collect();
        let mut shading = RainShading::open_sky();
        shading.drop_radiance = 1.3;
        let (streaks, _) = prepare(&cam, &drops, 1.0 / 30.0, Vec3::ZERO, &shading);
        assert!(streaks.len() > 300);
        let n = w * h;
        let background: Vec<f32> = (0..3 * n).map(|_| rng.random()).collect();
        let depth: Vec<f32> = (0..n)
            .map(|_| {
                if rng.random_bool(0.3) {
                    f32::INFINITY
                } else {
                    rng.random_range(0.3..5.0)
                }
            })
            .collect();
        let (mut rgb, mut alpha, mut rd) = (background.clone(), vec![0.0; n], vec![0.0; n]);
        composite_streaks(
            &cam,
            &streaks,
            0.5,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &depth,
                alpha: &mut alpha,
                rain_depth_m: &mut rd,
            },
        );
        for i in 0..n {
            let p = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let (mut c, mut keep, mut near) = (
                [
                    background[3 * i],
                    background[3 * i + 1],
                    background[3 * i + 2],
                ],
                1.0f32,
                f32::INFINITY,
            );
            for s in &streaks {
                let Some((a, z)) = s.fragment(p) else {
                    continue;
                };
                if z >= depth[i] {
                    continue;
                }
                for (c, l) in c.iter_mut().zip(s.light.to_array()) {
                    *c += a * 0.5 * (l - *c);
                }
                keep *= 1.0 - a;
                near = near.min(z);
            }
            for ch in 0..3 {
                assert!(
                    (rgb[3 * i + ch] - c[ch]).abs() < 2e-4,
                    "pixel {i}: {} vs {}",
                    rgb[3 * i + ch],
                    c[ch]
                );
            }
            assert!(
                (alpha[i] - (1.0 - keep)).abs() < 2e-4,
                "pixel {i}: {} vs {}",
                alpha[i],
                1.0 - keep
            );
            assert!(
                rd[i] == near || (rd[i] - near).abs() < 1e-3 * near,
                "pixel {i}: {} vs {near}",
                rd[i]
            );
        }
        let rained = alpha.iter().filter(|&&a| a > 1e-3).count();
        assert!(rained > n / 20, "{rained}");
    }

    #[test]
    fn binning_lists_each_tiles_streaks_in_order() {
        // Per tile, in list order (the halves are binned in parallel and joined): every streak
        // that covers a pixel of the tile, and only streaks whose pixel bounds meet it. Slanted
        // streaks are listed in far fewer tiles than their bounds meet.
        use rand::{Rng, SeedableRng};
        let (w, h) = (200u32, 90u32);
        let cam = Camera::new(w, h, [80.0, 80.0, 100.0, 45.0], Vec3::ZERO, Mat3::IDENTITY).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(8);
        let streaks: Vec<ScreenStreak> = (0..301)
            .filter_map(|_| {
                let z: f32 = rng.random_range(0.2..6.0);
                let p = Vec3::new(
                    rng.random_range(-1.5..1.5) * z,
                    rng.random_range(-0.8..0.8) * z,
                    -z,
                );
                let v = Vec3::new(
                    rng.random_range(-12.0..12.0),
                    rng.random_range(-9.0..1.0),
                    0.0,
                );
                let d: f32 = rng.random_range(0.5e-3..6e-3);
                screen_streak(
                    &cam,
                    &Drop {
                        position_m: p,
                        velocity_m_s: v,
                        diameter_m: d,
                        id: [0; 5],
                    },
                    1.0 / 30.0,
                    Vec3::ZERO,
                )
            })
            .collect();
        // the tiles each streak covers, pixel by pixel
        let covered: Vec<Vec<(u32, u32)>> = streaks
            .iter()
            .map(|s| {
                let mut px = Vec::new();
                for y in 0..h {
                    for x in 0..w {
                        if s.fragment(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                            .is_some()
                        {
                            px.push((x, y));
                        }
                    }
                }
                px
            })
            .collect();
        for (tw, th) in [(16, 16), (128, 16), (200, 7), (2, 4)] {
            let (offsets, indices) = bin_by_tiles(&streaks, w, h, tw, th);
            let tx = w.div_ceil(tw);
            let mut boxed = 0usize;
            for t in 0..(tx * h.div_ceil(th)) {
                let (x, y) = ((t % tx) * tw, (t / tx) * th);
                let list = &indices[offsets[t as usize] as usize..offsets[t as usize + 1] as usize];
                assert!(
                    list.windows(2).all(|p| p[0] < p[1]),
                    "tile {t} out of order"
                );
                let meets = |k: usize| {
                    let (x0, x1, y0, y1) = streaks[k].pixel_bounds(w, h);
                    x0 < x + tw && x1 > x && y0 < y + th && y1 > y
                };
                boxed += (0..streaks.len()).filter(|&k| meets(k)).count();
                assert!(list.iter().all(|&k| meets(k as usize)), "tile {t}");
                for (k, px) in covered.iter().enumerate() {
                    if px
                        .iter()
                        .any(|&(px, py)| px >= x && px < x + tw && py >= y && py < y + th)
                    {
                        assert!(
                            list.contains(&(k as u32)),
                            "tile {t} ({tw}x{th}) misses streak {k}"
                        );
                    }
                }
            }
            if (tw, th) == (2, 4) {
                // (2096 against 4240 when written)
                assert!(
                    (indices.len() as f64) < 0.6 * boxed as f64,
                    "{} entries, bounds {boxed}",
                    indices.len()
                );
            }
        }
    }

    #[test]
    fn one_streak_carries_its_opacity_area() {
        let cam = Camera::new(
            400,
            400,
            [300.0, 300.0, 200.0, 200.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        // a 2 mm drop 1 m ahead falling 6.5 m/s for 1/30 s: w = 0.6 px, L = 65 px.
        let d = Drop {
            position_m: Vec3::new(0.0, -0.1, -1.0),
            velocity_m_s: Vec3::new(0.0, -6.5, 0.0),
            diameter_m: 2e-3,
            id: [0; 5],
        };
        let n = 400 * 400;
        let mut rgb = vec![0.0; 3 * n];
        let mut alpha = vec![0.0; n];
        let mut rd = vec![0.0; n];
        let depth = vec![f32::INFINITY; n];
        let white = RainShading {
            reflectance: 1.0,
            ..RainShading::open_sky()
        };
        let shown = composite(
            &cam,
            &[d],
            1.0 / 30.0,
            &white,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &depth,
                alpha: &mut alpha,
                rain_depth_m: &mut rd,
            },
        );
        assert_eq!(
            shown,
            RainStats {
                streaks: 1,
                culled: 0
            }
        );
        let w = 2e-3 * 300.0;
        let sum: f32 = alpha.iter().sum();
        // α w L = w² (plus round caps of the capsule, ≤ w² π/4 α): within 5 %.
        assert!((sum / (w * w) - 1.0).abs() < 0.05, "{sum} vs {}", w * w);
        // with r = 1 and I_R = 1 on black, rgb equals the coverage
        assert!((rgb.iter().step_by(3).sum::<f32>() - sum).abs() < 1e-3);
        let nearest = rd.iter().cloned().fold(f32::INFINITY, f32::min);
        assert!((nearest - 1.0).abs() < 0.01);
        // behind a wall at 0.5 m nothing shows
        let wall = vec![0.5f32; n];
        let mut alpha2 = vec![0.0; n];
        composite(
            &cam,
            &[d],
            1.0 / 30.0,
            &white,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &wall,
                alpha: &mut alpha2,
                rain_depth_m: &mut rd,
            },
        );
        assert!(alpha2.iter().all(|&a| a == 0.0));
        // culled when its light is below the threshold
        let culling = RainShading {
            cull_threshold: Some(1.5),
            ..white.clone()
        };
        let stats = composite(
            &cam,
            &[d],
            1.0 / 30.0,
            &culling,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &depth,
                alpha: &mut alpha2,
                rain_depth_m: &mut rd,
            },
        );
        assert_eq!(
            stats,
            RainStats {
                streaks: 0,
                culled: 1
            }
        );
        // a camera moving with the drop sees a dot (the drop's disc), not a streak: a pixel
        // long, at α = w, so that it still carries w²
        let s = screen_streak(&cam, &d, 1.0 / 30.0, d.velocity_m_s).unwrap();
        assert!(
            (s.len - 1.0).abs() < 1e-6 && (s.alpha - w).abs() < 1e-6,
            "{} {}",
            s.len,
            s.alpha
        );
        assert!((s.opacity_area_in(400.0, 400.0) / (w * w) - 1.0).abs() < 1e-4);
        // whatever the exposure, the pixels sum to w² (a still drop: a dot; a near drop in a
        // short exposure: lengthened; 1/30 s: a streak)
        for (v, z, t) in [
            (0.0, 1.0, 1.0 / 30.0),
            (0.0, 0.1, 1.0 / 30.0),
            (6.5, 0.3, 1e-4),
            (6.5, 1.0, 1e-3),
            (6.5, 1.0, 3e-3),
            (6.5, 5.0, 1e-4),
        ] {
            let d = Drop {
                position_m: Vec3::new(0.05, 0.0, -z),
                velocity_m_s: Vec3::new(0.0, -v, 0.0),
                ..d
            };
            let w = 2e-3 * 300.0 / z;
            let mut alpha = vec![0.0; n];
            composite(
                &cam,
                &[d],
                t,
                &white,
                RainTargets {
                    rgb: &mut rgb,
                    depth_m: &depth,
                    alpha: &mut alpha,
                    rain_depth_m: &mut rd,
                },
            );
            let sum: f32 = alpha.iter().sum();
            assert!(
                (sum / (w * w) - 1.0).abs() < 0.02,
                "v {v} z {z} T {t}: {sum} vs {}",
                w * w
            );
        }
        // a camera moving up at 6.5 m/s doubles the streak
        let still = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::ZERO).unwrap();
        let up = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::new(0.0, 6.5, 0.0)).unwrap();
        assert!((up.a.distance(up.b) / still.a.distance(still.b) - 2.0).abs() < 1e-3);
    }
}
