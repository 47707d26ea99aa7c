//! The procedural scene: a ground plane and axis-aligned boxes under the frame's sky,
//! ray cast per pixel. This file is the CPU reference of `skyfall-gpu`'s `scene_raycast.wgsl`,
//! kept line-for-line comparable.
//!
//! Radiance is relative: 1.0 is the luminance of a white Lambertian surface lit by the whole
//! unobstructed sky, E/π for horizontal sky illuminance E. Multiply by E/π to get cd/m².
//!
//! - Sky: the frame's [`Sky`] seen along the ray (the CIE standard overcast sky by default,
//!   L(γ)/(E/π) = (9/7)(1 + 2 sin γ)/3: horizon 3/7, zenith 9/7).
//! - Surfaces: Lambertian, lit by the sky they see: radiance = albedo · E_n/E with E_n the
//!   illuminance on the face's normal read from the ambient-light map (occlusion by the other
//!   boxes included; 1 for open ground, 0.396 for an open wall under the overcast sky, 0 for
//!   faces looking down).
//! - Windows: on walls, a 3 m × 3 m grid of dark panes (1.5 m wide, 1.5 m tall, from 1 m up)
//!   reflecting [`WINDOW_ALBEDO_FACTOR`] of the wall albedo.

use super::raycast::{inverse_direction, slabs};
use crate::error::{Error, Param, Range, Result};
use glam::Vec3;

/// Pane albedo relative to the wall's.
pub const WINDOW_ALBEDO_FACTOR: f32 = 0.2;
pub use super::raycast::T_MIN;
/// Largest number of boxes in a scene.
pub const MAX_BOXES: usize = 4096;

/// One axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneBox {
    /// Minimum corner, m.
    pub min_m: Vec3,
    /// Maximum corner, m.
    pub max_m: Vec3,
    /// Linear RGB albedo in [0, 1].
    pub albedo: Vec3,
}

/// Ground plus boxes.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxScene {
    /// The boxes.
    pub boxes: Vec<SceneBox>,
    /// Whether the ground plane y = 0 exists.
    pub ground: bool,
    /// Ground albedo, linear RGB.
    pub ground_albedo: Vec3,
}

impl BoxScene {
    /// Validated scene: finite corners with min < max, albedos in [0, 1], at most [`MAX_BOXES`].
    pub fn new(boxes: Vec<SceneBox>, ground: bool, ground_albedo: Vec3) -> Result<Self> {
        if boxes.len() > MAX_BOXES {
            return Err(Error::Invalid {
                param: Param {
                    name: "boxes",
                    index: None,
                },
                message: format!("{} boxes, at most {MAX_BOXES} are supported", boxes.len()),
            });
        }
        let coord = Range::closed(-1e6, 1e6, "m");
        let unit = Range::closed(0.0, 1.0, "");
        for (i, b) in boxes.iter().enumerate() {
            for k in 0..3 {
                coord.check("boxes.min", Some(i), f64::from(b.min_m[k]))?;
                coord.check("boxes.max", Some(i), f64::from(b.max_m[k]))?;
                unit.check("boxes.albedo", Some(i), f64::from(b.albedo[k]))?;
                if b.max_m[k] <= b.min_m[k] {
                    return Err(Error::Invalid {
                        param: Param {
                            name: "boxes",
                            index: Some(i),
                        },
                        message: format!(
                            "max must exceed min on every axis, got min {} max {}",
                            b.min_m, b.max_m
                        ),
                    });
                }
            }
        }
        for k in 0..3 {
            unit.check("ground_albedo", Some(k), f64::from(ground_albedo[k]))?;
        }
        Ok(BoxScene {
            boxes,
            ground,
            ground_albedo,
        })
    }
}

#[inline]
fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// Albedo at a hit point, with the window pattern on walls.
#[inline]
pub fn surface_albedo(albedo: Vec3, normal: Vec3, p: Vec3) -> Vec3 {
    if normal.y.abs() < 0.5 {
        let u = if normal.x.abs() > 0.5 { p.z } else { p.x };
        let fu = fract(u / 3.0);
        let fv = fract((p.y - 1.0) / 3.0);
        if p.y > 1.0 && fu > 0.25 && fu < 0.75 && fv < 0.5 {
            return albedo * WINDOW_ALBEDO_FACTOR;
        }
    }
    albedo
}

/// Nearest hit along `origin + t dir`, t > [`T_MIN`]: (t, normal, albedo), or None for sky.
pub fn trace(scene: &BoxScene, origin: Vec3, dir: Vec3) -> Option<(f32, Vec3, Vec3)> {
    let mut best_t = f32::INFINITY;
    let mut best_n = Vec3::ZERO;
    let mut best_a = Vec3::ZERO;
    if scene.ground && dir.y < 0.0 && origin.y > 0.0 {
        best_t = -origin.y / dir.y;
        best_n = Vec3::Y;
        best_a = scene.ground_albedo;
    }
    let inv = inverse_direction(dir);
    for b in &scene.boxes {
        let (lo, hi) = slabs(b, origin, inv);
        let t_near = lo.x.max(lo.y).max(lo.z);
        let t_far = hi.x.min(hi.y).min(hi.z);
        if t_near > T_MIN && t_near <= t_far && t_near < best_t {
            best_t = t_near;
            best_n = if t_near == lo.x {
                Vec3::new(-dir.x.signum(), 0.0, 0.0)
            } else if t_near == lo.y {
                Vec3::new(0.0, -dir.y.signum(), 0.0)
            } else {
                Vec3::new(0.0, 0.0, -dir.z.signum())
            };
            best_a = b.albedo;
        }
    }
    if best_t.is_finite() {
        Some((best_t, best_n, best_a))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_box_is_hit_and_windows_pattern_walls() {
        let b = SceneBox {
            min_m: Vec3::new(-1.0, 0.0, -6.0),
            max_m: Vec3::new(1.0, 3.0, -5.0),
            albedo: Vec3::splat(0.5),
        };
        let far = SceneBox {
            min_m: Vec3::new(-1.0, 0.0, -9.0),
            max_m: Vec3::new(1.0, 3.0, -8.0),
            albedo: Vec3::splat(0.9),
        };
        let scene = BoxScene::new(vec![far, b], false, Vec3::ZERO).unwrap();
        let (t, n, a) = trace(&scene, Vec3::new(0.0, 1.5, 0.0), Vec3::new(0.0, 0.0, -1.0)).unwrap();
        assert!((t - 5.0).abs() < 1e-6 && n == Vec3::Z && a == Vec3::splat(0.5));
        assert!(trace(&scene, Vec3::new(0.0, 1.5, 0.0), Vec3::new(0.0, 0.0, 1.0)).is_none());
        // a pane (u, v in the window's half of a 3 m cell) against the wall beside it
        assert_eq!(
            surface_albedo(Vec3::ONE, Vec3::Z, Vec3::new(1.5, 1.5, 0.0)),
            Vec3::splat(WINDOW_ALBEDO_FACTOR)
        );
        assert_eq!(
            surface_albedo(Vec3::ONE, Vec3::Z, Vec3::new(0.1, 1.5, 0.0)),
            Vec3::ONE
        );
        assert_eq!(
            surface_albedo(Vec3::ONE, Vec3::Y, Vec3::new(1.5, 1.5, 0.0)),
            Vec3::ONE
        );
    }
}
