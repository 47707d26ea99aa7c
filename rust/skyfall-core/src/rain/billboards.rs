//! Yoshida, Dobashi & Yamamoto's billboards, drawn sparsely: per voxel and diameter bin, the bin's rain texture
//! ([`super::texture::draw_streaks`], one per bin, shared by all voxels) on a 1 m × 1 m
//! billboard through the voxel centre. Billboards are cylindrical: they face the horizontal
//! direction to the camera. Each billboard's texture scrolls down at the fall speed of its
//! bin's middle diameter and wraps (the paper moves billboards down by v·dt and wraps them), and
//! gets a random offset per voxel and bin so neighbouring voxels do not repeat one pattern
//! (the paper repeats it). The texture's streaks become drops on the billboard plane: every
//! streak of a billboard is drawn at the billboard's depth, which is the approximation that the
//! per-drop reference ([`super::drops`]) measures.
//!
//! Drawn as is, that approximation comes out under the reference (5–20 % less mean opacity for
//! rain_near_m = 8 down to 2 m, measured over 8 seeds): a streak's opacity-area goes as 1/z²,
//! which is convex in the depth z,
//! so by Jensen's inequality drops moved to their voxel's centre plane lose opacity; and the
//! drops of a voxel whose centre plane lies behind the camera or outside the frame (the
//! camera's own voxel, for one) show nowhere. The billboards therefore widen their streaks so
//! that, in expectation, they carry the drops' on-screen opacity (see [`opacity_balance`]):
//! per voxel by the factor g_v with g_v² = A_v / B_v, A_v and B_v the mean opacity-area (α·w·L
//! inside the frame, [`ScreenStreak::opacity_area_in`]) of a probe drop placed through the
//! voxel and on its billboard (stratified samples, finer near the camera), g_v at most [`MAX_GAIN`]; and over the frame by one more factor
//! that spreads what the voxels could not show themselves (A_v − g_v² B_v) over all streaks.
//! Widening a thin streak by g scales its opacity α = w / L and its width w, so its
//! opacity-area, by g². Measured against the drops (640 × 360, 8–16 seeds): −4 to +2 % for
//! level, tilted, windy and narrow views at rain_near_m = 2–8 m; −2 % (± 1 %, 64 seeds) for a
//! camera moving forward at 15 m/s. A billboard frame's mean opacity varies more from seed to
//! seed than the drops' (the sampled balance varies with the seed too).

use super::drops::{Drop, RainRegion, voxel_in_view};
use super::texture::{Streak, draw_streaks};
use crate::particles::streak::{ScreenStreak, screen_streak_through};
use crate::particles::voxels::{map_voxel_columns, voxel_seed, wrap};
use crate::physics::fall_speed::FallSpeed;
use crate::scene::camera::{Camera, Defocus};
use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Largest widening of one voxel's streaks (a billboard that barely shows would otherwise
/// draw its few visible streaks many times too wide; what it cannot show goes to the frame).
pub const MAX_GAIN: f32 = 2.0;
/// Quadrature strata per axis of [`opacity_balance`]: through the voxel, and on the billboard
/// (the billboard's sum is the ratio's denominator, so it gets the finer grid).
const STRATA: usize = 3;
const BOARD_STRATA: usize = 6;
/// Voxels whose centre lies within this distance of the camera, m, get [`NEAR_FINER`] times as
/// many strata per axis: their drops' opacity-area varies most through them (1/z² near the
/// lens, the frame's edges) and they carry most of a frame's opacity, so their sampling noise
/// would otherwise make a frame's mean opacity vary from seed to seed (measured at 640 × 360,
/// 32 seeds: 4.1 % and 8.0 % std for a level and a moving camera with 4³ + 8² points
/// everywhere, 2.5 % and 2.7 % with this, against the drops' own 2.7 % and 3.9 %).
const NEAR_VOXEL_M: f32 = 2.5;
const NEAR_FINER: usize = 3;

/// A voxel's (A_v, B_v) of the module docs: the mean on-screen opacity-area, px², of a probe
/// drop ending uniformly through the voxel (`corner` its lowest corner) and of one ending
/// uniformly over the billboard through `centre` along `right` (as the textures' streaks do:
/// their end uniform over the voxel's height, their axis uniform over its width);
/// `area_at(end)` is the probe's opacity-area ending at `end`. Stratified sampling, one jittered point per stratum ((3·`finer`)³ and
/// (6·`finer`)²): unbiased for each voxel, so the frame's sums converge as voxels add up;
/// `rng` makes it deterministic.
fn opacity_balance(
    area_at: &impl Fn(Vec3) -> f32,
    rng: &mut Pcg64Mcg,
    corner: Vec3,
    centre: Vec3,
    right: Vec3,
    finer: usize,
) -> (f64, f64) {
    let mut at = |i: usize, n: usize| (i as f32 + rng.random::<f32>()) / n as f32;
    let (n, m) = (STRATA * finer, BOARD_STRATA * finer);
    let (mut drops, mut board) = (0.0f64, 0.0f64);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                drops += f64::from(area_at(corner + Vec3::new(at(i, n), at(j, n), at(k, n))));
            }
        }
    }
    for i in 0..m {
        for j in 0..m {
            board += f64::from(area_at(
                centre + right * (at(i, m) - 0.5) + Vec3::Y * (0.5 - at(j, m)),
            ));
        }
    }
    (drops / (n * n * n) as f64, board / (m * m) as f64)
}

/// The probe of [`opacity_balance`], a drop of the region's middle diameter falling at its
/// speed in the wind: its on-screen opacity-area ending at a point (0 beyond the region).
fn probe_area(
    region: &RainRegion,
    cam: &Camera,
    exposure_s: f64,
    camera_velocity_m_s: Vec3,
    lens: Option<&Defocus>,
) -> impl Fn(Vec3) -> f32 + Sync {
    let law = *FallSpeed::beard_standard();
    let d_mid = region.middle_diameter_mm();
    let velocity = Vec3::new(
        region.wind_m_s.x as f32,
        -law.m_s(d_mid) as f32,
        region.wind_m_s.z as f32,
    );
    let (near, frame) = (region.near_m as f32, (cam.width as f32, cam.height as f32));
    let (cam, lens) = (*cam, lens.copied());
    move |end: Vec3| -> f32 {
        if end.length() > near {
            return 0.0;
        }
        let probe = Drop {
            position_m: end,
            velocity_m_s: velocity,
            diameter_m: (d_mid * 1e-3) as f32,
            id: [0; 5],
        };
        screen_streak_through(
            &cam,
            lens.as_ref(),
            &probe,
            exposure_s as f32,
            camera_velocity_m_s,
        )
        .map_or(0.0, |s: ScreenStreak| s.opacity_area_in(frame.0, frame.1))
    }
}

/// One column of voxels' billboard streaks, and its share of the frame's opacity balance.
struct Column {
    drops: Vec<Drop>,
    /// Σ A_v: what the voxels' drops would show.
    wanted: f64,
    /// Σ g_v² B_v: what their widened billboards show.
    shown: f64,
    /// The length `drops` could not grow to (None: every voxel's streaks made).
    refused: Option<usize>,
}

impl AsMut<Vec<Drop>> for Column {
    fn as_mut(&mut self) -> &mut Vec<Drop> {
        &mut self.drops
    }
}

/// The billboards' streaks as drops, for the voxels that can draw into `cam`'s frame, widened
/// to carry the drops' opacity (see the module docs; `camera_velocity_m_s` as in the drawn
/// streaks, and `lens` too: the balance's probes are defocused as the drawn streaks are).
pub fn billboards_in_view(
    region: &RainRegion,
    cam: &Camera,
    exposure_s: f64,
    camera_velocity_m_s: Vec3,
    lens: Option<&Defocus>,
    ground: bool,
) -> crate::error::Result<Vec<Drop>> {
    let camera_speed_m_s = f64::from(camera_velocity_m_s.length());
    let law = *FallSpeed::beard_standard();
    let textures: Vec<Vec<Streak>> = region
        .bins
        .iter()
        .map(|&(lo, hi)| draw_streaks(region.rain_rate_mm_h, lo, hi, exposure_s, region.seed))
        .collect();
    let scroll: Vec<f64> = region
        .bins
        .iter()
        .map(|&(lo, hi)| law.m_s(0.5 * (lo + hi)) * region.time_s)
        .collect();
    let eye = cam.position_m;
    let voxel_rel = |voxel: [i64; 3], offset: f64| {
        (DVec3::new(voxel[0] as f64, voxel[1] as f64, voxel[2] as f64) + offset - eye).as_vec3()
    };
    let area_at = probe_area(region, cam, exposure_s, camera_velocity_m_s, lens);
    let per_voxel: usize = textures.iter().map(Vec::len).sum();
    let board_streaks = |voxel: [i64; 3], column: &mut Column| {
        // Reserved fallibly, then pushed without growing (a voxel makes per_voxel drops).
        if column.refused.is_some() || column.drops.try_reserve(per_voxel).is_err() {
            column.refused.get_or_insert(column.drops.len() + per_voxel);
            return;
        }
        // Relative to the camera, as the drops are.
        let centre = voxel_rel(voxel, 0.5);
        let to_eye = Vec3::new(-centre.x, 0.0, -centre.z);
        let n = if to_eye.length_squared() > 1e-12 {
            to_eye.normalize()
        } else {
            Vec3::Z
        };
        let right = Vec3::new(n.z, 0.0, -n.x);
        let corner = voxel_rel(voxel, 0.0);
        let mut rng = Pcg64Mcg::seed_from_u64(voxel_seed(region.seed, voxel, &[0x0BA1_A4CE]));
        let finer = if centre.length() < NEAR_VOXEL_M {
            NEAR_FINER
        } else {
            1
        };
        let (want, board) = opacity_balance(&area_at, &mut rng, corner, centre, right, finer);
        let gain = if board > 0.0 {
            ((want / board).sqrt() as f32).min(MAX_GAIN)
        } else {
            1.0
        };
        column.wanted += want;
        column.shown += f64::from(gain * gain) * board;
        for (bin, streaks) in textures.iter().enumerate() {
            let key = voxel_seed(region.seed, voxel, &[bin as u64, 0xB111_B0A4D]);
            let mut rng = Pcg64Mcg::seed_from_u64(key);
            let (ox, oy): (f64, f64) = (rng.random(), rng.random());
            for (k, s) in streaks.iter().enumerate() {
                let u = wrap(s.x_m + ox);
                let top = wrap(s.y_m + oy + scroll[bin]);
                // The texture's top is where the drop is at the end of the exposure (its
                // streak reaches up from there), as the per-drop reference's drops end
                // uniformly through their voxel. (Taking it for the streak's top put every
                // billboard's rain a streak's length lower than the voxel's drops: a near
                // voxel's opacity moved down the frame, 0.80 / 1.05 / 1.17 of the drops' by
                // thirds, top to bottom, at 640 × 360.)
                let end = centre + right * (u - 0.5) as f32 + Vec3::Y * (0.5 - top) as f32;
                let fall = (s.length_m / exposure_s) as f32;
                column.drops.push(Drop {
                    position_m: end,
                    velocity_m_s: Vec3::new(
                        region.wind_m_s.x as f32,
                        -fall,
                        region.wind_m_s.z as f32,
                    ),
                    diameter_m: s.diameter_m as f32 * gain,
                    id: [voxel[0], voxel[1], voxel[2], bin as i64, k as i64],
                });
            }
        }
    };
    let keep = voxel_in_view(region, cam, exposure_s, camera_speed_m_s, 0.0);
    let columns = map_voxel_columns(eye, region.near_m, ground, keep, |voxels| {
        let mut column = Column {
            drops: Vec::new(),
            wanted: 0.0,
            shown: 0.0,
            refused: None,
        };
        for voxel in voxels {
            board_streaks(voxel, &mut column);
        }
        column
    });
    if let Some(n) = columns.iter().find_map(|c| c.refused) {
        return Err(crate::error::Error::out_of_memory::<Drop>(
            "the rain's billboards",
            n,
        ));
    }
    // What no billboard could show, spread over all of them (the sums in column order: the
    // same bits in every run).
    let (wanted, shown) = columns
        .iter()
        .fold((0.0, 0.0), |(w, s), c| (w + c.wanted, s + c.shown));
    let spread = if shown > 0.0 {
        ((wanted / shown).sqrt() as f32).min(MAX_GAIN)
    } else {
        1.0
    };
    let mut drops: Vec<Drop> = crate::error::try_with_capacity(
        "the rain's billboards",
        columns.iter().map(|c| c.drops.len()).sum(),
    )?;
    for c in columns {
        drops.extend(c.drops.into_iter().map(|d| Drop {
            diameter_m: d.diameter_m * spread,
            ..d
        }));
    }
    Ok(drops)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rain::drops::drops_in_view;
    use glam::Mat3;

    #[test]
    fn the_balance_of_a_voxel_straight_ahead_is_jensens_ratio() {
        // A voxel straight ahead of a level camera, 1 to 2 m away, all in view: its drops' depth
        // is uniform on [1, 2] m and its billboard stands at 1.5 m facing the camera, so with
        // opacity-area ∝ 1/z² the ratio is E[1/z²] · 1.5² = 1/(1·2) · 2.25 = 1.125.
        let r = RainRegion::new(10.0, &[1.0, 2.0], 5.0, [0.0; 3], 0.0, 1).unwrap();
        let cam = Camera::new(
            400,
            400,
            [100.0, 100.0, 200.0, 200.0],
            Vec3::new(0.5, 1.5, 1.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let area_at = probe_area(&r, &cam, 1.0 / 30.0, Vec3::ZERO, None);
        // (positions relative to the camera, as billboards_in_view makes them)
        let (corner_m, centre_m) = (Vec3::new(0.0, 1.0, -1.0), Vec3::new(0.5, 1.5, -0.5));
        let (corner, centre) = (corner_m - cam.eye(), centre_m - cam.eye());
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let (a, b) = opacity_balance(&area_at, &mut rng, corner, centre, Vec3::X, NEAR_FINER);
        assert!((a / b - 1.125).abs() < 0.02, "{}", a / b);
        // Through a lens the probes blur as the drawn streaks do and keep their opacity-area,
        // so the balance is Jensen's ratio still (f = 100 px · 400 mm / 400 px = 100 mm at f/1
        // focused at infinity: blur circles of 5 to 10 px over the voxel's depths).
        let lens = crate::scene::camera::ThinLens::new(1.0, f64::INFINITY, 400.0).unwrap();
        let defocus = lens.defocus(&cam).unwrap();
        assert!(defocus.blur_px(1.0 / 1.5) > 5.0);
        let area_at = probe_area(&r, &cam, 1.0 / 30.0, Vec3::ZERO, Some(&defocus));
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let (a, b) = opacity_balance(&area_at, &mut rng, corner, centre, Vec3::X, NEAR_FINER);
        assert!((a / b - 1.125).abs() < 0.02, "through a lens: {}", a / b);
        // far away the spread of depths no longer matters
        let far = Camera::new(
            400,
            400,
            [100.0, 100.0, 200.0, 200.0],
            Vec3::new(0.5, 1.5, 20.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let r = RainRegion::new(10.0, &[1.0, 2.0], 30.0, [0.0; 3], 0.0, 1).unwrap();
        let area_at = probe_area(&r, &far, 1.0 / 30.0, Vec3::ZERO, None);
        let (corner, centre) = (corner_m - far.eye(), centre_m - far.eye());
        let (a, b) = opacity_balance(&area_at, &mut rng, corner, centre, Vec3::X, NEAR_FINER);
        assert!((a / b - 1.0).abs() < 0.003, "{}", a / b);
    }

    #[test]
    fn billboards_hold_as_many_drops_as_the_reference_and_face_the_camera() {
        let r = RainRegion::new(20.0, &[1.0, 1.5, 2.0], 4.0, [0.0; 3], 0.3, 2).unwrap();
        let cam = Camera::new(
            120,
            80,
            [90.0, 90.0, 60.0, 40.0],
            Vec3::new(0.3, 1.6, 0.2),
            Mat3::IDENTITY,
        )
        .unwrap();
        let b = billboards_in_view(&r, &cam, 1.0 / 30.0, Vec3::ZERO, None, true).unwrap();
        let d = drops_in_view(&r, &cam, 1.0 / 30.0, 0.0, true).unwrap();
        // Over the voxels both draw (billboards keep a few more at the frustum's edge: their
        // streaks reach below the voxel).
        let voxel = |x: &Drop| [x.id[0], x.id[1], x.id[2]];
        let drawn: std::collections::HashSet<[i64; 3]> = d.iter().map(voxel).collect();
        let shared = b.iter().filter(|x| drawn.contains(&voxel(x))).count();
        assert!(shared <= b.len() && b.len() < 2 * shared);
        let ratio = shared as f64 / d.len() as f64;
        assert!(
            (ratio - 1.0).abs() < 0.1,
            "{shared} billboard drops vs {} drops",
            d.len()
        );
        // every billboard drop lies on its voxel's plane through the centre, facing the camera
        for drop in b.iter().take(500) {
            // (relative to the camera, as the drops are)
            let c = (DVec3::new(drop.id[0] as f64, drop.id[1] as f64, drop.id[2] as f64) + 0.5
                - cam.position_m)
                .as_vec3();
            let n = Vec3::new(-c.x, 0.0, -c.z).normalize();
            assert!((drop.position_m - c).dot(n).abs() < 1e-4);
        }
    }
}
