//! Rain haze (Yamamoto & Tadamura, eq. 2): attenuation and airlight along each pixel's view ray.
//!
//! I = I0 e^(−σ d) + L_air (1 − e^(−σ d)), d the distance along the view ray (depth · |ray|,
//! not the depth), σ = σ_air + σ_rain. Yamamoto & Tadamura write the airlight as Is/σ with
//! Is = ks·E_h; we take ks so that the airlight saturates at the sky's own airlight (the cloud
//! base's horizon luminance, [`crate::sky::Sky`]): distant objects fade into the horizon sky
//! as in real haze, and the σ → 0 limit is exact (no division by σ).
//!
//! Near the eye a frame draws part of σ as particles: the rain's drops of the drawn bins
//! within `rain_near_m`, the flakes of the drawn sizes within `snow_near_m`. Their share is
//! left out of the haze along each ray's stretch inside those spheres ([`Drawn`]: σ·d becomes
//! σ·d − Σ s·min(d, r)), so drawn particles and the haze do not count the same extinction
//! twice; the haze there carries only what is not drawn (drops outside the bins, flakes under
//! the smallest drawn size) and the air.
//!
//! A sky pixel (depth ∞) is seen through the rain and mist only up to the cloud base, a shell
//! h above the eye on the Earth's sphere ([`path_to_ceiling_m`]): h / sin γ overhead, about
//! √(2Rh) (138 km under a 1500 m base) along the horizon, so the sky fades continuously as σ
//! grows, σ → 0 returns it unchanged, and heavy rain turns the horizon to the airlight. For a box scene the pixel holds the
//! cloud base's luminance and this gives the sky's received luminance; for a photo it is the
//! photo's own sky. With σ = 0 every pixel is returned unchanged.
//!
//! [`apply_row`] is the CPU reference of `skyfall-gpu`'s `haze.wgsl`; the CPU frame
//! (`crate::frame`) calls it row by row.

pub mod airlight;
pub mod stage;

use crate::error::{Error, Param, Range, Result};
use crate::scene::camera::Camera;
use rayon::prelude::*;

/// Extinction that a frame draws as particles within `radius_m` of the eye (the rain's drops
/// within `rain_near_m`, the flakes within `snow_near_m`): the haze leaves it out of each ray's
/// stretch inside that sphere, so the particles and the haze do not count it twice.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Drawn {
    /// The sphere's radius, m.
    pub radius_m: f32,
    /// The drawn particles' share of σ, 1/m.
    pub extinction_per_m: f32,
}

/// Parameters of the haze pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Haze {
    /// Total extinction σ, 1/m (beyond the particles' spheres).
    pub extinction_per_m: f32,
    /// Airlight radiance at saturation, linear RGB (relative units).
    pub airlight: [f32; 3],
    /// Height of the cloud base above the eye, m: where a sky pixel's path ends (∞: sky
    /// pixels are the airlight, as for a fog without a top).
    pub sky_ceiling_m: f32,
    /// The rain's and the snow's drawn shares (zero where a frame draws none): along a ray of
    /// length d the optical depth is σ·d − Σ s·min(d, r).
    pub drawn: [Drawn; 2],
    /// The red and the blue channels' extinction beyond σ (the green's, at the visibility's
    /// 550 nm), 1/m: the clear air's Rayleigh and aerosol extinction at each channel's
    /// wavelength ([`clear_air_spectral`]), so distance turns blue-grey before it turns to the
    /// airlight; surfaces only (a sky pixel's colour is the sky model's). Zero (a grey haze)
    /// unless set by [`Haze::with_spectral`].
    pub spectral: [f32; 2],
}

/// Rayleigh extinction of air at 550 nm at sea level, 1/m (Bucholtz 1995, *Rayleigh-scattering
/// calculations for the terrestrial atmosphere*, the US standard atmosphere at 288 K:
/// 1.16e-2 /km).
pub const RAYLEIGH_550_PER_M: f64 = 1.16e-5;
/// Rayleigh extinction's wavelength exponent in the visible (Bucholtz 1995: λ^−4.08).
pub const RAYLEIGH_EXPONENT: f64 = 4.08;
/// The aerosol's Ångström exponent (Ångström's continental mean, 1.3).
pub const ANGSTROM_EXPONENT: f64 = 1.3;
/// The wavelengths the red and blue channels stand for, nm: the dominant wavelengths of the
/// Rec. 709 red and blue primaries against D65 (611 and 464 nm, as colour-science's
/// `dominant_wavelength` gives them on the CIE 1931 table at 1 nm; the green's, 549 nm, is
/// taken as the visibility's 550 nm).
pub const CHANNEL_NM: [f64; 2] = [611.0, 464.0];

/// The clear air's extinction at the red and blue channels' wavelengths less its extinction at
/// 550 nm, 1/m, for an air of extinction `air_per_m` at 550 nm (Koschmieder's 3.912/V): its
/// Rayleigh share β_R ([`RAYLEIGH_550_PER_M`], at most the whole) scales as λ^−4.08, the rest,
/// the aerosol's, as λ^−1.3. At V = 20 km the blue channel's extinction is 1.28 times the
/// green's and the red's 0.87 times.
pub fn clear_air_spectral(air_per_m: f64) -> [f32; 2] {
    let rayleigh = RAYLEIGH_550_PER_M.min(air_per_m.max(0.0));
    let aerosol = air_per_m.max(0.0) - rayleigh;
    CHANNEL_NM.map(|nm| {
        let x = nm / 550.0;
        (rayleigh * x.powf(-RAYLEIGH_EXPONENT) + aerosol * x.powf(-ANGSTROM_EXPONENT) - air_per_m)
            as f32
    })
}

/// A channel's transmittance along a finite path of `path_m` whose green optical depth is
/// `tau`, the channel's extinction `extra_per_m` beyond the green's: e^(−(τ + Δ·d)).
#[inline(always)]
pub fn channel_transmittance(tau: f32, path_m: f32, extra_per_m: f32) -> f32 {
    exp_neg(-(tau + extra_per_m * path_m).max(0.0))
}

impl Haze {
    /// Validated haze parameters, with sky pixels hazed up to a cloud base `sky_ceiling_m`
    /// above the eye (≥ 0, ∞ allowed).
    pub fn new(extinction_per_m: f32, airlight: [f32; 3], sky_ceiling_m: f32) -> Result<Self> {
        Range::closed(0.0, 1e3, "1/m").check(
            "extinction_per_m",
            None,
            f64::from(extinction_per_m),
        )?;
        for (i, a) in airlight.iter().enumerate() {
            Range::closed(0.0, 1e6, "").check("airlight", Some(i), f64::from(*a))?;
        }
        Range::closed(0.0, f64::INFINITY, "m").check(
            "sky_ceiling_m",
            None,
            f64::from(sky_ceiling_m),
        )?;
        Ok(Haze {
            extinction_per_m,
            airlight,
            sky_ceiling_m,
            drawn: [Drawn::default(); 2],
            spectral: [0.0; 2],
        })
    }

    /// The haze with the red and blue channels' extra extinction `spectral` (1/m, each finite
    /// and at least −σ: no channel's extinction below zero).
    pub fn with_spectral(mut self, spectral: [f32; 2]) -> Result<Self> {
        for (i, d) in spectral.iter().enumerate() {
            Range::closed(-f64::from(self.extinction_per_m), 1e3, "1/m").check(
                "spectral",
                Some(i),
                f64::from(*d),
            )?;
        }
        self.spectral = spectral;
        Ok(self)
    }

    /// The path to a surface at depth `depth_m` (m along the axis, finite) along a ray of
    /// squared column slope `u2` in `rays`' row: depth·|ray|.
    #[inline(always)]
    pub fn path_m(rays: &RowRays<'_>, u2: f32, depth_m: f32) -> f32 {
        depth_m * (u2 + rays.v2 + 1.0).sqrt()
    }

    /// The haze with `drawn` left out near the eye: each share within [0, σ] and its radius
    /// finite and ≥ 0.
    pub fn with_drawn(mut self, drawn: [Drawn; 2]) -> Result<Self> {
        let total: f32 = drawn.iter().map(|d| d.extinction_per_m).sum();
        for (i, d) in drawn.iter().enumerate() {
            Range::closed(0.0, 1e6, "m").check("drawn radius_m", Some(i), f64::from(d.radius_m))?;
            Range::closed(0.0, f64::from(self.extinction_per_m), "1/m").check(
                "drawn extinction_per_m",
                Some(i),
                f64::from(d.extinction_per_m),
            )?;
        }
        if total > self.extinction_per_m * (1.0 + 1e-6) {
            return Err(Error::Invalid {
                param: Param {
                    name: "drawn extinction_per_m",
                    index: None,
                },
                message: format!(
                    "the drawn shares sum to {total} 1/m, more than σ = {} 1/m",
                    self.extinction_per_m
                ),
            });
        }
        self.drawn = drawn;
        Ok(self)
    }

    /// The optical depth along `distance_m` from the eye: σ·d less the drawn shares over the
    /// ray's stretch inside their spheres (∞ for d = ∞ when σ > 0).
    #[inline(always)]
    pub fn optical_depth(&self, distance_m: f32) -> f32 {
        // (plain comparisons, not f32::min's NaN handling: they vectorise to one instruction)
        let within = |radius: f32| {
            if distance_m < radius {
                distance_m
            } else {
                radius
            }
        };
        let [r, s] = self.drawn;
        let tau = self.extinction_per_m * distance_m
            - r.extinction_per_m * within(r.radius_m)
            - s.extinction_per_m * within(s.radius_m);
        if tau > 0.0 { tau } else { 0.0 }
    }

    /// Transmittance e^(−τ) along `distance_m`, τ its [`Self::optical_depth`] (1 when σ = 0,
    /// 0 for d = ∞ when σ > 0), through [`exp_neg`].
    #[inline(always)]
    pub fn transmittance(&self, distance_m: f32) -> f32 {
        if self.extinction_per_m <= 0.0 {
            1.0
        } else {
            exp_neg(-self.optical_depth(distance_m))
        }
    }

    /// A row's transmittances into `t`: every pixel along depth·|ray| first (branch-free: the
    /// loop vectorises; a sky pixel's ∞ gives 0), then the sky pixels again along their path to
    /// the cloud base, when the ceiling is finite. Always inlined, so `crate::simd` compiles
    /// it a second time for AVX2.
    #[inline(always)]
    pub fn transmittance_row(&self, rays: &RowRays<'_>, depth: &[f32], t: &mut [f32]) {
        if self.drawn.iter().all(|d| d.extinction_per_m == 0.0) {
            // (nothing drawn near the eye: σ·d alone, the cheaper loop)
            for ((t, &d), &u2) in t.iter_mut().zip(depth).zip(rays.u2) {
                *t = if self.extinction_per_m <= 0.0 {
                    1.0
                } else {
                    exp_neg(-self.extinction_per_m * (d * (u2 + rays.v2 + 1.0).sqrt()))
                };
            }
        } else {
            for ((t, &d), &u2) in t.iter_mut().zip(depth).zip(rays.u2) {
                *t = self.transmittance(d * (u2 + rays.v2 + 1.0).sqrt());
            }
        }
        // Rows without sky (most of them in most frames) skip the second pass after one
        // branch-free scan.
        let has_sky = depth
            .iter()
            .fold(false, |any, &d| any | (d == f32::INFINITY));
        if !has_sky || self.sky_ceiling_m == f32::INFINITY || self.extinction_per_m <= 0.0 {
            return;
        }
        // Every pixel's sky value computed and kept where the pixel is sky: a select, not a
        // branch, so the loop vectorises (the sky pixels' values are the same either way).
        for (((t, &d), &u2), &rise) in t.iter_mut().zip(depth).zip(rays.u2).zip(rays.rise) {
            let len = (u2 + rays.v2 + 1.0).sqrt();
            let sin_elevation = (rise + rays.rise_row) / len;
            let sky = self.transmittance(path_to_ceiling_m(sin_elevation, self.sky_ceiling_m));
            *t = if d == f32::INFINITY { sky } else { *t };
        }
    }
}

/// The Earth's mean radius, m: the cloud base is a shell above it.
pub const EARTH_RADIUS_M: f32 = 6.371e6;

/// The distance from the eye along a ray of elevation γ (`sin_elevation` = sin γ) to a cloud
/// base `ceiling_m` above it, on the Earth's sphere of radius R:
/// √((R + h)² − R² cos² γ) − R sin γ, which is h / sin γ for high rays and √(2Rh + h²) along
/// the horizon (the curvature bounds the horizontal path a flat layer would make infinite).
/// Written as (2Rh + h²) / (√(…) + R sin γ) for γ ≥ 0, where the subtraction would cancel.
/// ∞ for an infinite ceiling.
#[inline(always)]
pub fn path_to_ceiling_m(sin_elevation: f32, ceiling_m: f32) -> f32 {
    const R: f32 = EARTH_RADIUS_M;
    let s = sin_elevation.clamp(-1.0, 1.0);
    let k = ceiling_m * (2.0 * R + ceiling_m);
    let root = (k + (R * s) * (R * s)).sqrt();
    let path = if s >= 0.0 {
        k / (root + R * s)
    } else {
        root - R * s
    };
    if ceiling_m == f32::INFINITY {
        f32::INFINITY
    } else {
        path
    }
}

/// The view rays of a camera as the haze reads them: per column the squared slope u² and the
/// world-y rise of the column's offset, per row the rest (ray = R·(u, −v, −1)).
#[derive(Debug, Clone)]
pub struct ViewRays {
    u2: Vec<f32>,
    rise: Vec<f32>,
    fy: f32,
    cy: f32,
    up_y: f32,
    back_y: f32,
}

/// One row's (or a run of columns') view rays, from [`ViewRays::row`].
#[derive(Debug, Clone, Copy)]
pub struct RowRays<'a> {
    /// Squared column slopes.
    pub u2: &'a [f32],
    /// The row's squared slope.
    pub v2: f32,
    /// The columns' share of the ray's world-y component.
    pub rise: &'a [f32],
    /// The row's share of it.
    pub rise_row: f32,
}

impl ViewRays {
    /// The rays of `cam`.
    pub fn new(cam: &Camera) -> Self {
        let right_y = cam.rotation.x_axis.y;
        let u = |x: u32| (x as f32 + 0.5 - cam.cx) / cam.fx;
        ViewRays {
            u2: (0..cam.width).map(|x| u(x) * u(x)).collect(),
            rise: (0..cam.width).map(|x| right_y * u(x)).collect(),
            fy: cam.fy,
            cy: cam.cy,
            up_y: cam.rotation.y_axis.y,
            back_y: cam.rotation.z_axis.y,
        }
    }

    /// Row `y`'s rays over the columns `cols`.
    #[inline]
    pub fn row(&self, y: u32, cols: std::ops::Range<usize>) -> RowRays<'_> {
        let v = (y as f32 + 0.5 - self.cy) / self.fy;
        RowRays {
            u2: &self.u2[cols.clone()],
            v2: v * v,
            rise: &self.rise[cols],
            rise_row: -(self.up_y * v) - self.back_y,
        }
    }
}

/// e^x for x ≤ 0 (−∞ gives 0, x > 0 is taken as 0), within 2 ulp of `f32::exp` and without a
/// branch or a libm call, so loops over pixels vectorise: x = n ln 2 + r with n rounded to
/// nearest (|r| ≤ ln 2 / 2, ln 2 split in two for an exact reduction), e^r by its Taylor
/// polynomial to r⁷ (truncation < 6e-9), 2ⁿ from the exponent bits. Below −87.3 (where f32
/// would turn subnormal) it returns 0.
#[inline(always)]
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

/// ln x for a normal, finite x > 0 (what `f32::ln` gives there, within 1.5e-7 absolute or 2
/// ulp, and without a libm call): x = 2ᵉ m with m in [√½, √2) from the bits, ln m =
/// 2 atanh s = 2 (s + s³/3 + … + s⁹/9) with s = (m − 1)/(m + 1), |s| ≤ 0.172 (truncation <
/// 1e-9), plus e ln 2 with ln 2 split in two. Zero, subnormals, infinities and NaN are outside
/// its domain: a caller clamps first.
#[inline(always)]
pub fn ln_normal(x: f32) -> f32 {
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    const SQRT_HALF_BITS: u32 = 0x3f35_04f3;
    let bits = x.to_bits();
    // The exponent that brings x into [√½, √2): an arithmetic shift of the bits' offset.
    let e = (bits.wrapping_sub(SQRT_HALF_BITS) as i32) >> 23;
    let m = f32::from_bits(bits.wrapping_sub((e as u32) << 23));
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let poly = s2 * (2.0 / 3.0 + s2 * (2.0 / 5.0 + s2 * (2.0 / 7.0 + s2 * (2.0 / 9.0))));
    let ef = e as f32;
    ef * LN2_HI + (ef * LN2_LO + (2.0 * s + s * poly))
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
        integer: false,
    })
}

/// The haze blend C·t + A·(1 − t): colour `c` seen through transmittance `t` with airlight `a`
/// (`one` the type's 1). Every CPU output's scalar and four-lane code draws the haze through
/// this one function (the SIMD twins in `simd.rs` and `haze.wgsl` are held to it by tests).
#[inline(always)]
pub fn blend<T>(c: T, t: T, a: T, one: T) -> T
where
    T: Copy + std::ops::Mul<Output = T> + std::ops::Add<Output = T> + std::ops::Sub<Output = T>,
{
    c * t + a * (one - t)
}

/// Applies haze to one row: `rgb_row` (W·3, in place), `t_row` (W) written, from
/// `depth_row` (W) seen along `rays` ([`ViewRays::row`]).
#[inline]
pub fn apply_row(
    haze: &Haze,
    rays: &RowRays<'_>,
    rgb_row: &mut [f32],
    depth_row: &[f32],
    t_row: &mut [f32],
) {
    haze.transmittance_row(rays, depth_row, t_row);
    if haze.spectral == [0.0; 2] {
        for (px, &t) in rgb_row.chunks_exact_mut(3).zip(t_row.iter()) {
            for (v, a) in px.iter_mut().zip(haze.airlight) {
                *v = blend(*v, t, a, 1.0);
            }
        }
        return;
    }
    // Red and blue through the air's extinction at their own wavelengths (the green, the
    // layer's, at 550 nm). A sky pixel keeps one transmittance: the sky model's colour already
    // holds what the air along its path scatters (Hosek & Wilkie's), and the sky pixels stay
    // the sky the ambient-light map integrates (`crate::sky::Sky::received_rgb`).
    let [dr, db] = haze.spectral;
    // In runs of 64 pixels: the channels' transmittances branch-free (a sky pixel's selected
    // back to the green's), so the loop vectorises; then the blend.
    const RUN: usize = 64;
    let mut red = [0.0f32; RUN];
    let mut blue = [0.0f32; RUN];
    for (((px, t), depth), u2) in rgb_row
        .chunks_mut(3 * RUN)
        .zip(t_row.chunks(RUN))
        .zip(depth_row.chunks(RUN))
        .zip(rays.u2.chunks(RUN))
    {
        for ((((r, b), &t), &d), &u2) in red.iter_mut().zip(&mut blue).zip(t).zip(depth).zip(u2) {
            let path = Haze::path_m(rays, u2, d);
            let tau = haze.optical_depth(path);
            let sky = d == f32::INFINITY;
            *r = if sky {
                t
            } else {
                channel_transmittance(tau, path, dr)
            };
            *b = if sky {
                t
            } else {
                channel_transmittance(tau, path, db)
            };
        }
        for (((px, &t), &r), &b) in px.chunks_exact_mut(3).zip(t).zip(&red).zip(&blue) {
            for ((v, a), t) in px.iter_mut().zip(haze.airlight).zip([r, t, b]) {
                *v = blend(*v, t, a, 1.0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::Camera;
    use glam::{Mat3, Vec3};

    #[test]
    fn drawn_shares_leave_the_haze_only_inside_their_spheres() {
        // σ = 0.01 /m, of which 0.004 drawn within 5 m and 0.003 within 8 m: the optical depth
        // is 0.003 d inside 5 m, 0.015 + 0.007 (d − 5) up to 8 m, 0.036 + 0.01 (d − 8) beyond.
        let h = Haze::new(0.01, [1.0; 3], f32::INFINITY)
            .unwrap()
            .with_drawn([
                Drawn {
                    radius_m: 5.0,
                    extinction_per_m: 0.004,
                },
                Drawn {
                    radius_m: 8.0,
                    extinction_per_m: 0.003,
                },
            ])
            .unwrap();
        for (d, want) in [(2.0f32, 0.006f32), (6.0, 0.022), (20.0, 0.156)] {
            assert!(
                (h.optical_depth(d) - want).abs() < 1e-6,
                "{d}: {}",
                h.optical_depth(d)
            );
            assert!((h.transmittance(d) - (-want).exp()).abs() < 1e-6);
        }
        assert_eq!(h.transmittance(f32::INFINITY), 0.0);
        // shares beyond σ are refused
        let too_much = [
            Drawn {
                radius_m: 5.0,
                extinction_per_m: 0.008,
            },
            Drawn {
                radius_m: 8.0,
                extinction_per_m: 0.003,
            },
        ];
        assert!(h.with_drawn(too_much).is_err());
    }

    #[test]
    fn haze_limits() {
        let h = Haze::new(0.01, [0.4; 3], f32::INFINITY).unwrap();
        assert_eq!(h.transmittance(f32::INFINITY), 0.0);
        assert!((h.transmittance(100.0) - (-1.0f32).exp()).abs() < 1e-7);
        let clear = Haze::new(0.0, [0.4; 3], 900.0).unwrap();
        assert_eq!(clear.transmittance(f32::INFINITY), 1.0);
        assert!(Haze::new(f32::NAN, [0.0; 3], 1.0).is_err());
        assert!(Haze::new(0.1, [0.0; 3], -1.0).is_err());
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
    fn ln_normal_is_libm_within_its_bound() {
        let mut worst = 0.0f64;
        let mut check = |x: f32| {
            let (got, want) = (f64::from(ln_normal(x)), f64::from(x).ln());
            let ulp = f64::from(want.abs() as f32) * f64::from(f32::EPSILON);
            let err = (got - want).abs();
            assert!(err <= 1.5e-7_f64.max(2.0 * ulp), "ln {x}: {got} vs {want}");
            worst = worst.max(err);
        };
        // every octave from the smallest normal to the largest finite, densely near 1
        for i in 0..=2_000_000u32 {
            let x = f32::MIN_POSITIVE * 2f32.powf(254.0 * i as f32 / 2e6);
            if x.is_finite() {
                check(x);
            }
        }
        for i in 0..200_000u32 {
            check(0.9 + 0.2 * i as f32 / 2e5);
        }
        check(1.0);
        check(f32::MAX);
        assert!(ln_normal(1.0) == 0.0 && worst > 0.0);
    }

    #[test]
    fn distance_uses_the_ray_not_the_depth() {
        let cam = Camera::new(3, 1, [1.0, 1.0, 1.5, 0.5], Vec3::ZERO, Mat3::IDENTITY).unwrap();
        let h = Haze::new(0.1, [1.0; 3], f32::INFINITY).unwrap();
        let mut rgb = vec![0.0; 9];
        let mut t = vec![0.0; 3];
        let rays = ViewRays::new(&cam);
        apply_row(&h, &rays.row(0, 0..3), &mut rgb, &[10.0; 3], &mut t);
        // side pixels are 1 px off axis with f = 1: |ray| = sqrt(2).
        assert!((t[0] - (-0.1f32 * 10.0 * 2f32.sqrt()).exp()).abs() < 1e-6);
        assert!((t[1] - (-1.0f32).exp()).abs() < 1e-6);
        assert!((rgb[3] - (1.0 - (-1.0f32).exp())).abs() < 1e-6);
    }

    #[test]
    fn clear_air_turns_distance_blue_grey_channel_by_channel() {
        // σ at 550 nm 0.004 /m (V ≈ 1 km), of it 1.16e-5 Rayleigh: the red's and the blue's σ
        // are β_R (λ/550)^−4.08 + (σ − β_R)(λ/550)^−1.3, written out here in f64.
        let sigma = 0.004f64;
        let at = |nm: f64| {
            let x = nm / 550.0;
            1.16e-5 * x.powf(-4.08) + (sigma - 1.16e-5) * x.powf(-1.3)
        };
        let spectral = clear_air_spectral(sigma);
        assert!((f64::from(spectral[0]) - (at(611.0) - sigma)).abs() < 1e-9);
        assert!((f64::from(spectral[1]) - (at(464.0) - sigma)).abs() < 1e-9);
        assert!(spectral[0] < 0.0 && spectral[1] > 0.0);
        // Beyond Rayleigh's own visibility (337 km) the air is Rayleigh's alone.
        let thin = clear_air_spectral(5e-6);
        let ratio = (5e-6 + f64::from(thin[1])) / 5e-6;
        assert!(
            (ratio - (464.0f64 / 550.0).powf(-4.08)).abs() < 1e-5,
            "{ratio}"
        );
        // A row: pixels 10 m to 2 km deep, a sky pixel without a ceiling (one transmittance:
        // the sky's colour is the sky model's).
        let cam = Camera::new(4, 1, [1.0, 1.0, 2.0, 0.5], Vec3::ZERO, Mat3::IDENTITY).unwrap();
        let air = [0.6f32, 0.7, 0.9];
        let h = Haze::new(sigma as f32, air, f32::INFINITY)
            .unwrap()
            .with_spectral(spectral)
            .unwrap();
        let depth = [10.0f32, 300.0, 2000.0, f32::INFINITY];
        let colour = [0.2f32, 0.3, 0.1];
        let mut rgb: Vec<f32> = colour.repeat(4);
        let mut t = vec![0.0; 4];
        let rays = ViewRays::new(&cam);
        apply_row(&h, &rays.row(0, 0..4), &mut rgb, &depth, &mut t);
        // The sky pixel (no ceiling) is the airlight in every channel.
        for c in 0..3 {
            assert_eq!(rgb[9 + c], air[c]);
        }
        for (i, &d) in depth.iter().enumerate().take(3) {
            let u = (i as f64 + 0.5 - 2.0) / 1.0;
            let path = f64::from(d) * (u * u + 1.0).sqrt();
            for (c, nm) in [(0usize, 611.0), (1, 550.0), (2, 464.0)] {
                let sig = if c == 1 { sigma } else { at(nm) };
                let tc = (-sig * path).exp();
                let want = f64::from(colour[c]) * tc + f64::from(air[c]) * (1.0 - tc);
                let got = f64::from(rgb[3 * i + c]);
                assert!(
                    (got - want).abs() < 2e-6,
                    "pixel {i} channel {c}: {got} vs {want}"
                );
            }
            assert!((f64::from(t[i]) - (-sigma * path).exp()).abs() < 1e-6);
        }
        // Blue fades first: at 10 m the pixel has moved a quarter further towards the airlight
        // in blue than in green, and less in red.
        let moved = |c: usize| (rgb[c] - colour[c]) / (air[c] - colour[c]);
        assert!(moved(2) > 1.2 * moved(1) && moved(0) < moved(1));
        // A negative extinction beyond the green's own is refused.
        assert!(h.with_spectral([-0.005, 0.0]).is_err());
    }

    #[test]
    fn a_sky_pixel_is_hazed_up_to_the_cloud_base_along_its_ray() {
        // A camera pitched up 30° and turned: every pixel's path to a ceiling 800 m above the
        // eye is the spherical shell's, from the ray itself (f64, direct form).
        let rot = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(30f32.to_radians());
        let cam = Camera::new(9, 7, [6.0, 6.0, 4.5, 3.5], Vec3::new(0.0, 2.0, 0.0), rot).unwrap();
        let h = Haze::new(1.5e-3, [0.5; 3], 800.0).unwrap();
        let rays = ViewRays::new(&cam);
        for y in 0..7 {
            let mut t = vec![0.0; 9];
            h.transmittance_row(&rays.row(y, 0..9), &[f32::INFINITY; 9], &mut t);
            for (x, &tx) in t.iter().enumerate() {
                let sin_el = f64::from(cam.ray_direction(x as u32, y).normalize().y);
                let r = f64::from(EARTH_RADIUS_M);
                let path =
                    ((r + 800.0).powi(2) - (r * r) * (1.0 - sin_el * sin_el)).sqrt() - r * sin_el;
                if sin_el > 0.5 {
                    assert!((path - 800.0 / sin_el).abs() < 1e-3 * path); // high rays: h / sin γ
                }
                let want = (-1.5e-3 * path).exp();
                assert!(
                    (f64::from(tx) - want).abs() < 1e-5,
                    "({x}, {y}): {tx} vs {want}"
                );
            }
        }
        // Along the horizon the path is √(2Rh + h²), 101 km: in this rain, the airlight.
        assert!(
            (path_to_ceiling_m(0.0, 800.0) - (2.0 * 6.371e6 * 800.0 + 640_000.0f32).sqrt()).abs()
                < 1.0
        );
        let level = Camera::new(1, 3, [1.0, 1.0, 0.5, 1.5], Vec3::ZERO, Mat3::IDENTITY).unwrap();
        let mut t = vec![1.0; 1];
        h.transmittance_row(
            &ViewRays::new(&level).row(2, 0..1),
            &[f32::INFINITY],
            &mut t,
        );
        assert_eq!(t[0], 0.0);
        // Below the horizon it is longer still, and an infinite ceiling never ends.
        assert!(path_to_ceiling_m(-0.1, 800.0) > path_to_ceiling_m(0.0, 800.0));
        assert_eq!(path_to_ceiling_m(0.5, f32::INFINITY), f32::INFINITY);
        // Continuous in σ: a whisper of haze leaves even the horizon's sky nearly as it was.
        let thin = Haze::new(1e-9, [0.5; 3], 800.0).unwrap();
        let mut t = vec![0.0; 1];
        thin.transmittance_row(
            &ViewRays::new(&level).row(1, 0..1),
            &[f32::INFINITY],
            &mut t,
        );
        let want = (-1e-9 * (2.0 * 6.371e6 * 800.0 + 640_000.0f64).sqrt()).exp();
        assert!(
            (f64::from(t[0]) - want).abs() < 1e-6 && want > 0.9998,
            "{}",
            t[0]
        );
        // Clear air returns the sky unchanged.
        let clear = Haze::new(0.0, [0.5; 3], 800.0).unwrap();
        let mut rgb = vec![0.25; 27];
        let mut t = vec![0.0; 9];
        apply_row(
            &clear,
            &rays.row(0, 0..9),
            &mut rgb,
            &[f32::INFINITY; 9],
            &mut t,
        );
        assert!(rgb.iter().all(|&v| v == 0.25) && t.iter().all(|&v| v == 1.0));
    }
}
