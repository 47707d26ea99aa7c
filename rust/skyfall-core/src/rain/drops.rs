//! Individual raindrops near the camera, anchored in the world (Yoshida, Dobashi & Yamamoto's rain region, drawn
//! drop by drop: the reference the billboard approximation is measured against).
//!
//! The world is cut into 1 m voxels at integer coordinates. Each voxel holds, for each
//! diameter bin, ⌊λ⌋ drops plus one with probability λ − ⌊λ⌋ (λ = the Marshall–Palmer count
//! of the bin in 1 m³), with diameters from Marshall–Palmer within the bin and uniform
//! positions, all drawn from a generator seeded by (seed, voxel, bin): the same drops for any
//! camera, frame or process. Drops move with velocity (wind_x, −v(D), wind_z) (Beard fall
//! speed) and wrap inside their voxel, so every voxel is statistically the same at all times
//! and rain is temporally coherent. Voxels below the ground (y < 0) hold no drops.

use super::bins::diameter_bins;
use crate::error::{Error, Range, Result};
use crate::particles::voxels::{in_view, voxel_seed, voxels_where, wrap};
use crate::physics::dsd::{BinSampler, RAIN_RATE_MM_H, drops_per_m3};
use crate::physics::fall_speed::FallSpeed;
use crate::scene::camera::Camera;
use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Valid rain-region radii, m.
pub const NEAR_M: Range = crate::ranges::RAIN_NEAR_M.range;
/// Valid wind components, m/s.
pub const WIND_M_S: Range = crate::ranges::WIND_M_S.range;

/// Which rain, where and when.
#[derive(Debug, Clone, PartialEq)]
pub struct RainRegion {
    /// Rain rate, mm/h.
    pub rain_rate_mm_h: f64,
    /// Diameter bin edges, mm.
    pub bins: Vec<(f64, f64)>,
    /// Region radius around the camera, m.
    pub near_m: f64,
    /// Wind, m/s.
    pub wind_m_s: DVec3,
    /// Time, s.
    pub time_s: f64,
    /// Seed.
    pub seed: u64,
    /// Drops or billboards.
    pub method: RainMethod,
    /// Drops farther than this horizontally, m, are drawn by the far level of detail
    /// ([`super::far`]) instead of one by one; None: every drop one by one.
    pub far_m: Option<f64>,
}

impl RainRegion {
    /// Validated region from texture-style diameters (bins around them, see [`diameter_bins`]).
    pub fn new(
        rain_rate_mm_h: f64,
        diameters_mm: &[f64],
        near_m: f64,
        wind_m_s: [f64; 3],
        time_s: f64,
        seed: u64,
    ) -> Result<Self> {
        RAIN_RATE_MM_H.check("rain_rate_mm_h", None, rain_rate_mm_h)?;
        NEAR_M.check("rain_near_m", None, near_m)?;
        for (i, w) in wind_m_s.iter().enumerate() {
            WIND_M_S.check("wind_m_s", Some(i), *w)?;
        }
        crate::ranges::TIME_S.check(time_s)?;
        Ok(RainRegion {
            rain_rate_mm_h,
            bins: diameter_bins(diameters_mm)?,
            near_m,
            wind_m_s: DVec3::from(wind_m_s),
            time_s,
            seed,
            method: RainMethod::Drops,
            far_m: None,
        })
    }
}

/// The most memory the drops of one call may take, bytes: the region's volume goes as
/// rain_near_m³, and at 50 m and 200 mm/h its drops would need ~40 GiB.
pub const DROP_BUDGET_BYTES: u64 = 2 << 30;

impl RainRegion {
    /// The middle of the region's diameters, mm (1.5 without bins): the diameter whose fall
    /// speed stands for all of them where one speed is needed.
    pub fn middle_diameter_mm(&self) -> f64 {
        self.bins
            .first()
            .zip(self.bins.last())
            .map_or(1.5, |(a, b)| 0.5 * (a.0 + b.1))
    }

    /// The drops expected in `fraction` of the region's sphere (grown by a voxel's diagonal,
    /// for the voxels its surface cuts).
    pub fn expected_drops(&self, fraction: f64) -> f64 {
        let per_m3: f64 = self
            .bins
            .iter()
            .map(|&(lo, hi)| drops_per_m3(self.rain_rate_mm_h, lo, hi))
            .sum();
        per_m3 * 4.0 / 3.0 * std::f64::consts::PI * (self.near_m + 1.8).powi(3) * fraction
    }

    /// [`Error::TooLarge`] when the drops expected in `fraction` of the region would take more
    /// than [`DROP_BUDGET_BYTES`]: refused before any is made, naming what sets their number.
    pub fn check_budget(&self, fraction: f64) -> Result<()> {
        let n = self.expected_drops(fraction);
        let bytes = (n * std::mem::size_of::<Drop>() as f64) as u128;
        if bytes > u128::from(DROP_BUDGET_BYTES) {
            let what = format!(
                "{n:.3e} drops (rain_near_m = {} m at {} mm/h; their number goes as rain_near_m³)",
                self.near_m, self.rain_rate_mm_h
            );
            return Err(Error::too_large(what, bytes, DROP_BUDGET_BYTES));
        }
        Ok(())
    }
}

/// A raindrop is a particle of the toolkit: its position (relative to the frame's camera),
/// velocity, diameter and identity (voxel, diameter bin, index in the voxel).
pub use crate::particles::Particle as Drop;

/// Fall speeds per diameter bin, tabulated: Beard's law (a logarithm, a polynomial and an
/// exponential per call) at `SPEED_STEPS` + 1 evenly spaced diameters of each bin, read back by
/// linear interpolation; the cells holding one of the law's regime boundaries (19 µm, 1.07 mm)
/// call the law itself. Relative error under 3e-5 (3e-7 over 0.5 mm, in bins up to 1 mm wide;
/// tested), against Beard's own ~2 % from measured speeds. Built per frame: 257 calls per bin.
pub(crate) struct BinSpeeds {
    law: FallSpeed,
    /// Per bin: lowest diameter (mm), 1/step (1/mm), the speeds, and the cell (if any) that
    /// straddles a regime boundary.
    tables: Vec<(f64, f64, Vec<f64>, [usize; 2])>,
}

const SPEED_STEPS: usize = 256;

impl BinSpeeds {
    pub(crate) fn new(bins: &[(f64, f64)]) -> Self {
        let law = *FallSpeed::beard_standard();
        let tables = bins
            .iter()
            .map(|&(lo, hi)| {
                let step = (hi - lo) / SPEED_STEPS as f64;
                let inv_step = if step > 0.0 { 1.0 / step } else { 0.0 };
                let cell = |d: f64| {
                    if d > lo && d < hi {
                        ((d - lo) * inv_step) as usize
                    } else {
                        usize::MAX
                    }
                };
                (
                    lo,
                    inv_step,
                    (0..=SPEED_STEPS)
                        .map(|k| law.m_s(lo + step * k as f64))
                        .collect(),
                    [cell(19e-3), cell(1.07)],
                )
            })
            .collect();
        BinSpeeds { law, tables }
    }

    /// The fall speed, m/s, of a drop of `d_mm` in bin `bin` (clamped to the bin).
    #[inline]
    pub(crate) fn m_s(&self, bin: usize, d_mm: f64) -> f64 {
        let (lo, inv_step, v, kinks) = &self.tables[bin];
        let x = ((d_mm - lo) * inv_step).clamp(0.0, SPEED_STEPS as f64);
        let k = (x as usize).min(SPEED_STEPS - 1);
        if kinks.contains(&k) {
            return self.law.m_s(d_mm);
        }
        let f = x - k as f64;
        v[k] + (v[k + 1] - v[k]) * f
    }
}

/// The drops of one voxel and bin.
fn voxel_drops(
    region: &RainRegion,
    speeds: &BinSpeeds,
    voxel: [i64; 3],
    bin: usize,
    origin_m: DVec3,
    out: &mut Vec<Drop>,
) -> bool {
    let (lo, hi) = region.bins[bin];
    let sampler = BinSampler::new(region.rain_rate_mm_h, lo, hi);
    if sampler.expected_per_m3() <= 0.0 {
        return true;
    }
    let key = voxel_seed(
        region.seed,
        voxel,
        &[bin as u64, lo.to_bits(), hi.to_bits()],
    );
    let mut rng = Pcg64Mcg::seed_from_u64(key);
    let n = sampler.count(&mut rng);
    // Room for the voxel's drops first, fallibly: the pushes below do not allocate.
    if out.try_reserve(n).is_err() {
        return false;
    }
    let base = DVec3::new(voxel[0] as f64, voxel[1] as f64, voxel[2] as f64);
    for k in 0..n {
        let d_mm = sampler.diameter_mm(rng.random());
        let v = speeds.m_s(bin, d_mm);
        let vel = DVec3::new(region.wind_m_s.x, -v, region.wind_m_s.z);
        let p0 = DVec3::new(rng.random(), rng.random(), rng.random());
        let p = p0 + vel * region.time_s;
        let local = DVec3::new(wrap(p.x), wrap(p.y), wrap(p.z));
        out.push(Drop {
            position_m: (base + local - origin_m).as_vec3(),
            velocity_m_s: vel.as_vec3(),
            diameter_m: (d_mm * 1e-3) as f32,
            id: [voxel[0], voxel[1], voxel[2], bin as i64, k as i64],
        });
    }
    true
}

/// How the rain region is filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RainMethod {
    /// Every drop individually (the reference).
    Drops,
    /// Yoshida, Dobashi & Yamamoto's billboards: per voxel and diameter bin, the bin's rain texture on a 1 m
    /// billboard through the voxel centre, facing the camera horizontally, scrolling down.
    Billboards,
}

impl RainMethod {
    /// Parses `"drops"` or `"billboards"`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "drops" => Ok(Self::Drops),
            "billboards" => Ok(Self::Billboards),
            other => Err(crate::error::Error::Invalid {
                param: crate::error::Param {
                    name: "rain_method",
                    index: None,
                },
                message: format!(
                    "unknown rain method {other:?}; expected \"drops\" or \"billboards\""
                ),
            }),
        }
    }
}

/// Every drop within `region.near_m` of `center_m` (voxels at or above the ground only when
/// `ground` is set), in a deterministic order, positioned relative to `center_m`.
pub fn drops_near(region: &RainRegion, center_m: DVec3, ground: bool) -> Result<Vec<Drop>> {
    let speeds = BinSpeeds::new(&region.bins);
    voxels_where(
        "the rain's drops",
        center_m,
        region.near_m,
        ground,
        |_| true,
        |voxel, out| {
            (0..region.bins.len())
                .all(|bin| voxel_drops(region, &speeds, voxel, bin, center_m, out))
        },
    )
}

/// Whether a voxel (by its centre) can draw into `cam`'s frame during `exposure_s`: the voxel's
/// box, grown by the farthest a drop moves relative to the camera (moving at
/// `camera_speed_m_s`) in the exposure plus `slack_m`, and by the reach of a streak's
/// anti-aliasing beyond the frame's edge (a drop's radius plus two pixels at the region's far
/// side), meets the view frustum (see [`in_view`]).
pub fn voxel_in_view(
    region: &RainRegion,
    cam: &Camera,
    exposure_s: f64,
    camera_speed_m_s: f64,
    slack_m: f64,
) -> impl Fn(Vec3) -> bool + Sync + use<> {
    let law = *FallSpeed::beard_standard();
    let d_max = region.bins.last().map_or(0.0, |b| b.1);
    let speed =
        (law.m_s(d_max).powi(2) + region.wind_m_s.x.powi(2) + region.wind_m_s.z.powi(2)).sqrt();
    let edge = 2.0 * (region.near_m + 2.0) / f64::from(cam.fx.min(cam.fy)) + 0.5e-3 * d_max;
    let margin = ((speed + camera_speed_m_s) * exposure_s + slack_m + edge) as f32;
    in_view(cam, margin)
}

/// The drops of [`drops_near`] that can draw into `cam`'s frame (see [`voxel_in_view`]): the
/// voxels that cannot are skipped without drawing their drops. The drops kept are exactly
/// those of [`drops_near`] in those voxels.
pub fn drops_in_view(
    region: &RainRegion,
    cam: &Camera,
    exposure_s: f64,
    camera_speed_m_s: f64,
    ground: bool,
) -> Result<Vec<Drop>> {
    drops_in_view_where(region, cam, exposure_s, camera_speed_m_s, ground, |_| true)
}

/// [`drops_in_view`] in the voxels `also` accepts too (by their centre relative to the camera).
pub fn drops_in_view_where(
    region: &RainRegion,
    cam: &Camera,
    exposure_s: f64,
    camera_speed_m_s: f64,
    ground: bool,
    also: impl Fn(Vec3) -> bool + Sync,
) -> Result<Vec<Drop>> {
    let speeds = BinSpeeds::new(&region.bins);
    let in_view = voxel_in_view(region, cam, exposure_s, camera_speed_m_s, 0.0);
    voxels_where(
        "the rain's drops in view",
        cam.position_m,
        region.near_m,
        ground,
        |c| also(c) && in_view(c),
        |voxel, out| {
            (0..region.bins.len())
                .all(|bin| voxel_drops(region, &speeds, voxel, bin, cam.position_m, out))
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region(t: f64) -> RainRegion {
        RainRegion::new(20.0, &[1.0, 1.5, 2.0], 3.0, [1.0, 0.0, 0.0], t, 9).unwrap()
    }

    #[test]
    fn tabulated_speeds_follow_beards_law() {
        use rand::{Rng, SeedableRng};
        let bins = [
            (0.01, 0.03),
            (0.1, 0.3),
            (1.0, 1.2),
            (1.8, 2.0),
            (2.0, 3.0),
            (5.0, 6.0),
        ];
        let t = BinSpeeds::new(&bins);
        let law = *FallSpeed::beard_standard();
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let mut worst = 0.0f64;
        for (b, &(lo, hi)) in bins.iter().enumerate() {
            for _ in 0..20_000 {
                let d = rng.random_range(lo..=hi);
                let e = (t.m_s(b, d) / law.m_s(d) - 1.0).abs();
                assert!(
                    e < if lo < 0.5 { 3e-5 } else { 3e-7 },
                    "bin {b} d = {d}: {e:e}"
                );
                worst = worst.max(e);
            }
            assert_eq!(t.m_s(b, lo), law.m_s(lo));
            assert!((t.m_s(b, hi) / law.m_s(hi) - 1.0).abs() < 1e-12);
        }
        assert!(worst < 3e-5, "{worst:e}");
    }

    #[test]
    fn drops_are_world_anchored_and_coherent_in_time() {
        use std::collections::HashMap;
        let (ca, cb) = (DVec3::new(0.0, 1.6, 0.0), DVec3::new(0.5, 1.6, 0.0));
        let a = drops_near(&region(0.0), ca, true).unwrap();
        let b: HashMap<_, _> = drops_near(&region(0.0), cb, true)
            .unwrap()
            .into_iter()
            .map(|d| (d.id, d))
            .collect();
        // drops seen from both centres are the same drops
        let shared: Vec<_> = a.iter().filter(|d| b.contains_key(&d.id)).collect();
        assert!(shared.len() > 100);
        // (positioned relative to each centre: the same world positions, to f32's rounding)
        for d in &shared {
            let e = &b[&d.id];
            let (pa, pb) = (ca + d.position_m.as_dvec3(), cb + e.position_m.as_dvec3());
            assert!(pa.distance(pb) < 1e-6, "{pa} vs {pb}");
            assert_eq!(
                (d.velocity_m_s, d.diameter_m),
                (e.velocity_m_s, e.diameter_m)
            );
        }
        // 10 ms later every drop moved by v dt (no wrap for most)
        let later: HashMap<_, _> = drops_near(&region(0.01), ca, true)
            .unwrap()
            .into_iter()
            .map(|d| (d.id, d))
            .collect();
        let mut moved = 0;
        for d in &a {
            if let Some(e) = later.get(&d.id) {
                let step = e.position_m - d.position_m;
                if (step - d.velocity_m_s * 0.01).length() < 1e-5 {
                    moved += 1;
                }
            }
        }
        assert!(
            moved as f64 > 0.9 * a.len() as f64,
            "{moved} of {}",
            a.len()
        );
    }

    #[test]
    fn frustum_culling_keeps_every_streak_that_reaches_the_frame() {
        use crate::particles::composite::RainTargets;
        use crate::rain::streaks::{RainShading, composite};
        use glam::Mat3;
        let r = RainRegion::new(30.0, &[1.0, 1.5, 2.0], 5.0, [4.0, 0.0, -2.0], 0.3, 4).unwrap();
        let rot = Mat3::from_rotation_y(0.4) * Mat3::from_rotation_x(-0.2);
        let cam = Camera::new(
            80,
            60,
            [60.0, 60.0, 40.0, 30.0],
            Vec3::new(0.2, 1.6, 0.3),
            rot,
        )
        .unwrap();
        let all = drops_near(&r, cam.position_m, true).unwrap();
        let seen = drops_in_view(&r, &cam, 1.0 / 30.0, 0.0, true).unwrap();
        assert!(
            seen.len() * 2 < all.len(),
            "{} of {}",
            seen.len(),
            all.len()
        );
        let draw = |drops: &[Drop]| {
            let n = cam.pixels();
            let (mut rgb, mut a, mut z) = (vec![0.1f32; 3 * n], vec![0.0; n], vec![0.0; n]);
            let depth = vec![f32::INFINITY; n];
            let shown = composite(
                &cam,
                drops,
                1.0 / 30.0,
                &RainShading::open_sky(),
                RainTargets {
                    rgb: &mut rgb,
                    depth_m: &depth,
                    alpha: &mut a,
                    rain_depth_m: &mut z,
                },
            )
            .unwrap();
            (rgb, a, shown)
        };
        let (rgb_all, a_all, shown_all) = draw(&all);
        let (rgb_seen, a_seen, shown_seen) = draw(&seen);
        assert_eq!(shown_all, shown_seen);
        assert_eq!(a_all, a_seen);
        assert_eq!(rgb_all, rgb_seen);
    }

    #[test]
    fn drop_count_follows_marshall_palmer() {
        let r = region(0.0);
        let d = drops_near(&r, DVec3::new(0.3, 10.0, 0.7), true).unwrap();
        let per_m3: f64 = r
            .bins
            .iter()
            .map(|&(lo, hi)| drops_per_m3(20.0, lo, hi))
            .sum();
        let expected = per_m3 * 4.0 / 3.0 * std::f64::consts::PI * 27.0;
        let sd = expected.sqrt();
        assert!(
            (d.len() as f64 - expected).abs() < 4.0 * sd + 0.02 * expected,
            "{} vs {expected}",
            d.len()
        );
        assert!(
            drops_near(&r, DVec3::new(0.0, -10.0, 0.0), true)
                .unwrap()
                .is_empty()
        );
        // the budget's estimate holds them (it grows the sphere by a voxel's diagonal)
        assert!(r.expected_drops(1.0) >= d.len() as f64);
    }

    #[test]
    fn regions_over_the_drop_budget_are_refused_before_drawing() {
        // 50 m at 200 mm/h: ~1.4e3 drops/m³ in 5.6e5 m³, ~55 GiB of drops.
        let big = RainRegion::new(200.0, &[1.0, 1.5, 2.0], 50.0, [0.0; 3], 0.0, 1).unwrap();
        let refused = big.check_budget(1.0);
        assert!(
            matches!(&refused, Err(Error::TooLarge { what, .. }) if what.contains("rain_near_m = 50")),
            "{refused:?}"
        );
        // a frame sees a fraction of it; a 5 m region at any rate fits whole
        assert!(big.check_budget(1e-3).is_ok());
        assert!(
            RainRegion::new(500.0, &[0.5, 1.0, 2.0, 3.0], 5.0, [0.0; 3], 0.0, 1)
                .unwrap()
                .check_budget(1.0)
                .is_ok()
        );
    }
}
