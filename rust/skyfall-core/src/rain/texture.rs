//! Rain textures: a 1 m³ cube of falling drops seen orthographically from the side.
//!
//! For one rain rate R and one diameter bin [lo, hi]: the expected number of drops in the
//! cube is λ = ∫ N(D) dD over the bin (Marshall–Palmer); the texture draws ⌊λ⌋ drops plus
//! one more with probability λ − ⌊λ⌋. Each drop's diameter follows N(D) inside the bin
//! (inverse CDF of the truncated exponential), its position is uniform, and during the
//! exposure T it sweeps a vertical segment of width D and length L = v(D)·T (Beard 1976
//! fall speed in Gunn & Kinzer's air). The value written is the fraction of the exposure the
//! drop covers a point on its path, α = min(1, D / (v T)), times the fraction of each pixel
//! the streak's rectangle covers (box-filter anti-aliasing: a drop narrower than a pixel
//! covers it partially). Streaks combine as 1 − ∏(1 − αᵢ cᵢ). Positions wrap on a torus, so
//! textures tile seamlessly in both directions. Image rows grow downwards: drops fall towards
//! larger row indices.
//!
//! Expected mean opacity over positions is exact for a given set of drops:
//! 1 − ∏ᵢ (1 − αᵢ Dᵢ Lᵢ) (areas in m², the texture being 1 m²).

use super::bins::diameter_bins;
use crate::error::{Error, Range, Result};
use crate::physics::dsd::{BinSampler, RAIN_RATE_MM_H};
use crate::physics::fall_speed::FallSpeed;
use crate::seed::derive;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

/// Largest result [`render_textures`] will allocate: 2 GiB.
pub const TEXTURE_BUDGET_BYTES: u64 = 2 << 30;
/// Valid texture sizes, pixels per side (pixels per metre of the cube).
pub const SIZE_PX: Range = crate::ranges::SIZE_PX.range;
/// Valid exposures, s: a streak must fit in the 1 m texture (v ≤ 9.3 m/s).
pub const EXPOSURE_S: Range = crate::ranges::EXPOSURE_S.range;

/// What to render.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureRequest<'a> {
    /// Rain rates, mm/h.
    pub rain_rates_mm_h: &'a [f64],
    /// Texture diameters, mm, strictly increasing.
    pub diameters_mm: &'a [f64],
    /// Side of each square texture, px.
    pub size_px: usize,
    /// Exposure time, s.
    pub exposure_s: f64,
    /// Seed.
    pub seed: u64,
}

impl TextureRequest<'_> {
    /// Number of f32 values in the result, after validating everything (no allocation).
    pub fn validate(&self) -> Result<usize> {
        RAIN_RATE_MM_H.check_all("rain_rates_mm_h", self.rain_rates_mm_h)?;
        diameter_bins(self.diameters_mm)?;
        SIZE_PX.check("size_px", None, self.size_px as f64)?;
        EXPOSURE_S.check("exposure_s", None, self.exposure_s)?;
        let n = self.rain_rates_mm_h.len() as u128
            * self.diameters_mm.len() as u128
            * (self.size_px as u128).pow(2);
        let bytes = n * 4;
        if bytes > TEXTURE_BUDGET_BYTES as u128 {
            let what = format!(
                "{} x {} textures of {}x{} float32",
                self.rain_rates_mm_h.len(),
                self.diameters_mm.len(),
                self.size_px,
                self.size_px
            );
            return Err(Error::too_large(what, bytes, TEXTURE_BUDGET_BYTES));
        }
        Ok(n as usize)
    }
}

/// One drawn drop, in metres within the unit cube face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Streak {
    /// Horizontal centre, m in [0, 1).
    pub x_m: f64,
    /// Top of the streak, m in [0, 1) (rows grow downward).
    pub y_m: f64,
    /// Drop diameter = streak width, m.
    pub diameter_m: f64,
    /// Streak length v·T, m.
    pub length_m: f64,
    /// Opacity along the streak, (π/4)·min(1, D / (v T)): the drop's silhouette on its band.
    pub alpha: f64,
}

/// The drops of one (rate, bin) texture, deterministic in `seed`.
pub fn draw_streaks(
    rain_rate_mm_h: f64,
    lo_mm: f64,
    hi_mm: f64,
    exposure_s: f64,
    seed: u64,
) -> Vec<Streak> {
    let bin = BinSampler::new(rain_rate_mm_h, lo_mm, hi_mm);
    if bin.expected_per_m3() <= 0.0 {
        return Vec::new();
    }
    let key = derive(
        seed,
        &[
            rain_rate_mm_h.to_bits(),
            lo_mm.to_bits(),
            hi_mm.to_bits(),
            exposure_s.to_bits(),
        ],
    );
    let mut rng = Pcg64Mcg::seed_from_u64(key);
    let n = bin.count(&mut rng);
    let law = FallSpeed::beard_standard();
    (0..n)
        .map(|_| {
            let d_mm = bin.diameter_mm(rng.random());
            let v = law.m_s(d_mm);
            let diameter_m = d_mm * 1e-3;
            let length_m = v * exposure_s;
            // D / (v T) of the exposure, times the sphere's silhouette on its D-wide band (π/4):
            // each streak carries the drop's cross-section πD²/4 of opacity-area.
            let covered = if length_m > 0.0 {
                (diameter_m / length_m).min(1.0)
            } else {
                1.0
            };
            let alpha = std::f64::consts::FRAC_PI_4 * covered;
            Streak {
                x_m: rng.random(),
                y_m: rng.random(),
                diameter_m,
                length_m,
                alpha,
            }
        })
        .collect()
}

/// Overlap of [a, b] with the pixel [k, k + 1].
#[inline]
fn overlap(a: f64, b: f64, k: i64) -> f64 {
    (b.min(k as f64 + 1.0) - a.max(k as f64)).max(0.0)
}

/// Composites the streak over `opacity` (size × size, row-major), wrapping at the edges:
/// a ← a + c (1 − a), i.e. 1 − a = ∏ (1 − cᵢ), with c = α × the pixel's coverage.
pub fn splat_streak(s: &Streak, size: usize, opacity: &mut [f32]) {
    let px = size as f64;
    let (x0, x1) = (
        (s.x_m - 0.5 * s.diameter_m) * px,
        (s.x_m + 0.5 * s.diameter_m) * px,
    );
    let (y0, y1) = (s.y_m * px, (s.y_m + s.length_m) * px);
    let size_i = size as i64;
    let cols: Vec<(usize, f64)> = (x0.floor() as i64..x1.ceil() as i64)
        .map(|c| (c.rem_euclid(size_i) as usize, overlap(x0, x1, c)))
        .filter(|&(_, w)| w > 0.0)
        .collect();
    for r in y0.floor() as i64..y1.ceil() as i64 {
        let cy = overlap(y0, y1, r) * s.alpha;
        if cy <= 0.0 {
            continue;
        }
        let row = r.rem_euclid(size_i) as usize * size;
        for &(c, cx) in &cols {
            let a = &mut opacity[row + c];
            let old = f64::from(*a);
            *a = (old + cy * cx * (1.0 - old)) as f32;
        }
    }
}

/// Renders one texture into `out` (size × size), overwriting it.
pub fn render_texture(
    rain_rate_mm_h: f64,
    lo_mm: f64,
    hi_mm: f64,
    size: usize,
    exposure_s: f64,
    seed: u64,
    out: &mut [f32],
) {
    out.fill(0.0);
    splat_all(rain_rate_mm_h, lo_mm, hi_mm, size, exposure_s, seed, out);
}

/// Composites every streak of one texture over `out`, which must start at zero.
fn splat_all(
    rain_rate_mm_h: f64,
    lo_mm: f64,
    hi_mm: f64,
    size: usize,
    exposure_s: f64,
    seed: u64,
    out: &mut [f32],
) {
    for s in draw_streaks(rain_rate_mm_h, lo_mm, hi_mm, exposure_s, seed) {
        splat_streak(&s, size, out);
    }
}

/// Renders every (rate, diameter) texture, shape (n_rates, n_diameters, size, size) flattened,
/// textures in parallel (see [`render_textures_into`]).
pub fn render_textures(req: &TextureRequest<'_>) -> Result<Vec<f32>> {
    let n = req.validate()?;
    // Reserved fallibly: out of memory is an error, not an abort.
    let mut out = crate::error::try_filled("the rain textures", n, 0.0f32)?;
    render_textures_into(req, &mut out)?;
    Ok(out)
}

/// [`render_textures`] into `out` (the caller's buffer of exactly the textures' size: numpy's,
/// from the Python binding, whose zeroed pages cost nothing until the textures touch them).
/// Every value is written: each texture is cleared in parallel, then drawn.
pub fn render_textures_into(req: &TextureRequest<'_>, out: &mut [f32]) -> Result<()> {
    let n = req.validate()?;
    if out.len() != n {
        return Err(Error::Length {
            param: crate::error::Param {
                name: "out",
                index: None,
            },
            len: out.len(),
            expected: n,
        });
    }
    let bins = diameter_bins(req.diameters_mm)?;
    let plane = req.size_px * req.size_px;
    let nd = bins.len();
    out.par_chunks_mut(plane).enumerate().for_each(|(k, tex)| {
        let rate = req.rain_rates_mm_h[k / nd];
        let (lo, hi) = bins[k % nd];
        tex.fill(0.0);
        splat_all(rate, lo, hi, req.size_px, req.exposure_s, req.seed, tex);
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_streak_integral_is_alpha_times_area() {
        let s = Streak {
            x_m: 0.9995,
            y_m: 0.95,
            diameter_m: 1.3e-3,
            length_m: 0.2,
            alpha: 0.3,
        };
        let size = 256;
        let mut t = vec![0.0f32; size * size];
        splat_streak(&s, size, &mut t);
        let sum: f64 = t.iter().map(|&v| f64::from(v)).sum();
        let want = s.alpha * s.diameter_m * s.length_m * (size * size) as f64;
        assert!((sum / want - 1.0).abs() < 1e-5, "{sum} vs {want}");
    }

    #[test]
    fn deterministic_and_seed_dependent() {
        let req = TextureRequest {
            rain_rates_mm_h: &[10.0],
            diameters_mm: &[1.0, 2.0],
            size_px: 64,
            exposure_s: 1.0 / 30.0,
            seed: 7,
        };
        let a = render_textures(&req).unwrap_or_default();
        let b = render_textures(&req).unwrap_or_default();
        let c = render_textures(&TextureRequest {
            seed: 8,
            ..req.clone()
        })
        .unwrap_or_default();
        assert!(!a.is_empty());
        assert_eq!(a, b);
        assert_ne!(a, c);
        let mut one = vec![1.0f32; 64 * 64];
        render_texture(10.0, 0.5, 1.5, 64, 1.0 / 30.0, 7, &mut one);
        assert_eq!(&one[..], &a[..64 * 64]);
    }

    #[test]
    fn budget_is_checked_before_allocating() {
        let rates = [1.0; 100];
        let req = TextureRequest {
            rain_rates_mm_h: &rates,
            diameters_mm: &[1.0],
            size_px: 16384,
            exposure_s: 0.03,
            seed: 0,
        };
        assert!(matches!(req.validate(), Err(Error::TooLarge { .. })));
    }
}
