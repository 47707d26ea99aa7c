//! The cover in a frame: white, lifted surfaces with the albedo of snow, lit as the surfaces
//! are (the ambient-light map, the lamps), and the `snow_depth_m` layer.
//!
//! - **Box scenes**: the snow is the height field's columns from each cell's base up to the
//!   base plus the depth, ray cast cell by cell (a 2D DDA over the grid,
//!   [`SnowRender::trace`]) up to the boxes' own hit; a ray that meets a column's top sees it
//!   with normal +Y, one that meets its side (above the base: below it is the box or the
//!   ground) with that side's normal.
//! - **Photos**: each pixel's world point (depth through the camera) and its normal from the
//!   depth map's neighbours; the snow of its cell lies on it when the point is on the cell's
//!   top surface and the normal faces up ([`super::photo::photo_depth_m`]), then the depth map's noise is
//!   cleaned away (holes in a covered surface filled, lone specks removed, edges kept); the
//!   pixel takes the snow's radiance where the snow's patches cover it.
//!
//! - Beyond the grid, upward faces of a box scene carry the open ground's cover
//!   ([`super::SnowCover::open_depth_m`], not lifted): the far ground of an open scene.
//!
//! **Soft edges.** The columns are the cover's geometry, but what a pixel shows of it, the
//! snow's depth and the surface's normal, is interpolated bilinearly between the centres of
//! the cells on the same surface ([`SnowRender::surface_at`]): the shading of a drift varies
//! smoothly instead of cell by cell, and where the cover ends its depth thins out over a cell,
//! onto the bare cells beside it too (their ground takes the interpolated depth, unlifted).
//!
//! **Thin snow** lies in patches ([`super::look`]): the share c(d) of a surface is under snow
//! (white, [`SNOW_ALBEDO`]) and the rest shows the surface beneath, sharp near the camera and
//! as the patches' mean share far away.

use super::SnowCover;
use super::look::{coverage, drawn_share, footprint_m};
use super::photo::photo_depth_m;
use super::sparkle::sparkle;
use crate::error::{Result, try_with_capacity};
use crate::scene::boxes::{BoxScene, surface_albedo, trace};
use crate::scene::camera::Camera;
use crate::scene::raycast::inverse_direction;
use crate::sky::ambient::AmbientMap;
use glam::Vec3;

use crate::snow::SNOW_ALBEDO;

/// Most height bands [`SnowRender::trace`] keeps apart (more: one).
const MAX_BANDS: usize = 64;

/// A cover's grid as the GPU takes it ([`SnowRender::gpu_grid`]).
#[derive(Debug, Clone, Copy)]
pub struct GpuGrid<'a> {
    /// Origin x, origin z (m), cell side (m), lowest base and highest top with snow (m).
    pub params: [f32; 5],
    /// Cells along x and z.
    pub dims: [u32; 2],
    /// Each cell's base, m (NaN: no surface).
    pub base: &'a [f32],
    /// Each cell's depth of snow, m.
    pub depth: &'a [f32],
    /// Each cell's snow surface slope (∂top/∂x, ∂top/∂z).
    pub slope: &'a [[f32; 2]],
}

/// A cover ready to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct SnowRender {
    /// The disjoint height ranges snow lies in (empty: one, [y_lo, y_hi]); the ray cast visits
    /// only the stretches of a ray within them.
    bands: Vec<(f32, f32)>,
    origin: [f32; 2],
    spacing: f32,
    nx: usize,
    nz: usize,
    base: Vec<f32>,
    depth: Vec<f32>,
    /// Each cell's snow surface slope (∂top/∂x, ∂top/∂z), [`Self::slope_of`].
    slope: Vec<[f32; 2]>,
    y_lo: f32,
    y_hi: f32,
    /// The depth on level open ground, m: drawn on upward faces beyond the grid.
    open_depth: f32,
    /// For a photo: the snow's depth on each pixel's surface, m.
    pub photo_depth_m: Option<Vec<f32>>,
    /// The photo's units relative to the renderer's (the snow's radiance is scaled by it).
    pub radiance_scale: Vec3,
}

impl SnowRender {
    /// The cover of a box scene.
    /// Its copies of the grid are allocated fallibly ([`crate::Error::OutOfMemory`]).
    pub fn boxes(cover: &SnowCover) -> Result<Self> {
        let g = cover.field.grid;
        let what = "the snow cover's render grid";
        let mut base: Vec<f32> = try_with_capacity(what, cover.field.base_m.len())?;
        base.extend(cover.field.base_m.iter().map(|&b| b as f32));
        let mut depth: Vec<f32> = try_with_capacity(what, cover.depth_m.len())?;
        depth.extend(cover.depth_m.iter().map(|&d| d as f32));
        let (mut y_lo, mut y_hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for (&b, &d) in base.iter().zip(depth.iter()) {
            if d > 0.0 && !b.is_nan() {
                y_lo = y_lo.min(b);
                y_hi = y_hi.max(b + d);
            }
        }
        // The heights snow lies at: each cell's [base, top], merged where they overlap.
        let covered = base
            .iter()
            .zip(depth.iter())
            .filter(|(b, d)| **d > 0.0 && !b.is_nan());
        let mut spans: Vec<(f32, f32)> = try_with_capacity(what, covered.clone().count())?;
        spans.extend(covered.map(|(&b, &d)| (b, b + d)));
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut bands: Vec<(f32, f32)> = Vec::new();
        for (lo, hi) in spans {
            match bands.last_mut() {
                Some(last) if lo <= last.1 => last.1 = last.1.max(hi),
                _ => bands.push((lo, hi)),
            }
        }
        if bands.len() > MAX_BANDS {
            bands.clear(); // one slab, [y_lo, y_hi]
        }
        let mut r = SnowRender {
            bands,
            origin: [g.origin_m[0] as f32, g.origin_m[1] as f32],
            spacing: g.spacing_m as f32,
            nx: g.nx,
            nz: g.nz,
            base,
            depth,
            slope: Vec::new(),
            y_lo,
            y_hi,
            open_depth: cover.open_depth_m as f32,
            photo_depth_m: None,
            radiance_scale: Vec3::ONE,
        };
        let mut slope: Vec<[f32; 2]> = try_with_capacity(what, r.depth.len())?;
        slope.extend((0..r.depth.len()).map(|c| r.slope_of(c % r.nx, c / r.nx)));
        r.slope = slope;
        Ok(r)
    }

    /// The cover of a photo seen by `cam` with `depth_m`, in the photo's units
    /// `radiance_scale`.
    pub fn photo(
        cover: &SnowCover,
        cam: &Camera,
        depth_m: &[f32],
        radiance_scale: Vec3,
    ) -> Result<Self> {
        if depth_m.len() != cam.pixels() {
            return Err(crate::error::Error::Length {
                param: crate::error::Param {
                    name: "depth_m",
                    index: None,
                },
                len: depth_m.len(),
                expected: cam.pixels(),
            });
        }
        let mut r = SnowRender::boxes(cover)?;
        r.photo_depth_m = Some(photo_depth_m(cover, cam, depth_m)?);
        r.radiance_scale = radiance_scale;
        // A photo's snow is drawn per pixel, never ray cast.
        r.y_lo = f32::INFINITY;
        r.y_hi = f32::NEG_INFINITY;
        Ok(r)
    }

    /// The grid's flat buffers for the GPU.
    pub fn gpu_grid(&self) -> GpuGrid<'_> {
        GpuGrid {
            params: [
                self.origin[0],
                self.origin[1],
                self.spacing,
                self.y_lo,
                self.y_hi,
            ],
            dims: [self.nx as u32, self.nz as u32],
            base: &self.base,
            depth: &self.depth,
            slope: &self.slope,
        }
    }

    /// The snow surface's normal over cell (i, k): (−∂top/∂x, 1, −∂top/∂z) normalised, of its
    /// [`Self::slope_of`] (made once per cell).
    #[inline]
    fn normal(&self, i: usize, k: usize) -> Vec3 {
        let [gx, gz] = self.slope[k * self.nx + i];
        Vec3::new(-gx, 1.0, -gz).normalize()
    }

    /// The snow surface's slope over cell (i, k): the central differences of its top over the
    /// neighbours that carry snow on the same surface (bases within a cell's width), each
    /// clamped to ±1.
    fn slope_of(&self, i: usize, k: usize) -> [f32; 2] {
        let s = self.spacing;
        let c = k * self.nx + i;
        let top = |j: usize| self.base[j] + self.depth[j];
        let same = |j: usize| self.depth[j] > 0.0 && (self.base[j] - self.base[c]).abs() <= s;
        let slope = |lo: Option<usize>, hi: Option<usize>| {
            let lo = lo.filter(|&j| same(j));
            let hi = hi.filter(|&j| same(j));
            match (lo, hi) {
                (Some(l), Some(h)) => (top(h) - top(l)) / (2.0 * s),
                (None, Some(h)) => (top(h) - top(c)) / s,
                (Some(l), None) => (top(c) - top(l)) / s,
                (None, None) => 0.0,
            }
            .clamp(-1.0, 1.0)
        };
        let gx = slope((i > 0).then(|| c - 1), (i + 1 < self.nx).then_some(c + 1));
        let gz = slope(
            (k > 0).then(|| c - self.nx),
            (k + 1 < self.nz).then_some(c + self.nx),
        );
        [gx, gz]
    }

    /// The snow's depth at `p`, over cell (i, k), and its surface's normal: bilinear between
    /// the centres of the four cells around `p` that lie on the same surface as `y_ref` (bases
    /// within a cell's width of it). A cell of that surface without snow counts as depth 0, so
    /// the cover thins out over a cell where it ends; a cell of another surface (a wall's top,
    /// the ground under an awning) or off the grid does not count. The normal is the
    /// snow-carrying cells' [`Self::normal`]s so weighted (`None` where none carries snow).
    pub fn surface_at(&self, p: Vec3, i: usize, k: usize, y_ref: f32) -> (f32, Option<Vec3>) {
        let s = self.spacing;
        let u = (p.x - self.origin[0]) / s - 0.5;
        let v = (p.z - self.origin[1]) / s - 0.5;
        // The lower corner of the four: i - 1 or i (k - 1 or k), whatever rounding did.
        let i0 = (u.floor() as i64).clamp(i as i64 - 1, i as i64);
        let k0 = (v.floor() as i64).clamp(k as i64 - 1, k as i64);
        let (fx, fz) = (
            (u - i0 as f32).clamp(0.0, 1.0),
            (v - k0 as f32).clamp(0.0, 1.0),
        );
        let (mut w_sum, mut d_sum, mut n_sum) = (0.0f32, 0.0f32, Vec3::ZERO);
        for (dk, wz) in [(0, 1.0 - fz), (1, fz)] {
            for (di, wx) in [(0, 1.0 - fx), (1, fx)] {
                let (ii, kk) = (i0 + di, k0 + dk);
                if ii < 0 || kk < 0 || ii >= self.nx as i64 || kk >= self.nz as i64 {
                    continue;
                }
                let (ii, kk) = (ii as usize, kk as usize);
                let j = kk * self.nx + ii;
                // (A NaN base is no surface.)
                let off = (self.base[j] - y_ref).abs();
                if off.is_nan() || off > s {
                    continue;
                }
                let w = wx * wz;
                w_sum += w;
                d_sum += w * self.depth[j];
                if self.depth[j] > 0.0 {
                    n_sum += w * self.normal(ii, kk);
                }
            }
        }
        let depth = if w_sum > 0.0 { d_sum / w_sum } else { 0.0 };
        let n = (n_sum != Vec3::ZERO).then(|| n_sum.normalize());
        (depth, n)
    }

    /// The cell over `p` (clamped to the grid).
    #[inline]
    fn cell_of(&self, p: Vec3) -> (usize, usize) {
        let cell = |v: f32, o: f32, n: usize| {
            (((v - o) / self.spacing).floor().max(0.0) as usize).min(n - 1)
        };
        (
            cell(p.x, self.origin[0], self.nx),
            cell(p.z, self.origin[1], self.nz),
        )
    }

    /// Whether world point `p` lies over the grid.
    #[inline]
    pub fn covers(&self, p: Vec3) -> bool {
        let (u, v) = (
            (p.x - self.origin[0]) / self.spacing,
            (p.z - self.origin[1]) / self.spacing,
        );
        u >= 0.0 && v >= 0.0 && u < self.nx as f32 && v < self.nz as f32
    }

    /// The depth drawn on upward faces beyond the grid, m.
    pub fn open_depth_m(&self) -> f32 {
        self.open_depth
    }

    /// Nearest snow along `o + t·d`, 0 ≤ t ≤ `t_max`: (t, normal, depth of snow there).
    pub fn trace(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, Vec3, f32)> {
        if self.y_lo > self.y_hi {
            return None;
        }
        if self.bands.is_empty() {
            return self.trace_in(o, d, t_max, self.y_lo, self.y_hi);
        }
        // Only where the ray is at a height some snow lies at (the bands are disjoint, so
        // their stretches of the ray are too): nearest first.
        let mut spans: [(f32, f32, f32); MAX_BANDS] = [(0.0, 0.0, 0.0); MAX_BANDS];
        let mut n = 0;
        for &(lo, hi) in &self.bands {
            let (t0, t1) = if d.y != 0.0 {
                let (a, b) = ((lo - o.y) / d.y, (hi - o.y) / d.y);
                (a.min(b), a.max(b))
            } else if o.y >= lo && o.y <= hi {
                (0.0, f32::INFINITY)
            } else {
                continue;
            };
            if t1 >= 0.0 && t0 <= t_max {
                spans[n] = (t0, lo, hi);
                n += 1;
            }
        }
        let spans = &mut spans[..n];
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        spans
            .iter()
            .find_map(|&(_, lo, hi)| self.trace_in(o, d, t_max, lo, hi))
    }

    /// [`Self::trace`] within the heights [`y_lo`, `y_hi`] (the DDA over the grid's slab).
    fn trace_in(
        &self,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        y_lo: f32,
        y_hi: f32,
    ) -> Option<(f32, Vec3, f32)> {
        let s = self.spacing;
        let lo = Vec3::new(self.origin[0], y_lo, self.origin[1]);
        let hi = Vec3::new(
            self.origin[0] + s * self.nx as f32,
            y_hi,
            self.origin[1] + s * self.nz as f32,
        );
        let inv = inverse_direction(d);
        let t1v = (lo - o) * inv;
        let t2v = (hi - o) * inv;
        let (tn, tf) = (t1v.min(t2v), t1v.max(t2v));
        let t_enter = tn.max_element().max(0.0);
        let t_exit = tf.min_element().min(t_max);
        if t_enter > t_exit {
            return None;
        }
        // The entry face's normal, for a hit on the first cell's side.
        let mut side = if tn.x >= tn.y && tn.x >= tn.z {
            Vec3::new(-d.x.signum(), 0.0, 0.0)
        } else if tn.z >= tn.y {
            Vec3::new(0.0, 0.0, -d.z.signum())
        } else {
            Vec3::new(0.0, -d.y.signum(), 0.0)
        };
        let p = o + d * t_enter;
        let cell = |v: f32, o: f32, n: usize| (((v - o) / s).floor().max(0.0) as usize).min(n - 1);
        let (mut i, mut k) = (
            cell(p.x, self.origin[0], self.nx),
            cell(p.z, self.origin[1], self.nz),
        );
        let (sx, sz) = (d.x >= 0.0, d.z >= 0.0);
        let boundary = |c: usize, o: f32, up: bool| o + s * (c as f32 + if up { 1.0 } else { 0.0 });
        let mut tx = if d.x != 0.0 {
            (boundary(i, self.origin[0], sx) - o.x) * inv.x
        } else {
            f32::INFINITY
        };
        let mut tz = if d.z != 0.0 {
            (boundary(k, self.origin[1], sz) - o.z) * inv.z
        } else {
            f32::INFINITY
        };
        let (dtx, dtz) = ((s * inv.x).abs(), (s * inv.z).abs());
        let mut t_in = t_enter;
        for _ in 0..(self.nx + self.nz + 2) {
            let t_out = tx.min(tz).min(t_exit);
            let idx = k * self.nx + i;
            let dep = self.depth[idx];
            if dep > 0.0 {
                let b = self.base[idx];
                let top = b + dep;
                let (a0, a1) = if d.y != 0.0 {
                    let ta = (b - o.y) / d.y;
                    let tb = (top - o.y) / d.y;
                    (ta.min(tb), ta.max(tb))
                } else if o.y >= b && o.y <= top {
                    (f32::NEG_INFINITY, f32::INFINITY)
                } else {
                    (f32::INFINITY, f32::NEG_INFINITY)
                };
                let h0 = t_in.max(a0);
                let h1 = t_out.min(a1);
                if h0 <= h1 {
                    // A step lower than half a cell is the snow's own relief: it shows the
                    // surface's slope, not a wall.
                    if h0 > t_in || o.y + d.y * h0 - b < 0.5 * s {
                        // The top: depth and normal interpolated over the surface.
                        let (dep_at, n) = self.surface_at(o + d * h0, i, k, b);
                        return Some((h0, n.unwrap_or_else(|| self.normal(i, k)), dep_at));
                    }
                    return Some((h0, side, dep));
                }
            }
            if t_out >= t_exit {
                return None;
            }
            if tx <= tz {
                if (sx && i + 1 >= self.nx) || (!sx && i == 0) {
                    return None;
                }
                i = if sx { i + 1 } else { i - 1 };
                t_in = tx;
                tx += dtx;
                side = Vec3::new(if sx { -1.0 } else { 1.0 }, 0.0, 0.0);
            } else {
                if (sz && k + 1 >= self.nz) || (!sz && k == 0) {
                    return None;
                }
                k = if sz { k + 1 } else { k - 1 };
                t_in = tz;
                tz += dtz;
                side = Vec3::new(0.0, 0.0, if sz { -1.0 } else { 1.0 });
            }
        }
        None
    }

    /// One pixel of a box scene with the cover: (radiance, depth along the axis, depth of snow
    /// the pixel shows ([`drawn_depth`]), the sun's share on the surface seen), lit as
    /// the frame's scene stage lights the surfaces (`light`: the frame's `SceneLight`).
    #[inline]
    pub fn shade_pixel(
        &self,
        scene: &BoxScene,
        cam: &Camera,
        light: &impl crate::scene::SurfaceLight,
        x: u32,
        y: u32,
    ) -> (Vec3, f32, f32, f32) {
        let dir = cam.ray_direction(x, y);
        let hit = trace(scene, cam.eye(), dir);
        let t_max = hit.map_or(f32::INFINITY, |h| h.0);
        // Snow of `dep` over a surface of albedo `under` at t: white where its patches lie,
        // sparkling where the sun reaches it.
        let snowy = |t: f32, n: Vec3, dep: f32, under: Vec3| {
            let p = cam.eye() + dir * t;
            let fp = footprint_m(t, dir, n, cam.fy);
            let cov = coverage(dep);
            let share = drawn_share(p.x, p.z, cov, fp);
            let a = under + (Vec3::splat(SNOW_ALBEDO) - under) * share;
            let (mut rad, sun) = light.surface_radiance_sun(&scene.boxes, p, n, a);
            if let Some((l, e)) = light.sun_glint()
                && sun * share > 0.0
            {
                rad += e * (sun * share * sparkle(p, n, -dir, l, fp));
            }
            (rad, t, drawn_depth(dep, cov, share), sun)
        };
        match self.trace(cam.eye(), dir, t_max) {
            Some((t, n, dep)) => {
                // Thin snow shows the surface it lies on.
                let under = match hit {
                    Some((_, hn, ha)) if hn.y > 0.5 => ha,
                    _ => Vec3::splat(SNOW_ALBEDO),
                };
                snowy(t, n, dep, under)
            }
            None => match hit {
                Some((t, n, ha)) if n.y > 0.5 => {
                    let p = cam.eye() + dir * t;
                    // Beyond the grid, upward faces carry the open ground's snow (not lifted);
                    // on it, bare cells beside snow take its depth thinning out over a cell.
                    let dep = if self.covers(p) {
                        let (i, k) = self.cell_of(p);
                        self.surface_at(p, i, k, p.y).0
                    } else {
                        self.open_depth
                    };
                    if dep > 0.0 {
                        snowy(t, n, dep, ha)
                    } else {
                        let a = surface_albedo(ha, n, p);
                        let (rad, sun) = light.surface_radiance_sun(&scene.boxes, p, n, a);
                        (rad, t, 0.0, sun)
                    }
                }
                // No snow: the surface as the scene stage shades it (`shade_pixel`, from the
                // same hit).
                Some((t, n, ha)) => {
                    let p = cam.eye() + dir * t;
                    let a = surface_albedo(ha, n, p);
                    let (rad, sun) = light.surface_radiance_sun(&scene.boxes, p, n, a);
                    (rad, t, 0.0, sun)
                }
                None => (light.sky_pixel(dir.normalize()), f32::INFINITY, 0.0, 1.0),
            },
        }
    }

    /// A photo's row `y` whitened by the snow on its pixels (`rgb_row` linear, in the photo's
    /// units; `depth_row` its depth, m); writes the snow's depth per pixel into `snow_row`.
    pub fn photo_row(
        &self,
        cam: &Camera,
        ambient: &AmbientMap,
        y: usize,
        rgb_row: &mut [f32],
        depth_row: &[f32],
        snow_row: Option<&mut [f32]>,
    ) {
        let w = depth_row.len();
        let Some(per_pixel) = &self.photo_depth_m else {
            return;
        };
        let row = &per_pixel[y * w..(y + 1) * w];
        let mut snow_row = snow_row;
        if let Some(out) = snow_row.as_deref_mut() {
            out.fill(0.0);
        }
        for (x, &dep) in row.iter().enumerate() {
            if dep <= 0.0 {
                continue;
            }
            let d = cam.ray_direction(x as u32, y as u32);
            let p = cam.eye() + d * depth_row[x];
            let e = ambient.sample(p)[0];
            let snow = self.radiance_scale * (SNOW_ALBEDO * e);
            // The snow lies on surfaces facing up: their footprint as a level one's.
            let cov = coverage(dep);
            let c = drawn_share(p.x, p.z, cov, footprint_m(depth_row[x], d, Vec3::Y, cam.fy));
            for k in 0..3 {
                let v = &mut rgb_row[3 * x + k];
                *v = *v * (1.0 - c) + snow[k] * c;
            }
            if let Some(out) = snow_row.as_deref_mut() {
                out[x] = drawn_depth(dep, cov, c);
            }
        }
    }
}

/// The depth of snow a pixel shows, m: a surface under a mean depth `dep` of snow covering
/// the share `cov` of it lies in patches `dep / cov` deep (the mass kept), of which the pixel
/// shows the share `share`; so `dep / cov` on a patch, 0 between, and `dep` where the pixel
/// spans many patches (share = cov). Its expectation is `dep` at every distance.
#[inline]
pub fn drawn_depth(dep: f32, cov: f32, share: f32) -> f32 {
    if share > 0.0 && cov > 0.0 {
        dep / cov * share
    } else {
        0.0
    }
}
