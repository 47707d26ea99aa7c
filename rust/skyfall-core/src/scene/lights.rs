//! Point and spot lights (street lamps, headlights): they light rain drops and the surfaces
//! that face them with inverse-square falloff and, for spots, a smooth cone
//! ([`Light::illuminance_lux`], shared by the drops, the surfaces and the glows).

use crate::error::{Error, Param, Range, Result};
use glam::Vec3;

/// A point or spot light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Position, m.
    pub position_m: Vec3,
    /// Luminous intensity on its axis, cd.
    pub intensity_cd: f32,
    /// Linear RGB colour (scales the intensity per channel).
    pub color: Vec3,
    /// For spots: unit axis, cosine of the outer half-angle, cosine of the inner half-angle
    /// (full intensity inside the inner cone, smooth falloff to zero at the outer one).
    pub spot: Option<(Vec3, f32, f32)>,
}

impl Light {
    /// A validated light from the packed row `[x, y, z, r, g, b, I_cd, dx, dy, dz, cos_outer,
    /// cos_inner]`; a zero direction makes a point light.
    pub fn from_row(row: &[f32], index: usize) -> Result<Self> {
        let i = Some(index);
        for (k, &v) in row.iter().enumerate() {
            if !v.is_finite() {
                return Err(Error::Invalid {
                    param: Param {
                        name: "lights",
                        index: i,
                    },
                    message: format!("value {k} = {v} is not finite"),
                });
            }
        }
        let [
            x,
            y,
            z,
            r,
            g,
            b,
            intensity,
            dx,
            dy,
            dz,
            cos_outer,
            cos_inner,
        ] = <[f32; 12]>::try_from(row).map_err(|_| Error::Invalid {
            param: Param {
                name: "lights",
                index: i,
            },
            message: format!("needs 12 values, got {}", row.len()),
        })?;
        for c in [x, y, z] {
            crate::ranges::POSITION_M.check_at(i, f64::from(c))?;
        }
        crate::ranges::INTENSITY_CD.check_at(i, f64::from(intensity))?;
        for c in [r, g, b] {
            crate::ranges::COLOR.check_at(i, f64::from(c))?;
        }
        let dir = Vec3::new(dx, dy, dz);
        let spot = if dir.length_squared() > 0.0 {
            Range::closed(-1.0, 1.0, "").check("cos_outer", i, f64::from(cos_outer))?;
            Range::closed(f64::from(cos_outer), 1.0, "").check(
                "cos_inner",
                i,
                f64::from(cos_inner),
            )?;
            Some((dir.normalize(), cos_outer, cos_inner))
        } else {
            None
        };
        Ok(Light {
            position_m: Vec3::new(x, y, z),
            intensity_cd: intensity,
            color: Vec3::new(r, g, b),
            spot,
        })
    }

    /// Illuminance at `p` from this light, lux per colour channel, on a surface facing it.
    #[inline]
    pub fn illuminance_lux(&self, p: Vec3) -> Vec3 {
        let d = p - self.position_m;
        let r2 = d.length_squared().max(1e-4);
        let cone = match self.spot {
            None => 1.0,
            Some((axis, cos_outer, cos_inner)) => {
                let c = axis.dot(d) / r2.sqrt();
                if c <= cos_outer {
                    0.0
                } else if c >= cos_inner {
                    1.0
                } else {
                    let t = (c - cos_outer) / (cos_inner - cos_outer).max(1e-6);
                    t * t * (3.0 - 2.0 * t)
                }
            }
        };
        self.color * (self.intensity_cd * cone / r2)
    }

    /// Illuminance at `p` on a surface of unit normal `n`, lux per channel: I·cone·cos θ / r²
    /// (Lambert's cosine law; zero for a face turned away), and the unit vector from `p` to
    /// the light with its distance, m (for the shadow ray).
    #[inline]
    pub fn surface_illuminance_lux(&self, p: Vec3, n: Vec3) -> (Vec3, Vec3, f32) {
        let to = self.position_m - p;
        let r = to.length().max(1e-2);
        let l = to / r;
        let cos = n.dot(l);
        if cos <= 0.0 {
            return (Vec3::ZERO, l, r);
        }
        (self.illuminance_lux(p) * cos, l, r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_square_and_cone() {
        let p = Light::from_row(
            &[
                0.0, 5.0, 0.0, 1.0, 1.0, 1.0, 1000.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            ],
            0,
        )
        .unwrap();
        assert!((p.illuminance_lux(Vec3::new(0.0, 3.0, 0.0)).x - 250.0).abs() < 1e-3);
        assert!((p.illuminance_lux(Vec3::new(0.0, 1.0, 0.0)).x - 62.5).abs() < 1e-3);
        let cos30 = 30f32.to_radians().cos();
        let cos20 = 20f32.to_radians().cos();
        let s = Light::from_row(
            &[
                0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 100.0, 0.0, 0.0, -1.0, cos30, cos20,
            ],
            0,
        )
        .unwrap();
        assert!((s.illuminance_lux(Vec3::new(0.0, 0.0, -2.0)).x - 25.0).abs() < 1e-3);
        assert_eq!(s.illuminance_lux(Vec3::new(0.0, 0.0, 2.0)).x, 0.0);
        assert_eq!(s.illuminance_lux(Vec3::new(2.0, 0.0, -1.0)).x, 0.0);
        assert!(Light::from_row(&[0.0; 11], 0).is_err());
        assert!(
            Light::from_row(
                &[
                    0.0,
                    0.0,
                    f32::NAN,
                    1.0,
                    1.0,
                    1.0,
                    1.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0
                ],
                0
            )
            .is_err()
        );
    }
}
