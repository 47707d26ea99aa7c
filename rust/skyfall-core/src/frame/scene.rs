//! The scene stage of the box scene: each pixel's ray cast against the boxes and the ground,
//! its surface lit by the ambient-light map (the sky light it sees), sky pixels the sky itself.

use crate::scene::boxes::{BoxScene, surface_albedo, trace};
use crate::scene::camera::Camera;
use crate::sky::Sky;
use crate::sky::ambient::AmbientMap;
use glam::Vec3;

/// How a frame's scene is lit: the sky seen by sky pixels and the map surfaces read.
#[derive(Debug, Clone, Copy)]
pub struct SceneLight<'a> {
    /// The sky.
    pub sky: &'a Sky,
    /// Illuminance relative to E on the five normals.
    pub ambient: &'a AmbientMap,
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
    use crate::scene::boxes::{SceneBox, WINDOW_ALBEDO_FACTOR};
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
