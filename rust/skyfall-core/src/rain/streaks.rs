//! Rain drawn as streaks: the drops of a frame lit, culled, projected and sorted, then handed
//! to the particle compositor.
//!
//! Brightness (Yamamoto & Tadamura, rainy scenes reflecting ambient light intensity, eq. 7):
//! a drop shows I_v = r·I_R + (1 − r)·I_T, I_T the background behind it,
//! I_R = k·E_R the light it receives: the sky's horizontal illuminance at the drop (relative
//! 1.0 in the open; read from the ambient-light map when there is one, so drops under a roof
//! are dimmer) plus, per point or spot light, k·I·cone/d² (inverse square; E in lux over the
//! sky's E). Compositing a = α·coverage of it over C gives C + a·r·(I_R − C); streaks are
//! composited far to near. Drops whose I_R is below an optional cull threshold are not drawn.
//! The `rain_alpha` layer is 1 − ∏(1 − aᵢ), the streaks' coverage; `rain_depth_m` is the
//! nearest visible streak's depth (inf: none). Streak fragments deeper than the scene at that
//! pixel are hidden.

use super::drops::Drop;
use crate::error::Result;
#[cfg(test)]
use crate::particles::composite::{RainTargets, composite_streaks};
use crate::particles::order::far_to_near;
use crate::particles::streak::{ScreenStreak, screen_streak_through};
use crate::scene::camera::{Camera, Defocus};
use crate::scene::lights::Light;
use crate::sky::ambient::AmbientMap;
use glam::Vec3;
use std::sync::Arc;

/// How streaks are lit: I_v = r·I_R + (1 − r)·I_T.
#[derive(Debug, Clone, PartialEq)]
pub struct RainShading {
    /// r, the share of the drop's own light, in [0, 1].
    pub reflectance: f32,
    /// I_R from the sky (relative units, E/π = 1).
    pub drop_radiance: f32,
    /// Point and spot lights.
    pub lights: Vec<Light>,
    /// The sky's horizontal illuminance E, lux: a light's illuminance E_L adds
    /// drop_radiance · E_L / E to I_R.
    pub sky_illuminance_lux: f32,
    /// Drops whose I_R (brightest channel) is below this are not drawn; None draws all.
    pub cull_threshold: Option<f32>,
    /// Sky illuminance relative to E per position (its "up" channel); None: the open sky, 1.
    pub ambient: Option<Arc<AmbientMap>>,
    /// The frame's units per relative unit, per channel (a photo's airlight over the sky's,
    /// [`crate::frame::FrameSetup`]): multiplies the drops' light after culling, which
    /// compares relative I_R. 1 for rendered scenes.
    pub radiance_scale: Vec3,
    /// The colour (of luminance 1) of the sky's light on the drops: the sky light's
    /// ([`crate::sky::Sky::light_colour`], blue under a clear sky) for a rendered scene, white
    /// for a photo (whose `radiance_scale` carries its own colour) and under grey skies.
    pub sky_colour: Vec3,
}

impl RainShading {
    /// Yamamoto & Tadamura's constant r (0.5 here), an open-sky drop light I_R = E/π (relative 1.0), no
    /// lights, no culling. The ambient-light map will lower I_R where drops see less sky.
    pub fn open_sky() -> Self {
        RainShading {
            reflectance: 0.5,
            drop_radiance: 1.0,
            lights: Vec::new(),
            sky_illuminance_lux: 10_000.0,
            cull_threshold: None,
            ambient: None,
            radiance_scale: Vec3::ONE,
            sky_colour: Vec3::ONE,
        }
    }

    /// I_R of a drop at `p`, per channel: the sky's share in the sky light's colour, the
    /// lamps' in their own.
    pub fn drop_light(&self, p: Vec3) -> Vec3 {
        let lit = self
            .lights
            .iter()
            .fold(Vec3::ZERO, |acc, l| acc + l.illuminance_lux(p));
        let sky = self.ambient.as_ref().map_or(1.0, |m| m.sample(p)[0]);
        self.sky_colour * (self.drop_radiance * sky)
            + lit * (self.drop_radiance / self.sky_illuminance_lux)
    }
}

/// What the rain pass did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RainStats {
    /// Streaks drawn (on screen, not culled).
    pub streaks: usize,
    /// Drops on screen skipped by the cull threshold.
    pub culled: usize,
}

/// Projects, lights and culls the drops (positioned relative to `cam`), sorted far to near (stable: ties keep the drops'
/// deterministic order). The GPU backend draws the same list.
pub fn prepare(
    cam: &Camera,
    lens: Option<&Defocus>,
    drops: &[Drop],
    exposure_s: f32,
    camera_velocity_m_s: Vec3,
    shading: &RainShading,
) -> Result<(Vec<ScreenStreak>, RainStats)> {
    // Lights and the ambient map are in the world; the drops relative to the camera.
    let eye = cam.eye();
    // Projected and lit in parallel, in the drops' order, into a list grown fallibly.
    let mut streaks: Vec<ScreenStreak> =
        crate::error::try_par_filter_map("the particles' streaks", drops, 1024, |d| {
            screen_streak_through(cam, lens, d, exposure_s, camera_velocity_m_s).map(|mut s| {
                s.light = shading.drop_light(eye + d.position_m);
                s.reflectance = shading.reflectance;
                s
            })
        })?;
    let mut stats = RainStats::default();
    if let Some(th) = shading.cull_threshold {
        let before = streaks.len();
        streaks.retain(|s| s.light.max_element() >= th);
        stats.culled = before - streaks.len();
    }
    if shading.radiance_scale != Vec3::ONE {
        for s in &mut streaks {
            s.light *= shading.radiance_scale;
        }
    }
    // Far to near, ties in the drops' order.
    far_to_near(&mut streaks)?;
    stats.streaks = streaks.len();
    Ok((streaks, stats))
}

/// The rain a frame draws.
#[derive(Debug, Clone, Copy)]
pub struct RainFrame<'a> {
    /// Which drops.
    pub region: &'a super::drops::RainRegion,
    /// The camera's exposure, s.
    pub exposure_s: f32,
    /// The camera's velocity, m/s: streaks follow the drops' motion relative to it.
    pub camera_velocity_m_s: Vec3,
    /// The camera's thin lens at the frame's resolution; None: a pinhole.
    pub lens: Option<Defocus>,
    /// Whether the ground bounds the rain.
    pub ground: bool,
    /// Boxes that shelter the rain (see [`super::shelter`]); empty: none.
    pub shelter: &'a [crate::scene::boxes::SceneBox],
    /// How drops are lit and culled.
    pub shading: &'a RainShading,
}

impl RainFrame<'_> {
    /// The frame's streaks (see [`prepare`]), its stats, and how many drops there were (those
    /// of the voxels that can reach the view, less the sheltered ones, and less those beyond
    /// the region's `far_m` when it has one).
    pub fn streaks(&self, cam: &Camera) -> Result<(Vec<ScreenStreak>, RainStats, usize)> {
        self.region
            .check_budget(cam.view_solid_angle_sr() / (4.0 * std::f64::consts::PI))?;
        let (t, v) = (
            f64::from(self.exposure_s),
            f64::from(self.camera_velocity_m_s.length()),
        );
        let mut drops = match (self.region.far_m, self.region.method) {
            // With the far level of detail the drops within far_m are drawn one by one,
            // whatever the method: the billboards balance whole voxels' opacity, and cut at
            // far_m they came out 7 % over the reference (benches/results/rain.md, 2026-12-02).
            // Voxels wholly beyond far_m horizontally make no drops.
            (Some(far), _) => {
                let reach = far + std::f64::consts::FRAC_1_SQRT_2;
                let mut d =
                    super::drops::drops_in_view_where(self.region, cam, t, v, self.ground, |c| {
                        f64::from(c.x).hypot(f64::from(c.z)) < reach
                    })?;
                // The far level of detail draws the rest ([`Self::far`]).
                let far2 = (far * far) as f32;
                d.retain(|d| {
                    d.position_m.x * d.position_m.x + d.position_m.z * d.position_m.z < far2
                });
                d
            }
            (None, super::drops::RainMethod::Drops) => {
                super::drops::drops_in_view(self.region, cam, t, v, self.ground)?
            }
            (None, super::drops::RainMethod::Billboards) => super::billboards::billboards_in_view(
                self.region,
                cam,
                t,
                self.camera_velocity_m_s,
                self.lens.as_ref(),
                self.ground,
            )?,
        };
        super::shelter::remove_sheltered(
            &mut drops,
            self.shelter,
            cam.eye(),
            self.region.near_m as f32,
        );
        let (streaks, stats) = prepare(
            cam,
            self.lens.as_ref(),
            &drops,
            self.exposure_s,
            self.camera_velocity_m_s,
            self.shading,
        )?;
        Ok((streaks, stats, drops.len()))
    }

    /// The far level of detail's layers for `cam` (see [`super::far`]), when the region has a
    /// `far_m`.
    pub fn far(&self, cam: &Camera) -> Result<Option<super::far::FarRain>> {
        super::far::FarRain::prepare(
            cam,
            &super::far::FarRequest {
                region: self.region,
                exposure_s: self.exposure_s,
                camera_velocity_m_s: self.camera_velocity_m_s,
                lens: self.lens.is_some(),
                shelter: self.shelter,
                shading: self.shading,
            },
        )
    }
}

/// Composites the drops' streaks over the frame, far to near, for a camera at rest (the tests'
/// whole-frame reference).
#[cfg(test)]
pub fn composite(
    cam: &Camera,
    drops: &[Drop],
    exposure_s: f32,
    shading: &RainShading,
    t: RainTargets<'_>,
) -> Result<RainStats> {
    let (streaks, stats) = prepare(cam, None, drops, exposure_s, Vec3::ZERO, shading).unwrap();
    composite_streaks(cam, &streaks, t)?;
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::streak::screen_streak;
    use glam::Vec2;
    use glam::{Mat3, Vec3};

    #[test]
    fn composite_matches_a_per_pixel_reference() {
        // Random streaks (near, far, thin, wide, slanted, crossing band and frame edges) over a
        // random frame and depth, against the definition: every pixel, every streak in order,
        // ScreenStreak::fragment.
        use rand::{Rng, SeedableRng};
        let (w, h) = (300usize, 45usize); // three column tiles, the last narrow
        let cam = Camera::new(
            w as u32,
            h as u32,
            [40.0, 40.0, 150.0, 22.5],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let drops: Vec<Drop> = (0..600)
            .map(|k| {
                let z: f32 = rng.random_range(0.2..6.0);
                let p = Vec3::new(
                    rng.random_range(-4.0..4.0) * z,
                    rng.random_range(-0.8..0.8) * z,
                    -z,
                );
                let v = Vec3::new(
                    rng.random_range(-4.0..4.0),
                    rng.random_range(-9.0..1.0),
                    rng.random_range(-3.0..3.0),
                );
                Drop {
                    position_m: p,
                    velocity_m_s: v,
                    diameter_m: rng.random_range(0.5e-3..5e-3),
                    id: [k, 0, 0, 0, 0],
                }
            })
            .collect();
        let mut shading = RainShading::open_sky();
        shading.drop_radiance = 1.3;
        let (mut streaks, _) =
            prepare(&cam, None, &drops, 1.0 / 30.0, Vec3::ZERO, &shading).unwrap();
        // Each particle carries its own r (particles of several effects share one list).
        assert!(streaks.iter().all(|s| s.reflectance == shading.reflectance));
        for s in &mut streaks {
            s.reflectance = rng.random_range(0.1..1.0);
        }
        assert!(streaks.len() > 300);
        let n = w * h;
        let background: Vec<f32> = (0..3 * n).map(|_| rng.random()).collect();
        let depth: Vec<f32> = (0..n)
            .map(|_| {
                if rng.random_bool(0.3) {
                    f32::INFINITY
                } else {
                    rng.random_range(0.3..5.0)
                }
            })
            .collect();
        let (mut rgb, mut alpha, mut rd) = (background.clone(), vec![0.0; n], vec![0.0; n]);
        composite_streaks(
            &cam,
            &streaks,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &depth,
                alpha: &mut alpha,
                rain_depth_m: &mut rd,
            },
        )
        .unwrap();
        for i in 0..n {
            let p = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let (mut c, mut keep, mut near) = (
                [
                    background[3 * i],
                    background[3 * i + 1],
                    background[3 * i + 2],
                ],
                1.0f32,
                f32::INFINITY,
            );
            for s in &streaks {
                let Some((a, z)) = s.fragment(p) else {
                    continue;
                };
                if z >= depth[i] {
                    continue;
                }
                for (c, l) in c.iter_mut().zip(s.light.to_array()) {
                    *c += a * s.reflectance * (l - *c);
                }
                keep *= 1.0 - a;
                near = near.min(z);
            }
            for ch in 0..3 {
                assert!(
                    (rgb[3 * i + ch] - c[ch]).abs() < 2e-4,
                    "pixel {i}: {} vs {}",
                    rgb[3 * i + ch],
                    c[ch]
                );
            }
            assert!(
                (alpha[i] - (1.0 - keep)).abs() < 2e-4,
                "pixel {i}: {} vs {}",
                alpha[i],
                1.0 - keep
            );
            assert!(
                rd[i] == near || (rd[i] - near).abs() < 1e-3 * near,
                "pixel {i}: {} vs {near}",
                rd[i]
            );
        }
        let rained = alpha.iter().filter(|&&a| a > 1e-3).count();
        assert!(rained > n / 20, "{rained}");
    }

    #[test]
    fn one_streak_carries_its_opacity_area() {
        let cam = Camera::new(
            400,
            400,
            [300.0, 300.0, 200.0, 200.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        // a 2 mm drop 1 m ahead falling 6.5 m/s for 1/30 s: w = 0.6 px, L = 65 px.
        let d = Drop {
            position_m: Vec3::new(0.0, -0.1, -1.0),
            velocity_m_s: Vec3::new(0.0, -6.5, 0.0),
            diameter_m: 2e-3,
            id: [0; 5],
        };
        let n = 400 * 400;
        let mut rgb = vec![0.0; 3 * n];
        let mut alpha = vec![0.0; n];
        let mut rd = vec![0.0; n];
        let depth = vec![f32::INFINITY; n];
        let white = RainShading {
            reflectance: 1.0,
            ..RainShading::open_sky()
        };
        let shown = composite(
            &cam,
            &[d],
            1.0 / 30.0,
            &white,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &depth,
                alpha: &mut alpha,
                rain_depth_m: &mut rd,
            },
        )
        .unwrap();
        assert_eq!(
            shown,
            RainStats {
                streaks: 1,
                culled: 0
            }
        );
        let w = 2e-3 * 300.0;
        // The drop's cross-section on screen, π w²/4 px² (a sphere of diameter D: π D²/4).
        let disc = |w: f32| std::f32::consts::PI / 4.0 * w * w;
        let sum: f32 = alpha.iter().sum();
        // α w L = π w²/4 (plus round caps of the capsule): within 5 %.
        assert!((sum / disc(w) - 1.0).abs() < 0.05, "{sum} vs {}", disc(w));
        // with r = 1 and I_R = 1 on black, rgb equals the coverage
        assert!((rgb.iter().step_by(3).sum::<f32>() - sum).abs() < 1e-3);
        let nearest = rd.iter().cloned().fold(f32::INFINITY, f32::min);
        assert!((nearest - 1.0).abs() < 0.01);
        // behind a wall at 0.5 m nothing shows
        let wall = vec![0.5f32; n];
        let mut alpha2 = vec![0.0; n];
        composite(
            &cam,
            &[d],
            1.0 / 30.0,
            &white,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &wall,
                alpha: &mut alpha2,
                rain_depth_m: &mut rd,
            },
        )
        .unwrap();
        assert!(alpha2.iter().all(|&a| a == 0.0));
        // culled when its light is below the threshold
        let culling = RainShading {
            cull_threshold: Some(1.5),
            ..white.clone()
        };
        let stats = composite(
            &cam,
            &[d],
            1.0 / 30.0,
            &culling,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &depth,
                alpha: &mut alpha2,
                rain_depth_m: &mut rd,
            },
        )
        .unwrap();
        assert_eq!(
            stats,
            RainStats {
                streaks: 0,
                culled: 1
            }
        );
        // a camera moving with the drop sees a dot (the drop's image), not a streak: a pixel
        // long, at α = π w/4 · sec θ, so that it carries π w²/4 · sec θ (0.1 m below the axis
        // 1 m ahead: its image is stretched by sec θ = √1.01 along the vertical, its path)
        let sec = 1.01f32.sqrt();
        let s = screen_streak(&cam, &d, 1.0 / 30.0, d.velocity_m_s).unwrap();
        assert!(
            (s.len - 1.0).abs() < 1e-6
                && (s.alpha - std::f32::consts::FRAC_PI_4 * w * sec).abs() < 1e-6,
            "{} {}",
            s.len,
            s.alpha
        );
        assert!((s.opacity_area_in(400.0, 400.0) / (disc(w) * sec) - 1.0).abs() < 1e-4);
        // whatever the exposure, the pixels sum to π w²/4 (a still drop: a dot; a near drop in a
        // short exposure: lengthened; 1/30 s: a streak)
        for (v, z, t) in [
            (0.0, 1.0, 1.0 / 30.0),
            (0.0, 0.1, 1.0 / 30.0),
            (6.5, 0.3, 1e-4),
            (6.5, 1.0, 1e-3),
            (6.5, 1.0, 3e-3),
            (6.5, 5.0, 1e-4),
        ] {
            let d = Drop {
                position_m: Vec3::new(0.05, 0.0, -z),
                velocity_m_s: Vec3::new(0.0, -v, 0.0),
                ..d
            };
            let w = 2e-3 * 300.0 / z;
            // (0.05 m off the axis: its image's area is the disc's times sec θ)
            let sec = (1.0 + (0.05 / z) * (0.05 / z)).sqrt();
            let mut alpha = vec![0.0; n];
            composite(
                &cam,
                &[d],
                t,
                &white,
                RainTargets {
                    rgb: &mut rgb,
                    depth_m: &depth,
                    alpha: &mut alpha,
                    rain_depth_m: &mut rd,
                },
            )
            .unwrap();
            let sum: f32 = alpha.iter().sum();
            assert!(
                (sum / (disc(w) * sec) - 1.0).abs() < 0.02,
                "v {v} z {z} T {t}: {sum} vs {}",
                disc(w) * sec
            );
        }
        // a camera moving up at 6.5 m/s doubles the streak
        let still = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::ZERO).unwrap();
        let up = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::new(0.0, 6.5, 0.0)).unwrap();
        assert!((up.a.distance(up.b) / still.a.distance(still.b) - 2.0).abs() < 1e-3);
    }
}
