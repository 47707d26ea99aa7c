//! sRGB transfer function (IEC 61966-2-1) for output encoding.

use rayon::prelude::*;

/// Encodes one linear value to sRGB in [0, 1] (input clipped to [0, 1]).
#[inline]
pub fn encode_srgb(linear: f32) -> f32 {
    let x = linear.clamp(0.0, 1.0);
    if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}

/// Encodes linear values to 8-bit sRGB (rounded to nearest), in parallel. NaN encodes as 0.
pub fn encode_srgb8(linear: &[f32], out: &mut [u8]) {
    out.par_chunks_mut(1 << 16).zip(linear.par_chunks(1 << 16)).for_each(|(o, l)| {
        for (b, &x) in o.iter_mut().zip(l) {
            let x = if x.is_nan() { 0.0 } else { x };
            *b = (encode_srgb(x) * 255.0).round() as u8;
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
}
