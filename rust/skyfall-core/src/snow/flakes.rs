//! Snowflakes near the camera, anchored in the world as the rain's drops are
//! ([`crate::rain::drops`]): the world is cut into 1 m voxels, each holding, per melted-diameter
//! bin, ⌊λ⌋ flakes plus one with probability λ − ⌊λ⌋ (λ the bin's count in 1 m³ under
//! [`Snowfall`]: Gunn & Marshall's sizes, Locatelli & Hobbs' masses and fall speeds), with
//! sizes, positions, sprites and perturbations drawn from a generator seeded by
//! (seed, voxel, bin): the same flakes for any camera, frame or process.
//!
//! **Motion.** A flake falls with the wind at its Locatelli & Hobbs speed v(S), plus a
//! perturbation that stands in for the turbulence Koitabashi et al. model as Brownian motion:
//! per horizontal axis a sum of [`SWAYS`] seeded oscillations, and one vertical,
//! δ(t) = Σ (u_k/ω_k) sin(ω_k t + φ_k), so that its velocity u_k cos(ω_k t + φ_k) has a
//! random amplitude u_k, angular frequency ω_k and phase φ_k per flake. Position
//! p(t) = p₀ + (w_x, −v, w_z) t + δ(t), wrapped inside the flake's voxel like a drop's: the
//! position is a smooth function of t (continuous, with a continuous velocity) except where it
//! wraps, so flakes are coherent from frame to frame, and δ has mean 0, so the mean vertical
//! velocity, and with it the mass flux through a horizontal plane, is the fall speed's.
//!
//! **The flux relation, drawn.** Every flake of bin [lo, hi] crosses a horizontal plane once
//! per 1/v of time, on average; over a plane's area A and a time T the flakes crossing it carry
//! Σ m v T per m³ of voxels, which is ∫ N(D) m(D) v(D) dD = R ρ_w (see [`Snowfall`]) when
//! the bins span every size (`tests`: the crossings counted).

use crate::error::{Error, Result};
use crate::particles::Particle;
use crate::particles::voxels::{in_view, voxel_seed, voxels_where, wrap};
use crate::physics::snow::{
    FLAKE_SIZE_MAX_MM, Snowfall, flake_fall_speed_m_s, flake_melted_mm, flake_size_mm,
};
use crate::scene::camera::Camera;
use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// The smallest flake drawn as a particle, S (maximum dimension), mm: 1 mm is under a pixel
/// at 1 m in a 1080p frame with a 60° field of view (f ≈ 935 px); smaller flakes (and every
/// flake beyond the region) are the haze's σ_snow.
pub const FLAKE_DRAWN_MIN_MM: f64 = 1.0;
/// Melted-diameter bins drawn, evenly spaced between the smallest and the largest flake.
pub const SNOW_BINS: usize = 8;
/// Oscillations per horizontal axis of a flake's perturbation.
pub const SWAYS: usize = 2;
/// Range of a horizontal oscillation's velocity amplitude u_k, m/s. With [`SWAYS`] of them per
/// axis a flake's horizontal velocity varies with a standard deviation of 11-15 % of its fall
/// speed in the median (10 to 2 mm flakes; 16 % at 1 mm): within, and at the top of, the
/// 4-15 % Kajikawa & Okuhara (1997) observed for falling plate crystals (tested).
pub const SWAY_M_S: (f64, f64) = (0.05, 0.2);
/// Range of the vertical oscillation's velocity amplitude, m/s.
pub const BOB_M_S: (f64, f64) = (0.0, 0.1);
/// Range of the oscillations' angular frequencies ω_k, rad/s (periods of 1.6 to 8 s).
pub const SWAY_RAD_S: (f64, f64) = (0.8, 4.0);
/// The most memory the flakes of one call may take, bytes.
pub const FLAKE_BUDGET_BYTES: u64 = 2 << 30;

/// Which snow, where and when.
#[derive(Debug, Clone, PartialEq)]
pub struct SnowRegion {
    /// The flakes of the rate.
    pub snowfall: Snowfall,
    /// Melted-diameter bin edges, mm.
    pub bins: Vec<(f64, f64)>,
    /// Region radius around the camera, m.
    pub near_m: f64,
    /// Wind, m/s (its vertical component is ignored, as the rain's is).
    pub wind_m_s: DVec3,
    /// Time, s.
    pub time_s: f64,
    /// Seed.
    pub seed: u64,
}

/// The sway of one axis: (u_k / ω_k, ω_k, φ_k) per oscillation.
type Sway = [(f64, f64, f64); SWAYS];

/// One flake's perturbation: x and z sways, and the vertical bob.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Perturbation {
    x: Sway,
    z: Sway,
    y: (f64, f64, f64),
}

impl Perturbation {
    fn draw(rng: &mut Pcg64Mcg) -> Self {
        let mut osc = |(lo, hi): (f64, f64)| {
            let u = lo + (hi - lo) * rng.random::<f64>();
            let w = SWAY_RAD_S.0 + (SWAY_RAD_S.1 - SWAY_RAD_S.0) * rng.random::<f64>();
            let phase = std::f64::consts::TAU * rng.random::<f64>();
            (u / w, w, phase)
        };
        let x = [osc(SWAY_M_S), osc(SWAY_M_S)];
        let z = [osc(SWAY_M_S), osc(SWAY_M_S)];
        let y = osc(BOB_M_S);
        Perturbation { x, z, y }
    }

    /// The displacement δ(t), m, and its velocity δ'(t), m/s.
    pub fn at(&self, t: f64) -> (DVec3, DVec3) {
        let one = |&(a, w, phase): &(f64, f64, f64)| {
            let (s, c) = (w * t + phase).sin_cos();
            (a * s, a * w * c)
        };
        let sum = |sway: &Sway| {
            sway.iter()
                .map(one)
                .fold((0.0, 0.0), |(p, v), (dp, dv)| (p + dp, v + dv))
        };
        let ((px, vx), (pz, vz), (py, vy)) = (sum(&self.x), sum(&self.z), one(&self.y));
        (DVec3::new(px, py, pz), DVec3::new(vx, vy, vz))
    }
}

impl SnowRegion {
    /// Validated region of the liquid-equivalent rate `snow_rate_mm_h`, radius `near_m`.
    pub fn new(
        snow_rate_mm_h: f64,
        near_m: f64,
        wind_m_s: [f64; 3],
        time_s: f64,
        seed: u64,
    ) -> Result<Self> {
        crate::ranges::SNOW_RATE_MM_H.check(snow_rate_mm_h)?;
        crate::ranges::SNOW_NEAR_M.check(near_m)?;
        for (i, w) in wind_m_s.iter().enumerate() {
            crate::ranges::WIND_M_S.check_at(Some(i), *w)?;
        }
        crate::ranges::TIME_S.check(time_s)?;
        let snowfall = Snowfall::new(snow_rate_mm_h);
        Ok(SnowRegion {
            snowfall,
            bins: bins_from(FLAKE_DRAWN_MIN_MM),
            near_m,
            wind_m_s: DVec3::from(wind_m_s),
            time_s,
            seed,
        })
    }

    /// The region with flakes drawn down to size `size_mm` (S, mm; 0: every flake, as the
    /// flux test counts them).
    pub fn with_smallest_size_mm(mut self, size_mm: f64) -> Self {
        self.bins = bins_from(size_mm);
        self
    }

    /// Flakes per m³ in the drawn bins.
    pub fn flakes_per_m3(&self) -> f64 {
        self.bins
            .iter()
            .map(|&(lo, hi)| self.snowfall.bin_sampler(lo, hi).expected_per_m3())
            .sum()
    }

    /// The flakes expected in `fraction` of the region's sphere (grown by a voxel's diagonal).
    pub fn expected_flakes(&self, fraction: f64) -> f64 {
        self.flakes_per_m3() * 4.0 / 3.0
            * std::f64::consts::PI
            * (self.near_m + 1.8).powi(3)
            * fraction
    }

    /// [`Error::TooLarge`] when the flakes expected in `fraction` of the region would take more
    /// than [`FLAKE_BUDGET_BYTES`], naming what sets their number.
    pub fn check_budget(&self, fraction: f64) -> Result<()> {
        let n = self.expected_flakes(fraction);
        let bytes = (n * std::mem::size_of::<Particle>() as f64) as u128;
        if bytes > u128::from(FLAKE_BUDGET_BYTES) {
            let what = format!(
                "{n:.3e} snowflakes (snow_near_m = {} m at {} mm/h; their number goes as snow_near_m³)",
                self.near_m,
                self.snowfall.rate_mm_h()
            );
            return Err(Error::too_large(what, bytes, FLAKE_BUDGET_BYTES));
        }
        Ok(())
    }

    /// The fastest a flake moves, m/s: the largest's fall speed, the wind and the
    /// perturbation's largest velocity.
    pub fn max_speed_m_s(&self) -> f64 {
        let fall = flake_fall_speed_m_s(FLAKE_SIZE_MAX_MM) + BOB_M_S.1;
        let sway = SWAYS as f64 * SWAY_M_S.1;
        let (wx, wz) = (self.wind_m_s.x.abs() + sway, self.wind_m_s.z.abs() + sway);
        (fall * fall + wx * wx + wz * wz).sqrt()
    }
}

/// [`SNOW_BINS`] melted-diameter bins from the flake of size `size_mm` to the largest.
fn bins_from(size_mm: f64) -> Vec<(f64, f64)> {
    let lo = if size_mm > 0.0 {
        flake_melted_mm(size_mm.min(FLAKE_SIZE_MAX_MM))
    } else {
        0.0
    };
    let hi = flake_melted_mm(FLAKE_SIZE_MAX_MM);
    let step = (hi - lo) / SNOW_BINS as f64;
    (0..SNOW_BINS)
        .map(|k| (lo + step * k as f64, lo + step * (k + 1) as f64))
        .collect()
}

/// A flake at the frame's time: the particle (its `diameter_m` is the flake's maximum
/// dimension S) and its sprite's seed.
pub type Flake = Particle;

/// The sprite's key of a flake: a function of the seed and the flake's identity.
pub fn sprite_key(seed: u64, id: &[i64; 5]) -> u64 {
    voxel_seed(
        seed,
        [id[0], id[1], id[2]],
        &[id[3] as u64, id[4] as u64, 0x5e1f],
    )
}

/// The flakes of one voxel and bin.
fn voxel_flakes(
    region: &SnowRegion,
    voxel: [i64; 3],
    bin: usize,
    origin_m: DVec3,
    out: &mut Vec<Flake>,
) -> bool {
    let (lo, hi) = region.bins[bin];
    let sampler = region.snowfall.bin_sampler(lo, hi);
    if sampler.expected_per_m3() <= 0.0 {
        return true;
    }
    let key = voxel_seed(
        region.seed,
        voxel,
        &[0x5_0000 + bin as u64, lo.to_bits(), hi.to_bits()],
    );
    let mut rng = Pcg64Mcg::seed_from_u64(key);
    let n = sampler.count(&mut rng);
    // Room for the voxel's flakes first, fallibly: the pushes below do not allocate.
    if out.try_reserve(n).is_err() {
        return false;
    }
    let base = DVec3::new(voxel[0] as f64, voxel[1] as f64, voxel[2] as f64);
    let t = region.time_s;
    for k in 0..n {
        let melted_mm = sampler.diameter_mm(rng.random());
        let size_mm = flake_size_mm(melted_mm);
        let fall = DVec3::new(
            region.wind_m_s.x,
            -flake_fall_speed_m_s(size_mm),
            region.wind_m_s.z,
        );
        let p0 = DVec3::new(rng.random(), rng.random(), rng.random());
        let (dp, dv) = Perturbation::draw(&mut rng).at(t);
        let p = p0 + fall * t + dp;
        let local = DVec3::new(wrap(p.x), wrap(p.y), wrap(p.z));
        out.push(Flake {
            position_m: (base + local - origin_m).as_vec3(),
            velocity_m_s: (fall + dv).as_vec3(),
            diameter_m: (size_mm * 1e-3) as f32,
            id: [voxel[0], voxel[1], voxel[2], bin as i64, k as i64],
        });
    }
    true
}

/// Every flake within `region.near_m` of `center_m` (voxels at or above the ground only when
/// `ground` is set), in a deterministic order, positioned relative to `center_m`.
pub fn flakes_near(region: &SnowRegion, center_m: DVec3, ground: bool) -> Result<Vec<Flake>> {
    flakes_where(region, center_m, ground, |_| true)
}

fn flakes_where(
    region: &SnowRegion,
    center_m: DVec3,
    ground: bool,
    keep_voxel: impl Fn(Vec3) -> bool + Sync,
) -> Result<Vec<Flake>> {
    voxels_where(
        "the snow's flakes",
        center_m,
        region.near_m,
        ground,
        keep_voxel,
        |voxel, out| {
            (0..region.bins.len()).all(|bin| voxel_flakes(region, voxel, bin, center_m, out))
        },
    )
}

/// The flakes of [`flakes_near`] `cam` that can draw into its frame during `exposure_s`: the
/// voxels whose box, grown by the farthest a flake moves relative to the camera (moving at
/// `camera_speed_m_s`) in the exposure and by the reach of a streak's anti-aliasing beyond the
/// frame's edge, misses the view frustum are skipped without drawing their flakes.
pub fn flakes_in_view(
    region: &SnowRegion,
    cam: &Camera,
    exposure_s: f64,
    camera_speed_m_s: f64,
    ground: bool,
) -> Result<Vec<Flake>> {
    let edge =
        2.0 * (region.near_m + 2.0) / f64::from(cam.fx.min(cam.fy)) + 0.5e-3 * FLAKE_SIZE_MAX_MM;
    let margin = ((region.max_speed_m_s() + camera_speed_m_s) * exposure_s + edge) as f32;
    flakes_where(region, cam.position_m, ground, in_view(cam, margin))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::snow::flake_mass_mg;
    use std::collections::HashMap;

    #[test]
    fn flakes_crossing_a_plane_carry_the_rate() {
        // Count the flakes of a 5 m × 5 m slab of voxels (1 ≤ y < 2) crossing the plane
        // y = 1.5 over 4 s, in steps short enough that none moves half a voxel, and sum their
        // masses: the mass flux, against the rate (every size drawn). Independent of the
        // quadrature that sets N0: the flakes themselves are counted.
        for (rate, wind) in [(1.0, [0.0, 0.0, 0.0]), (4.0, [6.0, 0.0, -3.0])] {
            let (t_total, dt) = (4.0, 0.2);
            let at = |t: f64| {
                let r = SnowRegion::new(rate, 20.0, wind, t, 11)
                    .unwrap()
                    .with_smallest_size_mm(0.0);
                let mut out = Vec::new();
                for ix in -2..3 {
                    for iz in -2..3 {
                        for bin in 0..r.bins.len() {
                            assert!(voxel_flakes(&r, [ix, 1, iz], bin, DVec3::ZERO, &mut out));
                        }
                    }
                }
                out.into_iter()
                    .map(|f| {
                        (
                            f.id,
                            (f64::from(f.position_m.y), f64::from(f.diameter_m) * 1e3),
                        )
                    })
                    .collect::<HashMap<_, _>>()
            };
            let (mut mass_mg, mut prev) = (0.0, at(0.0));
            let steps = (t_total / dt) as usize;
            for s in 1..=steps {
                let now = at(s as f64 * dt);
                for (id, &(y, size_mm)) in &now {
                    let y0 = prev[id].0;
                    // downward through 1.5, not a wrap (a wrap jumps up by ~1 m)
                    if y0 > 1.5 && y <= 1.5 && y0 - y < 0.5 {
                        mass_mg += flake_mass_mg(flake_melted_mm(size_mm));
                    }
                }
                prev = now;
            }
            let got_mm_h = mass_mg / (25.0 * t_total) * 3600.0 / 1e6;
            assert!(
                (got_mm_h / rate - 1.0).abs() < 0.05,
                "{rate} mm/h: flakes carry {got_mm_h} mm/h"
            );
        }
    }

    #[test]
    fn the_sway_is_as_strong_as_falling_crystals_are_observed_to_sway() {
        // Kajikawa & Okuhara (1997, J. Meteor. Soc. Japan 75, "Observations of the falling
        // motion of plate-like snow crystals, Part II"): the horizontal velocity of falling
        // (rimed plate) crystals varies with a standard deviation of 4-15 % of their mean fall
        // speed. Each drawn flake's horizontal velocity along x, sampled over 200 s, has its own
        // standard deviation; against the Locatelli & Hobbs speed of flakes of 2, 5 and 10 mm
        // (the sizes the observed crystals span and beyond), its median ratio must lie in that
        // range, and its middle half within 3-20 %.
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        let draws: Vec<Perturbation> = (0..2000).map(|_| Perturbation::draw(&mut rng)).collect();
        let sds: Vec<f64> = draws
            .iter()
            .map(|p| {
                let vx: Vec<f64> = (0..540).map(|k| p.at(0.37 * k as f64).1.x).collect();
                let mean = vx.iter().sum::<f64>() / vx.len() as f64;
                (vx.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vx.len() as f64).sqrt()
            })
            .collect();
        for size_mm in [2.0, 5.0, 10.0] {
            let fall = flake_fall_speed_m_s(size_mm);
            let mut ratios: Vec<f64> = sds.iter().map(|sd| sd / fall).collect();
            ratios.sort_by(f64::total_cmp);
            let q = |f: f64| ratios[((ratios.len() - 1) as f64 * f) as usize];
            assert!(
                (0.04..=0.15).contains(&q(0.5)),
                "{size_mm} mm: median {}",
                q(0.5)
            );
            assert!(
                q(0.25) > 0.03 && q(0.75) < 0.2,
                "{size_mm} mm: quartiles {} {}",
                q(0.25),
                q(0.75)
            );
        }
    }

    #[test]
    fn flakes_fall_with_the_wind_and_sway_coherently() {
        let center = DVec3::new(0.2, 6.0, -0.4);
        for wind in [[0.0, 0.0, 0.0], [5.0, 0.0, 2.0]] {
            let r = |t: f64| SnowRegion::new(2.0, 3.0, wind, t, 3).unwrap();
            let a = flakes_near(&r(10.0), center, true).unwrap();
            assert!(a.len() > 1000, "{}", a.len());
            let mut mean = DVec3::ZERO;
            for f in &a {
                let v = f.velocity_m_s.as_dvec3();
                let fall = flake_fall_speed_m_s(f64::from(f.diameter_m) * 1e3);
                // velocity = wind + fall + a perturbation within its bounds
                let sway = DVec3::new(wind[0], -fall, wind[2]) - v;
                assert!(sway.x.abs() <= 0.4 + 1e-6 && sway.z.abs() <= 0.4 + 1e-6);
                assert!(sway.y.abs() <= 0.1 + 1e-6);
                mean += v;
            }
            mean /= a.len() as f64;
            // slanted with the wind: the mean horizontal velocity is the wind's
            assert!(
                (mean.x - wind[0]).abs() < 0.02 && (mean.z - wind[2]).abs() < 0.02,
                "{mean}"
            );
            assert!((-1.2..-0.8).contains(&mean.y), "{mean}");
            // coherent: 1 ms later each flake (but those wrapping) moved by about v·dt
            let dt = 1e-3;
            let later: HashMap<_, _> = flakes_near(&r(10.0 + dt), center, true)
                .unwrap()
                .into_iter()
                .map(|f| (f.id, f))
                .collect();
            let mut close = 0;
            for f in &a {
                if let Some(g) = later.get(&f.id) {
                    let step = (g.position_m - f.position_m).as_dvec3();
                    if (step - f.velocity_m_s.as_dvec3() * dt).length() < 1e-5 {
                        close += 1;
                    }
                }
            }
            assert!(
                close as f64 > 0.98 * a.len() as f64,
                "{close} of {}",
                a.len()
            );
        }
    }

    #[test]
    fn flakes_are_world_anchored_and_deterministic() {
        let r = SnowRegion::new(1.0, 4.0, [2.0, 0.0, 0.0], 3.5, 8).unwrap();
        let (ca, cb) = (DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.7, 2.0, 0.3));
        let a = flakes_near(&r, ca, true).unwrap();
        assert_eq!(a, flakes_near(&r, ca, true).unwrap());
        let b: HashMap<_, _> = flakes_near(&r, cb, true)
            .unwrap()
            .into_iter()
            .map(|f| (f.id, f))
            .collect();
        let shared: Vec<_> = a.iter().filter(|f| b.contains_key(&f.id)).collect();
        assert!(shared.len() > 100);
        for f in shared {
            let g = &b[&f.id];
            let (pa, pb) = (ca + f.position_m.as_dvec3(), cb + g.position_m.as_dvec3());
            assert!(pa.distance(pb) < 1e-5);
            assert_eq!(f.diameter_m, g.diameter_m);
        }
        // no snow: no flakes
        let dry = SnowRegion::new(0.0, 4.0, [0.0; 3], 0.0, 8).unwrap();
        assert!(flakes_near(&dry, ca, true).unwrap().is_empty());
        // sizes within the drawn range
        assert!(a.iter().all(|f| {
            let s = f64::from(f.diameter_m) * 1e3;
            (FLAKE_DRAWN_MIN_MM - 1e-4..=FLAKE_SIZE_MAX_MM + 1e-4).contains(&s)
        }));
    }

    #[test]
    fn bad_regions_are_refused_by_name() {
        let e = SnowRegion::new(101.0, 4.0, [0.0; 3], 0.0, 1).unwrap_err();
        assert!(e.to_string().starts_with("snow_rate_mm_h = 101"), "{e}");
        let e = SnowRegion::new(1.0, 0.0, [0.0; 3], 0.0, 1).unwrap_err();
        assert!(e.to_string().starts_with("snow_near_m = 0"), "{e}");
        let e = SnowRegion::new(1.0, 4.0, [f64::NAN, 0.0, 0.0], 0.0, 1).unwrap_err();
        assert!(e.to_string().starts_with("wind_m_s[0]"), "{e}");
        // 50 m at 100 mm/h: refused before any flake is made, naming snow_near_m
        let big = SnowRegion::new(100.0, 50.0, [0.0; 3], 0.0, 1).unwrap();
        assert!(matches!(
            big.check_budget(1.0),
            Err(Error::TooLarge { what, .. }) if what.contains("snow_near_m = 50")
        ));
    }
}
