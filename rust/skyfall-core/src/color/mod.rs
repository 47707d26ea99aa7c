//! sRGB transfer function (IEC 61966-2-1) for output encoding.

use rayon::prelude::*;
use std::sync::OnceLock;

/// Encodes one linear value to sRGB in [0, 1] (input clipped to [0, 1]).
#[inline]
pub fn encode_srgb(linear: f32) -> f32 {
    let x = linear.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// One value to 8-bit sRGB by the formula: round(255 · encode(x)). NaN encodes as 0.
#[inline]
pub fn encode_srgb8_formula(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x };
    (encode_srgb(x) * 255.0).round() as u8
}

/// Lookup tables that reproduce [`encode_srgb8_formula`] bit for bit without `powf`: the
/// smallest input of each code from 1 to 255 (and +inf after them), and per block of 2¹⁶
/// float bit patterns below 1.0 the code of the block's first value. No block holds more than
/// one threshold (a block spans 1/128 of an octave, the code steps are wider; checked when
/// the table is built and by the tests), so one comparison finishes the lookup.
struct Srgb8Table {
    thresholds: [f32; 256],
    /// Per block of 2¹⁶ float bit patterns up to 1.0 (0x3F80 blocks), the first value's code;
    /// sized to a power of two the index is masked to, so lookups need no bounds check.
    coarse: Box<[u8; COARSE]>,
}

const COARSE: usize = 1 << 14;

fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: OnceLock<Srgb8Table> = OnceLock::new();
    TABLE.get_or_init(|| {
        let one = 1.0f32.to_bits();
        let mut thresholds = [f32::INFINITY; 256];
        for (k, t) in thresholds.iter_mut().enumerate().take(255) {
            // Smallest non-negative float whose code exceeds k (the formula is monotonic).
            let (mut lo, mut hi) = (0u32, one);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if usize::from(encode_srgb8_formula(f32::from_bits(mid))) > k {
                    hi = mid
                } else {
                    lo = mid + 1
                }
            }
            *t = f32::from_bits(lo);
        }
        let mut coarse = Box::new([255u8; COARSE]);
        for (b, c) in coarse.iter_mut().enumerate().take((one >> 16) as usize + 1) {
            *c = encode_srgb8_formula(f32::from_bits((b as u32) << 16));
        }
        debug_assert!(
            thresholds
                .windows(2)
                .all(|p| p[0].to_bits() >> 16 < p[1].to_bits() >> 16 || p[1].is_infinite())
        );
        Srgb8Table { thresholds, coarse }
    })
}

/// The 8-bit sRGB encoder: [`encode_srgb8_formula`]'s bits without `powf` (a table lookup
/// and at most a few comparisons), for fused passes that encode pixel by pixel.
#[derive(Clone, Copy)]
pub struct Srgb8Encoder(&'static Srgb8Table);

impl Srgb8Encoder {
    /// The encoder (its tables are built once per process, ~2 ms).
    pub fn new() -> Self {
        Srgb8Encoder(srgb8_table())
    }

    /// One linear value to 8-bit sRGB (rounded to nearest, clipped, NaN as 0), without a
    /// branch on the value.
    #[inline]
    pub fn encode(self, x: f32) -> u8 {
        // NaN and negatives (−0 included: max may keep it) to 0, ≥ 1 to the last block.
        self.encode_unit(if x > 0.0 { x.min(1.0) } else { 0.0 })
    }

    /// The smallest input of each code from 1 to 255 at index code − 1 (+inf at 255): the
    /// table [`Self::encode_unit`] finishes with, for the vectorised twins in [`crate::simd`].
    pub(crate) fn thresholds(self) -> &'static [f32; 256] {
        &self.0.thresholds
    }

    /// [`Self::encode`] of a value already in [0, 1] (clamped by the caller, NaN as 0).
    #[inline]
    pub fn encode_unit(self, x: f32) -> u8 {
        let t = self.0;
        let c = t.coarse[(x.to_bits() >> 16) as usize & (COARSE - 1)];
        c + u8::from(x >= t.thresholds[usize::from(c)])
    }
}

impl Default for Srgb8Encoder {
    fn default() -> Self {
        Self::new()
    }
}

/// Encodes linear values to 8-bit sRGB (rounded to nearest, clipped, NaN as 0), in parallel;
/// the same bits as [`encode_srgb8_formula`], through [`Srgb8Encoder`].
pub fn encode_srgb8(linear: &[f32], out: &mut [u8]) {
    encode_srgb8_at(crate::simd::Dispatch::detect().encode(), linear, out)
}

/// [`encode_srgb8`] with its kernel at `level` (the same bits at every level).
pub fn encode_srgb8_at(level: crate::simd::Level, linear: &[f32], out: &mut [u8]) {
    out.par_chunks_mut(1 << 16)
        .zip(linear.par_chunks(1 << 16))
        .for_each(|(o, l)| encode_srgb8_serial(level, l, o));
}

/// [`encode_srgb8_at`] on the calling thread (for callers already in parallel, as the 8-bit
/// output's bands are): the same bits.
pub fn encode_srgb8_serial(level: crate::simd::Level, linear: &[f32], out: &mut [u8]) {
    let e = Srgb8Encoder::new();
    let done = crate::simd::encode_row(level, e.thresholds(), linear, out);
    for (b, &x) in out[done..].iter_mut().zip(&linear[done..]) {
        *b = e.encode(x);
    }
}

/// Maps bytes through a 256-entry table (8-bit decoding), in parallel.
pub fn apply_lut8(bytes: &[u8], table: &[f32; 256], out: &mut [f32]) {
    out.par_chunks_mut(1 << 16)
        .zip(bytes.par_chunks(1 << 16))
        .for_each(|(o, b)| {
            for (v, &x) in o.iter_mut().zip(b) {
                *v = table[usize::from(x)];
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        assert_eq!(encode_srgb(0.0), 0.0);
        assert!((encode_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((encode_srgb(0.18) - 0.461_356).abs() < 1e-5); // middle grey
        let mut out = [0u8; 4];
        encode_srgb8(&[0.0, 1.0, 2.0, f32::NAN], &mut out);
        assert_eq!(out, [0, 255, 255, 0]);
    }

    #[test]
    fn lut8_maps_every_byte() {
        let table: [f32; 256] = std::array::from_fn(|i| i as f32 * 0.5);
        let bytes: Vec<u8> = (0..=255u8).rev().collect();
        let mut out = vec![0.0; 256];
        apply_lut8(&bytes, &table, &mut out);
        assert!(
            out.iter()
                .zip(&bytes)
                .all(|(v, &b)| *v == f32::from(b) * 0.5)
        );
    }

    #[test]
    fn no_coarse_block_holds_two_thresholds() {
        // What lets the encoder finish with one comparison.
        let t = srgb8_table();
        let blocks: Vec<u32> = t.thresholds[..255]
            .iter()
            .map(|v| v.to_bits() >> 16)
            .collect();
        assert!(blocks.windows(2).all(|p| p[0] < p[1]), "{blocks:?}");
    }

    #[test]
    fn the_table_gives_the_formula_bits() {
        // Every threshold and its neighbours, and a sweep of float bit patterns in [0, 1].
        let t = srgb8_table();
        let mut xs: Vec<f32> = t
            .thresholds
            .iter()
            .flat_map(|&v| {
                [
                    f32::from_bits(v.to_bits() - 1),
                    v,
                    f32::from_bits(v.to_bits() + 1),
                ]
            })
            .collect();
        xs.extend((0..1_000_000u32).map(|i| f32::from_bits(i * (1.0f32.to_bits() / 1_000_000))));
        xs.extend([
            -1.0,
            -0.0,
            f32::MIN_POSITIVE,
            1e-40,
            0.999_999_9,
            1.0,
            1.5,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ]);
        let mut out = vec![0u8; xs.len()];
        encode_srgb8(&xs, &mut out);
        for (x, b) in xs.iter().zip(&out) {
            assert_eq!(*b, encode_srgb8_formula(*x), "{x:e}");
        }
    }
}
