//! Rain haze (Yamamoto & Tadamura, eq. 2): attenuation and airlight along each pixel's view ray.
//!
//! I = I0 e^(−σ d) + L_air (1 − e^(−σ d)), d = depth · |ray| (the distance along the view
//! ray, not the depth), σ = σ_air + σ_rain. Yamamoto & Tadamura write the airlight as Is/σ with
//! Is = ks·E_h; we set ks so that the airlight saturates at the horizon luminance of the CIE
//! overcast sky ([`AIRLIGHT_RELATIVE`] = 3/7 of E/π): then distant objects fade into the
//! horizon sky as in real haze, and the σ → 0 limit is exact (no division by σ). Sky pixels
//! (d = ∞) become the airlight when σ > 0; with σ = 0 every pixel is returned unchanged.
//!
//! [`apply_row`] is the CPU reference of `skyfall-gpu`'s `haze.wgsl`; the CPU frame
//! (`crate::frame`) calls it row by row.

use crate::error::{Error, Param, Range, Result};
use rayon::prelude::*;

/// Airlight at saturation, relative to E/π: the overcast sky's horizon luminance, 3/7.
pub const AIRLIGHT_RELATIVE: f32 = 3.0 / 7.0;

/// Parameters of the haze pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Haze {
    /// Total extinction σ, 1/m.
    pub extinction_per_m: f32,
    /// Airlight radiance at saturation, linear RGB (relative units).
    pub airlight: [f32; 3],
}

impl Haze {
    /// Validated haze parameters.
    pub fn new(extinction_per_m: f32, airlight: [f32; 3]) -> Result<Self> {
        Range::closed(0.0, 1e3, "1/m").check(
            "extinction_per_m",
            None,
            f64::from(extinction_per_m),
        )?;
        for (i, a) in airlight.iter().enumerate() {
            Range::closed(0.0, 1e6, "").check("airlight", Some(i), f64::from(*a))?;
        }
        Ok(Haze {
            extinction_per_m,
            airlight,
        })
    }

    /// Transmittance e^(−σ d) along `distance_m` (1 when σ = 0, 0 for d = ∞ when σ > 0),
    /// through [`exp_neg`].
    #[inline]
    pub fn transmittance(&self, distance_m: f32) -> f32 {
        if self.extinction_per_m <= 0.0 {
            1.0
        } else {
            exp_neg(-self.extinction_per_m * distance_m)
        }
    }
}

/// e^x for x ≤ 0 (−∞ gives 0, x > 0 is taken as 0), within 2 ulp of `f32::exp` and without a
/// branch or a libm call, so loops over pixels vectorise: x = n ln 2 + r with n rounded to
/// nearest (|r| ≤ ln 2 / 2, ln 2 split in two for an exact reduction), e^r by its Taylor
/// polynomial to r⁷ (truncation < 6e-9), 2ⁿ from the exponent bits. Below −87.3 (where f32
/// would turn subnormal) it returns 0.
#[inline]
pub fn exp_neg(x: f32) -> f32 {
    const LOG2_E: f32 = std::f32::consts::LOG2_E;
    const LN2_HI: f32 = 0.693_145_75; // ln 2 with its low 12 bits zero: n·LN2_HI is exact
    const LN2_LO: f32 = 1.428_606_8e-6;
    const ROUND: f32 = 12_582_912.0; // 1.5·2²³: adding it rounds to an integer
    let under = x < -87.3;
    let x = x.clamp(-87.3, 0.0);
    let shifted = x * LOG2_E + ROUND;
    let n = shifted - ROUND;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    let mut p = 1.0 / 5040.0;
    for c in [
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ] {
        p = p * r + c;
    }
    // n in [−126, 0] sits in the low mantissa bits of `shifted` (offset by 2²²): the
    // exponent field of 2ⁿ is n + 127 ≥ 1. Integer arithmetic, so it vectorises too.
    let n_int = shifted.to_bits().wrapping_sub(ROUND.to_bits()) as i32;
    let scale = f32::from_bits(((n_int + 127) as u32) << 23);
    if under { 0.0 } else { p * scale }
}

/// Checks that a depth map holds no NaN and no negative value (in parallel; the first bad
/// value is named).
pub fn check_depth(depth_m: &[f32]) -> Result<()> {
    const CHUNK: usize = 1 << 16;
    let bad = |d: f32| d.is_nan() || d < 0.0;
    // `d >= 0` is false exactly for NaN and negatives; folded without an early exit over a
    // chunk, it vectorises (a clean map is the common case).
    let clean = |c: &[f32]| c.iter().fold(true, |ok, &d| ok & (d >= 0.0));
    let Some(k) = depth_m.par_chunks(CHUNK).position_first(|c| !clean(c)) else {
        return Ok(());
    };
    let i = k * CHUNK
        + depth_m[k * CHUNK..]
            .iter()
            .position(|&d| bad(d))
            .unwrap_or(0);
    let d = depth_m[i];
    Err(Error::OutOfRange {
        param: Param {
            name: "depth_m",
            index: Some(i),
        },
        value: f64::from(d),
        range: "[0, inf] m (inf for sky)".into(),
    })
}

/// Applies haze to one row: `rgb_row` (W·3, in place), `t_row` (W) written, from
/// `depth_row` (W); `u2` are the camera's squared column slopes and `v2` the row's
/// (see [`crate::scene::camera::Camera::column_slopes_sq`]), so the ray length per unit depth is √(u² + v² + 1).
#[inline]
pub fn apply_row(
    haze: &Haze,
    u2: &[f32],
    v2: f32,
    rgb_row: &mut [f32],
    depth_row: &[f32],
    t_row: &mut [f32],
) {
    for (x, (&d, t_out)) in depth_row.iter().zip(t_row.iter_mut()).enumerate() {
        let t = haze.transmittance(d * (u2[x] + v2 + 1.0).sqrt());
        *t_out = t;
        for (c, v) in rgb_row[3 * x..3 * x + 3].iter_mut().enumerate() {
            *v = *v * t + haze.airlight[c] * (1.0 - t);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::Camera;
    use glam::{Mat3, Vec3};

    #[test]
    fn haze_limits() {
        let h = Haze::new(0.01, [0.4; 3]).unwrap_or(Haze {
            extinction_per_m: 0.0,
            airlight: [0.0; 3],
        });
        assert_eq!(h.transmittance(f32::INFINITY), 0.0);
        assert!((h.transmittance(100.0) - (-1.0f32).exp()).abs() < 1e-7);
        let clear = Haze {
            extinction_per_m: 0.0,
            airlight: [0.4; 3],
        };
        assert_eq!(clear.transmittance(f32::INFINITY), 1.0);
        assert!(Haze::new(f32::NAN, [0.0; 3]).is_err());
        assert!(
            check_depth(&[1.0, f32::INFINITY]).is_ok()
                && check_depth(&[f32::NAN]).is_err()
                && check_depth(&[-1.0]).is_err()
        );
        // the first bad value is named, past the first parallel chunk too
        let mut far = vec![1.0f32; 300_000];
        far[250_000] = -2.0;
        far[200_001] = f32::NAN;
        let e = check_depth(&far).unwrap_err().to_string();
        assert!(e.contains("200001") && e.contains("depth_m"), "{e}");
    }

    #[test]
    fn exp_neg_is_within_2_ulp_of_libm() {
        let ulps = |a: f32, b: f32| (a.to_bits() as i64 - b.to_bits() as i64).abs();
        let mut worst = 0;
        for i in 0..=2_000_000u32 {
            let x = -87.3 * i as f32 / 2e6;
            worst = worst.max(ulps(exp_neg(x), x.exp()));
        }
        // and near zero, where most haze lives
        for i in 0..100_000u32 {
            let x = -(i as f32) * 1e-7;
            worst = worst.max(ulps(exp_neg(x), x.exp()));
        }
        assert!(worst <= 2, "worst {worst} ulp");
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp_neg(-1000.0), 0.0);
        assert!(exp_neg(-87.4) == 0.0 && (-87.4f32).exp() < 1.2e-38);
    }

    #[test]
    fn distance_uses_the_ray_not_the_depth() {
        let cam = Camera::new(3, 1, [1.0, 1.0, 1.5, 0.5], Vec3::ZERO, Mat3::IDENTITY);
        let cam = cam.unwrap_or(Camera {
            width: 3,
            height: 1,
            fx: 1.0,
            fy: 1.0,
            cx: 1.5,
            cy: 0.5,
            position_m: glam::DVec3::ZERO,
            rotation: Mat3::IDENTITY,
        });
        let h = Haze {
            extinction_per_m: 0.1,
            airlight: [1.0; 3],
        };
        let mut rgb = vec![0.0; 9];
        let mut t = vec![0.0; 3];
        apply_row(
            &h,
            &cam.column_slopes_sq(),
            cam.row_slope_sq(0),
            &mut rgb,
            &[10.0; 3],
            &mut t,
        );
        // side pixels are 1 px off axis with f = 1: |ray| = sqrt(2).
        assert!((t[0] - (-0.1f32 * 10.0 * 2f32.sqrt()).exp()).abs() < 1e-6);
        assert!((t[1] - (-1.0f32).exp()).abs() < 1e-6);
        assert!((rgb[3] - (1.0 - (-1.0f32).exp())).abs() < 1e-6);
    }
}
