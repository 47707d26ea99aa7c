//! Snowfall drawn through the particle toolkit: a frame's flakes lit, faded with distance,
//! given their sprites, projected into streaks (their exposure-long paths, motion-blurred as the
//! drops' are) for the one far-to-near list of [`crate::frame::passes::Particles`].
//!
//! - **Light**: a flake is an opaque white scatterer (r = 1: where it covers a pixel it
//!   replaces the background) of albedo [`crate::snow::SNOW_ALBEDO`], lit as the drops are
//!   ([`RainShading::drop_light`]: the sky's light at the flake from the ambient-light map,
//!   plus the lamps' I·cone/d²), so its radiance is ρ·I_R.
//! - **Silhouette**: a streak carries (π/4)·w² of opacity-area, a disc's; a flake's projected
//!   area is Mitchell's A(S), so α is scaled by A / (π S²/4) (about 0.3: aggregates are lacy).
//! - **Sprite**: seeded per flake ([`crate::snow::flakes::sprite_key`]): a lump, a six-armed
//!   star at a random angle, or a broad aggregate ([`crate::particles::streak::Sprite`]).
//! - **Opacity with distance** ([`SnowOpacity`]): by default continuous, α·e^(−τ(d)) with τ the
//!   haze's optical depth to the flake (air, rain and the snow's own σ_snow, less what the frame
//!   draws as particles near the eye, [`crate::haze::Drawn`]: a flake fades into the haze
//!   exactly as a surface at its distance does); or Koitabashi et al.'s three levels,
//!   0.75 / 0.5 / 0.25 of α in the near, middle and far thirds of the snow region.

use super::flakes::{Flake, SnowRegion, flakes_in_view, sprite_key};
use crate::error::{Error, Param, Result};
use crate::particles::streak::{
    LAYER_SNOW, SPRITE_AGGREGATE, SPRITE_LUMP, SPRITE_STAR, ScreenStreak, Sprite,
    screen_streak_through,
};
use crate::physics::snow::flake_area_mm2;
use crate::rain::streaks::RainShading;
use crate::scene::camera::{Camera, Defocus};
use glam::Vec3;
use rayon::prelude::*;

/// Koitabashi et al.'s flake opacities, near to far, by thirds of the snow region.
pub const OPACITY_LEVELS: [f32; 3] = [0.75, 0.5, 0.25];

/// How a flake's opacity falls with its distance d.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SnowOpacity {
    /// e^(−σ d), σ the frame's extinction (the default).
    Extinction,
    /// Koitabashi et al.'s three levels ([`OPACITY_LEVELS`]).
    Levels,
}

impl SnowOpacity {
    /// Parses `"extinction"` or `"levels"`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "extinction" => Ok(Self::Extinction),
            "levels" => Ok(Self::Levels),
            other => Err(Error::Invalid {
                param: Param {
                    name: "snow_opacity",
                    index: None,
                },
                message: format!(
                    "unknown snow opacity {other:?}; expected \"extinction\" or \"levels\""
                ),
            }),
        }
    }
}

/// What the snow pass did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SnowStats {
    /// Flakes generated (in the voxels that can reach the view, less the sheltered ones).
    pub flakes: usize,
    /// Streaks drawn (on screen, not culled).
    pub streaks: usize,
}

/// The snow a frame draws.
#[derive(Debug, Clone, Copy)]
pub struct SnowFrame<'a> {
    /// Which flakes.
    pub region: &'a SnowRegion,
    /// The camera's exposure, s.
    pub exposure_s: f32,
    /// The camera's velocity, m/s.
    pub camera_velocity_m_s: Vec3,
    /// The camera's thin lens at the frame's resolution; None: a pinhole.
    pub lens: Option<Defocus>,
    /// Whether the ground bounds the snow.
    pub ground: bool,
    /// Boxes that shelter the flakes; empty: none.
    pub shelter: &'a [crate::scene::boxes::SceneBox],
    /// How flakes are lit (the drops' shading: lights, ambient map, culling, units).
    pub shading: &'a RainShading,
    /// How their opacity falls with distance.
    pub opacity: SnowOpacity,
    /// The frame's haze (its optical depth to each flake fades it), None in clear air.
    pub haze: Option<crate::haze::Haze>,
}

/// A flake's sprite, from its identity.
pub fn flake_sprite(seed: u64, f: &Flake) -> Sprite {
    let key = sprite_key(seed, &f.id);
    let kind = [SPRITE_LUMP, SPRITE_STAR, SPRITE_AGGREGATE][(key % 3) as usize];
    let turn = ((key >> 40) as f32) / (1u64 << 24) as f32;
    Sprite::new(kind, turn)
}

/// A flake's opacity factor: its share of the disc's silhouette (Mitchell's area over π S²/4)
/// times its fading at distance `d_m` in a region of radius `near_m`, `tau` the haze's optical
/// depth to it.
pub fn flake_opacity(size_mm: f32, d_m: f32, near_m: f32, opacity: SnowOpacity, tau: f32) -> f32 {
    let s = f64::from(size_mm);
    let fill = (flake_area_mm2(s) / (std::f64::consts::FRAC_PI_4 * s * s)) as f32;
    let fade = match opacity {
        SnowOpacity::Extinction => (-tau).exp(),
        SnowOpacity::Levels => {
            let third = near_m / 3.0;
            if d_m < third {
                OPACITY_LEVELS[0]
            } else if d_m < 2.0 * third {
                OPACITY_LEVELS[1]
            } else {
                OPACITY_LEVELS[2]
            }
        }
    };
    fill.min(1.0) * fade
}

/// Projects, lights, fades and culls the flakes (positioned relative to `cam`), in the flakes'
/// order (not sorted: the frame sorts every effect's particles together).
pub fn prepare(cam: &Camera, frame: &SnowFrame<'_>, flakes: &[Flake]) -> Result<Vec<ScreenStreak>> {
    let eye = cam.eye();
    let shading = frame.shading;
    let near = frame.region.near_m as f32;
    let seed = frame.region.seed;
    let mut streaks: Vec<ScreenStreak> =
        crate::error::try_par_filter_map("the snow's streaks", flakes, 1024, |f| {
            let s = screen_streak_through(
                cam,
                frame.lens.as_ref(),
                f,
                frame.exposure_s,
                frame.camera_velocity_m_s,
            )?;
            let light = shading.drop_light(eye + f.position_m);
            if let Some(th) = shading.cull_threshold
                && light.max_element() < th
            {
                return None;
            }
            let d = f.position_m.length();
            let tau = frame.haze.map_or(0.0, |h| h.optical_depth(d));
            let opacity = flake_opacity(f.diameter_m * 1e3, d, near, frame.opacity, tau);
            Some(s.with_particle(
                LAYER_SNOW,
                flake_sprite(seed, f),
                light * shading.radiance_scale,
                1.0,
                opacity,
            ))
        })?;
    streaks.retain(|s| s.alpha() > 0.0);
    Ok(streaks)
}

/// How far back along its path a box shelters a flake, m: under a roof, an awning or a
/// balcony no flake falls, but the straight path back of a wind-blown flake (at 5 m/s it
/// climbs 1 m in 5) meets the upwind buildings of any street, and real flakes reach the air of
/// a street canyon through its eddies. Bare lee-side ground is the snow cover's to decide.
pub const SHELTER_PATH_M: f32 = 3.0;

/// Removes the flakes (positioned relative to `center_m`, within `near_m` of it) whose path
/// back along their velocity meets a box within [`SHELTER_PATH_M`], keeping the others in
/// order.
pub fn remove_sheltered(
    flakes: &mut Vec<Flake>,
    boxes: &[crate::scene::boxes::SceneBox],
    center_m: Vec3,
    near_m: f32,
) {
    let reach = near_m + SHELTER_PATH_M;
    let near: Vec<_> = boxes
        .iter()
        .filter(|b| {
            let q = center_m.clamp(b.min_m, b.max_m);
            q.distance(center_m) <= reach
        })
        .copied()
        .collect();
    if near.is_empty() || flakes.is_empty() {
        return;
    }
    let keep: Vec<bool> = flakes
        .par_iter()
        .map(|f| {
            let back = -f.velocity_m_s;
            let len = back.length();
            len == 0.0
                || !crate::scene::raycast::occluded_within(
                    &near,
                    center_m + f.position_m,
                    back / len,
                    SHELTER_PATH_M,
                )
        })
        .collect();
    let mut k = keep.iter();
    flakes.retain(|_| k.next().copied().unwrap_or(true));
}

impl SnowFrame<'_> {
    /// The frame's flake streaks (unsorted, see [`prepare`]) and its stats.
    pub fn streaks(&self, cam: &Camera) -> Result<(Vec<ScreenStreak>, SnowStats)> {
        self.region
            .check_budget(cam.view_solid_angle_sr() / (4.0 * std::f64::consts::PI))?;
        let mut flakes = flakes_in_view(
            self.region,
            cam,
            f64::from(self.exposure_s),
            f64::from(self.camera_velocity_m_s.length()),
            self.ground,
        )?;
        remove_sheltered(
            &mut flakes,
            self.shelter,
            cam.eye(),
            self.region.near_m as f32,
        );
        let streaks = prepare(cam, self, &flakes)?;
        let stats = SnowStats {
            flakes: flakes.len(),
            streaks: streaks.len(),
        };
        Ok((streaks, stats))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::composite::{RainTargets, composite_streaks_with_snow};
    use crate::particles::order::far_to_near;
    use crate::particles::streak::{LAYER_RAIN, SPRITE_FLAT};
    use glam::{Mat3, Vec2, Vec4};

    fn cam(w: u32, h: u32) -> Camera {
        Camera::new(
            w,
            h,
            [w as f32, w as f32, w as f32 / 2.0, h as f32 / 2.0],
            Vec3::new(0.0, 1.6, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap()
    }

    #[test]
    fn sprites_keep_the_opacity_area_and_their_x4_bits() {
        // Each profile has mean 1 over [0, 1] (midpoint rule, against the analytic 1), and
        // profile_x4 is profile lane for lane.
        for kind in [SPRITE_FLAT, SPRITE_LUMP, SPRITE_STAR, SPRITE_AGGREGATE] {
            for turn in [0.0, 0.13, 0.5, 0.9] {
                let s = Sprite::new(kind, turn);
                let n = 200_000;
                let mean: f64 = (0..n)
                    .map(|k| f64::from(s.profile((k as f32 + 0.5) / n as f32)))
                    .sum::<f64>()
                    / n as f64;
                assert!((mean - 1.0).abs() < 2e-3, "kind {kind} turn {turn}: {mean}");
                for k in 0..300 {
                    let x = Vec4::new(0.0, 0.3, 0.77, 1.2) + Vec4::splat(k as f32 * 0.0037);
                    let v = s.profile_x4(x).to_array();
                    for l in 0..4 {
                        assert_eq!(v[l].to_bits(), s.profile(x[l]).to_bits());
                    }
                }
            }
        }
        // The ends: each kind's density has mean 1 over the end's quarter square (midpoint
        // rule), density_x4 is density lane for lane, and a lump's and an aggregate's ends are
        // round: nothing at the square's corner beyond the unit circle, the disc's density on it.
        for kind in [SPRITE_LUMP, SPRITE_STAR, SPRITE_AGGREGATE] {
            let s = Sprite::new(kind, 0.3);
            let n = 1000;
            let mut sum = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    let x = (i as f32 + 0.5) / n as f32;
                    let e = (j as f32 + 0.5) / n as f32 * 4.0;
                    sum += f64::from(s.density(x, e, 4.0));
                }
            }
            let mean = sum / (n * n) as f64;
            assert!((mean - 1.0).abs() < 2e-3, "kind {kind}: {mean}");
            for k in 0..300 {
                let x = Vec4::new(0.0, 0.3, 0.77, 1.2) + Vec4::splat(k as f32 * 0.0037);
                let e = Vec4::new(0.0, 1.1, 2.9, 5.0) + Vec4::splat(k as f32 * 0.011);
                let v = s.density_x4(x, e, Vec4::splat(4.0)).to_array();
                for l in 0..4 {
                    assert_eq!(v[l].to_bits(), s.density(x[l], e[l], 4.0).to_bits());
                }
            }
            // Further in than half a width: the profile across.
            assert_eq!(s.density(0.4, 4.0, 4.0), s.profile(0.4));
        }
        for kind in [SPRITE_LUMP, SPRITE_AGGREGATE] {
            let s = Sprite::new(kind, 0.0);
            // x = u = 0.75: r = 1.06, outside the disc; the product of profiles was not 0.
            assert_eq!(s.density(0.75, 1.0, 4.0), 0.0);
            assert!(s.profile(0.75) * s.profile(0.75) > 0.4);
            // The same radius across (x = 0.6, u ≈ 0) and along (x = 0, u = 0.6), the same
            // density: round.
            let across = s.density(0.6, 4.0 * 0.999_999, 4.0);
            let along = s.density(0.0, 4.0 * 0.4, 4.0);
            assert!((across - along).abs() < 1e-3, "{across} {along}");
        }
        // A wide flake's pixels still sum to its opacity-area, sprite and all.
        let c = Camera::new(
            400,
            400,
            [600.0, 600.0, 200.0, 200.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        for kind in [SPRITE_LUMP, SPRITE_STAR, SPRITE_AGGREGATE] {
            let f = Flake {
                position_m: Vec3::new(0.02, -0.05, -0.4),
                velocity_m_s: Vec3::new(0.3, -1.0, 0.0),
                diameter_m: 8e-3,
                id: [0; 5],
            };
            let s = screen_streak_through(&c, None, &f, 1.0 / 30.0, Vec3::ZERO)
                .unwrap()
                .with_particle(LAYER_SNOW, Sprite::new(kind, 0.3), Vec3::ONE, 1.0, 1.0);
            assert!(s.wa > 8.0, "{}", s.wa);
            let sum: f32 = (0..400 * 400)
                .filter_map(|i| {
                    s.fragment(Vec2::new((i % 400) as f32 + 0.5, (i / 400) as f32 + 0.5))
                })
                .map(|f| f.0)
                .sum();
            let area = s.opacity_area_in(400.0, 400.0);
            assert!(
                (sum / area - 1.0).abs() < 0.03,
                "kind {kind}: {sum} vs {area}"
            );
        }
    }

    fn mixed(c: &Camera, snow_rate: f64, wind: [f64; 3]) -> (Vec<ScreenStreak>, usize) {
        let rain =
            crate::rain::drops::RainRegion::new(30.0, &[1.0, 2.0], 3.0, wind, 0.4, 5).unwrap();
        let shading = RainShading::open_sky();
        let (mut all, _) = crate::rain::streaks::prepare(
            c,
            None,
            &crate::rain::drops::drops_in_view(&rain, c, 1.0 / 30.0, 0.0, true).unwrap(),
            1.0 / 30.0,
            Vec3::ZERO,
            &shading,
        )
        .unwrap();
        let region = SnowRegion::new(snow_rate, 4.0, wind, 0.4, 5).unwrap();
        let snow_shading = RainShading {
            reflectance: 1.0,
            drop_radiance: crate::snow::SNOW_ALBEDO,
            ..RainShading::open_sky()
        };
        let frame = SnowFrame {
            region: &region,
            exposure_s: 1.0 / 30.0,
            camera_velocity_m_s: Vec3::ZERO,
            lens: None,
            ground: true,
            shelter: &[],
            shading: &snow_shading,
            opacity: SnowOpacity::Extinction,
            haze: Some(crate::haze::Haze::new(0.02, [1.0; 3], f32::INFINITY).unwrap()),
        };
        let (flakes, stats) = frame.streaks(c).unwrap();
        assert_eq!(stats.streaks, flakes.len());
        let n = flakes.len();
        all.extend(flakes);
        far_to_near(&mut all).unwrap();
        (all, n)
    }

    #[test]
    fn rain_and_snow_composite_in_one_list_into_their_own_layers() {
        // Against the per-pixel definition: every streak in order, ScreenStreak::fragment, its
        // coverage into its own layer's product (the rain's depth from the rain only).
        let (w, h) = (120usize, 68usize);
        let c = cam(w as u32, h as u32);
        let (streaks, n_snow) = mixed(&c, 3.0, [2.0, 0.0, 0.0]);
        assert!(
            n_snow > 200 && streaks.len() > n_snow + 50,
            "{n_snow} {}",
            streaks.len()
        );
        assert!(
            streaks
                .iter()
                .any(|s| s.sprite().kind() == SPRITE_STAR && s.wa > 2.5)
        );
        let n = w * h;
        let background: Vec<f32> = (0..3 * n).map(|i| (i % 7) as f32 * 0.05).collect();
        let depth: Vec<f32> = (0..n)
            .map(|i| if i % w < w / 3 { 2.5 } else { f32::INFINITY })
            .collect();
        let (mut rgb, mut ra, mut rd, mut sa) =
            (background.clone(), vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        composite_streaks_with_snow(
            &c,
            &streaks,
            RainTargets {
                rgb: &mut rgb,
                depth_m: &depth,
                alpha: &mut ra,
                rain_depth_m: &mut rd,
            },
            &mut sa,
        )
        .unwrap();
        let mut snowed = 0;
        for i in 0..n {
            let p = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let mut col = [
                background[3 * i],
                background[3 * i + 1],
                background[3 * i + 2],
            ];
            let (mut keep_r, mut keep_s, mut near) = (1.0f32, 1.0f32, f32::INFINITY);
            for s in &streaks {
                let Some((a, z)) = s.fragment(p) else {
                    continue;
                };
                if z >= depth[i] {
                    continue;
                }
                for (c, l) in col.iter_mut().zip(s.light.to_array()) {
                    *c += a * s.reflectance * (l - *c);
                }
                if s.layer() == LAYER_SNOW {
                    keep_s *= 1.0 - a;
                } else {
                    assert_eq!(s.layer(), LAYER_RAIN);
                    keep_r *= 1.0 - a;
                    near = near.min(z);
                }
            }
            for ch in 0..3 {
                assert!((rgb[3 * i + ch] - col[ch]).abs() < 3e-4, "pixel {i}");
            }
            assert!((ra[i] - (1.0 - keep_r)).abs() < 3e-4, "pixel {i}");
            assert!(
                (sa[i] - (1.0 - keep_s)).abs() < 3e-4,
                "pixel {i}: {} vs {}",
                sa[i],
                1.0 - keep_s
            );
            assert!(rd[i] == near || (rd[i] - near).abs() < 1e-3 * near);
            snowed += usize::from(sa[i] > 1e-3);
        }
        assert!(snowed > n / 20, "{snowed}");
        // flakes are hidden behind the near wall (depth 2.5 m) unless nearer
        let deep = streaks
            .iter()
            .filter(|s| s.layer() == LAYER_SNOW && 1.0 / s.inv_za.max(s.inv_zb) > 3.0)
            .count();
        assert!(deep > 0);
    }

    #[test]
    fn opacity_falls_with_distance_continuously_or_by_levels() {
        let s = 5.0;
        let fill = flake_opacity(s, 0.0, 8.0, SnowOpacity::Extinction, 0.0);
        let want_fill = (flake_area_mm2(5.0) / (std::f64::consts::FRAC_PI_4 * 25.0)) as f32;
        assert!(
            (fill - want_fill).abs() < 1e-6 && (0.2..0.5).contains(&fill),
            "{fill}"
        );
        let far = flake_opacity(s, 6.0, 8.0, SnowOpacity::Extinction, 0.05 * 6.0);
        assert!((far / fill - (-0.3f32).exp()).abs() < 1e-6);
        let lv = |d: f32| flake_opacity(s, d, 9.0, SnowOpacity::Levels, 0.05 * d) / fill;
        assert_eq!([lv(1.0), lv(4.0), lv(8.0)], OPACITY_LEVELS);
        assert!(SnowOpacity::parse("levels").is_ok());
        let e = SnowOpacity::parse("fog").unwrap_err().to_string();
        assert!(
            e.contains("snow_opacity") && e.contains("extinction"),
            "{e}"
        );
    }

    #[test]
    fn flakes_slant_with_the_wind_on_screen() {
        // A still camera looking along −z: with wind along +x the flakes' streaks lean right
        // (screen +x while they fall, screen +y); without wind they hang down (dx ≈ 0 on
        // average).
        let c = cam(160, 90);
        let lean = |wind: f64| {
            let (streaks, _) = mixed(&c, 2.0, [wind, 0.0, 0.0]);
            let flakes: Vec<_> = streaks
                .iter()
                .filter(|s| s.layer() == LAYER_SNOW && s.len > 3.0)
                .collect();
            assert!(flakes.len() > 50);
            // a → b is the path forwards in time
            flakes
                .iter()
                .map(|s| s.dir.x / s.dir.y.abs().max(1e-3))
                .sum::<f32>()
                / flakes.len() as f32
        };
        let (calm, windy) = (lean(0.0), lean(3.0));
        assert!(calm.abs() < 0.15, "{calm}");
        assert!(windy > 1.5, "{windy}");
    }
}
