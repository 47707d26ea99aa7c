//! A photo's airlight, estimated from the photo itself: the atmospheric light of He, Sun &
//! Tang, "Single image haze removal using dark channel prior" (CVPR 2009).
//!
//! The dark channel is the minimum over a square patch of the minimum over the colour
//! channels. Haze-free surfaces have a dark channel near zero (shadows, colourful or dark
//! things in every patch); the haze-opaque parts of an image, the sky and the far horizon,
//! have a bright one. Among the brightest 0.1 % of dark-channel pixels, the one whose colour
//! channels sum highest in the input is the atmospheric light. Its value is what the rain and
//! mist of a frame tend to with distance, in the photo's own units and colour.
//!
//! The min filter and the order statistics only compare values, so the estimate is the same
//! whether it runs on sRGB codes or on linear light (the transfer function is monotonic): the
//! 8-bit path runs it on the codes without decoding the photo.

use crate::error::{Error, Param, Range, Result};
use rayon::prelude::*;

/// He, Sun & Tang's patch side, px (15×15 for their 600×400 images).
pub const PATCH_PX: usize = 15;
/// The brightest share of the dark channel taken as haze-opaque (0.1 %).
pub const TOP_FRACTION: f64 = 1e-3;

/// The dark channel of an H·W·3 image: per pixel, the minimum of its channels over the
/// `patch_px`-square window centred on it (clamped at the borders: the window is cut, as a
/// "nearest" border repeats the edge).
pub fn dark_channel<T>(rgb: &[T], width: usize, height: usize, patch_px: usize) -> Result<Vec<f32>>
where
    T: Copy + Into<f32> + Sync,
{
    check_image(rgb.len(), width, height, patch_px)?;
    let r = patch_px / 2;
    // Horizontal pass: each row's channel minimum, then its running window minimum.
    let mut rows = vec![0.0f32; width * height];
    rows.par_chunks_mut(width)
        .zip(rgb.par_chunks(3 * width))
        .for_each(|(out, src)| {
            let m: Vec<f32> = src
                .chunks_exact(3)
                .map(|p| p[0].into().min(p[1].into()).min(p[2].into()))
                .collect();
            window_min(&m, r, out);
        });
    // Vertical pass, row-wise: each output row is the element-wise minimum of the 2r + 1
    // filtered rows around it (cut at the ends), so the inner loop runs along a row and
    // vectorises.
    let mut dark = vec![0.0f32; width * height];
    dark.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let (lo, hi) = (y.saturating_sub(r), (y + r).min(height - 1));
        out.copy_from_slice(&rows[lo * width..(lo + 1) * width]);
        for src in rows[(lo + 1) * width..(hi + 1) * width].chunks_exact(width) {
            for (o, &v) in out.iter_mut().zip(src) {
                *o = o.min(v);
            }
        }
    });
    Ok(dark)
}

/// `out[i]` = min of `v[i − r ..= i + r]` (cut at the ends), by the van Herk / Gil–Werman
/// blocks: prefix and suffix minima over blocks of 2r + 1, three comparisons per value.
fn window_min(v: &[f32], r: usize, out: &mut [f32]) {
    let n = v.len();
    let k = 2 * r + 1;
    let mut pre = vec![0.0f32; n];
    let mut suf = vec![0.0f32; n];
    for start in (0..n).step_by(k) {
        let end = (start + k).min(n);
        let mut m = f32::INFINITY;
        for i in start..end {
            m = m.min(v[i]);
            pre[i] = m;
        }
        let mut m = f32::INFINITY;
        for i in (start..end).rev() {
            m = m.min(v[i]);
            suf[i] = m;
        }
    }
    for (i, o) in out.iter_mut().enumerate() {
        let (lo, hi) = (i.saturating_sub(r), (i + r).min(n - 1));
        // [lo, hi] spans at most two blocks: the suffix of lo's and the prefix of hi's.
        *o = if lo / k == hi / k {
            v[lo..=hi].iter().copied().fold(f32::INFINITY, f32::min)
        } else {
            suf[lo].min(pre[hi])
        };
    }
}

/// The index (row-major pixel) of the atmospheric light of an H·W·3 image: among the
/// brightest `top_fraction` of its dark channel (at least one pixel), the pixel whose
/// channels sum highest (ties: the first).
pub fn atmospheric_light_pixel<T>(
    rgb: &[T],
    width: usize,
    height: usize,
    patch_px: usize,
    top_fraction: f64,
) -> Result<usize>
where
    T: Copy + Into<f32> + Sync,
{
    Range::open_closed(0.0, 1.0, "").check("top_fraction", None, top_fraction)?;
    let dark = dark_channel(rgb, width, height, patch_px)?;
    let n = dark.len();
    let top = ((n as f64 * top_fraction).ceil() as usize).clamp(1, n);
    let mut order: Vec<u32> = (0..n as u32).collect();
    // The `top` brightest (ties broken by index, so the choice is the same in any process).
    let key = |i: &u32| (std::cmp::Reverse(ordered(dark[*i as usize])), *i);
    order.select_nth_unstable_by_key(top - 1, key);
    let intensity = |i: usize| -> f32 { (0..3).map(|c| rgb[3 * i + c].into()).sum() };
    let best = order[..top]
        .iter()
        .map(|&i| i as usize)
        .max_by(|&a, &b| intensity(a).total_cmp(&intensity(b)).then(b.cmp(&a)))
        .unwrap_or(0);
    Ok(best)
}

/// A total order on f32 for the selection (NaN sorts last; images are checked finite).
fn ordered(v: f32) -> u32 {
    let b = v.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

fn check_image(len: usize, width: usize, height: usize, patch_px: usize) -> Result<()> {
    if width == 0 || height == 0 || len != 3 * width * height {
        return Err(Error::Invalid {
            param: Param {
                name: "image",
                index: None,
            },
            message: format!(
                "must be H x W x 3 with H, W >= 1, got {len} values for {width} x {height}"
            ),
        });
    }
    Range::closed(1.0, 1001.0, "px").check("patch_px", None, patch_px as f64)?;
    if patch_px.is_multiple_of(2) {
        return Err(Error::Invalid {
            param: Param {
                name: "patch_px",
                index: None,
            },
            message: format!("{patch_px} must be odd (a window centred on its pixel)"),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dark channel by brute force.
    fn brute(rgb: &[f32], w: usize, h: usize, patch: usize) -> Vec<f32> {
        let r = patch as isize / 2;
        let mut out = vec![0.0; w * h];
        for y in 0..h as isize {
            for x in 0..w as isize {
                let mut m = f32::INFINITY;
                for yy in (y - r).max(0)..=(y + r).min(h as isize - 1) {
                    for xx in (x - r).max(0)..=(x + r).min(w as isize - 1) {
                        let i = 3 * (yy as usize * w + xx as usize);
                        m = m.min(rgb[i]).min(rgb[i + 1]).min(rgb[i + 2]);
                    }
                }
                out[y as usize * w + x as usize] = m;
            }
        }
        out
    }

    #[test]
    fn the_dark_channel_is_the_patch_minimum() {
        let (w, h) = (37, 23);
        let mut s = 12345u32;
        let rgb: Vec<f32> = (0..3 * w * h)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (s >> 8) as f32 / (1u32 << 24) as f32
            })
            .collect();
        for patch in [1, 3, 15, 31, 71] {
            assert_eq!(
                dark_channel(&rgb, w, h, patch).unwrap(),
                brute(&rgb, w, h, patch)
            );
        }
        assert!(dark_channel(&rgb, w, h, 4).is_err());
        assert!(dark_channel(&rgb[1..], w, h, 3).is_err());
    }

    #[test]
    fn the_atmospheric_light_is_the_brightest_haze_opaque_pixel() {
        // A dark, colourful ground (one channel 0 everywhere) under a bright sky band.
        let (w, h) = (40, 30);
        let mut rgb = vec![0.0f32; 3 * w * h];
        for y in 0..h {
            for x in 0..w {
                let i = 3 * (y * w + x);
                let p = if y < 8 {
                    [0.7, 0.75, 0.8].map(|c| c + 0.001 * x as f32)
                } else {
                    [0.9, 0.0, 0.3]
                };
                rgb[i..i + 3].copy_from_slice(&p);
            }
        }
        let i = atmospheric_light_pixel(&rgb, w, h, 5, 0.01).unwrap();
        // the top 1 % (12 px) of the dark channel lie in the sky's upper rows, at its right
        // (the sky brightens to the right); the brightest of them is the rightmost
        assert_eq!(i % w, w - 1);
        assert!(i / w < 8);
        assert!(atmospheric_light_pixel(&rgb, w, h, 5, 0.0).is_err());
    }
}
