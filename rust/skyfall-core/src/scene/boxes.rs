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

use super::camera::Camera;
use super::raycast::{inverse_direction, slabs};
use crate::error::{Error, Param, Range, Result};
use crate::sky::Sky;
use crate::sky::ambient::AmbientMap;
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

/// How a frame's scene is lit: the sky seen by sky pixels and the map surfaces read.
#[derive(Debug, Clone, Copy)]
pub struct SceneLight<'a> {
    /// The sky.
    pub sky: &'a Sky,
    /// Illuminance relative to E on the five normals.
    pub ambient: &'a AmbientMap,
}

#[inline]
fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// Albedo at a hit point, with the window pattern on walls.
#[inline]
fn surface_albedo(albedo: Vec3, normal: Vec3, p: Vec3) -> Vec3 {
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

/// Radiance (relative) and depth (m along the optical axis, inf for sky) of one pixel.
#[inline]
pub fn shade_pixel(
    scene: &BoxScene,
    cam: &Camera,
    light: &SceneLight<'_>,
    x: u32,
    y: u32,
) -> (Vec3, f32) {
    let dir = cam.ray_direction(x, y);
    match trace(scene, cam.eye(), dir) {
        Some((t, n, albedo)) => {
            let p = cam.eye() + dir * t;
            let a = surface_albedo(albedo, n, p);
            let e = AmbientMap::channel(n).map_or(0.0, |c| light.ambient.sample(p)[c]);
            (a * e, t)
        }
        None => (
            Vec3::splat(light.sky.sky_pixel(dir.normalize())),
            f32::INFINITY,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::cie::SkyKind;
    use crate::sky::illuminance::{SkyTable, irradiance};
    use glam::Mat3;

    /// The overcast sky and its open-sky light (no occluders).
    fn open() -> (Sky, AmbientMap) {
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let e = irradiance(&[], &SkyTable::new(&sky, 256).unwrap(), Vec3::ZERO);
        (sky, AmbientMap::uniform(e))
    }

    fn cam() -> Camera {
        Camera::new(
            64,
            48,
            [40.0, 40.0, 32.0, 24.0],
            Vec3::new(0.0, 1.5, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap_or(Camera {
            width: 1,
            height: 1,
            fx: 1.0,
            fy: 1.0,
            cx: 0.0,
            cy: 0.0,
            position_m: glam::DVec3::ZERO,
            rotation: Mat3::IDENTITY,
        })
    }

    #[test]
    fn overcast_sky_integrates_to_its_illuminance() {
        // ∫ L cos θ dω over the hemisphere = E, i.e. ∫ (L/(E/π)) cos θ dω = π.
        let (sky, _) = open();
        let n = 2000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let el = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
            let l = sky.emitted(Vec3::new(0.0, el.sin() as f32, el.cos() as f32));
            sum += l
                * el.sin()
                * el.cos()
                * (std::f64::consts::FRAC_PI_2 / n as f64)
                * 2.0
                * std::f64::consts::PI;
        }
        assert!((sum / std::f64::consts::PI - 1.0).abs() < 1e-4, "{sum}");
    }

    #[test]
    fn ground_depth_is_analytic() {
        let scene = BoxScene::new(vec![], true, Vec3::splat(0.2)).unwrap_or(BoxScene {
            boxes: vec![],
            ground: true,
            ground_albedo: Vec3::ONE,
        });
        let c = cam();
        let (sky, amb) = open();
        let light = SceneLight {
            sky: &sky,
            ambient: &amb,
        };
        // bottom row centre: ray dir y = -(47.5 - 24)/40, so t = 1.5 / ((47.5 - 24) / 40)
        let (rad, t) = shade_pixel(&scene, &c, &light, 32, 47);
        assert!((t - 1.5 * 40.0 / 23.5).abs() < 1e-4, "{t}");
        assert!((rad - Vec3::splat(0.2)).length() < 1e-5);
        let (_, t_sky) = shade_pixel(&scene, &c, &light, 32, 0);
        assert!(t_sky.is_infinite());
    }

    #[test]
    fn a_wall_ahead_is_hit_at_its_distance_with_windows() {
        let wall = SceneBox {
            min_m: Vec3::new(-5.0, 0.0, -10.0),
            max_m: Vec3::new(5.0, 3.0, -9.0),
            albedo: Vec3::splat(0.5),
        };
        let scene = BoxScene::new(vec![wall], false, Vec3::ZERO).unwrap_or(BoxScene {
            boxes: vec![],
            ground: false,
            ground_albedo: Vec3::ZERO,
        });
        let c = cam();
        let (sky, amb) = open();
        let light = SceneLight {
            sky: &sky,
            ambient: &amb,
        };
        let wall_e = amb.sample(Vec3::ZERO)[3];
        assert!(
            (f64::from(wall_e) - (3.0 / 14.0 + 4.0 / (7.0 * std::f64::consts::PI))).abs() < 2e-3
        );
        // Row 23 looks 0.5/40 up: the front face z = -9 at depth 9, p.y = 1.61, p.x = 0.1125 (a wall facing +Z, lit by the open sky's vertical illuminance).
        let (rad, t) = shade_pixel(&scene, &c, &light, 32, 23);
        assert!((t - 9.0).abs() < 1e-4, "{t}");
        assert!((rad - Vec3::splat(0.5 * wall_e)).length() < 1e-6, "{rad}");
        // Column 38: p.x = 1.4625, inside a pane.
        let (pane, _) = shade_pixel(&scene, &c, &light, 38, 23);
        assert!(
            (pane - Vec3::splat(0.5 * WINDOW_ALBEDO_FACTOR * wall_e)).length() < 1e-6,
            "{pane}"
        );
        assert!(
            BoxScene::new(
                vec![SceneBox {
                    min_m: Vec3::ONE,
                    max_m: Vec3::ZERO,
                    albedo: Vec3::ZERO
                }],
                true,
                Vec3::ZERO
            )
            .is_err()
        );
    }
}
