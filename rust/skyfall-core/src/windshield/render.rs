//! Drawing the drops: Gotou, Tanaka & Sagawa's 2D metaballs summed into a height map,
//! compressed, thresholded, and refracting the frame behind the glass.
//!
//! Image coordinates: x right, y down, pixel (i, j) centred at (i + 0.5, j + 0.5); the scene
//! lies along +z. A metaball of radius R at c adds N = 1/(1 + (h/R)⁴), h = |p − c|, out to
//! h = [`CUTOFF`]·R (N = 1/257 there); the sum V is compressed five times,
//! V ← k (V − V0) + V0 where V > V0, V0 = 0.5, 0.6, …, 0.9, k = 0.3, and the drops are where
//! V > 0.5 ([`THRESHOLD`]). The outer water surface's normal, from central differences of V
//! scaled by `slope_px` (px of height per unit of V), is n ∝ (−s ∂V/∂x, −s ∂V/∂y, 1).
//!
//! Refraction, from the camera through the glass (flat, facing the camera) into the drop and out
//! of its curved surface into the air:
//! - [`RefractMode::Offset`] (the paper's): the background at p − K (n_x, n_y), with
//!   K = (η − 1)·f: a thin water prism of tilt β deviates the ray by (η − 1)β, f px per radian.
//! - [`RefractMode::Snell`]: the pixel's pinhole ray refracted into the water at the flat glass
//!   (η sin θ_w = sin θ_air) and out at the surface by Snell's law (at total internal reflection
//!   the grazing ray), projected back to the image.
//!
//! The background is looked up bilinearly, mirrored at the edges, in a copy box-averaged to
//! `lookup_px` on its short side (the paper's 64², against the jaggies of sampling a sharp image
//! through minifying lenses; 0: the frame itself). A camera focused beyond the glass blurs the
//! drops by their blur circle c: the drop layer (coverage M and M × refracted light) is box
//! blurred to width c and laid over the sharp frame, out = frame (1 − M_c) + (M·L)_c.

use crate::error::{Error, Param, Result};
use rayon::prelude::*;

/// Metaballs are summed out to this many radii.
pub const CUTOFF: f32 = 4.0;
/// The field's threshold: a drop is where V > 0.5.
pub const THRESHOLD: f32 = 0.5;
/// The compression's gain k.
pub const COMPRESS_K: f32 = 0.3;
/// The compression's thresholds V0.
pub const COMPRESS_V0: [f32; 5] = [0.5, 0.6, 0.7, 0.8, 0.9];
/// Water's refractive index (20 °C, 589 nm, rounded).
pub const WATER_INDEX: f64 = 1.333;
/// Rows per band of the parallel passes.
const BAND: usize = 16;

/// The paper's compression of one value.
#[inline]
pub fn compress(mut v: f32) -> f32 {
    for v0 in COMPRESS_V0 {
        if v > v0 {
            v = COMPRESS_K * (v - v0) + v0;
        }
    }
    v
}

/// One metaball's field at distance² `h2` for radius² `r2`.
#[inline]
pub fn metaball(h2: f32, r2: f32) -> f32 {
    let q = h2 / r2;
    1.0 / (1.0 + q * q)
}

fn check_size(width: usize, height: usize) -> Result<()> {
    crate::ranges::WIDTH.check(width as f64)?;
    crate::ranges::HEIGHT.check(height as f64)?;
    Ok(())
}

/// The summed (and, with `compress`, compressed) metaball field, `width` × `height`, row major.
/// `centres_px` are (x, y) in pixels, `radii_px` positive.
pub fn height_map(
    centres_px: &[[f32; 2]],
    radii_px: &[f32],
    width: usize,
    height: usize,
    compress_peaks: bool,
) -> Result<Vec<f32>> {
    check_size(width, height)?;
    if centres_px.len() != radii_px.len() {
        // Not a broadcast (`Error::Length` says "1 or n"): one radius per centre.
        return Err(Error::Invalid {
            param: Param {
                name: "radii_px",
                index: None,
            },
            message: format!(
                "has length {}, expected {} (one radius per row of centers_px)",
                radii_px.len(),
                centres_px.len()
            ),
        });
    }
    for (i, (c, &r)) in centres_px.iter().zip(radii_px).enumerate() {
        if !(r > 0.0 && r <= 1e4) {
            return Err(Error::OutOfRange {
                param: Param {
                    name: "radii_px",
                    index: Some(i),
                },
                value: r as f64,
                range: "(0, 1e4] px".into(),
                integer: false,
            });
        }
        if !(c[0].is_finite() && c[1].is_finite()) {
            return Err(Error::Invalid {
                param: Param {
                    name: "centers_px",
                    index: Some(i),
                },
                message: format!("({}, {}) is not finite", c[0], c[1]),
            });
        }
    }
    let bands = height.div_ceil(BAND);
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); bands];
    for (i, (c, &r)) in centres_px.iter().zip(radii_px).enumerate() {
        let reach = CUTOFF * r;
        let (y0, y1) = (c[1] - reach, c[1] + reach);
        if y1 < 0.0 || y0 > height as f32 || c[0] + reach < 0.0 || c[0] - reach > width as f32 {
            continue;
        }
        let b0 = ((y0.max(0.0) as usize) / BAND).min(bands - 1);
        let b1 = ((y1.min(height as f32 - 1.0).max(0.0) as usize) / BAND).min(bands - 1);
        for list in &mut lists[b0..=b1] {
            list.push(i as u32);
        }
    }
    let mut out = crate::error::try_filled_par("the height map", width * height, 0.0f32)?;
    out.par_chunks_mut(BAND * width)
        .zip(lists.par_iter())
        .enumerate()
        .for_each(|(b, (rows, list))| {
            let row0 = b * BAND;
            let nrows = rows.len() / width;
            for &i in list {
                let c = centres_px[i as usize];
                let r = radii_px[i as usize];
                let (r2, reach) = (r * r, CUTOFF * r);
                let reach2 = reach * reach;
                let ja = ((c[1] - reach - 0.5).ceil().max(row0 as f32) as usize).max(row0);
                let jb =
                    ((c[1] + reach - 0.5).floor() + 1.0).clamp(0.0, (row0 + nrows) as f32) as usize;
                let ia = (c[0] - reach - 0.5).ceil().max(0.0) as usize;
                let ib = ((c[0] + reach - 0.5).floor() + 1.0).clamp(0.0, width as f32) as usize;
                for j in ja..jb {
                    let dy = j as f32 + 0.5 - c[1];
                    let row = &mut rows[(j - row0) * width..(j - row0 + 1) * width];
                    for (ii, v) in row.iter_mut().enumerate().take(ib).skip(ia) {
                        let dx = ii as f32 + 0.5 - c[0];
                        let h2 = dx * dx + dy * dy;
                        if h2 <= reach2 {
                            *v += metaball(h2, r2);
                        }
                    }
                }
            }
            if compress_peaks {
                for v in rows.iter_mut() {
                    *v = compress(*v);
                }
            }
        });
    Ok(out)
}

/// ∂V/∂x, ∂V/∂y at pixel (i, j) by central differences (one-sided at the edges), per px.
#[inline]
fn gradient(field: &[f32], width: usize, height: usize, i: usize, j: usize) -> (f32, f32) {
    let at = |x: usize, y: usize| field[y * width + x];
    let (il, ir) = (i.saturating_sub(1), (i + 1).min(width - 1));
    let (ju, jd) = (j.saturating_sub(1), (j + 1).min(height - 1));
    let gx = if ir > il {
        (at(ir, j) - at(il, j)) / (ir - il) as f32
    } else {
        0.0
    };
    let gy = if jd > ju {
        (at(i, jd) - at(i, ju)) / (jd - ju) as f32
    } else {
        0.0
    };
    (gx, gy)
}

/// The unit normals (x, y, z) of the field at every pixel, `slope_px` px of height per unit V.
/// `slope_px` in [0, 1e5] px, as the refraction's (beyond, its square overflows: NaN normals).
pub fn normals(field: &[f32], width: usize, height: usize, slope_px: f32) -> Result<Vec<f32>> {
    check_size(width, height)?;
    check_field(field, width, height)?;
    if !(0.0..=1e5).contains(&slope_px) {
        return Err(Error::OutOfRange {
            param: Param {
                name: "slope_px",
                index: None,
            },
            value: f64::from(slope_px),
            range: "[0, 1e5] px".into(),
            integer: false,
        });
    }
    let mut out = crate::error::try_filled_par("the normals", width * height * 3, 0.0f32)?;
    out.par_chunks_mut(width * 3)
        .enumerate()
        .for_each(|(j, row)| {
            for i in 0..width {
                let n = normal_at(field, width, height, i, j, slope_px);
                row[i * 3..i * 3 + 3].copy_from_slice(&n);
            }
        });
    Ok(out)
}

#[inline]
fn normal_at(field: &[f32], width: usize, height: usize, i: usize, j: usize, s: f32) -> [f32; 3] {
    let (gx, gy) = gradient(field, width, height, i, j);
    let (nx, ny) = (-s * gx, -s * gy);
    let inv = 1.0 / (nx * nx + ny * ny + 1.0).sqrt();
    [nx * inv, ny * inv, inv]
}

fn check_field(field: &[f32], width: usize, height: usize) -> Result<()> {
    if field.len() != width * height {
        return Err(Error::Length {
            param: Param {
                name: "height_map",
                index: None,
            },
            len: field.len(),
            expected: width * height,
        });
    }
    Ok(())
}

/// How the refracted ray is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RefractMode {
    /// The paper's offset approximation.
    Offset,
    /// Snell's law at the flat glass and the curved water surface.
    Snell,
}

impl RefractMode {
    /// By name: `"offset"` or `"snell"`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "offset" => Ok(RefractMode::Offset),
            "snell" => Ok(RefractMode::Snell),
            _ => Err(Error::Invalid {
                param: Param {
                    name: "refraction",
                    index: None,
                },
                message: format!("{name:?}: use \"offset\" or \"snell\""),
            }),
        }
    }
}

/// The refraction's camera and water.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refraction {
    /// Offset or Snell.
    pub mode: RefractMode,
    /// Focal length, px.
    pub focal_px: f64,
    /// Principal point, px.
    pub principal_px: [f64; 2],
    /// Water's refractive index.
    pub index: f64,
    /// Height of the water surface, px per unit of the field V.
    pub slope_px: f64,
    /// The background's lookup copy's short side, px (0: the frame itself).
    pub lookup_px: usize,
    /// The drops' blur circle, px (0: in focus).
    pub blur_px: f64,
}

impl Refraction {
    /// The half-width of the box blur that stands for the blur circle, px (0: sharp).
    pub fn blur_radius_px(&self) -> usize {
        (0.5 * self.blur_px).round() as usize
    }

    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        crate::ranges::FX.check(self.focal_px)?;
        crate::ranges::CX.check(self.principal_px[0])?;
        crate::ranges::CY.check(self.principal_px[1])?;
        let named = |name: &'static str, v: f64, ok: bool, range: &str| {
            if ok {
                Ok(())
            } else {
                Err(Error::OutOfRange {
                    param: Param { name, index: None },
                    value: v,
                    range: range.into(),
                    integer: false,
                })
            }
        };
        named(
            "index",
            self.index,
            (1.0..=3.0).contains(&self.index),
            "[1, 3]",
        )?;
        named(
            "slope_px",
            self.slope_px,
            (0.0..=1e5).contains(&self.slope_px),
            "[0, 1e5] px",
        )?;
        named(
            "blur_px",
            self.blur_px,
            (0.0..=1024.0).contains(&self.blur_px),
            "[0, 1024] px",
        )?;
        Ok(())
    }
}

/// Refracts `n` (unit) of incidence `d` (unit) with relative index `eta` = n1/n2, `n` facing
/// against `d`; at total internal reflection the grazing ray.
#[inline]
fn refract(d: [f64; 3], n: [f64; 3], eta: f64) -> [f64; 3] {
    let cosi = -(d[0] * n[0] + d[1] * n[1] + d[2] * n[2]);
    let k = (1.0 - eta * eta * (1.0 - cosi * cosi)).max(0.0);
    let a = eta * cosi - k.sqrt();
    [
        eta * d[0] + a * n[0],
        eta * d[1] + a * n[1],
        eta * d[2] + a * n[2],
    ]
}

/// Where pixel centre (px, py) looks through the water surface of normal `n` (outward, +z).
#[inline]
pub fn lookup_point(r: &Refraction, px: f64, py: f64, n: [f32; 3]) -> (f64, f64) {
    match r.mode {
        RefractMode::Offset => {
            let k = (r.index - 1.0) * r.focal_px;
            (px - k * n[0] as f64, py - k * n[1] as f64)
        }
        RefractMode::Snell => {
            let f = r.focal_px;
            let (x, y) = ((px - r.principal_px[0]) / f, (py - r.principal_px[1]) / f);
            let inv = 1.0 / (x * x + y * y + 1.0).sqrt();
            let d = [x * inv, y * inv, inv];
            // into the water through the flat glass (a parallel slab: glass drops out)
            let dw = refract(d, [0.0, 0.0, -1.0], 1.0 / r.index);
            // out of the water through its surface, the normal turned to face the ray
            let nf = [-(n[0] as f64), -(n[1] as f64), -(n[2] as f64)];
            let o = refract(dw, nf, r.index);
            let z = o[2].max(1e-6);
            (
                r.principal_px[0] + f * o[0] / z,
                r.principal_px[1] + f * o[1] / z,
            )
        }
    }
}

/// Mirrors a coordinate into [0, n).
#[inline]
fn mirror(x: f64, n: usize) -> f64 {
    let n = n as f64;
    let period = 2.0 * n;
    let m = x.rem_euclid(period);
    if m < n { m } else { period - m }.clamp(0.0, n - 1e-6)
}

/// A box-averaged copy of `frame` (H·W·3) whose short side is `short_px` (or the frame
/// itself where it is already that small, or `short_px` is 0): (values, width, height, scale).
pub fn lookup_copy(
    frame: &[f32],
    width: usize,
    height: usize,
    short_px: usize,
) -> Result<(Vec<f32>, usize, usize, usize)> {
    let s = width
        .min(height)
        .checked_div(short_px)
        .map_or(1, |s| s.max(1));
    if s == 1 {
        let mut copy =
            crate::error::try_with_capacity("the refraction's lookup copy", frame.len())?;
        copy.extend_from_slice(frame);
        return Ok((copy, width, height, 1));
    }
    let (lw, lh) = (width.div_ceil(s), height.div_ceil(s));
    let mut out = crate::error::try_filled("the refraction's lookup copy", lw * lh * 3, 0.0f32)?;
    out.par_chunks_mut(lw * 3)
        .enumerate()
        .for_each(|(bj, row)| {
            for bi in 0..lw {
                let mut acc = [0.0f32; 3];
                let mut n = 0.0f32;
                for j in bj * s..((bj + 1) * s).min(height) {
                    for i in bi * s..((bi + 1) * s).min(width) {
                        let p = &frame[(j * width + i) * 3..(j * width + i) * 3 + 3];
                        acc[0] += p[0];
                        acc[1] += p[1];
                        acc[2] += p[2];
                        n += 1.0;
                    }
                }
                for c in 0..3 {
                    row[bi * 3 + c] = acc[c] / n;
                }
            }
        });
    Ok((out, lw, lh, s))
}

/// Bilinear lookup of `img` (w·h·3) at image point (x, y) (pixel centres at +0.5), mirrored.
#[inline]
fn sample(img: &[f32], w: usize, h: usize, x: f64, y: f64) -> [f32; 3] {
    let (x, y) = (mirror(x, w) - 0.5, mirror(y, h) - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let clampi = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
    let (i0, i1) = (clampi(x0, w), clampi(x0 + 1.0, w));
    let (j0, j1) = (clampi(y0, h), clampi(y0 + 1.0, h));
    let px = |i: usize, j: usize, c: usize| img[(j * w + i) * 3 + c];
    let mut out = [0.0f32; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let top = px(i0, j0, c) * (1.0 - fx) + px(i1, j0, c) * fx;
        let bot = px(i0, j1, c) * (1.0 - fx) + px(i1, j1, c) * fx;
        *o = top * (1.0 - fy) + bot * fy;
    }
    out
}

/// The drops' anti-aliased coverage at a pixel: the field's crossing of the threshold spread
/// over one pixel along its gradient.
#[inline]
pub fn coverage(v: f32, gx: f32, gy: f32) -> f32 {
    let g = (gx * gx + gy * gy).sqrt().max(1e-6);
    ((v - THRESHOLD) / g + 0.5).clamp(0.0, 1.0)
}

/// The frame seen through the drops: `frame` (H·W·3, linear) refracted where the `field`
/// (the [`height_map`]) marks drops, into `out_rgb` (H·W·3); `out_mask` gets the sharp coverage.
pub fn refract_frame(
    frame: &[f32],
    width: usize,
    height: usize,
    field: &[f32],
    r: &Refraction,
    out_rgb: &mut [f32],
    out_mask: &mut [f32],
) -> Result<()> {
    check_size(width, height)?;
    check_field(field, width, height)?;
    r.validate()?;
    let n = width * height;
    for (name, len, want) in [
        ("frame", frame.len(), n * 3),
        ("out_rgb", out_rgb.len(), n * 3),
        ("out_mask", out_mask.len(), n),
    ] {
        if len != want {
            return Err(Error::Length {
                param: Param { name, index: None },
                len,
                expected: want,
            });
        }
    }
    let (look, lw, lh, s) = lookup_copy(frame, width, height, r.lookup_px)?;
    let slope = r.slope_px as f32;
    // the drop layer: coverage M and M × refracted light (premultiplied), sharp
    let mut layer = crate::error::try_filled_par("the drop layer", n * 4, 0.0f32)?;
    layer
        .par_chunks_mut(width * 4)
        .zip(out_mask.par_chunks_mut(width))
        .enumerate()
        .for_each(|(j, (row, mrow))| {
            for i in 0..width {
                let v = field[j * width + i];
                let (gx, gy) = gradient(field, width, height, i, j);
                let m = coverage(v, gx, gy);
                mrow[i] = m;
                if m <= 0.0 {
                    continue;
                }
                let nrm = normal_at(field, width, height, i, j, slope);
                let (x, y) = lookup_point(r, i as f64 + 0.5, j as f64 + 0.5, nrm);
                let c = sample(&look, lw, lh, x / s as f64, y / s as f64);
                row[i * 4] = m * c[0];
                row[i * 4 + 1] = m * c[1];
                row[i * 4 + 2] = m * c[2];
                row[i * 4 + 3] = m;
            }
        });
    let radius = r.blur_radius_px();
    if radius > 0 {
        box_blur(&mut layer, width, height, 4, radius);
    }
    out_rgb
        .par_chunks_mut(width * 3)
        .zip(layer.par_chunks(width * 4))
        .zip(frame.par_chunks(width * 3))
        .for_each(|((o, l), f)| {
            for i in 0..width {
                let a = l[i * 4 + 3];
                for c in 0..3 {
                    o[i * 3 + c] = f[i * 3 + c] * (1.0 - a) + l[i * 4 + c];
                }
            }
        });
    Ok(())
}

/// A separable box blur of half-width `radius` px (clamped at the edges, normalised by the
/// pixels inside), over `ch` interleaved channels, in place.
pub fn box_blur(data: &mut [f32], width: usize, height: usize, ch: usize, radius: usize) {
    // rows
    data.par_chunks_mut(width * ch).for_each(|row| {
        let src = row.to_vec();
        blur_line(&src, row, width, ch, 1, radius);
    });
    // columns, by transposing bands of columns through a scratch line
    let cols: Vec<Vec<f32>> = (0..width)
        .into_par_iter()
        .map(|i| {
            let mut line = vec![0.0f32; height * ch];
            for j in 0..height {
                line[j * ch..(j + 1) * ch]
                    .copy_from_slice(&data[(j * width + i) * ch..(j * width + i + 1) * ch]);
            }
            let mut out = vec![0.0f32; height * ch];
            blur_line(&line, &mut out, height, ch, 1, radius);
            out
        })
        .collect();
    data.par_chunks_mut(width * ch)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, col) in cols.iter().enumerate() {
                row[i * ch..(i + 1) * ch].copy_from_slice(&col[j * ch..(j + 1) * ch]);
            }
        });
}

fn blur_line(src: &[f32], dst: &mut [f32], n: usize, ch: usize, _stride: usize, radius: usize) {
    // running sums over a window [k − radius, k + radius] ∩ [0, n)
    let mut acc = vec![0.0f64; ch];
    let mut count = 0usize;
    for k in 0..radius.min(n) {
        for c in 0..ch {
            acc[c] += src[k * ch + c] as f64;
        }
        count += 1;
    }
    for k in 0..n {
        let add = k + radius;
        if add < n {
            for c in 0..ch {
                acc[c] += src[add * ch + c] as f64;
            }
            count += 1;
        }
        if k > radius {
            let sub = k - radius - 1;
            for c in 0..ch {
                acc[c] -= src[sub * ch + c] as f64;
            }
            count -= 1;
        }
        for c in 0..ch {
            dst[k * ch + c] = (acc[c] / count as f64) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_metaball_thresholds_to_a_disk_of_its_radius() {
        for &r in &[3.0f32, 7.5, 20.0] {
            let (w, h) = (96, 96);
            let f = height_map(&[[48.3, 47.6]], &[r], w, h, true).unwrap();
            let inside = f.iter().filter(|&&v| v > THRESHOLD).count() as f32;
            let area = std::f32::consts::PI * r * r;
            // within the pixels the circle's boundary crosses
            assert!(
                (inside - area).abs() < 2.0 * std::f32::consts::PI * r * 0.5 + 2.0,
                "{r}: {inside} vs {area}"
            );
        }
    }

    #[test]
    fn the_field_follows_the_formula_and_sums() {
        let f = height_map(&[[10.0, 10.0], [14.0, 10.0]], &[4.0, 2.0], 32, 24, false).unwrap();
        for j in 0..24 {
            for i in 0..32 {
                let (x, y) = (i as f32 + 0.5, j as f32 + 0.5);
                let mut want = 0.0;
                for (cx, r) in [(10.0f32, 4.0f32), (14.0, 2.0)] {
                    let h2 = (x - cx).powi(2) + (y - 10.0).powi(2);
                    if h2 <= (CUTOFF * r).powi(2) {
                        want += 1.0 / (1.0 + (h2.sqrt() / r).powi(4));
                    }
                }
                assert!((f[j * 32 + i] - want).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn compression_flattens_peaks_and_keeps_the_threshold() {
        assert_eq!(compress(0.5), 0.5);
        assert_eq!(compress(0.3), 0.3);
        assert!((compress(1.0) - 0.615).abs() < 1e-6);
        let mut last = 0.0;
        for k in 0..100 {
            let v = compress(k as f32 * 0.05);
            assert!(v >= last);
            last = v;
        }
        assert!(compress(5.0) < 1.0);
    }

    #[test]
    fn normals_match_the_analytic_gradient() {
        let (w, h, r, s) = (128usize, 128usize, 24.0f32, 40.0f32);
        let c = [64.0f32, 63.0];
        let f = height_map(&[c], &[r], w, h, false).unwrap();
        let n = normals(&f, w, h, s).unwrap();
        for j in 16..112 {
            for i in 16..112 {
                let (x, y) = (i as f32 + 0.5 - c[0], j as f32 + 0.5 - c[1]);
                let h2 = x * x + y * y;
                let q = h2 / (r * r);
                // dN/dx = −4 q x / (R² (1 + q²)²)
                let d = -4.0 * q / (r * r * (1.0 + q * q).powi(2));
                let (gx, gy) = (d * x, d * y);
                let want = [-s * gx, -s * gy, 1.0];
                let len = (want[0] * want[0] + want[1] * want[1] + 1.0).sqrt();
                for k in 0..3 {
                    let got = n[(j * w + i) * 3 + k];
                    assert!(
                        (got - want[k] / len).abs() < 0.01,
                        "{i} {j} {k}: {got} vs {}",
                        want[k] / len
                    );
                }
            }
        }
    }

    fn lens(mode: RefractMode) -> Refraction {
        Refraction {
            mode,
            focal_px: 200.0,
            principal_px: [32.0, 32.0],
            index: WATER_INDEX,
            slope_px: 30.0,
            lookup_px: 0,
            blur_px: 0.0,
        }
    }

    #[test]
    fn a_uniform_background_refracts_to_itself() {
        let (w, h) = (64, 64);
        let f = height_map(&[[30.0, 30.0], [40.0, 35.0]], &[8.0, 5.0], w, h, true).unwrap();
        let frame = vec![0.25f32; w * h * 3];
        for mode in [RefractMode::Offset, RefractMode::Snell] {
            for blur in [0.0, 6.0] {
                let mut r = lens(mode);
                r.blur_px = blur;
                let mut out = vec![0.0; w * h * 3];
                let mut mask = vec![0.0; w * h];
                refract_frame(&frame, w, h, &f, &r, &mut out, &mut mask).unwrap();
                assert!(out.iter().all(|&v| (v - 0.25).abs() < 1e-5));
                assert!(mask.contains(&1.0));
            }
        }
    }

    #[test]
    fn offset_is_snell_for_gentle_slopes_and_parts_from_it_when_steep() {
        let r_off = lens(RefractMode::Offset);
        let r_sn = lens(RefractMode::Snell);
        // on the axis, a slope of 0.02 rad: both ≈ (η − 1) f β
        for (beta, tol) in [(0.02f64, 0.05f64), (0.1, 1.0)] {
            let t = beta.tan() as f32;
            let len = (1.0 + t * t).sqrt();
            let n = [-t / len, 0.0, 1.0 / len];
            let (xo, _) = lookup_point(&r_off, 32.0, 32.0, n);
            let (xs, _) = lookup_point(&r_sn, 32.0, 32.0, n);
            assert!((xo - xs).abs() < tol, "{beta}: {xo} vs {xs}");
            assert!(xs > 32.0);
        }
        // a flat surface off the axis: Snell leaves the ray where it was
        let (xs, ys) = lookup_point(&r_sn, 5.0, 60.0, [0.0, 0.0, 1.0]);
        assert!((xs - 5.0).abs() < 1e-9 && (ys - 60.0).abs() < 1e-9);
    }

    #[test]
    fn the_box_blur_keeps_a_constant_and_the_mean() {
        let (w, h) = (17, 21);
        let mut d = vec![2.0f32; w * h];
        box_blur(&mut d, w, h, 1, 3);
        assert!(d.iter().all(|&v| (v - 2.0).abs() < 1e-6));
        let mut e = vec![0.0f32; w * h];
        e[10 * w + 8] = 49.0;
        box_blur(&mut e, w, h, 1, 3);
        assert!((e[10 * w + 8] - 1.0).abs() < 1e-6);
        assert!((e.iter().sum::<f32>() - 49.0).abs() < 1e-4);
    }

    #[test]
    fn bad_inputs_name_the_parameter() {
        let e = height_map(&[[0.0, 0.0]], &[0.0], 4, 4, true)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("radii_px[0] = 0.0"), "{e}");
        let e = height_map(&[[0.0, 0.0]], &[], 4, 4, true)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("radii_px: has length 0, expected 1"), "{e}");
        let e = height_map(&[[1.0, 1.0], [2.0, 2.0]], &[5.0], 4, 4, true)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "radii_px: has length 1, expected 2 (one radius per row of centers_px)"
        );
        assert!(RefractMode::parse("exact").is_err());
    }
}
