//! Sky luminance distributions, as L/Lz (relative to the zenith luminance).
//!
//! - Overcast (Yamamoto & Tadamura, eq. 4): the CIE standard overcast sky of Moon & Spencer,
//!   L/Lz = (1 + 2 sin γ)/3, γ the elevation.
//! - General sky, CIE S 011/E:2003 (ISO 15469), types 1–15: L/Lz = φ(Z) f(χ) / (φ(0) f(Z_s)),
//!   φ(Z) = 1 + a·exp(b / cos Z) (1 at the horizon), f(χ) = 1 + c·(exp(dχ) − exp(dπ/2)) + e·cos²χ,
//!   Z the zenith angle, χ the angle to the sun, Z_s the sun's zenith angle.

use crate::error::{Error, Param, Result};
use glam::Vec3;
use std::f64::consts::FRAC_PI_2;

/// Parameters a–e of the 15 CIE general skies (CIE S 011/E:2003, table 1; copied into
/// `tests/data/cie_general_sky_15_types.csv` with its source).
pub const CIE_TYPES: [[f64; 5]; 15] = [
    [4.0, -0.7, 0.0, -1.0, 0.0],
    [4.0, -0.7, 2.0, -1.5, 0.15],
    [1.1, -0.8, 0.0, -1.0, 0.0],
    [1.1, -0.8, 2.0, -1.5, 0.15],
    [0.0, -1.0, 0.0, -1.0, 0.0],
    [0.0, -1.0, 2.0, -1.5, 0.15],
    [0.0, -1.0, 5.0, -2.5, 0.3],
    [0.0, -1.0, 10.0, -3.0, 0.45],
    [-1.0, -0.55, 2.0, -1.5, 0.15],
    [-1.0, -0.55, 5.0, -2.5, 0.3],
    [-1.0, -0.55, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 16.0, -3.0, 0.3],
    [-1.0, -0.15, 16.0, -3.0, 0.3],
    [-1.0, -0.15, 24.0, -2.8, 0.15],
];

/// A sky luminance distribution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SkyKind {
    /// Yamamoto & Tadamura's CIE standard overcast sky (Moon & Spencer).
    Overcast,
    /// CIE general sky type 1–15 with the sun's unit direction.
    General {
        /// The type, 1–15.
        sky_type: u8,
        /// Unit vector towards the sun (may be below the horizon for the azimuthally uniform types).
        sun: Vec3,
    },
}

impl SkyKind {
    /// Validated general sky. Types whose indicatrix depends on the sun (c ≠ 0 or e ≠ 0)
    /// need a sun direction; the others ignore it.
    pub fn general(sky_type: i64, sun: Option<Vec3>) -> Result<Self> {
        if !(1..=15).contains(&sky_type) {
            return Err(Error::OutOfRange {
                param: Param {
                    name: "sky",
                    index: None,
                },
                value: sky_type as f64,
                range: "1..15 (CIE general sky type) or \"overcast\"".into(),
                integer: true,
            });
        }
        let p = CIE_TYPES[(sky_type - 1) as usize];
        let needs_sun = p[2] != 0.0 || p[4] != 0.0;
        let sun = match sun {
            Some(s) if s.is_finite() && s.length() > 0.0 => s.normalize(),
            Some(_) => {
                return Err(Error::Invalid {
                    param: Param {
                        name: "sun",
                        index: None,
                    },
                    message: "the sun direction must be finite and non-zero".into(),
                });
            }
            None if needs_sun => {
                return Err(Error::Invalid {
                    param: Param {
                        name: "sun_elevation_deg",
                        index: None,
                    },
                    message: format!(
                        "CIE sky type {sky_type} depends on the sun: give sun_elevation_deg and sun_azimuth_deg"
                    ),
                });
            }
            None => Vec3::Y,
        };
        if needs_sun && sun.y < 0.0 {
            return Err(Error::OutOfRange {
                param: Param {
                    name: "sun_elevation_deg",
                    index: None,
                },
                value: f64::from(sun.y.asin().to_degrees()),
                range: crate::ranges::SUN_ELEVATION_DEG.range.to_string(),
                integer: false,
            });
        }
        Ok(SkyKind::General {
            sky_type: sky_type as u8,
            sun,
        })
    }

    /// Whether the sky is the same at every azimuth: the overcast sky, and the general types
    /// whose indicatrix ignores the sun (c = e = 0: types 1, 3 and 5).
    pub fn symmetric(&self) -> bool {
        match *self {
            SkyKind::Overcast => true,
            SkyKind::General { sky_type, .. } => {
                let p = CIE_TYPES[usize::from(sky_type) - 1];
                p[2] == 0.0 && p[4] == 0.0
            }
        }
    }

    /// The five parameters a–e, and the sun (for the GPU uniform); the overcast sky is
    /// encoded as a = NaN.
    pub fn params(&self) -> ([f32; 5], Vec3) {
        match *self {
            SkyKind::Overcast => ([f32::NAN, 0.0, 0.0, 0.0, 0.0], Vec3::Y),
            SkyKind::General { sky_type, sun } => {
                (CIE_TYPES[usize::from(sky_type) - 1].map(|v| v as f32), sun)
            }
        }
    }

    /// The sky's luminance distribution, L/Lz along any direction
    /// ([`Shape::relative_to_zenith`]), with what does not depend on the direction worked out
    /// once: the normalisation φ(0)·f(Z_s) and the indicatrix's constant part.
    pub fn shape(&self) -> Shape {
        match *self {
            SkyKind::Overcast => Shape::Overcast,
            SkyKind::General { sky_type, sun } => {
                let [a, b, c, d, e] = CIE_TYPES[usize::from(sky_type) - 1];
                // f(χ) = 1 − c·exp(dπ/2) + c·exp(dχ) + e·cos²χ, cos χ = ω·sun
                let base = 1.0 - c * (d * FRAC_PI_2).exp();
                let cos_zs = f64::from(sun.y).clamp(-1.0, 1.0);
                let f_zs = base + c * (d * cos_zs.acos()).exp() + e * cos_zs * cos_zs;
                let phi_0 = 1.0 + a * b.exp();
                Shape::General {
                    a,
                    b,
                    c,
                    d,
                    e,
                    base,
                    sun,
                    inv_norm: 1.0 / (phi_0 * f_zs),
                }
            }
        }
    }
}

/// A [`SkyKind`]'s luminance distribution ready to evaluate along many directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// (1 + 2 sin γ)/3.
    Overcast,
    /// φ(Z)·f(χ)/(φ(0)·f(Z_s)).
    General {
        /// The gradation's a and b, the indicatrix's c, d and e.
        a: f64,
        /// b.
        b: f64,
        /// c.
        c: f64,
        /// d.
        d: f64,
        /// e.
        e: f64,
        /// 1 − c·exp(dπ/2).
        base: f64,
        /// Unit vector towards the sun.
        sun: Vec3,
        /// 1 / (φ(0)·f(Z_s)).
        inv_norm: f64,
    },
}

impl Shape {
    /// L/Lz along unit direction `dir` (0 below the horizon): [`Shape::gradation`] times
    /// [`Shape::indicatrix`].
    #[inline]
    pub fn relative_to_zenith(&self, dir: Vec3) -> f64 {
        self.gradation(f64::from(dir.y)) * self.indicatrix(dir)
    }

    /// The part of L/Lz that depends on the elevation alone, at sin(elevation) `cz`: φ(Z)
    /// over the normalisation φ(0)·f(Z_s), (1 + 2 sin γ)/3 overcast; 0 below the horizon.
    #[inline]
    pub fn gradation(&self, cz: f64) -> f64 {
        if cz < 0.0 {
            return 0.0;
        }
        match *self {
            Shape::Overcast => (1.0 + 2.0 * cz) / 3.0,
            Shape::General { a, b, inv_norm, .. } => {
                let phi = if cz <= 0.0 {
                    1.0
                } else {
                    1.0 + a * (b / cz).exp()
                };
                phi * inv_norm
            }
        }
    }

    /// The part of L/Lz that depends on the angle χ to the sun along unit `dir`: the
    /// indicatrix f(χ) (1 overcast).
    #[inline]
    pub fn indicatrix(&self, dir: Vec3) -> f64 {
        match *self {
            Shape::Overcast => 1.0,
            Shape::General {
                c, d, e, base, sun, ..
            } => {
                let cos_chi = f64::from(dir.dot(sun)).clamp(-1.0, 1.0);
                let peak = if c == 0.0 {
                    0.0
                } else {
                    c * (d * cos_chi.acos()).exp()
                };
                base + peak + e * cos_chi * cos_chi
            }
        }
    }
}
